//! §3: domain primitives — a PCA support rectangle per domain (§3.1) carrying
//! a texture of colour and Ψ (alpha), resampled by linear interpolation over the
//! Delaunay triangulation of the projected points with concavity triangles
//! removed, radial fall-off near its boundary and zero elsewhere (§3.2).

use glam::{DMat3, DVec3, Vec2, Vec3};
use rayon::prelude::*;
use spade::{DelaunayTriangulation, HasPosition, Point2, PositionInTriangulation, Triangulation};

use super::Multiscale;
use super::basis::domain_neighbours;
use super::classifier::symmetric_eigen;
use crate::io::image::encode_srgb;
use crate::lod::{DrawSet, Splat, Texture};
use crate::progress::{Cancelled, Progress};

/// Largest texture side; coarser texels are used for larger domains.
pub const MAX_TEXTURE: u32 = 1024;

/// The domain primitives of one level.
#[derive(Debug, Clone, Default)]
pub struct Primitives {
    pub level: usize,
    /// One per non-empty domain; `texture` indexes `textures`, `neighbours` the splats.
    pub splats: Vec<Splat>,
    pub textures: Vec<Texture>,
    /// Largest distance of a domain's points from its support plane.
    pub errors: Vec<f32>,
    /// Radius of the sphere around each splat's centre that holds its domain.
    pub bounds: Vec<f32>,
}

impl Primitives {
    pub fn texels(&self) -> usize {
        self.textures.iter().map(|t| t.rgba.len()).sum()
    }

    /// The primitives as a [`DrawSet`], sorted front to back from `eye` when
    /// given (§4: by distance to the primitive's centre), neighbours re-indexed.
    pub fn draw_set(&self, eye: Option<Vec3>) -> DrawSet {
        let mut order: Vec<usize> = (0..self.splats.len()).collect();
        if let Some(eye) = eye {
            let d = |i: usize| self.splats[i].center.distance_squared(eye);
            order.sort_by(|&a, &b| d(a).total_cmp(&d(b)));
        }
        let mut slot = vec![0usize; order.len()];
        for (k, &i) in order.iter().enumerate() {
            slot[i] = k;
        }
        let splats = order
            .iter()
            .map(|&i| {
                let mut s = self.splats[i].clone();
                s.neighbours = s.neighbours.iter().map(|&j| slot[j]).collect();
                s
            })
            .collect();
        DrawSet {
            splats,
            textures: self.textures.clone(),
            error_bound: self.errors.iter().copied().fold(0.0, f32::max),
            // Points to plane, not the distance of the quads to the surface.
            error_bound_kind: crate::lod::BoundKind::Estimate,
            ..DrawSet::default()
        }
    }
}

/// A projected domain point with its colour and Ψ.
#[derive(Debug, Clone, Copy)]
struct Sample {
    at: Point2<f64>,
    rgba: [f32; 4],
    radius: f64,
}

impl HasPosition for Sample {
    type Scalar = f64;
    fn position(&self) -> Point2<f64> {
        self.at
    }
}

/// Most texels a level's textures may hold per input point (or
/// [`MIN_TEXEL_CAP`] in all): a texture resamples the points (§4.3), so
/// texels far finer than the points add nothing but memory.
pub const TEXELS_PER_POINT: u64 = 4096;
/// What every level may hold, however few its points.
pub const MIN_TEXEL_CAP: u64 = 1 << 24;

/// Refuses a texel size whose textures for `level` would be absurdly fine
/// or not fit the memory budget (`--texel 1e-9` grew past 2.4 GB): each
/// domain's texture spans its members' extent along the plane's axes (at
/// most their bounding-box diagonal) padded by their median radius (at most
/// the largest) on each side, clamped to [`MAX_TEXTURE`], which bounds the
/// texels before any texture is made.
pub fn check_texel(ms: &Multiscale, level: usize, texel: f32) -> Result<(), String> {
    let positions = &ms.points.positions;
    let texels: u64 = ms
        .domains(level)
        .iter()
        .map(|members| {
            let (mut lo, mut hi) = (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY);
            let mut pad = 0f32;
            for &(m, _) in members {
                let p = positions[m as usize];
                lo = lo.min(p);
                hi = hi.max(p);
                pad = pad.max(ms.radii[m as usize]);
            }
            let side = f64::from((hi - lo).length() + 2.0 * pad);
            let n = ((side / f64::from(texel)).ceil() as u64).clamp(1, u64::from(MAX_TEXTURE));
            n * n
        })
        .sum();
    let cap = (positions.len() as u64 * TEXELS_PER_POINT).max(MIN_TEXEL_CAP);
    if texels > cap {
        return Err(format!(
            "texel {texel} gives level {level} up to {texels} texels, over the {cap} its {} points \
             can fill ({TEXELS_PER_POINT} per point): use a larger texel",
            positions.len()
        ));
    }
    crate::io::limits::check_budget(
        &format!("level {level}'s textures at texel {texel}"),
        texels * 4,
    )
    .map_err(|e| e.expected)
}

/// The primitives of `level` with texels of side `texel` (object units).
pub fn primitives(
    ms: &Multiscale,
    level: usize,
    texel: f32,
    progress: &Progress,
) -> Result<Primitives, Cancelled> {
    progress.stage("domain primitives");
    let domains = ms.domains(level);
    let neighbours = domain_neighbours(
        &domains,
        ms.points.positions.len(),
        ms.options.neighbour_fraction,
    );
    let centre = super::centre(&ms.points.positions);
    let built: Vec<Option<(Splat, Texture, f32, f32)>> = domains
        .par_iter()
        .enumerate()
        .map(|(d, members)| {
            if progress.is_cancelled() {
                return None;
            }
            Some(primitive(ms, members, texel, centre, d))
        })
        .collect();
    progress.check()?;
    let mut out = Primitives {
        level,
        ..Primitives::default()
    };
    for (d, b) in built.into_iter().enumerate() {
        let (mut splat, tex, err, bound) = b.expect("not cancelled");
        splat.texture = out.textures.len();
        splat.neighbours = neighbours[d].iter().map(|&j| j as usize).collect();
        out.splats.push(splat);
        out.textures.push(tex);
        out.errors.push(err);
        out.bounds.push(bound);
    }
    Ok(out)
}

/// §3.1–3.2 for one domain: its splat, texture, plane error and bounding radius.
fn primitive(
    ms: &Multiscale,
    members: &[(u32, f32)],
    texel: f32,
    model_centre: Vec3,
    domain: usize,
) -> (Splat, Texture, f32, f32) {
    let pos = |i: u32| ms.points.positions[i as usize].as_dvec3();
    let count = members.len() as f64;
    let mean = members.iter().map(|&(i, _)| pos(i)).sum::<DVec3>() / count;
    let mut cov = DMat3::ZERO;
    for &(i, _) in members {
        let d = pos(i) - mean;
        cov += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    let (_, e) = symmetric_eigen(cov * (1.0 / count));
    // Orient the normal outwards: along the points' normals when known,
    // else away from the model's centre.
    let outward = match &ms.points.normals {
        Some(n) => members
            .iter()
            .map(|&(i, _)| n[i as usize].as_dvec3())
            .sum::<DVec3>(),
        None => mean - model_centre.as_dvec3(),
    };
    let normal = if e[2].dot(outward) < 0.0 { -e[2] } else { e[2] };
    let e0 = e[0];
    let e1 = normal.cross(e0);
    let color = |i: u32| {
        ms.points
            .colors
            .as_ref()
            .map_or(Vec3::splat(0.8), |c| c[i as usize])
    };
    let samples: Vec<Sample> = members
        .iter()
        .map(|&(i, psi)| {
            let d = pos(i) - mean;
            let c = color(i);
            Sample {
                at: Point2::new(d.dot(e0), d.dot(e1)),
                rgba: [c.x, c.y, c.z, psi],
                radius: ms.radii[i as usize] as f64,
            }
        })
        .collect();
    let error = members
        .iter()
        .map(|&(i, _)| (pos(i) - mean).dot(normal).abs())
        .fold(0f64, f64::max) as f32;
    // The rectangle on the principal axes, padded by the median point radius
    // so the radial fall-off at the border is kept.
    let mut radii: Vec<f64> = samples.iter().map(|s| s.radius).collect();
    radii.sort_by(f64::total_cmp);
    let pad = radii[radii.len() / 2];
    let (mut lo, mut hi) = (
        Vec2::splat(f32::INFINITY).as_dvec2(),
        Vec2::splat(f32::NEG_INFINITY).as_dvec2(),
    );
    for s in &samples {
        let p = glam::DVec2::new(s.at.x, s.at.y);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    lo -= pad;
    hi += pad;
    let size = hi - lo;
    let dims = |len: f64| ((len / texel as f64).ceil() as u32).clamp(1, MAX_TEXTURE);
    let (w, h) = (dims(size.x), dims(size.y));
    let texture = resample(&samples, lo, size, w, h);
    let mid = (lo + hi) * 0.5;
    let center = mean + e0 * mid.x + e1 * mid.y;
    let bound = members
        .iter()
        .map(|&(i, _)| (pos(i) - center).length())
        .fold(0f64, f64::max)
        .max(0.5 * size.length());
    let splat = Splat {
        center: center.as_vec3(),
        axes: [(e0 * 0.5 * size.x).as_vec3(), (e1 * 0.5 * size.y).as_vec3()],
        normal: normal.as_vec3(),
        texture: 0,
        domain,
        neighbours: Vec::new(),
    };
    (splat, texture, error, bound as f32)
}

/// §3.2: resamples the scattered samples on a w×h grid over the rectangle
/// `lo + [0, size]`, row 0 at the low end of the second axis.
fn resample(samples: &[Sample], lo: glam::DVec2, size: glam::DVec2, w: u32, h: u32) -> Texture {
    let mut tri: DelaunayTriangulation<Sample> = DelaunayTriangulation::new();
    for s in samples {
        // Coincident projections: the first sample keeps the vertex.
        let _ = tri.insert(*s);
    }
    // Concavity triangles: an edge longer than the sum of its vertices' radii.
    let kept: Vec<bool> = std::iter::once(false)
        .chain(tri.inner_faces().map(|f| {
            f.adjacent_edges().iter().all(|e| {
                let [a, b] = e.vertices();
                e.length_2().sqrt() <= a.data().radius + b.data().radius
            })
        }))
        .collect();
    let mut rgba = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let p = Point2::new(
                lo.x + (x as f64 + 0.5) / w as f64 * size.x,
                lo.y + (y as f64 + 0.5) / h as f64 * size.y,
            );
            let face = match tri.locate(p) {
                PositionInTriangulation::OnFace(f) => Some(f),
                PositionInTriangulation::OnEdge(e) => {
                    let e = tri.directed_edge(e);
                    e.face()
                        .as_inner()
                        .or(e.rev().face().as_inner())
                        .map(|f| f.fix())
                }
                _ => None,
            };
            let value = match face.filter(|f| kept[f.index()]) {
                Some(f) => {
                    let f = tri.face(f);
                    let [a, b, c] = f.vertices().map(|v| *v.data());
                    let bary = barycentric(p, a.at, b.at, c.at);
                    std::array::from_fn(|k| {
                        bary[0] * a.rgba[k] + bary[1] * b.rgba[k] + bary[2] * c.rgba[k]
                    })
                }
                None => radial(&tri, p),
            };
            let [r, g, b, a] = value;
            rgba.push([
                encode_srgb(r),
                encode_srgb(g),
                encode_srgb(b),
                (a.clamp(0.0, 1.0) * 255.0).round() as u8,
            ]);
        }
    }
    Texture {
        width: w,
        height: h,
        rgba,
    }
}

/// Radial basis near the triangulation's boundary: the nearest sample's colour
/// with its Ψ falling off linearly to zero at its radius.
fn radial(tri: &DelaunayTriangulation<Sample>, p: Point2<f64>) -> [f32; 4] {
    let Some(v) = tri.nearest_neighbor(p) else {
        return [0.0; 4];
    };
    let s = v.data();
    let d = ((s.at.x - p.x).powi(2) + (s.at.y - p.y).powi(2)).sqrt();
    if d >= s.radius {
        return [0.0; 4];
    }
    let fall = (1.0 - d / s.radius) as f32;
    [s.rgba[0], s.rgba[1], s.rgba[2], s.rgba[3] * fall]
}

fn barycentric(p: Point2<f64>, a: Point2<f64>, b: Point2<f64>, c: Point2<f64>) -> [f32; 3] {
    let det = (b.y - c.y) * (a.x - c.x) + (c.x - b.x) * (a.y - c.y);
    if det.abs() < 1e-300 {
        return [1.0 / 3.0; 3];
    }
    let l0 = ((b.y - c.y) * (p.x - c.x) + (c.x - b.x) * (p.y - c.y)) / det;
    let l1 = ((c.y - a.y) * (p.x - c.x) + (a.x - c.x) * (p.y - c.y)) / det;
    let l = [l0, l1, 1.0 - l0 - l1].map(|v| v.clamp(0.0, 1.0) as f32);
    let sum: f32 = l.iter().sum();
    l.map(|v| v / sum.max(1e-12))
}
