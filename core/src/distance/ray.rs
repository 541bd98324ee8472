//! First hits of rays on a triangle mesh: the BVH's nearest-first search
//! with the ray's entry distance into each box as the box distance, and
//! Möller–Trumbore ("Fast, minimum storage ray/triangle intersection",
//! 1997) at the leaves. What impostors are rendered with.

use glam::Vec3;

use super::Bvh;
use crate::geom::{Aabb, TriMesh};

/// A mesh's triangles ready for rays.
pub struct RayCaster<'a> {
    mesh: &'a TriMesh,
    bvh: Bvh,
}

/// Where a ray first meets the mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) direction.
    pub distance: f32,
    pub triangle: u32,
    /// Barycentric coordinates of the hit in the triangle.
    pub bary: [f32; 3],
}

impl<'a> RayCaster<'a> {
    pub fn new(mesh: &'a TriMesh) -> Self {
        let bounds: Vec<Aabb> = (0..mesh.triangles.len())
            .map(|t| Aabb::from_points(&mesh.triangle(t)))
            .collect();
        RayCaster {
            mesh,
            bvh: Bvh::build(&bounds),
        }
    }

    /// The first hit of the ray from `origin` along unit `dir` (either side
    /// of a triangle), if any.
    pub fn cast(&self, origin: Vec3, dir: Vec3) -> Option<Hit> {
        let inv = dir.recip();
        let (distance, triangle) = self.bvh.nearest_by(
            (f32::INFINITY, u32::MAX),
            |b| entry(origin, inv, b),
            |t| self.hit(origin, dir, t).map_or(f32::INFINITY, |h| h.0),
        )?;
        let (_, bary) = self.hit(origin, dir, triangle)?;
        Some(Hit {
            distance,
            triangle,
            bary,
        })
    }

    fn hit(&self, origin: Vec3, dir: Vec3, t: u32) -> Option<(f32, [f32; 3])> {
        let [a, b, c] = self.mesh.triangle(t as usize);
        let (e1, e2) = (b - a, c - a);
        let p = dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() <= f32::MIN_POSITIVE {
            return None;
        }
        let s = (origin - a) / det;
        let u = s.dot(p);
        let q = s.cross(e1);
        let v = dir.dot(q);
        let along = e2.dot(q);
        let inside = (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && along >= 0.0;
        inside.then_some((along, [1.0 - u - v, u, v]))
    }
}

/// The distance along a ray (`inv`: its direction's reciprocal) at which
/// it enters box `b` (0 from inside); infinite when it misses.
fn entry(origin: Vec3, inv: Vec3, b: &Aabb) -> f32 {
    let t0 = (b.min - origin) * inv;
    let t1 = (b.max - origin) * inv;
    // NaN (0 · ∞ on a face) reads as no limit from that axis.
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element();
    if near <= far { near } else { f32::INFINITY }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a torus every ray's first hit, found through the BVH, is the
    /// nearest of all the triangles it crosses (brute force), and lies on
    /// the ray and its triangle.
    #[test]
    fn the_first_hit_is_the_nearest_crossing() {
        let torus = crate::builtins::torus(1.0, 0.3, 32, 16);
        let caster = RayCaster::new(&torus);
        let mut rng = crate::rng::Rng::new(7);
        let (mut hits, mut misses) = (0, 0);
        for _ in 0..400 {
            let origin = Vec3::new(rng.f32() * 4.0 - 2.0, rng.f32() * 4.0 - 2.0, 3.0);
            let dir = Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, -1.0).normalize();
            let brute = (0..torus.triangles.len() as u32)
                .filter_map(|t| caster.hit(origin, dir, t).map(|h| (h.0, t)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            match (caster.cast(origin, dir), brute) {
                (Some(h), Some((d, _))) => {
                    hits += 1;
                    assert!((h.distance - d).abs() < 1e-5, "{h:?} vs {d}");
                    let [a, b, c] = torus.triangle(h.triangle as usize);
                    let p = a * h.bary[0] + b * h.bary[1] + c * h.bary[2];
                    assert!(p.distance(origin + dir * h.distance) < 1e-4);
                }
                (None, None) => misses += 1,
                (h, b) => panic!("{h:?} vs {b:?}"),
            }
        }
        assert!(hits > 50 && misses > 50, "{hits} hits, {misses} misses");
    }
}
