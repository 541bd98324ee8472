//! `compare`: two models rendered through the studio's pipelines from the same
//! views. A model against itself does not differ at all; a copy moved further
//! differs more, in silhouette and in PSNR; an exported LOD differs less than
//! a grossly displaced copy; a missing level of a chain is bad input.

use std::path::Path;

use glam::Vec3;
use lodstudio_core::io;
use lodstudio_tests::{lodstudio, lodstudio_json, shared_mesh, shared_model};
use serde_json::Value;

fn fandisk() -> String {
    shared_model("fandisk.obj").display().to_string()
}

/// `compare A B --json` (8 views of 256 px, the defaults): the mean silhouette
/// difference and PSNR, after checking the per-view list against them.
fn compare(a: &str, b: &str) -> (f64, f64) {
    let report = lodstudio_json(&["compare", a, b]);
    assert_eq!(report["size"], 256);
    let views = report["views"].as_array().expect("views");
    assert_eq!(views.len(), 8);
    let mean = |key: &str| views.iter().map(|v| v[key].as_f64().unwrap()).sum::<f64>() / 8.0;
    let (silhouette, psnr) = (
        f64_of(&report["silhouette_difference"]),
        f64_of(&report["psnr"]),
    );
    assert!(
        (mean("silhouette_difference") - silhouette).abs() < 1e-12,
        "{report}"
    );
    assert!((mean("psnr") - psnr).abs() < 1e-9, "{report}");
    for (i, v) in views.iter().enumerate() {
        assert_eq!(v["view"], i);
    }
    (silhouette, psnr)
}

fn f64_of(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("a number, not {v}"))
}

/// Fandisk moved by `fraction` of its bounding-box diagonal (obliquely), as OBJ
/// in `dir`.
fn displaced(dir: &Path, fraction: f32) -> String {
    let mut mesh = shared_mesh("fandisk.obj");
    let shift = Vec3::new(1.0, 0.6, 0.3).normalize() * fraction * mesh.bounds().diagonal();
    for p in &mut mesh.positions {
        *p += shift;
    }
    let out = dir.join(format!("fandisk-{fraction}.obj"));
    io::write_atomic(&out, &io::encode_mesh(&out, &mesh).unwrap()).unwrap();
    out.display().to_string()
}

#[test]
fn a_model_against_itself_differs_nowhere() {
    let report = lodstudio_json(&["compare", &fandisk(), &fandisk()]);
    for v in report["views"].as_array().unwrap() {
        assert_eq!(f64_of(&v["silhouette_difference"]), 0.0, "{v}");
        assert_eq!(f64_of(&v["psnr"]), 100.0, "capped: {v}");
    }
    assert_eq!(compare(&fandisk(), &fandisk()), (0.0, 100.0));
}

#[test]
fn a_copy_moved_further_differs_more() {
    let tmp = tempfile::tempdir().unwrap();
    let measured: Vec<(f64, f64)> = [0.005, 0.01, 0.02]
        .into_iter()
        .map(|f| compare(&fandisk(), &displaced(tmp.path(), f)))
        .collect();
    eprintln!("0.5%, 1%, 2% of the diagonal: {measured:?}");
    assert!(measured[0].0 > 0.0 && measured[0].1 < 100.0, "{measured:?}");
    for pair in measured.windows(2) {
        assert!(pair[1].0 > pair[0].0, "silhouette grows: {measured:?}");
        assert!(pair[1].1 < pair[0].1, "PSNR falls: {measured:?}");
    }
}

#[test]
fn an_exported_lod_differs_less_than_a_displaced_copy() {
    let tmp = tempfile::tempdir().unwrap();
    let chain = tmp.path().join("fandisk.glb");
    let chain_arg = chain.display().to_string();
    let out = lodstudio(&[
        "export",
        &fandisk(),
        "--method",
        "simplify",
        "--lods",
        "0.5%,8%",
        "-o",
        &chain_arg,
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lod0 = compare(&fandisk(), &format!("{chain_arg}#lod0"));
    let lod1 = compare(&fandisk(), &format!("{chain_arg}#lod1"));
    let far = compare(&fandisk(), &displaced(tmp.path(), 0.3));
    eprintln!("LOD0 {lod0:?}, LOD1 {lod1:?}, displaced by 30% {far:?}");
    assert!(
        lod0.0 <= lod1.0,
        "the finer LOD is closer: {lod0:?} {lod1:?}"
    );
    assert!(lod1.0 < far.0 && lod1.1 > far.1, "{lod1:?} vs {far:?}");

    // A level the chain does not have, and out-of-range options: bad input.
    let bad_runs: [&[&str]; 3] = [
        &["compare", &fandisk(), &format!("{chain_arg}#lod9")],
        &["compare", &fandisk(), &fandisk(), "--views", "65"],
        &["compare", &fandisk(), &fandisk(), "--size", "8"],
    ];
    for args in bad_runs {
        let out = lodstudio(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(out.stdout.is_empty());
    }
    let missing = lodstudio(&["compare", &fandisk(), &format!("{chain_arg}#lod9")]);
    assert!(String::from_utf8_lossy(&missing.stderr).contains("LOD 9"));
}

#[test]
fn difference_images_are_written_per_view() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("diff");
    let dir_arg = dir.display().to_string();
    let out = lodstudio(&[
        "compare",
        "builtin:torus",
        "builtin:sphere",
        "--views",
        "3",
        "--size",
        "64",
        "--save-diff",
        &dir_arg,
        "--save-views",
        &format!("{dir_arg}-views"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let size = |png: &[u8]| {
        let word = |at: usize| u32::from_be_bytes(png[at..at + 4].try_into().unwrap());
        (word(16), word(20))
    };
    for i in 0..3 {
        let png = std::fs::read(dir.join(format!("view{i}.png"))).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        assert_eq!(size(&png), (64, 64));
        // The two renders and the difference side by side.
        let views = std::fs::read(tmp.path().join(format!("diff-views/view{i}.png"))).unwrap();
        assert_eq!(size(&views), (3 * 64, 64));
    }
    assert!(!dir.join("view3.png").exists());
}
