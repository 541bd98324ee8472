//! The studio window: menu, model list, LOD method and its parameters, 3D
//! viewport, inspector and log.
//!
//! Everything slow (loading, summarising, building a LOD, preparing GPU
//! geometry, file dialogs, exporting) runs on worker threads; the UI polls
//! them each frame so it never blocks, and a failed or cancelled load or build
//! keeps the previous model and result.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::time::Duration;

use lodstudio_core::builtins;
use lodstudio_core::implicit::MeshSolid;
use lodstudio_core::io::{LoadError, LoadOptions, Loaded};
use lodstudio_core::lod::Picked;
use lodstudio_core::open::open;
use lodstudio_core::progress::{Cancelled, Progress};
use lodstudio_core::stats::ModelSummary;

use crate::build::{self, Built};
use crate::export::{self, Saved};
use crate::frame_stats::FrameStats;
use crate::heatmap;
use crate::job::{Job, Poll};
use crate::live_cut::{self, CutStyle};
use crate::panels::voxel::VolumeGrid;
use crate::panels::{BuildParams, Method, MethodSettings};
use crate::session::{Autosave, Session};
use crate::viewport::{Scene, SceneStyle, Viewport};

/// With auto rebuild, a build starts once parameters have been still this long
/// (seconds), so dragging a slider does not start a build every frame.
const REBUILD_DELAY: f64 = 0.4;
const MAX_RECENT: usize = 10;
/// Older log lines are dropped beyond this many.
const MAX_LOG: usize = 500;
/// How often the UI refreshes the progress bar while a worker runs; the worker
/// also wakes the UI the moment it finishes.
const POLL_INTERVAL: Duration = Duration::from_millis(50);
/// Extensions offered by the file dialog (the loader detects formats by content).
const MODEL_EXTENSIONS: &[&str] = &[
    "obj", "gltf", "glb", "ply", "off", "nrrd", "nhdr", "nii", "inr", "gz",
];

/// The bundled default model, when the binary runs from its source tree.
fn default_model() -> PathBuf {
    let asset = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../assets/couplingdown.off"
    ));
    if asset.is_file() {
        asset.canonicalize().unwrap_or_else(|_| asset.to_path_buf())
    } else {
        PathBuf::from("builtin:csg-part")
    }
}

/// Short name of a model source for the UI (file name or `builtin:NAME`).
fn display_name(path: &Path) -> String {
    let text = path.to_string_lossy();
    if text.starts_with("builtin:") {
        return text.into_owned();
    }
    path.file_name()
        .map_or_else(|| text.to_string(), |n| n.to_string_lossy().into_owned())
}

/// `path` from the root (a session may restart in another folder).
fn absolute(path: &Path) -> PathBuf {
    match is_builtin(path) {
        true => path.to_path_buf(),
        false => std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
    }
}

fn is_builtin(path: &Path) -> bool {
    path.to_str().is_some_and(|s| s.starts_with("builtin:"))
}

/// The model on screen.
struct Current {
    name: String,
    path: PathBuf,
    loaded: Arc<Loaded>,
    summary: ModelSummary,
    /// Inspector rows, computed once so drawing allocates nothing new.
    rows: Vec<(String, String)>,
    /// The model as the viewport draws it.
    scene: Arc<Scene>,
    /// The grid and value range of a volume model.
    volume: Option<VolumeGrid>,
}

/// A build's work on its worker thread (one per method).
type BuildWork = Box<dyn FnOnce(&Progress) -> Result<Result<Built, String>, Cancelled> + Send>;

/// When a requested build starts.
#[derive(Debug, Clone, Copy, PartialEq)]
enum BuildRequest {
    /// At the next frame (the Build button).
    Now,
    /// [`REBUILD_DELAY`] after the next frame; a further change asks again, which
    /// postpones it (parameter changes with auto rebuild).
    Settled,
    /// Once egui's clock reaches this time.
    At(f64),
}

/// Which version of the model the viewport shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum View {
    Original,
    /// The last build's result (the original while there is none).
    Simplified,
    /// The original on the left, the result on the right, through one camera.
    SideBySide,
}

impl View {
    /// Whether the result (the LOD) is on screen.
    pub fn shows_lod(self) -> bool {
        self != View::Original
    }
}

/// What a load worker hands back.
struct Finished {
    loaded: Loaded,
    summary: ModelSummary,
    scene: Scene,
    volume: Option<VolumeGrid>,
    /// A saved hierarchy's own structure, to cut live without rebuilding.
    reopened: Option<build::Reopened>,
}

struct LoadJob {
    path: PathBuf,
    job: Job<Result<Box<Finished>, LoadError>>,
}

struct LogLine {
    text: String,
    error: bool,
}

/// The lodstudio GUI.
pub struct StudioApp {
    viewport: Viewport,
    /// The original beside the result (View::SideBySide).
    compare: Viewport,
    current: Option<Current>,
    job: Option<LoadJob>,
    /// Requested by [`StudioApp::open`]; started at the next frame, which has a context.
    pending: Option<PathBuf>,
    /// An open file dialog's answer.
    picker: Option<Receiver<Option<PathBuf>>>,
    recent: Vec<PathBuf>,
    log: Vec<LogLine>,
    /// Message of the last failed load, shown in a window until dismissed.
    error: Option<String>,
    /// The chosen method and its parameters (persisted, except the voxel
    /// threshold: see `threshold_volume`).
    methods: MethodSettings,
    /// The volume the voxel threshold (`methods.voxel.threshold`) was chosen
    /// for. The threshold is in that volume's value units, so it resets to the
    /// middle of the value range when a different volume opens (and is not
    /// persisted between sessions); reopening the same volume keeps it.
    threshold_volume: Option<PathBuf>,
    build: Option<Job<Result<Built, String>>>,
    /// The last finished build of the model on screen.
    result: Option<Built>,
    /// Time of the last frame, for the inspector.
    frame_ms: f32,
    /// CPU time of the last frame (layout, cuts, tessellation, submission), as
    /// eframe measures it; `None` outside eframe.
    cpu_ms: Option<f32>,
    frame_stats: FrameStats,
    /// What the running build has made so far (shown while it runs).
    preview: Option<Arc<Scene>>,
    /// What the last click hit on the live cut.
    picked: Option<String>,
    /// Live cuts coloured by primitive type or by region, and splats outlined.
    by_type: bool,
    regions: bool,
    outlines: bool,
    /// A build asked for but not started yet.
    build_at: Option<BuildRequest>,
    /// Why the last build request failed, shown under the Build button.
    build_note: Option<String>,
    view: View,
    /// Colour the simplified mesh by each triangle's certified bound.
    heat: bool,
    export: Option<Job<Saved>>,
    autosave: Autosave,
}

impl StudioApp {
    /// Called by eframe: reopens the last session (and its model unless
    /// `initial` names one), or opens the default model.
    pub fn new(cc: &eframe::CreationContext<'_>, initial: Option<PathBuf>) -> Self {
        let reopen_model = initial.is_none();
        let mut app = Self::with_render_state(cc.wgpu_render_state.as_ref(), initial);
        app.resume(Autosave::from_env(), reopen_model);
        app
    }

    /// Takes the session `autosave` holds (recent files, method settings,
    /// thresholds and, with `reopen_model`, the model) and autosaves into it
    /// from now on. A damaged session is reported and left for the defaults.
    pub fn resume(&mut self, autosave: Autosave, reopen_model: bool) {
        match autosave.load() {
            Ok(Some(session)) => {
                self.recent = session.recent.into_iter().take(MAX_RECENT).collect();
                self.methods = session.methods;
                if let Some((volume, threshold)) = session.volume_threshold {
                    self.methods.voxel.threshold = Some(threshold);
                    self.threshold_volume = Some(volume);
                }
                match session.model {
                    Some(model) if reopen_model && (is_builtin(&model) || model.is_file()) => {
                        self.info(format!(
                            "Reopening the last session ({})",
                            display_name(&model)
                        ));
                        self.pending = Some(model);
                    }
                    Some(model) if reopen_model => self.error(format!(
                        "The last session's model {} is gone; opening the default model",
                        model.display()
                    )),
                    _ => {}
                }
            }
            Ok(None) => {}
            Err(e) => self.error(e),
        }
        self.autosave = autosave;
    }

    /// What the autosave keeps.
    fn session(&self) -> Session {
        Session {
            model: self.current.as_ref().map(|c| absolute(&c.path)),
            recent: self.recent.clone(),
            methods: self.methods,
            volume_threshold: self
                .threshold_volume
                .as_deref()
                .map(absolute)
                .zip(self.methods.voxel.threshold.filter(|t| t.is_finite())),
        }
    }

    /// Autosaves when a check is due; otherwise asks for a frame when it will
    /// be, so the last change before the studio goes idle is saved too.
    fn autosave(&mut self, ctx: &egui::Context) {
        match self.autosave.wait() {
            Some(wait) if wait.is_zero() => {
                let session = self.session();
                if let Err(e) = self.autosave.offer(&session) {
                    self.error(e);
                }
            }
            Some(wait) => ctx.request_repaint_after(wait),
            None => {}
        }
    }

    /// A studio without eframe (for tests): draws with `render_state` if given.
    pub fn with_render_state(
        render_state: Option<&egui_wgpu::RenderState>,
        initial: Option<PathBuf>,
    ) -> Self {
        StudioApp {
            viewport: Viewport::new(render_state),
            compare: Viewport::second(render_state, "original viewport"),
            current: None,
            job: None,
            pending: Some(initial.unwrap_or_else(default_model)),
            picker: None,
            recent: Vec::new(),
            log: Vec::new(),
            error: None,
            methods: MethodSettings::default(),
            threshold_volume: None,
            build: None,
            result: None,
            frame_ms: 0.0,
            cpu_ms: None,
            frame_stats: FrameStats::default(),
            preview: None,
            picked: None,
            by_type: false,
            regions: false,
            outlines: false,
            build_at: None,
            build_note: None,
            view: View::Simplified,
            heat: false,
            export: None,
            autosave: Autosave::off(),
        }
    }

    /// Starts loading `path` (a file or `builtin:NAME`) in the background,
    /// cancelling any load in progress.
    pub fn open(&mut self, path: impl Into<PathBuf>) {
        self.pending = Some(path.into());
    }

    pub fn is_loading(&self) -> bool {
        self.pending.is_some() || self.job.is_some()
    }

    /// Summary of the model on screen.
    pub fn summary(&self) -> Option<&ModelSummary> {
        self.current.as_ref().map(|c| &c.summary)
    }

    /// The model on screen, as loaded.
    pub fn loaded(&self) -> Option<&Loaded> {
        self.current.as_ref().map(|c| c.loaded.as_ref())
    }

    /// The 3D view (its camera is public).
    /// The camera, for scripted sessions and tests.
    pub fn viewport_mut(&mut self) -> &mut Viewport {
        &mut self.viewport
    }

    pub fn viewport(&self) -> &Viewport {
        &self.viewport
    }

    /// Messages of the log panel, oldest first.
    pub fn log_lines(&self) -> impl Iterator<Item = &str> {
        self.log.iter().map(|l| l.text.as_str())
    }

    /// The chosen method and its parameters.
    pub fn methods(&self) -> &MethodSettings {
        &self.methods
    }

    /// Changes parameters as the controls do (so with auto rebuild on, a
    /// build follows after the usual delay).
    pub fn set_methods(&mut self, methods: MethodSettings) {
        if methods != self.methods {
            self.methods = methods;
            self.parameters_changed();
        }
    }

    /// Builds the chosen method on the model on screen (starting at the next
    /// frame), replacing any build in progress.
    pub fn build(&mut self) {
        self.build_at = Some(BuildRequest::Now);
    }

    /// Whether a build is waiting to start or running.
    pub fn is_building(&self) -> bool {
        self.build_at.is_some() || self.build.is_some()
    }

    /// The last finished build of the model on screen.
    pub fn result(&self) -> Option<&Built> {
        self.result.as_ref()
    }

    /// Which version of the model the viewport shows.
    pub fn view(&self) -> View {
        self.view
    }

    /// Writes the last result to `path` (format by extension) on a worker
    /// thread, without a dialog; the outcome goes to the log.
    pub fn export_to(&mut self, path: impl Into<PathBuf>, ctx: &egui::Context) {
        let path = path.into();
        self.start_export(ctx, move |set| export::write(set, &path));
    }

    /// Whether an export (its dialog or its writing) is under way.
    pub fn is_exporting(&self) -> bool {
        self.export.is_some()
    }

    /// Draws the whole studio into `ui` (the root of the window).
    pub fn show(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        self.handle_global_input(&ctx);
        self.poll_picker();
        if let Some(path) = self.pending.take() {
            self.start_load(path, &ctx);
        }
        self.poll_job(&ctx);
        self.poll_build();
        self.poll_preview();
        self.poll_export();
        self.start_build_when_due(&ctx);
        self.autosave(&ctx);

        egui::Panel::top("menu").show(ui, |ui| self.menu_bar(ui));
        egui::Panel::bottom("status")
            .resizable(true)
            .default_size(110.0)
            .show(ui, |ui| self.status_panel(ui));
        egui::Panel::left("model")
            .default_size(250.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.left_panel(ui));
            });
        egui::Panel::right("inspector")
            .default_size(260.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.inspector(ui));
            });
        egui::CentralPanel::no_frame().show(ui, |ui| {
            self.view_bar(ui);
            self.update_cut();
            self.sync_view();
            if self.view == View::SideBySide && self.result.is_some() && self.preview.is_none() {
                self.show_side_by_side(ui);
            } else {
                self.viewport.show(ui);
            }
            self.pick();
        });
        self.frame_ms = ctx.input(|i| i.unstable_dt) * 1000.0;
        self.frame_stats.record(
            ctx.input(|i| i.time),
            self.frame_ms,
            self.cpu_ms,
            self.build.is_some(),
        );

        self.error_window(&ctx);
        drop_hint(&ctx);
        if self.job.is_some()
            || self.picker.is_some()
            || self.build.is_some()
            || self.export.is_some()
        {
            ctx.request_repaint_after(POLL_INTERVAL);
        }
    }

    /// Dropped files and the Ctrl+O shortcut.
    fn handle_global_input(&mut self, ctx: &egui::Context) {
        let open_shortcut = egui::KeyboardShortcut::new(egui::Modifiers::COMMAND, egui::Key::O);
        if ctx.input_mut(|i| i.consume_shortcut(&open_shortcut)) {
            self.open_dialog(ctx);
        }
        let (dropped, count) = ctx.input(|i| {
            let files = &i.raw.dropped_files;
            (files.first().map(|f| f.path().to_path_buf()), files.len())
        });
        if let Some(path) = dropped {
            if count > 1 {
                self.info(format!("{count} files dropped; opening only the first"));
            }
            self.open(path);
        }
    }

    /// Runs the native file dialog on a worker thread so the UI keeps drawing.
    fn open_dialog(&mut self, ctx: &egui::Context) {
        if self.picker.is_some() {
            return;
        }
        let (tx, rx) = mpsc::channel();
        let ctx = ctx.clone();
        let spawned = std::thread::Builder::new()
            .name("file dialog".into())
            .spawn(move || {
                let picked = rfd::FileDialog::new()
                    .set_title("Open model")
                    .add_filter("Models", MODEL_EXTENSIONS)
                    .add_filter("All files", &["*"])
                    .pick_file();
                let _ = tx.send(picked);
                ctx.request_repaint();
            });
        match spawned {
            Ok(_) => self.picker = Some(rx),
            Err(e) => self.error(format!("cannot open the file dialog: {e}")),
        }
    }

    fn poll_picker(&mut self) {
        let Some(rx) = &self.picker else {
            return;
        };
        match rx.try_recv() {
            Err(TryRecvError::Empty) => {}
            Ok(Some(path)) => {
                self.picker = None;
                self.open(path);
            }
            Ok(None) | Err(TryRecvError::Disconnected) => {
                self.picker = None;
                self.info("No file chosen (the dialog needs xdg-desktop-portal; dropping a file on the window works too)".into());
            }
        }
    }

    fn start_load(&mut self, path: PathBuf, ctx: &egui::Context) {
        if let Some(old) = self.job.take() {
            self.info(format!("Stopped loading {}", old.job.label()));
        }
        let name = display_name(&path);
        let worker_path = path.clone();
        let spawned = Job::spawn("model loader", name.clone(), ctx, move |progress| {
            let loaded = open(&worker_path, &LoadOptions::default(), progress);
            // A cancelled load may fail for that reason alone: say nothing.
            progress.check()?;
            let loaded = match loaded {
                Ok(loaded) => loaded,
                Err(e) => return Ok(Err(e)),
            };
            progress.stage("summarising");
            let summary = ModelSummary::of(&loaded);
            progress.check()?;
            progress.stage("preparing the view");
            let scene = Scene::from_model(&loaded.model);
            let volume = match &loaded.model {
                lodstudio_core::io::Model::Volume(v) => Some(VolumeGrid::of(v)),
                _ => None,
            };
            let reopened = if loaded.format == lodstudio_core::io::Format::Hierarchy {
                progress.stage("reopening the hierarchy");
                match build::reopen(&worker_path) {
                    Ok(r) => Some(r),
                    Err(e) => return Ok(Err(e)),
                }
            } else {
                None
            };
            Ok(Ok(Box::new(Finished {
                loaded,
                summary,
                scene,
                volume,
                reopened,
            })))
        });
        match spawned {
            Ok(job) => {
                self.info(format!("Loading {}", path.display()));
                self.job = Some(LoadJob { path, job });
            }
            Err(e) => self.load_failed(format!("cannot start loading {name}: {e}")),
        }
    }

    fn poll_job(&mut self, ctx: &egui::Context) {
        let Some(load) = &self.job else {
            return;
        };
        let outcome = match load.job.poll() {
            Poll::Running => return,
            Poll::Done(outcome) => outcome,
            Poll::Lost => {
                let msg = format!(
                    "{}: loading stopped unexpectedly (internal error)",
                    load.job.label()
                );
                self.job = None;
                self.load_failed(msg);
                return;
            }
        };
        let Some(LoadJob { path, job }) = self.job.take() else {
            return;
        };
        let name = job.label().to_string();
        match outcome {
            Ok(done) => {
                let Finished {
                    loaded,
                    summary,
                    scene,
                    volume,
                    reopened,
                } = *done;
                let seconds = job.elapsed().as_secs_f32();
                let counts = match (summary.triangles, summary.points) {
                    (0, 0) => summary.kind.to_string(),
                    (0, p) => format!("{p} points"),
                    (t, _) => format!("{t} triangles"),
                };
                self.info(format!(
                    "Loaded {name} ({}, {counts}) in {seconds:.2} s",
                    summary.format.name()
                ));
                self.forget_result();
                if volume.is_some() && self.threshold_volume.as_ref() != Some(&path) {
                    self.methods.voxel.threshold = None;
                    self.threshold_volume = Some(path.clone());
                }
                let scene = Arc::new(scene);
                self.viewport.frame_scene(Arc::clone(&scene));
                if !is_builtin(&path) {
                    self.remember(&path);
                }
                ctx.send_viewport_cmd(egui::ViewportCommand::Title(format!("lodstudio — {name}")));
                self.current = Some(Current {
                    rows: summary.lines(),
                    name,
                    path,
                    loaded: Arc::new(loaded),
                    summary,
                    scene,
                    volume,
                });
                if let Some(reopened) = reopened {
                    // Its parameters become the shown ones, so it is not stale.
                    self.methods = reopened.apply(self.methods);
                    let built = reopened.built(
                        &self.methods,
                        &self.viewport.core_view(),
                        self.methods.threshold.tolerance(),
                    );
                    self.info(format!(
                        "Reopened the saved {} hierarchy without rebuilding",
                        built.method().name()
                    ));
                    self.result = Some(built);
                    self.show_result();
                }
            }
            Err(e) => self.load_failed(e.to_string()),
        }
    }

    fn cancel_load(&mut self) {
        if let Some(load) = self.job.take() {
            self.info(format!("Cancelled loading {}", load.job.label()));
        }
    }

    /// A new model makes the last result (and any build of the old one) moot.
    fn forget_result(&mut self) {
        if let Some(old) = self.build.take() {
            self.info(format!("Stopped building {}", old.label()));
        }
        self.result = None;
        self.build_at = None;
        self.build_note = None;
    }

    /// Whether the chosen method can build the model on screen (`None`
    /// without a model), or why not.
    fn input_check(&self) -> Option<Result<(), String>> {
        self.current
            .as_ref()
            .map(|c| build::check(self.methods.method, &c.path, &c.loaded.model))
    }

    /// After a parameter changed: schedule a rebuild if wanted and possible.
    fn parameters_changed(&mut self) {
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
    fn start_build_when_due(&mut self, ctx: &egui::Context) {
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
                let settings = crate::panels::amg::AmgSettings {
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

    fn poll_build(&mut self) {
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

    fn cancel_build(&mut self) {
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

    /// Inspects what a click in the viewport hit on the live cut.
    fn pick(&mut self) {
        let Some((origin, dir)) = self.viewport.take_click() else {
            return;
        };
        let Some(live) = self.result.as_ref().and_then(|b| b.live.as_ref()) else {
            return;
        };
        let diagonal = self
            .current
            .as_ref()
            .map_or(1.0, |c| c.scene.bounds().diagonal())
            .max(f32::MIN_POSITIVE);
        let bound = |e: f32| format!("bound {} ({:.3} %)", build::length(e), 100.0 * e / diagonal);
        let set = live.draw_set();
        // Merge-tree triangles also tell their tree level.
        let level = |t: usize| {
            set.triangle_levels
                .get(t)
                .map_or(String::new(), |l| format!(", level {l}"))
        };
        self.picked = Some(match set.pick(origin, dir) {
            None => "nothing under the pointer".to_string(),
            Some((_, Picked::Triangle { index, error })) => match error {
                Some(e) => format!("triangle {index}, {}{}", bound(e), level(index)),
                None => format!("triangle {index}{}", level(index)),
            },
            Some((
                _,
                Picked::Point {
                    index,
                    radius,
                    error,
                },
            )) => {
                format!(
                    "point {index}, radius {}, {}",
                    build::length(radius),
                    bound(error)
                )
            }
            Some((_, Picked::Splat { index, domain })) => format!("splat {index}, domain {domain}"),
            Some((_, Picked::Layer { layer, isodensity })) => {
                format!("voxel layer {layer}, isodensity {isodensity:.3}")
            }
        });
    }

    /// The latest intermediate state of the running build, as a scene.
    fn poll_preview(&mut self) {
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

    /// Re-selects a live cut for the camera and the threshold (only when the
    /// hierarchy says they change it).
    fn update_cut(&mut self) {
        let heat = self.heat && self.view.shows_lod();
        if let Some(live) = self.result.as_mut().and_then(|b| b.live.as_mut()) {
            live.set_style(CutStyle {
                heat,
                by_type: self.by_type && self.view.shows_lod(),
                regions: self.regions && self.view.shows_lod(),
                outlines: self.outlines,
            });
            let mut view = self.viewport.core_view();
            let input_triangles = self
                .current
                .as_ref()
                .and_then(|c| build::mesh_of(&c.loaded.model).ok())
                .map_or(0, |m| m.triangles.len());
            let mt = &self.methods.merge_tree;
            if let Some(light) = mt.light() {
                view.light_dir = light;
            }
            live.set_knobs(&lodstudio_core::lod::Knobs {
                criteria: lodstudio_core::lod::Criteria {
                    backface: mt.backface,
                    silhouette: mt.silhouette,
                    lighting: mt.lighting,
                },
                pyramid_position: self.methods.voxel.runtime_position(),
                amg_level: self.methods.amg.runtime_level(),
                collapse: self.methods.edge_collapse.runtime(input_triangles),
            });
            live.update(&view, self.methods.threshold.tolerance());
        }
    }

    /// Shows the scene the view toggles ask for (uploads only on a change).
    fn sync_view(&mut self) {
        let Some(current) = &self.current else {
            return;
        };
        if let Some(preview) = &self.preview {
            // Watching the build: its intermediate state.
            self.viewport.swap_scene(preview);
            return;
        }
        let scene = match (&self.result, self.view) {
            (Some(built), View::Simplified | View::SideBySide) => match &built.live {
                Some(live) => live.scene(),
                None => &built.scene,
            },
            _ => &current.scene,
        };
        self.viewport.swap_scene(scene);
    }

    /// Shows a new result, side by side with the original if that is the view.
    fn show_result(&mut self) {
        if self.view == View::Original {
            self.view = View::Simplified;
        }
    }

    /// Compares the original (left) with the result (right, the main viewport:
    /// cuts are taken and picked there) through one camera.
    fn show_side_by_side(&mut self, ui: &mut egui::Ui) {
        let Some(current) = &self.current else {
            return;
        };
        self.compare.swap_scene(&current.scene);
        self.compare.follow(&self.viewport);
        let full = ui.available_rect_before_wrap();
        let (left, right) = full.split_left_right_at_fraction(0.5);
        let gap = egui::vec2(1.0, 0.0);
        ui.scope_builder(egui::UiBuilder::new().max_rect(left.shrink2(gap)), |ui| {
            self.compare.show(ui);
        });
        if !self.compare.same_camera(&self.viewport) {
            self.viewport.follow(&self.compare);
        }
        ui.scope_builder(egui::UiBuilder::new().max_rect(right.shrink2(gap)), |ui| {
            self.viewport.show(ui);
        });
    }

    /// Runs `write` (which may show a dialog) on the last result, on a worker.
    fn start_export(
        &mut self,
        ctx: &egui::Context,
        write: impl FnOnce(&lodstudio_core::lod::DrawSet) -> Saved + Send + 'static,
    ) {
        if self.export.is_some() {
            return;
        }
        let Some(built) = &self.result else {
            self.error("Nothing to export yet: build a LOD first".into());
            return;
        };
        // What is on screen: a live cut, every primitive of it, or the built mesh.
        let set = match &built.live {
            Some(live) => live.draw_set().clone(),
            None => lodstudio_core::lod::DrawSet {
                mesh: built.mesh().clone(),
                ..Default::default()
            },
        };
        match Job::spawn("export", "Exporting".into(), ctx, move |_| Ok(write(&set))) {
            Ok(job) => self.export = Some(job),
            Err(e) => self.error(format!("cannot start the export: {e}")),
        }
    }

    /// The running result's hierarchy as saved-hierarchy bytes, with the shown
    /// parameters of its method.
    fn hierarchy_bytes(&self) -> Option<Vec<u8>> {
        let live = self.result.as_ref()?.live.as_ref()?;
        let m = &self.methods;
        let params = match m.method {
            Method::Hybrid => serde_json::json!({"kappa": m.hybrid.kappa, "tau": m.hybrid.tau}),
            Method::MergeTree => serde_json::json!({
                "min_vertices": m.merge_tree.min_vertices,
                "min_quality": m.merge_tree.min_quality,
            }),
            Method::Voxel => {
                serde_json::json!({"resolution": m.voxel.resolution, "radius": m.voxel.radius})
            }
            Method::Amg => serde_json::json!({"k": m.amg.k}),
            Method::EdgeCollapse => serde_json::json!({
                "lock_borders": m.edge_collapse.lock_borders,
                "min_quality": m.edge_collapse.min_quality,
                "min_normal_cos": m.edge_collapse.min_normal_cos,
            }),
        };
        live.save(&params)
    }

    /// Saves the built hierarchy to `path` on a worker (no dialog).
    pub fn save_hierarchy_to(&mut self, path: impl Into<PathBuf>, ctx: &egui::Context) {
        let path = path.into();
        match self.hierarchy_bytes() {
            Some(bytes) => self.spawn_save(ctx, move || export::write_bytes(&bytes, &path)),
            None => self.error(
                "Nothing to save: only whole hierarchies save (hybrid, merge tree, voxel pyramid)"
                    .into(),
            ),
        }
    }

    fn save_hierarchy_dialog(&mut self, ctx: &egui::Context) {
        let (Some(current), Some(bytes)) = (&self.current, self.hierarchy_bytes()) else {
            self.error(
                "Nothing to save: only whole hierarchies save (hybrid, merge tree, voxel pyramid)"
                    .into(),
            );
            return;
        };
        let name = format!(
            "{}.lodh",
            current
                .name
                .trim_start_matches("builtin:")
                .split('.')
                .next()
                .unwrap_or("model")
        );
        self.spawn_save(ctx, move || {
            export::choose_and_write_hierarchy(&bytes, &name)
        });
    }

    /// Runs a save (dialog and writing) on a worker, reported like exports.
    fn spawn_save(&mut self, ctx: &egui::Context, save: impl FnOnce() -> Saved + Send + 'static) {
        if self.export.is_some() {
            return;
        }
        match Job::spawn("export", "Saving".into(), ctx, move |_| Ok(save())) {
            Ok(job) => self.export = Some(job),
            Err(e) => self.error(format!("cannot start saving: {e}")),
        }
    }

    fn export_dialog(&mut self, ctx: &egui::Context) {
        let (Some(current), Some(built)) = (&self.current, &self.result) else {
            return;
        };
        let name = export::suggested_name(&current.path, built.mesh().triangles.len());
        self.start_export(ctx, move |set| export::choose_and_write(set, &name));
    }

    fn poll_export(&mut self) {
        let Some(job) = &self.export else {
            return;
        };
        let saved = match job.poll() {
            Poll::Running => return,
            Poll::Done(saved) => saved,
            Poll::Lost => Saved::Failed("the export stopped unexpectedly (internal error)".into()),
        };
        self.export = None;
        match saved {
            Saved::Written {
                path,
                bytes,
                beside,
            } => {
                let beside: Vec<String> = beside.iter().map(|p| p.display().to_string()).collect();
                let also = if beside.is_empty() {
                    String::new()
                } else {
                    format!(", with {}", beside.join(", "))
                };
                self.info(format!("Exported {}{also} ({bytes} bytes)", path.display()));
            }
            Saved::NoFile => self.info(
                "Nothing exported: no file chosen (the dialog needs xdg-desktop-portal)".into(),
            ),
            Saved::Failed(message) => self.error(format!("Export failed: {message}")),
        }
    }

    /// Puts `path` first in the recent list.
    fn remember(&mut self, path: &Path) {
        let path = path
            .canonicalize()
            .or_else(|_| std::path::absolute(path))
            .unwrap_or_else(|_| path.to_path_buf());
        self.recent.retain(|p| *p != path);
        self.recent.insert(0, path);
        self.recent.truncate(MAX_RECENT);
    }

    fn info(&mut self, text: String) {
        self.push_log(text, false);
    }

    fn error(&mut self, text: String) {
        self.push_log(text, true);
    }

    fn load_failed(&mut self, text: String) {
        self.error(text.clone());
        self.error = Some(text);
    }

    fn push_log(&mut self, text: String, error: bool) {
        if self.log.len() >= MAX_LOG {
            self.log.drain(..MAX_LOG / 10);
        }
        self.log.push(LogLine { text, error });
    }

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.button("Open…").clicked() {
                    self.open_dialog(ui.ctx());
                }
                ui.menu_button("Built-in models", |ui| {
                    for (name, description) in builtins::NAMES {
                        if ui.button(*name).on_hover_text(*description).clicked() {
                            self.open(format!("builtin:{name}"));
                        }
                    }
                });
                ui.add_enabled_ui(!self.recent.is_empty(), |ui| {
                    ui.menu_button("Recent files", |ui| {
                        if let Some(path) = self.recent_list(ui) {
                            self.open(path);
                        }
                    });
                });
                ui.separator();
                if ui.button("Quit").clicked() {
                    ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                }
            });
        });
    }

    /// Buttons for the recent files; returns the one clicked.
    fn recent_list(&self, ui: &mut egui::Ui) -> Option<PathBuf> {
        let mut clicked = None;
        for path in &self.recent {
            let name = path
                .file_name()
                .map_or_else(|| path.to_string_lossy(), |n| n.to_string_lossy());
            if ui
                .button(name)
                .on_hover_text(path.display().to_string())
                .clicked()
            {
                clicked = Some(path.clone());
            }
        }
        clicked
    }

    /// The model section, then the method section, scrolling together.
    fn left_panel(&mut self, ui: &mut egui::Ui) {
        egui::ScrollArea::vertical().show(ui, |ui| {
            self.model_section(ui);
            ui.separator();
            self.method_section(ui);
        });
    }

    fn model_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Model");
        match &self.current {
            Some(c) => {
                ui.label(egui::RichText::new(&c.name).strong())
                    .on_hover_text(c.path.display().to_string());
            }
            None => {
                ui.label("No model loaded");
            }
        }
        if ui.button("Open…").clicked() {
            self.open_dialog(ui.ctx());
        }
        egui::CollapsingHeader::new("Built-in models")
            .default_open(true)
            .show(ui, |ui| {
                for (name, description) in builtins::NAMES {
                    if ui.button(*name).on_hover_text(*description).clicked() {
                        self.open(format!("builtin:{name}"));
                    }
                }
            });
        egui::CollapsingHeader::new("Recent files")
            .default_open(true)
            .show(ui, |ui| {
                if self.recent.is_empty() {
                    ui.weak("none yet");
                } else if let Some(path) = self.recent_list(ui) {
                    self.open(path);
                }
            });
    }

    /// The method list, its parameters, and Build / Export.
    fn method_section(&mut self, ui: &mut egui::Ui) {
        ui.heading("Method");
        let mut changed = self.methods.method_list(ui);
        ui.add_space(4.0);
        let input_triangles = self
            .current
            .as_ref()
            .and_then(|c| build::mesh_of(&c.loaded.model).ok())
            .map(|m| m.triangles.len());
        match self.methods.method {
            Method::EdgeCollapse => {
                changed |= self.methods.edge_collapse.ui(ui, input_triangles);
            }
            Method::Voxel => {
                let volume = self.current.as_ref().and_then(|c| c.volume);
                changed |= self.methods.voxel.ui(ui, volume.as_ref());
            }
            Method::Hybrid => {
                changed |= self.methods.hybrid.ui(ui);
            }
            Method::Amg => {
                let levels = self
                    .result
                    .as_ref()
                    .filter(|b| b.method() == Method::Amg)
                    .and_then(|b| b.plots.first())
                    .and_then(|p| p.series.first())
                    .map(|s| s.1.len());
                changed |= self.methods.amg.ui(ui, levels);
            }
            Method::MergeTree => {
                // Criteria changes re-cut the live tree; only build options rebuild.
                changed |= self.methods.merge_tree.ui(ui).0;
            }
        }
        if self.result.as_ref().is_some_and(|b| b.live.is_some()) {
            ui.add_space(4.0);
            ui.label("Cut").on_hover_text(
                "The built hierarchy is cut live for the camera: no rebuild needed.",
            );
            self.methods.threshold.ui(ui);
        }
        ui.add_space(4.0);
        let auto = ui
            .checkbox(&mut self.methods.auto_rebuild, "Auto rebuild")
            .on_hover_text("Rebuild by itself 0.4 s after the last parameter change.");
        if changed || (auto.changed() && self.methods.auto_rebuild && self.result_is_stale()) {
            self.parameters_changed();
        }
        let input = self.input_check();
        let can_build = matches!(input, Some(Ok(())));
        ui.horizontal(|ui| {
            let build = ui
                .add_enabled(can_build, egui::Button::new("Build"))
                .on_hover_text("Build the LOD now with these parameters.");
            if build.clicked() {
                self.build();
            }
            let can_export = self.result.is_some() && self.export.is_none();
            let export = ui
                .add_enabled(can_export, egui::Button::new("Export…"))
                .on_hover_text("Save the simplified mesh as glb, obj or ply.")
                .on_disabled_hover_text("Build a LOD first.");
            if export.clicked() {
                self.export_dialog(ui.ctx());
            }
            let can_save = self.export.is_none()
                && self.result.as_ref().is_some_and(|b| b.live.is_some());
            let save = ui
                .add_enabled(can_save, egui::Button::new("Save hierarchy…"))
                .on_hover_text("Save the built hierarchy (versioned, checksummed .lodh) to reopen it later without rebuilding.")
                .on_disabled_hover_text("Build a hybrid, merge-tree or voxel-pyramid hierarchy first.");
            if save.clicked() {
                self.save_hierarchy_dialog(ui.ctx());
            }
        });
        let error_color = ui.visuals().error_fg_color;
        if let Some(Err(why)) = &input {
            ui.colored_label(error_color, why);
        } else if let Some(note) = &self.build_note {
            ui.colored_label(error_color, note);
        } else if self.result.is_some() && !self.is_building() && self.result_is_stale() {
            ui.weak("Parameters changed since the last build.");
        }
    }

    /// Whether the result (if any) was built with other parameters than shown.
    fn result_is_stale(&self) -> bool {
        self.result
            .as_ref()
            .is_none_or(|r| r.params != self.methods.params(self.volume_grid()))
    }

    /// The grid of the model on screen, when it is a volume.
    fn volume_grid(&self) -> Option<&VolumeGrid> {
        self.current.as_ref().and_then(|c| c.volume.as_ref())
    }

    /// Original / simplified toggle and the heat-map switch above the viewport.
    fn view_bar(&mut self, ui: &mut egui::Ui) {
        let has_result = self.result.is_some();
        let has_heat = self
            .result
            .as_ref()
            .is_some_and(|r| r.live.as_ref().is_some_and(|l| l.has_errors()));
        // Without a result the original is what is shown, whatever was chosen.
        let mut shown = if has_result {
            self.view
        } else {
            View::Original
        };
        let mut heat = self.heat;
        egui::Frame::new()
            .inner_margin(egui::Margin::symmetric(6, 3))
            .show(ui, |ui| {
                ui.horizontal_wrapped(|ui| {
                    ui.add_enabled_ui(has_result, |ui| {
                        ui.selectable_value(&mut shown, View::Original, "Original")
                            .on_hover_text("Show the model as opened.");
                        ui.selectable_value(&mut shown, View::Simplified, "Simplified")
                            .on_hover_text("Show the last build's result.")
                            .on_disabled_hover_text("Build a LOD first.");
                        ui.selectable_value(&mut shown, View::SideBySide, "Side by side")
                            .on_hover_text(
                                "The original on the left, the result on the right, seen through \
                                 one camera: orbiting either turns both.",
                            )
                            .on_disabled_hover_text("Build a LOD first.");
                        ui.separator();
                        ui.add_enabled(
                            shown.shows_lod() && has_heat,
                            egui::Checkbox::new(&mut heat, "Colour by certified bound"),
                        )
                        .on_hover_text(
                            "Colour each simplified triangle (and each point of a hybrid cut) \
                             by its guaranteed error bound, from dark (near 0) to yellow (the \
                             largest).",
                        )
                        .on_disabled_hover_text(
                            "Only edge collapse, hybrid and merge-tree cuts carry a bound per \
                             primitive.",
                        );
                    });
                    ui.separator();
                    let live = self.result.as_ref().is_some_and(|b| b.live.is_some());
                    ui.add_enabled(
                        live,
                        egui::Checkbox::new(&mut self.by_type, "Colour by type"),
                    )
                    .on_hover_text("Triangles orange, points blue; splats keep their textures.")
                    .on_disabled_hover_text("Build a hierarchy first.");
                    let region = self.result.as_ref().and_then(|b| {
                        let live = b.live.as_ref()?;
                        live_cut::region_name(live.method()).filter(|_| live.has_regions())
                    });
                    ui.add_enabled(
                        region.is_some(),
                        egui::Checkbox::new(
                            &mut self.regions,
                            format!("Colour by {}", region.unwrap_or("region")),
                        ),
                    )
                    .on_hover_text(
                        "Merge tree: each triangle by the highest tree level among its display \
                         vertices (dark: original, yellow: the coarsest). AMG: each domain \
                         primitive in a hue of its own. Voxel: each translucent layer in a hue \
                         of its own.",
                    )
                    .on_disabled_hover_text(
                        "Merge-tree cuts, AMG splats and layered voxel cuts have regions.",
                    );
                    ui.add_enabled(
                        live,
                        egui::Checkbox::new(&mut self.outlines, "Splat outlines"),
                    )
                    .on_hover_text("Outline every domain primitive (AMG paper, Fig. 12).")
                    .on_disabled_hover_text("Build a hierarchy first.");
                    ui.separator();
                    ui.checkbox(&mut self.viewport.fly, "Fly").on_hover_text(
                        "Walk through the scene: W/S forward and back, A/D sideways, Q/E down \
                         and up (Shift: faster); drag to look around.",
                    );
                });
            });
        if has_result {
            self.view = shown;
            self.heat = heat;
        }
    }

    fn inspector(&self, ui: &mut egui::Ui) {
        ui.heading("Inspector");
        let Some(current) = &self.current else {
            ui.label("No model loaded");
            return;
        };
        egui::ScrollArea::vertical().show(ui, |ui| {
            egui::Grid::new("inspector grid")
                .num_columns(2)
                .striped(true)
                .show(ui, |ui| {
                    for (label, value) in &current.rows {
                        ui.label(label);
                        ui.label(value);
                        ui.end_row();
                    }
                });
            if let Some(built) = &self.result {
                ui.separator();
                ui.label(egui::RichText::new(built.method().name()).strong());
                egui::Grid::new("build grid")
                    .num_columns(2)
                    .striped(true)
                    .show(ui, |ui| {
                        for row in &built.rows {
                            ui.label(row.label).on_hover_text(row.hint);
                            ui.label(&row.value);
                            ui.end_row();
                        }
                    });
                for plot in &built.plots {
                    ui.separator();
                    ui.label(plot.title);
                    let mut chart = egui_plot::Plot::new(plot.title)
                        .height(140.0)
                        .x_axis_label(plot.x_label)
                        .y_axis_label(if plot.log_y {
                            format!("log10 {}", plot.y_label)
                        } else {
                            plot.y_label.to_string()
                        })
                        .allow_scroll(false)
                        .legend(egui_plot::Legend::default());
                    chart = chart.allow_drag(false);
                    chart.show(ui, |p| {
                        for (name, points) in &plot.series {
                            let pts: Vec<[f64; 2]> = points
                                .iter()
                                .map(|&[x, y]| [x, if plot.log_y { y.max(1e-12).log10() } else { y }])
                                .collect();
                            p.line(egui_plot::Line::new(name.as_str(), egui_plot::PlotPoints::from(pts)));
                        }
                    });
                }
                if let Some(live) = &built.live {
                    ui.separator();
                    ui.label(egui::RichText::new("Cut").strong());
                    let st = live.stats;
                    let pixels = self.viewport.core_view().pixels(
                        st.error_bound,
                        self.viewport.target,
                        0.0,
                    );
                    egui::Grid::new("cut grid").num_columns(2).striped(true).show(ui, |ui| {
                        let diagonal = current.scene.bounds().diagonal().max(f32::MIN_POSITIVE);
                        for (label, value, hint) in [
                            ("cut triangles", st.triangles.to_string(), "Triangles on the current cut."),
                            ("cut points", st.points.to_string(), "Point primitives (discs) on the current cut."),
                            ("cut splats", st.splats.to_string(), "Textured domain primitives on the current cut."),
                            ("layer triangles", st.layer_triangles.to_string(), "Triangles of the translucent voxel layers."),
                            ("cut bound", format!("{} ({:.3} %)", build::length(st.error_bound), 100.0 * st.error_bound / diagonal), "The cut's object-space error bound (max over its elements)."),
                            ("bound is", st.error_bound_kind.name().to_string(), "Certified: no point of the cut or of the original lies farther than the bound from the other (a dense measurement never exceeds it). Estimate: a measure of the method's own (AMG: the largest distance of a domain's points to its splat's plane), not a bound on the distance to the original."),
                            ("bound at target", format!("{pixels:.2} px"), "The cut's bound projected at the camera's target distance."),
                            ("cut time", format!("{:.2} ms", st.cut_ms), "Time of the last re-selection of the cut and its scene."),
                            ("frame time", self.frame_summary(), "Median time between frames of the studio over the last second, and the median CPU time of a frame (layout, cut, tessellation and submitting the draw)."),
                            ("picked", self.picked.clone().unwrap_or_else(|| "click the model".into()), "What the last click in the viewport hit on the cut: its type, index and error bound (or domain, layer)."),
                        ] {
                            ui.label(label).on_hover_text(hint);
                            ui.label(value);
                            ui.end_row();
                        }
                    });
                }
                if let Some(live) = built.live.as_ref().filter(|l| l.has_errors())
                    && self.heat
                    && self.view.shows_lod()
                {
                    ui.add_space(4.0);
                    ui.label("error bound per primitive");
                    heatmap::legend(ui, &build::length(live.stats.error_bound));
                }
            }
        });
    }

    fn status_panel(&mut self, ui: &mut egui::Ui) {
        if self.job.as_ref().is_some_and(|l| l.job.progress_row(ui)) {
            self.cancel_load();
        }
        if self.build.as_ref().is_some_and(|b| b.progress_row(ui)) {
            self.cancel_build();
        }
        if self.build.is_some() {
            // The UI keeps its frame rate while the worker builds: show it.
            ui.weak(format!("frame {}", self.frame_summary()))
                .on_hover_text("Time between frames, and the CPU time of the last frame.");
        }
        let row_height = ui.text_style_height(&egui::TextStyle::Body);
        let error_color = ui.visuals().error_fg_color;
        egui::ScrollArea::vertical()
            .auto_shrink([false, false])
            .stick_to_bottom(true)
            .show_rows(ui, row_height, self.log.len(), |ui, rows| {
                for line in &self.log[rows] {
                    if line.error {
                        ui.colored_label(error_color, &line.text);
                    } else {
                        ui.label(&line.text);
                    }
                }
            });
    }

    /// "16.7 ms (CPU 3.2 ms)": the median frame interval over the last second
    /// and, under eframe, the median CPU time (the last frame's until a second
    /// has passed).
    fn frame_summary(&self) -> String {
        let stats = &self.frame_stats;
        let (interval, cpu) = if stats.median_ms > 0.0 {
            (stats.median_ms, stats.median_cpu_ms)
        } else {
            (self.frame_ms, self.cpu_ms)
        };
        match cpu {
            Some(cpu) => format!("{interval:.1} ms (CPU {cpu:.1} ms)"),
            None => format!("{interval:.1} ms"),
        }
    }

    /// A dismissable window with the last load error.
    fn error_window(&mut self, ctx: &egui::Context) {
        let Some(message) = &self.error else {
            return;
        };
        let mut dismissed = false;
        egui::Window::new("Could not open model")
            .collapsible(false)
            .resizable(false)
            .anchor(egui::Align2::CENTER_CENTER, [0.0, 0.0])
            .show(ctx, |ui| {
                ui.colored_label(ui.visuals().error_fg_color, message);
                ui.label("The previous model is still open.");
                dismissed = ui.button("OK").clicked();
            });
        if dismissed {
            self.error = None;
        }
    }
}

impl eframe::App for StudioApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        self.cpu_ms = frame.info().cpu_usage.map(|s| s * 1000.0);
        self.show(ui);
    }

    fn on_exit(&mut self) {
        let session = self.session();
        if let Err(e) = self.autosave.save_now(&session) {
            eprintln!("lodstudio: {e}");
        }
    }
}

/// Tells the user a file dragged over the window will open when dropped.
fn drop_hint(ctx: &egui::Context) {
    if ctx.input(|i| i.raw.hovered_files.is_empty()) {
        return;
    }
    let painter = ctx.layer_painter(egui::LayerId::new(
        egui::Order::Foreground,
        egui::Id::unique("drop hint"),
    ));
    let rect = ctx.content_rect();
    painter.rect_filled(rect, 0.0, egui::Color32::from_black_alpha(160));
    painter.text(
        rect.center(),
        egui::Align2::CENTER_CENTER,
        "Drop to open",
        egui::FontId::proportional(28.0),
        egui::Color32::WHITE,
    );
}
