//! A 3D Tiles tileset in the studio (issue 47, item 4): its tiles read once
//! on a worker, and the cut a viewer draws at the camera and the maximum
//! screen-space error (`lodstudio_core::tiles::cut`), re-selected only when
//! the view or the threshold changes and turned into a scene only when the
//! cut changes, on a worker thread (a cut of a large tileset is hundreds of
//! thousands of triangles: the frame keeps the last scene meanwhile), its
//! tiles coloured by level (the studio's level ramp, the root at one end
//! and the deepest leaves at the other).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::mpsc::Receiver;

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
    /// Each tile's content (none for a tile without one).
    meshes: Arc<Vec<Option<TriMesh>>>,
    /// The view, threshold and colouring the cut was last taken for.
    last: Option<(View, f32, bool)>,
    drawn: Vec<Drawn>,
    /// The tiles of the latest scene asked for, to tell a new cut from the same.
    shown: Vec<usize>,
    scene: Arc<Scene>,
    /// The scene of `shown`, being made.
    making: Option<Receiver<Scene>>,
    /// The largest box diagonal: errors are also shown as a fraction of it.
    pub diagonal: f32,
}

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
        for (i, tile) in set.tiles.iter().enumerate() {
            progress.check()?;
            progress.stage(&format!("reading tile {i} of {}", set.tiles.len()));
            progress.set_fraction(i as f32 / set.tiles.len() as f32);
            let Some(uri) = &tile.content else {
                meshes.push(None);
                continue;
            };
            let what = format!("{shown}: tile {i}");
            let read = confine::resolve_path(folder, Path::new(uri), &what)
                .map_err(|e| e.message().to_string())
                .and_then(|file| {
                    let bytes = confine::read_regular(&file, budget)
                        .map_err(|e| e.message().to_string())?;
                    lodstudio_core::io::gltf::read(&bytes, file.parent())
                        .map(|(mesh, _)| mesh)
                        .map_err(|e| LoadError::malformed(&file, e).to_string())
                });
            match read {
                Ok(mesh) => meshes.push(Some(mesh)),
                Err(e) => return Ok(Err(e)),
            }
        }
        let diagonal = set.tiles.first().map_or(0.0, |t| t.bounds.diagonal());
        Ok(Ok(TilesetView {
            path: path.to_path_buf(),
            set,
            meshes: Arc::new(meshes),
            last: None,
            drawn: Vec::new(),
            shown: Vec::new(),
            scene: Arc::new(Scene::from_mesh(&TriMesh::default())),
            making: None,
            diagonal,
        }))
    }

    /// Re-selects the cut for `view` at `max_sse_px`, and starts making its
    /// scene when the drawn tiles (or their colouring) changed; takes a
    /// scene made since. Nothing is allocated while the view stays put.
    pub fn update(&mut self, view: &View, max_sse_px: f32, by_level: bool) {
        if let Some(made) = self.making.as_ref().and_then(|rx| rx.try_recv().ok()) {
            self.scene = Arc::new(made);
            self.making = None;
        }
        let now = (*view, max_sse_px, by_level);
        if self.last == Some(now) {
            return;
        }
        let recolour = self.last.is_none_or(|l| l.2 != by_level);
        self.last = Some(now);
        cut(&self.set, view, max_sse_px, &mut self.drawn);
        let same = self.drawn.len() == self.shown.len()
            && self
                .drawn
                .iter()
                .zip(&self.shown)
                .all(|(d, s)| d.tile == *s);
        if same && !recolour {
            return;
        }
        self.shown.clear();
        self.shown.extend(self.drawn.iter().map(|d| d.tile));
        // A scene still being made for an older cut is dropped with its
        // receiver (its thread's send then fails).
        let (tx, rx) = std::sync::mpsc::channel();
        let (tiles, meshes) = (self.shown.clone(), Arc::clone(&self.meshes));
        let levels: Vec<usize> = tiles.iter().map(|i| self.set.tiles[*i].depth).collect();
        let top = self.set.levels().saturating_sub(1).max(1) as f32;
        let spawned = std::thread::Builder::new()
            .name("tileset cut".into())
            .spawn(move || {
                let _ = tx.send(cut_scene(&meshes, &tiles, &levels, top, by_level));
            });
        self.making = spawned.is_ok().then_some(rx);
    }

    /// Whether a cut's scene is being made (the studio polls for it).
    pub fn is_making(&self) -> bool {
        self.making.is_some()
    }

    /// The root tile alone, to frame the camera on.
    pub fn root_scene(&self) -> Scene {
        cut_scene(&self.meshes, &[0], &[0], 1.0, false)
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

/// The scene of the cut `tiles` (at `levels`), coloured by level on a ramp
/// up to `top`, or in their materials.
fn cut_scene(
    meshes: &[Option<TriMesh>],
    tiles: &[usize],
    levels: &[usize],
    top: f32,
    by_level: bool,
) -> Scene {
    let mut mesh = TriMesh::default();
    let mut colors: Vec<Vec3> = Vec::new();
    for (i, level) in tiles.iter().zip(levels) {
        if let Some(m) = &meshes[*i] {
            mesh.append(m);
            let colour = heatmap::linear(*level as f32 / top);
            colors.extend(std::iter::repeat_n(colour, m.triangles.len()));
        }
    }
    match by_level {
        true => Scene::from_mesh_with_triangle_colors(&mesh, &colors),
        false => Scene::from_mesh(&mesh),
    }
}
