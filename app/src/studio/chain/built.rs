//! A chain built by the builder `lodstudio export` uses, with what the
//! viewport and the table show of it.

use std::path::Path;
use std::sync::Arc;

use lodstudio_core::Progress;
use lodstudio_core::io::{LoadOptions, Loaded};
use lodstudio_core::recipe::{Chain, Recipe, build_chain};

use super::ChainError;
use crate::panels::chain::RowFigures;
use crate::render::camera::distance_at_coverage;
use crate::render::{Scene, SceneStyle};

/// A chain built for the model on screen, with what the viewport and the
/// table show of it.
pub struct BuiltChain {
    pub chain: Arc<Chain>,
    /// One scene per LOD, made on the worker.
    pub(super) scenes: Vec<Arc<Scene>>,
    /// The same with their wireframes, made the first time one is shown.
    pub(super) wire_scenes: Vec<std::sync::OnceLock<Arc<Scene>>>,
    /// Per recipe row: its LOD and its table cells.
    pub(super) figures: Vec<RowFigures>,
}

impl BuiltChain {
    /// LOD `k`'s scene, with its wireframe when asked.
    pub(super) fn scene(&self, k: usize, wireframe: bool) -> Option<Arc<Scene>> {
        let scene = self.scenes.get(k)?;
        if !wireframe {
            return Some(Arc::clone(scene));
        }
        let wire = self.wire_scenes.get(k)?.get_or_init(|| {
            Arc::new(Scene::clone(scene).with_wireframe(&self.chain.lods[k].set.mesh))
        });
        Some(Arc::clone(wire))
    }

    /// The recipe it was built with.
    pub fn recipe(&self) -> &Recipe {
        &self.chain.recipe
    }

    /// Builds `recipe` on the model as `lodstudio export` loads it for this
    /// recipe: `loaded`, or the file at `path` reopened when the recipe welds
    /// otherwise than the studio loaded it.
    pub(super) fn build(
        loaded: &Loaded,
        path: &Path,
        recipe: &Recipe,
        progress: &Progress,
    ) -> Result<BuiltChain, ChainError> {
        let reloaded;
        let model = if recipe.weld() == LoadOptions::default().repair.weld {
            &loaded.model
        } else {
            let mut options = LoadOptions::default();
            options.repair.weld = recipe.weld();
            reloaded = lodstudio_core::open::open(path, &options, progress)?;
            &reloaded.model
        };
        Ok(BuiltChain::new(build_chain(model, recipe, progress)?))
    }

    fn new(chain: Chain) -> BuiltChain {
        let scenes = chain
            .lods
            .iter()
            .map(|l| Arc::new(Scene::from_draw_set(&l.set, &SceneStyle::default())))
            .collect();
        let figures = figures(&chain);
        BuiltChain {
            wire_scenes: chain.lods.iter().map(|_| Default::default()).collect(),
            chain: Arc::new(chain),
            scenes,
            figures,
        }
    }
}

/// The table's cells of every recipe row (rows met by one cut share its LOD).
fn figures(chain: &Chain) -> Vec<RowFigures> {
    let mut out: Vec<Option<RowFigures>> = vec![None; chain.recipe.rows.len()];
    for (k, lod) in chain.lods.iter().enumerate() {
        let c_out = chain.coverages[k];
        let c_in = chain.coverage_in(k);
        let set = &lod.set;
        let cells = [
            set.mesh.triangles.len().to_string(),
            set.points.len().to_string(),
            set.splats.len().to_string(),
            format!("{:.3}%", 100.0 * lod.bound() / chain.diagonal),
            format!("{:.2}", chain.pixels_at(k, c_in)),
            format!("{c_out:.4} {:.1}r", distance_at_coverage(c_out)),
            format!("{:.2} s", lod.build_seconds),
        ];
        let estimate = set.error_bound_kind == lodstudio_core::lod::BoundKind::Estimate;
        for &r in &lod.rows {
            out[r] = Some(RowFigures {
                lod: k,
                cells: cells.clone(),
                estimate,
            });
        }
    }
    out.into_iter()
        .map(|f| f.expect("every row has its LOD"))
        .collect()
}
