//! Click to inspect: the primitive of a cut nearest along a ray.

use glam::Vec3;

use super::DrawSet;

/// What a ray hit on a cut (the studio's click-to-inspect).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Picked {
    /// Triangle `index` of the cut's mesh, with its error bound when known.
    Triangle {
        index: usize,
        error: Option<f32>,
    },
    Point {
        index: usize,
        radius: f32,
        error: f32,
    },
    Splat {
        index: usize,
        domain: usize,
    },
    Layer {
        layer: usize,
        isodensity: f32,
    },
}

/// Distance along the ray (origin, unit dir) to triangle `t`, if it is hit
/// (Möller–Trumbore, both faces).
fn ray_triangle(origin: Vec3, dir: Vec3, [a, b, c]: [Vec3; 3]) -> Option<f32> {
    let (e1, e2) = (b - a, c - a);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return None;
    }
    let s = origin - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0).then_some(t)
}

impl DrawSet {
    /// The primitive nearest along the ray from `origin` in direction `dir`.
    pub fn pick(&self, origin: Vec3, dir: Vec3) -> Option<(f32, Picked)> {
        let dir = dir.normalize_or_zero();
        let mut best: Option<(f32, Picked)> = None;
        let mut offer = |t: f32, p: Picked| {
            if best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, p));
            }
        };
        for i in 0..self.mesh.triangles.len() {
            if let Some(t) = ray_triangle(origin, dir, self.mesh.triangle(i)) {
                let error = self.triangle_errors.get(i).copied();
                offer(t, Picked::Triangle { index: i, error });
            }
        }
        for (i, p) in self.points.iter().enumerate() {
            // Ray against the point's ball.
            let oc = p.center - origin;
            let along = oc.dot(dir);
            let d2 = oc.length_squared() - along * along;
            if along > 0.0 && d2 <= p.radius * p.radius {
                let t = along - (p.radius * p.radius - d2).max(0.0).sqrt();
                offer(
                    t,
                    Picked::Point {
                        index: i,
                        radius: p.radius,
                        error: p.error,
                    },
                );
            }
        }
        for (i, s) in self.splats.iter().enumerate() {
            let corners = s.corners();
            for tri in [
                [corners[0], corners[1], corners[2]],
                [corners[0], corners[2], corners[3]],
            ] {
                if let Some(t) = ray_triangle(origin, dir, tri) {
                    offer(
                        t,
                        Picked::Splat {
                            index: i,
                            domain: s.domain,
                        },
                    );
                }
            }
        }
        for (l, layer) in self.layers.iter().enumerate() {
            for i in 0..layer.mesh.triangles.len() {
                if let Some(t) = ray_triangle(origin, dir, layer.mesh.triangle(i)) {
                    offer(
                        t,
                        Picked::Layer {
                            layer: l,
                            isodensity: layer.isodensity,
                        },
                    );
                }
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::TriMesh;
    use crate::lod::{CutPoint, DrawSet};

    #[test]
    fn picking_finds_the_nearest_primitive_of_each_kind() {
        let mut set = DrawSet {
            mesh: TriMesh::new(
                vec![
                    Vec3::new(-1.0, -1.0, 0.0),
                    Vec3::new(1.0, -1.0, 0.0),
                    Vec3::new(0.0, 1.0, 0.0),
                ],
                vec![[0, 1, 2]],
            ),
            triangle_errors: vec![0.25],
            ..Default::default()
        };
        let down = Vec3::NEG_Z;
        let hit = set.pick(Vec3::new(0.0, 0.0, 5.0), down);
        assert_eq!(
            hit,
            Some((
                5.0,
                Picked::Triangle {
                    index: 0,
                    error: Some(0.25)
                }
            ))
        );
        assert_eq!(set.pick(Vec3::new(3.0, 0.0, 5.0), down), None, "beside it");
        // A point in front of the triangle is nearer.
        set.points.push(CutPoint {
            center: Vec3::new(0.0, 0.0, 1.0),
            radius: 0.5,
            color: Vec3::ONE,
            normal: Vec3::Z,
            error: 0.7,
        });
        let (t, p) = set.pick(Vec3::new(0.0, 0.0, 5.0), down).unwrap();
        assert!((t - 3.5).abs() < 1e-5);
        assert_eq!(
            p,
            Picked::Point {
                index: 0,
                radius: 0.5,
                error: 0.7
            }
        );
        // Behind the eye nothing counts.
        assert_eq!(set.pick(Vec3::new(0.0, 0.0, -5.0), down), None);
    }
}
