//! Guaranteed error bounds of the collapse nodes (see the `build` module doc
//! for why they are upper bounds), computed wave by wave while the collapses
//! go on: a collapse's bound needs only what it and the collapses before it
//! made, so a worker bounds each finished wave of [`WAVE`] collapses (its
//! triangles in parallel) while the collapser makes the next one.

use glam::Vec3;
use rayon::prelude::*;

use super::mrg::DRAIN;
use crate::distance::MeshDistance;
use crate::distance::facets::Facets;
use crate::geom::TriMesh;
use crate::simplify::bound::{BoundOptions, Original, max_distance_bound};
use crate::simplify::projection::Projection;

/// Collapses per wave. A triangle's refinement stops below the final error of
/// a child node from an earlier wave, so the waves' size is part of the result.
pub(crate) const WAVE: usize = 1024;

/// One edge collapse as the MRG recorded it.
pub(crate) struct Recorded {
    pub node: u32,
    pub removed: Vec<u32>,
    pub added: Vec<u32>,
    /// The nodes that produced `removed` (the node's children), deduplicated.
    pub kids: Vec<u32>,
}

/// Up to [`WAVE`] collapses in build order, with the vertices and triangles
/// made since the previous wave (the first wave brings the input's too).
pub(crate) struct Wave {
    pub collapses: Vec<Recorded>,
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// The bounding worker's state: its own copy of the MRG's geometry, the
/// attribution of the original triangles and the errors found so far.
pub(crate) struct NodeBounds<'a> {
    mesh: &'a TriMesh,
    original: &'a MeshDistance<'a>,
    projection: &'a Projection<'a>,
    opts: BoundOptions,
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Nearest original distance (and triangle) of every vertex.
    nearest: Vec<(f32, u32)>,
    /// The original triangles each triangle stands for, until it is removed.
    owned: Vec<Vec<u32>>,
    /// Per triangle, the largest distance of its originals to it.
    forward: Vec<f32>,
    /// Per node: the largest exact distance found under it, and its error.
    floor: Vec<f32>,
    error: Vec<f32>,
    facets: Facets,
    region: Vec<u32>,
}

impl<'a> NodeBounds<'a> {
    pub fn new(original: &'a Original<'a>, diagonal: f32) -> Self {
        Self {
            mesh: original.mesh(),
            original: original.distance(),
            projection: original.projection(),
            // Looser than the simplifier's certificate (there are ~3 bounds per
            // collapse): still a true upper bound, within 25% of the lower one or 8 splits.
            opts: BoundOptions {
                rel_tol: 0.25,
                max_splits: 8,
                ..BoundOptions::for_diagonal(diagonal)
            },
            positions: Vec::new(),
            triangles: Vec::new(),
            nearest: Vec::new(),
            owned: Vec::new(),
            forward: Vec::new(),
            floor: vec![0.0; DRAIN as usize + 1],
            error: vec![0.0; DRAIN as usize + 1],
            facets: Facets::default(),
            region: Vec::new(),
        }
    }

    /// Per node id, the error of every collapse node bounded so far.
    pub fn into_errors(self) -> Vec<f32> {
        self.error
    }

    /// Bounds one wave's nodes.
    pub fn wave(&mut self, wave: Wave) {
        let first = self.positions.len();
        self.positions.extend(wave.positions);
        let nearest: Vec<(f32, u32)> = self.positions[first..]
            .par_iter()
            .map(|p| self.original.nearest(*p))
            .collect();
        self.nearest.extend(nearest);
        let originals = self.mesh.triangles.len();
        let t0 = self.triangles.len();
        self.triangles.extend(wave.triangles);
        self.owned.extend((t0..self.triangles.len()).map(|t| {
            if t < originals {
                vec![t as u32]
            } else {
                Vec::new()
            }
        }));
        self.forward.resize(self.triangles.len(), 0.0);
        let last = wave.collapses.iter().map(|c| c.node).max().unwrap_or(0) as usize;
        if self.floor.len() <= last {
            self.floor.resize(last + 1, 0.0);
            self.error.resize(last + 1, 0.0);
        }
        for c in &wave.collapses {
            self.attribute(c);
            // Exact distances bound each triangle's error from below, and a
            // node's error is at least its descendants'.
            let own = c.added.iter().map(|t| self.low(*t)).fold(0.0, f32::max);
            self.floor[c.node as usize] = c
                .kids
                .iter()
                .map(|k| self.floor[*k as usize])
                .fold(own, f32::max);
        }
        // A triangle's refinement stops at what cannot raise its node's error:
        // the floor, or the final error of a child from an earlier wave.
        let jobs: Vec<(u32, f32)> = wave
            .collapses
            .iter()
            .flat_map(|c| {
                let below = self.child_error(c).max(self.floor[c.node as usize]);
                c.added.iter().map(move |t| (*t, below))
            })
            .collect();
        let tri_error: Vec<f32> = jobs
            .par_iter()
            .map(|&(t, below)| self.triangle_bound(t, below))
            .collect();
        let mut errors = tri_error.into_iter();
        for c in &wave.collapses {
            let own = errors.by_ref().take(c.added.len()).fold(0.0, f32::max);
            self.error[c.node as usize] = own.max(self.child_error(c));
        }
    }

    fn child_error(&self, c: &Recorded) -> f32 {
        c.kids
            .iter()
            .map(|k| self.error[*k as usize])
            .fold(0.0, f32::max)
    }

    /// The largest exact distance known on triangle `t`: its vertices' and its originals'.
    fn low(&self, t: u32) -> f32 {
        self.triangles[t as usize]
            .iter()
            .map(|v| self.nearest[*v as usize].0)
            .fold(self.forward[t as usize], f32::max)
    }

    /// Both directions of triangle `t`'s bound, refined no further than `below`.
    fn triangle_bound(&self, t: u32, below: f32) -> f32 {
        let tri = self.triangles[t as usize];
        let p = tri.map(|v| self.positions[v as usize]);
        let at = tri.map(|v| self.nearest[v as usize]);
        let forward = self.forward[t as usize];
        let enough = forward.max(below);
        let to = (self.original, Some(self.projection));
        let (reverse, _, _) = max_distance_bound(p, at, to, &self.opts, enough);
        // f32 round-off of the coordinates (flat collapses bound to 0).
        let scale = p.iter().map(|v| v.abs().max_element()).fold(0.0, f32::max);
        reverse.max(forward) + 8.0 * f32::EPSILON * scale
    }

    /// Attributes the originals of a collapse's removed triangles to its new
    /// triangles: each goes to the nearest one (the largest distance of its
    /// vertices, exact for a whole triangle since the distance to a triangle
    /// is convex), which raises that triangle's original-to-simplified bound.
    fn attribute(&mut self, c: &Recorded) {
        self.region.clear();
        for t in &c.removed {
            self.region
                .extend(std::mem::take(&mut self.owned[*t as usize]));
        }
        self.facets.clear();
        for t in &c.added {
            let p = self.triangles[*t as usize].map(|v| self.positions[v as usize]);
            self.facets.push(&p);
        }
        let (facets, mesh) = (&self.facets, self.mesh);
        let choice: Vec<(usize, f32)> = self
            .region
            .par_iter()
            .with_min_len(256)
            .map(|o| {
                let (k, d) = facets.nearest_cover(&mesh.triangle(*o as usize));
                (k, d.sqrt())
            })
            .collect();
        for (o, (k, d)) in self.region.iter().zip(choice) {
            let t = c.added[k] as usize;
            self.owned[t].push(*o);
            self.forward[t] = self.forward[t].max(d);
        }
    }
}
