#!/usr/bin/env bash
# Writes the same exports of the shared models with two lodstudio binaries
# and compares them byte for byte: what changing the build path (or anything
# else that should not change outputs) must leave alone.
#
#   scripts/same-exports.sh OLD_BIN NEW_BIN [WORK_DIR]
#
# Prints one line per output: "same", or "DIFFERS" with both sizes. Exit 0
# when every output is the same, 1 otherwise. Runs in ~2 min (release).
set -uo pipefail
old=$1 new=$2
work=${3:-$(mktemp -d)}
mkdir -p "$work"
m=$(cd "$(dirname "$0")/../../shared/models" && pwd)

run_all() {
  local bin=$1 out=$2
  mkdir -p "$out"
  local q=(--json --force)
  "$bin" simplify "$m/fandisk.obj" --ratio 0.1 -o "$out/simplify.glb" --save "$out/simplify.lodh" "${q[@]}"
  "$bin" simplify "$m/stanford-bunny.obj" --error 0.5% --lock-borders -o "$out/bunny.ply" "${q[@]}"
  "$bin" hybrid "$m/fandisk.obj" --cut-error 1% -o "$out/hybrid.glb" --curve "$out/hybrid.csv" --save "$out/hybrid.lodh" "${q[@]}"
  "$bin" mergetree "$m/fandisk.obj" --frames 5 -o "$out/mergetree.ply" --save "$out/mergetree.lodh" "${q[@]}"
  "$bin" voxel "$m/fandisk.obj" --resolution 48 --radius 1.5 -o "$out/voxel.ply" "${q[@]}"
  "$bin" voxel "$m/fandisk.obj" --resolution 32 --layers-error 0.05 -o "$out/layers.glb" "${q[@]}"
  "$bin" voxel "$m/fandisk.obj" --pyramid --resolution 48 -o "$out/pyramid" --save "$out/pyramid.lodh" "${q[@]}"
  "$bin" voxel "$m/skull_2.9.inr" --radius 1 -o "$out/skull.ply" "${q[@]}"
  "$bin" amg "$m/fandisk.obj" -o "$out/amg.glb" --save "$out/amg.lodh" "${q[@]}"
  "$bin" amg "$m/fandisk.obj" --k 30 --texel 0.01 --level 2 -o "$out/amg-texel.glb" "${q[@]}"
  "$bin" export "$m/fandisk.obj" --lods simplify:0.5,hybrid:1%,mergetree:2%,amg:20% -o "$out/chain.glb" "${q[@]}"
  "$bin" export "$m/CesiumMilkTruck.glb" --method simplify --lods 0.5,0.1 -o "$out/truck.glb" "${q[@]}"
  "$bin" export "$m/fandisk.obj" --lods voxel:2% -o "$out/chain-voxel.glb" "${q[@]}"
  "$bin" voxel "$m/fandisk.obj" -o "$out/voxel-default.ply" "${q[@]}"
}

run_all "$old" "$work/old" >"$work/old.log" 2>&1
run_all "$new" "$work/new" >"$work/new.log" 2>&1
status=0
while IFS= read -r f; do
  rel=${f#"$work/old/"}
  if cmp -s "$f" "$work/new/$rel"; then
    echo "same     $rel"
  else
    echo "DIFFERS  $rel ($(stat -c %s "$f") vs $(stat -c %s "$work/new/$rel" 2>/dev/null || echo missing) bytes)"
    status=1
  fi
done < <(find "$work/old" -type f | sort)
exit $status
