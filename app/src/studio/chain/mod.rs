//! The LOD chain, the studio's main object: rows from any method built on a
//! worker by the builder `lodstudio export` uses (`recipe::build_chain`, so
//! the studio's chain export is byte for byte the CLI's), a row shown on
//! click, the switch preview (a dolly from near to far drawing the LOD the
//! chain uses there, with the bound in pixels at each switch), the visual
//! difference of its LODs, and the chain's export and recipe files.
//!
//! A component of its own: [`ChainState`] holds all of it and makes its
//! transitions without a window (so they are tested without one), [`ui`]
//! draws it, and what either needs of the studio comes back as a
//! [`ChainEvent`] to log or a [`ChainRequest`]. `studio/chain_glue.rs` wires
//! it into the studio.

mod built;
mod difference;
mod dolly;
mod error;
mod event;
mod files;
pub mod kept;
mod preview;
#[cfg(test)]
mod tests;
pub mod ui;

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::Receiver;

use lodstudio_core::Progress;
use lodstudio_core::io::Loaded;
use lodstudio_core::progress::Cancelled;
use lodstudio_core::recipe::Recipe;

pub use self::built::BuiltChain;
pub use self::difference::LodDifference;
pub use self::error::ChainError;
pub use self::event::{ChainEvent, ChainRequest, SaveWork};
pub use self::files::Target;
use self::kept::Kept;
use crate::job::{Job, Poll};
use crate::render::{Camera, Offscreen, Scene};
use crate::settings::chain::ChainSettings;

/// The model a chain is built from.
pub struct Source {
    pub loaded: Arc<Loaded>,
    /// Where it was opened from: reopened when the recipe welds otherwise.
    pub path: PathBuf,
}

/// The switch preview: the camera's distance (in bounding radii) picks the
/// LOD a loader would draw there.
#[derive(Debug, Clone, Copy, Default)]
struct SwitchPreview {
    on: bool,
    /// egui time the dolly started at, while it runs.
    dolly_from: Option<f64>,
}

/// What a chain build does with the rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum Mode {
    /// Builds them.
    #[default]
    Build,
    /// Only reopens the last session's chain of them.
    Reopen,
    /// Builds them less the rows the chain flags (`recipe::build_unflagged`),
    /// which then replace them: Auto chain.
    Unflagged,
}

/// The chain: its rows, their build, the switch preview, the visual
/// difference and the recipe files.
#[derive(Default)]
pub struct ChainState {
    /// The rows and the Auto chain rule (what Save recipe… writes).
    pub settings: ChainSettings,
    pub recent_recipes: Vec<PathBuf>,
    /// What the chain's builds made, shared by them and saved for the next
    /// session.
    kept: Kept,
    job: Option<Job<Result<Option<BuiltChain>, ChainError>>>,
    /// What the running build does with its rows.
    mode: Mode,
    /// The rows it started from.
    started_from: Option<Recipe>,
    built: Option<BuiltChain>,
    /// The recipe row whose LOD is shown.
    selected: Option<usize>,
    preview: SwitchPreview,
    picker: Option<Receiver<Option<PathBuf>>>,
    /// Why the last chain build failed, shown on the panel.
    note: Option<String>,
    /// The visual difference of every LOD, measuring or measured.
    measuring: Option<Job<Result<Vec<LodDifference>, ChainError>>>,
    differences: Option<Vec<LodDifference>>,
    /// The shown LOD's difference image, uploaded once.
    difference_image: Option<(usize, egui::TextureHandle)>,
}

impl ChainState {
    /// Replaces the rows (as opening a recipe does); the built chain stays,
    /// stale until built again.
    pub fn set_recipe(&mut self, recipe: Recipe) {
        self.settings.recipe = recipe;
        self.selected = None;
    }

    /// Saves the chain's work into `file` from now on (`None`: nowhere).
    pub fn keep_in(&mut self, file: Option<PathBuf>) {
        self.kept = Kept::in_file(file);
    }

    /// Builds the rows on `source` on a worker, replacing any chain build;
    /// returns what to log. Without a model the reason is noted on the panel.
    pub fn start_build(
        &mut self,
        source: Option<Source>,
        ctx: &egui::Context,
    ) -> Option<ChainEvent> {
        self.start(source, ctx, Mode::Build)
    }

    /// Replaces the rows by the Auto chain rule's and builds them on
    /// `source`, leaving out each row the chain flags (the same LOD as a
    /// row before, never shown, costlier than the finer LOD); the rows kept
    /// replace the rule's when the build ends.
    pub fn start_auto(
        &mut self,
        source: Option<Source>,
        ctx: &egui::Context,
    ) -> Option<ChainEvent> {
        self.set_recipe(Recipe {
            rows: self.settings.auto.make(),
            ..self.settings.recipe.clone()
        });
        self.start(source, ctx, Mode::Unflagged)
    }

    /// Reopens the chain the last session built on `source` with these rows,
    /// on a worker, without building anything; nothing when none was saved.
    pub fn reopen(&mut self, source: Source, ctx: &egui::Context) -> Option<ChainEvent> {
        match self.kept.has_saved() {
            true => self.start(Some(source), ctx, Mode::Reopen),
            false => None,
        }
    }

    fn start(
        &mut self,
        source: Option<Source>,
        ctx: &egui::Context,
        mode: Mode,
    ) -> Option<ChainEvent> {
        self.note = None;
        // A measurement of the chain being replaced would land on the new one.
        self.measuring = None;
        let Some(Source { loaded, path }) = source else {
            self.note = Some(ChainError::NoModel.to_string());
            return None;
        };
        let recipe = self.settings.recipe.clone();
        let kept = self.kept.clone();
        let work = move |progress: &Progress| {
            BuiltChain::build(&loaded, &path, &recipe, progress, &kept, mode)
        };
        match spawn("chain", "Chain", "the chain build", ctx, work) {
            Ok(job) => {
                // What the rows' builds have made so far, for the viewport.
                job.progress().watch();
                self.job = Some(job);
                self.mode = mode;
                self.started_from = Some(self.settings.recipe.clone());
                None
            }
            Err(e) => Some(ChainEvent::Failed(e)),
        }
    }

    /// Stops the chain build; the last chain built stays.
    pub fn cancel_build(&mut self) -> ChainEvent {
        self.job = None;
        ChainEvent::BuildStopped
    }

    /// How long the running build has run, if one runs.
    pub fn building_for(&self) -> Option<std::time::Duration> {
        self.job.as_ref().map(Job::elapsed)
    }

    pub fn is_building(&self) -> bool {
        self.job.is_some()
    }

    /// The running build's progress (its stage, and what it made so far).
    pub fn build_progress(&self) -> Option<&Progress> {
        self.job.as_ref().map(Job::progress)
    }

    /// The last chain built for the model on screen.
    pub fn built(&self) -> Option<&BuiltChain> {
        self.built.as_ref()
    }

    /// The built chain, when it was built with the rows as they are.
    fn fresh(&self) -> Option<&BuiltChain> {
        self.built
            .as_ref()
            .filter(|b| b.recipe() == &self.settings.recipe)
    }

    /// Renders every LOD of the built chain and `original` off-screen with
    /// `renderer`, from `camera` and from 8 views around, on a worker;
    /// returns what to log.
    pub fn start_measuring(
        &mut self,
        ctx: &egui::Context,
        renderer: Option<&egui_wgpu::RenderState>,
        original: Option<&Arc<Scene>>,
        camera: Camera,
    ) -> Option<ChainEvent> {
        let (Some(renderer), Some(built), Some(original)) = (renderer, &self.built, original)
        else {
            return Some(ChainEvent::Failed(ChainError::NothingToMeasure));
        };
        let mut offscreen = Offscreen::new(renderer);
        let original = Arc::clone(original);
        let lods = built.scenes.clone();
        let cameras = difference::cameras(camera, &original);
        let work = move |progress: &Progress| {
            difference::measure(&mut offscreen, &original, &lods, &cameras, progress)
        };
        match spawn(
            "difference",
            "Visual difference",
            "the visual difference",
            ctx,
            work,
        ) {
            Ok(job) => {
                self.measuring = Some(job);
                None
            }
            Err(e) => Some(ChainEvent::Failed(e)),
        }
    }

    pub fn is_measuring(&self) -> bool {
        self.measuring.is_some()
    }

    /// Stops measuring (nothing to log).
    pub fn cancel_measuring(&mut self) {
        self.measuring = None;
    }

    /// The last visual difference of the built chain's LODs.
    pub fn differences(&self) -> Option<&[LodDifference]> {
        self.differences.as_deref()
    }

    /// Closes the visual difference (its window).
    pub fn close_differences(&mut self) {
        self.differences = None;
        self.difference_image = None;
    }

    /// A new model: its chain is still to be built.
    pub fn forget(&mut self) {
        self.job = None;
        self.kept = self.kept.emptied();
        self.built = None;
        self.measuring = None;
        self.close_differences();
        self.selected = None;
        self.preview = SwitchPreview::default();
    }

    /// Takes what the recipe dialog, the build and the measurement finished;
    /// returns what to log, in that order.
    pub fn poll(&mut self) -> Vec<ChainEvent> {
        [
            self.poll_picker(),
            self.poll_build(),
            self.poll_difference(),
        ]
        .into_iter()
        .flatten()
        .collect()
    }

    fn poll_build(&mut self) -> Option<ChainEvent> {
        let job = self.job.as_ref()?;
        let outcome = match job.poll() {
            Poll::Running => return None,
            Poll::Done(outcome) => outcome,
            Poll::Lost => Err(ChainError::Lost("chain build")),
        };
        let seconds = job.elapsed().as_secs_f64();
        self.job = None;
        Some(match outcome {
            Ok(None) => return None,
            Ok(Some(built)) => {
                self.measuring = None;
                self.close_differences();
                // Auto chain's rows, less those left out, unless edited meanwhile.
                let from = self.started_from.take();
                let rows = from.as_ref().map_or(0, |r| r.rows.len());
                let left_out = rows.saturating_sub(built.recipe().rows.len());
                if self.mode == Mode::Unflagged && from.as_ref() == Some(&self.settings.recipe) {
                    self.set_recipe(built.recipe().clone());
                }
                let event = ChainEvent::Built {
                    lods: built.chain.lods.len(),
                    kept: built.chain.lods.iter().filter(|l| l.reused).count(),
                    short: built
                        .chain
                        .lods
                        .iter()
                        .filter(|l| l.set.unmet.is_some())
                        .count(),
                    flagged: built.figures.iter().filter(|f| f.flags.is_some()).count(),
                    left_out,
                    seconds,
                    reopened: self.mode == Mode::Reopen,
                    not_saved: built.kept_error.clone(),
                };
                self.built = Some(built);
                event
            }
            Err(e) => {
                self.note = Some(e.to_string());
                ChainEvent::NotBuilt(e)
            }
        })
    }

    fn poll_difference(&mut self) -> Option<ChainEvent> {
        let outcome = match self.measuring.as_ref()?.poll() {
            Poll::Running => return None,
            Poll::Done(outcome) => outcome,
            Poll::Lost => Err(ChainError::Lost("visual difference")),
        };
        self.measuring = None;
        match outcome {
            Ok(d) => {
                self.differences = Some(d);
                self.difference_image = None;
                None
            }
            Err(e) => Some(ChainEvent::DifferenceFailed(e)),
        }
    }
}

/// Runs `work` on a thread; a run the user cancelled sends nothing (see
/// [`Job`]), whatever it answered.
fn spawn<T: Send + 'static>(
    thread: &str,
    label: &str,
    task: &'static str,
    ctx: &egui::Context,
    work: impl FnOnce(&Progress) -> Result<T, ChainError> + Send + 'static,
) -> Result<Job<Result<T, ChainError>>, ChainError> {
    let work = move |progress: &Progress| match work(progress) {
        Err(ChainError::Cancelled) => Err(Cancelled),
        answer => Ok(answer),
    };
    Job::spawn(thread, label.into(), ctx, work).map_err(|source| ChainError::Spawn { task, source })
}
