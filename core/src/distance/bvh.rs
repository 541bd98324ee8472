//! Bounding volume hierarchy over boxes, with a nearest-primitive query that
//! visits the closer child first and prunes by box distance.

use glam::Vec3;

use super::triangle::closest_point_on_triangle;
use crate::geom::{Aabb, TriMesh};

const LEAF_SIZE: usize = 4;

#[derive(Debug, Clone)]
struct Node {
    bounds: Aabb,
    /// Leaf: first index into `order`; internal: index of the right child
    /// (the left child follows the node).
    start_or_right: u32,
    /// Leaf: number of primitives; internal: 0.
    count: u32,
}

#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
}

impl Bvh {
    /// Median split on the longest axis of the centroids.
    pub fn build(bounds: &[Aabb]) -> Bvh {
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * bounds.len() / LEAF_SIZE + 1),
            order: (0..bounds.len() as u32).collect(),
        };
        if !bounds.is_empty() {
            let mut order = std::mem::take(&mut bvh.order);
            bvh.split(bounds, &mut order, 0);
            bvh.order = order;
        }
        bvh
    }

    fn split(&mut self, bounds: &[Aabb], order: &mut [u32], start: usize) {
        let node_bounds = order
            .iter()
            .fold(Aabb::EMPTY, |b, i| b.union(bounds[*i as usize]));
        let id = self.nodes.len();
        self.nodes.push(Node {
            bounds: node_bounds,
            start_or_right: start as u32,
            count: order.len() as u32,
        });
        if order.len() <= LEAF_SIZE {
            return;
        }
        let cb = order
            .iter()
            .fold(Aabb::EMPTY, |b, i| b.grow(bounds[*i as usize].center()));
        let axis = cb.extent().max_position();
        let mid = order.len() / 2;
        order.select_nth_unstable_by(mid, |a, b| {
            bounds[*a as usize].center()[axis].total_cmp(&bounds[*b as usize].center()[axis])
        });
        let (left, right) = order.split_at_mut(mid);
        self.split(bounds, left, start);
        let right_id = self.nodes.len() as u32;
        self.split(bounds, right, start + mid);
        self.nodes[id].start_or_right = right_id;
        self.nodes[id].count = 0;
    }

    /// Number of nodes; node 0 is the root and children follow their parent
    /// (a child always has a larger id), so a reverse sweep visits children first.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The box of node `n`.
    pub fn node_bounds(&self, n: u32) -> Aabb {
        self.nodes[n as usize].bounds
    }

    /// `Ok(primitives)` for a leaf, `Err((left, right))` for an internal node.
    pub fn node(&self, n: u32) -> Result<&[u32], (u32, u32)> {
        let node = &self.nodes[n as usize];
        if node.count > 0 {
            let s = node.start_or_right as usize;
            Ok(&self.order[s..s + node.count as usize])
        } else {
            Err((n + 1, node.start_or_right))
        }
    }

    /// The primitive nearest to `p` under `dist` (which must be at least the
    /// distance to the primitive's box), and its distance; `None` when empty.
    pub fn nearest(&self, p: Vec3, dist: impl Fn(u32) -> f32) -> Option<(f32, u32)> {
        self.nearest_from(p, (f32::INFINITY, u32::MAX), dist)
    }

    /// [`Bvh::nearest`] starting from a known (distance, primitive): a good
    /// guess prunes most boxes from the first one on.
    pub fn nearest_from(
        &self,
        p: Vec3,
        start: (f32, u32),
        dist: impl Fn(u32) -> f32,
    ) -> Option<(f32, u32)> {
        self.nearest_by(start, |b| b.distance(p), dist)
    }

    /// [`Bvh::nearest_from`] in the units of `box_dist` (the distance to a
    /// box, or anything that grows with it: squares save the roots).
    pub fn nearest_by(
        &self,
        start: (f32, u32),
        box_dist: impl Fn(&Aabb) -> f32,
        dist: impl Fn(u32) -> f32,
    ) -> Option<(f32, u32)> {
        let mut best = start;
        let mut stack: [u32; 64] = [0; 64];
        let mut top = usize::from(!self.nodes.is_empty());
        while top > 0 {
            top -= 1;
            let node = &self.nodes[stack[top] as usize];
            if box_dist(&node.bounds) >= best.0 {
                continue;
            }
            if node.count > 0 {
                let s = node.start_or_right as usize;
                for &prim in &self.order[s..s + node.count as usize] {
                    let d = dist(prim);
                    if d < best.0 {
                        best = (d, prim);
                    }
                }
                continue;
            }
            let (l, r) = (stack[top] + 1, node.start_or_right);
            let (dl, dr) = (
                box_dist(&self.nodes[l as usize].bounds),
                box_dist(&self.nodes[r as usize].bounds),
            );
            // Push the farther child first so the nearer one is searched first.
            let (near, far) = if dl <= dr { (l, r) } else { (r, l) };
            if top + 2 <= stack.len() {
                stack[top] = far;
                stack[top + 1] = near;
                top += 2;
            }
        }
        (best.1 != u32::MAX).then_some(best)
    }
}

/// Distance from points to a triangle mesh's surface.
pub struct MeshDistance<'a> {
    pub(crate) mesh: &'a TriMesh,
    pub(crate) bvh: Bvh,
    /// Each triangle's corners: one read per triangle tested, not four.
    corners: Vec<[Vec3; 3]>,
}

impl<'a> MeshDistance<'a> {
    pub fn new(mesh: &'a TriMesh) -> Self {
        let corners: Vec<[Vec3; 3]> = (0..mesh.triangles.len())
            .map(|t| mesh.triangle(t))
            .collect();
        let boxes: Vec<Aabb> = corners.iter().map(Aabb::from_points).collect();
        Self {
            mesh,
            bvh: Bvh::build(&boxes),
            corners,
        }
    }

    /// Closest surface point and its triangle; `None` for an empty mesh.
    pub fn closest(&self, p: Vec3) -> Option<(Vec3, u32)> {
        let (_, t) = self.nearest_squared(p, (f32::INFINITY, u32::MAX))?;
        let [a, b, c] = self.corners[t as usize];
        Some((closest_point_on_triangle(p, a, b, c), t))
    }

    /// The nearest triangle by squared distance, from a known one.
    fn nearest_squared(&self, p: Vec3, start: (f32, u32)) -> Option<(f32, u32)> {
        let d2 = |t: u32| self.triangle_distance_squared(p, t);
        self.bvh.nearest_by(start, |b| b.distance_squared(p), d2)
    }

    fn triangle_distance_squared(&self, p: Vec3, t: u32) -> f32 {
        let [a, b, c] = self.corners[t as usize];
        closest_point_on_triangle(p, a, b, c).distance_squared(p)
    }

    pub fn distance(&self, p: Vec3) -> f32 {
        self.closest(p)
            .map_or(f32::INFINITY, |(q, _)| q.distance(p))
    }

    /// Each triangle's corners, in the mesh's order.
    pub fn corners(&self) -> &[[Vec3; 3]] {
        &self.corners
    }

    /// Exact distance from `p` to triangle `t` of the mesh.
    pub fn triangle_distance(&self, p: Vec3, t: u32) -> f32 {
        self.triangle_distance_squared(p, t).sqrt()
    }

    /// Distance to the surface and the nearest triangle (`u32::MAX` when empty).
    pub fn nearest(&self, p: Vec3) -> (f32, u32) {
        self.nearest_near(p, u32::MAX)
    }

    /// [`MeshDistance::nearest`] searched from triangle `hint` (a neighbour's
    /// nearest triangle is usually near).
    pub fn nearest_near(&self, p: Vec3, hint: u32) -> (f32, u32) {
        let start = if (hint as usize) < self.corners.len() {
            (self.triangle_distance_squared(p, hint), hint)
        } else {
            (f32::INFINITY, u32::MAX)
        };
        self.nearest_squared(p, start)
            .map_or((f32::INFINITY, u32::MAX), |(d2, t)| (d2.sqrt(), t))
    }
}

/// Distance from points to a union of solid balls (points with radii).
pub struct SphereSetDistance<'a> {
    centers: &'a [Vec3],
    radii: &'a [f32],
    bvh: Bvh,
}

impl<'a> SphereSetDistance<'a> {
    pub fn new(centers: &'a [Vec3], radii: &'a [f32]) -> Self {
        let boxes: Vec<Aabb> = centers
            .iter()
            .zip(radii)
            .map(|(c, r)| Aabb {
                min: *c - Vec3::splat(*r),
                max: *c + Vec3::splat(*r),
            })
            .collect();
        Self {
            centers,
            radii,
            bvh: Bvh::build(&boxes),
        }
    }

    /// 0 inside a ball, else the distance to the nearest ball's surface.
    pub fn distance(&self, p: Vec3) -> f32 {
        self.bvh
            .nearest(p, |i| {
                (p.distance(self.centers[i as usize]) - self.radii[i as usize]).max(0.0)
            })
            .map_or(f32::INFINITY, |(d, _)| d)
    }
}
