//! End-to-end runs of `lodstudio amg` (AMG extreme point-set simplification).

use lodstudio_tests::{lodstudio, lodstudio_json, shared_model};

fn counts(j: &serde_json::Value, key: &str) -> Vec<u64> {
    j[key]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect()
}

#[test]
fn octahedron_reaches_eight_face_primitives_in_a_glb() {
    let probe = lodstudio_json(&["amg", "builtin:octahedron-points"]);
    let levels = counts(&probe, "levels");
    assert_eq!(probe["points"], 16000);
    assert_eq!(levels[0], 16000, "level 0: one domain per point");
    assert!(levels.windows(2).all(|w| w[1] < w[0]), "{levels:?}");
    let eight = levels
        .iter()
        .position(|&d| d == 8)
        .expect("a level of 8 domains");
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("octahedron.glb");
    let j = lodstudio_json(&[
        "amg",
        "builtin:octahedron-points",
        "--level",
        &eight.to_string(),
        "--texel",
        "0.02",
        "-o",
        out.to_str().unwrap(),
        "--force",
    ]);
    assert_eq!(j["primitives"], 8);
    // Face planes: every domain point (crease points shared with the next face
    // included) within 0.1 of its plane; a domain across two faces would reach ~0.4.
    assert!(j["max_plane_error"].as_f64().unwrap() < 0.1, "{j}");
    let texels = j["texels"].as_u64().unwrap();
    // Each face (area √3/2) at texel 0.02 needs at least ~2,165 texels.
    assert!((8 * 2165..8 * 20_000).contains(&texels), "{texels} texels");
    let glb = std::fs::read(&out).unwrap();
    assert_eq!(&glb[..4], b"glTF");
    let text = String::from_utf8_lossy(&glb);
    assert_eq!(text.matches("\"image/png\"").count(), 8);
    assert_eq!(text.matches("\"BLEND\"").count(), 8);
}

#[test]
fn ball_decomposes_like_table_1() {
    let j = lodstudio_json(&["amg", &shared_model("ball.ply").to_string_lossy()]);
    let levels = counts(&j, "levels");
    assert_eq!(j["points"], 31374);
    assert!(levels.windows(2).all(|w| w[1] < w[0]), "{levels:?}");
    // 2–3× fewer per level (§2.3) and about ten levels.
    assert!((7..=16).contains(&levels.len()), "{levels:?}");
    let level = j["level"].as_u64().unwrap() as usize;
    assert_eq!(j["primitives"].as_u64().unwrap(), levels[level]);
    assert!(j["texels"].as_u64().unwrap() > j["primitives"].as_u64().unwrap());
}

#[test]
fn bad_amg_arguments_exit_2_with_one_line() {
    let oct = "builtin:octahedron-points";
    for args in [
        vec!["amg", oct, "--k", "2"],
        vec!["amg", oct, "--level", "99"],
        vec!["amg", oct, "--texel", "-1"],
        vec!["amg", oct, "--texel", "nan"],
        vec!["amg", "/nonexistent/points.ply"],
        vec!["amg", "builtin:sphereflake", "--k", "100000"],
    ] {
        let out = lodstudio(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
}

/// The plane error AMG reports (an estimate: how flat each domain is) is
/// what the drawn splats show: recomputed here from each splat's plane and
/// its domain's points, it agrees; on the octahedron's 8-domain level every
/// splat lies on a face (normal within 3° of the face's) and no point is
/// farther than 0.1 from its splat's plane.
#[test]
fn plane_errors_are_the_distances_of_the_domains_to_their_splats() {
    use lodstudio_core::amg;
    let p = lodstudio_core::Progress::new();
    let lodstudio_core::Model::Points(points) =
        lodstudio_core::builtins::build("octahedron-points", &p).unwrap()
    else {
        panic!("octahedron-points is a point set");
    };
    let ms = amg::decompose(&points, &Default::default(), &p).unwrap();
    let levels = ms.coarsening.level_sizes().len();
    let mut faces_checked = false;
    for level in 1..levels {
        let domains = ms.domains(level);
        let prims = amg::primitives(&ms, level, ms.default_texel(), &p).unwrap();
        assert_eq!(prims.splats.len(), domains.len(), "level {level}");
        for (splat, &reported) in prims.splats.iter().zip(&prims.errors) {
            let measured = domains[splat.domain]
                .iter()
                .map(|&(i, _)| {
                    (points.positions[i as usize] - splat.center)
                        .dot(splat.normal)
                        .abs()
                })
                .fold(0.0f32, f32::max);
            assert!(
                (measured - reported).abs() <= 1e-4 * (1.0 + reported),
                "level {level} domain {}: reported {reported}, measured {measured}",
                splat.domain
            );
        }
        if domains.len() == 8 {
            faces_checked = true;
            for splat in &prims.splats {
                let face = splat.normal.signum() / 3f32.sqrt();
                assert!(
                    splat.normal.dot(face) > 3f32.to_radians().cos(),
                    "{:?}",
                    splat.normal
                );
            }
            let worst = prims.errors.iter().copied().fold(0.0, f32::max);
            assert!(worst < 0.1, "8 faces, plane error {worst}");
        }
    }
    assert!(faces_checked, "a level of 8 domains");
}
