#!/usr/bin/env bash
# How long three.js takes to load a GLB and draw its first frame, and how
# many meshes and draw calls it makes, in headless Chromium (by hand, not
# part of the suite; BENCHMARKS.md records what it printed).
#
#   bash scripts/threejs-load.sh OUT1.glb [OUT2.glb ...]
#
# Needs Debian's chromium (`apt-get install chromium`) and npm; installs
# three.js r170 and playwright-core into a temporary folder.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
work="$(mktemp -d)"
trap 'kill "${server:-0}" 2>/dev/null || true; rm -rf "$work"' EXIT
cp "$here/threejs/load.html" "$here/threejs/run.js" "$work/"
names=()
for f in "$@"; do
  cp "$f" "$work/"
  names+=("$(basename "$f")")
done
(cd "$work" && npm install --silent three@0.170.0 playwright-core@1.49.0 >/dev/null)
(cd "$work" && exec python3 -m http.server 8765 --bind 127.0.0.1 >/dev/null 2>&1) &
server=$!
sleep 1
(cd "$work" && node run.js "${names[@]}" 2> >(grep -v 'status of 404' >&2))
