//! The studio window: menu, model list, LOD method and its parameters, 3D
//! viewport, inspector and log. This file is the frame loop and the state it
//! works on; each part of the window and each kind of job has its own file.
//!
//! Everything slow (loading, summarising, building a LOD, preparing GPU
//! geometry, file dialogs, exporting) runs on worker threads; the UI polls
//! them each frame so it never blocks, and a failed or cancelled load or build
//! keeps the previous model and result.

pub mod asset;
mod building;
mod chain;
mod chain_glue;
mod cut;
mod inspector;
mod left_panel;
mod loading;
mod menu;
mod saving;
mod status;
mod tileset;
mod view_bar;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::Receiver;
use std::time::Duration;

use lodstudio_core::io::Loaded;
use lodstudio_core::stats::ModelSummary;

use self::building::BuildRequest;
pub use self::chain::{BuiltChain, LodDifference};
use self::loading::{LoadJob, MAX_RECENT, absolute, default_model, display_name, is_builtin};
use self::status::{LogLine, drop_hint};
pub use self::view_bar::View;
use crate::build::Built;
use crate::export::{self, Saved};
use crate::frame_stats::FrameStats;
use crate::job::Job;
use crate::render::{Scene, Viewport};
use crate::session::{Autosave, Session};
use crate::settings::MethodSettings;
use crate::settings::tiles::TilesSettings;
use crate::settings::voxel::VolumeGrid;

/// How often the UI refreshes the progress bar while a worker runs (input
/// still draws at once; the worker also wakes the UI the moment it ends);
/// a build running longer than [`LONG_BUILD`] refreshes at [`LONG_POLL_INTERVAL`].
/// Under a software renderer a frame costs ~55 ms of CPU, so polling at 20 Hz
/// took both cores from the build (horse edge collapse 26.6 s in the studio
/// against 4.65 s on the CLI); at 4 Hz it takes 5.2–5.6 s
/// (benchmarks/studio.md, "Builds against the CLI").
const POLL_INTERVAL: Duration = Duration::from_millis(250);
/// Past this, a build's progress moves slowly: a frame a second shows it,
/// and each frame less gives the build ~55 ms of CPU under lavapipe (2 s
/// before: the horse's default chain took 1.1–1.6× the CLI's time, now
/// 0.99–1.24×; benchmarks/studio.md).
const LONG_BUILD: Duration = Duration::from_secs(1);
const LONG_POLL_INTERVAL: Duration = Duration::from_secs(1);
/// Between the frames of a playing animation.
const ASSET_FRAME: Duration = Duration::from_millis(33);

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
    /// The same with its wireframe, made the first time it is asked for.
    wire_scene: Option<Arc<Scene>>,
    /// The grid and value range of a volume model.
    volume: Option<VolumeGrid>,
    /// A built-in implicit's exact solid (voxel builds sample it).
    solid: Option<Arc<dyn lodstudio_core::implicit::Implicit>>,
}

impl Current {
    /// What builds work on.
    fn source(&self) -> crate::build::Source {
        crate::build::Source {
            loaded: Arc::clone(&self.loaded),
            solid: self.solid.clone(),
        }
    }

    /// Its triangle mesh, if it is one with triangles.
    fn mesh(&self) -> Option<&lodstudio_core::TriMesh> {
        match &self.loaded.model {
            lodstudio_core::io::Model::Mesh(m) if !m.triangles.is_empty() => Some(m),
            _ => None,
        }
    }
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
    build: Option<Job<Result<Built, lodstudio_core::lod::BuildError>>>,
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
    /// Triangle edges drawn over the original and the cut.
    wireframe: bool,
    /// A build asked for but not started yet.
    build_at: Option<BuildRequest>,
    /// Why the last build request failed, shown under the Build button.
    build_note: Option<String>,
    view: View,
    /// Colour the simplified mesh by each triangle's certified bound.
    heat: bool,
    export: Option<Job<Saved>>,
    /// The LOD chain: its rows, their build, the switch preview.
    chain: chain::ChainState,
    /// The GPU device the viewports draw with, for off-screen renders.
    render_state: Option<egui_wgpu::RenderState>,
    autosave: Autosave,
    /// The in-app file browser, where the desktop has no dialog.
    file_dialog: crate::file_dialog::InApp,
    /// A glTF scene's nodes, meshes, chains and animations.
    asset: Option<asset::AssetState>,
    /// A 3D Tiles tileset on screen (instead of a model).
    tileset: Option<crate::tileset_view::TilesetView>,
    /// Its load, or a tileset's build.
    tileset_job: Option<Job<Result<tileset::TilesetDone, String>>>,
    tiles: TilesSettings,
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
                self.chain.settings = session.chain;
                self.chain.recent_recipes = session.recent_recipes;
                self.tiles = session.tiles;
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
            Err(e) => self.error(e.to_string()),
        }
        let kept = autosave.file().and_then(Path::parent);
        self.chain
            .keep_in(kept.map(|dir| dir.join(chain::kept::FILE_NAME)));
        self.autosave = autosave;
    }

    /// What the autosave keeps.
    fn session(&self) -> Session {
        Session {
            model: self
                .current
                .as_ref()
                .map(|c| absolute(&c.path))
                .or_else(|| self.tileset.as_ref().map(|t| absolute(&t.path))),
            recent: self.recent.clone(),
            methods: self.methods,
            chain: self.chain.settings.clone(),
            recent_recipes: self.chain.recent_recipes.clone(),
            volume_threshold: self
                .threshold_volume
                .as_deref()
                .map(absolute)
                .zip(self.methods.voxel.threshold.filter(|t| t.is_finite())),
            tiles: self.tiles,
        }
    }

    /// Autosaves when a check is due; otherwise asks for a frame when it will
    /// be, so the last change before the studio goes idle is saved too.
    fn autosave(&mut self, ctx: &egui::Context) {
        match self.autosave.wait() {
            Some(wait) if wait.is_zero() => {
                let session = self.session();
                if let Err(e) = self.autosave.offer(&session) {
                    self.error(e.to_string());
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
            wireframe: false,
            build_at: None,
            build_note: None,
            view: View::Simplified,
            heat: false,
            export: None,
            chain: chain::ChainState::default(),
            render_state: render_state.cloned(),
            autosave: Autosave::off(),
            file_dialog: Default::default(),
            asset: None,
            tileset: None,
            tileset_job: None,
            tiles: TilesSettings::default(),
        }
    }

    /// Starts loading `path` (a file or `builtin:NAME`) in the background,
    /// cancelling any load in progress.
    pub fn open(&mut self, path: impl Into<PathBuf>) {
        self.pending = Some(path.into());
    }

    /// Whether a model or a tileset is being read (or a tileset built).
    pub fn is_loading(&self) -> bool {
        self.pending.is_some() || self.job.is_some() || self.tileset_job.is_some()
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
    /// How soon the studio wants its next frame while workers run, with no
    /// input (`None`: not before the next input): at [`POLL_INTERVAL`], or at
    /// [`LONG_POLL_INTERVAL`] while only builds older than [`LONG_BUILD`] run.
    pub fn poll_interval(&self) -> Option<Duration> {
        if self
            .asset
            .as_ref()
            .is_some_and(asset::AssetState::is_moving)
        {
            // An animation playing: a new pose every frame, at most 30 a second.
            return Some(ASSET_FRAME);
        }
        let quick = self.job.is_some()
            || self.tileset_job.is_some()
            || self.tileset.as_ref().is_some_and(|t| t.is_making())
            || self.picker.is_some()
            || self.export.is_some()
            || self.is_measuring_difference();
        let builds = [
            self.build.as_ref().map(Job::elapsed),
            self.chain.building_for(),
            self.asset
                .as_ref()
                .and_then(asset::AssetState::building_for),
        ];
        let long = builds.iter().flatten().all(|t| *t > LONG_BUILD);
        match builds.iter().flatten().next() {
            _ if quick => Some(POLL_INTERVAL),
            Some(_) if long => Some(LONG_POLL_INTERVAL),
            Some(_) => Some(POLL_INTERVAL),
            None => None,
        }
    }

    /// A finished asset build, and the clock of a playing animation.
    fn poll_asset(&mut self, ctx: &egui::Context) {
        let Some(asset) = &mut self.asset else {
            return;
        };
        let message = asset.poll();
        asset.tick(ctx.input(|i| i.stable_dt).min(0.1));
        if let Some(m) = message {
            self.info(m);
        }
    }

    /// The glTF asset on screen (its outliner, chains and timeline).
    pub fn asset(&self) -> Option<&asset::AssetState> {
        self.asset.as_ref()
    }

    pub fn asset_mut(&mut self) -> Option<&mut asset::AssetState> {
        self.asset.as_mut()
    }

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
        self.poll_chain(&ctx);
        self.poll_asset(&ctx);
        self.poll_tileset(&ctx);
        self.start_build_when_due(&ctx);
        self.autosave(&ctx);

        egui::Panel::top("menu").show(ui, |ui| self.menu_bar(ui));
        egui::Panel::bottom("status")
            .resizable(true)
            .default_size(110.0)
            .show(ui, |ui| self.status_panel(ui));
        egui::Panel::left("model")
            .default_size(250.0)
            .show(ui, |ui| self.left_panel(ui));
        egui::Panel::right("inspector")
            .default_size(260.0)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.inspector(ui));
            });
        egui::CentralPanel::no_frame().show(ui, |ui| {
            // The chain under the viewport; the side panels keep their height.
            egui::Panel::bottom("chain")
                .resizable(true)
                .default_size(240.0)
                .show(ui, |ui| self.chain_panel(ui));
            self.view_bar(ui);
            self.update_cut();
            self.sync_view();
            if self.view == View::SideBySide && self.has_lod() && self.preview.is_none() {
                self.show_side_by_side(ui);
            } else {
                let viewport = self.viewport.show(ui);
                // During the switch preview: which LOD is drawn, over it.
                if let Some(text) = self.chain.overlay(self.viewport.camera.distance) {
                    egui::Area::new(egui::Id::unique("lod overlay"))
                        .fixed_pos(viewport.rect.left_top() + egui::vec2(8.0, 8.0))
                        .interactable(false)
                        .show(ui.ctx(), |ui| ui.label(egui::RichText::new(text).strong()));
                }
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
        chain::ui::difference_window(&mut self.chain, &ctx, self.viewport.camera.distance);
        self.file_dialog.ui(&ctx);
        drop_hint(&ctx);
        if let Some(wait) = self.poll_interval() {
            ctx.request_repaint_after(wait);
        }
    }

    /// Whether there is a LOD to show: a build's result or a built chain.
    fn has_lod(&self) -> bool {
        self.result.is_some() || self.built_chain().is_some()
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
