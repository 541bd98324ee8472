//! Edge collapse with a certified bound, checked against an independent dense
//! measurement on real models (issue 3's checks), and the `simplify` CLI contract.

use lodstudio_core::distance::{SamplingOptions, hausdorff_mesh_mesh};
use lodstudio_core::geom::Topology;
use lodstudio_core::io::{self, Model};
use lodstudio_core::simplify::{self, CollapseOptions, SimplifyOptions, Target};
use lodstudio_core::{Progress, TriMesh};
use lodstudio_tests::{lodstudio, lodstudio_json, shared_model};

fn load(name: &str) -> TriMesh {
    load_file(shared_model(name).to_str().unwrap())
}

fn load_file(path: &str) -> TriMesh {
    match io::load(
        std::path::Path::new(path),
        &Default::default(),
        &Progress::new(),
    )
    .unwrap()
    .model
    {
        Model::Mesh(m) => m,
        _ => panic!("{path} is a mesh"),
    }
}

#[test]
fn certified_bound_holds_against_dense_sampling_and_is_tight() {
    let mut ratios = Vec::new();
    for name in [
        "stanford-bunny.obj",
        "horse.ply",
        "rocker-arm.obj",
        "fandisk.obj",
        "2CylinderEngine.gltf",
    ] {
        let mesh = load(name);
        let before = Topology::of(&mesh);
        for ratio in [0.5, 0.1, 0.01] {
            let opts = SimplifyOptions {
                per_triangle_bounds: false,
                target: Target::Ratio(ratio),
                collapse: CollapseOptions::default(),
            };
            let r = simplify::simplify(&mesh, &opts, &Progress::new()).unwrap();
            let measured = hausdorff_mesh_mesh(
                &mesh,
                &r.mesh,
                &SamplingOptions {
                    samples: 300_000,
                    seed: 3,
                },
            )
            .two_sided();
            let bound = r.error_bound();
            assert!(
                measured <= bound,
                "{name} at {ratio}: measured {measured} > bound {bound}"
            );
            ratios.push(bound / measured.max(f32::MIN_POSITIVE));
            // Topology kept, nothing flipped, attributes carried.
            let after = Topology::of(&r.mesh);
            assert_eq!(
                after.components.len(),
                before.components.len(),
                "{name} at {ratio}: components"
            );
            if before.non_manifold_edges == 0 {
                assert_eq!(after.genus, before.genus, "{name} at {ratio}: genus");
                assert_eq!(after.non_manifold_edges, 0);
            }
            assert_eq!(
                after.inconsistent_edges,
                before.inconsistent_edges.min(after.inconsistent_edges)
            );
            assert_eq!(
                r.mesh.normals.is_some(),
                mesh.normals.is_some(),
                "{name}: normals"
            );
            assert_eq!(
                r.mesh.colors.is_some(),
                mesh.colors.is_some(),
                "{name}: colours"
            );
            assert_eq!(r.certificate.triangle_bounds.len(), r.mesh.triangles.len());
            assert!(r.certificate.triangle_bounds.iter().all(|b| *b <= bound));
        }
    }
    ratios.sort_by(f32::total_cmp);
    let median = ratios[ratios.len() / 2];
    eprintln!("bound / measured, sorted: {ratios:?}");
    assert!(median <= 2.0, "median bound/measured {median}");
    // Every case, not only the median: the fandisk's flat faces end at
    // creases, where branch and bound alone left its bound 9× the measurement.
    let worst = ratios[ratios.len() - 1];
    assert!(worst <= 1.5, "worst bound/measured {worst}");
}

/// Issue 50, item 2: on the textured truck a larger UV tolerance crosses
/// more seams (fewer triangles), the geometric certificate still holds
/// against an independent measurement, and the texture stays where the
/// original shows it (measured within the bound, in texels); a tolerance
/// out of range is refused with exit code 2.
#[test]
fn the_truck_crosses_its_seams_within_the_uv_tolerance() {
    let truck = load("CesiumMilkTruck.glb");
    let run = |uv_tolerance: f32| {
        let opts = SimplifyOptions {
            per_triangle_bounds: false,
            target: Target::Triangles(100),
            collapse: CollapseOptions {
                uv_tolerance,
                ..Default::default()
            },
        };
        simplify::simplify(&truck, &opts, &Progress::new()).unwrap()
    };
    let counts: Vec<usize> = [0.0, 1.0, 16.0, 64.0]
        .iter()
        .map(|&t| {
            let r = run(t);
            let measured = hausdorff_mesh_mesh(
                &truck,
                &r.mesh,
                &SamplingOptions {
                    samples: 200_000,
                    seed: 5,
                },
            )
            .two_sided();
            assert!(
                measured <= r.error_bound(),
                "{t}: {measured} > {}",
                r.error_bound()
            );
            let uv = lodstudio_core::distance::uv_error(&truck, &r.mesh, r.error_bound()).unwrap();
            assert!(
                uv.mean_texels < 1.0 && uv.area_over_threshold < 1e-3,
                "{t}: {uv:?}"
            );
            // Short of 100: the seams say why, and how to go on.
            let unmet = r.unmet.expect("100 triangles need baked textures");
            assert!(unmet.why.contains("--uv-tolerance"), "{unmet:?}");
            r.mesh.triangles.len()
        })
        .collect();
    assert!(counts.windows(2).all(|w| w[1] < w[0]), "{counts:?}");
    assert!(counts[3] * 2 < counts[0], "{counts:?}");
    let out = tempfile::tempdir().unwrap();
    let bad = lodstudio(&[
        "simplify",
        shared_model("CesiumMilkTruck.glb").to_str().unwrap(),
        "--ratio",
        "0.5",
        "--uv-tolerance=-1",
        "-o",
        out.path().join("t.glb").to_str().unwrap(),
    ]);
    assert_eq!(bad.status.code(), Some(2));
    let message = String::from_utf8_lossy(&bad.stderr);
    assert!(
        message.contains("--uv-tolerance: must be in 0..=4096"),
        "{message}"
    );
}

/// With seams kept, the truck's texture seams (split vertices) and borders keep
/// every vertex position, so the two sides of a seam cannot open a crack.
#[test]
fn keep_seams_freezes_seam_and_border_vertices() {
    use lodstudio_core::geom::{Adjacency, RepairOptions, Weld};
    let opts = io::LoadOptions {
        repair: RepairOptions { weld: Weld::Off },
        raw: None,
    };
    let truck = match io::load(
        &shared_model("CesiumMilkTruck.glb"),
        &opts,
        &Progress::new(),
    )
    .unwrap()
    .model
    {
        Model::Mesh(m) => m,
        _ => unreachable!(),
    };
    let seam_positions: std::collections::HashSet<[u32; 3]> = Adjacency::new(&truck.triangles)
        .border_edges()
        .flatten()
        .map(|v| truck.positions[v as usize].to_array().map(f32::to_bits))
        .collect();
    let r = simplify::simplify(
        &truck,
        &SimplifyOptions {
            per_triangle_bounds: false,
            target: Target::Ratio(0.3),
            collapse: CollapseOptions {
                lock_borders: true,
                ..Default::default()
            },
        },
        &Progress::new(),
    )
    .unwrap();
    let kept: std::collections::HashSet<[u32; 3]> = r
        .mesh
        .positions
        .iter()
        .map(|p| p.to_array().map(f32::to_bits))
        .collect();
    assert!(
        seam_positions.iter().all(|p| kept.contains(p)),
        "every seam vertex kept"
    );
    assert!(
        r.mesh.triangles.len() < truck.triangles.len(),
        "something was simplified"
    );
    assert!(r.mesh.uvs.is_some(), "texture coordinates carried");
}

#[test]
fn simplify_cli_writes_every_format_and_reports_the_contract_keys() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    for ext in ["obj", "ply", "glb"] {
        let out = dir.join(format!("torus.{ext}"));
        let o = out.to_str().unwrap();
        let j = lodstudio_json(&["simplify", "builtin:torus", "-o", o, "--ratio", "0.25"]);
        for key in [
            "input_triangles",
            "output_triangles",
            "error_bound",
            "error_bound_relative",
            "seconds",
        ] {
            assert!(j.get(key).is_some(), "{key}");
        }
        assert_eq!(j["input_triangles"], 4096);
        assert!(j["output_triangles"].as_u64().unwrap() <= 1024);
        assert!(j.get("unmet").is_none(), "a met count says nothing: {j}");
        let back = lodstudio_json(&["info", o]);
        assert_eq!(back["triangles"], j["output_triangles"]);
        assert_eq!(back["genus"], 1);
        // An existing output is kept unless --force.
        let again = lodstudio(&["simplify", "builtin:torus", "-o", o, "--ratio", "0.5"]);
        assert_eq!(again.status.code(), Some(2));
        assert_eq!(
            lodstudio_json(&["info", o])["triangles"],
            j["output_triangles"]
        );
    }
    // A count the torus cannot reach (its handle stays): said, with why.
    let o = dir.join("one.obj");
    let j = lodstudio_json(&[
        "simplify",
        "builtin:torus",
        "-o",
        o.to_str().unwrap(),
        "--triangles",
        "1",
    ]);
    let unmet = &j["unmet"];
    assert_eq!(unmet["asked"], 1);
    assert_eq!(unmet["reached"], j["output_triangles"]);
    assert!(
        unmet["why"].as_str().unwrap().starts_with("topology kept"),
        "{j}"
    );
    let out = dir.join("e.ply");
    let o = out.to_str().unwrap();
    let xyz = dir.join("x.xyz");
    let j = lodstudio_json(&["simplify", "builtin:sphere", "-o", o, "--error", "1%"]);
    assert!(j["error_bound_relative"].as_f64().unwrap() <= 0.01);
    // The fewest triangles within the error: 3 % fewer, by the unlimited
    // collapse, break it.
    let n = j["output_triangles"].as_u64().unwrap();
    let fewer = ((n as f64) * 0.97).floor().to_string();
    let f = lodstudio_json(&[
        "simplify",
        "builtin:sphere",
        "-o",
        o,
        "--triangles",
        &fewer,
        "--force",
    ]);
    assert!(f["output_triangles"].as_u64().unwrap() < n);
    assert!(
        f["error_bound_relative"].as_f64().unwrap() > 0.01,
        "{f} vs {j}"
    );
    for bad in [
        &[
            "simplify",
            "builtin:sphere",
            "-o",
            o,
            "--ratio",
            "2",
            "--force",
        ][..],
        &[
            "simplify",
            "builtin:sphere",
            "-o",
            o,
            "--error",
            "-1",
            "--force",
        ],
        &[
            "simplify",
            "builtin:octahedron-points",
            "-o",
            o,
            "--ratio",
            "0.5",
            "--force",
        ],
        &[
            "simplify",
            "builtin:sphere",
            "-o",
            xyz.to_str().unwrap(),
            "--ratio",
            "0.5",
        ],
        &["simplify", "builtin:sphere", "-o", o],
    ] {
        let r = lodstudio(bad);
        assert_eq!(r.status.code(), Some(2), "{bad:?}");
        assert_eq!(String::from_utf8_lossy(&r.stderr).trim().lines().count(), 1);
    }
}

/// Issue 50, item 2: the truck's LODs crossing seams within the 1-texel
/// tolerance show no texture bled from another chart, in renders through
/// the studio's renderer (`compare`, 8 views): of the pixels the original
/// and the LOD both cover, under 0.1 % (2,400 triangles) and 0.5 %
/// (1,812) in any view show another colour (chromaticity, which shading
/// leaves alone; measured 0.03 % and 0.34 %), where its impostor's cards,
/// which do move colours, show over 10 %.
#[test]
fn the_trucks_lods_show_no_texture_bleeding() {
    let dir = tempfile::tempdir().unwrap();
    let truck = shared_model("CesiumMilkTruck.glb");
    let truck = truck.to_str().unwrap();
    let worst = |file: &str| {
        let report = lodstudio_json(&["compare", truck, file]);
        report["views"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v["wrong_colour"].as_f64().unwrap())
            .fold(0.0, f64::max)
    };
    for (n, most) in [("2400", 0.001), ("1812", 0.005)] {
        let out = dir.path().join(format!("t{n}.glb")).display().to_string();
        let r = lodstudio_json(&["simplify", truck, "--triangles", n, "--no-bake", "-o", &out]);
        assert_eq!(r["output_triangles"].to_string(), n, "{r}");
        let w = worst(&out);
        eprintln!(
            "truck at {n} triangles: {:.3} % of pixels in another colour",
            100.0 * w
        );
        assert!(w < most, "{n}: {w}");
    }
    let cards = dir.path().join("impostor.glb").display().to_string();
    lodstudio_json(&["impostor", truck, "-o", &cards]);
    assert!(worst(&cards) > 0.1);
}

/// `--topology free` past a handle's floor: a torus asked for fewer
/// triangles than the edge collapse can keep a handle with has its hole
/// closed by pair contraction (`simplify/pairs.rs`), reaches the count, says
/// so in its report, and stays within its certified bound by an independent
/// dense measurement; `keep` stops short of the count and says why.
#[test]
fn topology_free_closes_a_handle_past_its_floor() {
    let dir = tempfile::tempdir().unwrap();
    let torus = lodstudio_core::builtins::torus(1.0, 0.3, 32, 16);
    let file = dir.path().join("torus.obj");
    let plain = TriMesh::new(torus.positions, torus.triangles);
    std::fs::write(&file, io::obj::write(&plain)).unwrap();
    let file = file.to_str().unwrap();
    let out = |n: &str| dir.path().join(n).display().to_string();
    let kept = lodstudio_json(&["simplify", file, "--triangles", "8", "-o", &out("k.obj")]);
    assert!(kept["unmet"]["reached"].as_u64().unwrap() > 8, "{kept}");
    let free = out("f.obj");
    let r = lodstudio_json(&[
        "simplify",
        file,
        "--triangles",
        "8",
        "--topology",
        "free",
        "-o",
        &free,
    ]);
    let t = &r["topology"];
    assert_eq!(
        (&t["genus_before"], &t["genus_after"]),
        (&1.into(), &0.into()),
        "{r}"
    );
    assert!(t["pair_cell"].as_f64().unwrap() > 0.0, "{r}");
    assert!(t["contracted_vertices"].as_u64().unwrap() > 0, "{r}");
    assert!(r["unmet"].is_null(), "{r}");
    assert!(load_file(&free).triangles.len() <= 8);
    let measured = lodstudio_json(&["measure", file, &free])["hausdorff"]
        .as_f64()
        .unwrap();
    let bound = r["error_bound"].as_f64().unwrap();
    assert!(measured <= bound, "measured {measured} > {bound}");
    saved_free_cuts_as_run(file, "8", dir.path());
}

/// `simplify --topology free --triangles N --save` reopened with `cut`
/// (issue 48, tests: "saved/reopened hierarchies give the same cuts"): the
/// cut at N is the run's output byte for byte with the run's bound, and
/// cuts within an error, before or past the topology step, are within it
/// and hold against `measure`.
fn saved_free_cuts_as_run(file: &str, triangles: &str, dir: &std::path::Path) {
    let out = |n: &str| dir.join(n).display().to_string();
    let (run, saved) = (out("run.obj"), out("run.lodh"));
    let r = lodstudio_json(&[
        "simplify",
        file,
        "--triangles",
        triangles,
        "--topology",
        "free",
        "--save",
        &saved,
        "-o",
        &run,
    ]);
    let cut = out("cut.obj");
    let c = lodstudio_json(&["cut", &saved, "--triangles", triangles, "-o", &cut]);
    assert_eq!(std::fs::read(&run).unwrap(), std::fs::read(&cut).unwrap());
    assert_eq!(c["error_bound"], r["error_bound"], "{c} vs {r}");
    let diag = r["bbox_diagonal"].as_f64().unwrap();
    for e in [2.0, 20.0] {
        let cut = out(&format!("cut{e}.obj"));
        let c = lodstudio_json(&["cut", &saved, "--error", &format!("{e}%"), "-o", &cut]);
        let bound = c["error_bound"].as_f64().unwrap();
        assert!(bound <= e / 100.0 * diag, "{e}%: {c}");
        let measured = lodstudio_json(&["measure", file, &cut])["hausdorff"]
            .as_f64()
            .unwrap();
        // The input itself (bound 0) measures its text's rounding.
        let rounding = 1e-6 * diag;
        assert!(
            measured <= bound + rounding,
            "{e}%: measured {measured} > {bound}"
        );
    }
}

/// `--topology free` (issue 48, item 2): a speck beside a sphere is pruned
/// where that is certified within the budget (an error), or merged into
/// the sphere by contracted pairs (a count), the certificate holds
/// against an independent dense measurement of the whole input, and the
/// report gives components and genus before and after; `keep` (the
/// default) keeps both; saved and reopened, the record cuts as the run.
#[test]
fn topology_free_prunes_a_speck_within_the_certified_bound() {
    let dir = tempfile::tempdir().unwrap();
    let big = lodstudio_core::builtins::icosphere(glam::Vec3::ZERO, 1.0, 4);
    let speck = lodstudio_core::builtins::icosphere(glam::Vec3::new(1.05, 0.0, 0.0), 0.03, 1);
    let input = TriMesh::concat(&[big, speck]);
    let file = dir.path().join("two.obj");
    std::fs::write(&file, io::obj::write(&input)).unwrap();
    let file = file.to_str().unwrap();
    let out = |n: &str| dir.path().join(n).display().to_string();
    // Half of 10 % of the diagonal affords the speck's 0.08 (its far side
    // from the sphere); at 40 triangles merging it costs less than that.
    for (target, value, pruned) in [("--triangles", "40", 0), ("--error", "10%", 1)] {
        let free = out(&format!("free{value}.obj"));
        let r = lodstudio_json(&[
            "simplify",
            file,
            target,
            value,
            "--topology",
            "free",
            "-o",
            &free,
        ]);
        let t = &r["topology"];
        assert_eq!(
            (
                &t["components_before"],
                &t["components_after"],
                &t["pruned_components"]
            ),
            (&2.into(), &1.into(), &pruned.into()),
            "{target} {value}: {r}"
        );
        assert_eq!(t["contracted_vertices"] == 0, pruned == 1, "{r}");
        assert_eq!(
            (&t["genus_before"], &t["genus_after"]),
            (&0.into(), &0.into())
        );
        let measured = lodstudio_json(&["measure", file, &free])["hausdorff"]
            .as_f64()
            .unwrap();
        let bound = r["error_bound"].as_f64().unwrap();
        assert!(
            measured <= bound,
            "{target} {value}: measured {measured} > {bound}"
        );
        let kept = lodstudio_json(&[
            "simplify",
            file,
            target,
            value,
            "-o",
            &out("kept.obj"),
            "--force",
        ]);
        assert!(kept.get("topology").is_none(), "{kept}");
        assert_eq!(
            Topology::of(&load_file(&out("kept.obj"))).components.len(),
            2
        );
    }
    // Per export row: a free row prunes the speck, a kept one does not; the
    // saved recipe says which.
    for (topology, pieces) in [("free", 1), ("keep", 2)] {
        let chain = out(&format!("chain-{topology}.glb"));
        let recipe = out(&format!("recipe-{topology}.json"));
        let args = [
            "export",
            file,
            "--method",
            "simplify",
            "--lods",
            "source,0.0077",
            "--topology",
            topology,
            "--save-recipe",
            &recipe,
            "-o",
            &chain,
        ];
        lodstudio_json(&args);
        let lod1 = lodstudio_json(&["info", &format!("{chain}#lod1")]);
        assert_eq!(lod1["components"], pieces, "{topology}: {lod1}");
        let saved = std::fs::read_to_string(&recipe).unwrap();
        assert_eq!(
            saved.contains("\"topology\": \"free\""),
            topology == "free",
            "{saved}"
        );
    }
    saved_free_cuts_as_run(file, "40", dir.path());
}
