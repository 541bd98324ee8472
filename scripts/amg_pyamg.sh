#!/usr/bin/env bash
# The PyAMG peer of core/benches/amg.rs: Ruge–Stüben setup on the same
# MatrixMarket stiffness matrices (written by `lodstudio amg FILE --matrix-out A.mtx`),
# at the settings of lodstudio's coarsening (θ = 0.5, classical −a_ij strength,
# RS splitting, direct interpolation, at most 8 unknowns on the coarsest level).
# Not part of the test suite. Usage: scripts/amg_pyamg.sh A.mtx [B.mtx ...]
set -euo pipefail
tools="${LODSTUDIO_TOOLS:-$(dirname "$0")/../../shared/tools}"
for m in "$@"; do
  python3 "$tools/amg_ref.py" "$m" --theta 0.5 --strength-norm min --cf RS \
    --interpolation direct --max-coarse 8 |
    python3 -c 'import json,sys; j=json.load(sys.stdin); print(sys.argv[1], j["level_sizes"], "setup %.3f s" % j["seconds_setup"])' "$m"
done
