//! UV error of a LOD against its original: how far the texture coordinates a
//! LOD interpolates are from the original's at the same place. The certified
//! bound is geometric; this says whether the texture still lands where it did
//! (a face that took its UVs from across a seam shows a scrambled texture).
//!
//! At four points of every LOD triangle (its centroid and the midpoints
//! towards its corners, a quarter of its area each) the LOD's UV is compared
//! with the UVs the original shows near that point on the same part (of the
//! same material, when both carry materials: a file read back numbers its
//! parts by material): the error is the distance to the nearest of those
//! UVs, in UV units and in texels of the LOD face's texture. "Near" is
//! within `reach` (a LOD's certified bound: every LOD point stands for
//! original surface that close, so a texture carried along with the
//! geometry is no error; Cohen, Olano and Manocha's texture deviation
//! within the geometric one), and at least `SEAM_BAND` of the diagonal
//! beyond the nearest distance, so that on a seam, where both sides are
//! nearest, the point counts as on the side that agrees best.

use glam::Vec2;

use super::bvh::Bvh;
use super::triangle::{barycentric, closest_point_on_triangle};
use crate::geom::{Aabb, TriMesh, UNTEXTURED_TEXELS};

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
    /// The same in texels of each face's texture (`Materials::texels_per_uv`):
    /// what a UV tolerance is stated in.
    pub mean_texels: f64,
    pub max_texels: f32,
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

/// The UV error of `lod` against `original` within `reach` (module doc);
/// `None` unless both have UVs.
pub fn uv_error(original: &TriMesh, lod: &TriMesh, reach: f32) -> Option<UvError> {
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
    let (mut sum_texels, mut max_texels) = (0.0f64, 0.0f32);
    let flat = |u: Vec2| u.extend(0.0);
    let mut stack = Vec::new();
    for t in 0..lod.triangles.len() {
        let corners = lod.triangle(t);
        let area = 0.25 * lod.triangle_area(t) as f64;
        let part = of_lod(t);
        let texels = lod
            .materials
            .as_ref()
            .map_or(UNTEXTURED_TEXELS, |m| m.texels_per_uv(lod.part(t)));
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
            // The best agreeing original point within reach.
            let reach = (nearest + band).max(reach);
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
                            let tri = original.triangles[o as usize];
                            // The point of o whose UV is nearest, if within reach ...
                            let [u0, u1, u2] = tri.map(|v| flat(ouv[v as usize]));
                            let nearest_uv = closest_point_on_triangle(flat(uv), u0, u1, u2);
                            let [b0, b1, b2] = barycentric(nearest_uv, u0, u1, u2);
                            let y = p[0] * b0 + p[1] * b1 + p[2] * b2;
                            let ouv_q = if y.distance(x) <= reach {
                                nearest_uv.truncate()
                            } else {
                                // ... else the UV at o's point nearest to x.
                                let q = closest_point_on_triangle(x, p[0], p[1], p[2]);
                                uv_at(ouv, tri, barycentric(q, p[0], p[1], p[2]))
                            };
                            best = best.min(ouv_q.distance(uv));
                        }
                    }
                    Err((l, r)) => stack.extend([l, r]),
                }
            }
            if best.is_finite() {
                sum += best as f64 * area;
                max = max.max(best);
                sum_texels += (best * texels) as f64 * area;
                max_texels = max_texels.max(best * texels);
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
        mean_texels: of_total(sum_texels),
        max_texels,
        area_over_threshold: of_total(over),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

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
        let same = uv_error(&original, &original, 0.0).unwrap();
        assert!(
            same.max < 1e-6 && same.area_over_threshold == 0.0,
            "{same:?}"
        );
        // The same surface with the seam's shift gone: the right half is off by 0.5.
        let wrong = uv_error(&original, &strip(0.0), 0.0).unwrap();
        assert!((wrong.area_over_threshold - 0.5).abs() < 1e-6, "{wrong:?}");
        assert!((wrong.max - 0.5).abs() < 1e-5);
        // The texture carried along a move of 0.2 is found within that reach.
        let mut moved = strip(0.0);
        moved.positions.iter_mut().for_each(|p| p.x += 0.2);
        let near = uv_error(&strip(0.0), &moved, 0.0).unwrap();
        let within = uv_error(&strip(0.0), &moved, 0.2 + 1e-4).unwrap();
        assert!((near.max - 0.05).abs() < 1e-4, "{near:?}");
        assert!(within.max < 1e-4, "{within:?}");
        // Untextured, errors count 1024 texels per UV unit.
        assert!((near.max_texels - 0.05 * 1024.0).abs() < 0.1, "{near:?}");
        // Without UVs there is nothing to measure.
        let mut bare = original.clone();
        bare.uvs = None;
        assert!(uv_error(&bare, &original, 0.0).is_none());
    }
}
