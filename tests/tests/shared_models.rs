//! Every file in `../shared/models` loads through `lodstudio info --json` with the
//! counts that `../shared/models/SOURCES.md` gives.

use lodstudio_tests::{lodstudio_json, shared_model};
use serde_json::Value;

fn info(name: &str) -> Value {
    lodstudio_json(&["info", shared_model(name).to_str().unwrap()])
}

fn count(v: &Value, key: &str) -> i64 {
    v[key]
        .as_i64()
        .unwrap_or_else(|| panic!("{key} missing in {v}"))
}

/// (file, vertices, triangles, components, boundary loops, genus) for the clean
/// triangle meshes: no repair changes them.
const CLEAN_MESHES: &[(&str, i64, i64, i64, i64, i64)] = &[
    ("stanford-bunny.obj", 34_834, 69_451, 1, 5, 0),
    ("horse.ply", 48_485, 96_966, 1, 0, 0),
    ("rocker-arm.obj", 10_044, 20_088, 1, 0, 1),
    ("fandisk.obj", 6_475, 12_946, 1, 0, 0),
    ("couplingdown.off", 1_841, 3_714, 1, 0, 9),
    ("knot2.off", 5_760, 11_520, 2, 0, 2),
    ("bones.off", 2_154, 4_204, 26, 0, 0),
];

#[test]
fn clean_meshes_match_sources_md() {
    for &(file, v, f, cc, b, g) in CLEAN_MESHES {
        let j = info(file);
        assert_eq!(count(&j, "vertices"), v, "{file} vertices");
        assert_eq!(count(&j, "triangles"), f, "{file} triangles");
        assert_eq!(count(&j, "components"), cc, "{file} components");
        assert_eq!(count(&j, "boundary_loops"), b, "{file} boundary loops");
        assert_eq!(count(&j, "genus"), g, "{file} genus");
        assert_eq!(count(&j, "points"), 0);
        assert!(j["bbox_diagonal"].as_f64().unwrap() > 0.0);
        for key in ["repairs", "kind", "format"] {
            assert!(j.get(key).is_some(), "{file}: {key}");
        }
    }
}

/// The bunny has 35,947 vertex records of which 34,834 are used: the repair
/// report must say so rather than hide it.
#[test]
fn unused_bunny_vertices_are_reported() {
    let j = info("stanford-bunny.obj");
    assert_eq!(
        j["repairs"]["unused_vertices_dropped"].as_i64(),
        Some(35_947 - 34_834)
    );
}

fn repair(j: &Value, key: &str) -> i64 {
    j["repairs"][key]
        .as_i64()
        .unwrap_or_else(|| panic!("repairs.{key} missing in {j}"))
}

/// Files with seams, duplicates and degenerate triangles: the by-index and welded
/// figures of SOURCES.md, and every dropped triangle accounted for.
#[test]
fn welded_models_match_sources_md() {
    let path = |f: &str| shared_model(f).to_str().unwrap().to_string();
    let truck = info("CesiumMilkTruck.glb");
    assert_eq!(
        (count(&truck, "vertices"), count(&truck, "triangles")),
        (1_840, 3_624)
    );
    assert_eq!(
        (count(&truck, "components"), count(&truck, "genus")),
        (13, 0)
    );
    let truck_raw = lodstudio_json(&["info", &path("CesiumMilkTruck.glb"), "--no-weld"]);
    assert_eq!(count(&truck_raw, "vertices"), 3_564);
    assert_eq!(count(&truck_raw, "components"), 240);

    // Engine: 115 mesh instances, 84,657 vertices by index, 11,154 triangles with a
    // repeated index; welding to 60,041 positions makes 6 more degenerate.
    let engine_raw = lodstudio_json(&["info", &path("2CylinderEngine.gltf"), "--no-weld"]);
    assert_eq!(count(&engine_raw, "vertices"), 84_657);
    assert_eq!(count(&engine_raw, "components"), 1_410);
    assert_eq!(
        repair(&engine_raw, "repeated_index_triangles_dropped"),
        11_154
    );
    let engine = info("2CylinderEngine.gltf");
    let dropped = repair(&engine, "repeated_index_triangles_dropped")
        + repair(&engine, "zero_area_triangles_dropped");
    assert_eq!(count(&engine, "triangles") + dropped, 121_496);
    // SOURCES.md welds to 60,041 with trimesh; we weld +0.0 and -0.0 together and
    // get 60,030 distinct positions, 11 fewer.
    let distinct = 84_657 - repair(&engine, "vertices_welded");
    assert!(
        (60_030..=60_041).contains(&distinct),
        "{distinct} distinct positions"
    );
    // Vertices used only by degenerate triangles go, and may take a component with them.
    assert!(count(&engine, "vertices") <= 60_041 && count(&engine, "components") <= 86);

    // Dragon: 2,100 exact duplicates; welding closes the cracks into one surface
    // with 108 degenerate triangles.
    let dragon = info("dragon_vrip.ply.gz");
    assert_eq!(repair(&dragon, "vertices_welded"), 2_100);
    assert_eq!(
        repair(&dragon, "repeated_index_triangles_dropped")
            + repair(&dragon, "zero_area_triangles_dropped"),
        108
    );
    assert_eq!(count(&dragon, "vertices"), 437_645 - 2_100);
    assert_eq!(count(&dragon, "triangles"), 871_414 - 108);
    assert_eq!(
        (
            count(&dragon, "components"),
            count(&dragon, "boundary_loops")
        ),
        (1, 0)
    );
}

#[test]
fn point_sets_match_sources_md() {
    let j = info("table_scene_mug_stereo_textured.ply");
    assert_eq!(count(&j, "points"), 209_280);
    assert_eq!(j["kind"], "points");
    let j = info("ball.ply");
    assert_eq!(count(&j, "points"), 31_374);
}

#[test]
fn volumes_match_sources_md() {
    let j = info("skull_2.9.inr");
    assert_eq!(j["grid"], serde_json::json!([64, 64, 64]));
    let sp: Vec<f64> = j["spacing"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!((sp[0] - 3.94305).abs() < 1e-4 && (sp[2] - 3.65079).abs() < 1e-4);
    let hi = j["value_range"][1].as_f64().unwrap();
    assert!((hi - 5.43).abs() < 0.01, "skull max {hi}");
    let j = info("ch2.nii.gz");
    assert_eq!(j["grid"], serde_json::json!([181, 217, 181]));
    assert_eq!(j["value_range"][1].as_f64(), Some(254.0));
}
