//! Untrusted input (issue 51): what a model, a recipe or an argument may make
//! lodstudio read, allocate or overwrite.
//!
//! - URI policy: glTF buffers and images resolve only inside the model's
//!   folder (or `--asset-root DIR`; `--allow-outside-uris` opts out); special
//!   files (devices, FIFOs, folders) are refused whatever the policy, and a
//!   hostile batch leaks nothing of a secret file into its outputs.
//! - Special files as inputs (the model, the recipe) are refused within seconds.
//! - Data loss: outputs that coincide, a failed save, `--save-diff` without
//!   `--force`: nothing is written.
//! - Limits: chain rows, sample counts, texels, node-graph instances, image
//!   headers and gzip streams are checked against budgets before the work.
//! - Environment failures (a full disk, permission denied) exit 1, not 2.
//!
//! Every run is a child `lodstudio` with a time limit (killed, and the test
//! failed, past it: a FIFO must never hang a run) and an address-space cap
//! (a reader that fills memory from `/dev/zero` fails instead of taking the
//! machine with it). Every temporary folder is a `tempfile::tempdir()`.

use std::io::Write as _;
use std::os::unix::fs::PermissionsExt as _;
use std::os::unix::process::CommandExt as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use lodstudio_tests::lodstudio_bin;
use serde_json::{Value, json};

// ---------------------------------------------------------------- running

/// What one run of the CLI gave.
#[derive(Debug)]
struct Run {
    args: Vec<String>,
    /// The exit status; `None` when a signal ended it (`signal`).
    code: Option<i32>,
    signal: Option<i32>,
    stdout: String,
    stderr: String,
    time: Duration,
    /// Peak resident memory of the child alone (its own `rusage`).
    max_rss_bytes: u64,
    /// User and system CPU time of the child (and the children it waited for).
    cpu: Duration,
}

impl Run {
    /// The JSON object a `--json` run printed.
    fn json(&self) -> Value {
        serde_json::from_str(self.stdout.trim()).unwrap_or_else(|e| {
            panic!(
                "{:?}: stdout is not one JSON object ({e}): {}",
                self.args, self.stdout
            )
        })
    }
}

/// How a run is made.
#[derive(Debug, Clone)]
struct Opts {
    /// Killed (and the test failed) past this.
    limit: Duration,
    /// Run as this user and group (an unprivileged one, for permission tests).
    uid: Option<u32>,
    /// Cap on the child's address space (`RLIMIT_AS`), `None` for none.
    address_space: Option<u64>,
}

const GIB: u64 = 1 << 30;
const MIB: u64 = 1 << 20;

impl Default for Opts {
    fn default() -> Self {
        Opts {
            limit: Duration::from_secs(120),
            uid: None,
            address_space: Some(4 * GIB),
        }
    }
}

fn within(secs: u64) -> Opts {
    Opts {
        limit: Duration::from_secs(secs),
        ..Opts::default()
    }
}

/// `lodstudio ARGS` with the default limits.
fn cli(args: &[&str]) -> Run {
    cli_with(args, Opts::default())
}

/// Runs `lodstudio ARGS` in its own process group, without a display and
/// without the limit variables of the caller's environment; reaps it with
/// `wait4` for its rusage, and kills the group past `opts.limit`.
#[expect(clippy::zombie_processes, reason = "reaped by wait4, for its rusage")]
fn cli_with(args: &[&str], opts: Opts) -> Run {
    let logs = tempfile::tempdir().unwrap();
    let (out_path, err_path) = (logs.path().join("stdout"), logs.path().join("stderr"));
    let mut cmd = Command::new(lodstudio_bin());
    cmd.args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("LODSTUDIO_MAX_DECOMPRESSED")
        .env_remove("LODSTUDIO_MAX_MEMORY")
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out_path).unwrap())
        .stderr(std::fs::File::create(&err_path).unwrap())
        .process_group(0);
    if let Some(uid) = opts.uid {
        cmd.uid(uid).gid(uid);
    }
    if let Some(cap) = opts.address_space {
        // SAFETY: setrlimit is async-signal-safe and touches only the child.
        unsafe {
            cmd.pre_exec(move || {
                let lim = libc::rlimit {
                    rlim_cur: cap as libc::rlim_t,
                    rlim_max: cap as libc::rlim_t,
                };
                libc::setrlimit(libc::RLIMIT_AS, &lim);
                Ok(())
            });
        }
    }
    let start = Instant::now();
    let child = cmd.spawn().expect("run lodstudio");
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    // SAFETY: rusage is plain data; wait4 fills it for our own child.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    loop {
        let r = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        if r == pid {
            break;
        }
        assert_eq!(r, 0, "wait4 on lodstudio {args:?}");
        if start.elapsed() > opts.limit {
            // SAFETY: signals our own child's process group, then reaps the child.
            unsafe {
                libc::kill(-pid, libc::SIGKILL);
                libc::wait4(pid, &mut status, 0, &mut usage);
            }
            panic!(
                "lodstudio {args:?} was still running after {:?} (killed): it hangs",
                opts.limit
            );
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    let time = start.elapsed();
    let (code, signal) = if libc::WIFEXITED(status) {
        (Some(libc::WEXITSTATUS(status)), None)
    } else {
        (None, Some(libc::WTERMSIG(status)))
    };
    Run {
        args: args.iter().map(|a| a.to_string()).collect(),
        code,
        signal,
        stdout: std::fs::read_to_string(&out_path).unwrap_or_default(),
        stderr: String::from_utf8_lossy(&std::fs::read(&err_path).unwrap()).into_owned(),
        time,
        max_rss_bytes: usage.ru_maxrss as u64 * 1024, // KiB on Linux
        cpu: [usage.ru_utime, usage.ru_stime]
            .iter()
            .map(|t| Duration::new(t.tv_sec as u64, t.tv_usec as u32 * 1000))
            .sum(),
    }
}

/// Exactly one non-empty line on stderr, no panic, no internal error.
fn assert_one_line(run: &Run) {
    let lines: Vec<&str> = run.stderr.trim_end().lines().collect();
    assert_eq!(
        lines.len(),
        1,
        "{:?}: one line on stderr: {:?}",
        run.args,
        run.stderr
    );
    assert!(
        !lines[0].trim().is_empty(),
        "{:?}: an empty message",
        run.args
    );
    for bad in ["panicked", "internal error", "assertion", "RUST_BACKTRACE"] {
        assert!(!run.stderr.contains(bad), "{:?}: {}", run.args, run.stderr);
    }
}

/// Exit 2 (bad input), one line on stderr that contains every one of `all`.
fn assert_bad_input(run: &Run, all: &[&str]) {
    assert_eq!(
        (run.code, run.signal),
        (Some(2), None),
        "{:?}: exit 2 expected: {}",
        run.args,
        run.stderr
    );
    assert_one_line(run);
    for needle in all {
        assert!(
            run.stderr.contains(needle),
            "{:?}: {needle:?} not in {:?}",
            run.args,
            run.stderr
        );
    }
}

/// Refused as bad input within seconds, with nothing written in `out`.
fn assert_refused_at_once(run: &Run, out: &Path) {
    assert_bad_input(run, &[]);
    assert!(
        run.time < Duration::from_secs(5),
        "{:?}: {:?}",
        run.args,
        run.time
    );
    assert!(
        listing(out).is_empty(),
        "{:?} wrote {:?}",
        run.args,
        listing(out)
    );
}

/// The message contains at least one of `any`.
fn assert_mentions_any(run: &Run, any: &[&str]) {
    assert!(
        any.iter().any(|n| run.stderr.contains(n)),
        "{:?}: none of {any:?} in {:?}",
        run.args,
        run.stderr
    );
}

/// Exit 0, or a failure naming its stderr.
fn assert_ok(run: &Run) {
    assert_eq!(
        (run.code, run.signal),
        (Some(0), None),
        "{:?} failed: {}",
        run.args,
        run.stderr
    );
}

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 temporary paths")
}

/// The names in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Every regular file under `dir`, recursively (links not followed).
fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let e = e.unwrap();
            let t = e.file_type().unwrap();
            if t.is_dir() {
                stack.push(e.path());
            } else if t.is_file() {
                out.push(e.path());
            }
        }
    }
    out.sort();
    out
}

fn contains(haystack: &[u8], needle: &[u8]) -> bool {
    haystack.windows(needle.len()).any(|w| w == needle)
}

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(s(path)).unwrap();
    // SAFETY: a valid C string; mkfifo only creates a file.
    assert_eq!(
        unsafe { libc::mkfifo(c.as_ptr(), 0o600) },
        0,
        "mkfifo {}",
        path.display()
    );
}

// ---------------------------------------------------------------- models

/// What a hostile model must never copy into an output: 64 distinctive bytes.
const SECRET: &[u8; 64] = b"lodstudio/issue-51/SECRET:7e1d0c9b-never-in-an-output-4a6f8e2d!!";

/// A unit cube: 8 positions (96 bytes), 8 UVs (64), 36 u16 indices (72).
fn cube_bin() -> Vec<u8> {
    let mut out = Vec::with_capacity(CUBE_BYTES);
    for i in 0..8u32 {
        for axis in 0..3 {
            out.extend_from_slice(&(((i >> axis) & 1) as f32).to_le_bytes());
        }
    }
    for i in 0..8u32 {
        for axis in 0..2 {
            out.extend_from_slice(&(((i >> axis) & 1) as f32).to_le_bytes());
        }
    }
    let faces: [u16; 36] = [
        0, 2, 3, 0, 3, 1, // z = 0
        4, 5, 7, 4, 7, 6, // z = 1
        0, 1, 5, 0, 5, 4, // y = 0
        2, 6, 7, 2, 7, 3, // y = 1
        0, 4, 6, 0, 6, 2, // x = 0
        1, 3, 7, 1, 7, 5, // x = 1
    ];
    for i in faces {
        out.extend_from_slice(&i.to_le_bytes());
    }
    assert_eq!(out.len(), CUBE_BYTES);
    out
}
const CUBE_BYTES: usize = 232;

/// Standard base64 with padding (no dependency for one test).
fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

fn data_uri(bytes: &[u8]) -> String {
    format!("data:application/octet-stream;base64,{}", base64(bytes))
}

/// Where the cube's base-colour image comes from.
enum Image<'a> {
    None,
    /// `images[0].uri`.
    Uri(&'a str),
    /// A second buffer (64 bytes: the secret's size) at this URI, read as a
    /// PNG through a buffer view: what a reader without the policy copies
    /// into every export.
    Buffer(&'a str),
}

/// A glTF of the cube whose geometry is buffer 0 at `geometry_uri`, and a
/// textured material when `image` says where its image is.
fn cube_gltf(geometry_uri: &str, image: Image) -> Value {
    let mut g = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": CUBE_BYTES, "uri": geometry_uri}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 96, "target": 34962},
            {"buffer": 0, "byteOffset": 96, "byteLength": 64, "target": 34962},
            {"buffer": 0, "byteOffset": 160, "byteLength": 72, "target": 34963}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
            {"bufferView": 1, "componentType": 5126, "count": 8, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 36, "type": "SCALAR"}
        ],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2}]}],
        "nodes": [{"mesh": 0, "name": "cube"}],
        "scenes": [{"nodes": [0]}],
        "scene": 0
    });
    let source = match image {
        Image::None => return g,
        Image::Uri(uri) => json!({"uri": uri}),
        Image::Buffer(uri) => {
            g["buffers"]
                .as_array_mut()
                .unwrap()
                .push(json!({"byteLength": SECRET.len(), "uri": uri}));
            g["bufferViews"]
                .as_array_mut()
                .unwrap()
                .push(json!({"buffer": 1, "byteOffset": 0, "byteLength": SECRET.len()}));
            json!({"bufferView": 3, "mimeType": "image/png"})
        }
    };
    g["images"] = json!([source]);
    g["textures"] = json!([{"source": 0}]);
    g["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    g["meshes"][0]["primitives"][0]["material"] = json!(0);
    g
}

fn write_json(path: &Path, value: &Value) {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir).unwrap();
    }
    std::fs::write(path, serde_json::to_vec(value).unwrap()).unwrap();
}

/// A temporary tree: `secret.bin` (the secret) beside `model/`, the folder
/// the hostile models live in.
struct Tree {
    dir: tempfile::TempDir,
}

impl Tree {
    fn new() -> Tree {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir_all(dir.path().join("model")).unwrap();
        std::fs::write(dir.path().join("secret.bin"), SECRET).unwrap();
        Tree { dir }
    }
    fn root(&self) -> &Path {
        self.dir.path()
    }
    fn model(&self) -> PathBuf {
        self.root().join("model")
    }
    fn secret(&self) -> PathBuf {
        self.root().join("secret.bin")
    }
    fn out(&self) -> PathBuf {
        let out = self.root().join("out");
        std::fs::create_dir_all(&out).unwrap();
        out
    }
}

/// `info`, `simplify -o out.glb` and `export --lods simplify:50% -o out.glb`
/// of `model` each exit 2 with one line containing all of `needles`, and
/// leave `out` (an empty folder) empty: no output, no temporary.
fn refused_by_info_simplify_and_export(model: &Path, out: &Path, extra: &[&str], needles: &[&str]) {
    let target = out.join("out.glb");
    let runs: [Vec<&str>; 3] = [
        vec!["info", s(model)],
        vec!["simplify", s(model), "--ratio", "0.5", "-o", s(&target)],
        vec![
            "export",
            s(model),
            "--lods",
            "simplify:50%",
            "-o",
            s(&target),
        ],
    ];
    for mut args in runs {
        args.extend_from_slice(extra);
        let run = cli_with(&args, within(60));
        assert_bad_input(&run, needles);
        assert!(listing(out).is_empty(), "{args:?} left {:?}", listing(out));
    }
}

// ---------------------------------------------------------------- URI policy

#[test]
fn image_uris_outside_the_model_folder_are_refused() {
    let t = Tree::new();
    let geometry = data_uri(&cube_bin());
    for uri in ["/etc/passwd", s(&t.secret())] {
        let model = t.model().join("abs-image.gltf");
        write_json(&model, &cube_gltf(&geometry, Image::Uri(uri)));
        refused_by_info_simplify_and_export(
            &model,
            &t.out(),
            &[],
            &[
                "image 0",
                uri,
                "outside the asset folder",
                "an absolute path",
            ],
        );
    }
}

#[test]
fn buffer_uris_that_leave_the_model_folder_are_refused() {
    let t = Tree::new();
    let geometry = data_uri(&cube_bin());
    std::fs::create_dir_all(t.model().join("links")).unwrap();
    std::os::unix::fs::symlink(t.secret(), t.model().join("links/link.bin")).unwrap();
    let absolute = s(&t.secret()).to_string();
    let file_uri = format!("file://{absolute}");
    for (uri, why) in [
        ("../secret.bin", "it climbs out with .."),
        (absolute.as_str(), "an absolute path"),
        (file_uri.as_str(), "not file:"),
        ("links/link.bin", "a link leads out of it"),
    ] {
        let model = t.model().join("hostile-buffer.gltf");
        write_json(&model, &cube_gltf(&geometry, Image::Buffer(uri)));
        refused_by_info_simplify_and_export(
            &model,
            &t.out(),
            &[],
            &["buffer 1", uri, "outside the asset folder", why],
        );
    }
}

#[test]
fn special_files_named_as_buffers_are_refused_without_hanging() {
    let t = Tree::new();
    mkfifo(&t.model().join("fifo.bin"));
    std::fs::create_dir_all(t.model().join("folder.bin")).unwrap();
    let special = ["not a regular file", "a device", "a FIFO", "a folder"];
    let cases: [(&str, &[&str], &[&str]); 4] = [
        // Refused as outside (an absolute path) or as a device: either way unread.
        ("/dev/zero", &[], &["outside the asset folder", "a device"]),
        // Outside allowed: still a device, never read.
        ("/dev/zero", &["--allow-outside-uris"], &special),
        ("fifo.bin", &[], &special),
        ("folder.bin", &[], &special),
    ];
    for (uri, extra, any) in cases {
        let model = t.model().join("special.gltf");
        write_json(&model, &cube_gltf(uri, Image::None));
        let mut args = vec!["info", s(&model), "--max-memory", "512M"];
        args.extend_from_slice(extra);
        let run = cli_with(&args, within(20));
        assert_bad_input(&run, &["buffer 0", uri]);
        assert_mentions_any(&run, any);
        assert!(
            run.time < Duration::from_secs(10),
            "{args:?}: {:?}",
            run.time
        );
    }
}

#[test]
fn buffers_inside_the_folder_and_data_uris_load() {
    let t = Tree::new();
    std::fs::create_dir_all(t.model().join("sub")).unwrap();
    std::fs::write(t.model().join("sub/mesh.bin"), cube_bin()).unwrap();
    std::fs::write(t.model().join("sub/my mesh.bin"), cube_bin()).unwrap();
    let data = data_uri(&cube_bin());
    for uri in [
        "sub/mesh.bin",
        "sub/my%20mesh.bin",
        "./sub/../sub/mesh.bin",
        data.as_str(),
    ] {
        let model = t.model().join("good.gltf");
        write_json(&model, &cube_gltf(uri, Image::None));
        let run = cli(&["info", s(&model), "--json"]);
        assert_ok(&run);
        assert_eq!(run.json()["triangles"], 12, "{uri}: {}", run.stdout);
    }
}

#[test]
fn asset_root_and_allow_outside_uris_widen_the_folder() {
    let t = Tree::new();
    std::fs::write(t.root().join("shared.bin"), cube_bin()).unwrap();
    let up = t.model().join("up.gltf");
    write_json(&up, &cube_gltf("../shared.bin", Image::None));
    let run = cli(&["info", s(&up)]);
    assert_bad_input(
        &run,
        &[
            "buffer 0",
            "../shared.bin",
            "outside the asset folder",
            "climbs out",
        ],
    );
    // The parent named as the asset root makes ../shared.bin legal.
    let run = cli(&["info", s(&up), "--asset-root", s(t.root()), "--json"]);
    assert_ok(&run);
    assert_eq!(run.json()["triangles"], 12);
    // The model's own folder named: the same refusal as without the option.
    let run = cli(&["info", s(&up), "--asset-root", s(&t.model())]);
    assert_bad_input(&run, &["outside the asset folder"]);

    let shared = t.root().join("shared.bin");
    let absolute = t.model().join("absolute.gltf");
    write_json(&absolute, &cube_gltf(s(&shared), Image::None));
    let run = cli(&["info", s(&absolute)]);
    assert_bad_input(
        &run,
        &["buffer 0", "outside the asset folder", "an absolute path"],
    );
    let run = cli(&["info", s(&absolute), "--allow-outside-uris", "--json"]);
    assert_ok(&run);
    assert_eq!(run.json()["triangles"], 12);
}

/// A folder of hostile glTFs and one good model, exported as a batch: the
/// hostile ones fail (exit 2 overall), the good one is built, no cache
/// record or output names a hostile one, and no file anywhere under the
/// output folder holds the secret's bytes. The FIFO and `/dev/zero` also
/// pass through the cache's list of named files: they must not hang it.
#[test]
fn a_hostile_batch_leaks_nothing_and_builds_the_good_model() {
    let t = Tree::new();
    let models = t.model();
    let geometry = data_uri(&cube_bin());
    std::fs::create_dir_all(models.join("links")).unwrap();
    std::os::unix::fs::symlink(t.secret(), models.join("links/link.bin")).unwrap();
    std::fs::create_dir_all(models.join("pipes")).unwrap();
    mkfifo(&models.join("pipes/fifo.bin"));
    let absolute = s(&t.secret()).to_string();
    let file_uri = format!("file://{absolute}");
    let hostile: Vec<(&str, Value)> = vec![
        ("image-etc", cube_gltf(&geometry, Image::Uri("/etc/passwd"))),
        (
            "image-absolute",
            cube_gltf(&geometry, Image::Uri(&absolute)),
        ),
        (
            "image-up",
            cube_gltf(&geometry, Image::Uri("../secret.bin")),
        ),
        (
            "buffer-up",
            cube_gltf(&geometry, Image::Buffer("../secret.bin")),
        ),
        (
            "buffer-absolute",
            cube_gltf(&geometry, Image::Buffer(&absolute)),
        ),
        (
            "buffer-file",
            cube_gltf(&geometry, Image::Buffer(&file_uri)),
        ),
        (
            "buffer-link",
            cube_gltf(&geometry, Image::Buffer("links/link.bin")),
        ),
        ("buffer-zero", cube_gltf("/dev/zero", Image::None)),
        ("buffer-fifo", cube_gltf("pipes/fifo.bin", Image::None)),
    ];
    for (name, g) in &hostile {
        write_json(&models.join(format!("{name}.gltf")), g);
    }
    write_json(
        &models.join("good.gltf"),
        &cube_gltf(&geometry, Image::None),
    );
    let out = t.root().join("lods");
    let run = cli_with(
        &[
            "export",
            s(&models),
            "--lods",
            "simplify:50%",
            "-o",
            s(&out),
            "--json",
        ],
        within(300),
    );
    assert_eq!(run.code, Some(2), "a bad input among them: {}", run.stderr);
    assert!(
        out.join("good.glb").is_file(),
        "the good model is built: {}",
        run.stderr
    );
    let summary = run.json();
    assert_eq!(summary["built"], 1, "{summary}");
    assert_eq!(summary["failed"], hostile.len(), "{summary}");
    for (name, _) in &hostile {
        assert!(
            !out.join(format!("{name}.glb")).exists(),
            "{name}.glb written"
        );
    }
    // Cache records (records/OUTPUT/KEY.json) name the good output alone.
    let records: Vec<_> = files_under(&out.join(".lodstudio-cache/records"))
        .into_iter()
        .filter(|f| f.extension().is_some_and(|x| x == "json"))
        .collect();
    assert_eq!(records.len(), 1, "{records:?}");
    let record: Value = serde_json::from_slice(&std::fs::read(&records[0]).unwrap()).unwrap();
    assert_eq!(record["output"], "good.glb", "{record}");
    let files = files_under(&out);
    assert!(!files.is_empty());
    for f in files {
        let bytes = std::fs::read(&f).unwrap();
        assert!(
            !contains(&bytes, SECRET),
            "{} holds the secret",
            f.display()
        );
    }
}

// ---------------------------------------------------------------- special files

#[test]
fn special_files_as_the_model_are_refused_within_seconds() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("model.ply");
    mkfifo(&fifo);
    let folder = dir.path().join("folder.obj");
    std::fs::create_dir_all(&folder).unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    let target = out.join("x.obj");
    let special = ["not a regular file", "a device", "a FIFO", "a folder"];
    for model in [Path::new("/dev/zero"), &fifo, &folder] {
        for args in [
            vec!["info", s(model)],
            vec!["simplify", s(model), "--ratio", "0.5", "-o", s(&target)],
        ] {
            let run = cli_with(&args, within(20));
            assert_refused_at_once(&run, &out);
            assert_mentions_any(&run, &special);
        }
    }
}

#[test]
fn special_and_huge_recipes_are_refused_quickly() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("recipe.json");
    mkfifo(&fifo);
    let random = dir.path().join("random.json");
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let bytes: Vec<u8> = (0..20 * MIB)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 24) as u8
        })
        .collect();
    std::fs::write(&random, bytes).unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    let target = out.join("x.glb");
    for recipe in [Path::new("/dev/zero"), &fifo, &random] {
        let args = [
            "export",
            "builtin:sphere",
            "--recipe",
            s(recipe),
            "-o",
            s(&target),
        ];
        let run = cli_with(&args, within(20));
        assert_refused_at_once(&run, &out);
        assert!(
            run.stderr.len() < 1000,
            "{args:?}: a short message, not {} bytes",
            run.stderr.len()
        );
    }
}

// ---------------------------------------------------------------- data loss

#[test]
fn outputs_that_coincide_are_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let x = dir.path().join("x.glb");
    let run = cli(&[
        "simplify",
        "builtin:sphere",
        "--ratio",
        "0.5",
        "-o",
        s(&x),
        "--save",
        s(&x),
    ]);
    assert_bad_input(&run, &[s(&x)]);
    assert_mentions_any(&run, &["coincide", "two outputs"]);
    assert!(!x.exists(), "nothing written");

    let b = dir.path().join("b.glb");
    let run = cli(&[
        "export",
        "builtin:sphere",
        "--lods",
        "simplify:50%",
        "-o",
        s(&b),
        "--save-recipe",
        s(&b),
    ]);
    assert_bad_input(&run, &[s(&b)]);
    assert_mentions_any(&run, &["coincide", "two outputs"]);
    assert!(!b.exists(), "nothing written");
    assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));

    // An output that is the input, even with --force: the input is kept.
    let input = dir.path().join("cube.gltf");
    write_json(&input, &cube_gltf(&data_uri(&cube_bin()), Image::None));
    let before = std::fs::read(&input).unwrap();
    let run = cli(&[
        "simplify",
        s(&input),
        "--ratio",
        "0.5",
        "-o",
        s(&input),
        "--force",
    ]);
    assert_bad_input(&run, &["input"]);
    assert_eq!(
        std::fs::read(&input).unwrap(),
        before,
        "the input is unchanged"
    );
}

/// An unprivileged user to run as when this process is root (so a
/// read-only folder is read-only to the child), if switching works here.
fn unprivileged() -> Option<Option<u32>> {
    // SAFETY: geteuid has no preconditions.
    if unsafe { libc::geteuid() } != 0 {
        return Some(None);
    }
    let ok = Command::new("/bin/true")
        .uid(65534)
        .gid(65534)
        .status()
        .is_ok_and(|s| s.success());
    ok.then_some(Some(65534))
}

/// A read-only folder in `dir` and the options that run the CLI as an
/// unprivileged user (root writes anywhere); `None`, with a note, where
/// neither can be had.
fn read_only_as_unprivileged(dir: &Path) -> Option<(PathBuf, Opts)> {
    let Some(uid) = unprivileged() else {
        eprintln!("note: running as root without setuid: the read-only folder case is skipped");
        return None;
    };
    open_to(dir, uid);
    let Some(ro) = read_only_folder(dir, uid) else {
        eprintln!("note: a read-only folder is writable here (root): case skipped");
        return None;
    };
    Some((
        ro,
        Opts {
            uid,
            ..Opts::default()
        },
    ))
}

/// A folder the child cannot write to: 0o555 (0o500 when the child is this
/// user), checked by trying; `None` (the test skips) when writing works anyway.
fn read_only_folder(parent: &Path, as_uid: Option<u32>) -> Option<PathBuf> {
    let ro = parent.join("ro");
    std::fs::create_dir_all(&ro).unwrap();
    let mode = if as_uid.is_some() { 0o555 } else { 0o500 };
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(mode)).unwrap();
    if as_uid.is_none() && std::fs::write(ro.join("probe"), b"").is_ok() {
        let _ = std::fs::remove_file(ro.join("probe"));
        return None;
    }
    Some(ro)
}

/// `parent` made reachable and writable by the unprivileged child.
fn open_to(parent: &Path, as_uid: Option<u32>) {
    if as_uid.is_some() {
        std::fs::set_permissions(parent, std::fs::Permissions::from_mode(0o777)).unwrap();
    }
}

#[test]
fn a_save_that_cannot_be_written_leaves_no_output() {
    let dir = tempfile::tempdir().unwrap();
    // As root: a --save whose folder is a regular file cannot be written either.
    let not_a_folder = dir.path().join("plain");
    std::fs::write(&not_a_folder, b"").unwrap();
    let ok = dir.path().join("ok.ply");
    let save = not_a_folder.join("x.lodh");
    let run = cli(&[
        "simplify",
        "builtin:sphere",
        "--ratio",
        "0.5",
        "-o",
        s(&ok),
        "--save",
        s(&save),
    ]);
    assert!(
        run.code.is_some_and(|c| c != 0),
        "{:?}: {}",
        run.args,
        run.stderr
    );
    assert_one_line(&run);
    assert!(!ok.exists(), "ok.ply written though the save failed");

    let Some((ro, opts)) = read_only_as_unprivileged(dir.path()) else {
        return;
    };
    let save = ro.join("x.lodh");
    let run = cli_with(
        &[
            "simplify",
            "builtin:sphere",
            "--ratio",
            "0.5",
            "-o",
            s(&ok),
            "--save",
            s(&save),
        ],
        opts,
    );
    assert!(
        run.code.is_some_and(|c| c != 0),
        "{:?}: {}",
        run.args,
        run.stderr
    );
    assert_one_line(&run);
    assert!(!ok.exists(), "ok.ply written though the save failed");
    assert!(!save.exists());
}

/// `compare --save-diff D` never replaces D's images without `--force`.
/// Needs a (software) GPU adapter; skipped with a note where there is none.
#[test]
fn compare_save_diff_never_overwrites_without_force() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("diff");
    let args = [
        "compare",
        "builtin:sphere",
        "builtin:torus",
        "--views",
        "2",
        "--size",
        "16",
    ];
    let no_cap = Opts {
        address_space: None,
        ..Opts::default()
    };
    let mut first: Vec<&str> = args.to_vec();
    first.extend(["--save-diff", s(&d)]);
    let run = cli_with(&first, no_cap.clone());
    if run.code == Some(1) {
        eprintln!(
            "note: compare cannot render here ({}): skipped",
            run.stderr.trim()
        );
        return;
    }
    assert_ok(&run);
    let images = listing(&d);
    assert!(images.len() >= 2, "{images:?}");
    // A marker in place of one image shows whether a rerun replaced it.
    let view0 = d.join(&images[0]);
    std::fs::write(&view0, b"marker").unwrap();
    let run = cli_with(&first, no_cap.clone());
    assert_bad_input(&run, &[]);
    assert_mentions_any(&run, &["--force", "exists"]);
    assert_eq!(
        std::fs::read(&view0).unwrap(),
        b"marker",
        "replaced without --force"
    );
    let mut forced = first.clone();
    forced.push("--force");
    assert_ok(&cli_with(&forced, no_cap));
    assert!(
        std::fs::read(&view0).unwrap().starts_with(b"\x89PNG"),
        "--force rewrites it"
    );
}

// ---------------------------------------------------------------- limits

#[test]
fn chains_of_more_than_64_rows_are_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("out.glb");
    // 100,000 rows (3.7 MiB) may be refused for the recipe's size before
    // its rows are counted; 20,000 (0.8 MiB, under the recipe size cap)
    // are refused for their count.
    for (n, needles) in [(100_000, &[][..]), (20_000, &["20000", "at most 64"][..])] {
        let recipe = dir.path().join(format!("rows-{n}.json"));
        let rows = vec![json!({"method": "simplify", "tolerance": "1%"}); n];
        write_json(
            &recipe,
            &json!({"format": "lodstudio-recipe", "version": 1, "rows": rows}),
        );
        let run = cli_with(
            &[
                "export",
                "builtin:sphere",
                "--recipe",
                s(&recipe),
                "-o",
                s(&target),
            ],
            within(30),
        );
        assert_bad_input(&run, needles);
        assert!(
            run.time < Duration::from_secs(5),
            "{n} rows: {:?}",
            run.time
        );
        assert!(!target.exists());
    }

    let lods = vec!["1%"; 1000].join(",");
    let run = cli_with(
        &[
            "export",
            "builtin:sphere",
            "--method",
            "simplify",
            "--lods",
            &lods,
            "-o",
            s(&target),
        ],
        within(30),
    );
    assert_bad_input(&run, &["1000", "64"]);
    assert!(run.time < Duration::from_secs(5), "{:?}", run.time);
    assert!(!target.exists());
}

#[test]
fn sample_and_texel_options_are_checked_against_the_budget() {
    let run = cli_with(
        &[
            "measure",
            "builtin:sphere",
            "builtin:sphere",
            "--samples",
            "1000000000000",
        ],
        within(60),
    );
    assert_ne!(run.code, Some(134), "an abort: {}", run.stderr);
    assert_bad_input(&run, &["samples"]);
    assert_mentions_any(&run, &["budget", "--max-memory"]);

    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("splats.glb");
    let run = cli_with(
        &[
            "amg",
            "builtin:octahedron-points",
            "--texel",
            "1e-9",
            "-o",
            s(&target),
        ],
        within(300),
    );
    assert_bad_input(&run, &["texel"]);
    assert!(!target.exists());
}

/// 28 nodes, each listing the next twice as its children: 2^27 instances
/// of the last one's mesh from a file of about a kilobyte.
#[test]
fn a_node_graph_that_expands_to_2_pow_28_instances_is_refused_quickly() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = cube_gltf(&data_uri(&cube_bin()), Image::None);
    let nodes: Vec<Value> = (0..28)
        .map(|i| {
            if i < 27 {
                json!({"children": [i + 1, i + 1]})
            } else {
                json!({"mesh": 0})
            }
        })
        .collect();
    g["nodes"] = json!(nodes);
    let model = dir.path().join("dag.gltf");
    write_json(&model, &g);
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    let target = out.join("x.glb");
    for args in [
        vec!["info", s(&model)],
        vec!["simplify", s(&model), "--ratio", "0.5", "-o", s(&target)],
        vec![
            "export",
            s(&model),
            "--lods",
            "simplify:50%",
            "-o",
            s(&target),
        ],
    ] {
        let run = cli_with(&args, within(60));
        assert_bad_input(&run, &["instance"]);
        assert_mentions_any(&run, &["at most", "budget"]);
        assert!(
            run.time < Duration::from_secs(10),
            "{args:?}: {:?}",
            run.time
        );
        assert!(listing(&out).is_empty());
    }
}

/// A flat scene of `n` nodes instancing one mesh, each moved along x.
fn flat_scene(path: &Path, n: usize) {
    let mut g = cube_gltf(&data_uri(&cube_bin()), Image::None);
    let nodes: Vec<Value> = (0..n)
        .map(|i| json!({"mesh": 0, "translation": [2.0 * i as f64, 0.0, 0.0]}))
        .collect();
    g["nodes"] = json!(nodes);
    g["scenes"] = json!([{"nodes": (0..n).collect::<Vec<_>>()}]);
    write_json(path, &g);
}

#[test]
fn many_instances_load_in_linear_time() {
    let dir = tempfile::tempdir().unwrap();
    let (small, large) = (dir.path().join("4096.gltf"), dir.path().join("16384.gltf"));
    flat_scene(&small, 4096);
    flat_scene(&large, 16384);
    // CPU time, the least of three runs: the other tests and builds on the
    // machine change the wall time far more than the cost of the load.
    let time = |model: &Path, n: u64| {
        (0..3)
            .map(|_| {
                let run = cli(&["info", s(model), "--json"]);
                assert_ok(&run);
                assert_eq!(run.json()["triangles"], 12 * n);
                run.cpu
            })
            .min()
            .unwrap()
    };
    let (t_small, t_large) = (time(&small, 4096), time(&large, 16384));
    eprintln!("info of 4,096 instances: {t_small:?} CPU; of 16,384: {t_large:?}");
    let ratio = t_large.as_secs_f64() / t_small.as_secs_f64().max(1e-3);
    assert!(
        ratio < 8.0,
        "4× the instances took {ratio:.1}× the time ({t_small:?} → {t_large:?})"
    );

    // The size the issue names.
    let huge = dir.path().join("65536.gltf");
    flat_scene(&huge, 65536);
    let t_huge = time(&huge, 65536);
    eprintln!("info of 65,536 instances: {t_huge:?} CPU");
    let ratio = t_huge.as_secs_f64() / t_large.as_secs_f64().max(1e-3);
    assert!(
        ratio < 8.0,
        "4× the instances took {ratio:.1}× the time ({t_large:?} → {t_huge:?})"
    );
}

/// A PNG that declares `width`×`height` RGBA texels, padded to about `size`
/// bytes (an ancillary chunk): nothing decodes, the header is the bomb.
fn png_bomb(width: u32, height: u32, size: usize) -> Vec<u8> {
    let chunk = |kind: &[u8; 4], data: &[u8]| {
        let mut c = Vec::new();
        c.extend_from_slice(&(data.len() as u32).to_be_bytes());
        c.extend_from_slice(kind);
        c.extend_from_slice(data);
        let mut crc = flate2::Crc::new();
        crc.update(kind);
        crc.update(data);
        c.extend_from_slice(&crc.sum().to_be_bytes());
        c
    };
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&width.to_be_bytes());
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(chunk(b"IHDR", &ihdr));
    png.extend(chunk(b"lodS", &vec![0u8; size]));
    png.extend(chunk(
        b"IDAT",
        &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01],
    ));
    png.extend(chunk(b"IEND", &[]));
    png
}

#[test]
fn an_image_bomb_is_refused_from_its_header() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("big.png"),
        png_bomb(60_000, 60_000, 2 << 20),
    )
    .unwrap();
    let mut g = cube_gltf(&data_uri(&cube_bin()), Image::Uri("big.png"));
    // 60 materials naming the one image, one primitive each.
    let base = g["meshes"][0]["primitives"][0].clone();
    g["materials"] = json!(vec![
        json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}});
        60
    ]);
    g["meshes"][0]["primitives"] = json!(
        (0..60)
            .map(|i| {
                let mut p = base.clone();
                p["material"] = json!(i);
                p
            })
            .collect::<Vec<_>>()
    );
    let model = dir.path().join("bomb.gltf");
    write_json(&model, &g);
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    let target = out.join("x.glb");
    for args in [
        vec!["info", s(&model), "--max-memory", "1G"],
        vec![
            "export",
            s(&model),
            "--lods",
            "simplify:50%",
            "-o",
            s(&target),
            "--max-memory",
            "1G",
        ],
    ] {
        let run = cli_with(&args, within(60));
        assert_bad_input(&run, &["image 0"]);
        assert_mentions_any(&run, &["budget", "--max-memory"]);
        assert!(
            run.time < Duration::from_secs(10),
            "{args:?}: {:?}",
            run.time
        );
        assert!(
            run.max_rss_bytes < 512 * MIB,
            "{args:?}: {} MiB",
            run.max_rss_bytes / MIB
        );
        assert!(listing(&out).is_empty());
    }
}

/// A 2 MB gzip of a PLY header and 2 GiB of zeros, made by streaming (the
/// test never holds the inflated bytes), is refused under the default cap
/// (proportionate to the input as well as absolute) before it is inflated.
#[test]
fn a_gzip_bomb_is_refused_under_the_default_cap_quickly_and_small() {
    let dir = tempfile::tempdir().unwrap();
    let bomb = dir.path().join("bomb.ply.gz");
    let file = std::io::BufWriter::new(std::fs::File::create(&bomb).unwrap());
    let mut gz = flate2::write::GzEncoder::new(file, flate2::Compression::best());
    gz.write_all(
        b"ply\nformat binary_little_endian 1.0\nelement vertex 200000000\n\
          property float x\nproperty float y\nproperty float z\nend_header\n",
    )
    .unwrap();
    let zeros = vec![0u8; 4 << 20];
    for _ in 0..(2 * GIB / zeros.len() as u64) {
        gz.write_all(&zeros).unwrap();
    }
    gz.finish().unwrap().flush().unwrap();
    let size = std::fs::metadata(&bomb).unwrap().len();
    assert!(size < 4 * MIB, "{size} bytes");
    let run = cli_with(&["info", s(&bomb)], within(120));
    assert_bad_input(&run, &["--max-decompressed"]);
    assert!(run.time < Duration::from_secs(3), "{:?}", run.time);
    assert!(
        run.max_rss_bytes < 512 * MIB,
        "{} MiB resident",
        run.max_rss_bytes / MIB
    );
}

#[test]
fn negative_and_zero_arguments_are_refused_with_their_range() {
    let run = cli(&["hybrid", "builtin:sphere", "--kappa", "-1", "--tau", "1"]);
    assert_bad_input(&run, &["kappa"]);
    assert!(
        !run.stderr.contains("unexpected argument"),
        "{}",
        run.stderr
    );

    let dir = tempfile::tempdir().unwrap();
    let x = dir.path().join("x.obj");
    let run = cli(&[
        "simplify",
        "builtin:sphere",
        "--triangles",
        "0",
        "-o",
        s(&x),
    ]);
    assert_bad_input(&run, &["--triangles must be at least 1"]);
    let run = cli(&["simplify", "builtin:sphere", "--ratio", "0", "-o", s(&x)]);
    assert_bad_input(&run, &["--ratio"]);
    assert!(!x.exists());
}

/// The body of a saved hierarchy (offset, length), after its header.
fn body_of(bytes: &[u8]) -> (usize, usize) {
    assert_eq!(&bytes[..8], b"LODSTHRY");
    let mut at = 12;
    let n = u16::from_le_bytes(bytes[at..at + 2].try_into().unwrap()) as usize;
    at += 2 + n;
    let p = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    at += 4 + p;
    let b = u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap()) as usize;
    at += 8;
    assert_eq!(
        at + b + 4,
        bytes.len(),
        "header, body and checksum fill the file"
    );
    (at, b)
}

#[test]
fn a_saved_hierarchy_with_a_nan_position_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let h = dir.path().join("h.lodh");
    assert_ok(&cli_with(
        &["amg", "builtin:octahedron-points", "--save", s(&h)],
        within(300),
    ));
    let mut bytes = std::fs::read(&h).unwrap();
    let (body, _) = body_of(&bytes);
    // The multiscale's points come first: their count, then x y z of each.
    let count = u64::from_le_bytes(bytes[body..body + 8].try_into().unwrap());
    assert_eq!(count, 16_000, "the body starts with the points");
    bytes[body + 8..body + 12].copy_from_slice(&f32::NAN.to_le_bytes());
    let end = bytes.len() - 4;
    let mut crc = flate2::Crc::new();
    crc.update(&bytes[..end]);
    let sum = crc.sum().to_le_bytes();
    bytes[end..].copy_from_slice(&sum);
    std::fs::write(&h, &bytes).unwrap();
    let target = dir.path().join("cut.glb");
    let run = cli_with(
        &["cut", s(&h), "--error", "1%", "-o", s(&target)],
        within(120),
    );
    assert_bad_input(&run, &[]);
    assert!(!target.exists());
}

// ---------------------------------------------------------------- environment

/// A 64 KiB tmpfs, unmounted when dropped (before the folder holding it).
struct Tmpfs(PathBuf);

impl Drop for Tmpfs {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

#[test]
fn a_full_disk_is_an_environment_failure() {
    let dir = tempfile::tempdir().unwrap();
    let mnt = dir.path().join("full");
    std::fs::create_dir_all(&mnt).unwrap();
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=64k", "tmpfs", s(&mnt)])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|st| st.success());
    if !mounted {
        eprintln!("note: cannot mount a small tmpfs here: the full-disk case is skipped");
        return;
    }
    let _fs = Tmpfs(mnt.clone());
    // Fill it.
    let mut filler = std::fs::File::create(mnt.join("filler")).unwrap();
    let block = vec![0u8; 4096];
    while filler.write_all(&block).is_ok() {}
    let _ = filler.sync_all();
    drop(filler);
    let target = mnt.join("out.ply");
    let run = cli(&[
        "simplify",
        "builtin:torus",
        "--ratio",
        "0.5",
        "-o",
        s(&target),
    ]);
    assert_eq!(
        run.code,
        Some(1),
        "a full disk is no bad input: {}",
        run.stderr
    );
    assert_one_line(&run);
    assert_eq!(listing(&mnt), ["filler"], "no output, no temporary left");
}

#[test]
fn permission_denied_on_the_output_folder_is_an_environment_failure() {
    let dir = tempfile::tempdir().unwrap();
    let Some((ro, opts)) = read_only_as_unprivileged(dir.path()) else {
        return;
    };
    let target = ro.join("out.ply");
    let run = cli_with(
        &[
            "simplify",
            "builtin:torus",
            "--ratio",
            "0.5",
            "-o",
            s(&target),
        ],
        opts,
    );
    assert_eq!(
        run.code,
        Some(1),
        "permission denied is no bad input: {}",
        run.stderr
    );
    assert_one_line(&run);
    assert!(listing(&ro).is_empty());
}
