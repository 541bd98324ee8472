//! A chain built by the builder `lodstudio export` uses, with what the
//! viewport and the table show of it.

use std::path::Path;
use std::sync::{Arc, Mutex};

use lodstudio_core::Progress;
use lodstudio_core::io::{LoadOptions, Loaded};
use lodstudio_core::recipe::{
    Chain, Flag, Recipe, build_chain_cached, build_unflagged, fingerprint,
};

use super::kept::Kept;
use super::{ChainError, Mode};
use crate::live_cut::{CutStyle, styled_scene};
use crate::panels::chain::RowFigures;
use crate::render::camera::distance_at_coverage;
use crate::render::{Scene, SceneStyle};

/// A LOD's scene in a style other than the plain one.
type Styled = (CutStyle, Arc<Scene>);

/// A chain built for the model on screen, with what the viewport and the
/// table show of it.
pub struct BuiltChain {
    pub chain: Arc<Chain>,
    /// One scene per LOD, made on the worker.
    pub(super) scenes: Vec<Arc<Scene>>,
    /// Per LOD, its scene in the last style other than the plain one it was
    /// shown in (wireframe, colour by bound, type or region), made when shown.
    styled: Vec<Mutex<Option<Styled>>>,
    /// Per recipe row: its LOD and its table cells.
    pub(super) figures: Vec<RowFigures>,
    /// Why the chain's work could not be saved for the next session.
    pub(super) kept_error: Option<String>,
}

impl BuiltChain {
    /// LOD `k`'s scene drawn in `style`, as the live cut is drawn.
    pub(super) fn scene(&self, k: usize, style: CutStyle) -> Option<Arc<Scene>> {
        let scene = self.scenes.get(k)?;
        if style == CutStyle::default() {
            return Some(Arc::clone(scene));
        }
        let mut styled = self
            .styled
            .get(k)?
            .lock()
            .unwrap_or_else(|e| e.into_inner());
        match &*styled {
            Some((s, scene)) if *s == style => Some(Arc::clone(scene)),
            _ => {
                let scene = Arc::new(styled_scene(&self.chain.lods[k].set, style));
                *styled = Some((style, Arc::clone(&scene)));
                Some(scene)
            }
        }
    }

    /// The recipe it was built with.
    pub fn recipe(&self) -> &Recipe {
        &self.chain.recipe
    }

    /// Builds `recipe` on the model as `lodstudio export` loads it for this
    /// recipe (`loaded`, or the file at `path` reopened when the recipe welds
    /// otherwise than the studio loaded it), from the work `kept` holds, and
    /// keeps what it made. An empty cache first takes the work saved for
    /// this model; to [`Mode::Reopen`], only that work answers: `None`
    /// unless it holds this recipe's chain (nothing is built); to
    /// [`Mode::Unflagged`], the recipe less the rows its chain flags.
    pub(super) fn build(
        loaded: &Loaded,
        path: &Path,
        recipe: &Recipe,
        progress: &Progress,
        kept: &Kept,
        mode: Mode,
    ) -> Result<Option<BuiltChain>, ChainError> {
        let reopen = mode == Mode::Reopen;
        let reloaded;
        let model = if recipe.weld() == LoadOptions::default().repair.weld {
            &loaded.model
        } else {
            let mut options = LoadOptions::default();
            options.repair.weld = recipe.weld();
            reloaded = lodstudio_core::open::open(path, &options, progress)?;
            &reloaded.model
        };
        let mut cache = kept.lock();
        if reopen || cache.groups() == 0 {
            let saved = kept.saved(&fingerprint(model));
            let holds_recipe = saved.as_ref().is_some_and(|(r, _)| r == recipe);
            if let Some((_, saved)) = saved
                && cache.groups() == 0
            {
                *cache = saved;
            }
            if reopen && !holds_recipe {
                return Ok(None);
            }
        }
        let chain = match mode {
            Mode::Unflagged => build_unflagged(model, recipe, progress, &mut cache)?,
            _ => build_chain_cached(model, recipe, progress, &mut cache)?,
        };
        let kept_error = kept.save(&cache, &chain.recipe).err();
        Ok(Some(BuiltChain::new(chain, kept_error)))
    }

    fn new(chain: Chain, kept_error: Option<String>) -> BuiltChain {
        let scenes = chain
            .lods
            .iter()
            .map(|l| Arc::new(Scene::from_draw_set(&l.set, &SceneStyle::default())))
            .collect();
        let figures = figures(&chain);
        BuiltChain {
            styled: chain.lods.iter().map(|_| Mutex::default()).collect(),
            chain: Arc::new(chain),
            scenes,
            figures,
            kept_error,
        }
    }
}

/// What the table says of a baked LOD, and why it was baked.
fn baked_words(b: &lodstudio_core::bake::BakeReport) -> (String, String) {
    let why = match (b.automatic, &b.measured) {
        (false, _) => "the row asks for it".to_string(),
        (true, None) => "unasked: the seams kept it short of its budget".to_string(),
        (true, Some(m)) => format!(
            "unasked: baked, it measured closer to the model ({:.1} dB against {:.1} dB \
             keeping the model's atlas)",
            m.baked_db, m.kept_db
        ),
    };
    (
        format!("baked {}²", b.width.max(b.height)),
        format!(
            "Its own texture, {} × {} px, {} charts: {why}.",
            b.width, b.height, b.charts
        ),
    )
}

/// The table's cells of every recipe row (rows met by one cut share its LOD).
fn figures(chain: &Chain) -> Vec<RowFigures> {
    let mut out: Vec<Option<RowFigures>> = vec![None; chain.recipe.rows.len()];
    for ((k, lod), flags) in chain.lods.iter().enumerate().zip(chain.flags()) {
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
            match lod.reused {
                true => "kept".to_string(),
                false => format!("{:.2} s", lod.build_seconds),
            },
        ];
        let estimate = set.error_bound_kind == lodstudio_core::lod::BoundKind::Estimate;
        // Rows met by one LOD may ask for different counts: the reason is the
        // LOD's (its collapse went as far as it goes).
        let unmet = set.unmet.as_ref().map(|u| {
            format!(
                "Short of the budget of {} primitives: {} reached. {}",
                u.asked, u.reached, u.why
            )
        });
        for (i, &r) in lod.rows.iter().enumerate() {
            // The LOD's first row is its own; each other row repeats it.
            let row_flags: Vec<Flag> = flags
                .iter()
                .map(|f| match f {
                    Flag::Duplicate { of, .. } => Flag::Duplicate {
                        rows: vec![lod.labels[i].clone()],
                        of: format!("row {} ({of})", lod.rows[0]),
                    },
                    f => f.clone(),
                })
                .filter(|f| i > 0 || !matches!(f, Flag::Duplicate { .. }))
                .collect();
            let words: Vec<&str> = row_flags.iter().map(Flag::name).collect();
            let why: Vec<String> = row_flags.iter().map(Flag::why).collect();
            out[r] = Some(RowFigures {
                lod: k,
                cells: cells.clone(),
                estimate,
                unmet: unmet.clone(),
                flags: (!words.is_empty()).then(|| (words.join(", "), why.join("\n"))),
                baked: lod.baked.as_ref().map(baked_words),
            });
        }
    }
    out.into_iter()
        .map(|f| f.expect("every row has its LOD"))
        .collect()
}
