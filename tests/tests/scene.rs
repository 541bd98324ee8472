//! Assets, not meshes (issue 49): a glTF scene's export carries the scene
//! (node names, hierarchy, transforms, skins, animations, morph targets)
//! in each layout, simplifies each mesh once however many nodes draw it,
//! bounds each instance in world space, and measures skinned LODs at
//! sampled poses and morphing LODs per target shape.

use std::path::Path;

use glam::{Mat4, Quat, Vec3};
use lodstudio_core::distance::{SamplingOptions, hausdorff_mesh_mesh};
use lodstudio_core::io::{gltf, gltf_writer, scene};
use lodstudio_tests::{lod_meshes, lodstudio_json, shared_model};
use serde_json::{Value, json};

fn doc_of(path: &Path) -> Value {
    let bytes = std::fs::read(path).unwrap();
    match gltf::split_glb(&bytes, "x.bin") {
        Some((json, _)) => serde_json::from_slice(&json).unwrap(),
        None => serde_json::from_slice(&bytes).unwrap(),
    }
}

fn export(input: &Path, lods: &str, layout: &str, out: &Path) -> Value {
    lodstudio_json(&[
        "export",
        input.to_str().unwrap(),
        "--lods",
        lods,
        "--layout",
        layout,
        "-o",
        out.to_str().unwrap(),
    ])
}

fn read_scene(path: &Path) -> scene::Scene {
    scene::read(&std::fs::read(path).unwrap(), path.parent()).unwrap()
}

/// The bytes of every animation sampler's input and output accessors
/// (with their element counts and types), as the scene holds them.
fn sampler_bytes(s: &scene::Scene) -> Vec<(Value, Vec<u8>)> {
    let mut out = Vec::new();
    for a in s.doc["animations"].as_array().into_iter().flatten() {
        for sampler in a["samplers"].as_array().into_iter().flatten() {
            for key in ["input", "output"] {
                let acc = &s.doc["accessors"][sampler[key].as_u64().unwrap() as usize];
                let view = &s.doc["bufferViews"][acc["bufferView"].as_u64().unwrap() as usize];
                let start = view["byteOffset"].as_u64().unwrap_or(0)
                    + acc["byteOffset"].as_u64().unwrap_or(0);
                let width = match acc["type"].as_str().unwrap() {
                    "SCALAR" => 1,
                    "VEC3" => 3,
                    "VEC4" => 4,
                    other => panic!("{other}"),
                };
                assert_eq!(acc["componentType"], 5126, "float keyframes");
                let len = acc["count"].as_u64().unwrap() * width * 4;
                let bytes = s.bin[start as usize..(start + len) as usize].to_vec();
                let shape = json!([acc["count"], acc["type"], sampler["interpolation"]]);
                out.push((shape, bytes));
            }
        }
    }
    assert!(!out.is_empty());
    out
}

/// What places a node: the keys that must come back as the input had them.
const KEPT: [&str; 6] = [
    "name",
    "matrix",
    "translation",
    "rotation",
    "scale",
    "extras",
];

/// The engine (82 nodes, 29 meshes, 67 instances): in every layout the
/// input's nodes keep their names, transforms and children (the LOD nodes
/// come after them), and each mesh is written once per level.
#[test]
fn the_engine_keeps_its_scene_in_every_layout() {
    let tmp = tempfile::tempdir().unwrap();
    let engine = shared_model("2CylinderEngine.gltf");
    let src = doc_of(&engine);
    let src_nodes = src["nodes"].as_array().unwrap();
    let src_meshes = src["meshes"].as_array().unwrap().len();
    let lods = "source,simplify:1%,simplify:4%";
    for layout in ["msft_lod", "nodes", "files"] {
        let out = tmp.path().join(format!("engine-{layout}.glb"));
        let j = export(&engine, lods, layout, &out);
        assert_eq!(j["layout"], layout);
        assert_eq!(
            (j["nodes"].as_u64(), j["instances"].as_u64()),
            (Some(82), Some(67))
        );
        let meshes = j["meshes"].as_array().unwrap();
        assert_eq!(meshes.len(), src_meshes, "every mesh drawn");
        let instances: usize = meshes
            .iter()
            .map(|m| m["instances"].as_array().unwrap().len())
            .sum();
        assert_eq!(instances, 67);
        let levels = j["lods"].as_array().unwrap().len();
        assert_eq!(levels, 3);
        let doc = doc_of(&out);
        let nodes = doc["nodes"].as_array().unwrap();
        for (i, (a, b)) in src_nodes.iter().zip(nodes).enumerate() {
            for key in KEPT {
                if key != "extras" || layout == "files" {
                    assert_eq!(a.get(key), b.get(key), "{layout} node {i} {key}");
                }
            }
            let (ca, cb) = (&a["children"], &b["children"]);
            let ca: Vec<&Value> = ca.as_array().into_iter().flatten().collect();
            let cb: Vec<&Value> = cb.as_array().into_iter().flatten().collect();
            assert_eq!(ca[..], cb[..ca.len()], "{layout} node {i}: children first");
        }
        assert_eq!(doc["scenes"], src["scenes"], "{layout}");
        // The primitives the LODs replaced leave no accessor behind.
        let mut named = std::collections::BTreeSet::new();
        for m in doc["meshes"].as_array().unwrap() {
            for p in m["primitives"].as_array().unwrap() {
                named.extend(
                    p["attributes"]
                        .as_object()
                        .unwrap()
                        .values()
                        .filter_map(Value::as_u64),
                );
                named.extend(p["indices"].as_u64());
            }
        }
        let accessors = doc["accessors"].as_array().unwrap().len() as u64;
        assert_eq!(
            named,
            (0..accessors).collect(),
            "{layout}: every accessor named"
        );
        match layout {
            "msft_lod" => {
                // Each mesh once per level; each drawing node names its LODs.
                assert_eq!(doc["meshes"].as_array().unwrap().len(), src_meshes * levels);
                assert_eq!(nodes.len(), 82 + 67 * (levels - 1));
                for n in src_nodes
                    .iter()
                    .enumerate()
                    .filter(|(_, n)| n.get("mesh").is_some())
                {
                    let ids = &nodes[n.0]["extensions"]["MSFT_lod"]["ids"];
                    assert_eq!(ids.as_array().unwrap().len(), levels - 1);
                    let c = &nodes[n.0]["extras"]["MSFT_screencoverage"];
                    assert_eq!(c.as_array().unwrap().len(), levels);
                }
                assert!(
                    doc["asset"]["extras"]["MSFT_screencoverage"]
                        .as_str()
                        .unwrap()
                        .contains("height share")
                );
            }
            "nodes" => {
                assert_eq!(doc["meshes"].as_array().unwrap().len(), src_meshes * levels);
                assert_eq!(nodes.len(), 82 + 67 * levels);
                for (i, n) in src_nodes
                    .iter()
                    .enumerate()
                    .filter(|(_, n)| n.get("mesh").is_some())
                {
                    assert!(
                        nodes[i].get("mesh").is_none(),
                        "the mesh moves to the LOD nodes"
                    );
                    let kids = nodes[i]["children"].as_array().unwrap();
                    let name = n["name"].as_str().map_or(String::new(), str::to_string);
                    for (k, c) in kids[kids.len() - levels..].iter().enumerate() {
                        let child = &nodes[c.as_u64().unwrap() as usize];
                        let got = child["name"].as_str().unwrap();
                        assert!(got.ends_with(&format!("_LOD{k}")), "{got}");
                        if !name.is_empty() {
                            assert_eq!(got, format!("{name}_LOD{k}"));
                        }
                    }
                }
            }
            _ => {
                // One whole scene per level, each mesh in its place.
                let outputs = j["outputs"].as_array().unwrap();
                assert_eq!(outputs.len(), levels);
                for (k, o) in outputs.iter().enumerate() {
                    let d = doc_of(Path::new(o.as_str().unwrap()));
                    assert_eq!(d["nodes"], src["nodes"], "level {k}: the nodes as read");
                    assert_eq!(d["meshes"].as_array().unwrap().len(), src_meshes);
                    assert_eq!(d["asset"]["extras"]["lod_level"], json!(k));
                }
            }
        }
        // A client of MSFT_lod shows, at LOD l, one mesh per drawn mesh,
        // holding the triangles the report gives.
        if layout == "msft_lod" {
            for (l, lod) in j["lods"].as_array().unwrap().iter().enumerate() {
                let shown = lod_meshes(&doc, l);
                assert_eq!(shown.len(), src_meshes, "LOD {l}");
                let triangles: u64 = shown
                    .iter()
                    .flat_map(|&m| doc["meshes"][m]["primitives"].as_array().unwrap())
                    .map(|p| {
                        doc["accessors"][p["indices"].as_u64().unwrap() as usize]["count"]
                            .as_u64()
                            .unwrap()
                            / 3
                    })
                    .sum();
                assert_eq!(Some(triangles), lod["triangles"].as_u64(), "LOD {l}");
            }
        }
    }
}

/// One torus drawn by three nodes under scaled (non-uniformly), rotated
/// and translated transforms: simplified once, and each instance's world
/// bound (σ_max·ε) holds against an independent measurement of that
/// instance in world space.
#[test]
fn an_instanced_mesh_is_simplified_once_and_bounded_per_instance() {
    let tmp = tempfile::tempdir().unwrap();
    let torus = lodstudio_core::builtins::torus(1.0, 0.35, 64, 32);
    let glb = gltf_writer::write_glb(&torus);
    let (json, bin) = gltf::split_glb(&glb, "x.bin").unwrap();
    let mut doc: Value = serde_json::from_slice(&json).unwrap();
    doc["buffers"][0].as_object_mut().unwrap().remove("uri");
    let transforms = [
        Mat4::IDENTITY,
        Mat4::from_scale_rotation_translation(
            Vec3::new(3.0, 0.5, 1.0),
            Quat::from_rotation_y(0.7),
            Vec3::new(5.0, 0.0, 0.0),
        ),
        Mat4::from_scale_rotation_translation(
            Vec3::splat(0.25),
            Quat::from_rotation_x(-1.1),
            Vec3::new(0.0, 4.0, 0.0),
        ),
    ];
    doc["nodes"] = json!([
        {"name": "plain", "mesh": 0},
        {"name": "stretched", "mesh": 0, "matrix": transforms[1].to_cols_array()},
        {"name": "small", "mesh": 0, "matrix": transforms[2].to_cols_array()},
    ]);
    doc["scenes"] = json!([{"nodes": [0, 1, 2]}]);
    let input = tmp.path().join("three.glb");
    std::fs::write(&input, gltf_writer::glb(&doc, bin)).unwrap();

    let out = tmp.path().join("three-out.glb");
    let j = export(&input, "simplify:1%,simplify:5%", "files", &out);
    let mesh = &j["meshes"][0];
    assert_eq!(mesh["instances"], json!([0, 1, 2]));
    let original = read_scene(&input);
    for (k, o) in j["outputs"].as_array().unwrap().iter().enumerate() {
        let lod = read_scene(Path::new(o.as_str().unwrap()));
        assert_eq!(lod.meshes.len(), 1, "simplified once");
        assert_eq!(
            lod.meshes[0].mesh.triangles.len() as u64,
            mesh["lods"][k]["triangles"].as_u64().unwrap()
        );
        let bounds = &mesh["lods"][k]["world_error_bounds"];
        for (i, t) in transforms.iter().enumerate() {
            let world = |m: &lodstudio_core::TriMesh| {
                let mut w = m.clone();
                for p in &mut w.positions {
                    *p = t.transform_point3(*p);
                }
                w
            };
            let measured = hausdorff_mesh_mesh(
                &world(&original.meshes[0].mesh),
                &world(&lod.meshes[0].mesh),
                &SamplingOptions {
                    samples: 50_000,
                    seed: 3,
                },
            )
            .two_sided();
            let bound = bounds[i].as_f64().unwrap() as f32;
            assert!(
                measured <= bound * 1.0001 + 1e-6,
                "LOD {k} instance {i}: {measured} > {bound}"
            );
            assert!(
                bound > 0.0 && measured > 0.2 * bound,
                "LOD {k} instance {i}: a loose bound {bound} for {measured}"
            );
        }
        // Clients draw each instance: three times the triangles written.
        let level = &j["lods"][k];
        let written = level["triangles"].as_u64().unwrap();
        assert_eq!(level["drawn_triangles"], 3 * written, "{level}");
        assert_eq!(level["drawn_primitives"], 3 * written, "{level}");
        // The stretched instance's bound is σ_max = 3 times the mesh's.
        let e = mesh["lods"][k]["error_bound"].as_f64().unwrap();
        let stretched = bounds[1].as_f64().unwrap();
        assert!((stretched / e - 3.0).abs() < 1e-3, "{stretched} / {e}");
    }
}

/// A skinned, animated strip (Khronos' simple skin): the skin, its inverse
/// bind matrices and the animation's samples come back as read; the LOD's
/// joints are the original's, its weights sum to 1, and every LOD reports
/// its distance at 8 sampled poses, 0 where the LOD is the source.
#[test]
fn a_skinned_asset_keeps_its_skin_and_reports_pose_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let input = shared_model("production/simple_skin/simple_skin.gltf");
    let src = doc_of(&input);
    let original = read_scene(&input);
    for layout in ["msft_lod", "nodes", "files"] {
        let out = tmp.path().join(format!("skin-{layout}.glb"));
        let j = export(&input, "source,simplify:5%", layout, &out);
        let doc = doc_of(&out);
        // Accessors are renumbered (the replaced primitives' are left out):
        // the skin's joints and the channels as read, the data below.
        assert_eq!(
            doc["skins"][0]["joints"], src["skins"][0]["joints"],
            "{layout}"
        );
        assert_eq!(
            doc["animations"][0]["channels"], src["animations"][0]["channels"],
            "{layout}"
        );
        let back = read_scene(&out);
        assert_eq!(sampler_bytes(&back), sampler_bytes(&original), "{layout}");
        assert_eq!(back.rig.skins, original.rig.skins, "inverse bind matrices");
        assert_eq!(back.rig.animations, original.rig.animations, "sampler data");
        for (k, lod) in j["lods"].as_array().unwrap().iter().enumerate() {
            let pose = &lod["pose_error"];
            assert_eq!(pose["poses"].as_u64(), Some(8), "{layout} LOD {k}");
            assert!(pose["max"].as_f64().unwrap() >= pose["mean"].as_f64().unwrap());
            if k == 0 {
                assert!(pose["max"].as_f64().unwrap() < 1e-5, "the source: {pose}");
            }
        }
        let joints: Vec<u64> = src["skins"][0]["joints"]
            .as_array()
            .unwrap()
            .iter()
            .map(|j| j.as_u64().unwrap())
            .collect();
        // Every skinned primitive of the output: joint indices within the
        // skin's, weights summing to 1.
        for m in &back.meshes {
            let skin = m.skin.as_ref().expect("the LOD meshes are skinned");
            for (js, ws) in skin.joints.iter().zip(&skin.weights) {
                assert!(js.iter().all(|&i| (i as usize) < joints.len()));
                let sum: f32 = ws.iter().sum();
                assert!((sum - 1.0).abs() < 1e-5, "weights sum to {sum}");
            }
        }
    }
}

/// A cube with two morph targets, animated: every LOD mesh keeps both
/// targets, the animation drives every LOD node (in `nodes`, the mesh
/// node's own channel moves to its LOD children), and each target shape's
/// distance is reported.
#[test]
fn a_morphing_asset_keeps_its_targets_and_reports_them() {
    let tmp = tempfile::tempdir().unwrap();
    let input = shared_model("production/AnimatedMorphCube/AnimatedMorphCube.gltf");
    let src = doc_of(&input);
    for layout in ["msft_lod", "nodes"] {
        let out = tmp.path().join(format!("cube-{layout}.glb"));
        let j = export(&input, "source,simplify:5%", layout, &out);
        let doc = doc_of(&out);
        for m in doc["meshes"].as_array().unwrap() {
            for p in m["primitives"].as_array().unwrap() {
                assert_eq!(p["targets"].as_array().unwrap().len(), 2, "{layout}");
            }
            assert_eq!(m.get("weights"), src["meshes"][0].get("weights"));
        }
        let lod_nodes: Vec<usize> = doc["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
            .filter(|(_, n)| n["name"].as_str().is_some_and(|s| s.contains("_LOD")))
            .map(|(i, _)| i)
            .collect();
        let driven: Vec<u64> = doc["animations"][0]["channels"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|c| c["target"]["path"] == "weights")
            .map(|c| c["target"]["node"].as_u64().unwrap())
            .collect();
        for n in &lod_nodes {
            assert!(
                driven.contains(&(*n as u64)),
                "{layout}: LOD node {n} morphs"
            );
        }
        assert_eq!(
            sampler_bytes(&read_scene(&out)),
            sampler_bytes(&read_scene(&input)),
            "{layout}: the animation's keyframes"
        );
        for (k, lod) in j["lods"].as_array().unwrap().iter().enumerate() {
            let t = lod["target_errors"].as_array().unwrap();
            assert_eq!(t.len(), 2, "{layout} LOD {k}");
            // Certified per target (checked against a dense measurement
            // on the torus below: this cube is 0.02 wide and its second
            // target flattens a face into a 1e-4 sliver, where the f32
            // sampler's own rounding, ~1e-5, is above the distances).
            let b = lod["target_bounds"].as_array().unwrap();
            assert_eq!(b.len(), 2, "{layout} LOD {k}");
            for b in b {
                assert!(b["bound"].as_f64().unwrap() < 1e-4 * 0.0347, "{b}");
            }
            if k == 0 {
                assert!(
                    t.iter().all(|e| e["measured"].as_f64().unwrap() < 1e-4),
                    "{t:?}"
                );
            }
        }
    }
}

/// A torus with two morph targets (a wave and a pinch): each LOD's
/// certified bound per target shape holds against an independent dense
/// measurement of the LOD's target shape (read back from the file) against
/// the original's, and the LOD's bound is the largest over base and targets.
#[test]
fn each_morph_target_shape_is_certified() {
    let tmp = tempfile::tempdir().unwrap();
    let torus = lodstudio_core::builtins::torus(1.0, 0.35, 64, 32);
    let glb = gltf_writer::write_glb(&torus);
    let (json, mut bin) = gltf::split_glb(&glb, "x.bin").unwrap();
    let mut doc: Value = serde_json::from_slice(&json).unwrap();
    doc["buffers"][0].as_object_mut().unwrap().remove("uri");
    // The primitive's positions, as written.
    let position = &doc["accessors"][doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize];
    let view = &doc["bufferViews"][position["bufferView"].as_u64().unwrap() as usize];
    let start = (view["byteOffset"].as_u64().unwrap_or(0)
        + position["byteOffset"].as_u64().unwrap_or(0)) as usize;
    let positions: Vec<Vec3> = (0..position["count"].as_u64().unwrap() as usize)
        .map(|i| {
            let f = |c: usize| {
                let at = start + 12 * i + 4 * c;
                f32::from_le_bytes(bin[at..at + 4].try_into().unwrap())
            };
            Vec3::new(f(0), f(1), f(2))
        })
        .collect();
    let targets: [Vec<Vec3>; 2] = [
        positions
            .iter()
            .map(|p| Vec3::new(0.0, 0.0, 0.4 * (3.0 * p.y.atan2(p.x)).sin()))
            .collect(),
        positions
            .iter()
            .map(|p| -0.5 * p.x.max(0.0) * Vec3::new(p.x, p.y, 0.0))
            .collect(),
    ];
    for deltas in &targets {
        let (lo, hi) = deltas.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), d| (lo.min(*d), hi.max(*d)),
        );
        let offset = bin.len();
        bin.extend(
            deltas
                .iter()
                .flat_map(|d| d.to_array())
                .flat_map(f32::to_le_bytes),
        );
        let views = doc["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": 12 * deltas.len()}));
        let v = views.len() - 1;
        let accessors = doc["accessors"].as_array_mut().unwrap();
        accessors.push(
            json!({"bufferView": v, "componentType": 5126, "count": deltas.len(),
            "type": "VEC3", "min": lo.to_array(), "max": hi.to_array()}),
        );
        let a = accessors.len() - 1;
        let prim = &mut doc["meshes"][0]["primitives"][0];
        if prim.get("targets").is_none() {
            prim["targets"] = json!([]);
        }
        prim["targets"]
            .as_array_mut()
            .unwrap()
            .push(json!({"POSITION": a}));
    }
    doc["meshes"][0]["weights"] = json!([0.0, 0.0]);
    doc["meshes"][0]["extras"] = json!({"targetNames": ["wave", "pinch"]});
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    let input = tmp.path().join("morphing.glb");
    std::fs::write(&input, gltf_writer::glb(&doc, bin)).unwrap();

    let out = tmp.path().join("morphing-out.glb");
    let j = export(&input, "simplify:1%,simplify:4%", "files", &out);
    let original = read_scene(&input);
    assert_eq!(original.meshes[0].targets.len(), 2);
    let lods = &j["meshes"][0]["lods"];
    for (k, o) in j["outputs"].as_array().unwrap().iter().enumerate() {
        let lod = read_scene(Path::new(o.as_str().unwrap()));
        let bounds = lods[k]["target_bounds"].as_array().unwrap();
        assert_eq!(bounds.len(), 2);
        for (t, b) in bounds.iter().enumerate() {
            assert_eq!(b["name"], ["wave", "pinch"][t]);
            let bound = b["bound"].as_f64().unwrap() as f32;
            let measured = hausdorff_mesh_mesh(
                &original.meshes[0].target_shape(t),
                &lod.meshes[0].target_shape(t),
                &SamplingOptions {
                    samples: 50_000,
                    seed: 5,
                },
            )
            .two_sided();
            assert!(
                measured <= bound * 1.0001 + 1e-6,
                "LOD {k} target {t}: {measured} > {bound}"
            );
            assert!(
                measured > 0.2 * bound,
                "LOD {k} target {t}: a loose bound {bound} for {measured}"
            );
            assert!(lods[k]["error_bound"].as_f64().unwrap() as f32 >= bound);
        }
        let top = &j["lods"][k]["target_bounds"];
        assert_eq!(top.as_array().unwrap().len(), 2, "{top}");
    }
}

/// `--compress meshopt` (EXT_meshopt_compression): the milk truck's scene
/// in every layout reads back, through lodstudio's own decoder, with the
/// positions, triangles (up to the rotation of a triangle's corners, which
/// the index codec allows), UVs and keyframes of the plain export to the
/// bit (the codecs are lossless there, so every bound holds as reported),
/// normals within their 8-bit octahedral step, in a smaller file.
#[test]
fn a_meshopt_compressed_export_reads_back_as_the_plain_one() {
    let tmp = tempfile::tempdir().unwrap();
    let input = shared_model("CesiumMilkTruck.glb");
    for layout in ["msft_lod", "nodes", "files"] {
        let run = |compress: &str| {
            let out = tmp.path().join(format!("truck-{layout}-{compress}.glb"));
            let j = lodstudio_json(&[
                "export",
                input.to_str().unwrap(),
                "--lods",
                "source,simplify:1%",
                "--layout",
                layout,
                "--compress",
                compress,
                "-o",
                out.to_str().unwrap(),
            ]);
            assert_eq!(j["compress"], compress);
            j
        };
        let (plain, packed) = (run("none"), run("meshopt"));
        assert_eq!(plain["lods"], packed["lods"], "{layout}: the same LODs");
        let outputs = |j: &Value| -> Vec<String> {
            j["outputs"]
                .as_array()
                .unwrap()
                .iter()
                .map(|o| o.as_str().unwrap().to_string())
                .collect()
        };
        for (p, c) in outputs(&plain).iter().zip(outputs(&packed)) {
            let (p, c) = (Path::new(p), Path::new(&c));
            let doc = doc_of(c);
            assert!(
                doc["extensionsRequired"]
                    .as_array()
                    .unwrap()
                    .contains(&json!("EXT_meshopt_compression")),
                "{layout}"
            );
            let size = |f: &Path| std::fs::metadata(f).unwrap().len();
            assert!(size(c) < size(p), "{layout}: {} ≥ {}", size(c), size(p));
            let (a, b) = (read_scene(p), read_scene(c));
            assert_eq!(a.meshes.len(), b.meshes.len(), "{layout}");
            for (m, n) in a.meshes.iter().zip(&b.meshes) {
                assert_eq!(m.mesh.positions, n.mesh.positions, "{layout} {}", m.name);
                // The index codec may rotate a triangle's corners (its
                // winding kept).
                let rotated = |t: &[[u32; 3]]| -> Vec<[u32; 3]> {
                    t.iter()
                        .map(|&[a, b, c]| match () {
                            _ if a <= b && a <= c => [a, b, c],
                            _ if b <= c => [b, c, a],
                            _ => [c, a, b],
                        })
                        .collect()
                };
                let same = rotated(&m.mesh.triangles) == rotated(&n.mesh.triangles);
                assert!(same, "{layout} {}: the triangles", m.name);
                assert_eq!(m.mesh.uvs, n.mesh.uvs, "{layout} {}", m.name);
                let normals = m.mesh.normals.iter().flatten();
                for (x, y) in normals.zip(n.mesh.normals.iter().flatten()) {
                    assert!(x.distance(*y) < 0.02, "{layout}: {x} / {y}");
                }
            }
            assert_eq!(sampler_bytes(&a), sampler_bytes(&b), "{layout}");
        }
    }
}

/// `assets/two-bone-cylinder.glb` is what `two_bone_cylinder` makes
/// (`UPDATE_ASSETS=1` writes it again), and its LODs keep the skin: the
/// bind-pose bound holds against an independent measurement, every
/// sampled pose is measured, the LODs' joints are the skin's and their
/// weights sum to 1.
#[test]
fn the_two_bone_cylinder_keeps_its_skin_through_its_lods() {
    let asset = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/two-bone-cylinder.glb");
    let made = lodstudio_tests::two_bone_cylinder();
    if std::env::var_os("UPDATE_ASSETS").is_some() {
        std::fs::write(&asset, &made).unwrap();
    }
    assert!(
        std::fs::read(&asset).unwrap() == made,
        "UPDATE_ASSETS=1 writes it"
    );
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("cylinder.glb");
    let j = export(&asset, "source,simplify:1%,simplify:4%", "files", &out);
    let original = read_scene(&asset);
    let mut coarser = usize::MAX;
    for (k, o) in j["outputs"].as_array().unwrap().iter().enumerate() {
        let lod = read_scene(Path::new(o.as_str().unwrap()));
        let m = &lod.meshes[0];
        assert!(m.mesh.triangles.len() < coarser, "LOD {k} is coarser");
        coarser = m.mesh.triangles.len();
        let skin = m.skin.as_ref().expect("skinned");
        for (js, ws) in skin.joints.iter().zip(&skin.weights) {
            assert!(js.iter().zip(ws).all(|(&i, &w)| i < 2 || w == 0.0));
            assert!((ws.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        }
        let lods = &j["meshes"][0]["lods"][k];
        let bound = lods["error_bound"].as_f64().unwrap() as f32;
        let measured = hausdorff_mesh_mesh(
            &original.meshes[0].mesh,
            &m.mesh,
            &SamplingOptions {
                samples: 50_000,
                seed: 7,
            },
        )
        .two_sided();
        assert!(
            measured <= bound * 1.0001 + 1e-6,
            "LOD {k}: {measured} > {bound}"
        );
        let pose = &lods["pose_error"];
        assert_eq!(pose["per_pose"].as_array().unwrap().len(), 8, "{pose}");
    }
    assert!(coarser < 300, "the coarsest LOD has {coarser} triangles");
}

/// The cylinder with each vertex's two joints split over `JOINTS_0` (joint
/// 0) and `JOINTS_1` (joint 1): read, the eight influences are the
/// cylinder's own, so the source LOD writes the cylinder's skin back
/// (folded into `_0`) and poses as it does; the fold is listed in
/// `dropped`; the collapse LODs carried their weights through the build.
#[test]
fn a_second_set_of_influences_is_folded_not_lost() {
    let tmp = tempfile::tempdir().unwrap();
    let cylinder = lodstudio_tests::two_bone_cylinder();
    let (json, mut bin) = gltf::split_glb(&cylinder, "x.bin").unwrap();
    let mut doc: Value = serde_json::from_slice(&json).unwrap();
    doc["buffers"][0].as_object_mut().unwrap().remove("uri");
    let original = scene::read(&cylinder, None).unwrap();
    let skin = original.meshes[0].skin.as_ref().unwrap();
    let weight_of = |v: usize, joint: u16| -> f32 {
        (skin.joints[v].iter().zip(skin.weights[v]))
            .filter(|(j, w)| **j == joint && *w > 0.0)
            .map(|(_, w)| w)
            .sum()
    };
    let n = skin.joints.len();
    let mut add = |bytes: Vec<u8>, component: u32| {
        let offset = bin.len();
        bin.extend(bytes);
        let views = doc["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bin.len() - offset, "target": 34962}));
        let v = views.len() - 1;
        let accessors = doc["accessors"].as_array_mut().unwrap();
        accessors
            .push(json!({"bufferView": v, "componentType": component, "count": n, "type": "VEC4"}));
        accessors.len() - 1
    };
    let sets: Vec<[f32; 4]> = (0..n).map(|v| [weight_of(v, 0), 0.0, 0.0, 0.0]).collect();
    let more: Vec<[f32; 4]> = (0..n).map(|v| [weight_of(v, 1), 0.0, 0.0, 0.0]).collect();
    let floats = |w: &[[f32; 4]]| w.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let j0 = add(vec![0u8; 8 * n], 5123);
    let w0 = add(floats(&sets), 5126);
    let j1 = add(
        (0..n).flat_map(|_| [1u8, 0, 0, 0, 0, 0, 0, 0]).collect(),
        5123,
    );
    let w1 = add(floats(&more), 5126);
    let attributes = &mut doc["meshes"][0]["primitives"][0]["attributes"];
    for (k, a) in [
        ("JOINTS_0", j0),
        ("WEIGHTS_0", w0),
        ("JOINTS_1", j1),
        ("WEIGHTS_1", w1),
    ] {
        attributes[k] = json!(a);
    }
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    let input = tmp.path().join("eight.glb");
    std::fs::write(&input, gltf_writer::glb(&doc, bin)).unwrap();

    let out = tmp.path().join("eight-out.glb");
    let j = export(&input, "source,simplify:1%", "files", &out);
    let dropped = j["dropped"].as_array().unwrap();
    assert!(
        dropped
            .iter()
            .any(|d| d["what"].as_str().unwrap().contains("JOINTS_1")),
        "{dropped:?}"
    );
    let lods = j["meshes"][0]["lods"].as_array().unwrap();
    for l in lods {
        assert_eq!(l["vertex_data"], "carried", "{l}");
    }
    assert!(lods[0]["pose_error"]["max"].as_f64().unwrap() < 1e-5);
    let plain = export(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../assets/two-bone-cylinder.glb")
            .as_path(),
        "source,simplify:1%",
        "files",
        &tmp.path().join("plain.glb"),
    );
    assert_eq!(
        lods[1]["pose_error"], plain["meshes"][0]["lods"][1]["pose_error"],
        "the same skin, the same LOD, the same poses"
    );
    let written = read_scene(Path::new(j["outputs"][0].as_str().unwrap()));
    let back = written.meshes[0].skin.as_ref().unwrap();
    assert!(back.more.is_empty(), "written in one set");
    // The source's vertices in the order written: matched by position.
    for (v, p) in written.meshes[0].mesh.positions.iter().enumerate() {
        let o = (original.meshes[0].mesh.positions.iter())
            .position(|q| q == p)
            .unwrap();
        for joint in [0u16, 1] {
            let w: f32 = (back.joints[v].iter().zip(back.weights[v]))
                .filter(|(j, w)| **j == joint && *w > 0.0)
                .map(|(_, w)| w)
                .sum();
            assert!(
                (w - weight_of(o, joint)).abs() < 1e-6,
                "vertex {v} joint {joint}"
            );
        }
    }
}

/// Two meshes in one scene, each drawn by its own node.
fn two_mesh_scene(a: &lodstudio_core::TriMesh, b: &lodstudio_core::TriMesh) -> Vec<u8> {
    let split = |m: &lodstudio_core::TriMesh| {
        let (json, bin) = gltf::split_glb(&gltf_writer::write_glb(m), "x.bin").unwrap();
        (serde_json::from_slice::<Value>(&json).unwrap(), bin)
    };
    let ((mut doc, mut bin), (other, more)) = (split(a), split(b));
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let (views, accessors) = (
        doc["bufferViews"].as_array().unwrap().len(),
        doc["accessors"].as_array().unwrap().len(),
    );
    let materials = doc["materials"].as_array().map_or(0, Vec::len);
    for mut v in other["bufferViews"].as_array().unwrap().clone() {
        v["byteOffset"] = json!(v["byteOffset"].as_u64().unwrap_or(0) + bin.len() as u64);
        doc["bufferViews"].as_array_mut().unwrap().push(v);
    }
    for mut a in other["accessors"].as_array().unwrap().clone() {
        a["bufferView"] = json!(a["bufferView"].as_u64().unwrap() + views as u64);
        doc["accessors"].as_array_mut().unwrap().push(a);
    }
    for m in other["materials"].as_array().into_iter().flatten() {
        doc["materials"].as_array_mut().unwrap().push(m.clone());
    }
    let mut mesh = other["meshes"][0].clone();
    for p in mesh["primitives"].as_array_mut().unwrap() {
        for (_, a) in p["attributes"].as_object_mut().unwrap() {
            *a = json!(a.as_u64().unwrap() + accessors as u64);
        }
        p["indices"] = json!(p["indices"].as_u64().unwrap() + accessors as u64);
        if let Some(m) = p.get("material").and_then(Value::as_u64) {
            p["material"] = json!(m + materials as u64);
        }
    }
    doc["meshes"].as_array_mut().unwrap().push(mesh);
    bin.extend(more);
    doc["buffers"] = json!([{"byteLength": bin.len()}]);
    doc["nodes"] = json!([{"name": "big", "mesh": 0},
        {"name": "small", "mesh": 1, "translation": [3.0, 0.0, 0.0]}]);
    doc["scenes"] = json!([{"nodes": [0, 1]}]);
    gltf_writer::glb(&doc, bin)
}

/// A row one mesh of a scene does not fit (an AMG impostor of an
/// icosahedron: 12 points, too few for its neighbourhoods) is left out of
/// that mesh's chain and said (stderr, `meshes[].skipped_rows`), while the
/// other mesh keeps it; before, the whole export failed.
#[test]
fn a_row_a_small_mesh_does_not_fit_is_left_out_of_its_chain_only() {
    let tmp = tempfile::tempdir().unwrap();
    let big = lodstudio_core::builtins::torus(1.0, 0.35, 48, 24);
    let small = lodstudio_core::builtins::icosphere(Vec3::ZERO, 0.3, 0);
    let input = tmp.path().join("two.glb");
    std::fs::write(&input, two_mesh_scene(&big, &small)).unwrap();
    let out = tmp.path().join("two-out.glb");
    let run = lodstudio_tests::lodstudio(&[
        "export",
        input.to_str().unwrap(),
        "--lods",
        "simplify:1%,amg:15%",
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let j: Value = serde_json::from_slice(&run.stdout).unwrap();
    let meshes = j["meshes"].as_array().unwrap();
    assert_eq!(meshes[0]["lods"].as_array().unwrap().len(), 2);
    assert!(meshes[0].get("skipped_rows").is_none());
    assert_eq!(meshes[1]["lods"].as_array().unwrap().len(), 1);
    let skipped = &meshes[1]["skipped_rows"][0];
    assert_eq!(
        (skipped["row"].as_u64(), skipped["label"].as_str()),
        (Some(1), Some("amg:15%"))
    );
    assert!(stderr.contains("rows[1] (amg:15%) left out"), "{stderr}");
    assert!(meshes[0]["lods"][1]["splats"].as_u64().unwrap() > 0);
}

/// `--layout nodes|files` lays out a scene: on one mesh it is refused,
/// not ignored.
#[test]
fn a_layout_for_one_mesh_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("sphere.glb");
    let run = lodstudio_tests::lodstudio(&[
        "export",
        "builtin:sphere",
        "--lods",
        "simplify:1%",
        "--layout",
        "nodes",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("--layout nodes"));
    assert!(!out.exists());
}

/// The truck's body node holds its wheels' nodes, and a lower LOD node
/// replaces its head whole, children included: the body's mesh moves onto
/// a child that heads its LODs, so the wheels are drawn at every level by
/// a client walking `MSFT_lod` and by `FILE.glb#lodN` (they vanished from
/// LOD1 on before).
#[test]
fn a_mesh_node_with_children_keeps_them_at_every_lod() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("truck.glb");
    let truck = shared_model("CesiumMilkTruck.glb");
    // The nodes are what is tested: no bakes (each a texture to make).
    let j = lodstudio_json(&[
        "export",
        truck.to_str().unwrap(),
        "--lods",
        "source,simplify:0.5,simplify:0.25",
        "--no-bake",
        "-o",
        out.to_str().unwrap(),
    ]);
    let doc = doc_of(&out);
    let lods = j["lods"].as_array().unwrap();
    assert_eq!(lods.len(), 3);
    for (l, lod) in lods.iter().enumerate() {
        assert_eq!(lod_meshes(&doc, l).len(), 2, "LOD {l}: body and wheels");
        let level = format!("{}#lod{l}", out.display());
        let read = lodstudio_json(&["info", &level]);
        assert_eq!(read["triangles"], lod["drawn_triangles"], "LOD {l}: {read}");
    }
}
