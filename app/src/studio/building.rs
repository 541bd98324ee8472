//! Build jobs: when a build starts (now or once parameters settle), its
//! worker for each method, its preview, and its outcome.

use std::sync::Arc;

use lodstudio_core::implicit::MeshSolid;
use lodstudio_core::progress::{Cancelled, Progress};

use super::StudioApp;
use crate::build::{self, Built};
use crate::job::{Job, Poll};
use crate::render::{Scene, SceneStyle};
use crate::settings::BuildParams;
use crate::settings::voxel::VolumeGrid;

/// With auto rebuild, a build starts once parameters have been still this long
/// (seconds), so dragging a slider does not start a build every frame.
const REBUILD_DELAY: f64 = 0.4;

/// A build's work on its worker thread (one per method).
type BuildWork = Box<dyn FnOnce(&Progress) -> Result<Result<Built, String>, Cancelled> + Send>;

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
    pub(super) fn input_check(&self) -> Option<Result<(), String>> {
        self.current
            .as_ref()
            .map(|c| build::check(self.methods.method, &c.path, &c.loaded.model))
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
        let ready = match &self.current {
            None => Err("Open a model first.".to_string()),
            Some(c) => build::check(self.methods.method, &c.path, &c.loaded.model).map(|()| c),
        };
        let current = match ready {
            Ok(current) => current,
            Err(message) => {
                self.build_failed(message);
                return;
            }
        };
        let label = format!("{} of {}", self.methods.method.name(), current.name);
        // Every method starts here; a new one makes this match incomplete.
        let work: BuildWork = match self.methods.params(current.volume.as_ref()) {
            BuildParams::EdgeCollapse(options) => {
                let loaded = Arc::clone(&current.loaded);
                Box::new(move |progress| build::run(&loaded.model, options, progress))
            }
            BuildParams::Amg(settings) => {
                let loaded = Arc::clone(&current.loaded);
                let settings = crate::settings::amg::AmgSettings {
                    level: self.methods.amg.level,
                    ..settings
                };
                Box::new(move |progress| build::amg::run(&loaded.model, settings, progress))
            }
            BuildParams::Hybrid(settings) => {
                let loaded = Arc::clone(&current.loaded);
                Box::new(move |progress| build::hybrid::run(&loaded.model, settings, progress))
            }
            BuildParams::MergeTree(_) => {
                let loaded = Arc::clone(&current.loaded);
                let settings = self.methods.merge_tree;
                Box::new(move |progress| build::mergetree::run(&loaded.model, settings, progress))
            }
            BuildParams::Voxel(settings) => {
                match build::voxel_source(&current.path, &current.loaded.model) {
                    Ok(build::VoxelSource::Implicit(name)) => {
                        let Some(solid) = lodstudio_core::builtins::implicit(name) else {
                            self.build_failed(format!("builtin:{name} is no implicit solid"));
                            return;
                        };
                        Box::new(move |progress| {
                            build::run_voxel(solid.as_ref(), settings, progress)
                        })
                    }
                    Ok(build::VoxelSource::Mesh(_)) => {
                        let loaded = Arc::clone(&current.loaded);
                        Box::new(move |progress| match build::mesh_of(&loaded.model) {
                            Ok(mesh) => build::run_voxel(&MeshSolid::new(mesh), settings, progress),
                            Err(message) => Ok(Err(message)),
                        })
                    }
                    Ok(build::VoxelSource::Volume(volume)) => {
                        let loaded = Arc::clone(&current.loaded);
                        let grid = current.volume.unwrap_or_else(|| VolumeGrid::of(volume));
                        Box::new(move |progress| {
                            build::run_voxel_volume(&loaded.model, &grid, settings, progress)
                        })
                    }
                    Err(message) => {
                        self.build_failed(message);
                        return;
                    }
                }
            }
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
            Poll::Lost => Err("the build stopped unexpectedly (internal error)".to_string()),
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
            Err(message) => self.build_failed(format!("{}: {message}", job.label())),
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

    /// The latest intermediate state of the running build, as a scene.
    pub(super) fn poll_preview(&mut self) {
        match &self.build {
            Some(job) => {
                if let Some(state) = job.progress().take_preview() {
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
