#!/usr/bin/env bash
# Issue 27 benchmark: batch throughput over the shared meshes (models per
# minute, input triangles per second) at 1 and 2 worker threads, and the
# rerun that finds everything in the cache. Release build; prints a Markdown
# table for BENCHMARKS.md. LODS=... picks the chain (default three
# edge-collapse rows); MODELS=DIR another shared/models.
set -euo pipefail
cd "$(dirname "$0")/.."
MODELS=${MODELS:-../shared/models}
LODS=${LODS:-simplify:0.5%,simplify:2%,simplify:8%}
cargo build --release -q -p lodstudio --bin lodstudio
BIN=$PWD/target/release/lodstudio
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
# The triangle meshes among the shared models (point clouds and volumes aside).
for m in bones.off couplingdown.off fandisk.obj knot2.off rocker-arm.obj horse.ply \
         stanford-bunny.obj CesiumMilkTruck.glb 2CylinderEngine.gltf dragon_vrip.ply.gz; do
  echo "$(realpath "$MODELS/$m")"
done > "$WORK/manifest.txt"
# The dragon alone takes most of a run; without it the workers' scaling shows.
grep -v dragon "$WORK/manifest.txt" > "$WORK/small.txt"
row() { # threads, out dir, label, manifest
  local start end
  start=$(date +%s.%N)
  "$BIN" export --manifest "$4" --lods "$LODS" -o "$2" --threads "$1" --json > "$WORK/summary.json"
  end=$(date +%s.%N)
  python3 - "$WORK/summary.json" "$start" "$end" "$1" "$3" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
s = float(sys.argv[3]) - float(sys.argv[2])
tris = sum(r.get("input_triangles") or 0 for r in j["reports"])
peak = max((r.get("peak_memory_bytes") or 0) for r in j["reports"])
print(f"| {sys.argv[5]} | {sys.argv[4]} | {j['models']} | {j['built']} | {j['skipped']} | {s:.2f} | "
      f"{60 * j['models'] / s:.1f} | {tris / s:,.0f} | {peak / 2**20:.0f} |")
PY
}
echo "chain: $LODS; $(nproc) cores; $(date -u +%F)"
echo
echo "| run | threads | models | built | skipped | wall s | models/min | input triangles/s | largest peak MiB |"
echo "|---|---|---|---|---|---|---|---|---|"
row 1 "$WORK/out1" "cold" "$WORK/manifest.txt"
row 2 "$WORK/out2" "cold" "$WORK/manifest.txt"
row 2 "$WORK/out2" "rerun, all cached" "$WORK/manifest.txt"
row 1 "$WORK/small1" "cold, without the dragon" "$WORK/small.txt"
row 2 "$WORK/small2" "cold, without the dragon" "$WORK/small.txt"
cmp -s <(cd "$WORK/out1" && cat *.glb | sha256sum) <(cd "$WORK/out2" && cat *.glb | sha256sum) \
  && echo && echo "1 and 2 threads wrote identical bytes."
