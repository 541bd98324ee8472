//! The tile tree as named steps, each a function of files in the work
//! folder ([`Store`]): [`plan`] partitions the mesh and makes the leaves
//! (the original triangles of each cell, with their materials and
//! attributes); [`make_level`] makes the parents of one level, each its
//! children's union welded along their shared border and simplified to
//! half (and to the tile budget) with every border locked, its error
//! composed (module doc of `tiles`). A tile depends on nothing but its
//! children, so the tiles of a level are independent jobs for threads,
//! shards and later runs alike, and the bytes depend on nothing but the
//! mesh and the budget.
//!
//! A level's tiles run on worker threads of their own, not as rayon tasks:
//! the collapse waits for its bound worker, which needs rayon's pool, so
//! tiles as tasks deadlock once every pool thread waits.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;

use super::partition::{Items, Rec, Spill, SplitError, records, split};
use super::store::{Made, Plan, Store};
use super::stream::Streamed;
use crate::batch::Shard;
use crate::geom::repair::repair_mesh;
use crate::geom::{Aabb, Materials, MeshArrays, RepairOptions, TriMesh, Weld};
use crate::progress::{Cancelled, Progress};
use crate::simplify::{self, CollapseOptions, SimplifyOptions, Target};

#[derive(Debug, thiserror::Error)]
pub enum TilesError {
    #[error(transparent)]
    Cancelled(#[from] Cancelled),
    #[error("the tileset's work folder: {0}")]
    Io(#[from] std::io::Error),
    /// `--level` asked for a level whose children are not all made.
    #[error("level {level} needs level {} first: tile {tile} is not made yet", level + 1)]
    NotReady { level: usize, tile: usize },
}

/// What one step did: tiles it made, tiles it found made (by an earlier
/// run, another shard or another thread).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    pub built: usize,
    pub reused: usize,
}

impl std::ops::AddAssign for Counts {
    fn add_assign(&mut self, o: Counts) {
        self.built += o.built;
        self.reused += o.reused;
    }
}

/// Plans the tileset of `mesh` with leaves of at most `tile_triangles`:
/// forgets what `store` held, makes every leaf, then writes the plan (the
/// sign that planning finished). The caller holds the plan lock.
pub fn plan(
    store: &Store,
    mesh: &TriMesh,
    tile_triangles: usize,
    key: &str,
    progress: &Progress,
) -> Result<Plan, TilesError> {
    let arrays = mesh.arrays();
    let input = Input {
        positions: &mesh.positions,
        root: Items::Memory(records(mesh)),
        triangles: mesh.triangles.len(),
        bounds: mesh.bounds(),
    };
    plan_with(
        store,
        input,
        tile_triangles,
        key,
        &Spill::none(),
        progress,
        |recs| arrays.gather(recs.iter().map(|r| r.index)),
    )
}

/// [`plan`] for a mesh streamed out of core (`stream`): its cells split on
/// disk while larger than `spill` allows, each leaf gathered from its cell
/// with what streaming reads of its vertices.
pub fn plan_streamed(
    store: &Store,
    streamed: Streamed,
    tile_triangles: usize,
    key: &str,
    spill: &Spill,
    progress: &Progress,
) -> Result<Plan, TilesError> {
    let positions = &streamed.positions;
    let (normals, colors) = (streamed.normals.as_deref(), streamed.colors.as_deref());
    let input = Input {
        positions,
        root: streamed.root,
        triangles: streamed.triangles,
        bounds: streamed.bounds,
    };
    plan_with(store, input, tile_triangles, key, spill, progress, |recs| {
        let local: Vec<[u32; 3]> = recs.iter().map(|r| r.vertices).collect();
        let arrays = MeshArrays {
            positions,
            triangles: &local,
            normals,
            colors,
            uvs: None,
            parts: None,
            materials: None,
            wedges: None,
            payload: None,
        };
        arrays.gather(0..local.len() as u32)
    })
}

/// What planning splits: the vertices, the triangles as the root cell.
struct Input<'a> {
    positions: &'a [Vec3],
    root: Items,
    triangles: usize,
    bounds: Aabb,
}

fn plan_with(
    store: &Store,
    input: Input<'_>,
    tile_triangles: usize,
    key: &str,
    spill: &Spill,
    progress: &Progress,
    gather: impl Fn(&[Rec]) -> TriMesh,
) -> Result<Plan, TilesError> {
    progress.stage("tiles: planning");
    store.clear()?;
    let tree = split(
        input.positions,
        input.root,
        tile_triangles,
        spill,
        progress,
        |at, recs| {
            let leaf = gather(recs);
            let made = Made {
                error: 0.0,
                covers: recs.len(),
                triangles: recs.len(),
                bounds: leaf.bounds(),
            };
            store.put(at, &leaf, &made)
        },
    )
    .map_err(|e| match e {
        SplitError::Cancelled(c) => TilesError::Cancelled(c),
        SplitError::Io(e) => TilesError::Io(e),
    })?;
    let plan = Plan {
        key: key.to_string(),
        tile_triangles,
        input_triangles: input.triangles,
        bbox_diagonal: input.bounds.diagonal(),
        children: tree
            .iter()
            .map(|kids| kids.map_or_else(Vec::new, |k| k.to_vec()))
            .collect(),
    };
    store.put_plan(&plan)?;
    Ok(plan)
}

/// Makes the parents at depth `level` that are not made yet, `workers` at
/// a time: this shard's share first, then any other shard's not yet begun,
/// then waiting for those another process is making (so every tile of the
/// level is made when it returns: the barrier between levels).
///
/// # Errors
/// `NotReady` when a child is not made; `Cancelled`, checked between
/// tiles; the work folder's I/O errors.
pub fn make_level(
    store: &Store,
    plan: &Plan,
    level: usize,
    shard: Shard,
    workers: usize,
    progress: &Progress,
) -> Result<Counts, TilesError> {
    let at = plan.parents_at(level);
    for i in &at {
        if let Some(k) = plan.children[*i].iter().find(|k| store.made(**k).is_none()) {
            return Err(TilesError::NotReady { level, tile: *k });
        }
    }
    let (mine, others): (Vec<_>, Vec<_>) = at
        .iter()
        .enumerate()
        .partition(|(n, _)| n % shard.count == shard.index);
    let queue: Vec<usize> = mine.into_iter().chain(others).map(|(_, i)| *i).collect();
    let next = AtomicUsize::new(0);
    let busy = Mutex::new(Vec::new());
    let counts = Mutex::new(Counts::default());
    let failed = Mutex::new(None);
    std::thread::scope(|scope| {
        for _ in 0..workers.clamp(1, queue.len().max(1)) {
            scope.spawn(|| {
                loop {
                    if progress.is_cancelled() || locked(&failed).is_some() {
                        return;
                    }
                    let (i, wait) = match queue.get(next.fetch_add(1, Ordering::Relaxed)) {
                        Some(i) => (*i, false),
                        None => match locked(&busy).pop() {
                            Some(i) => (i, true),
                            None => return,
                        },
                    };
                    match make_tile(store, plan, level, i, wait) {
                        Ok(Some(c)) => {
                            let mut all = locked(&counts);
                            *all += c;
                            let n = all.built + all.reused;
                            progress.set_fraction(n as f32 / queue.len() as f32);
                        }
                        Ok(None) => locked(&busy).push(i),
                        Err(e) => *locked(&failed) = Some(e),
                    }
                }
            });
        }
    });
    if let Some(e) = failed.into_inner().unwrap_or_else(|e| e.into_inner()) {
        return Err(e);
    }
    progress.check()?;
    Ok(counts.into_inner().unwrap_or_else(|e| e.into_inner()))
}

/// A mutex's value, whether or not a thread panicked holding it.
fn locked<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

/// Makes tile `i` (at depth `level`) from its children unless it is made;
/// `None` when another process holds it and `wait` is false.
fn make_tile(
    store: &Store,
    plan: &Plan,
    level: usize,
    i: usize,
    wait: bool,
) -> Result<Option<Counts>, TilesError> {
    let reused = Counts {
        built: 0,
        reused: 1,
    };
    if store.made(i).is_some() {
        return Ok(Some(reused));
    }
    let Some(_held) = store.tile_lock(i, wait)? else {
        return Ok(None);
    };
    if store.made(i).is_some() {
        return Ok(Some(reused));
    }
    let kids = &plan.children[i];
    let mut made = Vec::with_capacity(kids.len());
    let mut meshes = Vec::with_capacity(kids.len());
    for k in kids {
        made.push(
            store
                .made(*k)
                .ok_or(TilesError::NotReady { level, tile: *k })?,
        );
        meshes.push(store.mesh(*k)?);
    }
    let (mesh, record) = parent(&meshes, &made, plan.tile_triangles);
    store.put(i, &mesh, &record)?;
    Ok(Some(Counts {
        built: 1,
        reused: 0,
    }))
}

/// The whole tree of `mesh` in a fresh `store`, `workers` tiles at a time
/// (one process; the command line runs the steps itself for shards).
pub fn build(
    store: &Store,
    mesh: &TriMesh,
    tile_triangles: usize,
    workers: usize,
    progress: &Progress,
) -> Result<Plan, TilesError> {
    let plan = plan(store, mesh, tile_triangles, "", progress)?;
    let deepest = plan.levels().saturating_sub(1);
    for level in (0..=deepest).rev() {
        progress.stage(&format!("tiles: level {level} of {deepest}"));
        make_level(store, &plan, level, Shard::ALL, workers, progress)?;
    }
    Ok(plan)
}

/// Two children's contents as one mesh, welded along their shared border
/// (the same original vertices on both sides): what their parent simplifies.
///
/// A part here is a material: `concat` numbers each piece's parts apart,
/// and part borders are seams the locked collapse keeps, so every old cell
/// border would stay at full resolution up to the root.
pub fn union(a: &TriMesh, b: &TriMesh) -> TriMesh {
    let mut both = TriMesh::concat(&[a.clone(), b.clone()]);
    match both.materials.take() {
        None => both.parts = None,
        Some(m) => {
            let n = both.triangles.len();
            let parts: Vec<u32> = match &both.parts {
                Some(p) => p.iter().map(|p| m.of(*p)).collect(),
                None => vec![m.of(0); n],
            };
            both.parts = parts.iter().any(|p| *p != 0).then_some(parts);
            both.materials = Some(Materials {
                of_part: (0..m.table.len() as u32).collect(),
                table: m.table,
            });
        }
    }
    repair_mesh(both, &RepairOptions { weld: Weld::Exact }).0
}

/// A parent: its children's [`union`] simplified with borders locked to
/// half, and to at most `budget` triangles: children whose locked borders
/// kept them over the budget (a split plane across the whole model) give
/// it back where the border is theirs no longer.
fn parent(kids: &[TriMesh], made: &[Made], budget: usize) -> (TriMesh, Made) {
    let union = kids[1..].iter().fold(kids[0].clone(), |u, k| union(&u, k));
    let below = made.iter().map(|m| m.error).fold(0.0, f32::max);
    let opts = SimplifyOptions {
        target: Target::Triangles((union.triangles.len() / 2).min(budget)),
        collapse: CollapseOptions {
            lock_borders: true,
            ..CollapseOptions::default()
        },
        per_triangle_bounds: false,
    };
    // A fresh progress: the tiles of a level run at once, and the build's
    // own progress says which level.
    let (mesh, step) = match simplify::simplify(&union, &opts, &Progress::new()) {
        Ok(s) => {
            let bound = s.error_bound();
            (s.mesh, bound)
        }
        // Only a bad target fails, and half a union's count is a good one;
        // the union itself is then the honest parent.
        Err(_) => (union, 0.0),
    };
    let record = Made {
        // The triangle inequality (module doc), rounded up past f32's
        // round-off of the sum.
        error: (step + below) * (1.0 + 4.0 * f32::EPSILON),
        covers: made.iter().map(|m| m.covers).sum(),
        triangles: mesh.triangles.len(),
        bounds: mesh.bounds(),
    };
    (mesh, record)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtins::torus;
    use crate::distance::{SamplingOptions, hausdorff_mesh_mesh};
    use crate::tiles::partition::{Cell, partition};

    /// Errors grow upwards and hold against a dense measurement of each
    /// tile against the original triangles below it; each parent has at
    /// most the triangles of its children, and the root the tile budget.
    #[test]
    fn every_tile_is_within_its_error_of_the_original_below_it() {
        let mesh = torus(1.0, 0.35, 64, 32);
        let dir = tempfile::tempdir().unwrap();
        let store = Store::open(dir.path()).unwrap();
        let plan = build(&store, &mesh, 512, 2, &Progress::new()).unwrap();
        assert!(plan.levels() >= 3, "{}", plan.levels());
        let made: Vec<Made> = (0..plan.children.len())
            .map(|i| store.made(i).unwrap())
            .collect();
        // The root has no cell border left to keep: the old cells' borders
        // are no seams (parts), so it reaches the tile budget.
        assert!(made[0].triangles <= 512);
        let cells = partition(&mesh, 512);
        // The original triangles below each tile.
        fn below(cells: &[Cell], i: usize, out: &mut Vec<u32>) {
            match &cells[i] {
                Cell::Leaf(t) => out.extend(t),
                Cell::Split(k) => k.iter().for_each(|k| below(cells, *k, out)),
            }
        }
        let sampling = SamplingOptions {
            samples: 20_000,
            seed: 3,
        };
        for (i, tile) in made.iter().enumerate() {
            let content = store.mesh(i).unwrap();
            assert_eq!(content.triangles.len(), tile.triangles);
            let mut tris = Vec::new();
            below(&cells, i, &mut tris);
            assert_eq!(tile.covers, tris.len());
            let kids = &plan.children[i];
            for k in kids {
                assert!(made[*k].error <= tile.error);
            }
            if kids.is_empty() {
                assert_eq!(tile.error, 0.0);
                continue;
            }
            assert!(tile.triangles <= kids.iter().map(|k| made[*k].triangles).sum::<usize>());
            let original = mesh.subset(&tris);
            let measured = hausdorff_mesh_mesh(&original, &content, &sampling).two_sided();
            assert!(
                measured <= tile.error,
                "tile {i}: {measured} > {}",
                tile.error
            );
        }
    }
}
