#!/usr/bin/env python3
"""Issue 48's open, many-piece scan for the hybrid and voxel timings (by
hand, not part of the suite): the shared dragon simplified to 56 % by
lodstudio (487,930 triangles, certified), its bottom 3 % cut open and the
rest split by twelve thin slabs (nine across x, three across z; a triangle
that meets a slab is dropped). The result: 413,504 triangles, 106
components, 124 boundary loops, genus 39 (`lodstudio info`).

    python3 scripts/open-scan.py --lodstudio target/release/lodstudio \\
        ../shared/models/dragon_vrip.ply.gz /tmp/open-scan.ply
"""

import argparse
import os
import struct
import subprocess
import tempfile


def read_ply(path):
    """Vertices and triangles of a binary little-endian PLY as lodstudio writes it."""
    data = open(path, "rb").read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    head = data[:end].decode()
    nv = int(head.split("element vertex ")[1].split()[0])
    nf = int(head.split("element face ")[1].split()[0])
    verts = list(struct.iter_unpack("<3f", data[end:end + 12 * nv]))
    off = end + 12 * nv
    faces = []
    for _ in range(nf):
        assert data[off] == 3, "triangles only"
        faces.append(struct.unpack_from("<3i", data, off + 1))
        off += 13
    return verts, faces


def slabs(values, count, width):
    """`count` slabs evenly inside the range of `values`, each `width` of it wide."""
    lo, hi = min(values), max(values)
    return [(lo + (hi - lo) * (i + 1) / (count + 1), width * (hi - lo)) for i in range(count)]


def cut(verts, faces):
    xs, ys, zs = ([v[k] for v in verts] for k in range(3))
    bottom = min(ys) + 0.03 * (max(ys) - min(ys))
    planes = [(0, s) for s in slabs(xs, 9, 0.0015)] + [(2, s) for s in slabs(zs, 3, 0.002)]
    kept = []
    for f in faces:
        p = [verts[i] for i in f]
        if min(q[1] for q in p) < bottom:
            continue
        if any(min(q[k] for q in p) < c + w and max(q[k] for q in p) > c - w for k, (c, w) in planes):
            continue
        kept.append(f)
    return kept


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lodstudio", default="target/release/lodstudio")
    ap.add_argument("dragon")
    ap.add_argument("output")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        half = os.path.join(tmp, "dragon-56.ply")
        subprocess.run(
            [args.lodstudio, "simplify", args.dragon, "--ratio", "0.56", "-o", half],
            check=True,
            stdout=subprocess.DEVNULL,
        )
        verts, faces = read_ply(half)
    kept = cut(verts, faces)
    head = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {len(kept)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    out = bytearray(head.encode())
    for v in verts:
        out += struct.pack("<3f", *v)
    for f in kept:
        out += struct.pack("<B3i", 3, *f)
    with open(args.output, "wb") as f:
        f.write(out)
    print(f"{len(faces)} -> {len(kept)} triangles: {args.output}")


if __name__ == "__main__":
    main()
