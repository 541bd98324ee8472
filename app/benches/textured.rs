//! Issue 50's quality benchmark: textured LODs at 50 %, 25 %, 10 % and 5 % of
//! the triangles, rendered through the studio's renderer (`lodstudio
//! compare`, 8 views of 256²) against the original, for lodstudio (its
//! default: the 1-texel UV tolerance, baked where seams or the measure of
//! `bake::choice` say so; `--bake` at its default size; `--bake` at the
//! original's largest texture side) and for
//! meshoptimizer's `simplifyWithAttributes` (normals and UVs weighted as in
//! its demo, default and `Permissive`) on the same asset in the same run.
//!
//! Run with `cargo bench -p lodstudio --bench textured` (the milk truck) or
//! name textured models: `cargo bench -p lodstudio --bench textured -- A.glb`.
//! Prints a Markdown table.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::Vec3;
use lodstudio_core::TriMesh;
use lodstudio_core::io::gltf_writer::write_glb;
use meshopt::{SimplifyOptions, VertexDataAdapter, simplify_with_attributes_and_locks};

const RATIOS: [f32; 4] = [0.5, 0.25, 0.1, 0.05];

fn lodstudio(args: &[&str]) -> serde_json::Value {
    let out = Command::new(env!("CARGO_BIN_EXE_lodstudio"))
        .args(args)
        .arg("--json")
        .output()
        .expect("run lodstudio");
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON")
}

/// PSNR of `lod` against `model` over 8 views.
fn psnr(model: &Path, lod: &Path) -> f64 {
    lodstudio(&[
        "compare",
        &model.display().to_string(),
        &lod.display().to_string(),
    ])["psnr"]
        .as_f64()
        .unwrap_or(f64::NAN)
}

/// meshoptimizer on the model as a client stores it (one vertex per
/// wedge): positions, with normals (weight 0.5) and UVs (weight 1) as
/// attributes; each triangle keeps the part of its first corner.
fn meshopt_lod(records: &TriMesh, triangles: usize, options: SimplifyOptions) -> TriMesh {
    let positions: Vec<[f32; 3]> = records.positions.iter().map(|p| p.to_array()).collect();
    let bytes: Vec<u8> = positions
        .iter()
        .flatten()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    let adapter = VertexDataAdapter::new(&bytes, 12, 0).expect("positions");
    let n = records.positions.len();
    let attributes: Vec<f32> = (0..n)
        .flat_map(|v| {
            let normal = records.normals.as_ref().map_or(Vec3::ZERO, |x| x[v]);
            let uv = records.uvs.as_ref().map_or(glam::Vec2::ZERO, |x| x[v]);
            [normal.x, normal.y, normal.z, uv.x, uv.y]
        })
        .collect();
    let weights = [0.5, 0.5, 0.5, 1.0, 1.0];
    let mut part_of = vec![0u32; n];
    for (t, tri) in records.triangles.iter().enumerate() {
        for v in tri {
            part_of[*v as usize] = records.part(t);
        }
    }
    let indices: Vec<u32> = records.triangles.iter().flatten().copied().collect();
    let locks = vec![false; n];
    let kept = simplify_with_attributes_and_locks(
        &indices,
        &adapter,
        &attributes,
        &weights,
        5 * 4,
        &locks,
        3 * triangles,
        f32::MAX,
        options,
        None,
    );
    let mut lod = records.clone();
    lod.triangles = kept.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    lod.parts = Some(
        lod.triangles
            .iter()
            .map(|t| part_of[t[0] as usize])
            .collect(),
    );
    lod
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let models: Vec<PathBuf> = match args.is_empty() {
        true => vec![
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../shared/models/CesiumMilkTruck.glb"),
        ],
        false => args.iter().map(PathBuf::from).collect(),
    };
    let dir = tempfile::tempdir().expect("temp dir");
    println!(
        "| model | % | asked | ours (default) | ours --bake | ours --bake, original's side | meshopt attributes | meshopt permissive |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for model in models {
        let loaded = lodstudio_core::io::load(
            &model,
            &Default::default(),
            &lodstudio_core::Progress::new(),
        )
        .expect("load");
        let lodstudio_core::Model::Mesh(mesh) = loaded.model else {
            panic!("{} is no mesh", model.display());
        };
        let records = mesh.unwelded();
        // The original's largest texture side: what meshoptimizer's LODs,
        // which keep its atlas, draw with.
        let own_size = mesh
            .materials
            .iter()
            .flat_map(|m| &m.table)
            .filter_map(|m| m.base_color_texture.as_ref()?.size())
            .map(|(w, h)| w.max(h))
            .max()
            .unwrap_or(1024)
            .to_string();
        let name = model
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        for ratio in RATIOS {
            let asked = ((mesh.triangles.len() as f32 * ratio).round() as usize).max(1);
            let file = |tag: &str| dir.path().join(format!("{tag}-{asked}.glb"));
            let cell = |path: &Path, triangles: usize| {
                format!("{triangles} tris, {:.2} dB", psnr(&model, path))
            };
            let mut cells = Vec::new();
            let own = ["--bake", "--texture-size", own_size.as_str()];
            for (tag, extra) in [
                ("ours", &[][..]),
                ("baked", &["--bake"][..]),
                ("own", &own[..]),
            ] {
                let out = file(tag);
                let mut a = vec![
                    "simplify".to_string(),
                    model.display().to_string(),
                    "--triangles".into(),
                    asked.to_string(),
                    "-o".into(),
                    out.display().to_string(),
                    "--force".into(),
                ];
                a.extend(extra.iter().map(|s| s.to_string()));
                let refs: Vec<&str> = a.iter().map(String::as_str).collect();
                let r = lodstudio(&refs);
                cells.push(cell(
                    &out,
                    r["output_triangles"].as_u64().unwrap_or(0) as usize,
                ));
            }
            for (tag, options) in [
                ("meshopt", SimplifyOptions::None),
                ("permissive", SimplifyOptions::Permissive),
            ] {
                let lod = meshopt_lod(&records, asked, options);
                let out = file(tag);
                std::fs::write(&out, write_glb(&lod)).expect("write");
                cells.push(cell(&out, lod.triangles.len()));
            }
            println!(
                "| {name} | {} | {asked} | {} |",
                ratio * 100.0,
                cells.join(" | ")
            );
        }
    }
}
