#!/usr/bin/env bash
# The layering, checked on the includes (docs/architecture.md): each folder may
# include only the folders below it, and the pure core (types/, slam/, control/)
# nothing that reaches a clock, a socket, a file, a thread, the event loop, CAN
# frames or JSON. Exits 1 naming every offending line.
#   vcan-scripts/check-layers.sh [ROOT]     (CI runs it before the build)
set -euo pipefail
root=${1:-$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)}
cd "$root"

# folder -> the project folders it may include (besides itself).
declare -A allowed=(
  [types]=""
  [io]="types"
  [proto]="types"
  [slam]="types"
  [control]="types slam"
  [drivers]="types proto"
  [robot]="types proto drivers slam control"
  [daemon]="types io proto drivers slam control robot"
  [sim]="types io proto drivers slam control robot daemon"
)
# What the pure core must not include: the event loop, sockets, files, clocks,
# threads, CAN frames, JSON.
forbidden_pure='^#include <(boost/|asio|sys/|linux/|netinet/|arpa/|unistd\.h|fcntl\.h|fstream|iostream|cstdio|stdio\.h|chrono|ctime|time\.h|thread|mutex|future|condition_variable|random|filesystem|nlohmann/|gpiod)'

status=0
for dir in "${!allowed[@]}"; do
  [ -d "$dir" ] || continue
  while IFS= read -r hit; do
    file=${hit%%:*}
    rest=${hit#*:}
    line=${rest%%:*}
    inc=${rest#*:}
    target=$(sed -n 's/^#include "\([a-z_]*\)\/.*/\1/p' <<<"$inc")
    if [ -n "$target" ] && [ "$target" != "$dir" ] && ! grep -qw "$target" <<<"${allowed[$dir]}"; then
      echo "check-layers: $file:$line: $dir/ may not include $target/ ($inc)" >&2
      status=1
    fi
    case "$dir" in
      types|slam|control)
        if grep -Eq "$forbidden_pure" <<<"$inc"; then
          echo "check-layers: $file:$line: the pure core may not include ${inc#\#include } (clock, socket, file, thread, loop, CAN or JSON)" >&2
          status=1
        fi ;;
    esac
  done < <(grep -rn --include='*.h' --include='*.cc' '^#include' "$dir" || true)
done
if [ "$status" -eq 0 ]; then echo "check-layers: ok"; fi
exit $status
