#!/usr/bin/env python3
"""Checks a 3D Tiles tileset from outside lodstudio (issue 47), by hand:

1. `tileset.json` against the official 3D Tiles 1.1 JSON Schemas (the
   `specification/schema` folder of github.com/CesiumGS/3d-tiles), with
   `jsonschema` (draft 2020-12);
2. the rules of the 3D Tiles validator that the schemas cannot state: the
   asset version, a refinement on the root, geometric errors that never grow
   from a parent to a child or from the tileset to its root, content URIs
   that stay in the tileset's folder and name GLB files, and children's boxes
   inside their parent's (a warning, as the validator gives it);
3. with `--gltf-check SCRIPT`, every tile's GLB with the Khronos glTF
   validator (`../shared/tools/gltf_check.sh`).

The npm package of the 3D Tiles validator could not be installed here, so
this is what stands in for it. Prints one line of JSON; exit 0 when there
are no errors, 1 when there are, 2 when the input cannot be read.

    python3 scripts/tileset-check.py DIR/tileset.json --schema SCHEMA_DIR \
        [--gltf-check ../shared/tools/gltf_check.sh]
"""

import argparse
import json
import pathlib
import subprocess
import sys


def schema_validator(folder):
    """A draft 2020-12 validator for tileset.schema.json whose relative
    references resolve to the files of `folder`."""
    import jsonschema
    import referencing

    root = pathlib.Path(folder).resolve()
    base = "file://" + str(root) + "/"

    def retrieve(uri):
        path = pathlib.Path(uri.removeprefix("file://"))
        if root not in path.parents:
            raise referencing.exceptions.NoSuchResource(ref=uri)
        return referencing.Resource.from_contents(json.loads(path.read_text()))

    registry = referencing.Registry(retrieve=retrieve)
    top = json.loads((root / "tileset.schema.json").read_text())
    top["$id"] = base + "tileset.schema.json"
    return jsonschema.Draft202012Validator(top, registry=registry)


def box_corners(box):
    """The eight corners of an oriented box [centre, three half axes]."""
    c, axes = box[:3], [box[3:6], box[6:9], box[9:12]]
    for sx in (-1, 1):
        for sy in (-1, 1):
            for sz in (-1, 1):
                yield [c[i] + sx * axes[0][i] + sy * axes[1][i] + sz * axes[2][i] for i in range(3)]


def inside_box(point, box, slack):
    """Whether `point` lies in the oriented box, within `slack` per axis."""
    c, axes = box[:3], [box[3:6], box[6:9], box[9:12]]
    d = [point[i] - c[i] for i in range(3)]
    for a in axes:
        n2 = sum(x * x for x in a)
        if n2 == 0.0:
            if abs(sum(d[i] * a[i] for i in range(3))) > slack:
                return False
            continue
        n = n2 ** 0.5
        if abs(sum(d[i] * a[i] for i in range(3))) / n > n + slack:
            return False
    return True


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("tileset")
    ap.add_argument("--schema", required=True, help="3d-tiles specification/schema folder")
    ap.add_argument("--gltf-check", help="gltf_check.sh, to validate every tile's GLB")
    args = ap.parse_args()
    path = pathlib.Path(args.tileset)
    try:
        tileset = json.loads(path.read_text())
    except (OSError, ValueError) as e:
        print(f"error: {path}: {e}", file=sys.stderr)
        sys.exit(2)
    folder = path.parent.resolve()
    errors, warnings = [], []

    for e in schema_validator(args.schema).iter_errors(tileset):
        errors.append(f"schema: {'/'.join(map(str, e.absolute_path))}: {e.message}")

    if tileset.get("asset", {}).get("version") not in ("1.0", "1.1"):
        errors.append("asset.version is neither 1.0 nor 1.1")
    root = tileset.get("root", {})
    if "refine" not in root:
        errors.append("the root has no refine")
    if root.get("geometricError", 0.0) > tileset.get("geometricError", 0.0):
        errors.append("the root's geometricError is over the tileset's")

    tiles, contents, glbs = 0, 0, []
    stack = [(root, "root", None)]
    while stack:
        tile, where, parent = stack.pop()
        tiles += 1
        if parent is not None:
            if tile.get("geometricError", 0.0) > parent.get("geometricError", 0.0):
                errors.append(f"{where}: geometricError over its parent's")
            box, outer = tile.get("boundingVolume", {}).get("box"), parent.get("boundingVolume", {}).get("box")
            if box and outer:
                slack = 1e-5 * max(abs(x) for x in outer[3:]) + 1e-9
                if not all(inside_box(p, outer, slack) for p in box_corners(box)):
                    warnings.append(f"{where}: box not inside its parent's")
        content = tile.get("content")
        if content is not None:
            contents += 1
            uri = content.get("uri", "")
            target = (folder / uri).resolve()
            if "://" in uri or uri.startswith("/") or folder not in target.parents:
                errors.append(f"{where}: content {uri!r} leaves the tileset's folder")
            elif not target.is_file():
                errors.append(f"{where}: content {uri!r} is missing")
            elif target.read_bytes()[:4] != b"glTF":
                errors.append(f"{where}: content {uri!r} is not a GLB")
            else:
                glbs.append(target)
        for i, child in enumerate(tile.get("children", [])):
            stack.append((child, f"{where}/children/{i}", tile))

    gltf_errors = None
    if args.gltf_check:
        gltf_errors = 0
        for glb in glbs:
            out = subprocess.run(["bash", args.gltf_check, str(glb)], capture_output=True, text=True)
            report = json.loads(out.stdout) if out.stdout.strip() else {"errors": 1}
            if report.get("errors", 1) or report.get("warnings", 0):
                gltf_errors += 1
                errors.append(f"{glb.name}: glTF validator: {out.stdout.strip() or out.stderr.strip()}")

    print(json.dumps({
        "tileset": str(path),
        "tiles": tiles,
        "contents": contents,
        "glb_with_issues": gltf_errors,
        "errors": len(errors),
        "warnings": len(warnings),
        "first": (errors + warnings)[:10],
    }))
    sys.exit(1 if errors else 0)


if __name__ == "__main__":
    main()
