//! Baking: a LOD gets its own texture. Past its seams' floor (or past the
//! UV tolerance) a textured LOD cannot keep the original's atlas: its
//! charts no longer fit the surface. Here the LOD is unwrapped afresh and
//! the original's appearance is transferred onto its new atlas, as
//! Simplygon, InstaLOD and meshoptimizer's demo (remesh → unwrap → rebake)
//! do; every material of the LOD becomes one, so it is also one draw call.
//!
//! The steps, in order:
//! 1. **Unwrap**: charts, LSCM and packing by `uvunwrap` (pure Rust; chosen
//!    over xatlas bindings, which need a C++ toolchain in the build and on
//!    every CI machine, for the same segmentation → LSCM → packing
//!    pipeline), `padding` empty texels around each chart.
//! 2. **Transfer**: every texel whose centre lies in a LOD triangle's UV
//!    image is the LOD surface point there; the original's nearest surface
//!    point (the BVH of `distance`) gives what it shows (`io::appearance`):
//!    its colour (factor × texture × vertex colour) and its shading normal
//!    (its own normal map's included), written in the LOD's tangent frame
//!    there (MikkTSpace, `geom::tangents`, as glTF clients rebuild it): a
//!    normal map that gives the LOD the original's shading detail, creases
//!    and normal-mapped relief included. The LOD is within its certified
//!    bound of the original, so that point is at most the bound away.
//! 3. **Dilate**: `padding` rings of empty texels around the charts take
//!    their covered neighbours' mean, so bilinear filtering and mip levels
//!    never fetch the empty background at a chart's edge.
//! 4. **Encode**: PNGs, the LOD's only material's base-colour (sRGB) and
//!    normal (linear) textures.

pub mod choice;

pub use choice::{Asked, Measured, bake_unasked, short_of_seams};

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use crate::distance::{MeshDistance, barycentric, closest_point_on_triangle};
use crate::geom::tangents::TangentFrame;
use crate::geom::{Image, Material, Materials, TriMesh, VertexAttributes, Wedges};
use crate::io::appearance::Appearance;
use crate::io::image::{CLAMP_TO_EDGE, encode_srgb};
use crate::lod::Texture;

/// A baked texture's least side where none is given, in texels (and an
/// impostor's side).
pub const DEFAULT_TEXTURE_SIZE: u32 = 1024;

/// A baked texture's largest side where none is given, in texels.
const LARGEST_DEFAULT_SIZE: u32 = 4096;

/// The baked texture's side for a LOD of `original` with `triangles`
/// where none is given: the original's texels per triangle, kept (its
/// distinct textures' texels × the share of its triangles the LOD keeps),
/// the side rounded up to a power of two, within 1024..=4096. At half the
/// truck's triangles that is its own 2048² (1,024² renders 1.2 dB further
/// from it, BENCHMARKS.md); far LODs and lightly textured models get 1024².
pub fn default_size(original: &TriMesh, triangles: usize) -> u32 {
    let mut seen: Vec<&std::sync::Arc<[u8]>> = Vec::new();
    let mut texels = 0.0f64;
    for m in original.materials.iter().flat_map(|m| &m.table) {
        let maps = [
            m.base_color_texture.as_ref(),
            m.normal_texture.as_ref().map(|n| &n.0),
        ];
        for image in maps.into_iter().flatten() {
            if seen.iter().any(|s| std::sync::Arc::ptr_eq(s, &image.bytes)) {
                continue;
            }
            seen.push(&image.bytes);
            texels += image.size().map_or(0.0, |(w, h)| w as f64 * h as f64);
        }
    }
    let share = triangles as f64 / original.triangles.len().max(1) as f64;
    let side = (texels * share.min(1.0)).sqrt().ceil() as u32;
    side.next_power_of_two()
        .clamp(DEFAULT_TEXTURE_SIZE, LARGEST_DEFAULT_SIZE)
}

/// The baked texture's side's range, in texels.
pub const TEXTURE_SIZE_RANGE: std::ops::RangeInclusive<u32> = 64..=8192;

/// Empty texels around each chart, filled by dilation.
const PADDING: u32 = 4;

/// What a bake made.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct BakeReport {
    /// The texture's size in texels.
    pub width: u32,
    pub height: u32,
    pub charts: u32,
    /// Texels whose centre lies in a chart (transferred), of the texture.
    pub covered: f64,
    pub seconds: f64,
    /// Baked unasked ([`choice`]): seams kept the LOD short of its
    /// triangle budget, or it measured closer to the original baked.
    pub automatic: bool,
    /// The measurement that chose the bake, when one did.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measured: Option<Measured>,
}

/// A LOD with its own baked texture, and what it took.
pub struct Baked {
    pub mesh: TriMesh,
    pub report: BakeReport,
}

/// Bakes `original`'s appearance onto `lod` with a texture of at most
/// `size` texels a side.
///
/// # Errors
/// A message when the size is out of range, the LOD is empty, or its
/// charts do not fit one texture.
pub fn bake(original: &TriMesh, lod: &TriMesh, size: u32) -> Result<Baked, String> {
    let start = std::time::Instant::now();
    if !TEXTURE_SIZE_RANGE.contains(&size) {
        return Err(format!(
            "texture size must be in {}..={}, got {size}",
            TEXTURE_SIZE_RANGE.start(),
            TEXTURE_SIZE_RANGE.end()
        ));
    }
    if lod.triangles.is_empty() {
        return Err("an empty LOD has nothing to bake".into());
    }
    // 1. Unwrap.
    let positions: Vec<[f32; 3]> = lod.positions.iter().map(|p| p.to_array()).collect();
    let indices: Vec<u32> = lod.triangles.iter().flatten().copied().collect();
    let options = uvunwrap::Options {
        density: uvunwrap::Density::Auto { page_size: size },
        padding: PADDING,
        ..Default::default()
    };
    let atlas = uvunwrap::generate(&[uvunwrap::MeshInput::new(&positions, &indices)], &options)
        .map_err(|e| format!("unwrapping the LOD: {e}"))?;
    if atlas.page_count != 1 {
        return Err(format!(
            "the LOD's {} charts need {} textures of {size}²: give a larger texture size",
            atlas.chart_count, atlas.page_count
        ));
    }
    let unwrapped = &atlas.meshes[0];
    // Power-of-two sides (the atlas crops its unused rows), for mip chains
    // on every client: the UVs shrink to the part the atlas fills.
    let (width, height) = (
        atlas.width.next_power_of_two(),
        atlas.height.next_power_of_two(),
    );
    let fill = Vec2::new(
        atlas.width as f32 / width as f32,
        atlas.height as f32 / height as f32,
    );
    // One vertex per wedge, normals facing their faces and split where
    // their MikkTSpace tangents differ: the mesh as written and as a
    // client builds its frames.
    let mut mesh = with_atlas_uvs(lod, unwrapped, fill).unwelded();
    mesh.orient_normals_to_winding();
    let (mesh, tangents) = mesh.with_tangents().ok_or("the unwrapped LOD has no UVs")?;
    let normals = mesh.normals.clone().unwrap_or_default();

    // 2. Transfer.
    let nearest = MeshDistance::new(original);
    let appearance = Appearance::new(original);
    let uvs = mesh.uvs.as_deref().unwrap_or_default();
    let corner_uv = |t: usize, k: usize| uvs[mesh.triangles[t][k] as usize];
    // Per row of texels, the triangles whose UV bounds cross it.
    let mut rows: Vec<Vec<u32>> = vec![Vec::new(); height as usize];
    for t in 0..mesh.triangles.len() {
        let ys = [0, 1, 2].map(|k| corner_uv(t, k).y * height as f32 - 0.5);
        let lo = ys
            .iter()
            .copied()
            .fold(f32::INFINITY, f32::min)
            .floor()
            .max(0.0) as usize;
        let hi = ys.iter().copied().fold(f32::NEG_INFINITY, f32::max).ceil();
        let hi = (hi.max(0.0) as usize).min(height as usize - 1);
        for row in rows.iter_mut().take(hi + 1).skip(lo) {
            row.push(t as u32);
        }
    }
    let texels: Vec<Option<(Vec3, Vec3)>> = rows
        .par_iter()
        .enumerate()
        .flat_map_iter(|(y, tris)| {
            let mut line = vec![None; width as usize];
            let mut hint = u32::MAX;
            for &t in tris {
                let t = t as usize;
                let uv =
                    [0, 1, 2].map(|k| corner_uv(t, k) * Vec2::new(width as f32, height as f32));
                let x0 = uv
                    .iter()
                    .map(|u| u.x)
                    .fold(f32::INFINITY, f32::min)
                    .floor()
                    .max(0.0) as usize;
                let x1 = (uv
                    .iter()
                    .map(|u| u.x)
                    .fold(f32::NEG_INFINITY, f32::max)
                    .ceil()
                    .max(0.0) as usize)
                    .min(width as usize);
                let corners = mesh.triangle(t);
                let frame = mesh.triangles[t].map(|v| (normals[v as usize], tangents[v as usize]));
                for (x, slot) in line.iter_mut().enumerate().take(x1).skip(x0) {
                    let c = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                    let Some(b) = inside(c, uv) else {
                        continue;
                    };
                    let p = corners[0] * b[0] + corners[1] * b[1] + corners[2] * b[2];
                    // The texel before's nearest triangle bounds the search.
                    let (_, o) = nearest.nearest_near(p, hint);
                    if o == u32::MAX {
                        continue;
                    }
                    hint = o;
                    let [a, bb, cc] = original.triangle(o as usize);
                    let q = closest_point_on_triangle(p, a, bb, cc);
                    let at = barycentric(q, a, bb, cc);
                    let color = appearance.color(o as usize, at);
                    let normal = tangent_space(appearance.normal(o as usize, at), frame, b);
                    *slot = Some((color, normal));
                }
            }
            line
        })
        .collect();
    let covered = texels.iter().filter(|t| t.is_some()).count();

    // 3. Dilate.
    let rings = PADDING as usize + 1;
    let colors = dilate(
        texels.iter().map(|t| t.map(|t| t.0)).collect(),
        width as usize,
        rings,
    );
    let normals = dilate(
        texels.iter().map(|t| t.map(|t| t.1)).collect(),
        width as usize,
        rings,
    );

    // 4. Encode.
    let encode = |texels: &[Option<Vec3>], empty: Vec3, channel: &dyn Fn(f32) -> u8| Texture {
        width,
        height,
        rgba: texels
            .iter()
            .map(|c| {
                let c = c.unwrap_or(empty);
                [channel(c.x), channel(c.y), channel(c.z), 255]
            })
            .collect(),
    };
    let texture = encode(&colors, Vec3::ZERO, &encode_srgb);
    let flat = Vec3::Z;
    let normal_map = encode(&normals, flat, &|x| {
        ((x * 0.5 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8
    });
    let first = lod
        .materials
        .as_ref()
        .and_then(|m| m.table.first())
        .cloned()
        .unwrap_or_default();
    let material = Material {
        name: Some("baked".into()),
        base_color: [1.0, 1.0, 1.0, first.base_color[3]],
        normal_texture: Some((png_image(&normal_map), 1.0)),
        ..textured(&texture, first)
    };
    let mut mesh = mesh;
    mesh.materials = Some(Materials::single(material));
    mesh.parts = None;
    Ok(Baked {
        mesh,
        report: BakeReport {
            width,
            height,
            charts: atlas.chart_count,
            covered: covered as f64 / (width as f64 * height as f64),
            seconds: start.elapsed().as_secs_f64(),
            automatic: false,
            measured: None,
        },
    })
}

/// `base` wearing `texture` (PNG) with UVs and no vertex colours.
fn textured(texture: &Texture, base: Material) -> Material {
    Material {
        base_color_texture: Some(png_image(texture)),
        vertex_attributes: VertexAttributes {
            colors: false,
            uvs: true,
        },
        ..base
    }
}

/// `texture` as a PNG image on the atlas's UVs: clamped, as the atlas is
/// padded and its edges never need the other side.
fn png_image(texture: &Texture) -> Image {
    crate::io::image::png_image(texture, CLAMP_TO_EDGE)
}

/// `n` in the tangent frame a client rebuilds at barycentric `b` of a
/// triangle with corners `frame`; a normal behind the surface is laid flat
/// on it.
fn tangent_space(n: Vec3, frame: [(Vec3, Vec4); 3], b: [f32; 3]) -> Vec3 {
    let Some(frame) = TangentFrame::at(frame, b) else {
        return Vec3::Z;
    };
    let local = frame.local(n);
    local
        .with_z(local.z.max(0.0))
        .try_normalize()
        .unwrap_or(Vec3::Z)
}

/// The barycentric coordinates of `c` in the 2-D triangle `t`, when it is
/// inside (edges included); `None` outside or for a degenerate triangle.
fn inside(c: Vec2, t: [Vec2; 3]) -> Option<[f32; 3]> {
    let d = (t[1] - t[0]).perp_dot(t[2] - t[0]);
    if d.abs() <= f32::MIN_POSITIVE {
        return None;
    }
    let b1 = (c - t[0]).perp_dot(t[2] - t[0]) / d;
    let b2 = (t[1] - t[0]).perp_dot(c - t[0]) / d;
    let b0 = 1.0 - b1 - b2;
    const EDGE: f32 = -1e-5;
    (b0 >= EDGE && b1 >= EDGE && b2 >= EDGE).then(|| [b0, b1, b2].map(|b| b.max(0.0)))
}

/// `lod` with the atlas's UVs (scaled by `fill`, the share of the texture
/// the atlas covers) as its wedges: one wedge per atlas vertex and
/// normal wedge of the LOD (normal seams stay, chart seams are new), the
/// LOD's colours dropped (they are in the texture now).
fn with_atlas_uvs(lod: &TriMesh, unwrapped: &uvunwrap::OutputMesh, fill: Vec2) -> TriMesh {
    let old = lod.wedges.as_ref();
    let mut ids = std::collections::HashMap::new();
    let mut wedges = Wedges {
        corners: Vec::with_capacity(lod.triangles.len()),
        vertex: Vec::new(),
        normals: lod.normals.as_ref().map(|_| Vec::new()),
        colors: None,
        uvs: Some(Vec::new()),
        payload: None,
    };
    let mut picked = Vec::new();
    for (t, tri) in lod.triangles.iter().enumerate() {
        let corners = [0, 1, 2].map(|k| {
            let out = unwrapped.indices[3 * t + k];
            let before = old.map_or(tri[k], |w| w.corners[t][k]);
            *ids.entry((out, before)).or_insert_with(|| {
                let v = &unwrapped.vertices[out as usize];
                wedges.vertex.push(v.xref);
                if let Some(n) = &mut wedges.normals {
                    n.push(match old.and_then(|w| w.normals.as_ref()) {
                        Some(wn) => wn[before as usize],
                        None => lod.normals.as_ref().map_or(Vec3::Z, |n| n[tri[k] as usize]),
                    });
                }
                if let Some(u) = &mut wedges.uvs {
                    u.push(Vec2::from_array(v.uv) * fill);
                }
                picked.push(before as usize);
                wedges.vertex.len() as u32 - 1
            })
        });
        wedges.corners.push(corners);
    }
    wedges.payload = match (old.and_then(|w| w.payload.as_ref()), &lod.payload) {
        (Some(p), _) => Some(p.pick(picked.iter().copied())),
        (None, Some(p)) => Some(p.pick(picked.iter().copied())),
        _ => None,
    };
    let mut uvs = vec![Vec2::ZERO; lod.positions.len()];
    if let Some(u) = &wedges.uvs {
        for (i, &v) in wedges.vertex.iter().enumerate() {
            uvs[v as usize] = u[i];
        }
    }
    TriMesh {
        colors: None,
        uvs: Some(uvs),
        wedges: Some(wedges),
        ..lod.clone()
    }
}

/// `rings` passes of filling each empty texel next to a filled one with its
/// filled neighbours' mean (8-connected).
pub(crate) fn dilate(
    mut texels: Vec<Option<Vec3>>,
    width: usize,
    rings: usize,
) -> Vec<Option<Vec3>> {
    let height = texels.len() / width.max(1);
    for _ in 0..rings {
        let before = texels.clone();
        for y in 0..height {
            for x in 0..width {
                if before[y * width + x].is_some() {
                    continue;
                }
                let (mut sum, mut n) = (Vec3::ZERO, 0);
                for (dx, dy) in [
                    (-1, -1),
                    (0, -1),
                    (1, -1),
                    (-1, 0),
                    (1, 0),
                    (-1, 1),
                    (0, 1),
                    (1, 1),
                ] {
                    let (i, j) = (x as i64 + dx, y as i64 + dy);
                    if i < 0 || j < 0 || i >= width as i64 || j >= height as i64 {
                        continue;
                    }
                    if let Some(c) = before[j as usize * width + i as usize] {
                        sum += c;
                        n += 1;
                    }
                }
                if n > 0 {
                    texels[y * width + x] = Some(sum / n as f32);
                }
            }
        }
    }
    texels
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::appearance::Appearance;
    use crate::io::base_color::SurfaceColor;
    use crate::io::image::decode_rgba;

    /// A unit square in z = 0, `n`×`n` cells, textured by a 32² image whose
    /// texel (i, j) is (i/31, j/31, ½) over UV = (x, y).
    fn textured_square(n: u32) -> TriMesh {
        let mut m = crate::simplify::collapse::tests::height_grid(n, |_, _| 0.0);
        m.uvs = Some(m.positions.iter().map(|p| p.truncate()).collect());
        let texture = Texture {
            width: 32,
            height: 32,
            rgba: (0..32 * 32)
                .map(|k| [(k % 32) as u8 * 8, (k / 32) as u8 * 8, 128, 255])
                .collect(),
        };
        m.materials = Some(Materials::single(textured(&texture, Material::default())));
        m
    }

    #[test]
    fn a_baked_lod_shows_the_originals_colours_and_no_empty_texel_in_a_chart() {
        let original = textured_square(16);
        let lod = textured_square(2);
        let baked = bake(&original, &lod, 128).unwrap();
        let report = &baked.report;
        assert!(report.width <= 128 && report.height <= 128, "{report:?}");
        assert!(report.width.is_power_of_two() && report.height.is_power_of_two());
        assert!(report.covered > 0.3, "{report:?}");
        let m = &baked.mesh;
        let corners = |m: &TriMesh| {
            (0..m.triangles.len())
                .map(|t| m.triangle(t))
                .collect::<Vec<_>>()
        };
        assert_eq!(corners(m), corners(&lod), "the LOD's triangles, in order");
        let material = &m.materials.as_ref().unwrap().table[0];
        let image = decode_rgba(material.base_color_texture.as_ref().unwrap()).unwrap();
        let surface = SurfaceColor::new(&original).unwrap();
        let truth = SurfaceColor::new(m).unwrap();
        let mut worst = 0.0f32;
        for t in 0..m.triangles.len() {
            for b in [
                [1.0 / 3.0; 3],
                [0.6, 0.2, 0.2],
                [0.2, 0.6, 0.2],
                [0.2, 0.2, 0.6],
            ] {
                let [p0, p1, p2] = m.triangle(t);
                let p = p0 * b[0] + p1 * b[1] + p2 * b[2];
                let (q, o) = MeshDistance::new(&original).closest(p).unwrap();
                let [a, bb, c] = original.triangle(o as usize);
                let want = surface.at(o as usize, barycentric(q, a, bb, c));
                worst = worst.max((truth.at(t, b) - want).abs().max_element());
            }
        }
        // A baked texel is the colour at its centre: within a texel's
        // step of the gradient (1/31 over ~1/40 of the square) and 8 bits.
        assert!(worst < 0.06, "{worst}");
        // Every texel of every chart was transferred or dilated: none is
        // the black background.
        let w = image.width as usize;
        let uvs = m.uvs.as_ref().unwrap();
        for (t, tri) in m.triangles.iter().enumerate() {
            let uv =
                tri.map(|v| uvs[v as usize] * Vec2::new(image.width as f32, image.height as f32));
            for y in 0..image.height as usize {
                for x in 0..w {
                    if inside(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), uv).is_some() {
                        assert_ne!(
                            image.texels[y * w + x][..3],
                            [0, 0, 0],
                            "triangle {t} at {x},{y}"
                        );
                    }
                }
            }
        }
        assert!(bake(&original, &lod, 16).is_err());
        assert!(bake(&original, &TriMesh::default(), 256).is_err());
    }

    /// A flat LOD of a wavy sheet z = 0.03·sin(2πx) whose vertices carry
    /// the wave's exact normals: the baked normal map, read back in the
    /// frames a client builds (the written mesh's MikkTSpace tangents),
    /// gives the wave's normal wherever the LOD lies over it, within 3°.
    #[test]
    fn the_normal_map_gives_the_flat_lod_the_originals_normals() {
        let wave = |x: f32| {
            let slope = 0.03 * std::f32::consts::TAU * (std::f32::consts::TAU * x).cos();
            Vec3::new(-slope, 0.0, 1.0).normalize()
        };
        let mut original = textured_square(64);
        for p in &mut original.positions {
            p.z = 0.03 * (std::f32::consts::TAU * p.x).sin();
        }
        original.normals = Some(original.positions.iter().map(|p| wave(p.x)).collect());
        let lod = textured_square(2);
        let baked = bake(&original, &lod, 256).unwrap();
        let m = &baked.mesh;
        let (framed, tangents) = m.with_tangents().unwrap();
        assert_eq!(
            framed.positions.len(),
            m.positions.len(),
            "written as framed"
        );
        let (image, _) = m.materials.as_ref().unwrap().table[0]
            .normal_texture
            .as_ref()
            .unwrap();
        let map = decode_rgba(image).unwrap();
        let (uvs, normals) = (m.uvs.as_ref().unwrap(), m.normals.as_ref().unwrap());
        let mut worst = 0.0f32;
        for tri in &m.triangles {
            for b in [
                [1.0 / 3.0; 3],
                [0.6, 0.3, 0.1],
                [0.1, 0.6, 0.3],
                [0.3, 0.1, 0.6],
            ] {
                let at = |f: &dyn Fn(usize) -> Vec3| {
                    (0..3).map(|k| f(tri[k] as usize) * b[k]).sum::<Vec3>()
                };
                let n = at(&|v| normals[v]).normalize();
                let t0 = at(&|v| tangents[v].truncate());
                let tangent = (t0 - n * n.dot(t0)).normalize();
                let bitangent = n.cross(tangent) * tangents[tri[0] as usize].w;
                let uv: Vec2 = (0..3).map(|k| uvs[tri[k] as usize] * b[k]).sum();
                let (x, y) = (
                    (uv.x * map.width as f32) as usize,
                    (uv.y * map.height as f32) as usize,
                );
                let texel = map.texels[y * map.width as usize + x];
                let local =
                    Vec3::new(texel[0] as f32, texel[1] as f32, texel[2] as f32) / 127.5 - 1.0;
                let world = (tangent * local.x + bitangent * local.y + n * local.z).normalize();
                let p: Vec3 = (0..3).map(|k| m.positions[tri[k] as usize] * b[k]).sum();
                worst = worst.max(world.angle_between(wave(p.x)).to_degrees());
            }
        }
        assert!(worst < 3.0, "{worst}°");
    }

    /// The original's own normal map is part of what it shows: a flat
    /// square whose map leans its normal towards +x on the left and −x on
    /// the right (2 × 1 texels, clamped, so it ramps in between) bakes onto
    /// a coarser square, in new charts, a map that gives the same normals
    /// (read back in the baked mesh's frames) within 3°.
    #[test]
    fn the_originals_own_normal_map_is_baked() {
        let lean = [Vec3::new(0.6, 0.0, 0.8), Vec3::new(-0.6, 0.0, 0.8)];
        let encode = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
        let texel = |n: Vec3| [encode(n.x), encode(n.y), encode(n.z), 255];
        let map = Texture {
            width: 2,
            height: 1,
            rgba: vec![texel(lean[0]), texel(lean[1])],
        };
        let image = png_image(&map);
        let mut original = textured_square(8);
        original.normals = Some(vec![Vec3::Z; original.positions.len()]);
        original.materials.as_mut().unwrap().table[0].normal_texture = Some((image, 1.0));
        // The map's normal at x: its two texels' (as decoded) mixed from
        // their centres at x = ¼ and ¾; the square's frame is x, y, z.
        let decoded = |n: Vec3| {
            Vec3::from_array(
                texel(n).map(|c| c as f32 / 127.5 - 1.0)[..3]
                    .try_into()
                    .unwrap(),
            )
        };
        let want = |x: f32| {
            let f = ((x - 0.25) / 0.5).clamp(0.0, 1.0);
            decoded(lean[0]).lerp(decoded(lean[1]), f).normalize()
        };
        let baked = bake(&original, &textured_square(2), 256).unwrap();
        let shown = Appearance::new(&baked.mesh);
        let m = &baked.mesh;
        let mut worst = 0.0f32;
        for t in 0..m.triangles.len() {
            for b in [
                [1.0 / 3.0; 3],
                [0.6, 0.3, 0.1],
                [0.1, 0.6, 0.3],
                [0.3, 0.1, 0.6],
            ] {
                let p: Vec3 = (0..3).map(|k| m.triangle(t)[k] * b[k]).sum();
                worst = worst.max(shown.normal(t, b).angle_between(want(p.x)).to_degrees());
            }
        }
        assert!(worst < 3.0, "{worst}°");
        // Without the map the bake is flat: the lean is the map's doing.
        original.materials.as_mut().unwrap().table[0].normal_texture = None;
        let flat = bake(&original, &textured_square(2), 256).unwrap();
        let n = Appearance::new(&flat.mesh).normal(0, [1.0 / 3.0; 3]);
        assert!(n.angle_between(Vec3::Z) < 0.02, "{n}");
    }

    /// The default side keeps the original's texels per triangle, a power
    /// of two within 1024..=4096.
    #[test]
    fn the_default_size_keeps_the_texels_per_triangle() {
        let with_texture = |side: u32| {
            let mut m = textured_square(4);
            let texture = Texture {
                width: side,
                height: side,
                rgba: vec![[9, 9, 9, 255]; (side * side) as usize],
            };
            m.materials = Some(Materials::single(textured(&texture, Material::default())));
            m
        };
        let truck_like = with_texture(2048);
        let n = truck_like.triangles.len();
        assert_eq!(default_size(&truck_like, n / 2), 2048);
        assert_eq!(default_size(&truck_like, n / 4), 1024);
        assert_eq!(default_size(&truck_like, 1), 1024);
        assert_eq!(default_size(&with_texture(4096), n), 4096);
        assert_eq!(default_size(&with_texture(256), n), 1024);
        assert_eq!(default_size(&textured_square(4), n), 1024);
    }
}
