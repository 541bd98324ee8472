#!/usr/bin/env python3
"""Issue 48, item 2's peer table (by hand, not part of the suite): for each
model and triangle fraction, lodstudio `simplify` with `--topology keep` and
`--topology free`, meshoptimizer `simplify` (default and `Prune`) and
`simplifySloppy`, MeshLab's QEM and fast-simplification, every result judged
by the same independent two-sided Hausdorff measurement (`hausdorff.py`'s
`measure`: the larger of pymeshlab's and its own sampled lower bounds).
Prints a Markdown table: triangles reached and judged error (% of the
diagonal) per tool, and lodstudio's certified bound beside its error.

Run with the shared tools' Python (after `bash ../shared/tools/setup.sh`):

    ../shared/tools/.venv/bin/python scripts/topology-peers.py \\
        --tools ../shared/tools --lodstudio target/release/lodstudio \\
        ../shared/models/bones.off ../shared/models/2CylinderEngine.gltf
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("models", nargs="+")
    ap.add_argument("--tools", required=True, help="the shared tools' folder")
    ap.add_argument("--lodstudio", required=True, help="the lodstudio executable")
    ap.add_argument("--targets", default="0.1,0.01,0.0025")
    ap.add_argument("--samples", type=int, default=200_000)
    args = ap.parse_args()
    sys.path.insert(0, os.path.abspath(args.tools))
    import meshoptimizer
    import numpy as np
    from _common import compact, load_mesh, weld
    from hausdorff import measure
    from peers import PEERS, _meshopt

    def meshopt_prune(V, F, target):
        def fn(dest, idx, pos, **kw):
            return meshoptimizer.simplify(dest, idx, pos, options=meshoptimizer.SIMPLIFY_PRUNE, **kw)
        return _meshopt(fn, V, F, target)

    peers = dict(PEERS, meshopt_prune=meshopt_prune)
    order = ["meshopt_simplify", "meshopt_prune", "meshopt_sloppy", "pymeshlab_qem",
             "fast_simplification"]
    tmp = tempfile.mkdtemp()
    cols = ["lodstudio keep", "lodstudio free"] + order
    print("| model | % | asked | " + " | ".join(cols) + " |")
    print("|---|---|---|" + "---|" * len(cols))
    for model in args.models:
        V, F, _ = compact(*weld(*load_mesh(model)))
        V = np.ascontiguousarray(V)
        name = os.path.basename(model)
        for frac in [float(t) for t in args.targets.split(",")]:
            asked = max(1, int(round(frac * len(F))))
            cells = []
            for topology in ["keep", "free"]:
                out = os.path.join(tmp, f"{topology}.ply")
                t0 = time.perf_counter()
                run = subprocess.run([args.lodstudio, "simplify", model, "--triangles", str(asked),
                                      "--topology", topology, "-o", out, "--force", "--json"],
                                     capture_output=True, text=True)
                dt = time.perf_counter() - t0
                if run.returncode != 0:
                    cells.append("failed")
                    continue
                r = json.loads(run.stdout)
                V2, F2 = compact(*load_mesh(out))[:2]
                h = measure((V, F), (V2, F2), samples=args.samples, budget=200_000)
                cells.append(f"{r['output_triangles']}, {100 * h['hausdorff_relative']:.2f} % "
                             f"(bound {100 * r['error_bound_relative']:.2f} %), {dt:.1f} s")
            for peer in order:
                t0 = time.perf_counter()
                V2, F2, _ = peers[peer](V, F, asked)
                dt = time.perf_counter() - t0
                if len(F2) == 0:
                    cells.append("0 triangles")
                    continue
                h = measure((V, F), (V2, F2), samples=args.samples, budget=200_000)
                cells.append(f"{len(F2)}, {100 * h['hausdorff_relative']:.2f} %, {dt:.2f} s")
            print(f"| {name} | {100 * frac:g} | {asked} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
