//! Point replacement (§5.3): cover one triangle with at most ⌊κ⌋ point samples.
//!
//! §5.3.1: in a frame where the longest edge AB lies horizontal at the bottom,
//! rows of height d run parallel to AB; each row is tiled from the left by
//! squares of side d, the first one starting where the triangle starts at the
//! row's bottom (no gap left or below), the last one moved as far left as it
//! can while still reaching the right end (just covering B on the first row).
//! Each square is circumscribed by a disc of radius r = d/√2. A centre outside
//! the triangle is pushed down (towards AB) onto edge AC or BC, so colours are
//! interpolated, never extrapolated. Pushing a centre can leave part of its
//! square outside the nominal disc, so each sample's radius is the exact
//! covering radius of its square's piece of the triangle: the discs provably
//! cover the triangle (better than the nominal r, never looser where the
//! centre is the square's). The last square of a row overlaps its neighbour;
//! the overlap stays with the neighbour, so pieces tile the triangle (their
//! areas weight colours and coverage). The incremental error is the largest radius.
//!
//! §5.3.2: the smallest d giving at most s samples starts at √(area/s), doubles
//! until the count is at most s, then bisects; each s < κ is tried and the one
//! with the smallest cost/benefit, r / (1 − s/κ), wins.

use glam::{Vec2, Vec3};

/// One sample: a ball over part of the triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub center: Vec3,
    pub radius: f32,
    /// Barycentric weights of the centre (for colour interpolation).
    pub weights: [f32; 3],
    /// Area of the triangle piece it covers.
    pub area: f32,
}

/// The best replacement of a triangle.
#[derive(Debug, Clone, PartialEq)]
pub struct Replacement {
    pub distance: f32,
    pub samples: Vec<Sample>,
    /// Largest sample radius: the increase in error (§5.3.1).
    pub radius: f32,
    /// cost / benefit (§5.1, §5.3).
    pub value: f64,
}

/// The §5.3.1 frame: A at the origin, B = (len, 0), C = (cx, h) with h ≥ 0 and
/// 0 ≤ cx ≤ len (AB is the longest edge).
struct Frame {
    origin: Vec3,
    ex: Vec3,
    ey: Vec3,
    len: f32,
    cx: f32,
    h: f32,
    /// Which input vertex is A, B and C.
    order: [usize; 3],
}

impl Frame {
    fn new(p: &[Vec3; 3]) -> Frame {
        let l = |i: usize| p[i].distance_squared(p[(i + 1) % 3]);
        let i = (0..3).max_by(|a, b| l(*a).total_cmp(&l(*b))).unwrap_or(0);
        let order = [i, (i + 1) % 3, (i + 2) % 3];
        let [a, b, c] = order.map(|k| p[k]);
        let len = a.distance(b);
        let ex = (b - a).normalize_or_zero();
        let ac = c - a;
        let cx = ac.dot(ex).clamp(0.0, len);
        let perp = ac - ex * ac.dot(ex);
        let h = perp.length();
        Frame {
            origin: a,
            ex,
            ey: perp.normalize_or_zero(),
            len,
            cx,
            h,
            order,
        }
    }

    /// The triangle's extent [left, right] at height y.
    fn extent(&self, y: f32) -> (f32, f32) {
        if self.h <= 0.0 {
            return (0.0, self.len);
        }
        let t = (y / self.h).clamp(0.0, 1.0);
        (self.cx * t, self.len + (self.cx - self.len) * t)
    }

    /// Height of the triangle above x (0 ≤ x ≤ len).
    fn top(&self, x: f32) -> f32 {
        if x <= self.cx {
            if self.cx > 0.0 {
                self.h * x / self.cx
            } else {
                self.h
            }
        } else if self.len > self.cx {
            self.h * (self.len - x) / (self.len - self.cx)
        } else {
            self.h
        }
    }

    /// Rows: (bottom y, number of squares).
    fn rows(&self, d: f32) -> impl Iterator<Item = (f32, usize)> + '_ {
        let n = ((self.h / d).ceil() as usize).max(1);
        (0..n).map(move |k| {
            let y0 = k as f32 * d;
            let (l, r) = self.extent(y0);
            (y0, (((r - l) / d) * (1.0 - 1e-6)).ceil().max(1.0) as usize)
        })
    }

    /// Samples needed at distance d (capped, so absurd d stay cheap).
    fn count(&self, d: f32) -> usize {
        if self.len <= 0.0 || d.is_nan() || d <= 0.0 {
            return 1;
        }
        if self.h / d > 1e6 {
            return usize::MAX;
        }
        self.rows(d).map(|(_, m)| m).sum()
    }

    fn corners(&self) -> [Vec2; 3] {
        [
            Vec2::ZERO,
            Vec2::new(self.len, 0.0),
            Vec2::new(self.cx, self.h),
        ]
    }
}

/// Samples a triangle needs at distance d.
pub fn count(tri: &[Vec3; 3], d: f32) -> usize {
    Frame::new(tri).count(d)
}

/// The §5.3.1 samples at distance d.
pub fn sample(tri: &[Vec3; 3], d: f32) -> Vec<Sample> {
    let f = Frame::new(tri);
    let corners = f.corners();
    let mut out = Vec::new();
    if f.len <= 0.0 || d.is_nan() || d <= 0.0 {
        out.push(Sample {
            center: tri[0],
            radius: tri.iter().map(|p| p.distance(tri[0])).fold(0.0, f32::max),
            weights: [1.0, 0.0, 0.0],
            area: 0.0,
        });
        return out;
    }
    for (y0, m) in f.rows(d) {
        let (l, r) = f.extent(y0);
        for j in 0..m {
            let left = if m > 1 && j == m - 1 {
                r - d
            } else {
                l + j as f32 * d
            };
            // The piece it covers is its tile of the row (the last square's
            // overlap with its neighbour stays with the neighbour).
            let x0 = l + j as f32 * d;
            let tile = [
                Vec2::new(x0, y0),
                Vec2::new(x0 + d, y0),
                Vec2::new(x0 + d, y0 + d),
                Vec2::new(x0, y0 + d),
            ];
            let piece = clip(&tile, &corners);
            if piece.len() < 3 {
                continue;
            }
            // Push the centre down onto AC or BC when it is above them.
            let x = (left + 0.5 * d).clamp(0.0, f.len);
            let c = Vec2::new(x, (y0 + 0.5 * d).min(f.top(x)).max(0.0));
            let radius = piece.iter().map(|q| q.distance(c)).fold(0.0, f32::max);
            let w = barycentric(c, &corners);
            let mut weights = [0.0; 3];
            for k in 0..3 {
                weights[f.order[k]] = w[k];
            }
            out.push(Sample {
                center: f.origin + f.ex * c.x + f.ey * c.y,
                radius: radius * (1.0 + 1e-5),
                weights,
                area: polygon_area(&piece),
            });
        }
    }
    out
}

/// The smallest d (to 0.1%) with at most s samples (§5.3.2).
pub fn smallest_distance(tri: &[Vec3; 3], s: usize) -> f32 {
    let area = 0.5 * (tri[1] - tri[0]).cross(tri[2] - tri[0]).length();
    let longest = (0..3)
        .map(|i| tri[i].distance(tri[(i + 1) % 3]))
        .fold(0.0, f32::max);
    let mut hi = (area / s as f32).sqrt().max(longest * 1e-4);
    if hi.is_nan() || hi <= 0.0 {
        return 0.0;
    }
    // One frame for every count of the search.
    let frame = Frame::new(tri);
    let mut lo = 0.0;
    while frame.count(hi) > s {
        lo = hi;
        hi *= 2.0;
    }
    if lo == 0.0 {
        return hi;
    }
    while hi - lo > 1e-3 * hi {
        let mid = 0.5 * (lo + hi);
        if frame.count(mid) <= s {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// The triangle moved to its first vertex and scaled so its largest
/// coordinate offset is 1, with that scale: the construction is
/// scale-invariant, and areas of triangles near f32's range would overflow.
fn unit(tri: &[Vec3; 3]) -> ([Vec3; 3], f32) {
    let scale = (1..3)
        .map(|i| (tri[i] - tri[0]).abs().max_element())
        .fold(0.0, f32::max);
    let scale = if scale > 0.0 && scale.is_finite() {
        scale
    } else {
        1.0
    };
    (tri.map(|p| (p - tri[0]) / scale), scale)
}

/// Sample counts worth trying: 1 ≤ s < κ (s ≤ ⌊κ⌋ and a positive benefit).
fn counts(kappa: f32) -> impl Iterator<Item = usize> {
    let max = if kappa.is_finite() && kappa > 1.0 {
        (kappa.ceil() as usize - 1).min(64)
    } else {
        0
    };
    1..=max
}

/// The optimisation value of replacing `tri` (nominal r = d/√2, §5.3.2), or
/// infinity when κ ≤ 1 (no replacement can reduce the primitive count).
pub fn value(tri: &[Vec3; 3], kappa: f32) -> f64 {
    let (tri, scale) = unit(tri);
    counts(kappa)
        .map(|s| {
            let d = smallest_distance(&tri, s) as f64 * scale as f64;
            let r = d / std::f64::consts::SQRT_2;
            r / (1.0 - s as f64 / kappa as f64)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The replacement with the smallest cost/benefit, with its samples; None when κ ≤ 1.
pub fn best(tri: &[Vec3; 3], kappa: f32) -> Option<Replacement> {
    let (unit_tri, scale) = unit(tri);
    counts(kappa)
        .map(|s| {
            let d = smallest_distance(&unit_tri, s);
            let distance = d * scale;
            let samples: Vec<Sample> = sample(&unit_tri, d)
                .into_iter()
                .map(|q| Sample {
                    center: tri[0] + q.center * scale,
                    radius: q.radius * scale,
                    area: q.area * scale * scale,
                    ..q
                })
                .collect();
            let radius = samples.iter().map(|q| q.radius).fold(0.0, f32::max);
            let benefit = 1.0 - samples.len() as f64 / kappa as f64;
            Replacement {
                distance,
                value: radius as f64 / benefit,
                samples,
                radius,
            }
        })
        .min_by(|a, b| a.value.total_cmp(&b.value))
}

/// Sutherland–Hodgman: the convex polygon `poly` clipped to the CCW triangle.
fn clip(poly: &[Vec2], tri: &[Vec2; 3]) -> Vec<Vec2> {
    let mut out = poly.to_vec();
    for i in 0..3 {
        let (a, b) = (tri[i], tri[(i + 1) % 3]);
        let side = |p: Vec2| (b - a).perp_dot(p - a);
        let input = std::mem::take(&mut out);
        for k in 0..input.len() {
            let (p, q) = (input[k], input[(k + 1) % input.len()]);
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 {
                out.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                out.push(p + (q - p) * (sp / (sp - sq)));
            }
        }
        if out.is_empty() {
            break;
        }
    }
    out
}

fn polygon_area(p: &[Vec2]) -> f32 {
    0.5 * (0..p.len())
        .map(|i| p[i].perp_dot(p[(i + 1) % p.len()]))
        .sum::<f32>()
        .abs()
}

fn barycentric(p: Vec2, t: &[Vec2; 3]) -> [f32; 3] {
    let area = (t[1] - t[0]).perp_dot(t[2] - t[0]);
    if area.abs() <= f32::MIN_POSITIVE {
        return [1.0, 0.0, 0.0];
    }
    let w1 = (p - t[0]).perp_dot(t[2] - t[0]) / area;
    let w2 = (t[1] - t[0]).perp_dot(p - t[0]) / area;
    let w1 = w1.clamp(0.0, 1.0);
    let w2 = w2.clamp(0.0, 1.0 - w1);
    [1.0 - w1 - w2, w1, w2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distance::closest_point_on_triangle;
    use crate::rng::Rng;

    fn random_triangle(rng: &mut Rng) -> [Vec3; 3] {
        [(); 3].map(|_| Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0)
    }

    #[test]
    fn samples_cover_the_triangle_with_centres_on_it() {
        let mut rng = Rng::new(8);
        for _ in 0..300 {
            let tri = random_triangle(&mut rng);
            let longest = (0..3)
                .map(|i| tri[i].distance(tri[(i + 1) % 3]))
                .fold(0.0, f32::max);
            let d = longest * (0.02 + rng.f32());
            let s = sample(&tri, d);
            assert_eq!(s.len(), count(&tri, d), "count and sample agree");
            let area = 0.5 * (tri[1] - tri[0]).cross(tri[2] - tri[0]).length();
            let covered: f32 = s.iter().map(|q| q.area).sum();
            assert!(
                (covered - area).abs() <= 1e-3 * area,
                "pieces tile the triangle"
            );
            for q in &s {
                let on = closest_point_on_triangle(q.center, tri[0], tri[1], tri[2]);
                assert!(
                    on.distance(q.center) <= 1e-4 * longest,
                    "centre on the triangle"
                );
                let w = q.weights;
                let back = tri[0] * w[0] + tri[1] * w[1] + tri[2] * w[2];
                assert!(back.distance(q.center) <= 1e-3 * longest);
                // Never looser than the nominal disc by more than the pushed distance.
                assert!(q.radius <= 2.0 * d);
            }
            for _ in 0..200 {
                let (mut u, mut v) = (rng.f32(), rng.f32());
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                let p = tri[0] + (tri[1] - tri[0]) * u + (tri[2] - tri[0]) * v;
                assert!(
                    s.iter().any(|q| q.center.distance(p) <= q.radius),
                    "point of the triangle outside every sample"
                );
            }
        }
    }

    #[test]
    fn smallest_distance_meets_the_count_and_is_minimal() {
        let mut rng = Rng::new(9);
        for _ in 0..100 {
            let tri = random_triangle(&mut rng);
            for s in 1..5 {
                let d = smallest_distance(&tri, s);
                assert!(count(&tri, d) <= s);
                assert!(count(&tri, d * 0.99) > s || d * 0.99 < 1e-6);
            }
        }
    }

    #[test]
    fn kappa_at_most_one_never_replaces() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        assert!(best(&tri, 1.0).is_none() && best(&tri, 0.5).is_none());
        assert!(value(&tri, 1.0).is_infinite());
        let r = best(&tri, 3.0).unwrap();
        assert!(r.samples.len() <= 2 && (r.value - value(&tri, 3.0)).abs() <= r.value);
        // More points allowed never gives a worse value.
        assert!(value(&tri, 8.0) <= value(&tri, 3.0));
    }
}
