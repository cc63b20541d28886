#!/usr/bin/env bash
# Builds the Debian package (CPack DEB) into build-deb/ and checks it with lintian.
#   vcan-scripts/package.sh            -> build-deb/irslam_<version>_<arch>.deb
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
bash "$IRSLAM_ROOT/vcan-scripts/install-deps.sh" --package
build=$IRSLAM_ROOT/build-deb
cmake -S "$IRSLAM_ROOT" -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX=/usr \
  -DIRSLAM_TESTS=OFF -DIRSLAM_BENCHMARKS=OFF >/dev/null
cmake --build "$build" -j"$(nproc)"
(cd "$build" && cpack -G DEB >/dev/null)
deb=$(ls "$build"/irslam_*.deb | head -1)
echo "package.sh: $deb"
# lintian: errors fail the build; warnings are printed.
if ! lintian --fail-on error --suppress-tags dir-or-file-in-opt "$deb"; then
  echo "package.sh: lintian reports errors" >&2
  exit 1
fi
