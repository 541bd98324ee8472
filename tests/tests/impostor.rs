//! Octahedral impostors (issue 50, item 5): the milk truck as alpha-masked
//! cards on one atlas looks more like the truck than its AMG splat
//! impostor (its texture sampled too), in one valid primitive; bad
//! requests are refused with exit code 2.

use lodstudio_tests::{glb_json, lodstudio, lodstudio_json, shared_model};

#[test]
fn the_trucks_impostor_is_recognisable() {
    let dir = tempfile::tempdir().unwrap();
    let truck = shared_model("CesiumMilkTruck.glb");
    let truck = truck.to_str().unwrap();
    let out = |name: &str| dir.path().join(name).display().to_string();
    let cards = out("impostor.glb");
    let r = lodstudio_json(&["impostor", truck, "-o", &cards]);
    assert_eq!(r["views"], 8, "{r}");
    let n = r["cards"].as_u64().unwrap();
    assert!((6..=10).contains(&n), "{r}");
    assert_eq!(r["triangles"].as_u64().unwrap(), 2 * n, "{r}");
    let relative = r["silhouette_error_relative"].as_f64().unwrap();
    assert!(relative > 0.0 && relative < 0.3, "{r}");
    // One alpha-masked material with a colour atlas and a normal map, one
    // primitive with its tangents.
    let doc = glb_json(&std::fs::read(&cards).unwrap());
    let material = &doc["materials"][0];
    assert_eq!(doc["materials"].as_array().unwrap().len(), 1);
    assert_eq!(material["alphaMode"], "MASK", "{material}");
    assert!(material["normalTexture"]["index"].is_u64(), "{material}");
    let primitives = doc["meshes"][0]["primitives"].as_array().unwrap();
    assert_eq!(primitives.len(), 1);
    assert!(primitives[0]["attributes"]["TANGENT"].is_u64());
    // Against the AMG splat impostor (15 %) through the studio's renderer
    // (8 views): measured 14.4 dB and 5.4 % of pixels covered by one only,
    // against 12.0 dB and 9.9 %.
    let splats = out("splats.glb");
    lodstudio_json(&[
        "export", truck, "--method", "amg", "--lods", "15%", "-o", &splats,
    ]);
    let compare = |file: &str| lodstudio_json(&["compare", truck, file]);
    let (a, b) = (compare(&cards), compare(&format!("{splats}#lod0")));
    let (pa, pb) = (a["psnr"].as_f64().unwrap(), b["psnr"].as_f64().unwrap());
    let (sa, sb) = (
        a["silhouette_difference"].as_f64().unwrap(),
        b["silhouette_difference"].as_f64().unwrap(),
    );
    eprintln!("truck impostor: {pa:.2} dB, silhouette {sa:.3}; AMG splats {pb:.2} dB, {sb:.3}");
    assert!(pa > pb + 1.0, "{pa} vs {pb}");
    assert!(sa < 0.75 * sb, "{sa} vs {sb}");
    for bad in [
        vec!["--views", "1", "-o", &out("a.glb")],
        vec!["--views", "8", "--texture-size", "64", "-o", &out("b.glb")],
        vec!["-o", &out("c.obj")],
    ] {
        let mut args = vec!["impostor", truck];
        args.extend(bad);
        let o = lodstudio(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
    }
}

/// An impostor row joins a chain as its farthest LOD: its cards, its
/// measured silhouette error as its bound, and the smallest switch
/// coverage, whatever tolerance the row gives (it has one cut).
#[test]
fn an_impostor_row_ends_the_chain() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("chain.glb").display().to_string();
    let torus = "builtin:torus";
    let solo = dir.path().join("solo.glb").display().to_string();
    let alone = lodstudio_json(&["impostor", torus, "-o", &solo]);
    let report = lodstudio_json(&[
        "export",
        torus,
        "--lods",
        "simplify:1%,simplify:0.1,impostor:1px",
        "-o",
        &out,
    ]);
    let lods = report["lods"].as_array().unwrap();
    assert_eq!(lods.len(), 3, "{report}");
    let last = &lods[2];
    assert_eq!(last["triangles"], alone["triangles"], "{last}");
    assert_eq!(
        last["error_bound"], alone["silhouette_error"],
        "{last} against {alone}"
    );
    assert_eq!(last["error_bound_kind"], "estimate");
    assert!(last.get("uv_error").is_none_or(|u| u.is_null()), "{last}");
    let coverage = |l: &serde_json::Value| l["screen_coverage"].as_f64().unwrap();
    assert!(coverage(last) < coverage(&lods[1]) && coverage(&lods[1]) < coverage(&lods[0]));
    // A recipe row takes views and the atlas's size; it refuses bake.
    let recipe = dir.path().join("r.json");
    let saved = dir.path().join("saved.glb").display().to_string();
    lodstudio_json(&[
        "export",
        torus,
        "--lods",
        "simplify:1%,impostor:1px",
        "-o",
        &saved,
        "--save-recipe",
        recipe.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&recipe).unwrap();
    assert!(
        text.contains("\"views\": 8") || text.contains("\"views\":8"),
        "{text}"
    );
}
