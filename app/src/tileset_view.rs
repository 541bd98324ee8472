//! A 3D Tiles tileset in the studio (issue 47, item 4): its tiles read once
//! on a worker, and the cut a viewer draws at the camera and the maximum
//! screen-space error (`lodstudio_core::tiles::cut`), re-selected only when
//! the view or the threshold changes and turned into a scene only when the
//! cut changes, on a worker thread (a cut of a large tileset is hundreds of
//! thousands of triangles: the frame keeps the last scene meanwhile), its
//! tiles coloured by level (the studio's level ramp, the root at one end
//! and the deepest leaves at the other).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::{Receiver, TryRecvError};

use glam::Vec3;
use lodstudio_core::io::{LoadError, confine};
use lodstudio_core::tiles::cut::{Drawn, cut};
use lodstudio_core::tiles::tileset::{Tileset, decode};
use lodstudio_core::view::View;
use lodstudio_core::{Progress, TriMesh, progress::Cancelled};

use crate::heatmap;
use crate::render::Scene;

/// A tileset on screen.
pub struct TilesetView {
    /// Its `tileset.json`.
    pub path: PathBuf,
    pub set: Tileset,
    /// Each tile's content (none for a tile without one; tiles naming one
    /// file share it).
    meshes: Arc<Vec<Option<Arc<TriMesh>>>>,
    /// The view, threshold and colouring the cut was last taken for.
    last: Option<(View, f32, bool)>,
    drawn: Vec<Drawn>,
    /// The cut's tiles and colouring as last selected.
    wanted: CutOf,
    scene: Arc<Scene>,
    /// What `scene` shows.
    scene_of: CutOf,
    /// One scene being made at a time, and what it is of.
    making: Option<(Receiver<Scene>, CutOf)>,
    /// The largest box diagonal: errors are also shown as a fraction of it.
    pub diagonal: f32,
}

/// A cut's tiles, and whether they are coloured by level.
type CutOf = (Vec<usize>, bool);

/// Whether `path` is a tileset the studio opens as one: a `tileset.json`,
/// or a folder holding one.
pub fn tileset_file(path: &Path) -> Option<PathBuf> {
    if path.is_dir() {
        let inner = path.join("tileset.json");
        return inner.is_file().then_some(inner);
    }
    (path.file_name()? == "tileset.json").then(|| path.to_path_buf())
}

impl TilesetView {
    /// Reads `tileset.json` and every tile's GLB (each inside its folder).
    pub fn open(
        path: &Path,
        progress: &Progress,
    ) -> Result<Result<TilesetView, String>, Cancelled> {
        let shown = path.display();
        let budget = lodstudio_core::io::limits::current().memory_budget;
        let bytes = match confine::read_regular(path, budget) {
            Ok(b) => b,
            Err(e) => return Ok(Err(e.message().to_string())),
        };
        let set = match decode(&bytes) {
            Ok(s) => s,
            Err(e) => return Ok(Err(format!("{shown}: {e}"))),
        };
        let folder = path.parent().unwrap_or(Path::new("."));
        let mut meshes = Vec::with_capacity(set.tiles.len());
        // Each file read once, and all of them within the memory budget.
        let mut read_before: HashMap<PathBuf, Arc<TriMesh>> = HashMap::new();
        let mut bytes_read = 0u64;
        for (i, tile) in set.tiles.iter().enumerate() {
            progress.check()?;
            progress.stage(&format!("reading tile {i} of {}", set.tiles.len()));
            progress.set_fraction(i as f32 / set.tiles.len() as f32);
            let Some(uri) = &tile.content else {
                meshes.push(None);
                continue;
            };
            let what = format!("{shown}: tile {i}");
            let file = match confine::resolve_path(folder, Path::new(uri), &what) {
                Ok(f) => f,
                Err(e) => return Ok(Err(e.message().to_string())),
            };
            if let Some(mesh) = read_before.get(&file) {
                meshes.push(Some(Arc::clone(mesh)));
                continue;
            }
            let read = confine::read_regular(&file, budget.saturating_sub(bytes_read))
                .map_err(|e| {
                    format!(
                        "{}{}",
                        e.message(),
                        " (the tileset's files together are over the memory budget)"
                    )
                })
                .and_then(|bytes| {
                    bytes_read += bytes.len() as u64;
                    lodstudio_core::io::gltf::read(&bytes, file.parent())
                        .map(|(mesh, _)| Arc::new(mesh))
                        .map_err(|e| LoadError::malformed(&file, e).to_string())
                });
            match read {
                Ok(mesh) => {
                    read_before.insert(file, Arc::clone(&mesh));
                    meshes.push(Some(mesh));
                }
                Err(e) => return Ok(Err(e)),
            }
        }
        let diagonal = set.tiles.first().map_or(0.0, |t| t.bounds.diagonal());
        progress.stage("preparing the view");
        // The root alone, to frame the camera on (made here, off the UI thread).
        let root = (vec![0], false);
        let scene = Arc::new(cut_scene(&meshes, &set, &root));
        Ok(Ok(TilesetView {
            path: path.to_path_buf(),
            set,
            meshes: Arc::new(meshes),
            last: None,
            drawn: Vec::new(),
            wanted: root.clone(),
            scene,
            scene_of: root,
            making: None,
            diagonal,
        }))
    }

    /// Re-selects the cut for `view` at `max_sse_px`; takes a scene made
    /// since, and starts making the one the latest cut wants when none is
    /// being made (one worker at a time: a camera in motion never piles
    /// them up). Nothing is allocated while the view stays put.
    pub fn update(&mut self, view: &View, max_sse_px: f32, by_level: bool) {
        if let Some((rx, of)) = &self.making {
            match rx.try_recv() {
                Ok(made) => {
                    self.scene = Arc::new(made);
                    self.scene_of = of.clone();
                    self.making = None;
                }
                Err(TryRecvError::Empty) => {}
                // A worker that died: its cut is not asked for again.
                Err(TryRecvError::Disconnected) => {
                    self.scene_of = of.clone();
                    self.making = None;
                }
            }
        }
        let now = (*view, max_sse_px, by_level);
        if self.last != Some(now) {
            self.last = Some(now);
            cut(&self.set, view, max_sse_px, &mut self.drawn);
            let same = self.drawn.len() == self.wanted.0.len()
                && self
                    .drawn
                    .iter()
                    .zip(&self.wanted.0)
                    .all(|(d, s)| d.tile == *s);
            if !same || self.wanted.1 != by_level {
                self.wanted.0.clear();
                self.wanted.0.extend(self.drawn.iter().map(|d| d.tile));
                self.wanted.1 = by_level;
            }
        }
        if self.making.is_some() || self.scene_of == self.wanted {
            return;
        }
        let (tx, rx) = std::sync::mpsc::channel();
        let (wanted, meshes, set) = (
            self.wanted.clone(),
            Arc::clone(&self.meshes),
            self.set.clone(),
        );
        let of = wanted.clone();
        let spawned = std::thread::Builder::new()
            .name("tileset cut".into())
            .spawn(move || {
                let _ = tx.send(cut_scene(&meshes, &set, &of));
            });
        if spawned.is_ok() {
            self.making = Some((rx, wanted));
        }
    }

    /// Whether a cut's scene is being made (the studio polls for it).
    pub fn is_making(&self) -> bool {
        self.making.is_some()
    }

    pub fn scene(&self) -> &Arc<Scene> {
        &self.scene
    }

    /// The tiles drawn, with their screen-space errors.
    pub fn drawn(&self) -> &[Drawn] {
        &self.drawn
    }

    /// Triangles of tile `i`'s content.
    pub fn triangles(&self, i: usize) -> usize {
        self.meshes[i].as_ref().map_or(0, |m| m.triangles.len())
    }
}

/// The scene of the cut `(tiles, by_level)` of `set`: coloured by level
/// on a ramp from the root to the deepest level, or in their materials.
fn cut_scene(meshes: &[Option<Arc<TriMesh>>], set: &Tileset, (tiles, by_level): &CutOf) -> Scene {
    let top = set.levels().saturating_sub(1).max(1) as f32;
    let mut mesh = TriMesh::default();
    let mut colors: Vec<Vec3> = Vec::new();
    for i in tiles {
        if let Some(m) = &meshes[*i] {
            mesh.append(m);
            let colour = heatmap::linear(set.tiles[*i].depth as f32 / top);
            colors.extend(std::iter::repeat_n(colour, m.triangles.len()));
        }
    }
    match by_level {
        true => Scene::from_mesh_with_triangle_colors(&mesh, &colors),
        false => Scene::from_mesh(&mesh),
    }
}
