//! Batch export at scale (issue 27): shards run as separate processes write
//! every output once, byte for byte what one unsharded run writes; a killed
//! run leaves only whole files and the next completes it; the cache skips
//! what has not changed.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use lodstudio_tests::{lodstudio, lodstudio_bin, malformed_dir, shared_model};
use serde_json::Value;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("lodstudio-batch-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A new folder `name` holding copies of the shared models `models`.
fn copies(name: &str, models: &[&str]) -> PathBuf {
    let dir = temp(name);
    for m in models {
        std::fs::copy(shared_model(m), dir.join(m)).unwrap();
    }
    dir
}

/// 30 models: seven shared ones (the engine with its .bin), 19 built-ins
/// written as OBJ, PLY and GLB, and four malformed files.
fn thirty_models() -> (PathBuf, usize) {
    let dir = copies(
        "thirty",
        &[
            "bones.off",
            "couplingdown.off",
            "fandisk.obj",
            "knot2.off",
            "rocker-arm.obj",
            "CesiumMilkTruck.glb",
            "2CylinderEngine.gltf",
            "2CylinderEngine0.bin",
        ],
    );
    for i in 0..19u32 {
        let mesh = if i % 2 == 0 {
            lodstudio_core::builtins::torus(1.0, 0.2 + 0.02 * i as f32, 12 + 2 * i, 8 + i)
        } else {
            lodstudio_core::builtins::icosphere(glam::Vec3::splat(i as f32), 1.0, 1 + i % 4)
        };
        let ext = ["obj", "ply", "glb"][i as usize % 3];
        let path = dir.join(format!("builtin{i:02}.{ext}"));
        let bytes = lodstudio_core::io::encode_mesh(&path, &mesh).unwrap();
        std::fs::write(&path, bytes).unwrap();
    }
    let broken = [
        "empty.obj",
        "bad_header.off",
        "truncated.ply",
        "broken_json.gltf",
    ];
    for name in broken {
        std::fs::copy(malformed_dir().join(name), dir.join(name)).unwrap();
    }
    (dir, broken.len())
}

const LODS: &str = "simplify:0.5,simplify:2%";

fn export(input: &Path, out: &Path, extra: &[&str]) -> (Option<i32>, Value) {
    let mut args = vec![
        "export",
        input.to_str().unwrap(),
        "--lods",
        LODS,
        "-o",
        out.to_str().unwrap(),
        "--json",
    ];
    args.extend_from_slice(extra);
    let run = lodstudio(&args);
    let j = serde_json::from_slice(&run.stdout)
        .unwrap_or_else(|e| panic!("{args:?}: {e}: {}", String::from_utf8_lossy(&run.stderr)));
    (run.status.code(), j)
}

/// The outputs in a folder (name -> bytes), hidden files and reports aside.
fn outputs(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".glb"))
        .map(|n| {
            let bytes = std::fs::read(dir.join(&n)).unwrap();
            (n, bytes)
        })
        .collect()
}

fn strs(v: &Value) -> Vec<String> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap().to_string())
        .collect()
}

/// Three shards started at once as separate processes (one thread each)
/// write every output once, byte-identical to an unsharded run on two
/// threads; the malformed models fail in the reports and stop nothing.
#[test]
fn three_concurrent_shards_write_what_one_run_writes() {
    let (models, broken) = thirty_models();
    let one = temp("one");
    let (code, all) = export(&models, &one, &["--threads", "2"]);
    assert_eq!(code, Some(2), "malformed inputs make the exit 2");
    assert_eq!(all["models"], 30);
    assert_eq!(all["failed"].as_u64().unwrap() as usize, broken);
    assert_eq!(all["built"].as_u64().unwrap() as usize, 30 - broken);
    let reference = outputs(&one);
    assert_eq!(reference.len(), 30 - broken);
    // One report line per model.
    let lines = std::fs::read_to_string(one.join("report.jsonl")).unwrap();
    assert_eq!(lines.lines().count(), 30);
    for line in lines.lines() {
        let l: Value = serde_json::from_str(line).unwrap();
        match l["status"].as_str().unwrap() {
            "built" => {
                assert!(l["peak_memory_bytes"].as_u64().unwrap() > 0 && l["lods"].is_array())
            }
            "failed" => assert!(!l["error"].as_str().unwrap().is_empty()),
            other => panic!("{other}"),
        }
    }

    let sharded = temp("sharded");
    let children: Vec<_> = (0..3)
        .map(|i| {
            Command::new(lodstudio_bin())
                .args(["export", models.to_str().unwrap(), "--lods", LODS, "-o"])
                .arg(&sharded)
                .args(["--shards", "3", "--threads", "1", "--json"])
                .env("JOB_COMPLETION_INDEX", i.to_string())
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let mut seen = Vec::new();
    let (mut models_total, mut failed_total) = (0, 0);
    for child in children {
        let out = child.wait_with_output().unwrap();
        let j: Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(j["inputs_in_all_shards"], 30);
        models_total += j["models"].as_u64().unwrap();
        failed_total += j["failed"].as_u64().unwrap();
        // Balanced by bytes: the engine (1.9 MB with its buffer) is a shard's alone.
        assert!(j["models"].as_u64().unwrap() >= 1, "{}", j["models"]);
        seen.extend(strs(&j["outputs"]).into_iter().map(|p| {
            Path::new(&p)
                .file_name()
                .unwrap()
                .to_string_lossy()
                .into_owned()
        }));
    }
    assert_eq!(models_total, 30);
    assert_eq!(failed_total as usize, broken);
    seen.sort();
    let names: Vec<String> = reference.keys().cloned().collect();
    assert_eq!(seen, names, "every output once");
    assert!(
        outputs(&sharded) == reference,
        "byte-identical to the unsharded run"
    );
    for i in 0..3 {
        assert!(
            sharded
                .join(format!("report.shard-{i}-of-3.jsonl"))
                .exists()
        );
    }
}

/// A run killed (the whole process group, as a node loses a pod) leaves only
/// whole outputs; the next run completes the rest, byte for byte what an
/// uninterrupted run writes; nothing half-written is left in the folder.
#[test]
fn a_killed_run_leaves_whole_files_and_the_next_completes_it() {
    use std::os::unix::process::CommandExt;
    let models = copies(
        "kill-in",
        &[
            "horse.ply",
            "stanford-bunny.obj",
            "rocker-arm.obj",
            "fandisk.obj",
            "knot2.off",
            "bones.off",
        ],
    );
    let reference = temp("kill-ref");
    assert_eq!(export(&models, &reference, &[]).0, Some(0));
    let out = temp("kill-out");
    let mut child = Command::new(lodstudio_bin())
        .args(["export", models.to_str().unwrap(), "--lods", LODS, "-o"])
        .arg(&out)
        .args(["--threads", "2"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .process_group(0)
        .spawn()
        .unwrap();
    // Kill as soon as the first output lands: the others are mid-build.
    let start = std::time::Instant::now();
    while outputs(&out).is_empty() && start.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let group = format!("-{}", child.id());
    let killed = Command::new("kill")
        .args(["-KILL", "--", &group])
        .status()
        .unwrap();
    assert!(killed.success());
    let _ = child.wait();
    let partial = outputs(&out);
    assert!(
        partial.len() < 6,
        "killed before the end: {}",
        partial.len()
    );
    for (name, bytes) in &partial {
        assert_eq!(bytes, &reference_bytes(&reference, name), "{name} is whole");
    }
    let strays: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.') && n != ".lodstudio-cache")
        .collect();
    assert!(strays.is_empty(), "{strays:?}");
    let (code, rerun) = export(&models, &out, &[]);
    assert_eq!(code, Some(0));
    assert_eq!(rerun["skipped"].as_u64().unwrap() as usize, partial.len());
    assert_eq!(rerun["built"].as_u64().unwrap() as usize, 6 - partial.len());
    assert!(outputs(&out) == outputs(&reference));
}

fn reference_bytes(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(name)).unwrap()
}

/// A rerun with nothing changed skips everything from the cache; a changed
/// input rebuilds that one only; a touched (unchanged) one nothing; another
/// recipe everything.
#[test]
fn the_cache_skips_what_has_not_changed() {
    let models = copies(
        "cache-in",
        &[
            "fandisk.obj",
            "bones.off",
            "CesiumMilkTruck.glb",
            "2CylinderEngine.gltf",
            "2CylinderEngine0.bin",
        ],
    );
    // A copy under another name: the same key, its own output and record.
    std::fs::copy(models.join("bones.off"), models.join("bones-copy.off")).unwrap();
    let out = temp("cache-out");
    let (code, first) = export(&models, &out, &[]);
    assert_eq!((code, first["built"].as_u64()), (Some(0), Some(5)));
    let (_, again) = export(&models, &out, &[]);
    assert_eq!(
        (again["built"].as_u64(), again["skipped"].as_u64()),
        (Some(0), Some(5))
    );
    // Touching changes no content.
    let fandisk = models.join("fandisk.obj");
    let f = std::fs::File::options()
        .append(true)
        .open(&fandisk)
        .unwrap();
    f.set_modified(std::time::SystemTime::now()).unwrap();
    drop(f);
    let (_, touched) = export(&models, &out, &[]);
    assert_eq!(touched["built"].as_u64(), Some(0));
    // A changed input, and a changed file a glTF names, rebuild their model only.
    let mut text = std::fs::read_to_string(&fandisk).unwrap();
    text.push_str("# edited\n");
    std::fs::write(&fandisk, text).unwrap();
    let (_, edited) = export(&models, &out, &[]);
    assert_eq!(
        (edited["built"].as_u64(), edited["skipped"].as_u64()),
        (Some(1), Some(4))
    );
    let built: Vec<&Value> = edited["reports"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["status"] == "built")
        .collect();
    assert!(built[0]["input"].as_str().unwrap().ends_with("fandisk.obj"));
    let bin = models.join("2CylinderEngine0.bin");
    let mut b = std::fs::read(&bin).unwrap();
    b.push(0);
    std::fs::write(&bin, b).unwrap();
    let (_, buffer) = export(&models, &out, &[]);
    assert_eq!(buffer["built"].as_u64(), Some(1));
    // Another recipe is another key; --force rebuilds what is cached.
    let mut args_other = vec!["--pixels", "2"];
    let (_, other) = export(&models, &out, &args_other);
    assert_eq!(other["built"].as_u64(), Some(5));
    args_other.push("--force");
    let (_, forced) = export(&models, &out, &args_other);
    assert_eq!(forced["built"].as_u64(), Some(5));
}

/// A manifest lists inputs with per-asset overrides; two inputs that would
/// write one output, a bad override or a bad shard are refused with exit 2.
#[test]
fn manifests_take_overrides_and_bad_plans_are_refused() {
    let dir = temp("manifest");
    let recipe = dir.join("hero.json");
    let saved = lodstudio(&[
        "export",
        "builtin:torus",
        "--lods",
        "simplify:1%,amg:20%",
        "-o",
        dir.join("torus.glb").to_str().unwrap(),
        "--save-recipe",
        recipe.to_str().unwrap(),
    ]);
    assert!(
        saved.status.success(),
        "{}",
        String::from_utf8_lossy(&saved.stderr)
    );
    let manifest = dir.join("m.txt");
    std::fs::write(
        &manifest,
        format!(
            "# assets\n{}\n{} recipe=hero.json\n{} lods=simplify:0.25\n",
            shared_model("bones.off").display(),
            shared_model("fandisk.obj").display(),
            shared_model("knot2.off").display()
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let (m, o) = (manifest.to_str().unwrap(), out.to_str().unwrap());
    let run_manifest = |extra: &[&str]| {
        let mut args = vec!["export", "--manifest", m, "--lods", "simplify:2%", "-o", o];
        args.extend_from_slice(extra);
        lodstudio(&args)
    };
    let run = run_manifest(&["--json"]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let j: Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(j["built"], 3);
    let by_input = |name: &str| -> Value {
        j["reports"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["input"].as_str().unwrap().ends_with(name))
            .unwrap()
            .clone()
    };
    let rows = |r: &Value| -> Vec<String> {
        r["lods"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|l| strs(&l["rows"]))
            .collect()
    };
    assert_eq!(rows(&by_input("bones.off")), ["simplify:2%"]);
    assert_eq!(rows(&by_input("fandisk.obj")), ["simplify:1%", "amg:20%"]);
    assert_eq!(rows(&by_input("knot2.off")), ["simplify:0.25"]);
    // Two inputs, one output name.
    std::fs::write(
        &manifest,
        format!(
            "{}\n{}\n",
            shared_model("bones.off").display(),
            dir.join("x/bones.off").display()
        ),
    )
    .unwrap();
    let clash = run_manifest(&[]);
    assert_eq!(clash.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&clash.stderr).contains("bones.glb"));
    std::fs::write(&manifest, "a.obj colour=red\n").unwrap();
    let unknown = run_manifest(&[]);
    assert_eq!(unknown.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&unknown.stderr).contains("m.txt:1"));
    let d = dir.to_str().unwrap();
    for bad in [&["--shard", "3/3"][..], &["--shards", "2"][..]] {
        let mut args = vec![
            "export",
            d,
            "--lods",
            "simplify:2%",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(bad);
        let r = Command::new(lodstudio_bin())
            .args(&args)
            .env_remove("JOB_COMPLETION_INDEX")
            .output()
            .unwrap();
        assert_eq!(r.status.code(), Some(2), "{bad:?}");
    }
}
