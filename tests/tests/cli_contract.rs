//! The command-line contract of DESIGN.md: JSON keys, exit codes, one-line errors.

use lodstudio_tests::{lodstudio, lodstudio_json, malformed_dir};

#[test]
fn every_malformed_file_gives_exit_2_and_one_line() {
    let tmp = tempfile::tempdir().unwrap();
    let out_dir = tmp.path();
    let mut seen = 0;
    for entry in std::fs::read_dir(malformed_dir()).unwrap() {
        let path = entry.unwrap().path();
        let out = lodstudio(&["info", path.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{}: {stderr}", path.display());
        assert_eq!(
            stderr.trim().lines().count(),
            1,
            "{}: {stderr}",
            path.display()
        );
        assert!(!stderr.contains("panicked") && !stderr.contains("internal error"));
        let name = path.file_name().unwrap().to_string_lossy();
        assert!(
            stderr.contains(name.as_ref()),
            "the message names the file: {stderr}"
        );
        assert!(out.stdout.is_empty());

        // A command that writes refuses before writing: nothing, not even a
        // temporary file, is left in the output folder.
        let dir = out_dir.join(name.as_ref());
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("lod.glb");
        let out = lodstudio(&[
            "simplify",
            path.to_str().unwrap(),
            "-o",
            target.to_str().unwrap(),
        ]);
        assert_eq!(out.status.code(), Some(2), "simplify {}", path.display());
        let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
        assert!(left.is_empty(), "{}: {left:?} left behind", path.display());
        seen += 1;
    }
    assert!(seen >= 28, "the corpus is all there ({seen} files)");
}

#[test]
fn bad_arguments_and_missing_files_give_exit_2() {
    for args in [
        &["info", "/nonexistent/model.obj"][..],
        &["info", "builtin:no-such-model"],
        &["info"],
        &["no-such-subcommand"],
        &["info", "builtin:sphere", "--weld-tolerance", "-1"],
        &["info", "builtin:sphere", "--raw-dims", "2,2"],
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

#[test]
fn info_json_has_the_contract_keys() {
    let j = lodstudio_json(&["info", "builtin:torus"]);
    for key in [
        "vertices",
        "triangles",
        "points",
        "components",
        "genus",
        "bbox_diagonal",
        "repairs",
    ] {
        assert!(j.get(key).is_some(), "missing {key}");
    }
    assert_eq!(j["genus"], 1);
    assert_eq!(j["triangles"], 4096);
    let j = lodstudio_json(&["info", "builtin:octahedron-points"]);
    assert_eq!(j["points"], 16_000);
}

#[test]
fn builtins_are_listed_and_all_load() {
    let list = lodstudio_json(&["info", "--builtins"]);
    let names: Vec<String> = list["builtins"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["name"].as_str().unwrap().to_string())
        .collect();
    for want in [
        "sphere",
        "torus",
        "octahedron-points",
        "sphereflake",
        "csg-part",
    ] {
        assert!(names.contains(&format!("builtin:{want}")), "{want}");
    }
    let flake = lodstudio_json(&["info", "builtin:sphereflake"]);
    assert_eq!(flake["components"], 820);
    let part = lodstudio_json(&["info", "builtin:csg-part"]);
    assert_eq!(
        (part["components"].as_i64(), part["genus"].as_i64()),
        (Some(1), Some(5))
    );
}

#[test]
fn raw_volumes_need_and_use_their_layout() {
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("cube.raw");
    let data: Vec<u8> = (0..4 * 3 * 2).map(|i| i as u8).collect();
    std::fs::write(&path, &data).unwrap();
    let p = path.to_str().unwrap();
    assert_eq!(
        lodstudio(&["info", p]).status.code(),
        Some(2),
        "no layout given"
    );
    let j = lodstudio_json(&["info", p, "--raw-dims", "4,3,2", "--raw-type", "u8"]);
    assert_eq!(j["grid"], serde_json::json!([4, 3, 2]));
    assert_eq!(j["value_range"], serde_json::json!([0.0, 23.0]));
    let out = lodstudio(&["info", p, "--raw-dims", "4,3,3", "--raw-type", "u8"]);
    assert_eq!(out.status.code(), Some(2), "too few bytes for the grid");
}

/// `open FILE` (and no subcommand) starts the studio; with no display it
/// says so in one line and exits 1 (a failure of the machine, not of the
/// input), never panicking; a missing FILE is a usage error (exit 2).
#[test]
fn open_without_a_display_fails_cleanly() {
    for args in [&["open", "builtin:torus"][..], &[][..]] {
        let out = std::process::Command::new(lodstudio_tests::lodstudio_bin())
            .args(args)
            .env_remove("DISPLAY")
            .env_remove("WAYLAND_DISPLAY")
            .env_remove("WAYLAND_SOCKET")
            .output()
            .expect("run lodstudio");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(
            stderr.starts_with("lodstudio: cannot open the studio window"),
            "{args:?}: {stderr}"
        );
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(!stderr.contains("panicked") && out.stdout.is_empty());
    }
    let usage = lodstudio(&["open"]);
    assert_eq!(usage.status.code(), Some(2));
}
