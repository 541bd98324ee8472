//! Exported LODs as a real glTF client sees them (issue 30): textures on
//! the right side of every UV seam, normals on the front of their faces, no
//! vertex attribute the input did not have, and points a plain client can see.
//! The GLB is read back raw (accessors by hand), not through the exporter's
//! own structures.

use std::collections::BTreeMap;

use glam::Vec3;
use lodstudio_tests::{load_mesh, lod_meshes, lodstudio, lodstudio_json, shared_model};
use serde_json::Value;

/// A glTF document and its binary buffer (GLB, or `.gltf` with one `.bin`).
fn read_gltf(path: &std::path::Path) -> (Value, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    if &bytes[0..4] == b"glTF" {
        let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        let doc: Value = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
        let at = 20 + len;
        let bin_len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        (doc, bytes[at + 8..at + 8 + bin_len].to_vec())
    } else {
        let doc: Value = serde_json::from_slice(&bytes).unwrap();
        let uri = doc["buffers"][0]["uri"].as_str().unwrap();
        let bin = std::fs::read(path.parent().unwrap().join(uri)).unwrap();
        (doc, bin)
    }
}

/// The floats (or integer indices, as f64) of accessor `i`, `width` per element.
fn accessor(doc: &Value, bin: &[u8], i: u64) -> (Vec<f64>, usize) {
    let a = &doc["accessors"][i as usize];
    let v = &doc["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let width = match a["type"].as_str().unwrap() {
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" => 4,
        _ => 1,
    };
    let (size, read): (usize, fn(&[u8]) -> f64) = match a["componentType"].as_u64().unwrap() {
        5126 => (4, |b| f32::from_le_bytes(b.try_into().unwrap()) as f64),
        5125 => (4, |b| u32::from_le_bytes(b.try_into().unwrap()) as f64),
        5123 => (2, |b| u16::from_le_bytes(b.try_into().unwrap()) as f64),
        _ => (1, |b| b[0] as f64),
    };
    let start = v["byteOffset"].as_u64().unwrap_or(0) as usize
        + a["byteOffset"].as_u64().unwrap_or(0) as usize;
    let stride = v["byteStride"]
        .as_u64()
        .map_or(size * width, |s| s as usize);
    let count = a["count"].as_u64().unwrap() as usize;
    let mut out = Vec::with_capacity(count * width);
    for e in 0..count {
        for k in 0..width {
            let at = start + e * stride + k * size;
            out.push(read(&bin[at..at + size]));
        }
    }
    (out, width)
}

/// Fraction of a triangle primitive's area with a corner normal pointing
/// behind its face.
fn area_against_winding(doc: &Value, bin: &[u8], prim: &Value) -> f64 {
    let (p, _) = accessor(doc, bin, prim["attributes"]["POSITION"].as_u64().unwrap());
    let (n, _) = accessor(doc, bin, prim["attributes"]["NORMAL"].as_u64().unwrap());
    let (idx, _) = accessor(doc, bin, prim["indices"].as_u64().unwrap());
    let v3 =
        |a: &[f64], i: usize| Vec3::new(a[3 * i] as f32, a[3 * i + 1] as f32, a[3 * i + 2] as f32);
    let (mut bad, mut total) = (0.0, 0.0);
    for t in idx.chunks_exact(3) {
        let c = t.iter().map(|x| *x as usize).collect::<Vec<_>>();
        let f = (v3(&p, c[1]) - v3(&p, c[0])).cross(v3(&p, c[2]) - v3(&p, c[0]));
        let area = 0.5 * f.length() as f64;
        total += area;
        if c.iter().any(|&i| v3(&n, i).dot(f) < 0.0) {
            bad += area;
        }
    }
    if total > 0.0 { bad / total } else { 0.0 }
}

/// The optional attributes (`COLOR_0`, `TEXCOORD_0`) of the triangle
/// primitives of the given meshes, by material name.
fn attributes_by_material(doc: &Value, meshes: &[usize]) -> BTreeMap<String, Vec<String>> {
    let mut out = BTreeMap::new();
    for &m in meshes {
        for p in doc["meshes"][m]["primitives"].as_array().unwrap() {
            if p["mode"].as_u64().unwrap_or(4) != 4 {
                continue;
            }
            let material = p["material"].as_u64().map_or("none".to_string(), |i| {
                doc["materials"][i as usize]["name"]
                    .as_str()
                    .unwrap_or("unnamed")
                    .to_string()
            });
            let attrs: Vec<String> = ["COLOR_0", "TEXCOORD_0"]
                .iter()
                .filter(|a| p["attributes"].get(**a).is_some())
                .map(|a| a.to_string())
                .collect();
            out.insert(material, attrs);
        }
    }
    out
}

fn export(model: &str, method: &str, out: &std::path::Path, extra: &[&str]) -> Value {
    let file = shared_model(model);
    let mut args = vec![
        "export",
        file.to_str().unwrap(),
        "--method",
        method,
        "--lods",
        "0.5%,2%,8%",
        "-o",
        out.to_str().unwrap(),
        "--force",
    ];
    args.extend_from_slice(extra);
    lodstudio_json(&args)
}

#[test]
fn truck_textures_stay_on_their_side_of_every_seam() {
    let tmp = tempfile::tempdir().unwrap();
    let truck = shared_model("CesiumMilkTruck.glb");
    let original = load_mesh(&truck);
    let (src_doc, _) = read_gltf(&truck);
    let src_meshes: Vec<usize> = (0..src_doc["meshes"].as_array().unwrap().len()).collect();
    let src_attrs = attributes_by_material(&src_doc, &src_meshes);
    for method in ["simplify", "hybrid", "mergetree"] {
        let out = tmp.path().join(format!("truck-{method}.glb"));
        let report = export("CesiumMilkTruck.glb", method, &out, &[]);
        let (doc, bin) = read_gltf(&out);
        let lods = report["lods"].as_array().unwrap();
        for (l, lod) in lods.iter().enumerate() {
            // The reported UV error: the texture lands where it did.
            let uv = &lod["uv_error"];
            assert!(
                uv["area_over_threshold"].as_f64().unwrap() < 0.01,
                "{method} LOD {l}: {uv}"
            );
            // In texels too: 2,048 per UV unit on the textured faces (the
            // truck's 2048² texture), 1,024 on the untextured.
            let (texels, mean) = (
                uv["mean_texels"].as_f64().unwrap(),
                uv["mean"].as_f64().unwrap(),
            );
            assert!(
                texels >= 1024.0 * mean - 1e-6 && texels <= 2048.0 * mean + 1e-6,
                "{method} LOD {l}: {uv}"
            );
            let meshes = lod_meshes(&doc, l);
            for p in meshes
                .iter()
                .flat_map(|&m| doc["meshes"][m]["primitives"].as_array().unwrap())
            {
                if p["mode"].as_u64().unwrap_or(4) == 4 {
                    assert_eq!(area_against_winding(&doc, &bin, p), 0.0, "{method} LOD {l}");
                }
            }
            // Exactly the input's optional attributes, material by material.
            let attrs = attributes_by_material(&doc, &meshes);
            for (m, a) in &attrs {
                assert_eq!(Some(a), src_attrs.get(m), "{method} LOD {l} material {m}");
            }
        }
        // LOD0 read back through the ordinary reader (a client's view): its
        // UVs against the original's, measured afresh.
        let back = load_mesh(&out);
        let e = lodstudio_core::distance::uv_error(&original, &back, 0.0).unwrap();
        assert!(e.area_over_threshold < 0.01, "{method}: {e:?}");
    }
}

#[test]
fn engine_normals_face_their_triangles_and_gain_no_colours() {
    let tmp = tempfile::tempdir().unwrap();
    let engine = shared_model("2CylinderEngine.gltf");
    let (src_doc, src_bin) = read_gltf(&engine);
    let n_meshes = src_doc["meshes"].as_array().unwrap().len();
    // The original agrees with its winding: what the LODs must keep.
    for m in 0..n_meshes {
        for p in src_doc["meshes"][m]["primitives"].as_array().unwrap() {
            assert_eq!(area_against_winding(&src_doc, &src_bin, p), 0.0);
        }
    }
    let src_attrs = attributes_by_material(&src_doc, &(0..n_meshes).collect::<Vec<_>>());
    for method in ["simplify", "hybrid", "mergetree"] {
        let out = tmp.path().join(format!("engine-{method}.glb"));
        let report = export(
            "2CylinderEngine.gltf",
            method,
            &out,
            &["--points-as", "discs"],
        );
        let (doc, bin) = read_gltf(&out);
        for l in 0..report["lods"].as_array().unwrap().len() {
            let meshes = lod_meshes(&doc, l);
            for p in meshes
                .iter()
                .flat_map(|&m| doc["meshes"][m]["primitives"].as_array().unwrap())
            {
                assert_eq!(p["mode"].as_u64(), Some(4), "discs: no POINTS primitive");
                assert_eq!(area_against_winding(&doc, &bin, p), 0.0, "{method} LOD {l}");
            }
            for (m, a) in attributes_by_material(&doc, &meshes) {
                if m == "points" {
                    continue;
                }
                assert_eq!(Some(&a), src_attrs.get(&m), "{method} LOD {l} material {m}");
            }
        }
    }
}

/// The horse carries per-vertex normals (PLY nx ny nz) and nothing else:
/// every LOD's normals face its triangles and no LOD gains colours or UVs
/// (the hybrid's points, as discs, are the method's own).
#[test]
fn horse_normals_face_their_triangles_and_gain_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    for method in ["simplify", "hybrid", "mergetree"] {
        let out = tmp.path().join(format!("horse-{method}.glb"));
        let report = export("horse.ply", method, &out, &["--points-as", "discs"]);
        let (doc, bin) = read_gltf(&out);
        let lods = report["lods"].as_array().unwrap().len();
        assert_eq!(lods, 3, "{method}");
        for l in 0..lods {
            let meshes = lod_meshes(&doc, l);
            for p in meshes
                .iter()
                .flat_map(|&m| doc["meshes"][m]["primitives"].as_array().unwrap())
            {
                assert_eq!(p["mode"].as_u64().unwrap_or(4), 4, "{method} LOD {l}");
                assert_eq!(area_against_winding(&doc, &bin, p), 0.0, "{method} LOD {l}");
            }
            for (m, a) in attributes_by_material(&doc, &meshes) {
                if m != "points" {
                    assert!(a.is_empty(), "{method} LOD {l} material {m}: {a:?}");
                }
            }
        }
    }
}

#[test]
fn points_say_what_radius_means_or_become_covering_meshes() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("bones-points.glb");
    let report = export("bones.off", "hybrid", &out, &[]);
    let points: u64 = report["lods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["points"].as_u64().unwrap())
        .sum();
    assert!(points > 0, "the hybrid chain has points");
    let (doc, bin) = read_gltf(&out);
    // The first point's radius in each LOD (POINTS primitives carry `_RADIUS`).
    let mut first_radius = Vec::new();
    for l in 0..report["lods"].as_array().unwrap().len() {
        let meshes = lod_meshes(&doc, l);
        let p = meshes
            .iter()
            .flat_map(|&m| doc["meshes"][m]["primitives"].as_array().unwrap())
            .find(|p| p["mode"] == 0);
        first_radius.push(p.map(|p| {
            assert!(p["extras"]["_RADIUS"].as_str().unwrap().contains("radius"));
            accessor(&doc, &bin, p["attributes"]["_RADIUS"].as_u64().unwrap()).0[0]
        }));
    }
    assert!(first_radius.iter().any(Option::is_some));
    // Quads and discs: 4 and 8 triangles per point, and the polygon covers
    // the point's disc (its edges are at least the radius from the centre).
    for (how, per_point) in [("quads", 4u64), ("discs", 8)] {
        let out = tmp.path().join(format!("bones-{how}.glb"));
        let r = export("bones.off", "hybrid", &out, &["--points-as", how]);
        let (doc, bin) = read_gltf(&out);
        for (l, lod) in r["lods"].as_array().unwrap().iter().enumerate() {
            let meshes = lod_meshes(&doc, l);
            assert_eq!(meshes.len(), 1, "one model, one mesh per LOD");
            let prims = doc["meshes"][meshes[0]]["primitives"].as_array().unwrap();
            assert!(
                prims.iter().all(|p| p["mode"] == 4),
                "{how}: no POINTS left"
            );
            let point_prim = prims.iter().find(|p| {
                doc["materials"][p["material"].as_u64().unwrap() as usize]["name"] == "points"
            });
            let n = lod["points"].as_u64().unwrap();
            let Some(p) = point_prim else {
                assert_eq!(n, 0);
                continue;
            };
            let (idx, _) = accessor(&doc, &bin, p["indices"].as_u64().unwrap());
            assert_eq!(idx.len() as u64 / 3, n * per_point, "{how} LOD {l}");
            let (pos, _) = accessor(&doc, &bin, p["attributes"]["POSITION"].as_u64().unwrap());
            let v = |i: f64| {
                let i = i as usize;
                Vec3::new(
                    pos[3 * i] as f32,
                    pos[3 * i + 1] as f32,
                    pos[3 * i + 2] as f32,
                )
            };
            // The first point's fan: centre, then its rim's corners.
            let centre = v(idx[0]);
            let radius = first_radius[l].expect("same points as the POINTS export") as f32;
            for t in idx[..3 * per_point as usize].chunks_exact(3) {
                assert_eq!(v(t[0]), centre);
                let edge_mid = (v(t[1]) + v(t[2])) * 0.5;
                assert!(
                    edge_mid.distance(centre) >= radius * (1.0 - 1e-4),
                    "{how} LOD {l}"
                );
            }
        }
    }
    // A value that is none of them is bad input.
    let file = shared_model("2CylinderEngine.gltf");
    let o = lodstudio(&[
        "export",
        file.to_str().unwrap(),
        "--method",
        "hybrid",
        "--lods",
        "1%",
        "-o",
        tmp.path().join("bad.glb").to_str().unwrap(),
        "--points-as",
        "blobs",
    ]);
    assert_eq!(o.status.code(), Some(2));
}

/// `measure` reports the share of B's area whose normals point against its
/// winding: all of it for a square whose normals were flipped, none for the
/// square itself (and no distance between the two).
#[test]
fn measure_reports_normals_against_winding() {
    let tmp = tempfile::tempdir().unwrap();
    let square = |nz: i32| {
        format!(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 {nz}\n\
             f 1//1 2//1 3//1\nf 1//1 3//1 4//1\n"
        )
    };
    let good = tmp.path().join("square-up.obj");
    let flipped = tmp.path().join("square-down.obj");
    std::fs::write(&good, square(1)).unwrap();
    std::fs::write(&flipped, square(-1)).unwrap();
    let (g, f) = (good.to_str().unwrap(), flipped.to_str().unwrap());
    let same = lodstudio_json(&["measure", g, g, "--samples", "1000"]);
    assert_eq!(same["normals_against_winding"].as_f64(), Some(0.0));
    let bad = lodstudio_json(&["measure", g, f, "--samples", "1000"]);
    assert_eq!(bad["normals_against_winding"].as_f64(), Some(1.0));
    assert!(bad["hausdorff"].as_f64().unwrap() < 1e-6, "{bad}");
}

/// The voxel method makes a new surface: it writes its own normals, facing
/// every triangle's winding, and no colour or UV (it keeps none of the
/// input's, and invents none) — on the textured truck and the horse.
#[test]
fn voxel_surfaces_write_their_own_normals_and_nothing_else() {
    let tmp = tempfile::tempdir().unwrap();
    for model in ["CesiumMilkTruck.glb", "horse.ply"] {
        let out = tmp.path().join(format!("voxel-{model}.glb"));
        let file = shared_model(model);
        let report = lodstudio_json(&[
            "export",
            file.to_str().unwrap(),
            "--method",
            "voxel",
            "--lods",
            // Two levels of the pyramid at the default filter radius (2 voxels).
            "6%,30%",
            "--resolution",
            "48",
            "-o",
            out.to_str().unwrap(),
            "--force",
        ]);
        let (doc, bin) = read_gltf(&out);
        let lods = report["lods"].as_array().unwrap();
        assert_eq!(lods.len(), 2, "{report}");
        for (l, lod) in lods.iter().enumerate() {
            assert!(
                lod["uv_error"].is_null(),
                "{model} LOD {l}: no UVs to measure"
            );
            let meshes = lod_meshes(&doc, l);
            for p in meshes
                .iter()
                .flat_map(|&m| doc["meshes"][m]["primitives"].as_array().unwrap())
            {
                let mut attrs: Vec<&String> = p["attributes"].as_object().unwrap().keys().collect();
                attrs.sort();
                assert_eq!(attrs, ["NORMAL", "POSITION"], "{model} LOD {l}");
                assert_eq!(area_against_winding(&doc, &bin, p), 0.0, "{model} LOD {l}");
            }
        }
    }
}
