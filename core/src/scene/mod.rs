//! A scene's LOD chains (issue 49, DESIGN "Assets, not meshes"): each mesh
//! the scene draws gets the recipe's chain, built once in the mesh's own
//! space however many nodes draw it; the LODs go back into the scene in a
//! [`Layout`], carrying skins and morph targets through each collapse
//! ([`carry`]).
//!
//! Bounds in world space: a node draws its mesh through its world matrix
//! M, which stretches no length by more than σ_max(M), its largest
//! singular value ([`crate::io::scene::largest_singular_value`]); a LOD
//! within ε of the mesh in mesh space is within σ_max(M)·ε of the node's
//! drawing. The switch coverages need no scaling: the node's bounding
//! sphere grows by the same σ_max (`scene_writer::COVERAGE_NOTE`).

pub mod bones;
pub mod carry;
pub mod drawing;
pub mod pose;
pub mod targets;
pub mod transfer;

use serde_json::{Value, json};

use crate::geom::repair::{RepairOptions, repair_mesh};
use crate::io::gltf_writer::PointsAs;
use crate::io::scene::Scene;
pub use crate::io::scene_writer::Layout;
use crate::io::scene_writer::{self, MeshLods};
use crate::progress::Progress;
use crate::recipe::{Chain, ChainError, Flag, Recipe, build_chain};
use crate::{Model, TriMesh};

/// The vertical field of view the reported switch distances assume.
pub const SWITCH_FOV_Y_DEGREES: f32 = 60.0;

/// The chains of a scene's meshes, in the order of [`Scene::meshes`].
pub struct SceneChains {
    pub chains: Vec<Chain>,
    /// The glTF material of each part of each chain's meshes (skinned
    /// meshes are split by bone, [`bones`]).
    pub materials: Vec<Vec<Option<usize>>>,
    /// Per chain, per LOD: each morph target's certified bound ([`targets`];
    /// the LOD's own bound is already the largest over them).
    pub target_bounds: Vec<Vec<Vec<targets::TargetBound>>>,
    /// Per chain: the recipe's rows its mesh does not fit, left out of its
    /// chain (its levels then end sooner), with why.
    pub skipped: Vec<Vec<Skipped>>,
}

/// A recipe row one mesh of a scene does not fit (an AMG row on a bolt of
/// 48 vertices, a tolerance no cut of it meets): the scene's other meshes
/// keep it, this mesh's chain goes on without it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Skipped {
    /// Its index in the recipe, and its label (`amg:15%`).
    pub row: usize,
    pub label: String,
    pub why: String,
}

/// What is measured of one LOD of a skinned or morphing mesh.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct LodMeasures {
    /// Skinned meshes: original and LOD skinned at sampled poses.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pose_error: Option<pose::PoseError>,
    /// Morphing meshes, per target: the sampled two-sided distance between
    /// the original's target shape and the LOD's (base + deltas at weight 1).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub target_errors: Vec<TargetError>,
    /// Textured meshes: how far the LOD's UVs moved (`distance::uv`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uv_error: Option<crate::distance::UvError>,
    /// Meshes with a skin, morph targets or tangents: how the LOD's vertices
    /// got them, `carried` through each collapse of its build or
    /// `transferred` from their closest points (a method that made a new
    /// surface, [`transfer`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vertex_data: Option<&'static str>,
    /// The LOD's surface area (what a scene's UV errors are weighted by).
    #[serde(skip)]
    pub area: f64,
}

/// One morph target's measured distance.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TargetError {
    pub target: usize,
    pub name: Option<String>,
    pub measured: f32,
}

/// Builds `recipe`'s chain for each mesh of `scene`, each repaired as
/// loading repairs a model (`repair`); a mesh whose entry in `excluded` is
/// true keeps only its source (LOD0 at every level).
///
/// # Errors
/// A mesh the recipe does not fit (named), or cancellation.
pub fn build(
    scene: &Scene,
    recipe: &Recipe,
    excluded: &[bool],
    repair: &RepairOptions,
    progress: &Progress,
) -> Result<SceneChains, ChainError> {
    let source_only = Recipe {
        rows: vec![crate::recipe::Row::new(
            crate::lod::Method::EdgeCollapse,
            crate::recipe::RowTolerance::Source,
        )],
        ..recipe.clone()
    };
    // Meshes are independent: built on as many threads as there are cores,
    // each chain as alone (the output does not depend on the thread count).
    // Plain threads, not rayon's: a chain build blocks on threads of its
    // own that use rayon, which starved the pool from inside its workers.
    type Built = (
        Chain,
        Vec<Option<usize>>,
        Vec<Vec<targets::TargetBound>>,
        Vec<Skipped>,
    );
    let one = |i: usize, m: &crate::io::scene::SceneMesh| -> Result<Built, ChainError> {
        let mut recipe = match excluded.get(i) {
            Some(true) => source_only.clone(),
            _ => recipe.clone(),
        };
        let (mut mesh, parts) = match &m.skin {
            Some(skin) => bones::split_by_bone(&m.mesh, skin, &m.materials),
            None => (m.mesh.clone(), m.materials.clone()),
        };
        mesh.payload = carry::Columns::of(m).payload(m);
        let (mesh, _) = repair_mesh(mesh, repair);
        if mesh.triangles.is_empty() {
            return Err(ChainError::BadInput(format!(
                "mesh {} \"{}\": no valid triangles",
                m.index, m.name
            )));
        }
        // A row this mesh does not fit is left out of its chain and said;
        // the recipe's original index of each row still in it:
        let mut rows: Vec<usize> = (0..recipe.rows.len()).collect();
        let mut skipped = Vec::new();
        let model = Model::Mesh(mesh);
        let mut chain = loop {
            match build_chain(&model, &recipe, progress) {
                Ok(chain) => break chain,
                Err(ChainError::Row { row, rest }) if row < rows.len() => {
                    skipped.push(Skipped {
                        row: rows[row],
                        label: recipe.rows[row].label(),
                        why: rest.trim_start_matches([':', ' ']).to_string(),
                    });
                    rows.remove(row);
                    recipe.rows.remove(row);
                    if recipe.rows.is_empty() {
                        recipe.rows = source_only.rows.clone();
                    }
                }
                Err(ChainError::BadInput(why)) => {
                    return Err(ChainError::BadInput(format!(
                        "mesh {} \"{}\": {why}",
                        m.index, m.name
                    )));
                }
                Err(e) => return Err(e),
            }
        };
        let bounds = targets::certify(m, &mut chain, progress)?;
        Ok((chain, parts, bounds, skipped))
    };
    let threads = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .min(scene.meshes.len().max(1));
    let next = std::sync::atomic::AtomicUsize::new(0);
    // After a failure no new mesh starts (the first failing mesh by index
    // is the error reported, whatever the threads).
    let failed = std::sync::atomic::AtomicBool::new(false);
    let slots: Vec<std::sync::Mutex<Option<Result<_, ChainError>>>> = scene
        .meshes
        .iter()
        .map(|_| std::sync::Mutex::new(None))
        .collect();
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                while !failed.load(std::sync::atomic::Ordering::Relaxed) {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(m) = scene.meshes.get(i) else { break };
                    let result = one(i, m);
                    if result.is_err() {
                        failed.store(true, std::sync::atomic::Ordering::Relaxed);
                    }
                    if let Ok(mut slot) = slots[i].lock() {
                        *slot = Some(result);
                    }
                }
            });
        }
    });
    let built: Vec<Built> = slots
        .into_iter()
        .map(|slot| {
            slot.into_inner()
                .ok()
                .flatten()
                .unwrap_or(Err(ChainError::Cancelled))
        })
        .collect::<Result<_, _>>()?;
    let mut out = SceneChains {
        chains: Vec::with_capacity(built.len()),
        materials: Vec::with_capacity(built.len()),
        target_bounds: Vec::with_capacity(built.len()),
        skipped: Vec::with_capacity(built.len()),
    };
    for (chain, materials, bounds, skipped) in built {
        out.chains.push(chain);
        out.materials.push(materials);
        out.target_bounds.push(bounds);
        out.skipped.push(skipped);
    }
    Ok(out)
}

impl SceneChains {
    /// The scene with its LODs in `layout`: one GLB, or one per level,
    /// stored as the recipe says (`Recipe::compress`).
    pub fn write(&self, scene: &Scene, layout: Layout, points_as: PointsAs) -> Vec<Vec<u8>> {
        let transfers: Vec<transfer::Transfer> =
            scene.meshes.iter().map(transfer::Transfer::new).collect();
        let extras: Vec<_> = transfers
            .iter()
            .map(|t| move |lod: &TriMesh| t.extras(lod))
            .collect();
        let lods: Vec<MeshLods> = scene
            .meshes
            .iter()
            .zip(&self.chains)
            .zip(&extras)
            .zip(&self.materials)
            .map(|(((mesh, chain), extras), materials)| MeshLods {
                mesh,
                materials,
                sets: chain.lods.iter().map(|l| &l.set).collect(),
                coverages: chain.coverages.clone(),
                extras,
            })
            .collect();
        let compress = self.chains.first().map(|c| c.recipe.compress);
        scene_writer::write(scene, &lods, layout, points_as)
            .into_iter()
            .map(|glb| compress.unwrap_or_default().apply(glb))
            .collect()
    }

    /// Measures every LOD of every mesh: pose errors of skinned meshes at
    /// `poses` poses per animation, each morph target shape's distance, and
    /// how far textured meshes' UVs moved.
    pub fn measure(&self, scene: &Scene, poses: usize) -> Vec<Vec<LodMeasures>> {
        let sampled = match scene.meshes.iter().any(|m| m.skin.is_some()) {
            true => pose::sample_poses(&scene.rig, poses),
            false => Vec::new(),
        };
        let opts = crate::distance::SamplingOptions {
            samples: 20_000,
            ..Default::default()
        };
        scene
            .meshes
            .iter()
            .zip(&self.chains)
            .map(|(m, chain)| {
                let transfer = transfer::Transfer::new(m);
                let skin_index = m.instances.iter().find_map(|i| i.skin);
                chain
                    .lods
                    .iter()
                    .map(|l| {
                        let lod = &l.set.mesh;
                        let extras = transfer.extras(lod);
                        let pose_error = match (&m.skin, &extras.skin, skin_index) {
                            (Some(from), Some(to), Some(s)) => Some(pose::pose_error(
                                (&m.mesh, from),
                                (lod, to),
                                &scene.rig,
                                s,
                                &sampled,
                            )),
                            _ => None,
                        };
                        let target_errors = (0..m.targets.len())
                            .map(|t| {
                                let shape = extras.targets[t].applied(lod);
                                let original = m.target_shape(t);
                                let measured =
                                    crate::distance::hausdorff_mesh_mesh(&original, &shape, &opts)
                                        .two_sided();
                                TargetError {
                                    target: t,
                                    name: m.targets[t].name.clone(),
                                    measured,
                                }
                            })
                            .collect();
                        let carries = m.skin.is_some() || m.tangents.is_some();
                        let vertex_data =
                            (carries || !m.targets.is_empty()).then(|| {
                                match transfer.carried(lod) {
                                    true => "carried",
                                    false => "transferred",
                                }
                            });
                        LodMeasures {
                            vertex_data,
                            pose_error,
                            target_errors,
                            // A baked LOD's (or an impostor's) UVs are its own atlas's.
                            uv_error: match (&l.baked, l.method) {
                                (Some(_), _) | (_, crate::lod::Method::Impostor) => None,
                                _ => crate::distance::uv_error(&m.mesh, lod, l.bound()),
                            },
                            area: lod.area(),
                        }
                    })
                    .collect()
            })
            .collect()
    }

    /// The most LODs a chain has.
    pub fn levels(&self) -> usize {
        self.chains.iter().map(|c| c.lods.len()).max().unwrap_or(0)
    }

    /// The JSON of each mesh: its name, instances, and per LOD its
    /// triangles, mesh-space bound and coverage, and per instance the
    /// world-space bound (σ_max·ε) and the camera distance at which the
    /// LOD hands over to the next (vertical field of view
    /// [`SWITCH_FOV_Y_DEGREES`]).
    pub fn meshes_json(&self, scene: &Scene, measures: &[Vec<LodMeasures>]) -> Value {
        let meshes: Vec<Value> = scene
            .meshes
            .iter()
            .zip(&self.chains)
            .zip(measures)
            .zip(&self.target_bounds)
            .zip(&self.skipped)
            .map(|((((m, chain), measures), target_bounds), skipped)| {
                let flags = chain.flags();
                let lods: Vec<Value> = chain
                    .lods
                    .iter()
                    .zip(&chain.coverages)
                    .zip(measures)
                    .zip(target_bounds)
                    .zip(&flags)
                    .map(|((((l, c), measured), target_bounds), flags)| {
                        let world: Vec<f32> =
                            m.instances.iter().map(|i| i.scale() * l.bound()).collect();
                        // Where the coverage falls to `c` (LOD k is left for
                        // k+1): c = r_w / (d·tan(θ/2)) with r_w = σ_max·r.
                        let tan = (0.5 * SWITCH_FOV_Y_DEGREES.to_radians()).tan();
                        let distances: Vec<f32> = m
                            .instances
                            .iter()
                            .map(|i| i.scale() * chain.radius() / (c * tan))
                            .collect();
                        let mut j = json!({
                            "triangles": l.set.mesh.triangles.len(),
                            "points": l.set.points.len(),
                            "splats": l.set.splats.len(),
                            "error_bound": l.bound(),
                            "world_error_bounds": world,
                            "screen_coverage": c,
                            "switch_distances": distances,
                        });
                        if !target_bounds.is_empty() {
                            j["target_bounds"] = json!(target_bounds);
                        }
                        if let Some(baked) = &l.baked {
                            j["baked"] = json!(baked);
                        }
                        if let Some(unmet) = &l.set.unmet {
                            j["unmet"] = json!(unmet);
                        }
                        if !flags.is_empty() {
                            j["flags"] = flags.iter().map(Flag::json).collect();
                        }
                        if let (Value::Object(o), Ok(Value::Object(more))) =
                            (&mut j, serde_json::to_value(measured))
                        {
                            o.extend(more);
                        }
                        j
                    })
                    .collect();
                let mut j = json!({
                    "index": m.index,
                    "name": m.name,
                    "instances": m.instances.iter().map(|i| i.node).collect::<Vec<_>>(),
                    "triangles": m.mesh.triangles.len(),
                    "bbox_diagonal": chain.diagonal,
                    "skinned": m.skin.is_some(),
                    "morph_targets": m.targets.len(),
                    "lods": lods,
                });
                if !skipped.is_empty() {
                    j["skipped_rows"] = json!(skipped);
                }
                j
            })
            .collect();
        Value::Array(meshes)
    }

    /// Per level, over the scene (a chain shorter than the level stays at
    /// its coarsest).
    pub fn level_totals(&self, scene: &Scene, k: usize) -> LevelTotals {
        let mut totals = LevelTotals::default();
        for (m, chain) in scene.meshes.iter().zip(&self.chains) {
            let at = k.min(chain.lods.len().saturating_sub(1));
            let Some(l) = chain.lods.get(at) else {
                continue;
            };
            let t = l.set.mesh.triangles.len();
            totals.written += t;
            totals.drawn_triangles += t * m.instances.len();
            totals.drawn_primitives += chain.drawn(at) * m.instances.len();
            for i in &m.instances {
                totals.bound = totals.bound.max(i.scale() * l.bound());
            }
        }
        totals
    }
}

/// One level of a scene's chains, over its meshes.
#[derive(Debug, Clone, Copy, Default)]
pub struct LevelTotals {
    /// Triangles written (each mesh once).
    pub written: usize,
    /// Triangles drawn (each instance).
    pub drawn_triangles: usize,
    /// All a client draws, each instance: triangles, points as the recipe
    /// writes them, splat quads (`Chain::drawn`).
    pub drawn_primitives: usize,
    /// The largest world-space bound of any instance.
    pub bound: f32,
}
