#!/bin/bash
# vcan-scripts/run-in-vm.sh [--] COMMAND [ARGS...]   (the project's copy of shared/vm/run-in-vm.sh)
#
# Boots a Debian kernel under qemu (KVM if usable, else TCG) with a tiny
# busybox initramfs.  The host root filesystem is mounted read-only over
# virtio-9p with a tmpfs overlay on top (everything is writable inside the VM,
# nothing leaks back), $PWD is shared read-write, vcan interfaces and a
# gpio-sim chip are created, then COMMAND runs in $PWD with the caller's
# environment; the script exits with COMMAND's exit status.
# stdio: if stdin and stdout are ttys, COMMAND gets ttys (virtconsoles hvc0 =
# qemu stdio, hvc1 = our stderr); otherwise plain virtio-serial ports wired to
# our stdout/stderr (kept separate) and, if it is a pipe/file, our stdin (EOF
# is passed on).  Kernel/init log: serial ttyS0 -> a log file (or stderr).
#
# Environment knobs:
#   RUN_IN_VM_CACHE      cache dir (default ${TMPDIR:-/tmp}/run-in-vm-cache)
#   RUN_IN_VM_KERNEL     kernel ABI, e.g. 6.1.0-56-amd64 (default: newest one
#                        already cached, else what apt's linux-image-amd64 uses)
#   RUN_IN_VM_ACCEL      auto|kvm|tcg (default auto: kvm unless /dev/kvm is
#                        missing or is PVM, which cannot run stock kernels)
#   RUN_IN_VM_MEM / RUN_IN_VM_SMP   guest RAM / CPUs (default 1G / 2)
#   RUN_IN_VM_VCAN       vcan interfaces to create (default "vcan0"; "" = none)
#   RUN_IN_VM_GPIO_LINES lines of the gpio-sim chip (default 8; 0 = no chip)
#   RUN_IN_VM_GPIO_LABEL chip label (default gpio-sim-robot)
#   RUN_IN_VM_GPIO_NAMES comma-separated line names (optional)
#   RUN_IN_VM_SHARE_CWD  1 = share $PWD read-write (default); 0 = cwd changes
#                        stay in the VM
#   RUN_IN_VM_RW_DIRS    colon-separated extra host dirs to share read-write
#   RUN_IN_VM_TIMEOUT    kill the VM after N seconds, exit 124 (default 0 = off)
#   RUN_IN_VM_VERBOSE    1 = kernel/init console on stderr
#   RUN_IN_VM_CMDLINE    extra kernel command line
#   RUN_IN_VM_KEEP_DEBS  1 = keep downloaded .debs in the cache
# Exit status: COMMAND's; 124 on timeout; 125 if the VM never reported one.
set -eu

die() { echo "run-in-vm: $*" >&2; exit 125; }
say() { echo "run-in-vm: $*" >&2; }

[ "${1:-}" = "--" ] && shift
[ $# -ge 1 ] || die "usage: $0 -- COMMAND [ARGS...]"

CACHE=${RUN_IN_VM_CACHE:-${TMPDIR:-/tmp}/run-in-vm-cache}
MEM=${RUN_IN_VM_MEM:-1G}
SMP=${RUN_IN_VM_SMP:-2}
VCAN=${RUN_IN_VM_VCAN-vcan0}
GPIO_LINES=${RUN_IN_VM_GPIO_LINES:-8}
GPIO_LABEL=${RUN_IN_VM_GPIO_LABEL:-gpio-sim-robot}
GPIO_NAMES=${RUN_IN_VM_GPIO_NAMES:-}
SHARE_CWD=${RUN_IN_VM_SHARE_CWD:-1}
RW_DIRS=${RUN_IN_VM_RW_DIRS:-}
TIMEOUT=${RUN_IN_VM_TIMEOUT:-0}
VERBOSE=${RUN_IN_VM_VERBOSE:-0}

# Loaded at boot (dependencies are added automatically) ...
BOOT_MODS="virtio_pci virtio_console 9pnet_virtio 9p overlay configfs can can_raw can_dev vcan gpio_sim"
# ... and only put into the initramfs, for kernel auto-loading
# (request_module -> busybox modprobe), e.g. socket(AF_CAN, .., CAN_BCM).
EXTRA_MODS="can_bcm can_gw can_isotp can_j1939 vxcan"

mkdir -p "$CACHE"
CACHE=$(cd "$CACHE" && pwd)

# --------------------------------------------------------------------------
# one-time setup: host packages, kernel + modules, gpio-sim.ko
# --------------------------------------------------------------------------
file_is_static() { ! command -v readelf >/dev/null || ! readelf -l "$1" 2>/dev/null | grep -q 'program interpreter'; }

need_host_pkgs() {
    local missing=()
    command -v qemu-system-x86_64 >/dev/null || missing+=(qemu-system-x86)
    { [ -x /bin/busybox ] && /bin/busybox --list | grep -qx depmod; } || missing+=(busybox-static)
    if [ ${#missing[@]} -gt 0 ]; then
        [ "$(id -u)" = 0 ] || die "please install: ${missing[*]}"
        say "installing host packages: ${missing[*]}"
        DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends "${missing[@]}" >&2
    fi
    file_is_static /bin/busybox || die "/bin/busybox is not static (install busybox-static)"
}

# "depends=" of a (possibly compressed) module
mod_deps() {
    case $1 in
        *.xz)  xz -dc "$1" ;;
        *.zst) zstd -dc "$1" ;;
        *.gz)  gzip -dc "$1" ;;
        *)     cat "$1" ;;
    esac | tr '\0' '\n' | sed -n 's/^depends=//p' | head -n1 | tr ',' ' '
}

# Uncompressed ELF vmlinux for PVH boot: skips the real-mode setup and the
# in-guest xz decompression (~2.5 s under TCG).
extract_vmlinux() {
    local off
    off=$(LC_ALL=C grep -obUaP '\xfd7zXZ\x00' "$1" | head -n1 | cut -d: -f1 || true)
    [ -n "$off" ] || return 1
    tail -c +$((off + 1)) "$1" | xz -dc --single-stream > "$2" 2>/dev/null || return 1
    [ "$(head -c 4 "$2" | od -An -c | tr -d ' ')" = '177ELF' ] || return 1
    # needs the PVH entry note (XEN_ELFNOTE_PHYS32_ENTRY, CONFIG_PVH=y)
    ! command -v readelf >/dev/null || readelf -n "$2" | grep -q '(0x00000012)'
}

apt_version() { apt-cache show "$1" 2>/dev/null | awk '/^Version:/{print $2; exit}' || true; }

# Debian's kernels are built without CONFIG_GPIO_SIM (and CONFIG_IRQ_SIM):
# build gpio-sim.ko out of tree from linux-source + linux-headers.
build_gpio_sim() {
    local kd=$1 abi=$2 ver=$3 kver=$4 dl=$5 out=$6
    local hdeps common kbuild src b H d
    hdeps=$(apt-cache show "linux-headers-$abi=$ver" | sed -n 's/^Depends: //p' | head -n1 | tr ',' '\n' || true)
    common=$(echo "$hdeps" | grep -o 'linux-headers-[^ ]*-common' | head -n1 || true)
    kbuild=$(echo "$hdeps" | grep -o 'linux-kbuild-[^ ]*' | head -n1 || true)
    src=linux-source-$(echo "$kver" | cut -d. -f1,2)
    say "building gpio-sim.ko: downloading $src + headers (~155 MB, once)"
    ( cd "$dl" && apt-get download -q "linux-headers-$abi=$ver" "$common=$ver" "$kbuild=$ver" "$src=$ver" >&2 ) ||
        { say "download of headers/source failed"; return 1; }
    b=$kd/gpiosim-build
    rm -rf "$b"; mkdir -p "$b/hdr" "$b/src" "$b/m"
    for d in "$dl/linux-headers-${abi}_${ver}_amd64.deb" "$dl/${common}_${ver}_all.deb" "$dl/${kbuild}_${ver}_amd64.deb"; do
        dpkg -x "$d" "$b/hdr"
    done
    H=$b/hdr/usr/src/linux-headers-$abi
    # the arch Makefile includes the -common one by absolute path
    sed -i "s|include /usr/src/|include $b/hdr/usr/src/|" "$H/Makefile"
    dpkg-deb --fsys-tarfile "$dl/${src}_${ver}_all.deb" | tar -xO "./usr/src/$src.tar.xz" |
        tar -xJ -C "$b/src" --strip-components=1 \
            "$src/drivers/gpio/gpio-sim.c" "$src/drivers/gpio/gpiolib.h" "$src/kernel/irq/irq_sim.c" ||
        { say "could not extract gpio-sim sources"; return 1; }
    cp "$b/src/drivers/gpio/gpio-sim.c" "$b/m/gpio-sim-main.c"
    cp "$b/src/drivers/gpio/gpiolib.h" "$b/src/kernel/irq/irq_sim.c" "$b/m/"
    # link irq_sim.c into the module; irq_to_desc() is not exported, and
    # generic_handle_irq_safe() does the same job from irq_work context
    sed -i 's/handle_simple_irq(irq_to_desc(irqnum));/generic_handle_irq_safe(irqnum);/' "$b/m/irq_sim.c"
    printf 'obj-m := gpio-sim.o\ngpio-sim-y := gpio-sim-main.o irq_sim.o\n' > "$b/m/Kbuild"
    make -s -C "$H" M="$b/m" modules >"$b/build.log" 2>&1 || { cat "$b/build.log" >&2; return 1; }
    cp "$b/m/gpio-sim.ko" "$out"
    rm -rf "$b"
}

setup_kernel() {
    local abi=$1 kd=$CACHE/k/$1 dl=$CACHE/dl ver x kver mdir f n m d dst gs
    [ -e "$kd/.done" ] && return 0
    say "preparing kernel $abi in $kd (once)"
    rm -rf "$kd"; mkdir -p "$kd" "$dl"
    ver=$(apt_version "linux-image-$abi")
    [ -n "$ver" ] || die "apt does not know linux-image-$abi (run apt-get update?)"
    ( cd "$dl" && apt-get download -q "linux-image-$abi=$ver" >&2 ) || die "apt-get download linux-image-$abi failed"
    x=$kd/x; mkdir -p "$x"
    dpkg -x "$dl/linux-image-${abi}_${ver}_amd64.deb" "$x"
    cp "$x"/boot/vmlinuz-* "$kd/vmlinuz"
    cp "$x"/boot/config-* "$kd/config"
    extract_vmlinux "$kd/vmlinuz" "$kd/vmlinux" || rm -f "$kd/vmlinux"
    mdir=$(ls -d "$x"/lib/modules/* "$x"/usr/lib/modules/* 2>/dev/null | head -n1 || true)
    kver=$(basename "$mdir")
    echo "$kver" > "$kd/kver"

    declare -A idx=()          # normalised module name -> file
    while IFS= read -r f; do
        n=$(basename "$f"); n=${n%%.ko*}; n=${n//-/_}
        idx[$n]=$f
    done < <(find "$mdir/kernel" -name '*.ko*')

    gs=$kd/gpio-sim.ko
    if [ -z "${idx[gpio_sim]:-}" ]; then
        if build_gpio_sim "$kd" "$abi" "$ver" "$kver" "$dl" "$gs"; then idx[gpio_sim]=$gs
        else say "WARNING: could not build gpio-sim.ko; the VM will have no gpio-sim"; fi
    fi

    # dependency closure -> $kd/modroot/lib/modules/$kver (uncompressed)
    local want=() seen=" "
    for m in $BOOT_MODS $EXTRA_MODS; do want+=("${m//-/_}"); done
    while [ ${#want[@]} -gt 0 ]; do
        m=${want[0]}; want=("${want[@]:1}")
        case $seen in *" $m "*) continue ;; esac
        seen="$seen$m "
        f=${idx[$m]:-}
        if [ -z "$f" ]; then
            grep -qE "/${m//_/[-_]}\.ko" "$mdir/modules.builtin" 2>/dev/null || say "note: module $m not available"
            continue
        fi
        for d in $(mod_deps "$f"); do want+=("${d//-/_}"); done
        if [ "$f" = "$gs" ]; then dst=$kd/modroot/lib/modules/$kver/extra/gpio-sim.ko
        else dst=$kd/modroot/lib/modules/$kver/${f#"$mdir"/}; fi
        mkdir -p "$(dirname "$dst")"
        case $f in
            *.xz)  dst=${dst%.xz};  xz -dc "$f" > "$dst" ;;
            *.zst) dst=${dst%.zst}; zstd -dc "$f" > "$dst" ;;
            *.gz)  dst=${dst%.gz};  gzip -dc "$f" > "$dst" ;;
            *)     cp "$f" "$dst" ;;
        esac
        # also drops the appended signature: no RSA check in the (slow) guest
        strip --strip-debug "$dst" 2>/dev/null || true
    done
    cp "$mdir"/modules.builtin* "$mdir"/modules.order "$kd/modroot/lib/modules/$kver/" 2>/dev/null || true
    /bin/busybox depmod -b "$kd/modroot" "$kver"
    rm -rf "$x"
    [ "${RUN_IN_VM_KEEP_DEBS:-0}" = 1 ] || rm -f "$dl"/*.deb
    touch "$kd/.done"
}

resolve_abi() {
    local k
    if [ -n "${RUN_IN_VM_KERNEL:-}" ]; then echo "$RUN_IN_VM_KERNEL"; return; fi
    k=$(ls -t "$CACHE"/k/*/.done 2>/dev/null | head -n1 || true)
    if [ -n "$k" ]; then basename "$(dirname "$k")"; return; fi
    apt-cache depends linux-image-amd64 2>/dev/null |
        sed -n 's/^ *Depends: linux-image-\([^ <>]*-amd64\)$/\1/p' | head -n1 || true
}

# --------------------------------------------------------------------------
# initramfs: static busybox + modules + /init (PID 1 stays in the initramfs,
# COMMAND runs chrooted into the overlay root)
# --------------------------------------------------------------------------
write_init() {
cat <<'INIT'
#!/bin/busybox sh
export PATH=/sbin:/bin
mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
msg() { echo "run-in-vm(init): $*" > /dev/console; }
fail() { msg "$*"; poweroff -f; }
ts() { read up idle < /proc/uptime; msg "[$up] $*"; }
ts "init started"
modprobe -a $(cat /etc/boot-modules) 2>/dev/console
ts "modules loaded"
O9P=trans=virtio,version=9p2000.L,msize=512000
mount -t 9p -o $O9P vmrun /vmrun || fail "mount vmrun"
. /vmrun/config
mount -t 9p -o $O9P,cache=loose,ro hostroot /lower || fail "mount hostroot"
mount -t tmpfs -o mode=0755 tmpfs /rw
mkdir -p /rw/upper /rw/work
N=/newroot
if ! mount -t overlay -o lowerdir=/lower,upperdir=/rw/upper,workdir=/rw/work overlay $N 2>/dev/console; then
    msg "overlay failed, using read-only root + tmpfs on /tmp /var/tmp /root"
    mount --bind /lower $N
    for d in tmp var/tmp root; do mount -t tmpfs tmpfs "$N/$d"; done
fi
mount -t proc proc $N/proc
mount -t sysfs sysfs $N/sys
mount -t devtmpfs devtmpfs $N/dev
mkdir -p $N/dev/pts $N/dev/shm
mount -t devpts -o newinstance,ptmxmode=0666 devpts $N/dev/pts
mount -t tmpfs -o mode=1777 tmpfs $N/dev/shm
mount -t tmpfs -o mode=0755 tmpfs $N/run
mount -t configfs configfs $N/sys/kernel/config 2>/dev/null
mount -t debugfs debugfs $N/sys/kernel/debug 2>/dev/null
if [ "$SHARE_CWD" = 1 ]; then
    mkdir -p "$N$VM_CWD"
    mount -t 9p -o $O9P,cache=loose cwd "$N$VM_CWD" || fail "mount cwd $VM_CWD"
fi
i=1
while [ "$i" -le "${RW_COUNT:-0}" ]; do
    eval "d=\$RW_DIR_$i"
    mkdir -p "$N$d"
    mount -t 9p -o $O9P,cache=loose "rw$i" "$N$d" || fail "mount $d"
    i=$((i + 1))
done
hostname run-in-vm
ip link set lo up
for c in $VCAN; do
    chroot $N ip link add dev "$c" type vcan 2>/dev/console || ip link add dev "$c" type vcan
    ip link set "$c" up
done
if [ "${GPIO_LINES:-0}" -gt 0 ]; then
    g=$N/sys/kernel/config/gpio-sim/sim0
    if mkdir $g $g/bank0 2>/dev/console; then
        echo "$GPIO_LINES" > $g/bank0/num_lines
        echo "$GPIO_LABEL" > $g/bank0/label
        i=0
        for n in $(echo "$GPIO_NAMES" | tr ',' ' '); do
            mkdir $g/bank0/line$i && echo "$n" > $g/bank0/line$i/name
            i=$((i + 1))
        done
        echo 1 > $g/live || msg "gpio-sim: going live failed"
    else
        msg "gpio-sim not available"
    fi
fi
mkdir -p $N/run/run-in-vm
cp /vmrun/cmd.sh /vmrun/env.sh $N/run/run-in-vm/
port() {   # virtio-serial port by name
    for p in /sys/class/virtio-ports/*; do
        [ "$(cat "$p/name" 2>/dev/null)" = "$1" ] && { echo "/dev/${p##*/}"; return; }
    done
    echo /dev/null
}
if [ "$INTERACTIVE" = 1 ]; then
    # ttys: hvc0 = qemu stdio, hvc1 = host stderr.  Keep them open here, hvc
    # resets termios on last close.  The host terminal does the CR/LF.
    exec 3<>/dev/hvc0 4<>/dev/hvc1 5<&3
    stty sane -onlcr <&3; stty sane -onlcr -echo <&4
else
    # plain virtio-serial ports (no tty, EOF on stdin is passed through)
    exec 5<"$(port rvm.in)" 3>"$(port rvm.out)" 4>"$(port rvm.err)"
fi
ts "starting command"
setsid -c chroot $N /bin/bash /run/run-in-vm/cmd.sh <&5 >&3 2>&4
rc=$?
ts "command exited with $rc"
echo "$rc" > /vmrun/rc
sync
umount -a -r 2>/dev/null
poweroff -f
INIT
}

build_initramfs() {
    local kd=$1 h out st a
    h=$( { write_init; echo "$BOOT_MODS"; ls -l --time-style=+%s "$kd/.done"; md5sum < /bin/busybox; } | md5sum | cut -c1-12)
    out=$kd/initramfs-$h.cpio
    if [ ! -e "$out" ]; then
        st=$(mktemp -d "$kd/stage.XXXXXX")
        mkdir -p "$st"/{bin,sbin,etc,proc,sys,dev,lower,rw,newroot,vmrun,lib}
        cp /bin/busybox "$st/bin/busybox"
        for a in $(/bin/busybox --list); do
            [ "$a" = busybox ] || ln -s busybox "$st/bin/$a"
        done
        for a in modprobe insmod rmmod depmod lsmod poweroff reboot; do ln -sf ../bin/busybox "$st/sbin/$a"; done
        cp -a "$kd/modroot/lib/modules" "$st/lib/"
        echo "$BOOT_MODS" > "$st/etc/boot-modules"
        write_init > "$st/init"; chmod 755 "$st/init"
        ( cd "$st" && find . | /bin/busybox cpio -o -H newc 2>/dev/null ) > "$out.tmp"
        mv "$out.tmp" "$out"
        rm -rf "$st"
    fi
    echo "$out"
}

# dupfd SRC DST: make fd DST a write-only copy of fd SRC (or /dev/null)
dupfd() {
    local fl
    fl=$(sed -n 's/^flags:[[:space:]]*//p' "/proc/$$/fdinfo/$1" 2>/dev/null || true)
    if [ -n "$fl" ] && [ $((8#$fl & 3)) = 1 ]; then eval "exec $2>&$1"
    elif (eval "exec $2>>/proc/$$/fd/$1") 2>/dev/null; then eval "exec $2>>/proc/$$/fd/$1"
    else eval "exec $2>/dev/null"; fi
}

# --------------------------------------------------------------------------
main() {
    need_host_pkgs
    local abi kd initrd
    exec 9>"$CACHE/.lock"
    flock 9
    abi=$(resolve_abi)
    [ -n "$abi" ] || die "cannot determine a kernel (set RUN_IN_VM_KERNEL, or run apt-get update)"
    setup_kernel "$abi"
    kd=$CACHE/k/$abi
    initrd=$(build_initramfs "$kd")
    flock -u 9

    mkdir -p "$CACHE/runs"
    RUN=$(mktemp -d "$CACHE/runs/run.XXXXXX")
    trap 'rm -rf "$RUN"' EXIT
    local cwd=$PWD interactive=0 i=0 d
    [ -t 0 ] && [ -t 1 ] && interactive=1
    [ "$cwd" = / ] && SHARE_CWD=0
    local rwargs=()
    {
        printf 'VM_CWD=%q\nSHARE_CWD=%q\nVCAN=%q\nGPIO_LINES=%q\nGPIO_LABEL=%q\nGPIO_NAMES=%q\nINTERACTIVE=%q\n' \
            "$cwd" "$SHARE_CWD" "$VCAN" "$GPIO_LINES" "$GPIO_LABEL" "$GPIO_NAMES" "$interactive"
        local rwdirs=()
        [ -z "$RW_DIRS" ] || IFS=: read -ra rwdirs <<< "$RW_DIRS"
        for d in ${rwdirs[@]+"${rwdirs[@]}"}; do
            [ -d "$d" ] || die "RUN_IN_VM_RW_DIRS: $d is not a directory"
            d=$(cd "$d" && pwd); i=$((i + 1))
            printf 'RW_DIR_%d=%q\n' "$i" "$d"
            rwargs+=(-virtfs "local,path=${d//,/,,},mount_tag=rw$i,security_model=none,multidevs=remap")
        done
        echo "RW_COUNT=$i"
    } > "$RUN/config"
    export -p | grep -vE '^declare -[a-zA-Z-]* (PWD|OLDPWD|SHLVL|_)(=|$)' > "$RUN/env.sh" || true
    {
        echo 'source /run/run-in-vm/env.sh 2>/dev/null'
        printf 'cd -- %q || exit 125\n' "$cwd"
        printf 'exec'; printf ' %q' "$@"; printf '\n'
    } > "$RUN/cmd.sh"

    local accel
    case ${RUN_IN_VM_ACCEL:-auto} in
        auto) if [ -w /dev/kvm ] && [ ! -d /sys/module/kvm_pvm ]; then accel=kvm; else accel=tcg; fi ;;
        kvm|tcg) accel=$RUN_IN_VM_ACCEL ;;
        *) die "RUN_IN_VM_ACCEL must be auto, kvm or tcg" ;;
    esac
    local accel_args=(-accel tcg,thread=multi -cpu max)
    [ "$accel" = kvm ] && accel_args=(-enable-kvm -cpu host)
    local kernel=$kd/vmlinuz
    [ -s "$kd/vmlinux" ] && kernel=$kd/vmlinux

    local qemu=(qemu-system-x86_64 "${accel_args[@]}" -machine q35 -m "$MEM" -smp "$SMP"
        -nodefaults -no-user-config -nographic -no-reboot
        -kernel "$kernel" -initrd "$initrd"
        -append "console=ttyS0 quiet loglevel=4 panic=-1 mitigations=off tsc=reliable no_timer_check ${RUN_IN_VM_CMDLINE:-}"
        -virtfs "local,path=/,mount_tag=hostroot,security_model=none,readonly=on,multidevs=remap"
        -virtfs "local,path=${RUN//,/,,},mount_tag=vmrun,security_model=none"
        ${rwargs[@]+"${rwargs[@]}"}
        -device virtio-serial-pci)
    [ -r /usr/share/qemu/qboot.rom ] && qemu+=(-bios /usr/share/qemu/qboot.rom)
    [ "$SHARE_CWD" = 1 ] && qemu+=(-virtfs "local,path=${cwd//,/,,},mount_tag=cwd,security_model=none,multidevs=remap")
    # Guest stdio.  Our fds go to qemu with -add-fd, which refuses fds 0-2
    # and wants the exact access mode, so dup/reopen them as fds 7, 8.
    dupfd 2 8
    if [ "$interactive" = 1 ]; then
        qemu+=(-chardev stdio,id=con,signal=on -device virtconsole,chardev=con
            -add-fd fd=8,set=8 -chardev file,id=err,path=/dev/fdset/8,append=on -device virtconsole,chardev=err)
    else
        dupfd 1 7
        qemu+=(-add-fd fd=7,set=7 -chardev file,id=out,path=/dev/fdset/7,append=on -device virtserialport,chardev=out,name=rvm.out
            -add-fd fd=8,set=8 -chardev file,id=err,path=/dev/fdset/8,append=on -device virtserialport,chardev=err,name=rvm.err)
        # stdin: a tty or /dev/null stays outside; pipes/files are passed on
        # (qemu's stdio chardev, input only; EOF reaches the guest)
        if [ ! -t 0 ] && ! [ /dev/stdin -ef /dev/null ]; then
            qemu+=(-chardev stdio,id=in,signal=off -device virtserialport,chardev=in,name=rvm.in)
        fi
    fi
    if [ "$VERBOSE" = 1 ]; then qemu+=(-chardev file,id=ser,path=/dev/fdset/8,append=on)
    else qemu+=(-chardev "file,id=ser,path=${RUN//,/,,}/console.log"); fi
    qemu+=(-serial chardev:ser)
    [ "$TIMEOUT" != 0 ] && qemu=(timeout -s KILL "$TIMEOUT" "${qemu[@]}")

    local qrc=0
    if [ "$interactive" = 1 ]; then "${qemu[@]}" 9>&- || qrc=$?
    else "${qemu[@]}" 9>&- >/dev/null || qrc=$?; fi
    if [ -s "$RUN/rc" ]; then exit "$(cat "$RUN/rc")"; fi
    if [ "$TIMEOUT" != 0 ] && [ "$qrc" = 137 ]; then say "timed out after ${TIMEOUT}s"; exit 124; fi
    say "VM did not report an exit status (qemu rc=$qrc); console log tail:"
    tail -n 40 "$RUN/console.log" >&2 2>/dev/null || true
    exit 125
}

main "$@"
