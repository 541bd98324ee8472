//! UV error of a LOD against its original: how far the texture coordinates a
//! LOD interpolates are from the original's at the same place. The certified
//! bound is geometric; this says whether the texture still lands where it did
//! (a face that took its UVs from across a seam shows a scrambled texture).
//!
//! At four points of every LOD triangle (its centroid and the midpoints
//! towards its corners, a quarter of its area each) the LOD's UV is compared
//! with the original's UV at the nearest point of the same part (of the same
//! material, when both carry materials: a file read back numbers its parts
//! by material). On a seam
//! both sides are nearest; the point counts as on the side that agrees best
//! among the original triangles within `SEAM_BAND` of the diagonal beyond the
//! nearest distance.

use glam::{Vec2, Vec3};

use super::bvh::Bvh;
use super::triangle::closest_point_on_triangle;
use crate::geom::{Aabb, TriMesh};

/// A UV difference above this (a twentieth of the texture) is visibly wrong.
pub const UV_ERROR_THRESHOLD: f32 = 0.05;
/// How much farther than the nearest an original triangle may be (fraction
/// of the diagonal) and still count as the same place.
const SEAM_BAND: f32 = 1e-3;

/// The UV error of one LOD.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct UvError {
    /// Area-weighted mean difference (UV units).
    pub mean: f64,
    pub max: f32,
    /// Fraction of the LOD's area off by more than [`UV_ERROR_THRESHOLD`].
    pub area_over_threshold: f64,
}

/// Barycentric coordinates of the four sample points of a triangle.
const SAMPLES: [[f32; 3]; 4] = [
    [1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0],
    [2.0 / 3.0, 1.0 / 6.0, 1.0 / 6.0],
    [1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0],
    [1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0],
];

/// Barycentric coordinates of `p` (on or near the triangle) in `[a, b, c]`.
fn barycentric(p: Vec3, [a, b, c]: [Vec3; 3]) -> [f32; 3] {
    let (v0, v1, v2) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (v0.dot(v0), v0.dot(v1), v1.dot(v1));
    let (d20, d21) = (v2.dot(v0), v2.dot(v1));
    let den = d00 * d11 - d01 * d01;
    if den.abs() <= f32::MIN_POSITIVE {
        return [1.0, 0.0, 0.0];
    }
    let v = (d11 * d20 - d01 * d21) / den;
    let w = (d00 * d21 - d01 * d20) / den;
    [1.0 - v - w, v, w]
}

fn uv_at(uvs: &[Vec2], tri: [u32; 3], w: [f32; 3]) -> Vec2 {
    uvs[tri[0] as usize] * w[0] + uvs[tri[1] as usize] * w[1] + uvs[tri[2] as usize] * w[2]
}

/// Which surface each triangle belongs to, comparable between the two
/// meshes: the index of its material in the original's table when both
/// carry materials, else its part.
fn surface_keys<'a>(
    original: &'a TriMesh,
    lod: &'a TriMesh,
) -> (impl Fn(usize) -> u32 + 'a, impl Fn(usize) -> u32 + 'a) {
    let both = original.materials.as_ref().zip(lod.materials.as_ref());
    let lod_table: Option<Vec<u32>> = both.map(|(o, l)| {
        l.table
            .iter()
            .map(|m| {
                o.table
                    .iter()
                    .position(|x| x == m)
                    .map_or(u32::MAX, |i| i as u32)
            })
            .collect()
    });
    let by_material = lod_table.is_some();
    let of_original = move |t: usize| match (&original.materials, by_material) {
        (Some(m), true) => m.of(original.part(t)),
        _ => original.part(t),
    };
    let of_lod = move |t: usize| match (&lod.materials, &lod_table) {
        (Some(m), Some(table)) => table
            .get(m.of(lod.part(t)) as usize)
            .copied()
            .unwrap_or(u32::MAX),
        _ => lod.part(t),
    };
    (of_original, of_lod)
}

/// The UV error of `lod` against `original`; `None` unless both have UVs.
pub fn uv_error(original: &TriMesh, lod: &TriMesh) -> Option<UvError> {
    let (original, lod) = (original.unwelded(), lod.unwelded());
    let (Some(ouv), Some(luv)) = (&original.uvs, &lod.uvs) else {
        return None;
    };
    let boxes: Vec<Aabb> = (0..original.triangles.len())
        .map(|t| Aabb::from_points(&original.triangle(t)))
        .collect();
    let bvh = Bvh::build(&boxes);
    let band = SEAM_BAND * original.bounds().diagonal();
    let (of_original, of_lod) = surface_keys(&original, &lod);
    let (mut sum, mut max, mut over, mut total) = (0.0f64, 0.0f32, 0.0f64, 0.0f64);
    let mut stack = Vec::new();
    for t in 0..lod.triangles.len() {
        let corners = lod.triangle(t);
        let area = 0.25 * lod.triangle_area(t) as f64;
        let part = of_lod(t);
        for w in SAMPLES {
            let x = corners[0] * w[0] + corners[1] * w[1] + corners[2] * w[2];
            let uv = uv_at(luv, lod.triangles[t], w);
            let dist = |o: u32| {
                if of_original(o as usize) != part {
                    return f32::INFINITY;
                }
                let [a, b, c] = original.triangle(o as usize);
                closest_point_on_triangle(x, a, b, c).distance(x)
            };
            let Some((nearest, _)) = bvh.nearest(x, dist) else {
                continue;
            };
            // The best agreeing original triangle within the band.
            let reach = nearest + band;
            let mut best = f32::INFINITY;
            stack.clear();
            stack.push(0u32);
            while let Some(n) = stack.pop() {
                if bvh.node_bounds(n).distance(x) > reach {
                    continue;
                }
                match bvh.node(n) {
                    Ok(prims) => {
                        for &o in prims {
                            if dist(o) > reach {
                                continue;
                            }
                            let p = original.triangle(o as usize);
                            let q = closest_point_on_triangle(x, p[0], p[1], p[2]);
                            let ouv_q =
                                uv_at(ouv, original.triangles[o as usize], barycentric(q, p));
                            best = best.min(ouv_q.distance(uv));
                        }
                    }
                    Err((l, r)) => stack.extend([l, r]),
                }
            }
            if best.is_finite() {
                sum += best as f64 * area;
                max = max.max(best);
                total += area;
                if best > UV_ERROR_THRESHOLD {
                    over += area;
                }
            }
        }
    }
    let of_total = |x: f64| if total > 0.0 { x / total } else { 0.0 };
    Some(UvError {
        mean: of_total(sum),
        max,
        area_over_threshold: of_total(over),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of squares along x, UV u = x / 4, with a seam at x = 2 where
    /// the right half's UVs are shifted by `shift`.
    fn strip(shift: f32) -> TriMesh {
        let mut m = TriMesh::default();
        let mut uvs = Vec::new();
        for i in 0..4u32 {
            let base = m.positions.len() as u32;
            let s = if i >= 2 { shift } else { 0.0 };
            for (x, y) in [(i, 0), (i + 1, 0), (i + 1, 1), (i, 1)] {
                m.positions.push(Vec3::new(x as f32, y as f32, 0.0));
                uvs.push(Vec2::new(x as f32 / 4.0 + s, y as f32));
            }
            m.triangles
                .extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
        }
        m.uvs = Some(uvs);
        m
    }

    #[test]
    fn a_copy_has_no_uv_error_and_a_shift_shows_on_its_side_only() {
        let original = strip(0.5);
        let same = uv_error(&original, &original).unwrap();
        assert!(
            same.max < 1e-6 && same.area_over_threshold == 0.0,
            "{same:?}"
        );
        // The same surface with the seam's shift gone: the right half is off by 0.5.
        let wrong = uv_error(&original, &strip(0.0)).unwrap();
        assert!((wrong.area_over_threshold - 0.5).abs() < 1e-6, "{wrong:?}");
        assert!((wrong.max - 0.5).abs() < 1e-5);
        // Without UVs there is nothing to measure.
        let mut bare = original.clone();
        bare.uvs = None;
        assert!(uv_error(&bare, &original).is_none());
    }
}
