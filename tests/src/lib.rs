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

/// The JSON chunk of a GLB.
pub fn glb_json(glb: &[u8]) -> serde_json::Value {
    assert_eq!(&glb[0..4], b"glTF");
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    assert_eq!(&glb[16..20], b"JSON");
    serde_json::from_slice(&glb[20..20 + len]).expect("glTF JSON chunk")
}

/// The meshes a client shows at LOD `l` of an exported chain: walking the
/// scene, each node's mesh at level 0, or for a node with `MSFT_lod` the
/// mesh of its `l`-th LOD node (its coarsest where the chain is shorter),
/// which replaces the node whole: the walk goes on into that node's
/// children, not the head's (Babylon.js swaps the nodes); each mesh once.
/// Holds for a flattened chain (node 0) and for a scene.
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
        let children: Vec<usize> = doc["nodes"][shown]["children"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(index)
            .collect();
        stack.extend(children.into_iter().rev());
    }
    out
}

/// A skinned, animated cylinder (the issue's "two-bone cylinder with one
/// animation", `assets/two-bone-cylinder.glb`): radius 0.25 and height 2
/// along +y, 25 rings of 24 vertices; joint `root` at the origin and joint
/// `bend` at y = 1 under it, each vertex weighted between them by a
/// smoothstep over 0.6 ≤ y ≤ 1.4; animation `bend` turns the upper joint
/// about z to 60° and back over 2 s. Node `cylinder` draws it with the skin.
pub fn two_bone_cylinder() -> Vec<u8> {
    use glam::{Mat4, Quat, Vec3};
    use serde_json::json;
    const RINGS: u32 = 25;
    const SEGMENTS: u32 = 24;
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut influences: Vec<([u16; 4], [f32; 4])> = Vec::new();
    for i in 0..RINGS {
        let y = 2.0 * i as f32 / (RINGS - 1) as f32;
        let s = ((y - 0.6) / 0.8).clamp(0.0, 1.0);
        let w = s * s * (3.0 - 2.0 * s);
        for j in 0..SEGMENTS {
            let a = std::f32::consts::TAU * j as f32 / SEGMENTS as f32;
            positions.push(Vec3::new(0.25 * a.cos(), y, 0.25 * a.sin()));
            normals.push(Vec3::new(a.cos(), 0.0, a.sin()));
            // A joint only where it weighs (glTF: no joint at weight 0).
            influences.push(match w {
                0.0 => ([0, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]),
                1.0 => ([1, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]),
                _ => ([0, 1, 0, 0], [1.0 - w, w, 0.0, 0.0]),
            });
        }
    }
    let mut indices: Vec<u16> = Vec::new();
    for i in 0..RINGS - 1 {
        for j in 0..SEGMENTS {
            let v = |i: u32, j: u32| (i * SEGMENTS + j % SEGMENTS) as u16;
            let (a, b, c, d) = (v(i, j), v(i, j + 1), v(i + 1, j), v(i + 1, j + 1));
            indices.extend([a, c, b, b, c, d]);
        }
    }
    let bend = Quat::from_rotation_z(std::f32::consts::FRAC_PI_3);
    let times = [0.0f32, 1.0, 2.0];
    let rotations = [Quat::IDENTITY, bend, Quat::IDENTITY];
    let inverse_bind = [
        Mat4::IDENTITY,
        Mat4::from_translation(Vec3::new(0.0, -1.0, 0.0)),
    ];
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut push = |bytes: Vec<u8>, target: Option<u32>| {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let mut view = json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            view["target"] = json!(t);
        }
        bin.extend(bytes);
        views.push(view);
        views.len() - 1
    };
    let floats =
        |v: &mut dyn Iterator<Item = f32>| -> Vec<u8> { v.flat_map(f32::to_le_bytes).collect() };
    let p = push(
        floats(&mut positions.iter().flat_map(|p| p.to_array())),
        Some(34962),
    );
    let n = push(
        floats(&mut normals.iter().flat_map(|p| p.to_array())),
        Some(34962),
    );
    let joints: Vec<u8> = influences
        .iter()
        .flat_map(|(j, _)| *j)
        .flat_map(u16::to_le_bytes)
        .collect();
    let jv = push(joints, Some(34962));
    let wv = push(
        floats(&mut influences.iter().flat_map(|(_, w)| *w)),
        Some(34962),
    );
    let iv = push(
        indices.iter().flat_map(|i| i.to_le_bytes()).collect(),
        Some(34963),
    );
    let ibm = push(
        floats(&mut inverse_bind.iter().flat_map(|m| m.to_cols_array())),
        None,
    );
    let tv = push(floats(&mut times.iter().copied()), None);
    let rv = push(
        floats(&mut rotations.iter().flat_map(|q| q.to_array())),
        None,
    );
    let count = positions.len();
    let (lo, hi) = positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    let doc = json!({
        "asset": {"version": "2.0", "generator": "lodstudio-tests two_bone_cylinder"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "cylinder", "mesh": 0, "skin": 0},
            {"name": "root", "children": [2]},
            {"name": "bend", "translation": [0.0, 1.0, 0.0]}
        ],
        "meshes": [{"name": "cylinder", "primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1, "JOINTS_0": 2, "WEIGHTS_0": 3},
            "indices": 4, "mode": 4}]}],
        "skins": [{"joints": [1, 2], "inverseBindMatrices": 5, "skeleton": 1}],
        "animations": [{"name": "bend", "channels": [{"sampler": 0, "target": {"node": 2, "path": "rotation"}}],
            "samplers": [{"input": 6, "output": 7, "interpolation": "LINEAR"}]}],
        "accessors": [
            {"bufferView": p, "componentType": 5126, "count": count, "type": "VEC3",
             "min": lo.to_array(), "max": hi.to_array()},
            {"bufferView": n, "componentType": 5126, "count": count, "type": "VEC3"},
            {"bufferView": jv, "componentType": 5123, "count": count, "type": "VEC4"},
            {"bufferView": wv, "componentType": 5126, "count": count, "type": "VEC4"},
            {"bufferView": iv, "componentType": 5123, "count": indices.len(), "type": "SCALAR"},
            {"bufferView": ibm, "componentType": 5126, "count": 2, "type": "MAT4"},
            {"bufferView": tv, "componentType": 5126, "count": 3, "type": "SCALAR", "min": [0.0], "max": [2.0]},
            {"bufferView": rv, "componentType": 5126, "count": 3, "type": "VEC4"}
        ],
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}]
    });
    lodstudio_core::io::gltf_writer::glb(&doc, bin)
}
