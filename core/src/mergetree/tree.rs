//! §4.1: the merge tree, built upwards level by level. At each level as many
//! edges as possible collapse, shortest first, such that no two of their
//! regions of influence share a triangle; the children stay at the level and
//! every other vertex is promoted.
//!
//! The region of influence is "the set of triangles that can change as an edge
//! is gradually collapsed": with the parent kept in place (Fig. 2) that is the
//! child's fan. Taking the parent's fan too (as for a midpoint placement)
//! blocks more collapses per level (36 levels instead of 19 for a 2562-vertex
//! icosphere, above 3·log2(n)); each vertex still takes part in one merge per level,
//! so the tree stays binary.

use glam::Vec3;

use super::criteria::NormalCone;
use super::{Csr, MergeTreeOptions};
use crate::geom::{Adjacency, TriMesh};
use crate::progress::{Cancelled, Progress};
use crate::simplify::collapse::{
    border_vertices, constrained_vertices, link_condition, quality, triangle_change_allowed,
};

/// One parent-child relationship (Fig. 2): `child` merges into `parent`, which
/// stays where it is, at tree level `level`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Merge {
    pub child: u32,
    pub parent: u32,
    pub level: u32,
}

/// What the levels produce, for the dependency pass.
pub(crate) struct Built {
    pub merges: Vec<Merge>,
    pub triangles: Vec<[u32; 3]>,
    pub origin: Vec<u32>,
    pub removed: Csr,
    pub added: Csr,
    /// Per merge, the vertices of its region of influence (parent and child
    /// included): the n0…nk of §4.3.
    pub region: Csr,
    /// Per merge, the normals of the triangles of its region, before and after.
    pub cones: Vec<NormalCone>,
    pub levels: Vec<usize>,
}

fn normal(p: [Vec3; 3]) -> Vec3 {
    (p[1] - p[0]).cross(p[2] - p[0])
}

struct Builder<'a> {
    mesh: &'a TriMesh,
    opts: &'a MergeTreeOptions,
    tri_part: Vec<u32>,
    constrained: Vec<bool>,
    /// On a border of the mesh itself: two such joined by an inner edge never merge.
    border: Vec<bool>,
    tris: Vec<[u32; 3]>,
    origin: Vec<u32>,
    vtris: Vec<Vec<u32>>,
    /// Level + 1 at which a triangle lies in some collapse's region of influence.
    taken: Vec<u32>,
    /// Level + 1 at which a vertex merged or absorbed a child.
    busy: Vec<u32>,
    mark: (Vec<u32>, u32),
}

impl Builder<'_> {
    fn pos(&self, v: u32) -> Vec3 {
        self.mesh.positions[v as usize]
    }

    /// Whether collapsing `c` into `p` is legal (§4.1, [17]): link condition,
    /// borders and seams only along themselves, no fold against the previous
    /// triangle (fold guard) nor against the input triangle it stands for, and
    /// the §6 sliver guard. Returns the worst quality (eq. 3) it makes.
    fn legal(&mut self, c: u32, p: u32) -> Option<f32> {
        let shared: Vec<u32> = self.vtris[c as usize]
            .iter()
            .copied()
            .filter(|t| self.tris[*t as usize].contains(&p))
            .collect();
        if shared.is_empty()
            || shared.len() > 2
            || shared.len() == 2 && self.border[c as usize] && self.border[p as usize]
        {
            return None;
        }
        if self.constrained[c as usize] {
            let along = shared.len() == 1
                || self.tri_part[self.origin[shared[0] as usize] as usize]
                    != self.tri_part[self.origin[shared[1] as usize] as usize];
            if self.opts.collapse.lock_borders || !self.constrained[p as usize] || !along {
                return None;
            }
        }
        let (mark, stamp) = &mut self.mark;
        if !link_condition(&self.vtris, &self.tris, mark, stamp, [c, p], shared.len()) {
            return None;
        }
        let mut worst = 1f32;
        for &t in &self.vtris[c as usize] {
            let tri = self.tris[t as usize];
            if tri.contains(&p) {
                continue;
            }
            let old = tri.map(|w| self.pos(w));
            let new = tri.map(|w| self.pos(if w == c { p } else { w }));
            let original = normal(self.mesh.triangle(self.origin[t as usize] as usize));
            if !triangle_change_allowed(old, new, &self.opts.collapse)
                || normal(new).dot(original) <= 0.0
            {
                return None;
            }
            worst = worst.min(quality(new));
        }
        Some(worst)
    }
}

pub(crate) fn build_levels(
    mesh: &TriMesh,
    opts: &MergeTreeOptions,
    progress: &Progress,
) -> Result<Built, Cancelled> {
    let n = mesh.positions.len();
    let nt = mesh.triangles.len();
    let tri_part: Vec<u32> = (0..nt).map(|t| mesh.part(t)).collect();
    let adj = Adjacency::new(&mesh.triangles);
    let mut vtris = vec![Vec::new(); n];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for v in tri {
            vtris[*v as usize].push(t as u32);
        }
    }
    let mut b = Builder {
        mesh,
        opts,
        constrained: constrained_vertices(mesh, &adj, &tri_part),
        border: border_vertices(mesh, &adj),
        tri_part,
        tris: mesh.triangles.clone(),
        origin: (0..nt as u32).collect(),
        vtris,
        taken: vec![0; nt],
        busy: vec![0; n],
        mark: (vec![0; n], 0),
    };
    let mut out = Built {
        merges: Vec::new(),
        triangles: Vec::new(),
        origin: Vec::new(),
        removed: Csr::default(),
        added: Csr::default(),
        region: Csr::default(),
        cones: Vec::new(),
        levels: Vec::new(),
    };
    let mut present = b.vtris.iter().filter(|t| !t.is_empty()).count();
    let mut edges: Vec<(f32, u32, u32)> = Vec::new();
    let mut ring: Vec<u32> = Vec::new();
    let mut level = 0u32;
    loop {
        progress.check()?;
        progress.set_fraction(1.0 - present as f32 / n.max(1) as f32);
        out.levels.push(present);
        if progress.wants_preview() {
            // Watching the build: this level's mesh (vertices keep their
            // positions; merged children simply leave the triangles).
            let mut alive: Vec<u32> = b.vtris.iter().flatten().copied().collect();
            alive.sort_unstable();
            alive.dedup();
            progress.publish(crate::lod::DrawSet {
                mesh: TriMesh::new(
                    mesh.positions.clone(),
                    alive.iter().map(|&t| b.tris[t as usize]).collect(),
                ),
                ..Default::default()
            });
        }
        if present <= opts.min_vertices {
            break;
        }
        // §4.1: shortest edges first.
        edges.clear();
        for (v, ts) in b.vtris.iter().enumerate() {
            for &t in ts {
                for w in b.tris[t as usize] {
                    if w as usize > v {
                        let len = mesh.positions[v].distance(mesh.positions[w as usize]);
                        edges.push((len, v as u32, w));
                    }
                }
            }
        }
        edges.sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
        edges.dedup();
        let tag = level + 1;
        let before = out.merges.len();
        for &(_, u, w) in &edges {
            if present <= opts.min_vertices {
                break;
            }
            // Regions of influence of one level share no triangle, and every
            // vertex takes part in at most one merge per level (a binary tree).
            let free = |c: u32, p: u32| {
                b.busy[c as usize] != tag
                    && b.busy[p as usize] != tag
                    && b.vtris[c as usize]
                        .iter()
                        .all(|t| b.taken[*t as usize] != tag)
            };
            // Either end may be the child; prefer the better-shaped result (§6).
            let dirs = [(u, w), (w, u)].map(|(c, p)| (c, p, free(c, p)));
            let best = dirs
                .into_iter()
                .filter(|d| d.2)
                .filter_map(|(c, p, _)| b.legal(c, p).map(|q| (q, c, p)))
                .max_by(|x, y| x.0.total_cmp(&y.0));
            let Some((_, c, p)) = best else { continue };
            b.busy[c as usize] = tag;
            b.busy[p as usize] = tag;
            // p takes c's edges, its border edges among them.
            b.border[p as usize] |= b.border[c as usize];
            ring.clear();
            let mut cone = NormalCone::EMPTY;
            for &t in b.vtris[c as usize].iter().chain(&b.vtris[p as usize]) {
                let tri = b.tris[t as usize];
                cone = cone.union(NormalCone::of(normal(tri.map(|v| b.pos(v)))));
            }
            for &t in &b.vtris[c as usize] {
                b.taken[t as usize] = tag;
                ring.extend(b.tris[t as usize]);
            }
            ring.sort_unstable();
            ring.dedup();
            out.region.push_row(ring.iter().copied());
            let fan = std::mem::take(&mut b.vtris[c as usize]);
            let mut added = Vec::with_capacity(fan.len());
            for &t in &fan {
                let tri = b.tris[t as usize];
                for w in tri {
                    if w != c {
                        b.vtris[w as usize].retain(|x| *x != t);
                    }
                }
                if tri.contains(&p) {
                    continue;
                }
                let id = b.tris.len() as u32;
                let new = tri.map(|w| if w == c { p } else { w });
                b.tris.push(new);
                b.origin.push(b.origin[t as usize]);
                b.taken.push(tag);
                for w in new {
                    b.vtris[w as usize].push(id);
                }
                cone = cone.union(NormalCone::of(normal(new.map(|v| b.pos(v)))));
                added.push(id);
            }
            out.removed.push_row(fan);
            out.added.push_row(added);
            out.cones.push(cone);
            out.merges.push(Merge {
                child: c,
                parent: p,
                level,
            });
            present -= 1;
        }
        if out.merges.len() == before {
            // §4.1 (b): nothing can merge any more; this is the top level.
            break;
        }
        level += 1;
    }
    out.triangles = b.tris;
    out.origin = b.origin;
    Ok(out)
}

#[cfg(test)]
mod watched {
    use super::*;

    /// A watched build publishes a level's mesh: the input's vertices, and
    /// no more triangles than the input.
    #[test]
    fn watched_builds_publish_a_level() {
        let mesh = crate::builtins::torus(1.0, 0.3, 32, 16);
        let progress = Progress::new();
        progress.watch();
        crate::mergetree::build(&mesh, &Default::default(), &progress).unwrap();
        let state = progress.take_preview().expect("a level");
        assert_eq!(state.mesh.positions, mesh.positions);
        let n = state.mesh.triangles.len();
        assert!(n > 0 && n <= mesh.triangles.len(), "{n}");
    }
}
