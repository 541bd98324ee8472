//! Point simplification (§5.4): an octree over the sample centres says which
//! points merge; each merge of up to eight children makes one parent point.
//!
//! The parent is a tight enclosing ball of the child balls ([`Sphere::enclose`],
//! better than the paper's heuristic), its colour the area-weighted mean.
//! Its error bound: every child ball lies inside the parent, so the original
//! surface stays within max εᵢ of it; every point of the parent ball is within
//! R + d(C, O) of the original surface O (d exact, from a BVH). So
//! ε = max(R + d(C, O), max εᵢ). The paper's R + max(εᵢ − rᵢ) assumes the
//! parent's centre lies on the surface; this does not.

use super::mrg::{Point, Sphere};
use crate::geom::Aabb;
use glam::Vec3;

/// One merge: children point ids → the parent point, with its error bound.
#[derive(Debug, Clone, PartialEq)]
pub struct Merge {
    pub children: Vec<u32>,
    pub parent: Point,
    pub error: f32,
}

/// Merges points (with their error bounds); returns the merges in bottom-up
/// order, their parents numbered from `points.len()` on. The last merge's
/// parent is the root (none when there is at most one point).
/// `distance` gives a point's exact distance to the original surface.
pub fn simplify(points: &[Point], errors: &[f32], distance: &Distance<'_>) -> Vec<Merge> {
    let mut w = Work {
        all: points.iter().copied().zip(errors.iter().copied()).collect(),
        merges: Vec::new(),
        distance,
    };
    let mut ids: Vec<u32> = (0..points.len() as u32).collect();
    if ids.len() > 1 {
        let b = Aabb::from_points(points.iter().map(|p| &p.center));
        let half = 0.5 * b.extent().max_element().max(f32::MIN_POSITIVE);
        cell(&mut w, &mut ids, b.center(), half, 0);
    }
    w.merges
}

const MAX_DEPTH: usize = 24;

/// Distance from a point to the original surface.
pub type Distance<'a> = dyn Fn(Vec3) -> f32 + Sync + 'a;

/// What every cell of the octree works with.
struct Work<'a> {
    all: Vec<(Point, f32)>,
    merges: Vec<Merge>,
    distance: &'a Distance<'a>,
}

/// Merges the points of one octree cell into one; returns its id.
fn cell(w: &mut Work, ids: &mut [u32], center: Vec3, half: f32, depth: usize) -> u32 {
    if ids.len() == 1 {
        return ids[0];
    }
    let mut results = Vec::with_capacity(8);
    if depth >= MAX_DEPTH || half <= f32::EPSILON * center.abs().max_element() {
        // Coincident centres: merge in groups of eight.
        let mut level: Vec<u32> = ids.to_vec();
        while level.len() > 8 {
            level = level
                .chunks(8)
                .map(|c| if c.len() == 1 { c[0] } else { merge(w, c) })
                .collect();
        }
        results = level;
    } else {
        let octant = |p: Vec3| {
            usize::from(p.x >= center.x)
                | usize::from(p.y >= center.y) << 1
                | usize::from(p.z >= center.z) << 2
        };
        ids.sort_unstable_by_key(|i| octant(w.all[*i as usize].0.center));
        let mut rest = &mut ids[..];
        while !rest.is_empty() {
            let o = octant(w.all[rest[0] as usize].0.center);
            let n = rest
                .iter()
                .take_while(|i| octant(w.all[**i as usize].0.center) == o)
                .count();
            let (group, tail) = rest.split_at_mut(n);
            let sign = |bit: usize| if o & bit != 0 { 0.5 } else { -0.5 };
            let c = center + Vec3::new(sign(1), sign(2), sign(4)) * half;
            results.push(cell(w, group, c, 0.5 * half, depth + 1));
            rest = tail;
        }
    }
    if results.len() == 1 {
        results[0]
    } else {
        merge(w, &results)
    }
}

fn merge(w: &mut Work, children: &[u32]) -> u32 {
    let kids: Vec<(Point, f32)> = children.iter().map(|i| w.all[*i as usize]).collect();
    let (parent, error) = merged(&kids, w.distance);
    w.all.push((parent, error));
    w.merges.push(Merge {
        children: children.to_vec(),
        parent,
        error,
    });
    w.all.len() as u32 - 1
}

/// The parent point of `children` (point, error bound) and its error bound.
pub fn merged(children: &[(Point, f32)], distance: &Distance<'_>) -> (Point, f32) {
    let balls: Vec<Sphere> = children
        .iter()
        .map(|(p, _)| Sphere {
            center: p.center,
            radius: p.radius,
        })
        .collect();
    let s = Sphere::enclose(&balls);
    let area: f32 = children.iter().map(|(p, _)| p.area).sum();
    let w = |p: &Point| {
        if area > 0.0 {
            p.area / area
        } else {
            1.0 / children.len() as f32
        }
    };
    let color = children.iter().map(|(p, _)| p.color * w(p)).sum();
    let normal = children
        .iter()
        .map(|(p, _)| p.normal * p.area.max(f32::MIN_POSITIVE))
        .sum::<Vec3>()
        .normalize_or_zero();
    let center_error = distance(s.center);
    let error = children
        .iter()
        .map(|c| c.1)
        .fold((s.radius + center_error) * (1.0 + 1e-5), f32::max);
    (
        Point {
            center: s.center,
            radius: s.radius,
            color,
            normal,
            area,
            center_error,
        },
        error,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn octree_merges_everything_into_one_root_with_at_most_eight_children() {
        let mut rng = Rng::new(2);
        let mut points: Vec<Point> = (0..500)
            .map(|_| Point {
                center: Vec3::new(rng.f32(), rng.f32(), 0.0),
                radius: 0.01,
                color: Vec3::new(rng.f32(), 0.5, 0.5),
                normal: Vec3::Z,
                area: 1e-4,
                center_error: 0.0,
            })
            .collect();
        // Coincident centres must still merge.
        points.extend(std::iter::repeat_n(points[0], 20));
        let errors: Vec<f32> = points.iter().map(|p| p.radius).collect();
        // The surface: the plane z = 0.
        let merges = simplify(&points, &errors, &|c: Vec3| c.z.abs());
        let mut consumed = vec![0; points.len() + merges.len()];
        for (i, m) in merges.iter().enumerate() {
            assert!((2..=8).contains(&m.children.len()));
            for c in &m.children {
                assert!(
                    (*c as usize) < points.len() + i,
                    "children exist before the merge"
                );
                consumed[*c as usize] += 1;
                let (child, child_error) = if (*c as usize) < points.len() {
                    (points[*c as usize], errors[*c as usize])
                } else {
                    let k = &merges[*c as usize - points.len()];
                    (k.parent, k.error)
                };
                let parent = Sphere {
                    center: m.parent.center,
                    radius: m.parent.radius,
                };
                assert!(parent.contains(&Sphere {
                    center: child.center,
                    radius: child.radius
                }));
                assert!(m.error >= child_error);
                assert!(m.error >= m.parent.radius + m.parent.center.z.abs());
            }
        }
        let root = points.len() + merges.len() - 1;
        assert!(
            consumed[..root].iter().all(|c| *c == 1),
            "each point merged once"
        );
        assert_eq!(consumed[root], 0);
        let root = merges.last().unwrap();
        assert!(root.parent.area > 0.0 && root.error >= root.parent.radius);
    }
}
