#!/usr/bin/env python3
"""Issue 47's large inputs (by hand, not part of the suite; not committed):
COPIES copies of the shared dragon on a square grid, each turned about the
vertical axis and shifted by a seeded jitter, as one binary little-endian
PLY. 12 copies make 10,456,968 triangles (~10⁷), 115 make ~10⁸.

    python3 scripts/large-scan.py ../shared/models/dragon_vrip.ply.gz 12 /tmp/dragons-12.ply
"""

import gzip
import math
import random
import struct
import sys


def read_ascii_ply(path):
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rt") as f:
        nv = nf = 0
        for line in f:
            if line.startswith("element vertex"):
                nv = int(line.split()[2])
            elif line.startswith("element face"):
                nf = int(line.split()[2])
            elif line.startswith("end_header"):
                break
        verts = [tuple(map(float, next(f).split()[:3])) for _ in range(nv)]
        faces = []
        for _ in range(nf):
            p = next(f).split()
            if p[0] == "3":
                faces.append((int(p[1]), int(p[2]), int(p[3])))
    return verts, faces


def main():
    src, copies, dst = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    verts, faces = read_ascii_ply(src)
    xs = [v[0] for v in verts]
    zs = [v[2] for v in verts]
    step = 1.2 * max(max(xs) - min(xs), max(zs) - min(zs))
    side = math.ceil(math.sqrt(copies))
    rng = random.Random(47)
    vbytes = bytearray()
    fbytes = bytearray()
    for c in range(copies):
        angle = rng.uniform(0.0, 2.0 * math.pi)
        ca, sa = math.cos(angle), math.sin(angle)
        ox = (c % side) * step + rng.uniform(-0.1, 0.1) * step
        oz = (c // side) * step + rng.uniform(-0.1, 0.1) * step
        for x, y, z in verts:
            vbytes += struct.pack("<3f", ca * x + sa * z + ox, y, -sa * x + ca * z + oz)
        base = c * len(verts)
        for a, b, d in faces:
            fbytes += struct.pack("<B3i", 3, a + base, b + base, d + base)
    head = (
        "ply\nformat binary_little_endian 1.0\n"
        f"element vertex {copies * len(verts)}\nproperty float x\nproperty float y\nproperty float z\n"
        f"element face {copies * len(faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    with open(dst, "wb") as f:
        f.write(head.encode())
        f.write(vbytes)
        f.write(fbytes)
    print(f"{copies} copies: {copies * len(faces)} triangles -> {dst}")


if __name__ == "__main__":
    main()
