//! Exact closest point on a triangle (Ericson, Real-Time Collision Detection §5.1.5),
//! by Voronoi region of the vertices, edges and face.

use glam::Vec3;

pub fn closest_point_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + ab * v;
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + ac * w;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + (c - b) * w;
    }
    let denom = va + vb + vc;
    if denom.abs() < f32::MIN_POSITIVE {
        // Degenerate triangle: closest of its three edges.
        return [(a, b), (b, c), (c, a)]
            .iter()
            .map(|(s, e)| closest_point_on_segment(p, *s, *e))
            .min_by(|x, y| x.distance_squared(p).total_cmp(&y.distance_squared(p)))
            .unwrap_or(a);
    }
    let v = vb / denom;
    let w = vc / denom;
    a + ab * v + ac * w
}

/// The point of segment a–b closest to `p`.
pub fn closest_point_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let d = b - a;
    let len2 = d.length_squared();
    if len2 == 0.0 {
        return a;
    }
    a + d * ((p - a).dot(d) / len2).clamp(0.0, 1.0)
}

/// The barycentric coordinates of `p` (a point of triangle abc), each in
/// [0, 1] and summing to 1; a degenerate triangle answers its first corner.
pub fn barycentric(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> [f32; 3] {
    let (v0, v1, v2) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (v0.dot(v0), v0.dot(v1), v1.dot(v1));
    let (d20, d21) = (v2.dot(v0), v2.dot(v1));
    let denom = d00 * d11 - d01 * d01;
    if denom.abs() <= f32::EPSILON * d00 * d11 || !denom.is_finite() {
        return [1.0, 0.0, 0.0];
    }
    let v = ((d11 * d20 - d01 * d21) / denom).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / denom).clamp(0.0, 1.0 - v);
    [1.0 - v - w, v, w]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn barycentric_coordinates_rebuild_the_point() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let p = Vec3::new(0.25, 0.5, 0.0);
        let [u, v, w] = barycentric(p, a, b, c);
        assert!(((u * a + v * b + w * c) - p).length() < 1e-6);
        assert_eq!(barycentric(Vec3::ONE, a, a, a), [1.0, 0.0, 0.0]);
    }

    /// The closest point is on the triangle and no dense barycentric sample is closer.
    #[test]
    fn matches_dense_barycentric_search() {
        let mut rng = Rng::new(3);
        let mut r = || Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - Vec3::ONE;
        for _ in 0..200 {
            let (a, b, c, p) = (r(), r(), r(), r() * 2.0);
            let q = closest_point_on_triangle(p, a, b, c);
            let d = q.distance(p);
            let n = 60;
            let mut best = f32::INFINITY;
            for i in 0..=n {
                for j in 0..=n - i {
                    let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                    best = best.min((a + (b - a) * u + (c - a) * v).distance(p));
                }
            }
            assert!(d <= best + 1e-5, "exact {d} vs sampled {best}");
            assert!(
                best - d < 0.1,
                "sample grid is within 0.1 of the exact point"
            );
        }
    }
}
