//! The studio window: menu, model list, 3D viewport, inspector and log.
//!
//! Everything slow (loading, summarising, preparing GPU geometry, the file
//! dialog) runs on worker threads; the UI polls them each frame so it never
//! blocks, and a failed or cancelled load keeps the previous model.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::time::{Duration, Instant};

use lodstudio_core::Progress;
use lodstudio_core::builtins;
use lodstudio_core::io::{LoadError, LoadOptions, Loaded, load};
use lodstudio_core::stats::ModelSummary;

use crate::viewport::{Scene, Viewport};

/// Storage key of the recent-files list (JSON array of paths).
const RECENT_KEY: &str = "lodstudio.recent";
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
}

/// What a load worker hands back.
struct Finished {
    loaded: Loaded,
    summary: ModelSummary,
    scene: Scene,
}

struct LoadJob {
    path: PathBuf,
    name: String,
    progress: Arc<Progress>,
    started: Instant,
    result: Receiver<Result<Box<Finished>, LoadError>>,
}

struct LogLine {
    text: String,
    error: bool,
}

/// The lodstudio GUI.
pub struct StudioApp {
    viewport: Viewport,
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
}

impl StudioApp {
    /// Called by eframe: restores recent files and opens `initial` (or the default model).
    pub fn new(cc: &eframe::CreationContext<'_>, initial: Option<PathBuf>) -> Self {
        let mut app = Self::with_render_state(cc.wgpu_render_state.as_ref(), initial);
        if let Some(recent) = cc
            .storage
            .and_then(|s| s.get_string(RECENT_KEY))
            .and_then(|json| serde_json::from_str::<Vec<PathBuf>>(&json).ok())
        {
            app.recent = recent.into_iter().take(MAX_RECENT).collect();
        }
        app
    }

    /// A studio without eframe (for tests): draws with `render_state` if given.
    pub fn with_render_state(
        render_state: Option<&egui_wgpu::RenderState>,
        initial: Option<PathBuf>,
    ) -> Self {
        StudioApp {
            viewport: Viewport::new(render_state),
            current: None,
            job: None,
            pending: Some(initial.unwrap_or_else(default_model)),
            picker: None,
            recent: Vec::new(),
            log: Vec::new(),
            error: None,
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
    pub fn viewport(&self) -> &Viewport {
        &self.viewport
    }

    /// Messages of the log panel, oldest first.
    pub fn log_lines(&self) -> impl Iterator<Item = &str> {
        self.log.iter().map(|l| l.text.as_str())
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

        egui::Panel::top("menu").show(ui, |ui| self.menu_bar(ui));
        egui::Panel::bottom("status")
            .resizable(true)
            .default_size(110.0)
            .show(ui, |ui| self.status_panel(ui));
        egui::Panel::left("model")
            .default_size(210.0)
            .show(ui, |ui| self.model_panel(ui));
        egui::Panel::right("inspector")
            .default_size(250.0)
            .show(ui, |ui| self.inspector(ui));
        egui::CentralPanel::no_frame().show(ui, |ui| {
            self.viewport.show(ui);
        });

        self.error_window(&ctx);
        drop_hint(&ctx);
        if self.job.is_some() || self.picker.is_some() {
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
            old.progress.cancel();
            self.info(format!("Stopped loading {}", old.name));
        }
        let name = display_name(&path);
        let progress = Arc::new(Progress::new());
        let (tx, rx) = mpsc::channel();
        let worker_progress = Arc::clone(&progress);
        let worker_path = path.clone();
        let ctx = ctx.clone();
        let spawned = std::thread::Builder::new()
            .name("model loader".into())
            .spawn(move || {
                let progress = worker_progress;
                // After a cancel nobody waits for the result: skip the remaining work.
                let result = match load(&worker_path, &LoadOptions::default(), &progress) {
                    Ok(_) | Err(_) if progress.is_cancelled() => return,
                    Ok(loaded) => {
                        progress.stage("summarising");
                        let summary = ModelSummary::of(&loaded);
                        if progress.is_cancelled() {
                            return;
                        }
                        progress.stage("preparing the view");
                        let scene = Scene::from_model(&loaded.model);
                        Ok(Box::new(Finished {
                            loaded,
                            summary,
                            scene,
                        }))
                    }
                    Err(e) => Err(e),
                };
                // The receiver is gone if a newer load replaced this one.
                let _ = tx.send(result);
                ctx.request_repaint();
            });
        match spawned {
            Ok(_) => {
                self.info(format!("Loading {}", path.display()));
                self.job = Some(LoadJob {
                    path,
                    name,
                    progress,
                    started: Instant::now(),
                    result: rx,
                });
            }
            Err(e) => self.load_failed(format!("cannot start loading {name}: {e}")),
        }
    }

    fn poll_job(&mut self, ctx: &egui::Context) {
        let Some(job) = &self.job else {
            return;
        };
        let outcome = match job.result.try_recv() {
            Err(TryRecvError::Empty) => return,
            Ok(outcome) => outcome,
            Err(TryRecvError::Disconnected) => {
                let msg = format!(
                    "{}: loading stopped unexpectedly (internal error)",
                    job.name
                );
                self.job = None;
                self.load_failed(msg);
                return;
            }
        };
        let Some(job) = self.job.take() else {
            return;
        };
        match outcome {
            Ok(done) => {
                let Finished {
                    loaded,
                    summary,
                    scene,
                } = *done;
                let seconds = job.started.elapsed().as_secs_f32();
                let counts = match (summary.triangles, summary.points) {
                    (0, 0) => summary.kind.to_string(),
                    (0, p) => format!("{p} points"),
                    (t, _) => format!("{t} triangles"),
                };
                self.info(format!(
                    "Loaded {} ({}, {counts}) in {seconds:.2} s",
                    job.name,
                    summary.format.name()
                ));
                self.viewport.set_scene(scene);
                if !is_builtin(&job.path) {
                    self.remember(&job.path);
                }
                ctx.send_viewport_cmd(egui::ViewportCommand::Title(format!(
                    "lodstudio — {}",
                    job.name
                )));
                self.current = Some(Current {
                    rows: summary.lines(),
                    name: job.name,
                    path: job.path,
                    loaded: Arc::new(loaded),
                    summary,
                });
            }
            Err(e) => self.load_failed(e.to_string()),
        }
    }

    fn cancel_load(&mut self) {
        if let Some(job) = self.job.take() {
            job.progress.cancel();
            self.info(format!("Cancelled loading {}", job.name));
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

    fn model_panel(&mut self, ui: &mut egui::Ui) {
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
        ui.separator();
        egui::ScrollArea::vertical().show(ui, |ui| {
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
        });
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
        });
    }

    fn status_panel(&mut self, ui: &mut egui::Ui) {
        if let Some(job) = &self.job {
            let mut cancel = false;
            ui.horizontal(|ui| {
                let text = format!("{}: {}", job.name, job.progress.stage_name());
                ui.add(
                    egui::ProgressBar::new(job.progress.fraction())
                        .desired_width(ui.available_width() - 80.0)
                        .text(text),
                );
                cancel = ui.button("Cancel").clicked();
            });
            if cancel {
                self.cancel_load();
            }
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
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        self.show(ui);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        if let Ok(json) = serde_json::to_string(&self.recent) {
            storage.set_string(RECENT_KEY, json);
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
