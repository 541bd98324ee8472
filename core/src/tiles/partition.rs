//! The spatial partition of a tileset: a k-d tree over the triangles'
//! centroids, each cell split at the median of its longest axis until it
//! holds at most the tile budget. Balanced by count, so every leaf holds
//! between half the budget and the budget (the tree's levels stay even).

use glam::Vec3;

use crate::geom::TriMesh;

/// A node of the partition: a leaf with its triangles (input order), or
/// two children (indices into the node list).
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    Leaf(Vec<u32>),
    Split([usize; 2]),
}

/// The partition of `mesh`'s triangles into cells of at most `budget`
/// (≥ 1); node 0 is the root. Ties in the median break by triangle index,
/// so the partition depends on nothing but the mesh.
pub fn partition(mesh: &TriMesh, budget: usize) -> Vec<Cell> {
    let budget = budget.max(1);
    let centroid: Vec<Vec3> = mesh
        .triangles
        .iter()
        .map(|t| t.iter().map(|v| mesh.positions[*v as usize]).sum::<Vec3>() / 3.0)
        .collect();
    let mut cells = vec![Cell::Leaf(Vec::new())];
    let mut stack = vec![(
        0usize,
        (0..mesh.triangles.len() as u32).collect::<Vec<u32>>(),
    )];
    while let Some((at, mut tris)) = stack.pop() {
        if tris.len() <= budget {
            cells[at] = Cell::Leaf(tris);
            continue;
        }
        let (lo, hi) = tris.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), t| (lo.min(centroid[*t as usize]), hi.max(centroid[*t as usize])),
        );
        let extent = hi - lo;
        let axis = if extent.x >= extent.y && extent.x >= extent.z {
            0
        } else if extent.y >= extent.z {
            1
        } else {
            2
        };
        let half = tris.len() / 2;
        tris.select_nth_unstable_by(half, |a, b| {
            centroid[*a as usize][axis]
                .total_cmp(&centroid[*b as usize][axis])
                .then(a.cmp(b))
        });
        let right = tris.split_off(half);
        let kids = [cells.len(), cells.len() + 1];
        cells.push(Cell::Leaf(Vec::new()));
        cells.push(Cell::Leaf(Vec::new()));
        cells[at] = Cell::Split(kids);
        stack.push((kids[1], right));
        stack.push((kids[0], tris));
    }
    cells
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtins::icosphere;

    /// Every triangle in exactly one leaf, every leaf within the budget and
    /// at least half of it.
    #[test]
    fn leaves_cover_every_triangle_once_within_the_budget() {
        let mesh = icosphere(Vec3::ZERO, 1.0, 4);
        let budget = 300;
        let cells = partition(&mesh, budget);
        let mut seen = vec![0u32; mesh.triangles.len()];
        for c in &cells {
            if let Cell::Leaf(tris) = c {
                assert!(
                    tris.len() <= budget && 2 * tris.len() >= budget,
                    "{}",
                    tris.len()
                );
                for t in tris {
                    seen[*t as usize] += 1;
                }
            }
        }
        assert!(seen.iter().all(|s| *s == 1));
        assert_eq!(partition(&mesh, budget), cells, "the same partition again");
    }
}
