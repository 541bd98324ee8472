//! §4.3: merge-tree dependencies, and the node ranges (§4.2, §5.1) that grow
//! along them.
//!
//! A merge of level l may only happen (or be undone) while every vertex of its
//! region of influence stands as it stood at level l: present, with all its own
//! merges below l made and none above l made. Read as links between merges:
//! the merge requires the latest merge below l of each region vertex ("c can
//! collapse to p only when n0…nk are present"), and the earliest merge above l
//! of each region vertex other than the child requires it ("n0…nk can not
//! merge with other vertices unless c first merges with p"). The links point
//! from higher to lower levels, so the merges in place always form a down-set
//! and every swap meets exactly the fan it was built from.

use super::criteria::NormalCone;
use super::{Csr, Merge, NONE, Node};
use crate::geom::TriMesh;

pub(crate) struct Dependencies {
    pub requires: Csr,
    pub dependents: Csr,
}

/// Per vertex, the merges it takes part in (as child or parent), by level.
fn merges_by_vertex(merges: &[Merge], vertices: usize) -> Csr {
    let mut pairs: Vec<(u32, u32)> = merges
        .iter()
        .enumerate()
        .flat_map(|(k, m)| [(m.child, k as u32), (m.parent, k as u32)])
        .collect();
    // Merges are numbered level by level, so sorting by index sorts by level.
    Csr::from_pairs(vertices, &mut pairs)
}

/// The (dependent, requirement) links of §4.3, as read above.
pub(crate) fn links(merges: &[Merge], region: &Csr, vertices: usize) -> Vec<(u32, u32)> {
    let by_vertex = merges_by_vertex(merges, vertices);
    let mut links: Vec<(u32, u32)> = Vec::new();
    for (r, m) in merges.iter().enumerate() {
        for &v in region.row(r) {
            let own = by_vertex.row(v as usize);
            let below = own.partition_point(|k| merges[*k as usize].level < m.level);
            if below > 0 {
                links.push((r as u32, own[below - 1]));
            }
            let above = own.partition_point(|k| merges[*k as usize].level <= m.level);
            if v != m.child && above < own.len() {
                links.push((own[above], r as u32));
            }
        }
    }
    links.sort_unstable();
    links.dedup();
    links
}

/// The links without those implied through another requirement (r needs j
/// and j2, and j2 needs j): about half of them. Links go from higher to lower
/// levels, so the rest implies the same requirements transitively, and the
/// run time (merge once the direct requirements are in place, split the
/// direct dependents first, recursively) keeps the same down-sets while each
/// split or merge walks half as many.
pub(crate) fn dependencies(merges: &[Merge], region: &Csr, vertices: usize) -> Dependencies {
    let mut all = links(merges, region, vertices);
    let full = Csr::from_pairs(merges.len(), &mut all);
    let mut links: Vec<(u32, u32)> = Vec::new();
    for r in 0..merges.len() {
        let req = full.row(r);
        for &j in req {
            let implied = req
                .iter()
                .any(|&j2| j2 != j && full.row(j2 as usize).binary_search(&j).is_ok());
            if !implied {
                links.push((r as u32, j));
            }
        }
    }
    let mut flipped: Vec<(u32, u32)> = links.iter().map(|&(a, b)| (b, a)).collect();
    Dependencies {
        requires: Csr::from_pairs(merges.len(), &mut links),
        dependents: Csr::from_pairs(merges.len(), &mut flipped),
    }
}

/// Relative slack that keeps sphere containment through rounding.
const RADIUS_SLACK: f32 = 1e-5;

/// The node of every merge, and the node its parent had before it.
///
/// A node's downswitch distance bounds how far any original vertex below it
/// moved (the child's bound plus the child-parent distance); its sphere holds
/// them all; its cone holds the normals of every triangle in its regions. All
/// three only grow up the tree, so a node that must be refined has ancestors
/// that must be too, and the walk down from the display vertices finds it.
pub(crate) fn nodes(
    mesh: &TriMesh,
    merges: &[Merge],
    cones: &[NormalCone],
) -> (Vec<Node>, Vec<u32>) {
    let mut nodes: Vec<Node> = Vec::with_capacity(merges.len());
    let mut previous = Vec::with_capacity(merges.len());
    let mut current = vec![NONE; mesh.positions.len()];
    for (k, m) in merges.iter().enumerate() {
        let (pc, pp) = (
            mesh.positions[m.child as usize],
            mesh.positions[m.parent as usize],
        );
        let below = current[m.child as usize];
        let step = pc.distance(pp);
        let mut node = Node {
            center: pp,
            radius: step,
            downswitch: step,
            upswitch: f32::INFINITY,
            cone: cones[k],
        };
        // §4.2: the ranges of the subtree, i.e. of the parent's previous node
        // and of the child's node.
        for j in [current[m.parent as usize], below] {
            if j == NONE {
                continue;
            }
            let o = &nodes[j as usize];
            let reach = o.center.distance(node.center);
            node.downswitch = node.downswitch.max(reach + o.downswitch);
            node.radius = node.radius.max(reach + o.radius);
            node.cone = node.cone.union(o.cone);
        }
        node.radius *= 1.0 + RADIUS_SLACK;
        previous.push(current[m.parent as usize]);
        current[m.parent as usize] = k as u32;
        nodes.push(node);
    }
    // §5.1: a node switches up when its parent vertex's next merge happens.
    let by_vertex = merges_by_vertex(merges, mesh.positions.len());
    for (k, m) in merges.iter().enumerate() {
        let own = by_vertex.row(m.parent as usize);
        let at = own.partition_point(|j| *j <= k as u32);
        if let Some(&next) = own.get(at) {
            nodes[k].upswitch = nodes[next as usize].downswitch;
        }
    }
    (nodes, previous)
}
