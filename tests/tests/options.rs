//! One test per CLI option that changes a result (issue 31), each asserting
//! the option's effect, not only that it is accepted.

use std::collections::HashMap;

use glam::Vec3;
use lodstudio_core::TriMesh;
use lodstudio_tests::{load_mesh, lodstudio_json, shared_model};

/// Positions of the vertices on a border (an edge of one triangle only).
fn border_positions(m: &TriMesh) -> Vec<Vec3> {
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let mut v: Vec<u32> = uses
        .iter()
        .filter(|(_, n)| **n == 1)
        .flat_map(|((a, b), _)| [*a, *b])
        .collect();
    v.sort_unstable();
    v.dedup();
    v.iter().map(|i| m.positions[*i as usize]).collect()
}

/// `--lock-borders`: every border vertex of the bunny's open base stays
/// where it was; without it, borders slide.
#[test]
fn lock_borders_keeps_every_border_vertex() {
    let tmp = tempfile::tempdir().unwrap();
    let bunny = shared_model("stanford-bunny.obj");
    let b = bunny.to_str().unwrap();
    let input = border_positions(&load_mesh(&bunny));
    assert!(input.len() > 20, "the bunny is open");
    let kept = |extra: &[&str]| {
        let out = tmp.path().join(format!("bunny{}.ply", extra.len()));
        let mut args = vec![
            "simplify",
            b,
            "--ratio",
            "0.05",
            "-o",
            out.to_str().unwrap(),
            "--force",
        ];
        args.extend_from_slice(extra);
        lodstudio_json(&args);
        let out_positions: Vec<[u32; 3]> = load_mesh(&out)
            .positions
            .iter()
            .map(|p| p.to_array().map(f32::to_bits))
            .collect();
        input
            .iter()
            .filter(|p| out_positions.contains(&p.to_array().map(f32::to_bits)))
            .count()
    };
    assert_eq!(kept(&["--lock-borders"]), input.len());
    assert!(kept(&[]) < input.len(), "unlocked, borders simplify too");
}

/// `--keep-seams`: the truck's UV seams stay seams (as many open loops in the
/// unwelded output as in the unwelded input); welded simplification closes
/// some of them.
#[test]
fn keep_seams_keeps_every_seam_loop() {
    let tmp = tempfile::tempdir().unwrap();
    let truck = shared_model("CesiumMilkTruck.glb");
    let t = truck.to_str().unwrap();
    let loops = |file: &str| {
        lodstudio_json(&["info", file, "--no-weld"])["boundary_loops"]
            .as_u64()
            .unwrap()
    };
    let input = loops(t);
    let kept = tmp.path().join("truck-seams.glb");
    let welded = tmp.path().join("truck-welded.glb");
    let (k, w) = (kept.to_str().unwrap(), welded.to_str().unwrap());
    lodstudio_json(&[
        "simplify",
        t,
        "--ratio",
        "0.5",
        "--keep-seams",
        "-o",
        k,
        "--force",
    ]);
    lodstudio_json(&["simplify", t, "--ratio", "0.5", "-o", w, "--force"]);
    assert_eq!(loops(k), input, "seams kept");
    let tris = |f: &str| lodstudio_json(&["info", f])["triangles"].as_u64().unwrap();
    assert!(tris(k) < tris(t), "and still simplified");
    assert_ne!(
        std::fs::read(&kept).unwrap(),
        std::fs::read(&welded).unwrap(),
        "the option changed the result"
    );
}

/// `--no-backface`, `--no-silhouette`, `--no-lighting`: back faces coarsen,
/// silhouettes and lighting refine, so turning each off moves the adaptive
/// cut's size the other way.
#[test]
fn merge_tree_criteria_switches_change_the_cut() {
    let bunny = shared_model("stanford-bunny.obj");
    let b = bunny.to_str().unwrap();
    let mean = |extra: &[&str]| {
        let mut args = vec!["mergetree", b, "--frames", "3", "--pixels", "2"];
        args.extend_from_slice(extra);
        lodstudio_json(&args)["adaptive_triangles_mean"]
            .as_f64()
            .unwrap()
    };
    let all = mean(&[]);
    assert!(
        mean(&["--no-backface"]) > all,
        "back faces no longer coarsened"
    );
    assert!(
        mean(&["--no-silhouette"]) < all,
        "silhouettes no longer refined"
    );
    assert!(mean(&["--no-lighting"]) < all, "lighting no longer refined");
}

/// `--matrix-out`: the stiffness matrix of §2.2 in Matrix Market form, one
/// row and column per point, symmetric, as many entries as it says.
#[test]
fn amg_matrix_out_writes_the_stiffness_matrix() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("stiffness.mtx");
    let j = lodstudio_json(&[
        "amg",
        "builtin:octahedron-points",
        "--matrix-out",
        out.to_str().unwrap(),
    ]);
    let n = j["points"].as_u64().unwrap() as usize;
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('%'));
    let header: Vec<usize> = lines
        .next()
        .unwrap()
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(&header[..2], &[n, n]);
    let entries: Vec<(usize, usize, f64)> = lines
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            (
                w[0].parse().unwrap(),
                w[1].parse().unwrap(),
                w[2].parse().unwrap(),
            )
        })
        .collect();
    assert_eq!(entries.len(), header[2]);
    assert!(entries.len() > n, "neighbours couple");
    let at: HashMap<(usize, usize), f64> = entries.iter().map(|&(r, c, v)| ((r, c), v)).collect();
    for (&(r, c), v) in &at {
        let w = at.get(&(c, r)).copied().unwrap_or(0.0);
        assert!(
            (v - w).abs() <= 1e-9 * v.abs().max(1.0),
            "symmetric at {r},{c}"
        );
    }
}

/// `export --method amg`: LODs of textured splats, coarser for a looser
/// error, their bound labelled an estimate (AMG's plane error).
#[test]
fn export_amg_writes_splat_lods() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("octahedron-lods.glb");
    let j = lodstudio_json(&[
        "export",
        "builtin:octahedron-points",
        "--method",
        "amg",
        "--lods",
        "0.5%,20%",
        "-o",
        out.to_str().unwrap(),
        "--force",
    ]);
    let lods = j["lods"].as_array().unwrap();
    assert_eq!(lods.len(), 2, "{j}");
    let splats: Vec<u64> = lods.iter().map(|l| l["splats"].as_u64().unwrap()).collect();
    assert!(splats[1] < splats[0] && splats[1] >= 8, "{splats:?}");
    assert!(lods.iter().all(|l| l["error_bound_kind"] == "estimate"));
    let glb = std::fs::read(&out).unwrap();
    let text = String::from_utf8_lossy(&glb);
    assert!(text.contains("MSFT_lod"));
    // One textured primitive per LOD (its splats' quads, their textures
    // in one atlas), holding a quad per splat.
    assert_eq!(
        text.matches("\"TEXCOORD_0\"").count(),
        2,
        "a primitive per LOD"
    );
    assert_eq!(text.matches("\"image/png\"").count(), 2, "an atlas per LOD");
    let doc = lodstudio_tests::glb_json(&glb);
    let indices: Vec<u64> = doc["meshes"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|m| m["primitives"].as_array().unwrap())
        .map(|p| {
            doc["accessors"][p["indices"].as_u64().unwrap() as usize]["count"]
                .as_u64()
                .unwrap()
        })
        .collect();
    assert_eq!(
        indices.iter().sum::<u64>(),
        6 * splats.iter().sum::<u64>(),
        "a quad per splat"
    );
}
