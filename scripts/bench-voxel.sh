#!/usr/bin/env bash
# Issue 6 benchmark: our voxel stages, then scikit-image's marching cubes on the
# very same 256³ density (Python is used for the peer only, never by the tests).
# Needs ../shared/tools set up (bash ../shared/tools/setup.sh); TOOLS=DIR picks
# another copy of those tools.
set -euo pipefail
cd "$(dirname "$0")/.."
TOOLS=${TOOLS:-../shared/tools}
RAW=${TMPDIR:-/tmp}/lodstudio-dragon-density.f32
LODSTUDIO_BENCH_RAW=$RAW cargo bench -p lodstudio-core --bench voxel | tee /tmp/lodstudio-bench-voxel.txt
dims=$(grep -o 'dims [0-9]* [0-9]* [0-9]*' /tmp/lodstudio-bench-voxel.txt | tail -1 | cut -d' ' -f2-)
echo
echo "scikit-image marching_cubes (lewiner) on the same volume:"
python3 "$TOOLS/mc_ref.py" "$RAW" --dims $dims --dtype '<f4' --level 0.5 |
    python3 -c 'import json,sys; j=json.load(sys.stdin); print("  %.3f s, %d triangles, genus %d" % (j["seconds"], j["faces"], j["genus"]))'
