//! The tile tree as named steps: partition, leaves (the original
//! triangles of each cell, with their materials and attributes), then
//! level by level from the deepest, each parent as its children's union
//! welded along their shared border and simplified to half (and to the
//! tile budget) with every border locked, its error composed (module
//! doc of `tiles`). The tiles of one level are independent: they run on
//! worker threads of their own, not as rayon tasks (the collapse waits for
//! its bound worker, which needs rayon's pool: tiles as tasks deadlock once
//! every pool thread waits), and the tree depends on nothing but the mesh
//! and budget.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use super::partition::{Cell, partition};
use crate::geom::repair::repair_mesh;
use crate::geom::{Materials, RepairOptions, TriMesh, Weld};
use crate::progress::{Cancelled, Progress};
use crate::simplify::{self, CollapseOptions, SimplifyOptions, Target};

/// One tile: its content, its children (indices into [`TileTree::tiles`])
/// and its certified error against the original triangles it stands for.
#[derive(Debug, Clone)]
pub struct Tile {
    pub mesh: TriMesh,
    pub children: Vec<usize>,
    /// Depth in the tree (the root is 0).
    pub depth: usize,
    /// Two-sided Hausdorff bound against the original triangles below
    /// (0 for a leaf: it is the original).
    pub error: f32,
    /// How many original triangles it stands for.
    pub covers: usize,
}

/// A tileset's tree; tile 0 is the root.
#[derive(Debug, Clone)]
pub struct TileTree {
    pub tiles: Vec<Tile>,
}

impl TileTree {
    /// Levels from the root to the deepest leaf.
    pub fn levels(&self) -> usize {
        self.tiles.iter().map(|t| t.depth + 1).max().unwrap_or(0)
    }
}

/// The tile tree of `mesh` with leaves of at most `tile_triangles`, the
/// tiles of a level made by `workers` threads at a time.
///
/// # Errors
/// `Cancelled` when `progress` is cancelled (checked between tiles).
pub fn build(
    mesh: &TriMesh,
    tile_triangles: usize,
    workers: usize,
    progress: &Progress,
) -> Result<TileTree, Cancelled> {
    progress.stage("tiles: partitioning");
    let cells = partition(mesh, tile_triangles);
    let mut depth = vec![0usize; cells.len()];
    for (i, c) in cells.iter().enumerate() {
        if let Cell::Split(kids) = c {
            for k in kids {
                depth[*k] = depth[i] + 1;
            }
        }
    }
    let deepest = depth.iter().copied().max().unwrap_or(0);
    let mut made: Vec<Option<Tile>> = vec![None; cells.len()];
    for level in (0..=deepest).rev() {
        progress.stage(&format!("tiles: level {level} of {deepest}"));
        progress.set_fraction((deepest - level) as f32 / (deepest + 1) as f32);
        let at: Vec<usize> = (0..cells.len()).filter(|i| depth[*i] == level).collect();
        let next = AtomicUsize::new(0);
        let done = Mutex::new(Vec::with_capacity(at.len()));
        let made_so_far = &made;
        std::thread::scope(|scope| {
            for _ in 0..workers.clamp(1, at.len().max(1)) {
                scope.spawn(|| {
                    while let Some(&i) = at.get(next.fetch_add(1, Ordering::Relaxed)) {
                        if progress.is_cancelled() {
                            return;
                        }
                        let tile = match &cells[i] {
                            Cell::Leaf(tris) => Tile {
                                mesh: mesh.arrays().gather(tris.iter().copied()),
                                children: Vec::new(),
                                depth: level,
                                error: 0.0,
                                covers: tris.len(),
                            },
                            Cell::Split(kids) => {
                                let tiles =
                                    kids.map(|k| made_so_far[k].as_ref().expect("children first"));
                                Tile {
                                    children: kids.to_vec(),
                                    ..parent(&tiles, tile_triangles, level)
                                }
                            }
                        };
                        done.lock()
                            .unwrap_or_else(|e| e.into_inner())
                            .push((i, tile));
                    }
                });
            }
        });
        progress.check()?;
        for (i, tile) in done.into_inner().unwrap_or_else(|e| e.into_inner()) {
            made[i] = Some(tile);
        }
    }
    Ok(TileTree {
        tiles: made
            .into_iter()
            .map(|t| t.expect("every cell is made"))
            .collect(),
    })
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
fn parent(kids: &[&Tile; 2], budget: usize, depth: usize) -> Tile {
    let union = union(&kids[0].mesh, &kids[1].mesh);
    let below = kids[0].error.max(kids[1].error);
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
    Tile {
        mesh,
        children: Vec::new(),
        depth,
        // The triangle inequality (module doc), rounded up past f32's
        // round-off of the sum.
        error: (step + below) * (1.0 + 4.0 * f32::EPSILON),
        covers: kids[0].covers + kids[1].covers,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtins::torus;
    use crate::distance::{SamplingOptions, hausdorff_mesh_mesh};

    /// Errors grow upwards and hold against a dense measurement of each
    /// tile against the original triangles below it; each parent has at
    /// most the triangles of its children, and the root the tile budget.
    #[test]
    fn every_tile_is_within_its_error_of_the_original_below_it() {
        let mesh = torus(1.0, 0.35, 64, 32);
        let tree = build(&mesh, 512, 2, &Progress::new()).unwrap();
        assert!(tree.levels() >= 3, "{}", tree.levels());
        // The root has no cell border left to keep: the old cells' borders
        // are no seams (parts), so it reaches the tile budget.
        assert!(tree.tiles[0].mesh.triangles.len() <= 512);
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
        for (i, tile) in tree.tiles.iter().enumerate() {
            let mut tris = Vec::new();
            below(&cells, i, &mut tris);
            assert_eq!(tile.covers, tris.len());
            for k in &tile.children {
                assert!(tree.tiles[*k].error <= tile.error);
            }
            if tile.children.is_empty() {
                assert_eq!(tile.error, 0.0);
                continue;
            }
            let kids: usize = tile
                .children
                .iter()
                .map(|k| tree.tiles[*k].mesh.triangles.len())
                .sum();
            assert!(tile.mesh.triangles.len() <= kids);
            let original = mesh.subset(&tris);
            let measured = hausdorff_mesh_mesh(&original, &tile.mesh, &sampling).two_sided();
            assert!(
                measured <= tile.error,
                "tile {i}: {measured} > {}",
                tile.error
            );
        }
    }
}
