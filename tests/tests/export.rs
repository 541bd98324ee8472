//! `export` (issue 9): an LOD chain as one GLB with the MSFT_lod node extension
//! and MSFT_screencoverage thresholds. The file is read back two ways: through
//! core's glTF reader (a loader without the extension: it must see LOD0) and as
//! raw glTF JSON (the extension, the LOD order and the thresholds).

use std::path::Path;

use lodstudio_core::io::gltf;
use lodstudio_tests::{glb_json, lodstudio, lodstudio_json, shared_model};
use serde_json::Value;

/// The JSON chunk of a GLB.
fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("an array")
        .iter()
        .map(|x| x.as_f64().expect("a number"))
        .collect()
}

fn strictly_decreasing(v: &[f64]) -> bool {
    v.windows(2).all(|w| w[1] < w[0])
}

/// Checks the written file against the reported `lods` and returns them.
fn check_chain(out: &Path, report: &Value) -> Vec<Value> {
    let glb = std::fs::read(out).expect("export wrote the GLB");
    assert_eq!(report["bytes"].as_u64().unwrap() as usize, glb.len());
    let lods = report["lods"].as_array().expect("lods").clone();
    let triangles: Vec<u64> = lods
        .iter()
        .map(|l| l["triangles"].as_u64().unwrap())
        .collect();
    let points: Vec<u64> = lods.iter().map(|l| l["points"].as_u64().unwrap()).collect();
    let splats: Vec<u64> = lods.iter().map(|l| l["splats"].as_u64().unwrap()).collect();
    for l in &lods {
        assert!(l["tolerance"].is_string());
    }
    // Decreasing quality: bounds grow, triangle counts shrink.
    let bounds: Vec<f64> = lods
        .iter()
        .map(|l| l["error_bound"].as_f64().unwrap())
        .collect();
    assert!(bounds.windows(2).all(|w| w[0] <= w[1]), "{bounds:?}");
    assert!(triangles.windows(2).all(|w| w[0] >= w[1]), "{triangles:?}");
    let kinds: Vec<(u64, u64)> = triangles
        .iter()
        .copied()
        .zip(points.iter().copied())
        .collect();
    assert!(
        kinds.windows(2).all(|w| w[0] != w[1]),
        "distinct LODs: {kinds:?}"
    );

    // A reader without MSFT_lod sees LOD0 alone.
    let (back, _) = gltf::read(&glb, None).expect("the GLB reads back");
    if splats[0] == 0 {
        assert_eq!(back.triangles.len() as u64, triangles[0]);
        assert!(back.normals.is_some(), "every LOD has normals");
    }

    let doc = glb_json(&glb);
    assert!(
        doc["extensionsUsed"]
            .as_array()
            .unwrap()
            .contains(&Value::from("MSFT_lod"))
    );
    assert!(doc.get("extensionsRequired").is_none());
    assert_eq!(doc["scenes"][0]["nodes"], serde_json::json!([0]));
    let node0 = &doc["nodes"][0];
    let ids: Vec<u64> = node0["extensions"]["MSFT_lod"]["ids"]
        .as_array()
        .expect("MSFT_lod ids")
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert_eq!(ids, (1..lods.len() as u64).collect::<Vec<_>>());
    let coverage = f64s(&node0["extras"]["MSFT_screencoverage"]);
    assert_eq!(
        coverage.len(),
        lods.len(),
        "one threshold per LOD, LOD0's included"
    );
    assert!(strictly_decreasing(&coverage), "{coverage:?}");
    assert!(
        coverage.iter().all(|c| *c > 0.0 && *c <= 1.0),
        "{coverage:?}"
    );
    let reported: Vec<f64> = lods
        .iter()
        .map(|l| l["screen_coverage"].as_f64().unwrap())
        .collect();
    for (a, b) in coverage.iter().zip(&reported) {
        assert!(
            (a - b).abs() <= 1e-6 * a.max(1e-3),
            "{coverage:?} vs {reported:?}"
        );
    }
    // Node i (LOD0, then the ids in order) holds LOD i's triangles (with
    // normals) and its points (POINTS with _RADIUS).
    let nodes: Vec<u64> = std::iter::once(0).chain(ids).collect();
    for (i, node) in nodes.iter().enumerate() {
        let mesh = doc["nodes"][*node as usize]["mesh"].as_u64().unwrap() as usize;
        let prims = doc["meshes"][mesh]["primitives"].as_array().unwrap();
        let of_mode = |m: u64| prims.iter().find(|p| p["mode"] == m);
        // Unlit textured quads are the splats; the other triangles the surface,
        // one primitive per material of the input's.
        let splat = |p: &&Value| {
            let m = p["material"].as_u64().unwrap_or(u64::MAX) as usize;
            doc["materials"][m]["extensions"]["KHR_materials_unlit"].is_object()
        };
        // Every splat a quad of one primitive per atlas (a handful of draw calls).
        let quads: Vec<u64> = prims
            .iter()
            .filter(splat)
            .map(|p| {
                let acc = p["indices"].as_u64().unwrap() as usize;
                doc["accessors"][acc]["count"].as_u64().unwrap() / 6
            })
            .collect();
        assert_eq!(quads.iter().sum::<u64>(), splats[i], "lod{i} splats");
        assert!(quads.len() <= 4, "lod{i}: {} splat primitives", quads.len());
        let surface: Vec<&Value> = prims
            .iter()
            .filter(|p| p["mode"] == 4 && !splat(p))
            .collect();
        let indices: u64 = surface
            .iter()
            .map(|p| {
                let acc = p["indices"].as_u64().unwrap() as usize;
                doc["accessors"][acc]["count"].as_u64().unwrap()
            })
            .sum();
        assert_eq!(indices, 3 * triangles[i], "lod{i}");
        for prim in surface {
            for attr in ["POSITION", "NORMAL"] {
                assert!(prim["attributes"][attr].is_u64(), "lod{i} has {attr}");
            }
        }
        if let Some(prim) = of_mode(0) {
            let acc = prim["attributes"]["POSITION"].as_u64().unwrap() as usize;
            assert_eq!(
                doc["accessors"][acc]["count"].as_u64().unwrap(),
                points[i],
                "lod{i}"
            );
            assert!(
                prim["attributes"]["_RADIUS"].is_u64(),
                "lod{i} points carry _RADIUS"
            );
        } else {
            assert_eq!(points[i], 0, "lod{i}");
        }
    }
    lods
}

fn export_json(file: &str, lods: &str, out: &Path, extra: &[&str]) -> Value {
    let mut args = vec![
        "export",
        file,
        "--method",
        "simplify",
        "--lods",
        lods,
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    lodstudio_json(&args)
}

#[test]
fn torus_chain_round_trips() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("torus.glb");
    let report = export_json("builtin:torus", "0.5%,2%,8%", &out, &[]);
    let lods = check_chain(&out, &report);
    assert_eq!(lods.len(), 3);
    for (l, tol) in lods.iter().zip([0.005, 0.02, 0.08]) {
        assert_eq!(l["tolerance"], format!("{}%", tol * 100.0));
        let rel = l["error_bound_relative"].as_f64().unwrap();
        assert!(rel <= tol * (1.0 + 1e-5), "{l}");
    }
    // UVs travel too (the torus has them).
    let doc = glb_json(&std::fs::read(&out).unwrap());
    assert!(doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"].is_u64());
}

#[test]
fn bunny_chain_round_trips() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("bunny.glb");
    let bunny = shared_model("stanford-bunny.obj");
    let report = export_json(bunny.to_str().unwrap(), "0.5%,2%,8%", &out, &[]);
    let lods = check_chain(&out, &report);
    assert_eq!(lods.len(), 3);
    assert_eq!(report["input_triangles"], 69_451);
    assert!(lods[0]["triangles"].as_u64().unwrap() < 69_451);
}

#[test]
fn pixel_and_ratio_items_are_sorted_by_decreasing_quality() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("mixed.glb");
    let (pixels, height) = (2.0, 1000.0);
    let report = export_json(
        "builtin:torus",
        "0.25,16px,2px",
        &out,
        &["--pixels", "2", "--viewport-height", "1000"],
    );
    let lods = check_chain(&out, &report);
    let diag = report["bbox_diagonal"].as_f64().unwrap();
    // 2px then 16px (bounds grow with the tolerance); the ratio LOD wherever its bound falls.
    let order: Vec<&str> = lods
        .iter()
        .map(|l| l["tolerance"].as_str().unwrap())
        .collect();
    let at = |t: &str| order.iter().position(|o| *o == t).unwrap();
    assert!(at("2px") < at("16px"), "{order:?}");
    for (t, px) in [("2px", 2.0), ("16px", 16.0)] {
        // p pixels with the object filling the viewport: e = p · diag / H.
        let bound = lods[at(t)]["error_bound"].as_f64().unwrap();
        assert!(bound <= px * diag / height * (1.0 + 1e-5), "{t}: {bound}");
    }
    let ratio = &lods[at("0.25")];
    assert!(ratio["triangles"].as_u64().unwrap() <= 1024);
    // Each threshold but the last is where the next LOD's bound projects to
    // --pixels: c = 2r·p / (e·H) with r = diag / 2 (clamped to 1).
    let coverage: Vec<f64> = lods
        .iter()
        .map(|l| l["screen_coverage"].as_f64().unwrap())
        .collect();
    for i in 0..lods.len() - 1 {
        let e = lods[i + 1]["error_bound"].as_f64().unwrap();
        let expected = (diag * pixels / (e * height)).min(1.0);
        assert!(
            coverage[i] <= expected * (1.0 + 1e-5) && coverage[i] >= expected * 0.999,
            "{i}: {coverage:?} vs {expected}"
        );
    }
    assert!((coverage[lods.len() - 1] - pixels / height).abs() < 1e-6);
}

#[test]
fn bad_input_exits_2_and_loses_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("existing.glb");
    std::fs::write(&out, b"keep me").unwrap();
    let o = out.to_str().unwrap();
    // (input, method, LIST, further arguments): each exits 2 with one line on
    // stderr and leaves the existing file as it was.
    let cases: &[(&str, &str, &str, &[&str])] = &[
        // An existing file without --force.
        ("builtin:torus", "simplify", "1%", &[]),
        // Bad LIST items.
        ("builtin:torus", "simplify", "1%,abc", &["--force"]),
        ("builtin:torus", "simplify", "2", &["--force"]),
        ("builtin:torus", "simplify", "1%,,2%", &["--force"]),
        ("builtin:torus", "simplify", "-1px", &["--force"]),
        ("builtin:torus", "simplify", "", &["--force"]),
        // A method that does not export yet, and a point set.
        ("builtin:torus", "splines", "1%", &["--force"]),
        ("builtin:octahedron-points", "simplify", "1%", &["--force"]),
        // Bad thresholds.
        (
            "builtin:torus",
            "simplify",
            "1%",
            &["--force", "--pixels", "0"],
        ),
        (
            "builtin:torus",
            "simplify",
            "1%",
            &["--force", "--viewport-height", "nan"],
        ),
        // A missing input.
        ("/nonexistent/model.obj", "simplify", "1%", &["--force"]),
    ];
    for (input, method, lods, rest) in cases {
        let mut args = vec!["export", input, "--method", method, "--lods", lods, "-o", o];
        args.extend_from_slice(rest);
        let r = lodstudio(&args);
        assert_eq!(r.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: one line: {err}");
        assert!(r.stdout.is_empty(), "{args:?}");
        assert_eq!(std::fs::read(&out).unwrap(), b"keep me", "{args:?}");
    }
    // Not a .glb name: refused before anything is written.
    let obj = tmp.path().join("chain.obj");
    let r = lodstudio(&[
        "export",
        "builtin:torus",
        "--method",
        "simplify",
        "--lods",
        "1%",
        "-o",
        obj.to_str().unwrap(),
    ]);
    assert_eq!(r.status.code(), Some(2));
    assert!(!obj.exists());
    // --force replaces it; a one-LOD chain is a plain GLB.
    let report = export_json("builtin:torus", "1%", &out, &["--force"]);
    assert_eq!(report["lods"].as_array().unwrap().len(), 1);
    let glb = std::fs::read(&out).unwrap();
    assert_eq!(report["bytes"].as_u64().unwrap() as usize, glb.len());
    assert!(glb_json(&glb).get("extensionsUsed").is_none());
    assert_eq!(
        gltf::read(&glb, None).unwrap().0.triangles.len() as u64,
        report["lods"][0]["triangles"].as_u64().unwrap()
    );
}

/// `.gltf` output: the JSON references its buffer in OUT.bin, and a loader
/// reads LOD0 back through it.
#[test]
fn gltf_with_a_separate_buffer_round_trips() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("torus.gltf");
    let report = export_json("builtin:torus", "1%,4%", &out, &[]);
    let doc: Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(doc["buffers"][0]["uri"], "torus.bin");
    let bin = std::fs::read(out.with_extension("bin")).unwrap();
    assert_eq!(
        doc["buffers"][0]["byteLength"].as_u64(),
        Some(bin.len() as u64)
    );
    assert_eq!(
        doc["nodes"][0]["extensions"]["MSFT_lod"]["ids"],
        serde_json::json!([1])
    );
    let back = lodstudio_json(&["info", out.to_str().unwrap()]);
    assert_eq!(back["triangles"], report["lods"][0]["triangles"]);
}

/// A folder in, one GLB per model out with a summary; a bad file is reported
/// (exit 2) and the good ones are still written.
#[test]
fn folder_batch_writes_one_file_per_model_and_reports_failures() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("batch-in");
    std::fs::create_dir(&dir).unwrap();
    for name in ["bones.off", "fandisk.obj"] {
        std::fs::copy(shared_model(name), dir.join(name)).unwrap();
    }
    std::fs::write(dir.join("broken.obj"), "v 0 0 0\nf 1 2 3\n").unwrap();
    std::fs::write(dir.join("notes.txt"), "not a model").unwrap();
    let out = tmp.path().join("batch-out");
    let (d, o) = (dir.to_str().unwrap(), out.to_str().unwrap());
    let run = lodstudio(&[
        "export", d, "--method", "simplify", "--lods", "2%", "-o", o, "--json",
    ]);
    assert_eq!(run.status.code(), Some(2));
    let j: Value = serde_json::from_slice(&run.stdout).expect("one JSON object");
    assert_eq!(
        (j["models"].as_u64(), j["built"].as_u64()),
        (Some(3), Some(2))
    );
    assert_eq!(
        (j["skipped"].as_u64(), j["failed"].as_u64()),
        (Some(0), Some(1))
    );
    assert_eq!(j["outputs"].as_array().unwrap().len(), 2);
    assert!(
        j["failures"][0]["file"]
            .as_str()
            .unwrap()
            .ends_with("broken.obj")
    );
    for name in ["bones.glb", "fandisk.glb"] {
        let back = lodstudio_json(&["info", out.join(name).to_str().unwrap()]);
        assert!(back["triangles"].as_u64().unwrap() > 0, "{name}");
    }
    // A rerun skips what the cache has; a glob picks the OFF file only;
    // --force rebuilds it.
    let pattern = format!("{d}/*.off");
    let again = lodstudio_json(&[
        "export", &pattern, "--method", "simplify", "--lods", "2%", "-o", o,
    ]);
    assert_eq!(
        (again["models"].as_u64(), again["skipped"].as_u64()),
        (Some(1), Some(1))
    );
    let forced = lodstudio_json(&[
        "export", &pattern, "--method", "simplify", "--lods", "2%", "-o", o, "--force",
    ]);
    assert_eq!(forced["built"].as_u64(), Some(1));
    // A file the batch did not make is kept without --force.
    std::fs::write(out.join("fandisk.glb"), b"the user's own").unwrap();
    std::fs::remove_dir_all(out.join(".lodstudio-cache")).unwrap();
    let kept = lodstudio(&["export", d, "--method", "simplify", "--lods", "2%", "-o", o]);
    assert_eq!(kept.status.code(), Some(2));
    assert_eq!(
        std::fs::read(out.join("fandisk.glb")).unwrap(),
        b"the user's own"
    );
}

/// Every hierarchy method exports a chain whose bounds meet the tolerances:
/// hybrid cuts (points included), merge-tree cuts and certified voxel levels.
#[test]
fn hybrid_mergetree_and_voxel_chains_round_trip() {
    let tmp = tempfile::tempdir().unwrap();
    let bunny = shared_model("stanford-bunny.obj");
    let b = bunny.to_str().unwrap();
    for (method, lods, extra) in [
        ("hybrid", "0.5%,2%,8%", &["--kappa", "8", "--tau", "5"][..]),
        ("mergetree", "0.5%,2%,8%", &[][..]),
        ("voxel", "4%,30%", &["--resolution", "64"][..]),
    ] {
        let out = tmp.path().join(format!("bunny-{method}.glb"));
        let mut args = vec![
            "export",
            b,
            "--method",
            method,
            "--lods",
            lods,
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let report = lodstudio_json(&args);
        assert_eq!(report["method"], method);
        let chain = check_chain(&out, &report);
        for (l, tol) in chain.iter().zip(lods.split(',')) {
            let f: f64 = tol.trim_end_matches('%').parse::<f64>().unwrap() / 100.0;
            assert!(
                l["error_bound_relative"].as_f64().unwrap() <= f * (1.0 + 1e-5),
                "{method}: {l}"
            );
        }
        if method == "hybrid" {
            assert!(
                chain.iter().any(|l| l["points"].as_u64().unwrap() > 0),
                "points in the chain"
            );
        }
    }
}

/// The input's materials reach every LOD: the milk truck's four materials (two
/// sharing one texture atlas) are carried as the file has them (the scene's
/// document is carried, issue 49), the atlas embedded once, and every LOD's
/// primitives wear them, one primitive per material per mesh.
#[test]
fn original_materials_and_textures_are_carried_into_every_lod() {
    let tmp = tempfile::tempdir().unwrap();
    let truck = shared_model("CesiumMilkTruck.glb");
    let input = std::fs::read(&truck).unwrap();
    let (original, _) = gltf::read(&input, None).unwrap();
    let materials = original.materials.clone().expect("the truck has materials");
    assert_eq!(materials.table.len(), 4);
    let atlas = materials.table[0]
        .base_color_texture
        .clone()
        .expect("textured");
    let src = glb_json(&input);
    for method in ["simplify", "mergetree", "hybrid"] {
        let out = tmp.path().join(format!("truck-{method}.glb"));
        let report = lodstudio_json(&[
            "export",
            truck.to_str().unwrap(),
            "--method",
            method,
            "--lods",
            "0.5%,2%,8%",
            "-o",
            out.to_str().unwrap(),
        ]);
        let lods = report["lods"].as_array().unwrap();
        assert_eq!(lods.len(), 3, "{method}");
        let glb = std::fs::read(&out).unwrap();
        assert_eq!(report["bytes"].as_u64().unwrap() as usize, glb.len());
        let doc = glb_json(&glb);
        assert_eq!(doc["materials"], src["materials"], "{method}");
        assert_eq!(doc["images"].as_array().unwrap().len(), 1, "one atlas");
        for l in 0..lods.len() {
            let meshes = lodstudio_tests::lod_meshes(&doc, l);
            assert!(!meshes.is_empty(), "{method} LOD {l}");
            let mut worn = std::collections::BTreeSet::new();
            for m in meshes {
                // The surface's primitives (a hybrid LOD's points come on top).
                let prims: Vec<&Value> = doc["meshes"][m]["primitives"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .filter(|p| p["mode"] == 4)
                    .collect();
                let of: Vec<u64> = prims
                    .iter()
                    .map(|p| p["material"].as_u64().unwrap())
                    .collect();
                assert!(
                    of.windows(2).all(|w| w[0] < w[1]),
                    "one primitive per material"
                );
                worn.extend(of);
                for p in prims {
                    let m = &doc["materials"][p["material"].as_u64().unwrap() as usize];
                    if m["pbrMetallicRoughness"].get("baseColorTexture").is_some() {
                        assert!(p["attributes"]["TEXCOORD_0"].is_u64(), "textured needs UVs");
                    }
                }
            }
            // A hybrid LOD may show a whole small mesh as points.
            if method != "hybrid" {
                assert_eq!(worn.len(), 4, "{method} LOD {l}: every material worn");
            }
        }
        // LOD0 read back wears the input's materials, image bytes included.
        let (back, _) = gltf::read(&glb, None).unwrap();
        let got = back.materials.expect("materials read back");
        assert_eq!(got.table, materials.table, "{method}");
        assert_eq!(got.table[0].base_color_texture.as_ref(), Some(&atlas));
    }
}

/// Mixed chains name each LOD's method; `--save-recipe` writes the run's
/// recipe and `--recipe` replays it byte for byte; method options beside
/// `--recipe` and bad recipe values are refused (exit 2) naming what is wrong.
#[test]
fn recipes_replay_mixed_chains_byte_for_byte() {
    let tmp = tempfile::tempdir().unwrap();
    let (first, recipe, replay) = (
        tmp.path().join("mixed-a.glb"),
        tmp.path().join("mixed.json"),
        tmp.path().join("mixed-b.glb"),
    );
    let fandisk = shared_model("fandisk.obj");
    let f = fandisk.to_str().unwrap();
    let report = lodstudio_json(&[
        "export",
        f,
        "--lods",
        "simplify:0.5%,simplify:2%,amg:15%",
        "-o",
        first.to_str().unwrap(),
        "--save-recipe",
        recipe.to_str().unwrap(),
        "--pixels",
        "2",
    ]);
    let methods: Vec<&str> = report["lods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["method"].as_str().unwrap())
        .collect();
    assert_eq!(methods, ["simplify", "simplify", "amg"]);
    assert_eq!(report["method"], "mixed");
    let lods = check_chain(&first, &report);
    assert!(lods[2]["splats"].as_u64().unwrap() > 0);
    let saved: Value = serde_json::from_slice(&std::fs::read(&recipe).unwrap()).unwrap();
    assert_eq!(
        (saved["format"].as_str(), saved["pixels"].as_f64()),
        (Some("lodstudio-recipe"), Some(2.0))
    );
    assert_eq!(saved["rows"].as_array().unwrap().len(), 3);
    let again = lodstudio_json(&[
        "export",
        f,
        "--recipe",
        recipe.to_str().unwrap(),
        "-o",
        replay.to_str().unwrap(),
    ]);
    assert_eq!(again["lods"].as_array().unwrap().len(), 3);
    assert_eq!(
        std::fs::read(&first).unwrap(),
        std::fs::read(&replay).unwrap()
    );
    // Method options beside --recipe.
    for extra in [
        &["--kappa", "4"][..],
        &["--lods", "1%"],
        &["--method", "hybrid"],
        &["--pixels", "3"],
    ] {
        let mut args = vec![
            "export",
            f,
            "--recipe",
            recipe.to_str().unwrap(),
            "-o",
            replay.to_str().unwrap(),
            "--force",
        ];
        args.extend_from_slice(extra);
        let r = lodstudio(&args);
        assert_eq!(r.status.code(), Some(2), "{extra:?}");
    }
    // A refused run saves no recipe.
    let unsaved = tmp.path().join("unsaved.json");
    let not_gltf = tmp.path().join("not-gltf.png");
    let refused = lodstudio(&[
        "export",
        f,
        "--lods",
        "simplify:1%",
        "-o",
        not_gltf.to_str().unwrap(),
        "--save-recipe",
        unsaved.to_str().unwrap(),
    ]);
    assert_eq!(refused.status.code(), Some(2));
    assert!(!unsaved.exists(), "no recipe for a run that did not happen");
    // A bad value names the row and the field.
    let bad = tmp.path().join("bad.json");
    let mut text = String::from_utf8(std::fs::read(&recipe).unwrap()).unwrap();
    text = text.replacen("\"amg\"", "\"hybrid\",\n      \"kappa\": 500", 1);
    std::fs::write(&bad, text).unwrap();
    let r = lodstudio(&[
        "export",
        f,
        "--recipe",
        bad.to_str().unwrap(),
        "-o",
        replay.to_str().unwrap(),
        "--force",
    ]);
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.contains("rows[2].kappa"), "{err}");
    assert_eq!(
        std::fs::read(&first).unwrap(),
        std::fs::read(&replay).unwrap(),
        "nothing lost"
    );
}

/// Rows that do not earn their place are flagged in the JSON: a row whose
/// budget gives the LOD of the row before (the torus' topology floor), and
/// an LOD that hands over where it takes over (two rows within a pixel
/// where the torus fills the viewport), checked against the coverages the
/// file writes: a flagged LOD's range is a sliver, every other one's is not.
#[test]
fn rows_that_do_not_earn_their_place_are_flagged() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("flagged.glb");
    let rows = "source,0.05%,0.08%,0.25,0.002,0.001";
    let report = export_json("builtin:torus", rows, &out, &[]);
    let lods = check_chain(&out, &report);
    let flags = |l: &Value| -> Vec<String> {
        l["flags"].as_array().map_or(Vec::new(), |f| {
            f.iter()
                .map(|f| f["flag"].as_str().unwrap().to_string())
                .collect()
        })
    };
    let all: Vec<Vec<String>> = lods.iter().map(flags).collect();
    assert_eq!(
        all,
        [
            vec![],
            vec!["never_shown".to_string()],
            vec![],
            vec![],
            vec!["duplicate".into()]
        ],
        "{report}"
    );
    let dup = &lods[4]["flags"][0];
    assert_eq!(dup["rows"], serde_json::json!(["simplify:0.001"]));
    assert_eq!(dup["of"], "simplify:0.002");
    assert!(dup["why"].as_str().unwrap().contains("gave the same LOD"));
    assert_eq!(
        lods[4]["rows"],
        serde_json::json!(["simplify:0.002", "simplify:0.001"])
    );
    for (k, l) in lods.iter().enumerate().skip(1) {
        let (c_in, c_out) = (
            lods[k - 1]["screen_coverage"].as_f64().unwrap(),
            l["screen_coverage"].as_f64().unwrap(),
        );
        let sliver = c_in / c_out < 1.001;
        assert_eq!(
            sliver,
            all[k].contains(&"never_shown".to_string()),
            "LOD{k}: {c_in} {c_out}"
        );
        // Points as POINTS: one each; a splat is a quad.
        let drawn = l["triangles"].as_u64().unwrap()
            + l["points"].as_u64().unwrap()
            + 2 * l["splats"].as_u64().unwrap();
        assert_eq!(l["drawn_primitives"], drawn, "{l}");
    }
}

/// A ratio row the torus cannot reach (its handle stays) says so in the
/// JSON, with why; a row that is met says nothing.
#[test]
fn an_unmet_budget_is_reported_with_why() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("far.glb");
    let report = export_json("builtin:torus", "0.25,0.001", &out, &[]);
    let lods = report["lods"].as_array().unwrap();
    assert!(lods[0].get("unmet").is_none(), "{}", lods[0]);
    let unmet = &lods[1]["unmet"];
    assert_eq!(unmet["asked"], 4, "{}", lods[1]);
    assert_eq!(unmet["reached"], lods[1]["triangles"]);
    assert!(unmet["why"].as_str().unwrap().starts_with("topology kept"));
}
