//! `export` of a glTF scene (issue 49): the scene carried, one chain per
//! mesh (`lodstudio_core::scene`), laid out as `--layout` says.

use std::path::{Path, PathBuf};

use super::*;
use lodstudio_core::io::scene;
use lodstudio_core::scene::SceneChains;

/// Builds `recipe`'s chains of the scene `file`, writes them to `output`
/// (and beside it, for `files`) and returns the JSON report.
pub fn export_scene(
    input: &InputArgs,
    recipe: &Recipe,
    file: &Path,
    output: &Path,
    force: bool,
    poses: usize,
) -> Result<serde_json::Value, CliError> {
    let mut options = input.load_options()?;
    options.repair.weld = recipe.weld();
    super::super::outputs::input(file)?;
    let bytes = io::read_file(file, &Progress::new())?;
    let scene = scene::read(&bytes, file.parent()).map_err(|e| LoadError::malformed(file, e))?;
    for d in &scene.report.dropped {
        eprintln!(
            "lodstudio: {}: not carried: {} ({})",
            file.display(),
            d.what,
            d.place
        );
    }
    if scene.meshes.is_empty() {
        return Err(CliError::BadInput(format!(
            "{}: the scene draws no triangle mesh",
            file.display()
        )));
    }
    let start = std::time::Instant::now();
    let chains =
        lodstudio_core::scene::build(&scene, recipe, &[], &options.repair, &Progress::new())
            .map_err(|e| match e {
                ChainError::Cancelled => CliError::Failure("cancelled".into()),
                e => CliError::BadInput(format!("{}: {e}", file.display())),
            })?;
    for (m, skipped) in scene.meshes.iter().zip(&chains.skipped) {
        for s in skipped {
            eprintln!(
                "lodstudio: {}: mesh {} \"{}\": rows[{}] ({}) left out of its chain: {}",
                file.display(),
                m.index,
                m.name,
                s.row,
                s.label,
                s.why
            );
        }
    }
    let paths = recipe.layout.outputs(output, chains.levels());
    for path in &paths[1..] {
        check_output(path, force)?;
        if io::extension(path) == "gltf" {
            check_output(&path.with_extension("bin"), force)?;
        }
    }
    let mut bytes_written = 0;
    for (path, glb) in paths
        .iter()
        .zip(chains.write(&scene, recipe.layout, recipe.points_as))
    {
        for (p, data) in io::gltf_writer::encode_file(path, &glb).map_err(CliError::BadInput)? {
            bytes_written += data.len();
            write_output(&p, &data)?;
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    let measures = chains.measure(&scene, poses);
    Ok(report(
        &scene,
        &chains,
        &measures,
        recipe,
        file,
        &paths,
        bytes_written,
        seconds,
    ))
}

/// The JSON report: `lods[]` per level over the scene (triangles in the
/// file and drawn, the largest world-space bound over instances), the
/// meshes' own chains, the asset's counts and what was not carried.
#[allow(clippy::too_many_arguments)]
fn report(
    scene: &scene::Scene,
    chains: &SceneChains,
    measures: &[Vec<lodstudio_core::scene::LodMeasures>],
    recipe: &Recipe,
    file: &Path,
    paths: &[PathBuf],
    bytes: usize,
    seconds: f64,
) -> serde_json::Value {
    let world_diagonal = scene_diagonal(scene);
    let lods: Vec<serde_json::Value> = (0..chains.levels())
        .map(|k| {
            let totals = chains.level_totals(scene, k);
            let bound = totals.bound;
            let coverage = chains
                .chains
                .iter()
                .map(|c| c.coverages[k.min(c.coverages.len() - 1)])
                .fold(0.0f32, f32::max);
            // The largest over the meshes, at this level.
            let at = |m: &Vec<lodstudio_core::scene::LodMeasures>| {
                m.get(k.min(m.len().saturating_sub(1))).cloned()
            };
            let pose: Vec<_> = measures
                .iter()
                .filter_map(at)
                .filter_map(|m| m.pose_error)
                .collect();
            let targets: Vec<_> = measures
                .iter()
                .filter_map(at)
                .flat_map(|m| m.target_errors)
                .collect();
            // What the rows asked, from the longest chain (a mesh a row
            // does not fit goes without it, `meshes[].skipped_rows`);
            // primitives summed over the meshes.
            let first = (chains.chains.iter())
                .max_by_key(|c| c.lods.len())
                .unwrap_or(&chains.chains[0]);
            let l0 = &first.lods[k.min(first.lods.len() - 1)];
            let tolerances: Vec<String> = l0
                .rows
                .iter()
                .map(|&r| first.recipe.rows[r].tolerance.to_string())
                .collect();
            let sum = |f: &dyn Fn(&lodstudio_core::lod::DrawSet) -> usize| -> usize {
                chains
                    .chains
                    .iter()
                    .map(|c| f(&c.lods[k.min(c.lods.len() - 1)].set))
                    .sum()
            };
            let mut j = serde_json::json!({
                "tolerance": tolerances.join(","),
                "rows": l0.labels,
                "method": l0.method.tag(),
                "points": sum(&|s| s.points.len()),
                "splats": sum(&|s| s.splats.len()),
                "layers": sum(&|s| s.layers.len()),
                "vertices": sum(&|s| s.mesh.positions.len()),
                "triangles": totals.written,
                "drawn_triangles": totals.drawn_triangles,
                "drawn_primitives": totals.drawn_primitives,
                "error_bound": bound,
                "error_bound_relative": bound / world_diagonal.max(f32::MIN_POSITIVE),
                "error_bound_kind": "world space, largest over instances (σ_max · mesh bound)",
                "screen_coverage": coverage,
            });
            if !pose.is_empty() {
                j["pose_error"] = serde_json::json!({
                    "max": pose.iter().map(|p| p.max).fold(0.0f32, f32::max),
                    "mean": pose.iter().map(|p| p.mean).sum::<f32>() / pose.len() as f32,
                    "poses": pose.iter().map(|p| p.poses).max().unwrap_or(0),
                });
            }
            if !targets.is_empty() {
                j["target_errors"] = serde_json::json!(targets);
            }
            // Certified per target, per morphing mesh: in mesh space and in
            // world space over the mesh's instances (σ_max · bound).
            let target_bounds: Vec<serde_json::Value> = (scene.meshes.iter())
                .zip(&chains.target_bounds)
                .filter_map(|(m, per_lod)| {
                    let bounds = per_lod.get(k.min(per_lod.len().saturating_sub(1)))?;
                    let scale = m.instances.iter().map(|i| i.scale()).fold(0.0f32, f32::max);
                    Some(bounds.iter().map(move |b| {
                        serde_json::json!({
                            "mesh": m.index,
                            "target": b.target,
                            "name": b.name,
                            "bound": b.bound,
                            "world_bound": scale * b.bound,
                        })
                    }))
                })
                .flatten()
                .collect();
            if !target_bounds.is_empty() {
                j["target_bounds"] = serde_json::json!(target_bounds);
            }
            // UV errors over the textured meshes, weighted by LOD area.
            let uv: Vec<_> = measures
                .iter()
                .filter_map(at)
                .filter_map(|m| m.uv_error.map(|e| (e, m.area)))
                .collect();
            let area: f64 = uv.iter().map(|(_, a)| a).sum();
            if !uv.is_empty() && area > 0.0 {
                j["uv_error"] = serde_json::json!({
                    "mean": uv.iter().map(|(e, a)| e.mean * a).sum::<f64>() / area,
                    "max": uv.iter().map(|(e, _)| e.max).fold(0.0f32, f32::max),
                    "mean_texels": uv.iter().map(|(e, a)| e.mean_texels * a).sum::<f64>() / area,
                    "max_texels": uv.iter().map(|(e, _)| e.max_texels).fold(0.0f32, f32::max),
                    "area_over_threshold": uv.iter().map(|(e, a)| e.area_over_threshold * a).sum::<f64>() / area,
                });
            }
            j
        })
        .collect();
    let a = &scene.report;
    serde_json::json!({
        "file": file.display().to_string(),
        "layout": recipe.layout.name(),
        "compress": recipe.compress.name(),
        "method": match recipe.rows.iter().all(|r| r.method == recipe.rows[0].method) {
            true => recipe.rows[0].method.tag(),
            false => "mixed",
        },
        "lods": lods,
        "meshes": chains.meshes_json(scene, measures),
        "nodes": a.nodes,
        "instances": a.instances,
        "skins": a.skins,
        "animations": a.animations,
        "morph_targets": a.morph_targets,
        "extensions": a.extensions,
        "dropped": a.dropped,
        "bytes": bytes,
        "input_triangles": scene.meshes.iter().map(|m| m.mesh.triangles.len()).sum::<usize>(),
        "bbox_diagonal": world_diagonal,
        "pixels": recipe.pixels,
        "switch_fov_y_degrees": lodstudio_core::scene::SWITCH_FOV_Y_DEGREES,
        "screen_coverage_means": lodstudio_core::io::scene_writer::COVERAGE_NOTE,
        "viewport_height": recipe.viewport_height,
        "seconds": seconds,
        "output": paths[0].display().to_string(),
        "outputs": paths.iter().map(|p| p.display().to_string()).collect::<Vec<_>>(),
    })
}

/// The diagonal of the scene's drawn bounding box in world space.
fn scene_diagonal(scene: &scene::Scene) -> f32 {
    let mut b = lodstudio_core::Aabb::EMPTY;
    for m in &scene.meshes {
        let local = m.mesh.bounds();
        for i in &m.instances {
            b = b.union(local.transformed(i.world));
        }
    }
    b.diagonal()
}

/// The human summary of a scene export.
pub fn print_summary(j: &serde_json::Value) {
    let meshes = j["meshes"].as_array().map_or(&[][..], |m| &m[..]);
    println!(
        "{} -> {}: {} meshes drawn by {} nodes, layout {}, {} bytes, {:.2} s",
        j["file"].as_str().unwrap_or_default(),
        j["output"].as_str().unwrap_or_default(),
        meshes.len(),
        j["instances"],
        j["layout"].as_str().unwrap_or_default(),
        j["bytes"],
        j["seconds"].as_f64().unwrap_or_default(),
    );
    for (i, l) in j["lods"].as_array().into_iter().flatten().enumerate() {
        println!(
            "  lod{i}: {:>8} triangles in the file, {:>8} drawn, world bound {:.6} ({:.4}% of the scene's diagonal)",
            l["triangles"],
            l["drawn_triangles"],
            l["error_bound"].as_f64().unwrap_or_default(),
            100.0 * l["error_bound_relative"].as_f64().unwrap_or_default(),
        );
    }
}
