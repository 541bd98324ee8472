//! The `voxel` subcommand's contract (DESIGN.md) and the genus falling as the
//! low-pass filter widens (voxel paper §2, Tables 1–3).

use lodstudio_tests::{lodstudio, lodstudio_json, shared_model};

#[test]
fn single_level_reports_the_contract_keys_and_writes_the_mesh() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("voxel.ply");
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
/// one as the filter widens (Tables 1–3, the raw extraction: marching cubes
/// makes about 4× the triangles per halving of the voxel size).
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
        "--no-simplify",
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

/// §3: a tighter layer error takes more, increasingly translucent layers; a GLB
/// holds them all, one alpha-blended node each.
#[test]
fn layers_follow_the_error_bound_and_export_together() {
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("layers.glb");
    let o = out.to_str().unwrap();
    let args = |d: &'static str| {
        [
            "voxel",
            "builtin:csg-part",
            "--resolution",
            "32",
            "--layers-error",
            d,
        ]
    };
    let one = lodstudio_json(&args("0.5"));
    assert_eq!(one["layers"], 1);
    let mut many_args = args("0.03").to_vec();
    many_args.extend(["-o", o, "--force"]);
    let many = lodstudio_json(&many_args);
    let n = many["layers"].as_u64().unwrap() as usize;
    assert!(n >= 3, "{many}");
    assert!(many["layers_error"].as_f64().unwrap() <= 0.03);
    let alpha: Vec<f64> = many["opacities"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a.as_f64().unwrap())
        .collect();
    assert_eq!(alpha[0], 1.0);
    assert!(alpha.windows(2).all(|w| w[1] < w[0]), "{alpha:?}");
    let per_layer: u64 = many["layer_triangles"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_u64().unwrap())
        .sum();
    let back = lodstudio_json(&["info", o]);
    assert_eq!(back["triangles"].as_u64(), Some(per_layer));
    assert_eq!(back["parts"].as_u64(), Some(n as u64));
}

/// Table 3: the MRI head's pyramid pools the thresholded scan into coarser
/// grids; the raw extraction's triangles fall by about 4× per level and the
/// genus never rises.
#[test]
fn the_mri_head_pyramid_and_in_between_levels() {
    let head = shared_model("ch2.nii.gz");
    let h = head.to_str().unwrap();
    let raw = ["--radius", "1", "--filter", "cone", "--no-simplify"];
    let j = lodstudio_json(&[&["voxel", h, "--pyramid"][..], &raw].concat());
    let levels = j["levels"].as_array().unwrap();
    let column = |k: &str| -> Vec<i64> { levels.iter().map(|l| l[k].as_i64().unwrap()).collect() };
    assert_eq!(column("resolution"), [217, 108, 54, 27, 13]);
    let (genus, triangles) = (column("genus"), column("triangles"));
    assert!(genus.windows(2).all(|w| w[1] <= w[0]), "{genus:?}");
    assert!(
        triangles.windows(2).all(|w| w[0] > 3 * w[1]),
        "{triangles:?}"
    );
    // §5: halfway between the two finest levels lies between them.
    let mid = lodstudio_json(&[&["voxel", h, "--at", "0.5"][..], &raw].concat());
    let t = mid["triangles"].as_i64().unwrap();
    assert!(triangles[1] < t && t < triangles[0], "{t} in {triangles:?}");
}

/// Every non-empty pyramid level carries a certified bound against the input
/// surface that a dense measurement of its written mesh never exceeds; cuts
/// of the saved pyramid pick the coarsest level within the error, so
/// different errors pick different levels (issue 25).
#[test]
fn pyramid_levels_carry_certified_bounds_and_cuts_follow_the_error() {
    let horse = shared_model("horse.ply");
    let h = horse.to_str().unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("pyr-bounds");
    let saved = dir.with_extension("lodh");
    let j = lodstudio_json(&[
        "voxel",
        h,
        "--pyramid",
        "--resolution",
        "32",
        "-o",
        dir.to_str().unwrap(),
        "--save",
        saved.to_str().unwrap(),
        "--force",
    ]);
    assert_eq!(j["error_bound_against"], "input surface");
    assert_eq!(j["vanishes_at"], serde_json::Value::Null);
    let levels = j["levels"].as_array().unwrap();
    let mut bounds = Vec::new();
    for (i, l) in levels.iter().enumerate() {
        assert_eq!(l["empty"], false);
        let bound = l["error_bound"].as_f64().unwrap();
        let file = dir.join(format!("level{i}_{}.ply", l["resolution"]));
        let m = lodstudio_json(&["measure", h, file.to_str().unwrap(), "--samples", "100000"]);
        assert!(
            m["hausdorff"].as_f64().unwrap() <= bound,
            "level {i}: {m} vs {l}"
        );
        bounds.push(l["error_bound_relative"].as_f64().unwrap());
    }
    let saved = saved.to_str().unwrap();
    let mut picked = std::collections::BTreeSet::new();
    for b in &bounds {
        // Just above this level's bound: level i or a coarser one within it.
        let e = format!("{}%", 100.0 * b * 1.001);
        let cut = lodstudio_json(&["cut", saved, "--error", &e]);
        let got = cut["error_bound_relative"].as_f64().unwrap();
        assert!(got <= b * 1.001 + 1e-9, "{e}: {cut}");
        let level = bounds.iter().rposition(|x| *x <= b * 1.001).unwrap();
        assert_eq!(cut["triangles"], levels[level]["triangles"], "{e}");
        picked.insert(level);
    }
    assert!(
        picked.len() >= 2,
        "different errors, different levels: {picked:?}"
    );
    // The position stays an explicit override.
    let at = lodstudio_json(&["cut", saved, "--error", "100%", "--at", "0"]);
    assert_eq!(at["triangles"], levels[0]["triangles"]);
}

/// A thin plate vanishes once the filter is wider than it: the levels from
/// there on are reported empty, without a bound, and the pyramid says where.
#[test]
fn a_pyramid_says_where_a_thin_part_vanishes() {
    let tmp = tempfile::tempdir().unwrap();
    let plate = tmp.path().join("plate.obj");
    let (x, y, z) = (1.0, 1.0, 0.02);
    let mut obj = String::new();
    for i in 0..8 {
        let c = |bit: usize, v: f64| if i & bit != 0 { v } else { 0.0 };
        obj += &format!("v {} {} {}\n", c(1, x), c(2, y), c(4, z));
    }
    for f in [
        [1, 3, 4, 2],
        [5, 6, 8, 7],
        [1, 2, 6, 5],
        [3, 7, 8, 4],
        [1, 5, 7, 3],
        [2, 4, 8, 6],
    ] {
        obj += &format!(
            "f {} {} {}\nf {} {} {}\n",
            f[0], f[1], f[2], f[0], f[2], f[3]
        );
    }
    std::fs::write(&plate, obj).unwrap();
    let j = lodstudio_json(&[
        "voxel",
        plate.to_str().unwrap(),
        "--pyramid",
        "--resolution",
        "64",
    ]);
    let levels = j["levels"].as_array().unwrap();
    let gone = j["vanishes_at"].as_u64().expect("the plate vanishes") as usize;
    assert!(gone > 0, "{j}");
    for (i, l) in levels.iter().enumerate() {
        let empty = l["triangles"] == 0;
        assert_eq!(l["empty"], empty, "level {i}");
        assert_eq!(l.get("error_bound").is_none(), empty, "level {i}");
        assert_eq!(i >= gone, empty, "level {i}: {j}");
    }
}

/// The density profile across a plane (voxel paper eq. 5) computed here from
/// the filters' definitions, not from lodstudio's filtered slab: the
/// Gaussian is separable (σ = R/3, cut at R along each axis), so across a
/// plane it is its 1D kernel; the hyper-cone (R − r)·w of eq. 3 has the 1D
/// marginal ∝ R³/6 − R·x²/2 + |x|³/3. `d(r)` is the mass beyond r, for R = 1.
fn analytic_profile(filter: lodstudio_core::voxel::Filter) -> impl Fn(f64) -> f64 {
    let kernel = move |x: f64| match filter {
        lodstudio_core::voxel::Filter::Gaussian => (-x * x * 4.5).exp(),
        lodstudio_core::voxel::Filter::Cone => 1.0 / 6.0 - x * x / 2.0 + x.abs().powi(3) / 3.0,
    };
    let mass = move |a: f64, b: f64| {
        let n = 2000;
        let h = (b - a) / n as f64;
        // Simpson's rule.
        (0..=n)
            .map(|i| {
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * kernel(a + i as f64 * h)
            })
            .sum::<f64>()
            * h
            / 3.0
    };
    let total = mass(-1.0, 1.0);
    move |r: f64| mass(r.clamp(-1.0, 1.0), 1.0) / total
}

/// Eq. 6 measured independently: for the isodensities the layer plan chose,
/// the mean density error of the best piecewise-constant fit with those
/// values (each r takes the nearest isodensity) over the transition band.
/// It can only be below the plan's own error; above the plan's claim (or
/// above δ) would mean the layers leave more error than reported.
#[test]
fn the_layers_error_holds_against_the_analytic_density_profile() {
    use lodstudio_core::voxel::Filter;
    use lodstudio_core::voxel::layers::{plan, profile};
    for filter in [Filter::Gaussian, Filter::Cone] {
        let d = analytic_profile(filter);
        // The profile lodstudio samples matches the analytic one.
        let sampled = profile(filter);
        for (i, &s) in sampled.iter().enumerate() {
            let r = -1.0 + 2.0 * i as f64 / (sampled.len() - 1) as f64;
            assert!(
                (s as f64 - d(r)).abs() < 0.03,
                "{filter:?} at r = {r}: {s} vs {}",
                d(r)
            );
        }
        let mut last_layers = 0;
        for delta in [0.2f32, 0.05, 0.03, 0.015] {
            let p = plan(&sampled, delta);
            let steps = 4000;
            let measured = (0..steps)
                .map(|i| {
                    let r = -1.0 + 2.0 * (i as f64 + 0.5) / steps as f64;
                    let density = d(r);
                    p.isodensities
                        .iter()
                        .map(|&c| (c as f64 - density).abs())
                        .fold(f64::INFINITY, f64::min)
                })
                .sum::<f64>()
                / steps as f64;
            let tag = format!("{filter:?} δ {delta}: {} layers", p.isodensities.len());
            eprintln!("{tag}: reported {}, measured {measured:.4}", p.error);
            assert!(
                measured <= p.error as f64 + 0.005,
                "{tag}: measured {measured} > reported {}",
                p.error
            );
            assert!(
                measured <= delta as f64 + 0.005,
                "{tag}: measured {measured} > δ"
            );
            assert!(
                p.isodensities.len() >= last_layers,
                "{tag}: a tighter δ, fewer layers"
            );
            last_layers = p.isodensities.len();
        }
    }
}

/// §5's second stage: every level of the pyramid is collapsed to half a
/// voxel with the certified edge collapse, so each has fewer triangles than
/// the raw extraction (and than the input, for the coupling), the same genus
/// and components, and a certified bound measured on what it draws.
#[test]
fn post_simplified_levels_are_smaller_and_keep_their_topology() {
    let coupling = shared_model("couplingdown.off");
    let c = coupling.to_str().unwrap();
    let input = lodstudio_json(&["info", c])["triangles"].as_u64().unwrap();
    let run = |extra: &[&str]| {
        let j =
            lodstudio_json(&[&["voxel", c, "--pyramid", "--resolution", "64"][..], extra].concat());
        j["levels"].as_array().unwrap().clone()
    };
    let (raw, post) = (run(&["--no-simplify"]), run(&[]));
    assert_eq!(raw.len(), post.len());
    for (r, p) in raw.iter().zip(&post) {
        let (rt, pt) = (
            r["triangles"].as_u64().unwrap(),
            p["triangles"].as_u64().unwrap(),
        );
        assert!(pt < rt && pt < input, "{pt} of {rt} raw, {input} input");
        assert_eq!(
            (r["genus"].clone(), r["components"].clone()),
            (p["genus"].clone(), p["components"].clone())
        );
        assert!(p["error_bound"].as_f64().is_some(), "{p}");
    }
    let few = run(&["--post-triangles", "200"]);
    assert!(
        few.iter().all(|l| l["triangles"].as_u64().unwrap() <= 200),
        "{few:?}"
    );
    for bad in [
        &["--post-error", "-1"][..],
        &["--post-triangles", "0"],
        &["--no-simplify", "--post-error", "1"],
    ] {
        let out = lodstudio(&[&["voxel", c][..], bad].concat());
        assert_eq!(out.status.code(), Some(2), "{bad:?}");
    }
}

/// Issue 28: a mesh's solid sampled by rows equals the winding-number
/// sampler's, voxel for voxel but for a few sub-samples where the point
/// sampler's approximate winding number is near ½ (on the surface, across
/// the bunny's holes), and the filtered level has the same genus and
/// components, on every shared mesh (the bunny is open: five holes capped).
#[test]
fn row_sampling_equals_the_winding_number_on_the_shared_meshes() {
    use lodstudio_core::geom::Topology;
    use lodstudio_core::implicit::{Implicit, MeshSolid};
    use lodstudio_core::voxel::sampling::sample_implicit;
    use lodstudio_core::voxel::scanline::{applies, sample_by_rows};
    use lodstudio_core::voxel::{DENSITY_ISO, Filter, filter, marching_cubes};
    let p = lodstudio_core::Progress::new();
    for name in [
        "horse.ply",
        "couplingdown.off",
        "fandisk.obj",
        "knot2.off",
        "rocker-arm.obj",
        "bones.off",
        "stanford-bunny.obj",
    ] {
        let path = shared_model(name);
        let mesh = match lodstudio_core::io::load(&path, &Default::default(), &p)
            .unwrap()
            .model
        {
            lodstudio_core::Model::Mesh(m) => m,
            _ => panic!("{name} is a mesh"),
        };
        assert!(applies(&mesh), "{name}: rows apply");
        let solid = MeshSolid::new(&mesh);
        let n = 48;
        let h = solid.bounds().extent().max_element() / n as f32;
        let rows = sample_by_rows(&solid, &mesh, n, 2.0 * h, 3, &p).unwrap();
        let points = sample_implicit(&solid, n, 2.0 * h, 3, &p).unwrap();
        let differing: Vec<f32> = rows
            .data
            .iter()
            .zip(&points.data)
            .filter(|(a, b)| a != b)
            .map(|(a, b)| (a - b).abs())
            .collect();
        // Closed: round-off at a sub-sample or two. Open: a layer of voxels
        // across a hole, where the winding number is ½ within the point
        // sampler's approximation (the rows compute it exactly there).
        let closed = Topology::of(&mesh).is_closed();
        let (share, most) = if closed {
            (10_000, 2.0 / 27.0 + 1e-6)
        } else {
            (1_000, 1.0)
        };
        assert!(
            differing.len() * share <= rows.data.len() && differing.iter().all(|d| *d <= most),
            "{name}: {} of {} voxels differ: {differing:?}",
            differing.len(),
            rows.data.len()
        );
        let topology = |s| {
            let f = filter::apply(Filter::Gaussian, s, 2.0 * h, &p).unwrap();
            let t = Topology::of(&marching_cubes(&f, DENSITY_ISO, &p).unwrap());
            (t.genus, t.components.len())
        };
        assert_eq!(topology(&rows), topology(&points), "{name}");
    }
}
