#!/usr/bin/env bash
# Installs the Debian packages irslam needs to build, test and run the demo.
# Idempotent: runs apt-get only when a package is missing. Needs root (or sudo).
#   vcan-scripts/install-deps.sh          build + test dependencies
#   vcan-scripts/install-deps.sh --vm     also what the VM test harness needs (qemu ...)
#   vcan-scripts/install-deps.sh --fuzz   also clang + libFuzzer runtime
#   vcan-scripts/install-deps.sh --package  also what building and checking the .deb needs
set -euo pipefail

pkgs=(cmake make g++ pkg-config
      libboost-dev libeigen3-dev libgpiod-dev libsystemd-dev nlohmann-json3-dev
      libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev can-utils
      iproute2 systemd python3 python3-pil python3-numpy)
# Node.js and npm for the Foxglove test (tests/foxglove, @foxglove/ws-protocol):
# Debian's, unless the machine has a node and npm already (from another source).
command -v node >/dev/null || pkgs+=(nodejs)
command -v npm >/dev/null || pkgs+=(npm)
for arg in "$@"; do
  case "$arg" in
    --vm)   pkgs+=(qemu-system-x86 busybox-static cpio kmod gpiod) ;;
    --fuzz) pkgs+=(clang libclang-rt-14-dev) ;;
    --package) pkgs+=(dpkg-dev lintian man-db) ;;
    *) echo "install-deps: unknown option '$arg'" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "install-deps: installing ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
