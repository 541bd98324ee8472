//! Opening a model: the file dialog, dropped files, the load worker, and the
//! recent-files list.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{self, Receiver, TryRecvError};

use lodstudio_core::io::{LoadError, LoadOptions, Loaded};
use lodstudio_core::open::open;
use lodstudio_core::stats::ModelSummary;

use super::{Current, StudioApp};
use crate::build;
use crate::job::{Job, Poll};
use crate::render::Scene;
use crate::settings::voxel::VolumeGrid;

pub(super) const MAX_RECENT: usize = 10;

/// Extensions offered by the file dialog (the loader detects formats by content).
/// `json`: a 3D Tiles `tileset.json`.
const MODEL_EXTENSIONS: &[&str] = &[
    "obj", "gltf", "glb", "ply", "off", "nrrd", "nhdr", "nii", "inr", "gz", "json",
];

/// The bundled default model, when the binary runs from its source tree.
pub(super) fn default_model() -> PathBuf {
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
pub(super) fn display_name(path: &Path) -> String {
    let text = path.to_string_lossy();
    if text.starts_with("builtin:") {
        return text.into_owned();
    }
    path.file_name()
        .map_or_else(|| text.to_string(), |n| n.to_string_lossy().into_owned())
}

/// `path` from the root (a session may restart in another folder).
pub(super) fn absolute(path: &Path) -> PathBuf {
    match is_builtin(path) {
        true => path.to_path_buf(),
        false => std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()),
    }
}

pub(super) fn is_builtin(path: &Path) -> bool {
    path.to_str().is_some_and(|s| s.starts_with("builtin:"))
}

/// What a load worker hands back.
pub(super) struct Finished {
    loaded: Loaded,
    summary: ModelSummary,
    scene: Scene,
    volume: Option<VolumeGrid>,
    /// A saved hierarchy's own structure, to cut live without rebuilding.
    reopened: Option<build::Reopened>,
    /// A glTF read as a scene too (or why it could not be).
    asset: Option<Result<lodstudio_core::io::scene::Scene, String>>,
}

/// An open-file dialog on a worker thread, so the UI keeps drawing; the
/// choice (or `None`) arrives on the receiver and wakes the UI.
pub(super) fn pick_file(
    title: &'static str,
    filters: &'static [(&'static str, &'static [&'static str])],
    ctx: &egui::Context,
) -> std::io::Result<Receiver<Option<PathBuf>>> {
    let (tx, rx) = mpsc::channel();
    let ctx = ctx.clone();
    std::thread::Builder::new()
        .name("file dialog".into())
        .spawn(move || {
            let _ = tx.send(crate::file_dialog::pick_file(title, filters));
            ctx.request_repaint();
        })?;
    Ok(rx)
}

pub(super) struct LoadJob {
    pub(super) path: PathBuf,
    pub(super) job: Job<Result<Box<Finished>, LoadError>>,
}

impl StudioApp {
    /// Runs the native file dialog on a worker thread so the UI keeps drawing.
    pub(super) fn open_dialog(&mut self, ctx: &egui::Context) {
        if self.picker.is_some() {
            return;
        }
        const FILTERS: &[(&str, &[&str])] = &[("Models", MODEL_EXTENSIONS), ("All files", &["*"])];
        match pick_file("Open model", FILTERS, ctx) {
            Ok(rx) => self.picker = Some(rx),
            Err(e) => self.error(format!("cannot open the file dialog: {e}")),
        }
    }

    pub(super) fn poll_picker(&mut self) {
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

    pub(super) fn start_load(&mut self, path: PathBuf, ctx: &egui::Context) {
        if let Some(old) = self.job.take() {
            self.info(format!("Stopped loading {}", old.job.label()));
        }
        if let Some(tileset) = crate::tileset_view::tileset_file(&path) {
            self.start_tileset_load(tileset, ctx);
            return;
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
            let asset = lodstudio_core::io::scene::is_scene(&worker_path).then(|| {
                progress.stage("reading the scene");
                lodstudio_core::io::read_file(&worker_path, progress)
                    .map_err(|e| e.to_string())
                    .and_then(|bytes| {
                        lodstudio_core::io::scene::read(&bytes, worker_path.parent())
                            .map_err(|e| LoadError::malformed(&worker_path, e).to_string())
                    })
            });
            Ok(Ok(Box::new(Finished {
                loaded,
                summary,
                scene,
                volume,
                reopened,
                asset,
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

    pub(super) fn poll_job(&mut self, ctx: &egui::Context) {
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
                    asset,
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
                // Nothing is dropped silently: what exports leave out is said.
                for d in &summary.asset.dropped {
                    self.info(format!("{name}: not carried: {} ({})", d.what, d.place));
                }
                self.forget_result();
                self.chain.forget();
                self.asset = match asset {
                    Some(Ok(asset)) => Some(super::asset::AssetState::new(asset)),
                    Some(Err(why)) => {
                        self.info(format!("{name}: not opened as a scene: {why}"));
                        None
                    }
                    None => None,
                };
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
                let solid = path
                    .to_str()
                    .and_then(|p| p.strip_prefix("builtin:"))
                    .and_then(lodstudio_core::builtins::implicit)
                    .map(Arc::from);
                self.tileset = None;
                self.current = Some(Current {
                    rows: summary.lines(),
                    name,
                    path,
                    solid,
                    loaded: Arc::new(loaded),
                    summary,
                    scene,
                    wire_scene: None,
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
                self.reopen_chain(ctx);
            }
            Err(e) => self.load_failed(e.to_string()),
        }
    }

    pub(super) fn cancel_load(&mut self) {
        if let Some(load) = self.job.take() {
            self.info(format!("Cancelled loading {}", load.job.label()));
        }
    }

    /// Puts `path` first in the recent list.
    pub(super) fn remember(&mut self, path: &Path) {
        let path = path
            .canonicalize()
            .or_else(|_| std::path::absolute(path))
            .unwrap_or_else(|_| path.to_path_buf());
        self.recent.retain(|p| *p != path);
        self.recent.insert(0, path);
        self.recent.truncate(MAX_RECENT);
    }
}
