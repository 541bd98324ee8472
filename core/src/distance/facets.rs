//! Exact point distances to a handful of triangles (an edge collapse's star),
//! eight triangles per step: the hybrid queue and attribution ask a dozen
//! points against ten triangles for every candidate, where a branchy
//! closest-point search per pair costs more than the whole collapse.
//!
//! Branch-free form of the distance: a point whose projection falls inside
//! the triangle is at its plane distance; any other point is nearest to one of
//! the three edges (segment distance). A degenerate triangle has no inside.

use glam::Vec3;

/// Lanes per block.
const LANES: usize = 8;

/// Eight triangles in columns (structure of arrays); unused lanes are far away.
struct Block {
    /// Vertex 0 and the unit normal (zero when degenerate).
    a: [[f32; LANES]; 3],
    n: [[f32; LANES]; 3],
    /// Per edge i (from vertex i to i + 1): start, direction, 1/length²,
    /// outward in-plane normal.
    s: [[[f32; LANES]; 3]; 3],
    e: [[[f32; LANES]; 3]; 3],
    inv: [[f32; LANES]; 3],
    m: [[[f32; LANES]; 3]; 3],
    /// 0, or +∞ for a degenerate (or unused) lane: nothing is inside it.
    flat: [f32; LANES],
}

const FAR: f32 = 1e30;

impl Block {
    fn empty() -> Block {
        Block {
            a: [[FAR; LANES]; 3],
            n: [[0.0; LANES]; 3],
            s: [[[FAR; LANES]; 3]; 3],
            e: [[[0.0; LANES]; 3]; 3],
            inv: [[0.0; LANES]; 3],
            m: [[[0.0; LANES]; 3]; 3],
            flat: [f32::INFINITY; LANES],
        }
    }

    fn set(&mut self, l: usize, t: &[Vec3; 3]) {
        let cross = (t[1] - t[0]).cross(t[2] - t[0]);
        let n = cross.normalize_or_zero();
        let put = |c: &mut [[f32; LANES]; 3], v: Vec3| {
            c[0][l] = v.x;
            c[1][l] = v.y;
            c[2][l] = v.z;
        };
        put(&mut self.a, t[0]);
        put(&mut self.n, n);
        for i in 0..3 {
            let (s, e) = (t[i], t[(i + 1) % 3] - t[i]);
            put(&mut self.s[i], s);
            put(&mut self.e[i], e);
            put(&mut self.m[i], e.cross(n));
            let len2 = e.length_squared();
            self.inv[i][l] = if len2 > 0.0 { 1.0 / len2 } else { 0.0 };
        }
        self.flat[l] = if n == Vec3::ZERO { f32::INFINITY } else { 0.0 };
    }

    /// Squared distance from `q` to each lane's triangle, eight lanes per
    /// instruction where the CPU has AVX2 (FMA stays off: the same bits).
    #[inline(always)]
    fn distances(&self, q: Vec3, out: &mut [f32; LANES]) {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            #[target_feature(enable = "avx2")]
            fn wide(b: &Block, q: Vec3, out: &mut [f32; LANES]) {
                b.lanes(q, out)
            }
            // SAFETY: the CPU has AVX2.
            return unsafe { wide(self, q, out) };
        }
        self.lanes(q, out)
    }

    #[inline(always)]
    fn lanes(&self, q: Vec3, out: &mut [f32; LANES]) {
        let q = [q.x, q.y, q.z];
        for l in 0..LANES {
            let dot = |v: &[[f32; LANES]; 3], o: &[[f32; LANES]; 3]| {
                (q[0] - o[0][l]) * v[0][l] + (q[1] - o[1][l]) * v[1][l] + (q[2] - o[2][l]) * v[2][l]
            };
            let h = dot(&self.n, &self.a);
            let mut outside = self.flat[l];
            let mut edge = f32::INFINITY;
            for i in 0..3 {
                outside = max(outside, dot(&self.m[i], &self.s[i]));
                let t = min(max(dot(&self.e[i], &self.s[i]) * self.inv[i][l], 0.0), 1.0);
                let d: [f32; 3] =
                    std::array::from_fn(|k| q[k] - self.s[i][k][l] - t * self.e[i][k][l]);
                edge = min(edge, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            }
            out[l] = if outside <= 0.0 { h * h } else { edge };
        }
    }
}

/// `f32::max` and `f32::min` without their NaN rules, which keep the
/// compiler from using vector min/max; no input here is NaN, so the results
/// are the same.
#[inline(always)]
fn max(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

#[inline(always)]
fn min(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// A small set of triangles to measure points against.
#[derive(Default)]
pub struct Facets {
    blocks: Vec<Block>,
    len: usize,
}

impl Facets {
    pub fn clear(&mut self) {
        self.blocks.clear();
        self.len = 0;
    }

    pub fn push(&mut self, t: &[Vec3; 3]) {
        let l = self.len % LANES;
        if l == 0 {
            self.blocks.push(Block::empty());
        }
        if let Some(b) = self.blocks.last_mut() {
            b.set(l, t);
        }
        self.len += 1;
    }

    /// Squared distance from `q` to the nearest triangle (∞ when empty).
    #[inline(always)]
    pub fn nearest_squared(&self, q: Vec3) -> f32 {
        let mut d = [0.0f32; LANES];
        let mut best = f32::INFINITY;
        for b in &self.blocks {
            b.distances(q, &mut d);
            best = d.iter().fold(best, |m, x| min(m, *x));
        }
        best
    }

    /// The triangle whose largest squared distance to the points `v` is
    /// smallest, with that value (the first on ties; `(0, ∞)` when empty),
    /// and the largest over the points of their squared distance to the
    /// nearest triangle, in one pass; `nearest` is scratch, one per point.
    #[inline(always)]
    pub fn cover_and_nearest(&self, v: &[Vec3], nearest: &mut [f32]) -> (usize, f32, f32) {
        assert!(nearest.len() >= v.len(), "scratch for every point");
        let (mut d, mut worst) = ([0.0f32; LANES], [0.0f32; LANES]);
        let mut best = (0, f32::INFINITY);
        let nearest = &mut nearest[..v.len()];
        nearest.fill(f32::INFINITY);
        for (k, b) in self.blocks.iter().enumerate() {
            worst.fill(0.0);
            let used = self.len - k * LANES;
            for (i, q) in v.iter().enumerate() {
                b.distances(*q, &mut d);
                for l in 0..LANES {
                    worst[l] = max(worst[l], d[l]);
                }
                nearest[i] = d.iter().take(used).fold(nearest[i], |m, x| min(m, *x));
            }
            for (l, w) in worst.iter().enumerate().take(used) {
                if *w < best.1 {
                    best = (k * LANES + l, *w);
                }
            }
        }
        (best.0, best.1, nearest.iter().fold(0.0, |m, x| max(m, *x)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance::closest_point_on_triangle;
    use crate::rng::Rng;

    /// Against the closest-point search, over random, thin and degenerate
    /// triangles and points around them.
    #[test]
    fn distances_match_the_closest_point() {
        let mut rng = Rng::new(11);
        let mut v = || Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0;
        for round in 0..200 {
            let mut tris: Vec<[Vec3; 3]> = (0..1 + round % 13).map(|_| [v(), v(), v()]).collect();
            // A sliver, a segment and a point among them.
            let (p, q) = (v(), v());
            tris.push([p, q, p + (q - p) * 0.5 + Vec3::splat(1e-4)]);
            tris.push([p, q, p + (q - p) * 0.25]);
            tris.push([p, p, p]);
            let mut f = Facets::default();
            for t in &tris {
                f.push(t);
            }
            for _ in 0..20 {
                let x = v() * 1.5;
                let exact: Vec<f32> = tris
                    .iter()
                    .map(|t| closest_point_on_triangle(x, t[0], t[1], t[2]).distance_squared(x))
                    .collect();
                let min = exact.iter().copied().fold(f32::INFINITY, f32::min);
                let got = f.nearest_squared(x);
                assert!((got - min).abs() <= 1e-5 * (1.0 + min), "{got} vs {min}");
                let pts = [x, v(), v()];
                let (k, w, far) = f.cover_and_nearest(&pts, &mut [0.0; 3]);
                let farthest = pts
                    .iter()
                    .map(|q| f.nearest_squared(*q))
                    .fold(0.0, f32::max);
                assert_eq!(far, farthest);
                let cover = |t: &[Vec3; 3]| {
                    pts.iter()
                        .map(|q| {
                            closest_point_on_triangle(*q, t[0], t[1], t[2]).distance_squared(*q)
                        })
                        .fold(0.0, f32::max)
                };
                let best = tris.iter().map(cover).fold(f32::INFINITY, f32::min);
                assert!((w - best).abs() <= 1e-5 * (1.0 + best), "{w} vs {best}");
                assert!((cover(&tris[k]) - w).abs() <= 1e-5 * (1.0 + w));
            }
        }
        assert!(Facets::default().nearest_squared(Vec3::ZERO).is_infinite());
    }
}
