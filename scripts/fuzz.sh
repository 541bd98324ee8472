#!/usr/bin/env bash
# Coverage-guided fuzzing of every reader (cargo-fuzz / libFuzzer on nightly).
#   scripts/fuzz.sh [SECONDS] [TARGET...]   default: 600 s per target, all targets
# JOBS=N runs N targets at once (default 1). Seeds: fuzz/seeds/, tests/malformed/
# and small models made from ../shared/models (LODSTUDIO_SHARED_MODELS). Prints
# per target: executions, seconds, corpus size and crashes (fuzz/artifacts/T/).
# A crash becomes a file in tests/malformed/ and a regression test (stable).
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER_TARGET="${1:-600}"; shift || true
ALL=(obj ply off gltf nrrd nifti inr raw hierarchy gzip algorithms)
TARGETS=("${@:-${ALL[@]}}")
JOBS="${JOBS:-1}"
SHARED="${LODSTUDIO_SHARED_MODELS:-../shared/models}"
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz
(cd fuzz && for t in "${TARGETS[@]}"; do cargo +nightly fuzz build -a -s none "$t" >/dev/null; done)
cargo build --release -q -p lodstudio
BIN=target/release/lodstudio

# Seed corpora (fuzz/corpus/ is not committed; libFuzzer adds to it as it runs).
gen="$(mktemp -d)"; trap 'rm -rf "$gen"' EXIT
if [ -d "$SHARED" ]; then
  $BIN simplify "$SHARED/fandisk.obj" --triangles 60 -o "$gen/fandisk.obj" --force >/dev/null
  $BIN simplify "$SHARED/couplingdown.off" --triangles 80 -o "$gen/coupling.ply" --force >/dev/null
  $BIN simplify "$SHARED/CesiumMilkTruck.glb" --triangles 120 -o "$gen/truck.glb" --force >/dev/null
  $BIN simplify "$gen/fandisk.obj" --triangles 20 -o "$gen/fandisk20.ply" --save "$gen/s.lodh" --force >/dev/null
  $BIN hybrid "$gen/fandisk.obj" --save "$gen/h.lodh" --force >/dev/null
  $BIN mergetree "$gen/fandisk.obj" --save "$gen/m.lodh" --force >/dev/null
  $BIN voxel "$gen/fandisk.obj" --resolution 8 --pyramid --save "$gen/v.lodh" --force >/dev/null
  head -c 2000 "$SHARED/knot2.off" > "$gen/knot_head.off"
fi
seed() { # seed TARGET FILE...
  mkdir -p "fuzz/corpus/$1"
  shift_t="$1"; shift
  for f in "$@"; do [ -f "$f" ] && cp "$f" "fuzz/corpus/$shift_t/$(basename "$f")"; done; return 0
}
shopt -s nullglob
for t in "${ALL[@]}"; do seed "$t" fuzz/seeds/"$t"/*; done
seed obj "$gen"/*.obj tests/malformed/*.obj
seed ply "$gen"/*.ply tests/malformed/*.ply
seed off "$gen"/*.off tests/malformed/*.off
seed gltf "$gen"/*.glb tests/malformed/*.gltf tests/malformed/*.glb
seed nrrd tests/malformed/*.nrrd
seed nifti tests/malformed/*.nii
seed inr tests/malformed/*.inr
seed algorithms "$gen"/*.obj "$gen"/*.off "$gen"/*.ply fuzz/seeds/ply/* fuzz/seeds/off/* tests/malformed/*
for f in "$gen"/*.obj "$gen"/*.off fuzz/seeds/ply/*; do gzip -c "$f" > "$gen/$(basename "$f").gz"; done
seed gzip "$gen"/*.gz tests/malformed/*.gz
# Hierarchy seeds: the method byte, then the saved body (framing stripped).
for f in "$gen"/*.lodh; do
  python3 - "$f" "fuzz/corpus/hierarchy/$(basename "$f").body" <<'PY'
import struct, sys
d = open(sys.argv[1], 'rb').read()
at = 12; n = struct.unpack_from('<H', d, at)[0]; method = d[at+2:at+2+n].decode(); at += 2 + n
p = struct.unpack_from('<I', d, at)[0]; at += 4 + p
b = struct.unpack_from('<Q', d, at)[0]; at += 8
# The order of lod::Method::ALL.
pick = ["simplify", "hybrid", "mergetree", "voxel", "amg"].index(method)
open(sys.argv[2], 'wb').write(bytes([pick]) + d[at:at+b])
PY
done

run_one() {
  local t="$1" log="fuzz/logs/$1.log" start=$SECONDS
  mkdir -p fuzz/logs "fuzz/artifacts/$t"
  # The binaries built above, run directly: edits made meanwhile do not rebuild them.
  (cd fuzz && "target/$TRIPLE/release/$t" "corpus/$t" -artifact_prefix="artifacts/$t/" \
      -max_total_time="$SECONDS_PER_TARGET" -timeout=10 -rss_limit_mb=2048 \
      -max_len=65536 -print_final_stats=1 -close_fd_mask=3) >"$log" 2>&1 || true
  local execs secs crashes
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  secs=$((SECONDS - start)) # wall time: a crash ends the run early
  crashes=$(ls "fuzz/artifacts/$t" | wc -l)
  printf '%-11s executions %-10s seconds %-5s corpus %-6s crashes %s\n' \
    "$t" "$execs" "$secs" "$(ls "fuzz/corpus/$t" | wc -l)" "$crashes"
}
TRIPLE="$(rustc +nightly -vV | sed -n 's/^host: //p')"
export -f run_one; export SECONDS_PER_TARGET TRIPLE
printf '%s\n' "${TARGETS[@]}" | xargs -P "$JOBS" -I{} bash -c 'run_one {}'
