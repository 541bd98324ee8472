//! Helpers for the workspace-level end-to-end tests in `tests/tests/`: where the
//! shared models and the malformed corpus live, how to load a mesh and build
//! each method's hierarchy, and how to run the CLI.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

use lodstudio_core::lod::{Hierarchy, Method, Params};
use lodstudio_core::{Progress, TriMesh};

/// `../shared/models` beside the checkout (fixed by the project layout), or
/// `$LODSTUDIO_SHARED_MODELS` for checkouts elsewhere (git worktrees).
pub fn shared_models() -> PathBuf {
    match std::env::var_os("LODSTUDIO_SHARED_MODELS") {
        Some(dir) => PathBuf::from(dir),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/models"),
    }
}

pub fn shared_model(name: &str) -> PathBuf {
    shared_models().join(name)
}

/// The committed corpus of malformed files.
pub fn malformed_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("malformed")
}

/// Path of the `lodstudio` binary of this build, building it once if needed
/// (a test package cannot depend on another package's binary directly).
pub fn lodstudio_bin() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        let exe = std::env::current_exe().expect("test executable path");
        // target/<profile>/deps/<test> -> target/<profile>/lodstudio
        let profile_dir = exe.parent().and_then(Path::parent).expect("target layout");
        let bin = profile_dir.join(format!("lodstudio{}", std::env::consts::EXE_SUFFIX));
        let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
        let release = profile_dir.ends_with("release");
        let mut cmd = Command::new(cargo);
        cmd.args(["build", "-p", "lodstudio", "--bin", "lodstudio", "--quiet"]);
        if release {
            cmd.arg("--release");
        }
        let status = cmd.status().expect("run cargo build");
        assert!(status.success(), "building the lodstudio binary failed");
        bin
    })
}

/// Runs `lodstudio ARGS` without a display.
pub fn lodstudio(args: &[&str]) -> Output {
    Command::new(lodstudio_bin())
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .expect("run lodstudio")
}

/// Runs `lodstudio ARGS --json`, asserts success and parses its single JSON object.
pub fn lodstudio_json(args: &[&str]) -> serde_json::Value {
    let mut all: Vec<&str> = args.to_vec();
    all.push("--json");
    let out = lodstudio(&all);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "lodstudio {all:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        stdout.trim().lines().count(),
        1,
        "one JSON object on one line"
    );
    serde_json::from_str(stdout.trim()).expect("valid JSON")
}

/// The triangle mesh in the file at `path`, loaded (and repaired) as
/// `lodstudio` loads it.
pub fn load_mesh(path: &Path) -> TriMesh {
    let loaded = lodstudio_core::io::load(path, &Default::default(), &Progress::new())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    match loaded.model {
        lodstudio_core::Model::Mesh(m) => m,
        other => panic!("{}: a mesh, not {}", path.display(), other.kind()),
    }
}

/// The mesh of the shared model `name`.
pub fn shared_mesh(name: &str) -> TriMesh {
    load_mesh(&shared_model(name))
}

/// `method` built on `mesh` through `lod::build` with its default
/// parameters (a voxel build keeps its whole pyramid, as recipe rows do, so
/// its cuts have levels to choose between), and the parameters it is saved
/// with.
pub fn build_hierarchy(method: Method, mesh: &TriMesh) -> (Box<dyn Hierarchy>, serde_json::Value) {
    let params = match Params::default_for(method) {
        Params::Voxel(v) => {
            Params::Voxel(lodstudio_core::voxel::VoxelParams { pyramid: true, ..v })
        }
        other => other,
    };
    let model = lodstudio_core::Model::Mesh(mesh.clone());
    let built = lodstudio_core::lod::build(&params, &model, &Progress::new())
        .unwrap_or_else(|e| panic!("{method:?}: {e}"));
    (built, serde_json::json!({}))
}

/// The meshes a client shows at LOD `l` of an exported chain: walking the
/// scene, each node's mesh at level 0, or for a node with `MSFT_lod` the
/// mesh of its `l`-th LOD node (its coarsest where the chain is shorter);
/// each mesh once. Holds for a flattened chain (node 0) and for a scene.
pub fn lod_meshes(doc: &serde_json::Value, l: usize) -> Vec<usize> {
    let index = |v: &serde_json::Value| v.as_u64().map(|i| i as usize);
    let scene = index(&doc["scene"]).unwrap_or(0);
    let mut stack: Vec<usize> = doc["scenes"][scene]["nodes"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(index)
        .collect();
    stack.reverse();
    let mut out = Vec::new();
    while let Some(n) = stack.pop() {
        let node = &doc["nodes"][n];
        let ids: Vec<usize> = node["extensions"]["MSFT_lod"]["ids"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(index)
            .collect();
        let shown = match (l, ids.last()) {
            (0, _) | (_, None) => n,
            (l, Some(last)) => *ids.get(l - 1).unwrap_or(last),
        };
        if let Some(m) = index(&doc["nodes"][shown]["mesh"])
            && !out.contains(&m)
        {
            out.push(m);
        }
        let children: Vec<usize> = node["children"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(index)
            .collect();
        stack.extend(children.into_iter().rev());
    }
    out
}
