//! The `voxel` subcommand's contract (DESIGN.md) and the genus falling as the
//! low-pass filter widens (voxel paper §2, Tables 1–3).

use lodstudio_tests::{lodstudio, lodstudio_json, shared_model};

#[test]
fn single_level_reports_the_contract_keys_and_writes_the_mesh() {
    let out = std::env::temp_dir().join(format!("lodstudio-voxel-{}.ply", std::process::id()));
    let o = out.to_str().unwrap();
    let j = lodstudio_json(&[
        "voxel",
        "builtin:csg-part",
        "--resolution",
        "48",
        "--radius",
        "1",
        "--filter",
        "gaussian",
        "-o",
        o,
        "--force",
    ]);
    for key in [
        "resolution",
        "radius",
        "triangles",
        "components",
        "genus",
        "layers",
        "seconds",
    ] {
        assert!(j.get(key).is_some(), "{key}");
    }
    assert_eq!(
        (j["components"].as_i64(), j["genus"].as_i64()),
        (Some(1), Some(5))
    );
    let back = lodstudio_json(&["info", o]);
    assert_eq!(back["triangles"], j["triangles"]);
    assert_eq!(back["genus"], 5);
    std::fs::remove_file(&out).unwrap();
}

#[test]
fn pyramid_lists_levels_finest_first_and_loses_genus() {
    let j = lodstudio_json(&[
        "voxel",
        "builtin:csg-part",
        "--pyramid",
        "--resolution",
        "64",
        "--radius",
        "2",
        "--filter",
        "cone",
    ]);
    let levels = j["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 4, "64, 32, 16, 8");
    let res: Vec<i64> = levels
        .iter()
        .map(|l| l["resolution"].as_i64().unwrap())
        .collect();
    assert_eq!(res, [64, 32, 16, 8]);
    // Radius in finest voxels doubles as the grid halves.
    let radius: Vec<f64> = levels
        .iter()
        .map(|l| l["radius"].as_f64().unwrap())
        .collect();
    assert_eq!(radius, [2.0, 4.0, 8.0, 16.0]);
    let genus: Vec<i64> = levels
        .iter()
        .map(|l| l["genus"].as_i64().unwrap())
        .collect();
    assert_eq!(genus[0], 5);
    assert!(genus.last().unwrap() < &5, "genus falls: {genus:?}");
}

#[test]
fn volumes_use_their_grid_and_point_sets_are_refused_clearly() {
    let skull = shared_model("skull_2.9.inr");
    let j = lodstudio_json(&[
        "voxel",
        skull.to_str().unwrap(),
        "--iso",
        "2.9",
        "--radius",
        "1",
    ]);
    assert_eq!(j["resolution"], 64);
    assert!(j["triangles"].as_u64().unwrap() > 1000);
    for args in [
        &["voxel", "builtin:octahedron-points"][..],
        &["voxel", "builtin:csg-part", "--resolution", "2"],
        &["voxel", "builtin:csg-part", "--radius", "-1"],
        &["voxel", "builtin:csg-part", "--filter", "box"],
    ] {
        let out = lodstudio(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert_eq!(
            String::from_utf8_lossy(&out.stderr).trim().lines().count(),
            1,
            "{args:?}"
        );
    }
}

/// Meshes are sampled through their generalised winding number: the bunny's
/// open base still has an inside, and the holes of the coupling close one by
/// one as the filter widens (Tables 1–3).
#[test]
fn meshes_are_solids_and_their_genus_falls_along_the_pyramid() {
    let bunny = shared_model("stanford-bunny.obj");
    let j = lodstudio_json(&[
        "voxel",
        bunny.to_str().unwrap(),
        "--resolution",
        "40",
        "--radius",
        "1",
    ]);
    assert_eq!(
        (j["components"].as_i64(), j["genus"].as_i64()),
        (Some(1), Some(0))
    );

    let coupling = shared_model("couplingdown.off");
    let j = lodstudio_json(&[
        "voxel",
        coupling.to_str().unwrap(),
        "--pyramid",
        "--resolution",
        "64",
    ]);
    let levels = j["levels"].as_array().unwrap();
    let column = |k: &str| -> Vec<i64> { levels.iter().map(|l| l[k].as_i64().unwrap()).collect() };
    let (genus, triangles) = (column("genus"), column("triangles"));
    assert!(genus[0] >= 5, "the finest level keeps the holes: {genus:?}");
    assert!(
        genus.windows(2).all(|w| w[1] <= w[0]),
        "never rises: {genus:?}"
    );
    assert_eq!(*genus.last().unwrap(), 0, "{genus:?}");
    for w in triangles.windows(2) {
        let ratio = w[0] as f64 / w[1] as f64;
        assert!(
            (3.0..6.0).contains(&ratio),
            "about 4x per halving: {triangles:?}"
        );
    }
}
