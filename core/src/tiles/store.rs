//! The tileset's work folder, `DIR/.lodstudio-tiles/`: what lets a build
//! stop and go on, and several processes (threads, shards on other
//! machines sharing the folder) build one tileset together.
//!
//! - `plan.json`: the [`Plan`] (the partition's tree and the key of what it
//!   was built from), written last by the planning step: its presence says
//!   every leaf is made.
//! - `mesh/N.bin`: tile N's content, lossless (the saved-hierarchy
//!   container: checksummed, floats bit-exact), what its parent is made from.
//! - `made/N.json`: tile N's [`Made`] record, written after its GLB and its
//!   mesh: its presence says the tile is done. Every write is whole or
//!   none (a rename), so a killed build leaves whole files.
//! - `spill/`: the input's triangles and the partition's cells while
//!   planning out of core (empty once planned).
//! - `locks/`: advisory locks (`flock`, which the kernel releases when a
//!   process dies, on local disks and NFSv4 alike): `plan.lock` while one
//!   process reads or writes the plan, `run.lock` shared while any makes
//!   tiles and exclusive to replace the plan (so a `--force` of another
//!   input waits for the shards still running), and `N.lock` while one
//!   builds tile N. A process that finds
//!   a tile locked builds others first and then waits for it, so waiting
//!   for the last tile of a level is the barrier between levels.

use std::fs::File;
use std::path::{Path, PathBuf};

use crate::geom::{Aabb, TriMesh};
use crate::io::gltf_writer::write_glb;
use crate::io::hierarchy_file;

/// The work folder's name inside the tileset's folder.
pub const DIR_NAME: &str = ".lodstudio-tiles";

/// The method name of tile meshes in their container.
const MESH_KIND: &str = "tile";

/// The tree a tileset is built on, as planned from its input.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Plan {
    /// What the tiles are built from (input bytes, budget, tool): a work
    /// folder of another key is never reused.
    pub key: String,
    pub tile_triangles: usize,
    pub input_triangles: usize,
    pub bbox_diagonal: f32,
    /// Each tile's children (none: a leaf); tile 0 is the root, children
    /// come after their parent.
    pub children: Vec<Vec<usize>>,
}

impl Plan {
    /// Whether the children make one tree rooted at 0 with every child after
    /// its parent (a damaged or hand-made plan is no plan: planning again
    /// writes it whole).
    pub fn is_tree(&self) -> bool {
        let n = self.children.len();
        let mut parents = vec![0u32; n];
        for (i, kids) in self.children.iter().enumerate() {
            for k in kids {
                if *k <= i || *k >= n {
                    return false;
                }
                parents[*k] += 1;
            }
        }
        n > 0 && parents[0] == 0 && parents[1..].iter().all(|p| *p == 1)
    }

    /// Each tile's depth (the root's is 0).
    pub fn depths(&self) -> Vec<usize> {
        let mut depth = vec![0; self.children.len()];
        for (i, kids) in self.children.iter().enumerate() {
            for k in kids {
                depth[*k] = depth[i] + 1;
            }
        }
        depth
    }

    /// Levels from the root to the deepest leaf.
    pub fn levels(&self) -> usize {
        self.depths().into_iter().max().map_or(0, |d| d + 1)
    }

    /// The tiles at depth `level` that are made from children (leaves are
    /// made by planning).
    pub fn parents_at(&self, level: usize) -> Vec<usize> {
        let depth = self.depths();
        (0..self.children.len())
            .filter(|i| depth[*i] == level && !self.children[*i].is_empty())
            .collect()
    }
}

/// What is known of a made tile without reading its content.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Made {
    /// Certified two-sided Hausdorff bound against the original triangles
    /// below it (module doc of `tiles`).
    pub error: f32,
    /// Original triangles it stands for.
    pub covers: usize,
    pub triangles: usize,
    /// Its content's box (y-up, as the content).
    pub bounds: Aabb,
}

/// The work folder of the tileset in `dir`.
#[derive(Debug, Clone)]
pub struct Store {
    dir: PathBuf,
    work: PathBuf,
}

impl Store {
    /// The store of `dir` (the tileset's folder), its folders made if missing.
    pub fn open(dir: &Path) -> std::io::Result<Store> {
        let work = dir.join(DIR_NAME);
        for sub in ["mesh", "made", "locks"] {
            std::fs::create_dir_all(work.join(sub))?;
        }
        std::fs::create_dir_all(dir.join("tiles"))?;
        Ok(Store {
            dir: dir.to_path_buf(),
            work,
        })
    }

    /// The plan in the tileset folder `dir`, if one finished there (read
    /// only: nothing is made).
    pub fn plan_in(dir: &Path) -> Option<Plan> {
        let bytes = std::fs::read(dir.join(DIR_NAME).join("plan.json")).ok()?;
        serde_json::from_slice::<Plan>(&bytes)
            .ok()
            .filter(Plan::is_tree)
    }

    /// The tileset's folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The plan, once planning finished (an unreadable one is no plan:
    /// planning again writes it whole).
    pub fn plan(&self) -> Option<Plan> {
        Store::plan_in(&self.dir)
    }

    pub fn put_plan(&self, plan: &Plan) -> std::io::Result<()> {
        let json = serde_json::to_vec(plan).expect("a plan is numbers and a string");
        write_whole(&self.work.join("plan.json"), &json)
    }

    /// Forgets every tile and the plan (another input's work): the plan,
    /// `tileset.json`, and of `tiles/` only the GLBs of tiles it made
    /// (another file there is the user's).
    pub fn clear(&self) -> std::io::Result<()> {
        let _ = std::fs::remove_file(self.work.join("plan.json"));
        let _ = std::fs::remove_file(self.dir.join("tileset.json"));
        for entry in std::fs::read_dir(self.work.join("made"))? {
            let name = entry?.file_name();
            let tile = name.to_str().and_then(|n| n.strip_suffix(".json"));
            if let Some(i) = tile.and_then(|t| t.parse::<usize>().ok()) {
                let _ = std::fs::remove_file(self.dir.join(content_path(i)));
            }
        }
        for sub in ["made", "mesh"] {
            std::fs::remove_dir_all(self.work.join(sub))?;
            std::fs::create_dir_all(self.work.join(sub))?;
        }
        Ok(())
    }

    /// Whether `dir/tiles/` holds files while `dir` has no work folder: a
    /// folder lodstudio did not make, whose files a build would replace.
    pub fn foreign_tiles(dir: &Path) -> bool {
        !dir.join(DIR_NAME).exists()
            && std::fs::read_dir(dir.join("tiles")).is_ok_and(|mut d| d.next().is_some())
    }

    /// An empty folder for the cells planning spills to disk (what a
    /// killed run left there is removed).
    pub fn spill_dir(&self) -> std::io::Result<PathBuf> {
        let dir = self.work.join("spill");
        if dir.exists() {
            std::fs::remove_dir_all(&dir)?;
        }
        std::fs::create_dir_all(&dir)?;
        Ok(dir)
    }

    /// Tile `i`'s record, once it is made.
    pub fn made(&self, i: usize) -> Option<Made> {
        let bytes = std::fs::read(self.work.join(format!("made/{i}.json"))).ok()?;
        serde_json::from_slice(&bytes).ok()
    }

    /// Tile `i`'s content, as made.
    pub fn mesh(&self, i: usize) -> std::io::Result<TriMesh> {
        let path = self.work.join(format!("mesh/{i}.bin"));
        let bytes = std::fs::read(&path)?;
        let (_, mesh) = hierarchy_file::load::<TriMesh>(&bytes, MESH_KIND)
            .map_err(|e| std::io::Error::other(format!("{}: {e}", path.display())))?;
        mesh.check()
            .map_err(|e| std::io::Error::other(format!("{}: {e}", path.display())))?;
        Ok(mesh)
    }

    /// Records tile `i` as made: its GLB, its mesh, then its record.
    pub fn put(&self, i: usize, mesh: &TriMesh, made: &Made) -> std::io::Result<()> {
        write_whole(&self.dir.join(content_path(i)), &write_glb(mesh))?;
        let body = hierarchy_file::save(MESH_KIND, &serde_json::Value::Null, mesh);
        write_whole(&self.work.join(format!("mesh/{i}.bin")), &body)?;
        let json = serde_json::to_vec(made).expect("a record is numbers");
        write_whole(&self.work.join(format!("made/{i}.json")), &json)
    }

    /// The planning lock, waited for: one process at a time reads or
    /// writes the plan. Held until dropped.
    pub fn planning_lock(&self) -> std::io::Result<File> {
        let file = self.lock_file("plan")?;
        file.lock()?;
        Ok(file)
    }

    /// The run lock, waited for: shared while a process makes tiles of
    /// the plan, exclusive to replace the plan (another input's, with
    /// `--force`), so a plan is never replaced under a running build. Held
    /// until dropped; an exclusive one turns shared with `lock_shared`.
    pub fn run_lock(&self, exclusive: bool) -> std::io::Result<File> {
        let file = self.lock_file("run")?;
        match exclusive {
            true => file.lock()?,
            false => file.lock_shared()?,
        }
        Ok(file)
    }

    /// Tile `i`'s lock: waited for, or `None` when another holds it and
    /// `wait` is false. Held until dropped.
    pub fn tile_lock(&self, i: usize, wait: bool) -> std::io::Result<Option<File>> {
        let file = self.lock_file(&i.to_string())?;
        if wait {
            file.lock()?;
            return Ok(Some(file));
        }
        match file.try_lock() {
            Ok(()) => Ok(Some(file)),
            Err(std::fs::TryLockError::WouldBlock) => Ok(None),
            Err(std::fs::TryLockError::Error(e)) => Err(e),
        }
    }

    fn lock_file(&self, name: &str) -> std::io::Result<File> {
        std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(self.work.join(format!("locks/{name}.lock")))
    }
}

/// Writes `bytes` to `path` whole or not at all: to `.NAME.part` beside
/// it, then renamed. Only the holder of a tile's lock (or of the plan's)
/// writes its files, so the temporary's name can be fixed: the next holder
/// truncates what a killed one left, and a finished build leaves none.
fn write_whole(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let part = path.with_file_name(format!(".{name}.part"));
    let mut file = File::create(&part)?;
    file.write_all(bytes)?;
    file.sync_all()?;
    std::fs::rename(&part, path)
}

/// The path, inside the tileset's folder, of tile `i`'s content.
pub fn content_path(i: usize) -> String {
    format!("tiles/{i}.glb")
}
