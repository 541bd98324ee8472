//! Build jobs: when a build starts (now or once parameters settle), its
//! worker for each method, its preview, and its outcome.

use std::sync::Arc;

use lodstudio_core::lod::BuildError;
use lodstudio_core::progress::Cancelled;

use super::StudioApp;
use crate::build;
use crate::job::{Job, Poll};
use crate::render::{Scene, SceneStyle};
use crate::settings::voxel::VolumeGrid;

/// With auto rebuild, a build starts once parameters have been still this long
/// (seconds), so dragging a slider does not start a build every frame.
const REBUILD_DELAY: f64 = 0.4;

/// When a requested build starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum BuildRequest {
    /// At the next frame (the Build button).
    Now,
    /// [`REBUILD_DELAY`] after the next frame; a further change asks again, which
    /// postpones it (parameter changes with auto rebuild).
    Settled,
    /// Once egui's clock reaches this time.
    At(f64),
}

impl StudioApp {
    /// A new model makes the last result (and any build of the old one) moot.
    pub(super) fn forget_result(&mut self) {
        if let Some(old) = self.build.take() {
            self.info(format!("Stopped building {}", old.label()));
        }
        self.result = None;
        self.build_at = None;
        self.build_note = None;
    }

    /// Whether the chosen method can build the model on screen (`None`
    /// without a model), or why not.
    pub(super) fn input_check(&self) -> Option<Result<(), BuildError>> {
        self.current
            .as_ref()
            .map(|c| build::check(self.methods.method, &c.source()))
    }

    /// After a parameter changed: schedule a rebuild if wanted and possible.
    pub(super) fn parameters_changed(&mut self) {
        self.build_note = None;
        let buildable = matches!(self.input_check(), Some(Ok(())));
        // Run-time settings (the threshold, criteria, pyramid position) leave
        // the result current: nothing to rebuild.
        if self.methods.auto_rebuild && buildable && self.result_is_stale() {
            self.build_at = Some(BuildRequest::Settled);
        }
    }

    /// Starts a requested build once its time has come; an auto rebuild waits
    /// until parameters have been still for [`REBUILD_DELAY`].
    pub(super) fn start_build_when_due(&mut self, ctx: &egui::Context) {
        let Some(at) = self.build_at else {
            return;
        };
        let now = ctx.input(|i| i.time);
        match at {
            BuildRequest::Settled => {
                self.build_at = Some(BuildRequest::At(now + REBUILD_DELAY));
                ctx.request_repaint_after_secs(REBUILD_DELAY as f32);
            }
            BuildRequest::At(t) if now < t => ctx.request_repaint_after_secs((t - now) as f32),
            BuildRequest::Now | BuildRequest::At(_) => {
                self.build_at = None;
                self.start_build(ctx);
            }
        }
    }

    fn start_build(&mut self, ctx: &egui::Context) {
        let Some(current) = &self.current else {
            self.build_failed("Open a model first.".to_string());
            return;
        };
        let source = current.source();
        if let Err(e) = build::check(self.methods.method, &source) {
            self.build_failed(e.to_string());
            return;
        }
        let label = format!("{} of {}", self.methods.method.name(), current.name);
        let params = self.methods.params(current.volume.as_ref());
        let knobs = self
            .methods
            .knobs(current.mesh().map_or(0, |m| m.triangles.len()));
        // A cancelled build sends nothing (see `Job::spawn`).
        let work = move |progress: &_| match build::run(&params, &source, &knobs, progress) {
            Err(BuildError::Cancelled) => Err(Cancelled),
            outcome => Ok(outcome),
        };
        // Replacing the job cancels the running build (see `Job`'s Drop).
        if let Some(old) = self.build.take() {
            self.info(format!("Stopped {}", old.label()));
        }
        self.build_note = None;
        match Job::spawn("lod builder", label, ctx, work) {
            Ok(job) => {
                job.progress().watch();
                self.preview = None;
                self.build = Some(job);
            }
            Err(e) => self.build_failed(format!("cannot start the build: {e}")),
        }
    }

    pub(super) fn poll_build(&mut self) {
        let Some(job) = &self.build else {
            return;
        };
        let outcome = match job.poll() {
            Poll::Running => return,
            Poll::Done(outcome) => outcome,
            Poll::Lost => Err(BuildError::BadInput(
                "the build stopped unexpectedly (internal error)".to_string(),
            )),
        };
        let Some(job) = self.build.take() else {
            return;
        };
        match outcome {
            Ok(built) => {
                self.info(format!("{}: {}", job.label(), built.report()));
                self.result = Some(built);
                self.show_result();
            }
            Err(e) => self.build_failed(format!("{}: {e}", job.label())),
        }
    }

    pub(super) fn cancel_build(&mut self) {
        self.build_at = None;
        if let Some(job) = self.build.take() {
            let kept = if self.result.is_some() {
                "the previous result is kept"
            } else {
                "no result yet"
            };
            self.info(format!("Cancelled {}; {kept}", job.label()));
        }
    }

    fn build_failed(&mut self, message: String) {
        self.error(message.clone());
        self.build_note = Some(message);
    }

    /// The latest intermediate state of the running build (or chain
    /// build), as a scene.
    pub(super) fn poll_preview(&mut self) {
        let building = self.build.as_ref().map(Job::progress);
        match building.or_else(|| self.chain.build_progress()) {
            Some(progress) => {
                if let Some(state) = progress.take_preview() {
                    self.preview = Some(Arc::new(Scene::from_draw_set(
                        &state,
                        &SceneStyle::default(),
                    )));
                }
            }
            None => self.preview = None,
        }
    }

    /// Whether the result (if any) was built with other parameters than shown.
    pub(super) fn result_is_stale(&self) -> bool {
        self.result
            .as_ref()
            .is_none_or(|r| r.params != self.methods.params(self.volume_grid()))
    }

    /// The grid of the model on screen, when it is a volume.
    fn volume_grid(&self) -> Option<&VolumeGrid> {
        self.current.as_ref().and_then(|c| c.volume.as_ref())
    }
}
