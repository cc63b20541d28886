#!/usr/bin/env bash
# Installs the Debian package on this machine with apt, checks where every file
# went and that the installed programs work, then removes and purges it and
# checks nothing is left. Needs root. Builds the package first (package.sh).
#   vcan-scripts/package-test.sh
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
bash "$IRSLAM_ROOT/vcan-scripts/package.sh"
deb=$(ls "$IRSLAM_ROOT"/build-deb/irslam_*.deb | head -1)
fail() { echo "package-test: $*" >&2; exit 1; }
export DEBIAN_FRONTEND=noninteractive
apt-get install -y -qq "$deb" >/dev/null || fail "apt install failed"
for f in /usr/bin/irslamd /usr/bin/irslamctl /usr/bin/irslam-candump /usr/bin/irslam-sim /usr/bin/irslam-replay \
         /usr/lib/systemd/system/irslamd.service /usr/lib/sysusers.d/irslam.conf \
         /etc/irslam/irslamd.conf /usr/share/irslam/irslam.dbc \
         /usr/share/man/man8/irslamd.8.gz /usr/share/man/man1/irslamctl.1.gz \
         /usr/share/man/man1/irslam-sim.1.gz /usr/share/man/man1/irslam-candump.1.gz \
         /usr/share/man/man1/irslam-replay.1.gz /usr/share/bash-completion/completions/irslam-replay \
         /usr/share/bash-completion/completions/irslamctl /usr/share/bash-completion/completions/irslam-sim \
         /usr/share/doc/irslam/copyright; do
  dpkg -L irslam | grep -qx "$f" || fail "$f is not in the package"
  [ -e "$f" ] || fail "$f was not installed"
done
dpkg-query -W -f='${Conffiles}\n' irslam | grep -q /etc/irslam/irslamd.conf || fail "the config is not a conffile"
getent passwd irslam >/dev/null || fail "the irslam user was not created"
/usr/bin/irslamd --config /etc/irslam/irslamd.conf --print-config >/dev/null || fail "irslamd --print-config failed"
man -w irslamd >/dev/null 2>&1 || fail "man irslamd not found"
if command -v systemd-analyze >/dev/null; then
  out=$(systemd-analyze verify /usr/lib/systemd/system/irslamd.service 2>&1 || true)
  [ -z "$out" ] || fail "systemd-analyze verify: $out"
fi
if [ -d /run/systemd/system ]; then
  ! systemctl is-active -q irslamd || fail "the service was started on install"
fi
apt-get remove -y -qq irslam >/dev/null || fail "remove failed"
[ ! -e /usr/bin/irslamd ] || fail "/usr/bin/irslamd left after remove"
[ -e /etc/irslam/irslamd.conf ] || fail "remove must keep the conffile"
dpkg --purge irslam >/dev/null || fail "purge failed"
[ ! -e /etc/irslam/irslamd.conf ] || fail "/etc/irslam/irslamd.conf left after purge"
! dpkg -l irslam 2>/dev/null | grep -q '^.i' || fail "still installed after purge"
echo "package-test: installed, checked, removed and purged $(basename "$deb")"
echo "1 passed, 0 failed"
