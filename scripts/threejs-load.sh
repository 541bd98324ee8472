#!/usr/bin/env bash
# Loads what lodstudio wrote in three.js, in headless Chromium (by hand, not
# part of the suite; BENCHMARKS.md and the closing notes record what it
# printed):
# - GLBs: how long GLTFLoader takes to load each and draw its first frame,
#   and how many meshes and draw calls it makes;
# - tileset folders (`lodstudio tiles`): 3d-tiles-renderer 0.5.3 with a
#   camera at 200, 20, 4 and 1.2 radii of the root's bounding sphere, the
#   tiles drawn, their geometricErrors, triangles, draw calls and any load
#   error.
#
#   bash scripts/threejs-load.sh OUT1.glb [OUT2.glb ...]
#   bash scripts/threejs-load.sh TILESET_DIR1 [TILESET_DIR2 ...]
#
# Needs Debian's chromium (`apt-get install chromium`) and npm; installs
# three.js r170, 3d-tiles-renderer and playwright-core into a temporary
# folder.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
work="$(mktemp -d)"
trap 'kill "${server:-0}" 2>/dev/null || true; rm -rf "$work"' EXIT
cp "$here/threejs/load.html" "$here/threejs/tiles.html" "$here/threejs/run.js" "$work/"
page=load.html
names=()
for f in "$@"; do
  name="$(basename "$f")"
  cp -r "$f" "$work/$name"
  if [ -d "$f" ]; then
    page=tiles.html
    names+=("$name/tileset.json")
  else
    names+=("$name")
  fi
done
(cd "$work" && npm install --silent three@0.170.0 3d-tiles-renderer@0.5.3 playwright-core@1.49.0 >/dev/null)
(cd "$work" && exec python3 -m http.server 8765 --bind 127.0.0.1 >/dev/null 2>&1) &
server=$!
sleep 1
(cd "$work" && PAGE="$page" node run.js "${names[@]}" 2> >(grep -v 'status of 404' >&2))
