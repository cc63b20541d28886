#!/usr/bin/env bash
# ctest's foxglove_node: the node test of irslam-foxglove with @foxglove/ws-protocol.
#   tests/foxglove/run.sh BUILD_DIR
# Exits 77 (ctest: skipped) when node or the npm packages are missing; vcan-scripts/test.sh
# installs them (`npm ci` here) before it runs ctest.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
build=$(cd "${1:?usage: run.sh BUILD_DIR}" && pwd)
if ! command -v node >/dev/null; then
  echo "foxglove_node: skipped: node is not installed (vcan-scripts/install-deps.sh installs nodejs)"
  exit 77
fi
if [ ! -f "$here/node_modules/@foxglove/ws-protocol/package.json" ] || [ ! -d "$here/node_modules/ws" ]; then
  echo "foxglove_node: skipped: the npm packages are missing (cd tests/foxglove && npm ci)"
  exit 77
fi
echo "foxglove_node: @foxglove/ws-protocol $(node -p "require('$here/node_modules/@foxglove/ws-protocol/package.json').version"), node $(node --version)"
export IRSLAM_BINARY_DIR=$build IRSLAM_SOURCE_DIR=$(cd "$here/../.." && pwd)
cd "$here"
exec node --test --test-reporter=spec foxglove.test.mjs
