//! Batch export at scale (issue 27): shards run as separate processes write
//! every output once, byte for byte what one unsharded run writes; a killed
//! run leaves only whole files and the next completes it; the cache skips
//! what has not changed.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use lodstudio_tests::{lodstudio, lodstudio_bin, malformed_dir, shared_model};
use serde_json::Value;

/// A new, empty folder `name` in `tmp`.
fn folder(tmp: &Path, name: &str) -> PathBuf {
    let dir = tmp.join(name);
    std::fs::create_dir(&dir).unwrap();
    dir
}

/// A folder `thirty` in `tmp` holding 30 models: seven shared ones (the engine
/// with its .bin), 19 built-ins written as OBJ, PLY and GLB, and four
/// malformed files.
fn thirty_models(tmp: &Path) -> (PathBuf, usize) {
    let dir = copies_in(
        tmp,
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

/// A glTF with its buffer in a file of its own (the cache keys both).
const MORPH_CUBE: &str = "production/AnimatedMorphCube/AnimatedMorphCube.gltf";
const MORPH_CUBE_BIN: &str = "production/AnimatedMorphCube/AnimatedMorphCube.bin";

const LODS: &str = "simplify:0.5,simplify:2%";

/// What the batch is tested for is its bookkeeping, not bakes: the truck's
/// half-count row would otherwise bake a 2048² texture in every run.
const NO_BAKE: &str = "--no-bake";

fn export(input: &Path, out: &Path, extra: &[&str]) -> (Option<i32>, Value) {
    let run = export_command(input, out)
        .arg("--json")
        .args(extra)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("run lodstudio");
    let j = serde_json::from_slice(&run.stdout).unwrap_or_else(|e| {
        panic!(
            "{input:?} {extra:?}: {e}: {}",
            String::from_utf8_lossy(&run.stderr)
        )
    });
    (run.status.code(), j)
}

/// `export` of `input` to `out` at [`LODS`], as a process to start.
fn export_command(input: &Path, out: &Path) -> Command {
    let mut command = Command::new(lodstudio_bin());
    command
        .args([
            "export",
            input.to_str().unwrap(),
            "--lods",
            LODS,
            NO_BAKE,
            "-o",
        ])
        .arg(out);
    command
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
    let tmp = tempfile::tempdir().unwrap();
    let (models, broken) = thirty_models(tmp.path());
    let one = folder(tmp.path(), "one");
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

    let sharded = folder(tmp.path(), "sharded");
    let children: Vec<_> = (0..3)
        .map(|i| {
            export_command(&models, &sharded)
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
    let tmp = tempfile::tempdir().unwrap();
    let models = copies_in(
        tmp.path(),
        "kill-in",
        &[
            "couplingdown.off",
            "stanford-bunny.obj",
            "rocker-arm.obj",
            "fandisk.obj",
            "knot2.off",
            "bones.off",
        ],
    );
    let reference = folder(tmp.path(), "kill-ref");
    assert_eq!(export(&models, &reference, &[]).0, Some(0));
    let out = folder(tmp.path(), "kill-out");
    let mut child = export_command(&models, &out)
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
    let tmp = tempfile::tempdir().unwrap();
    let models = copies_in(
        tmp.path(),
        "cache-in",
        &[
            "fandisk.obj",
            "bones.off",
            "CesiumMilkTruck.glb",
            MORPH_CUBE,
            MORPH_CUBE_BIN,
        ],
    );
    // A copy under another name: the same key, its own output and record.
    std::fs::copy(models.join("bones.off"), models.join("bones-copy.off")).unwrap();
    let out = folder(tmp.path(), "cache-out");
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
    let bin = models.join("AnimatedMorphCube.bin");
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
    let tmp = tempfile::tempdir().unwrap();
    let dir = folder(tmp.path(), "manifest");
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
    // The models lie in the manifest's folder: a manifest may name nothing
    // outside it (issue 51; `manifest_paths_out_of_its_folder_are_refused`).
    for m in ["bones.off", "fandisk.obj", "knot2.off"] {
        std::fs::copy(shared_model(m), dir.join(m)).unwrap();
    }
    let manifest = dir.join("m.txt");
    std::fs::write(
        &manifest,
        format!(
            "# assets\nbones.off\nfandisk.obj recipe=hero.json\n{} lods=simplify:0.25\n",
            dir.join("knot2.off").display()
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
    std::fs::write(&manifest, "bones.off\nx/bones.off\n").unwrap();
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

// Untrusted input and faults (issue 51).

/// The one line a refused run prints on stderr.
fn one_line(run: &std::process::Output) -> String {
    let e = String::from_utf8_lossy(&run.stderr).into_owned();
    assert_eq!(e.trim_end().lines().count(), 1, "one line: {e:?}");
    e
}

/// Runs `lodstudio ARGS`, failing the test if it has not ended by `deadline`.
fn run_within(args: &[&str], deadline: std::time::Duration) -> std::process::Output {
    let mut child = Command::new(lodstudio_bin())
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{args:?} still running after {deadline:?}");
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    child.wait_with_output().unwrap()
}

/// Every file under `dir` (name relative to it -> bytes).
fn tree(dir: &Path) -> std::collections::BTreeMap<PathBuf, Vec<u8>> {
    let mut out = std::collections::BTreeMap::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        for e in std::fs::read_dir(&d).unwrap().filter_map(Result::ok) {
            let p = e.path();
            if e.file_type().unwrap().is_dir() {
                todo.push(p);
            } else {
                let bytes = std::fs::read(&p).unwrap();
                out.insert(p.strip_prefix(dir).unwrap().to_path_buf(), bytes);
            }
        }
    }
    out
}

/// A folder (in `tmp`) holding copies of the shared models `models`.
fn copies_in(tmp: &Path, name: &str, models: &[&str]) -> PathBuf {
    let dir = tmp.join(name);
    std::fs::create_dir_all(&dir).unwrap();
    for m in models {
        let name = Path::new(m).file_name().unwrap();
        std::fs::copy(shared_model(m), dir.join(name)).unwrap();
    }
    dir
}

/// A manifest line that leaves the manifest's folder (by `..`, an absolute
/// path, a recipe) or that is megabytes long is refused with exit 2 and one
/// short line naming FILE:LINE, before any output, cache or report exists.
#[test]
fn manifest_paths_out_of_its_folder_are_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let assets = copies_in(tmp.path(), "assets", &["bones.off"]);
    let secret = tmp.path().join("secret.obj");
    std::fs::copy(shared_model("fandisk.obj"), &secret).unwrap();
    let manifest = assets.join("m.txt");
    let out = tmp.path().join("out");
    let (m, o) = (manifest.to_str().unwrap(), out.to_str().unwrap());
    let absolute = secret.display().to_string();
    let long = format!("{}.obj", "y".repeat(5 << 20));
    for (line, why) in [
        (
            "../secret.obj",
            "input: uri \"../secret.obj\" is outside the asset folder (it climbs out with ..)",
        ),
        (
            absolute.as_str(),
            "is outside the asset folder (an absolute path)",
        ),
        (
            "bones.off recipe=../secret.obj",
            "recipe: uri \"../secret.obj\" is outside the asset folder",
        ),
        (long.as_str(), "characters)"),
    ] {
        std::fs::write(&manifest, format!("# models\nbones.off\n{line}\n")).unwrap();
        let run = lodstudio(&["export", "--manifest", m, "--lods", LODS, "-o", o]);
        assert_eq!(run.status.code(), Some(2), "{line:.80}");
        let e = one_line(&run);
        assert!(e.contains("m.txt:3: ") && e.contains(why), "{e:.300}");
        assert!(e.len() < 400, "quoted as an excerpt: {} bytes", e.len());
        assert!(!out.exists(), "nothing written: no output, cache or report");
    }
    // The same file named by an absolute path inside the folder is fine.
    std::fs::write(
        &manifest,
        format!("{}\n", assets.join("bones.off").display()),
    )
    .unwrap();
    let run = lodstudio(&["export", "--manifest", m, "--lods", LODS, "-o", o]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(out.join("bones.glb").exists());
}

/// `/dev/zero` or a FIFO as the manifest is refused at once (exit 2, one
/// line), not read forever or waited on.
#[cfg(unix)]
#[test]
fn special_files_as_the_manifest_are_refused_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let fifo = tmp.path().join("m.txt");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: a valid C string; mkfifo only creates a file.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let out = tmp.path().join("out");
    for (manifest, kind) in [
        ("/dev/zero", "a device"),
        (fifo.to_str().unwrap(), "a FIFO"),
    ] {
        let start = std::time::Instant::now();
        let run = run_within(
            &[
                "export",
                "--manifest",
                manifest,
                "--lods",
                LODS,
                "-o",
                out.to_str().unwrap(),
            ],
            std::time::Duration::from_secs(20),
        );
        assert_eq!(run.status.code(), Some(2), "{manifest}");
        let e = one_line(&run);
        assert!(e.contains(kind) && e.contains("not a regular file"), "{e}");
        assert!(start.elapsed().as_secs() < 10, "{:?}", start.elapsed());
        assert!(!out.exists());
    }
}

/// An output folder that is, or holds, the input folder is refused with
/// --force too, before anything is written: the inputs stay byte for byte.
#[test]
fn an_output_folder_holding_the_inputs_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let models = copies_in(tmp.path(), "models", &["bones.off", "fandisk.obj"]);
    let before = tree(tmp.path());
    let d = models.to_str().unwrap();
    let same_by_another_name = format!("{d}/../models");
    for out in [
        d,
        same_by_another_name.as_str(),
        tmp.path().to_str().unwrap(),
    ] {
        let run = lodstudio(&["export", d, "--lods", LODS, NO_BAKE, "-o", out, "--force"]);
        assert_eq!(run.status.code(), Some(2), "-o {out}");
        let e = one_line(&run);
        assert!(e.contains("inside the output folder"), "{e}");
        assert!(
            tree(tmp.path()) == before,
            "-o {out}: nothing written, inputs unchanged"
        );
    }
    // A manifest the batch would write over (its summary) is refused too.
    let out = tmp.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let manifest = out.join("summary.json");
    std::fs::write(
        &manifest,
        format!("{}\n", models.join("bones.off").display()),
    )
    .unwrap();
    let run = lodstudio(&[
        "export",
        "--manifest",
        manifest.to_str().unwrap(),
        "--asset-root",
        tmp.path().to_str().unwrap(),
        "--lods",
        LODS,
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(run.status.code(), Some(2));
    assert!(one_line(&run).contains("would be written by it"));
    assert!(!out.join(".lodstudio-cache").exists());
}

/// The cache records (JSON files) under an output folder whose `output` is `name`.
fn records_of(out: &Path, name: &str) -> Vec<PathBuf> {
    let cache = out.join(".lodstudio-cache");
    tree(&cache)
        .into_iter()
        .filter(|(p, bytes)| {
            p.extension().is_some_and(|e| e == "json")
                && serde_json::from_slice::<Value>(bytes).is_ok_and(|r| r["output"] == name)
        })
        .map(|(p, _)| cache.join(p))
        .collect()
}

/// A damaged cache record is a miss: the model is rebuilt with the reason
/// "cache record damaged" and the rerun succeeds (it is not taken for a
/// file the batch did not make), and the one after skips it again.
#[test]
fn a_damaged_cache_record_is_rebuilt() {
    let tmp = tempfile::tempdir().unwrap();
    let models = copies_in(tmp.path(), "models", &["bones.off", "fandisk.obj"]);
    let out = tmp.path().join("out");
    let (code, first) = export(&models, &out, &[]);
    assert_eq!((code, first["built"].as_u64()), (Some(0), Some(2)));
    let records = records_of(&out, "bones.glb");
    assert!(!records.is_empty());
    for r in &records {
        std::fs::write(r, b"{\"key\": \"tr").unwrap();
    }
    let (code, rerun) = export(&models, &out, &[]);
    assert_eq!(code, Some(0), "{rerun}");
    assert_eq!(
        (rerun["built"].as_u64(), rerun["skipped"].as_u64()),
        (Some(1), Some(1))
    );
    let built: Vec<&Value> = rerun["reports"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["status"] == "built")
        .collect();
    assert!(built[0]["input"].as_str().unwrap().ends_with("bones.off"));
    assert_eq!(built[0]["reason"], "cache record damaged");
    let (code, again) = export(&models, &out, &[]);
    assert_eq!((code, again["skipped"].as_u64()), (Some(0), Some(2)));
}

/// The temporaries a killed run left (made here by hand, with a token whose
/// lock nobody holds) are removed by the next run; a live run's (its lock
/// held) are not, until its lock is released.
#[cfg(unix)]
#[test]
fn temporaries_of_killed_runs_go_and_live_ones_stay() {
    use std::os::fd::AsRawFd;
    let tmp = tempfile::tempdir().unwrap();
    let models = copies_in(tmp.path(), "models", &["bones.off"]);
    let out = tmp.path().join("out");
    assert_eq!(export(&models, &out, &[]).0, Some(0));
    let cache = out.join(".lodstudio-cache");
    let (dead, live) = ("999999-00000000000dead0", "999998-000000000000a1e0");
    std::fs::write(cache.join(format!("locks/{dead}.lock")), b"").unwrap();
    let held = std::fs::File::create(cache.join(format!("locks/{live}.lock"))).unwrap();
    // SAFETY: flock on a descriptor this test owns.
    assert_eq!(unsafe { libc::flock(held.as_raw_fd(), libc::LOCK_EX) }, 0);
    let left = |token: &str| {
        let files = [
            out.join(format!(".summary.json.tmp{token}-0")),
            out.join(format!(".bones.glb.tmp{token}-4")),
            cache.join(format!("tmp/{token}/bones.glb/model.glb")),
            cache.join(format!(
                "tmp/{token}/bones.glb/.model.glb.tmp1-0123456789abcdef-0"
            )),
        ];
        for f in &files {
            std::fs::create_dir_all(f.parent().unwrap()).unwrap();
            std::fs::write(f, b"half").unwrap();
        }
        files
    };
    let (dead_files, live_files) = (left(dead), left(live));
    assert_eq!(export(&models, &out, &[]).0, Some(0));
    for f in &dead_files {
        assert!(!f.exists(), "{} left", f.display());
    }
    assert!(!cache.join(format!("locks/{dead}.lock")).exists());
    for f in &live_files {
        assert!(f.exists(), "{} removed while its run lives", f.display());
    }
    drop(held);
    assert_eq!(export(&models, &out, &[]).0, Some(0));
    for f in &live_files {
        assert!(!f.exists(), "{} left once its run ended", f.display());
    }
    // Nothing of the batches themselves is left either.
    let tmp_left: Vec<_> = std::fs::read_dir(cache.join("tmp")).unwrap().collect();
    assert!(tmp_left.is_empty(), "{tmp_left:?}");
}

/// Two batches with different recipes on one folder at once (after a first
/// run) neither refuse each other's outputs nor tear or drop report lines:
/// the report keeps every run's lines, each whole.
#[test]
fn concurrent_batches_on_one_folder_append_whole_report_lines() {
    let tmp = tempfile::tempdir().unwrap();
    let models = tmp.path().join("models");
    std::fs::create_dir(&models).unwrap();
    let n = 12;
    for i in 0..n {
        let mesh = lodstudio_core::builtins::torus(1.0, 0.2 + 0.01 * i as f32, 16 + 2 * i, 10 + i);
        let path = models.join(format!("torus{i:02}.obj"));
        std::fs::write(
            &path,
            lodstudio_core::io::encode_mesh(&path, &mesh).unwrap(),
        )
        .unwrap();
    }
    let out = tmp.path().join("out");
    assert_eq!(export(&models, &out, &["--threads", "2"]).0, Some(0));
    let children: Vec<_> = ["simplify:0.25", "simplify:0.75"]
        .iter()
        .map(|lods| {
            Command::new(lodstudio_bin())
                .args(["export", models.to_str().unwrap(), "--lods", lods, "-o"])
                .arg(&out)
                .args(["--threads", "2", "--json"])
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    for child in children {
        let run = child.wait_with_output().unwrap();
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let j: Value = serde_json::from_slice(&run.stdout).unwrap();
        assert_eq!(j["failed"], 0);
    }
    let text = std::fs::read_to_string(out.join("report.jsonl")).unwrap();
    assert!(text.ends_with('\n'));
    let mut runs: std::collections::BTreeMap<String, usize> = Default::default();
    for line in text.lines() {
        let l: Value = serde_json::from_str(line).unwrap_or_else(|e| panic!("{e}: {line}"));
        assert!(l["input"].as_str().unwrap().ends_with(".obj"));
        *runs
            .entry(l["run"].as_str().unwrap().to_string())
            .or_default() += 1;
    }
    assert_eq!(
        runs.values().copied().collect::<Vec<_>>(),
        [n as usize; 3],
        "{runs:?}"
    );
}

/// A model still building after `--timeout-per-model` is killed and reported
/// failed ("timeout after S s", exit 1); the others are built, and nothing
/// of its build is left in the cache.
#[test]
fn a_model_over_its_timeout_is_killed_and_reported() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = copies_in(tmp.path(), "models", &["dragon_vrip.ply.gz", "bones.off"]);
    let manifest = dir.join("m.txt");
    // A hybrid chain of the 871k-triangle dragon takes far longer than 3 s.
    std::fs::write(&manifest, "dragon_vrip.ply.gz lods=hybrid:1%\nbones.off\n").unwrap();
    let out = tmp.path().join("out");
    let (m, o) = (manifest.to_str().unwrap(), out.to_str().unwrap());
    let start = std::time::Instant::now();
    let run = run_within(
        &[
            "export",
            "--manifest",
            m,
            "--lods",
            LODS,
            "-o",
            o,
            "--threads",
            "2",
            "--timeout-per-model",
            "3",
            "--json",
        ],
        std::time::Duration::from_secs(60),
    );
    assert!(start.elapsed().as_secs() < 20, "{:?}", start.elapsed());
    let j = summary_of(&run, 1, 1, 1);
    let failure = &j["failures"][0];
    assert!(
        failure["file"]
            .as_str()
            .unwrap()
            .ends_with("dragon_vrip.ply.gz")
    );
    assert_eq!(failure["error"], "timeout after 3 s");
    let line = std::fs::read_to_string(out.join("report.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).unwrap())
        .find(|l| l["input"].as_str().unwrap().ends_with("dragon_vrip.ply.gz"))
        .unwrap();
    assert_eq!(
        (&line["status"], &line["error"]),
        (&"failed".into(), &"timeout after 3 s".into())
    );
    assert!(out.join("bones.glb").exists() && !out.join("dragon_vrip.glb").exists());
    let scratch: Vec<_> = std::fs::read_dir(out.join(".lodstudio-cache/tmp"))
        .unwrap()
        .collect();
    assert!(scratch.is_empty(), "{scratch:?}");
    for bad in ["0", "-1", "nan", "inf", "1e300"] {
        let r = lodstudio(&[
            "export",
            "--manifest",
            m,
            "--lods",
            LODS,
            "-o",
            o,
            "--timeout-per-model",
            bad,
        ]);
        assert_eq!(r.status.code(), Some(2), "{bad}");
    }
}

/// A gzip input's memory estimate counts what it inflates to (measured),
/// not its compressed bytes: 100 MiB of zeros in a 100 KiB file is
/// estimated at no less than 100 MiB; with a lower --max-decompressed, at
/// no less than that cap and below the full size's estimate.
#[test]
fn gzip_inputs_are_estimated_at_their_inflated_size() {
    use std::io::Write as _;
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("models");
    std::fs::create_dir(&dir).unwrap();
    let inflated: u64 = 100 << 20;
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    let zeros = vec![0u8; 1 << 20];
    for _ in 0..(inflated >> 20) {
        gz.write_all(&zeros).unwrap();
    }
    let bytes = gz.finish().unwrap();
    assert!(bytes.len() < 1 << 20);
    std::fs::write(dir.join("zeros.obj.gz"), &bytes).unwrap();
    let estimate = |extra: &[&str]| {
        let out = tempfile::tempdir().unwrap();
        let (_, j) = export(&dir, out.path(), extra);
        let line = &j["reports"][0];
        assert!(line["input"].as_str().unwrap().ends_with("zeros.obj.gz"));
        line["estimated_peak_bytes"].as_u64().unwrap()
    };
    let full = estimate(&[]);
    assert!(full >= inflated, "{full} < {inflated}");
    let capped = estimate(&["--max-decompressed", "50M"]);
    assert!(capped >= 50 << 20 && capped < full, "{capped} vs {full}");
}

/// The files a glTF names are confined to the batch's root (the manifest's
/// folder), in the batch and in its children alike: a buffer in a sibling
/// folder inside it is read (and its bytes are in the key), one outside it
/// fails that model alone as bad input with the policy's message.
#[test]
fn gltf_references_are_confined_to_the_batch_root() {
    let tmp = tempfile::tempdir().unwrap();
    let root = tmp.path().join("root");
    for sub in ["models", "buffers"] {
        std::fs::create_dir_all(root.join(sub)).unwrap();
    }
    // A small glTF (a torus) whose buffer lies in another folder.
    let mesh = lodstudio_core::builtins::torus(1.0, 0.3, 24, 12);
    let glb = lodstudio_core::io::encode_mesh(Path::new("t.glb"), &mesh).unwrap();
    let (json, bin) = lodstudio_core::io::gltf::split_glb(&glb, "engine.bin").unwrap();
    let json = String::from_utf8(json).unwrap();
    assert!(json.contains("\"engine.bin\""));
    let naming = |uri: &str| json.replace("\"engine.bin\"", &format!("{uri:?}"));
    std::fs::write(root.join("buffers/engine.bin"), &bin).unwrap();
    std::fs::write(tmp.path().join("outside.bin"), &bin).unwrap();
    std::fs::write(
        root.join("models/inside.gltf"),
        naming("../buffers/engine.bin"),
    )
    .unwrap();
    std::fs::write(root.join("models/escape.gltf"), naming("../../outside.bin")).unwrap();
    std::fs::copy(shared_model("bones.off"), root.join("models/bones.off")).unwrap();
    let manifest = root.join("m.txt");
    std::fs::write(
        &manifest,
        "models/inside.gltf\nmodels/escape.gltf\nmodels/bones.off\n",
    )
    .unwrap();
    let out = tmp.path().join("out");
    let (m, o) = (manifest.to_str().unwrap(), out.to_str().unwrap());
    let run = lodstudio(&["export", "--manifest", m, "--lods", LODS, "-o", o, "--json"]);
    let j = summary_of(&run, 2, 2, 1);
    let failure = &j["failures"][0];
    assert!(failure["file"].as_str().unwrap().ends_with("escape.gltf"));
    let error = failure["error"].as_str().unwrap();
    assert!(
        error.contains("buffer 0: uri \"../../outside.bin\" is outside the asset folder"),
        "{error}"
    );
    assert!(out.join("inside.glb").exists() && !out.join("escape.glb").exists());
    // The sibling folder's buffer is content: changing it rebuilds its model.
    let (_, again) = export_manifest(m, o);
    assert_eq!(again["skipped"].as_u64(), Some(2));
    let mut bin = std::fs::read(root.join("buffers/engine.bin")).unwrap();
    bin.push(0);
    std::fs::write(root.join("buffers/engine.bin"), bin).unwrap();
    let (_, changed) = export_manifest(m, o);
    assert_eq!(
        (changed["built"].as_u64(), changed["skipped"].as_u64()),
        (Some(1), Some(1))
    );
}

fn export_manifest(manifest: &str, out: &str) -> (Option<i32>, Value) {
    let run = lodstudio(&[
        "export",
        "--manifest",
        manifest,
        "--lods",
        LODS,
        "-o",
        out,
        "--json",
    ]);
    (
        run.status.code(),
        serde_json::from_slice(&run.stdout).unwrap(),
    )
}

/// A batch's summary, after checking its exit code and its built and failed counts.
fn summary_of(run: &std::process::Output, code: i32, built: u64, failed: u64) -> Value {
    assert_eq!(
        run.status.code(),
        Some(code),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let j: Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(
        (j["built"].as_u64(), j["failed"].as_u64()),
        (Some(built), Some(failed))
    );
    j
}
