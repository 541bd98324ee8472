//! The studio's glue for 3D Tiles (issue 47, item 4): opening a tileset on
//! a worker, building one from the model on screen (into the folder the
//! user chose), and showing the cut a viewer draws.

use std::path::PathBuf;
use std::sync::Arc;

use lodstudio_core::tiles::{self, Store};

use super::StudioApp;
use super::loading::display_name;
use crate::job::{Job, Poll};
use crate::tileset_view::TilesetView;

/// What a tileset job gives back.
pub(super) enum TilesetDone {
    Opened(Box<TilesetView>),
    /// Built and written here: open it.
    Built(PathBuf),
    /// No folder chosen.
    NoFile,
}

impl StudioApp {
    /// Reads the tileset `path` (its `tileset.json`) on a worker.
    pub(super) fn start_tileset_load(&mut self, path: PathBuf, ctx: &egui::Context) {
        let name = display_name(&path);
        let spawned = Job::spawn("tileset loader", name.clone(), ctx, move |progress| {
            Ok(TilesetView::open(&path, progress)?.map(|view| TilesetDone::Opened(Box::new(view))))
        });
        match spawned {
            Ok(job) => {
                self.info(format!("Loading the tileset {name}"));
                self.tileset_job = Some(job);
            }
            Err(e) => self.load_failed(format!("cannot start loading {name}: {e}")),
        }
    }

    /// Builds a tileset of the model on screen into `path` (a
    /// `tileset.json`; its tiles beside it) on a worker, then opens it;
    /// `None` asks for the place first.
    pub fn build_tileset(&mut self, path: Option<PathBuf>, ctx: &egui::Context) {
        if self.tileset_job.is_some() {
            return;
        }
        let Some(mesh) = self.current.as_ref().and_then(|c| c.mesh()).cloned() else {
            self.error("A tileset is built from a triangle mesh: open one first".into());
            return;
        };
        let budget = self.tiles.tile_triangles;
        let workers = std::thread::available_parallelism().map_or(1, |n| n.get());
        let spawned = Job::spawn(
            "tileset builder",
            "Building a tileset".into(),
            ctx,
            move |progress| {
                const FILTERS: &[(&str, &[&str])] = &[("3D Tiles", &["json"])];
                let Some(path) = path.or_else(|| {
                    crate::file_dialog::save_file("Build a tileset", "tileset.json", FILTERS)
                }) else {
                    return Ok(Ok(TilesetDone::NoFile));
                };
                let dir = path
                    .parent()
                    .unwrap_or(std::path::Path::new("."))
                    .to_path_buf();
                if Store::foreign_tiles(&dir) {
                    return Ok(Err(format!(
                        "{}: holds files lodstudio did not make; choose an empty folder",
                        dir.join("tiles").display()
                    )));
                }
                let built = Store::open(&dir)
                    .map_err(tiles::TilesError::Io)
                    .and_then(|store| {
                        // The whole folder is this build's: no shard of
                        // another run makes tiles in it meanwhile.
                        let _planning = store.planning_lock()?;
                        let _run = store.run_lock(true)?;
                        let plan = tiles::build(&store, &mesh, budget, workers, progress)?;
                        let made: Vec<_> = (0..plan.children.len())
                            .map(|i| store.made(i))
                            .collect::<Option<_>>()
                            .ok_or_else(|| std::io::Error::other("a tile went missing"))?;
                        lodstudio_core::io::write_atomic(
                            &path,
                            &tiles::tileset::encode(&plan, &made),
                        )?;
                        Ok(())
                    });
                match built {
                    Ok(()) => Ok(Ok(TilesetDone::Built(path))),
                    Err(tiles::TilesError::Cancelled(c)) => Err(c),
                    Err(e) => Ok(Err(format!("{}: {e}", dir.display()))),
                }
            },
        );
        match spawned {
            Ok(job) => self.tileset_job = Some(job),
            Err(e) => self.error(format!("cannot start building the tileset: {e}")),
        }
    }

    /// A finished tileset load or build.
    pub(super) fn poll_tileset(&mut self, ctx: &egui::Context) {
        let Some(job) = &self.tileset_job else {
            return;
        };
        let outcome = match job.poll() {
            Poll::Running => return,
            Poll::Done(outcome) => outcome,
            Poll::Lost => Err(format!(
                "{}: stopped unexpectedly (internal error)",
                job.label()
            )),
        };
        let seconds = job.elapsed().as_secs_f32();
        self.tileset_job = None;
        match outcome {
            Ok(TilesetDone::Opened(view)) => {
                self.info(format!(
                    "Loaded the tileset {} ({} tiles in {} levels) in {seconds:.2} s",
                    view.path.display(),
                    view.set.tiles.len(),
                    view.set.levels()
                ));
                self.forget_result();
                self.chain.forget();
                self.asset = None;
                self.current = None;
                self.remember(&view.path);
                // Framed on the root alone (the scene drawn is any cut of it).
                self.viewport.frame_scene(Arc::clone(view.scene()));
                self.tileset = Some(*view);
            }
            Ok(TilesetDone::Built(path)) => {
                self.info(format!(
                    "Built the tileset {} in {seconds:.1} s",
                    path.display()
                ));
                self.start_tileset_load(path, ctx);
            }
            Ok(TilesetDone::NoFile) => {
                self.info("No tileset built: no place chosen".into());
            }
            Err(message) => self.load_failed(message),
        }
    }

    /// How tilesets are viewed and built (as the 3D Tiles section sets them).
    pub fn tiles_mut(&mut self) -> &mut crate::settings::tiles::TilesSettings {
        &mut self.tiles
    }

    /// The tileset on screen.
    pub fn tileset(&self) -> Option<&TilesetView> {
        self.tileset.as_ref()
    }

    /// Re-selects the tileset's cut for the camera (only when it moved or
    /// the threshold changed) and shows its latest scene; false when no
    /// tileset is open.
    pub(super) fn sync_tileset(&mut self) -> bool {
        let Some(view) = &mut self.tileset else {
            return false;
        };
        view.update(
            &self.viewport.core_view(),
            self.tiles.max_sse_px,
            self.tiles.by_level,
        );
        self.viewport.swap_scene(view.scene());
        true
    }
}
