//! Saved hierarchies (issue 9): `--save` writes a versioned, checksummed file
//! that `cut` reopens without rebuilding, giving the very same cut; damaged
//! files are refused with a clear error (exit 2).

use lodstudio_tests::{lodstudio, lodstudio_json, shared_model};

#[test]
fn reopened_hierarchies_cut_exactly_as_built() {
    let tmp = tempfile::tempdir().unwrap();
    let bunny = shared_model("stanford-bunny.obj");
    let b = bunny.to_str().unwrap();
    // Hybrid: the cut written at build time and the reopened one are the same file.
    let (h, built, again) = (
        tmp.path().join("bunny.lodh"),
        tmp.path().join("built.glb"),
        tmp.path().join("again.glb"),
    );
    let j = lodstudio_json(&[
        "hybrid",
        b,
        "--kappa",
        "8",
        "--tau",
        "5",
        "--cut-error",
        "2%",
        "-o",
        built.to_str().unwrap(),
        "--save",
        h.to_str().unwrap(),
        "--force",
    ]);
    let reopened = lodstudio_json(&[
        "cut",
        h.to_str().unwrap(),
        "--error",
        "2%",
        "-o",
        again.to_str().unwrap(),
        "--force",
    ]);
    assert_eq!(reopened["method"], "hybrid");
    assert_eq!(reopened["params"]["kappa"], 8.0);
    assert_eq!(reopened["triangles"], j["cut"]["triangles"]);
    assert_eq!(reopened["points"], j["cut"]["points"]);
    assert_eq!(
        std::fs::read(&built).unwrap(),
        std::fs::read(&again).unwrap()
    );
    let info = lodstudio_json(&["info", h.to_str().unwrap()]);
    assert_eq!(
        (info["kind"].as_str(), info["method"].as_str()),
        (Some("hierarchy"), Some("hybrid"))
    );

    // Merge tree and voxel pyramid: reopened cuts are deterministic and sized sensibly.
    let m = tmp.path().join("bunny-tree.lodh");
    lodstudio_json(&[
        "mergetree",
        b,
        "--frames",
        "2",
        "--save",
        m.to_str().unwrap(),
        "--force",
    ]);
    let fine = lodstudio_json(&["cut", m.to_str().unwrap(), "--error", "0.2%"]);
    let coarse = lodstudio_json(&["cut", m.to_str().unwrap(), "--error", "4%"]);
    assert!(coarse["triangles"].as_u64() < fine["triangles"].as_u64());
    assert!(coarse["error_bound"].as_f64().unwrap() > 0.0);
    let v = tmp.path().join("part.lodh");
    lodstudio_json(&[
        "voxel",
        "builtin:csg-part",
        "--pyramid",
        "--resolution",
        "32",
        "--save",
        v.to_str().unwrap(),
        "--force",
    ]);
    let level0 = lodstudio_json(&["cut", v.to_str().unwrap()]);
    let direct = lodstudio_json(&[
        "voxel",
        "builtin:csg-part",
        "--pyramid",
        "--resolution",
        "32",
    ]);
    assert_eq!(level0["triangles"], direct["levels"][0]["triangles"]);
    let between = lodstudio_json(&["cut", v.to_str().unwrap(), "--at", "0.5"]);
    assert!(between["triangles"].as_u64() < level0["triangles"].as_u64());

    // AMG multiscale: a looser plane error draws fewer, larger splats.
    let a = tmp.path().join("octahedron.lodh");
    lodstudio_json(&[
        "amg",
        "builtin:octahedron-points",
        "--save",
        a.to_str().unwrap(),
        "--force",
    ]);
    let fine = lodstudio_json(&["cut", a.to_str().unwrap(), "--error", "1.8%"]);
    let coarse = lodstudio_json(&["cut", a.to_str().unwrap(), "--error", "8%"]);
    assert_eq!(fine["method"], "amg");
    assert!(
        coarse["splats"].as_u64() < fine["splats"].as_u64(),
        "{coarse} {fine}"
    );
}

#[test]
fn damaged_hierarchies_are_refused_clearly() {
    let tmp = tempfile::tempdir().unwrap();
    let v = tmp.path().join("damaged.lodh");
    lodstudio_json(&[
        "voxel",
        "builtin:csg-part",
        "--pyramid",
        "--resolution",
        "16",
        "--save",
        v.to_str().unwrap(),
        "--force",
    ]);
    let bytes = std::fs::read(&v).unwrap();
    let cases: Vec<(&str, Vec<u8>)> = vec![
        ("truncated", bytes[..bytes.len() / 2].to_vec()),
        ("checksum", {
            let mut b = bytes.clone();
            let mid = b.len() / 2;
            b[mid] ^= 0xff;
            b
        }),
        ("not a saved lodstudio hierarchy", b"LODSTHR".to_vec()),
    ];
    for (what, data) in cases {
        let path = tmp.path().join(format!("bad-{}.lodh", what.len()));
        std::fs::write(&path, data).unwrap();
        let out = lodstudio(&["cut", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2), "{what}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{what}: {err}");
        assert!(err.contains(what), "{what}: {err}");
    }
}

/// `simplify --save` keeps the progressive collapse (issue 25): a cut to N
/// triangles is byte for byte what `simplify --triangles N` writes, an
/// error cut is the coarsest within the error with a bound a dense
/// measurement never exceeds, and a tighter error never gives a larger bound.
#[test]
fn a_saved_edge_collapse_cuts_as_fresh_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let bunny = shared_model("stanford-bunny.obj");
    let b = bunny.to_str().unwrap();
    let (p, floor) = (
        tmp.path().join("bunny-collapse.lodh"),
        tmp.path().join("floor.ply"),
    );
    let run = lodstudio_json(&[
        "simplify",
        b,
        "--ratio",
        "0.05",
        "-o",
        floor.to_str().unwrap(),
        "--save",
        p.to_str().unwrap(),
        "--force",
    ]);
    let p = p.to_str().unwrap();
    let input = run["input_triangles"].as_u64().unwrap();
    let floor_n = run["output_triangles"].as_u64().unwrap();
    for n in [floor_n, input / 10, input / 3] {
        let (fresh, cut) = (
            tmp.path().join(format!("fresh{n}.ply")),
            tmp.path().join(format!("cut{n}.ply")),
        );
        let n_arg = n.to_string();
        let (fresh_s, cut_s) = (fresh.to_str().unwrap(), cut.to_str().unwrap());
        let f = lodstudio_json(&[
            "simplify",
            b,
            "--triangles",
            &n_arg,
            "-o",
            fresh_s,
            "--force",
        ]);
        let j = lodstudio_json(&["cut", p, "--triangles", &n_arg, "-o", cut_s, "--force"]);
        assert_eq!(j["method"], "simplify");
        assert_eq!(j["triangles"], f["output_triangles"], "{j}");
        assert!(j["triangles"].as_u64().unwrap() <= n);
        assert_eq!(
            std::fs::read(&fresh).unwrap(),
            std::fs::read(&cut).unwrap(),
            "{n}"
        );
        let measured = lodstudio_json(&["measure", b, cut_s, "--samples", "200000"]);
        let bound = j["error_bound"].as_f64().unwrap();
        assert!(
            measured["hausdorff"].as_f64().unwrap() <= bound,
            "{n}: {measured} vs {j}"
        );
        let rel = j["error_bound_relative"].as_f64().unwrap();
        assert!((rel * j["bbox_diagonal"].as_f64().unwrap() - bound).abs() <= 1e-6 * bound);
    }
    let mut last = (u64::MAX, f64::INFINITY);
    for e in ["0.01%", "0.05%", "0.2%"] {
        let j = lodstudio_json(&["cut", p, "--error", e]);
        let limit = e.trim_end_matches('%').parse::<f64>().unwrap() / 100.0;
        let rel = j["error_bound_relative"].as_f64().unwrap();
        assert!(rel <= limit * 1.0001, "{e}: {j}");
        let n = j["triangles"].as_u64().unwrap();
        assert!(
            n < last.0 && n >= floor_n,
            "a looser error, fewer triangles: {e}"
        );
        last = (n, rel);
    }
    // An absolute error is a distance: the diagonal's 0.05% as a number cuts alike.
    let rel = lodstudio_json(&["cut", p, "--error", "0.05%"]);
    let abs = format!("{}", 0.0005 * rel["bbox_diagonal"].as_f64().unwrap());
    let j = lodstudio_json(&["cut", p, "--error", &abs]);
    assert_eq!(j["triangles"], rel["triangles"]);
}
