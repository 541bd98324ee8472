//! The view-dependent merge tree (merge-tree paper) on real models: tree depth,
//! dependencies, folds and cold starts along a camera orbit, the screen-space
//! guarantee, back-face simplification, and the `mergetree` CLI contract.

use std::sync::{Arc, OnceLock};

use glam::Vec3;
use lodstudio_core::geom::Topology;
use lodstudio_core::io::{self, Model};
use lodstudio_core::mergetree::{self, Criteria, MergeTree, MergeTreeOptions, MergeTreeView, NONE};
use lodstudio_core::view::{Tolerance, View};
use lodstudio_core::{Progress, TriMesh};
use lodstudio_tests::{lodstudio, lodstudio_json, malformed_dir, shared_model};

fn load(name: &str) -> TriMesh {
    match io::load(&shared_model(name), &Default::default(), &Progress::new())
        .unwrap()
        .model
    {
        Model::Mesh(m) => m,
        _ => panic!("{name} is a mesh"),
    }
}

fn bunny_tree() -> Arc<MergeTree> {
    static TREE: OnceLock<Arc<MergeTree>> = OnceLock::new();
    TREE.get_or_init(|| {
        let mesh = load("stanford-bunny.obj");
        Arc::new(mergetree::build(&mesh, &MergeTreeOptions::default(), &Progress::new()).unwrap())
    })
    .clone()
}

/// Frame `i` of `frames` on an orbit at `distance` bounding-box diagonals.
fn orbit(tree: &MergeTree, i: usize, frames: usize, distance: f32) -> View {
    let b = tree.mesh().bounds();
    let a = i as f32 / frames as f32 * std::f32::consts::TAU;
    View::orbit(b.center(), distance * b.diagonal(), a, 0.3)
}

#[test]
fn tree_depth_is_within_three_log2_n_on_bunny_and_horse() {
    for (name, tree) in [
        ("bunny", bunny_tree()),
        (
            "horse",
            Arc::new(
                mergetree::build(
                    &load("horse.ply"),
                    &MergeTreeOptions::default(),
                    &Progress::new(),
                )
                .unwrap(),
            ),
        ),
    ] {
        let n = tree.mesh().positions.len();
        let levels = tree.levels();
        assert_eq!(levels[0], n, "{name}");
        assert!(levels.windows(2).all(|w| w[1] < w[0]), "{name}: {levels:?}");
        let bound = 3.0 * (n as f64).log2();
        assert!(
            (levels.len() as f64) <= bound,
            "{name}: {} levels > {bound:.1}",
            levels.len()
        );
        // Most of the way down: at most 1% of the vertices are left at the top.
        assert!(*levels.last().unwrap() * 100 <= n, "{name}: {levels:?}");
        assert_eq!(tree.merges().len(), n - levels.last().unwrap(), "{name}");
    }
}

#[test]
fn orbit_keeps_dependencies_no_folds_topology_and_matches_cold_starts() {
    let tree = bunny_tree();
    let before = Topology::of(tree.mesh());
    let mut warm = MergeTreeView::new(tree.clone(), Criteria::default());
    let mut cold = MergeTreeView::new(tree.clone(), Criteria::default());
    let frames = 200;
    let mut changes = 0;
    for i in 0..frames {
        let view = orbit(&tree, i, frames, 1.5);
        let stats = warm.update(&view, Tolerance::Pixels(4.0));
        assert_eq!(stats.fan_mismatches, 0, "frame {i}");
        if i > 0 {
            changes += stats.splits + stats.merges;
        }
        for k in 0..tree.merges().len() {
            if warm.is_merged(k) {
                for j in tree.requires(k) {
                    assert!(warm.is_merged(*j as usize), "frame {i}: {k} needs {j}");
                }
            }
        }
        assert_eq!(warm.folds(), 0, "frame {i}");
        cold.reset();
        assert_eq!(cold.update(&view, Tolerance::Pixels(4.0)).fan_mismatches, 0);
        let same = (0..tree.merges().len()).all(|k| warm.is_merged(k) == cold.is_merged(k));
        assert!(same, "frame {i}: incremental and cold-start cuts differ");
        if i % 25 == 0 {
            assert!(
                warm.display_triangles().eq(cold.display_triangles()),
                "frame {i}"
            );
            let set = warm.draw_set();
            assert!(set.mesh.triangles.len() < tree.mesh().triangles.len());
            let after = Topology::of(&set.mesh);
            assert_eq!(after.components.len(), before.components.len(), "frame {i}");
            let genus = |t: &Topology| t.components.iter().map(|c| c.genus).sum::<i64>();
            assert_eq!(genus(&after), genus(&before), "frame {i}");
            assert_eq!(after.is_manifold(), before.is_manifold(), "frame {i}");
        }
    }
    // The camera moved: the cut changed frame to frame.
    assert!(changes > frames, "{changes} changes");
}

#[test]
fn displayed_vertices_meet_the_screen_space_threshold() {
    let tree = bunny_tree();
    // Silhouettes and lighting only lower the threshold; back faces (off here)
    // would raise it.
    let criteria = Criteria {
        backface: false,
        ..Criteria::default()
    };
    let mut view_state = MergeTreeView::new(tree.clone(), criteria);
    let t = 3.0;
    let mut checked = 0;
    for i in 0..12 {
        // Flying in: from 3 diagonals to 0.8.
        let view = orbit(&tree, i, 12, 3.0 - 0.2 * i as f32);
        view_state.update(&view, Tolerance::Pixels(t));
        let set = view_state.draw_set();
        if i % 5 == 0 {
            // The cut's bound against a dense two-sided measurement of the original.
            let opts = lodstudio_core::distance::SamplingOptions {
                samples: 100_000,
                ..Default::default()
            };
            let d = lodstudio_core::distance::hausdorff_mesh_mesh(tree.mesh(), &set.mesh, &opts);
            assert!(
                d.two_sided() <= set.error_bound * 1.0001 + 1e-7,
                "frame {i}: {d:?} > {}",
                set.error_bound
            );
            assert!(
                set.mesh.triangles.len() < tree.mesh().triangles.len(),
                "frame {i}: coarser"
            );
        }
        let mut shown: Vec<u32> = view_state
            .display_triangles()
            .flat_map(|tri| tree.triangle(tri))
            .collect();
        shown.sort_unstable();
        shown.dedup();
        let mut worst = 0f32;
        for v in shown {
            let k = view_state.node_of(v);
            if k == NONE {
                continue; // a leaf
            }
            let node = &tree.nodes()[k as usize];
            let px = view.pixels(node.downswitch, node.center, node.radius);
            assert!(px <= t, "frame {i}: vertex {v} projects {px} px");
            worst = worst.max(node.downswitch);
            checked += 1;
        }
        assert!((set.error_bound - worst).abs() <= 1e-6 * worst.max(1.0));
    }
    assert!(
        checked > 1000,
        "{checked} non-leaf display vertices checked"
    );
}

/// Display triangles facing the eye and facing away.
fn front_and_back(view_state: &MergeTreeView, eye: Vec3) -> (usize, usize) {
    let tree = view_state.tree();
    let p = |v: u32| tree.mesh().positions[v as usize];
    let mut counts = (0, 0);
    for t in view_state.display_triangles() {
        let [a, b, c] = tree.triangle(t).map(p);
        if (b - a).cross(c - a).dot(a - eye) < 0.0 {
            counts.0 += 1;
        } else {
            counts.1 += 1;
        }
    }
    counts
}

#[test]
fn backface_criterion_simplifies_the_far_side() {
    let tree = bunny_tree();
    let only = |backface| Criteria {
        backface,
        silhouette: false,
        lighting: false,
    };
    let mut with = MergeTreeView::new(tree.clone(), only(true));
    let mut without = MergeTreeView::new(tree.clone(), only(false));
    for i in 0..4 {
        let view = orbit(&tree, i, 4, 1.5);
        with.update(&view, Tolerance::Pixels(2.0));
        without.update(&view, Tolerance::Pixels(2.0));
        let (front_on, back_on) = front_and_back(&with, view.eye);
        let (front_off, back_off) = front_and_back(&without, view.eye);
        assert!(
            back_on * 2 < back_off,
            "frame {i}: back {back_on} vs {back_off}"
        );
        assert!(
            front_on * 10 >= front_off * 8,
            "frame {i}: front {front_on} vs {front_off}"
        );
    }
}

#[test]
fn cli_reports_table_one_and_writes_the_last_frame() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("mergetree.ply");
    let o = out.to_str().unwrap();
    let horse = shared_model("horse.ply");
    let j = lodstudio_json(&[
        "mergetree",
        horse.to_str().unwrap(),
        "--frames",
        "30",
        "--pixels",
        "3",
        "-o",
        o,
        "--force",
    ]);
    for key in [
        "levels",
        "uniform_triangles",
        "adaptive_triangles_mean",
        "update_ms_mean",
        "rebuild_ms_mean",
        "folds",
    ] {
        assert!(j.get(key).is_some(), "{key}");
    }
    assert_eq!(j["folds"], 0);
    // Compared frame by frame with a cold start from all vertices.
    assert_eq!(j["frames_differing_from_cold"], 0, "{j}");
    assert_eq!(j["fan_mismatches"], 0);
    assert_eq!(j["incremental_equals_cold"], true);
    let levels = j["levels"].as_array().unwrap();
    assert_eq!(levels[0], j["vertices"]);
    let adaptive = j["adaptive_triangles_mean"].as_f64().unwrap();
    assert!(adaptive > 0.0 && adaptive < j["original_triangles"].as_f64().unwrap());
    let back = lodstudio_json(&["info", o]);
    assert_eq!(back["components"], 1);
    assert_eq!(back["genus"], 0);
    assert!(back["triangles"].as_f64().unwrap() > 0.0);
    // The zoom path refines as the camera comes closer.
    let zoom = lodstudio_json(&[
        "mergetree",
        "builtin:torus",
        "--frames",
        "10",
        "--pixels",
        "2",
        "--zoom",
    ]);
    assert_eq!(zoom["folds"], 0);
    // Flying in from 3 diagonals to 0.75 at a fixed pixel threshold: more
    // triangles near than far.
    let per_frame: Vec<f64> = zoom["adaptive_triangles"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(per_frame.len(), 10);
    assert!(per_frame[9] > 1.1 * per_frame[0], "{per_frame:?}");
    assert!(
        per_frame.windows(2).all(|w| w[1] >= 0.9 * w[0]),
        "{per_frame:?}"
    );
}

#[test]
fn cli_rejects_bad_arguments_with_exit_2() {
    let horse = shared_model("horse.ply");
    let h = horse.to_str().unwrap();
    let malformed: Vec<String> = std::fs::read_dir(malformed_dir())
        .unwrap()
        .map(|e| e.unwrap().path().to_str().unwrap().to_string())
        .collect();
    assert!(!malformed.is_empty());
    let mut cases: Vec<Vec<&str>> = malformed
        .iter()
        .map(|m| vec!["mergetree", m.as_str(), "--frames", "1"])
        .collect();
    cases.extend([
        vec!["mergetree", h, "--pixels", "0"],
        vec!["mergetree", h, "--pixels", "NaN"],
        vec!["mergetree", h, "--frames", "0"],
        vec!["mergetree", h, "--min-quality", "2"],
        vec!["mergetree", "/nonexistent/model.obj"],
        vec!["mergetree", "builtin:octahedron-points"],
    ]);
    for args in cases {
        let out = lodstudio(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}");
    }
}
