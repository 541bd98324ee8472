#!/usr/bin/env bash
# A measured studio session in a real window (Xvfb, Mesa lavapipe): opens
# MODEL, picks the method at y = METHOD_Y in the left panel (hybrid 342, merge
# tree 365, voxel 388, AMG 411 at 1280×800; auto rebuild then starts the
# build), and orbits the camera by dragging (300 px right and back, every two
# seconds, so the pointer stays in the window and the camera keeps moving) for
# ORBIT_S seconds while the build runs, then again for ORBIT_S seconds after it
# ended. Prints the studio's per-second frame
# statistics (LODSTUDIO_FRAME_STATS) with a phase label. Not part of the test
# suite; needs Xvfb and xdotool. Usage:
#   scripts/studio-session.sh target/release/lodstudio MODEL [METHOD_Y] [ORBIT_S] [BUILD_WAIT_S]
set -euo pipefail
bin=$1 model=$2 method_y=${3:-342} orbit_s=${4:-10} wait_s=${5:-600}
export DISPLAY=${DISPLAY:-:97}
if ! xdpyinfo >/dev/null 2>&1; then
  Xvfb "$DISPLAY" -screen 0 1280x800x24 >/dev/null 2>&1 &
  xvfb=$!
  trap 'kill $xvfb 2>/dev/null || true' EXIT
  sleep 2
fi
cfg=$(mktemp -d)
log=$cfg/frames.log
XDG_DATA_HOME=$cfg XDG_CONFIG_HOME=$cfg LODSTUDIO_FRAME_STATS=1 "$bin" open "$model" 2>"$log" &
app=$!
trap 'kill $app 2>/dev/null || true; kill ${xvfb:-0} 2>/dev/null || true' EXIT
sleep 8
orbit() { # one xdotool process: 100 moves per second, 1 s right then 1 s left
  local steps=$(($1 * 100)) chain=() dx
  for ((i = 0; i < steps; i++)); do
    dx=$((i / 100 % 2 == 0 ? 3 : -3))
    chain+=(mousemove_relative -- "$dx" 0 sleep 0.01)
  done
  xdotool mousemove 500 380 mousedown 1 "${chain[@]}" mouseup 1
}
xdotool mousemove 90 "$method_y" click 1
sleep 2
echo "phase build-start $(wc -l <"$log")"
orbit "$orbit_s"
echo "phase build-end $(wc -l <"$log")"
# Wait for the build to finish: the studio stops reporting "building true".
for ((t = 0; t < wait_s; t++)); do
  sleep 1
  tail -n 1 "$log" | grep -q "building true" || break
done
echo "phase idle-start $(wc -l <"$log")"
orbit "$orbit_s"
echo "phase idle-end $(wc -l <"$log")"
cat "$log"
