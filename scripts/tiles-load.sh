#!/usr/bin/env bash
# Loads tilesets that `lodstudio tiles` wrote in three.js' 3d-tiles-renderer
# (headless Chromium) and prints, for a camera at 200, 20, 4 and 1.2 radii of
# the root's bounding sphere, the tiles drawn, their geometricErrors, the
# triangles and draw calls, and any load error (by hand, not part of the
# suite; the closing note of issue 47 records what it printed).
#
#   bash scripts/tiles-load.sh DIR1 [DIR2 ...]
#
# Needs Debian's chromium and npm; installs three.js r170, 3d-tiles-renderer
# 0.5.3 and playwright-core into a temporary folder.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
work="$(mktemp -d)"
trap 'kill "${server:-0}" 2>/dev/null || true; rm -rf "$work"' EXIT
cp "$here/threejs/tiles.html" "$here/threejs/run.js" "$work/"
names=()
for d in "$@"; do
  name="$(basename "$d")"
  cp -r "$d" "$work/$name"
  names+=("$name/tileset.json")
done
(cd "$work" && npm install --silent three@0.170.0 3d-tiles-renderer@0.5.3 playwright-core@1.49.0 >/dev/null)
(cd "$work" && exec python3 -m http.server 8765 --bind 127.0.0.1 >/dev/null 2>&1) &
server=$!
sleep 1
(cd "$work" && PAGE=tiles.html node run.js "${names[@]}")
