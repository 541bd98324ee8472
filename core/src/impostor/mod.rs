//! Octahedral impostors (issue 50, item 5): the farthest LOD of an asset
//! as a handful of textured cards, as Unity's and Unreal's impostor tools
//! make them (Brucks' octahedral impostors). The model is rendered from
//! `views`² directions laid out on an octahedral map of the whole sphere
//! (each frame one cell of one atlas: colour with coverage in alpha, and a
//! tangent-space normal map with depth in alpha), then:
//!
//! 1. **Frames**: each texel of a frame is an orthographic ray along the
//!    frame's direction through the model's bounding sphere; its first hit
//!    (`distance::RayCaster`) gives the colour the original shows there
//!    (`io::base_color`), its shading normal (`geom::normals`) in the
//!    card's MikkTSpace frame, and its depth.
//! 2. **Cards**: the frames nearest the three axes and the two horizontal
//!    diagonals, both ways, each a quad through the centre facing its
//!    direction, single-sided, so any glTF client draws the impostor
//!    (alpha MASK) with one material and one primitive; engines with an
//!    octahedral impostor shader read every frame from the same atlas.
//! 3. **Silhouette error**: the cards against the original, both
//!    rendered as coverage masks (ray casts, the cards alpha-tested) from
//!    directions no frame was made from: the largest distance from a pixel
//!    only one covers to the nearest pixel the other covers, in object
//!    units. It stands for the impostor's error: the chain shows it where
//!    that length is under its pixel tolerance.

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::distance::{Hit, RayCaster};
use crate::geom::normals::ShadingNormals;
use crate::geom::{AlphaMode, Material, Materials, TriMesh, VertexAttributes};
use crate::io::base_color::SurfaceColor;
use crate::io::image::{CLAMP_TO_EDGE, encode_srgb, png_image};
use crate::lod::{BoundKind, BuildError, DrawSet, Hierarchy, Method, Texture};
use crate::progress::Progress;
use crate::view::{Tolerance, View};

/// Frames per side of the octahedral map.
pub const VIEWS_RANGE: std::ops::RangeInclusive<u32> = 2..=32;
pub const DEFAULT_VIEWS: u32 = 8;
/// Texels per side of a frame, at least.
const MIN_FRAME: u32 = 16;
/// Pixels per side of the silhouette masks.
const MASK: usize = 160;
/// Directions the silhouette error is measured from.
const CHECK_VIEWS: usize = 8;

/// What an impostor is built with.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ImpostorOptions {
    /// Frames per side of the octahedral map (`views`² directions).
    pub views: u32,
    /// The atlas's side in texels.
    pub texture: u32,
}

impl ImpostorOptions {
    /// Every value inside its range, each frame at least [`MIN_FRAME`] texels.
    pub fn validate(&self) -> Result<(), crate::lod::ParamError> {
        use crate::lod::in_range;
        in_range("views", self.views, &VIEWS_RANGE)?;
        in_range("texture", self.texture, &crate::bake::TEXTURE_SIZE_RANGE)?;
        if self.texture / self.views < MIN_FRAME {
            return Err(crate::lod::ParamError::new(
                "texture",
                format!(
                    "gives each of the {}² frames {} texels a side, fewer than {MIN_FRAME}",
                    self.views,
                    self.texture / self.views
                ),
            ));
        }
        Ok(())
    }
}

impl Default for ImpostorOptions {
    fn default() -> Self {
        ImpostorOptions {
            views: DEFAULT_VIEWS,
            texture: crate::bake::DEFAULT_TEXTURE_SIZE,
        }
    }
}

/// What an impostor build made.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ImpostorReport {
    pub views: u32,
    /// Texels per side of one frame.
    pub frame: u32,
    pub cards: usize,
    /// The measured silhouette error, in object units (step 3).
    pub silhouette_error: f32,
    pub seconds: f64,
}

/// The cards, wearing the atlas, and what it took.
pub struct Impostor {
    pub mesh: TriMesh,
    pub report: ImpostorReport,
}

/// A frame's orthographic camera: looking along `-dir`; `up = dir × right`.
#[derive(Debug, Clone, Copy)]
struct Frame {
    dir: Vec3,
    right: Vec3,
    up: Vec3,
}

impl Frame {
    fn new(dir: Vec3) -> Frame {
        let world_up = if dir.y.abs() > 0.999 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        let right = world_up.cross(dir).normalize();
        Frame {
            dir,
            right,
            up: dir.cross(right),
        }
    }

    /// The frame of cell (i, j) of an `n`×`n` octahedral map of the sphere.
    fn of_cell(i: u32, j: u32, n: u32) -> Frame {
        let u = Vec2::new(i as f32 + 0.5, j as f32 + 0.5) / n as f32 * 2.0 - 1.0;
        let mut p = Vec3::new(u.x, u.y, 1.0 - u.x.abs() - u.y.abs());
        if p.z < 0.0 {
            let folded = (Vec2::ONE - Vec2::new(p.y.abs(), p.x.abs()))
                * Vec2::new(p.x.signum(), p.y.signum());
            (p.x, p.y) = (folded.x, folded.y);
        }
        // The map's centre looks down from +y.
        Frame::new(Vec3::new(p.x, p.z, p.y).normalize())
    }

    /// The ray of texel (s, t) of a `side`² frame of the sphere (`center`,
    /// `radius`): from the sphere's front plane, along `-dir`; row 0 on top.
    fn ray(&self, s: u32, t: u32, side: u32, center: Vec3, radius: f32) -> Vec3 {
        let x = (2.0 * (s as f32 + 0.5) / side as f32 - 1.0) * radius;
        let y = (1.0 - 2.0 * (t as f32 + 0.5) / side as f32) * radius;
        center + self.dir * radius + self.right * x + self.up * y
    }
}

/// One frame's texels: colour, tangent-space normal, depth (0 at the
/// sphere's front, 1 at its back), `None` where the ray misses.
type Texel = Option<(Vec3, Vec3, f32)>;

/// Builds the impostor of `original`, its frames' share done in
/// `progress`, which may cancel it.
///
/// # Errors
/// An option out of range, a mesh empty or flat, or the build cancelled.
pub fn build(
    original: &TriMesh,
    opts: &ImpostorOptions,
    progress: &Progress,
) -> Result<Impostor, BuildError> {
    let start = std::time::Instant::now();
    opts.validate()?;
    let bounds = original.bounds();
    let radius = 0.5 * bounds.diagonal();
    if original.triangles.is_empty() || !(radius.is_finite() && radius > 0.0) {
        return Err(BuildError::BadInput(
            "an impostor needs a mesh with triangles and an extent".into(),
        ));
    }
    let center = bounds.center();
    let (n, side) = (opts.views, opts.texture / opts.views);

    // 1. Frames.
    let caster = RayCaster::new(original);
    let surface = SurfaceColor::new(original);
    let shading = ShadingNormals::new(original);
    progress.stage("rendering the frames");
    let done = std::sync::atomic::AtomicU32::new(0);
    let frames: Vec<Vec<Texel>> = (0..n * n)
        .into_par_iter()
        .map(|k| {
            if progress.is_cancelled() {
                return Vec::new();
            }
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress.set_fraction(d as f32 / (n * n) as f32);
            let f = Frame::of_cell(k % n, k / n, n);
            (0..side * side)
                .map(|p| {
                    let origin = f.ray(p % side, p / side, side, center, radius);
                    let hit = caster.cast(origin, -f.dir)?;
                    let (t, b) = (hit.triangle as usize, hit.bary);
                    let color = surface.as_ref().map_or(Vec3::ONE, |s| s.at(t, b));
                    let normal = shading.at(t, b);
                    // A card's MikkTSpace frame: tangent +right (u grows
                    // with x), bitangent −up (v grows downwards), normal dir.
                    let local =
                        Vec3::new(normal.dot(f.right), -normal.dot(f.up), normal.dot(f.dir));
                    Some((
                        color,
                        local,
                        (hit.distance / (2.0 * radius)).clamp(0.0, 1.0),
                    ))
                })
                .collect()
        })
        .collect();
    progress.check()?;
    let atlas = side * n;
    let mut color = vec![[0u8; 4]; (atlas * atlas) as usize];
    let mut normal = vec![[128u8, 128, 255, 255]; (atlas * atlas) as usize];
    let unit = |x: f32| ((x * 0.5 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8;
    for (k, texels) in frames.iter().enumerate() {
        let (fi, fj) = (k as u32 % n, k as u32 / n);
        // Empty texels take their covered neighbours' colour (alpha stays
        // 0), so filtering at a silhouette never fetches black.
        let filled = crate::bake::dilate(
            texels.iter().map(|t| t.map(|t| t.0)).collect(),
            side as usize,
            2,
        );
        for p in 0..side * side {
            let (x, y) = (fi * side + p % side, fj * side + p / side);
            let at = (y * atlas + x) as usize;
            if let Some(c) = filled[p as usize] {
                color[at] = [encode_srgb(c.x), encode_srgb(c.y), encode_srgb(c.z), 0];
            }
            if let Some((_, local, depth)) = texels[p as usize] {
                color[at][3] = 255;
                let d = (depth * 255.0).round() as u8;
                normal[at] = [unit(local.x), unit(local.y), unit(local.z.max(0.0)), d];
            }
        }
    }

    // 2. Cards.
    let wanted = [
        Vec3::X,
        Vec3::Y,
        Vec3::Z,
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, -1.0),
    ];
    let mut cells: Vec<u32> = Vec::new();
    for w in wanted.iter().flat_map(|w| [*w, -*w]) {
        let w = w.normalize();
        let best = (0..n * n)
            .max_by(|a, b| {
                let d = |k: u32| Frame::of_cell(k % n, k / n, n).dir.dot(w);
                d(*a).total_cmp(&d(*b))
            })
            .unwrap_or(0);
        if !cells.contains(&best) {
            cells.push(best);
        }
    }
    let mut mesh = TriMesh::default();
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    for &k in &cells {
        let f = Frame::of_cell(k % n, k / n, n);
        let base = mesh.positions.len() as u32;
        let cell = Vec2::new((k % n) as f32, (k / n) as f32);
        for (x, y) in [(-1.0, 1.0), (1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)] {
            mesh.positions
                .push(center + (f.right * x + f.up * y) * radius);
            normals.push(f.dir);
            let local = Vec2::new(0.5 * (x + 1.0), 0.5 * (1.0 - y));
            uvs.push((cell + local) / n as f32);
        }
        // Counter-clockwise seen from `dir` (right × up = dir).
        mesh.triangles.push([base, base + 3, base + 2]);
        mesh.triangles.push([base, base + 2, base + 1]);
    }
    mesh.normals = Some(normals);
    mesh.uvs = Some(uvs);
    // Frames are padded by the sphere's empty corners: clamped.
    let png = |rgba: Vec<[u8; 4]>| {
        let texture = Texture {
            width: atlas,
            height: atlas,
            rgba,
        };
        png_image(&texture, CLAMP_TO_EDGE)
    };
    mesh.materials = Some(Materials::single(Material {
        name: Some("impostor".into()),
        alpha_mode: AlphaMode::Mask(0.5),
        base_color_texture: Some(png(color.clone())),
        normal_texture: Some((png(normal), 1.0)),
        vertex_attributes: VertexAttributes {
            colors: false,
            uvs: true,
        },
        ..Material::default()
    }));

    // 3. Silhouette error.
    progress.stage("measuring the silhouette");
    let coverage = |at: Vec2| {
        let p = (at * atlas as f32)
            .as_uvec2()
            .min(glam::UVec2::splat(atlas - 1));
        color[(p.y * atlas + p.x) as usize][3] >= 128
    };
    let silhouette_error = silhouette_error(&caster, &mesh, &coverage, center, radius);
    Ok(Impostor {
        mesh,
        report: ImpostorReport {
            views: n,
            frame: side,
            cards: cells.len(),
            silhouette_error,
            seconds: start.elapsed().as_secs_f64(),
        },
    })
}

/// An impostor as the one cut a chain row takes: whatever the view or
/// tolerance, its cards, with the silhouette error as its bound (an
/// estimate: measured from some views, not a Hausdorff bound).
pub struct ImpostorCards {
    set: DrawSet,
    diagonal: f32,
}

impl ImpostorCards {
    pub fn build(
        mesh: &TriMesh,
        opts: &ImpostorOptions,
        progress: &Progress,
    ) -> Result<ImpostorCards, BuildError> {
        let imp = build(mesh, opts, progress)?;
        Ok(ImpostorCards {
            set: DrawSet {
                mesh: imp.mesh,
                error_bound: imp.report.silhouette_error,
                error_bound_kind: BoundKind::Estimate,
                ..Default::default()
            },
            diagonal: mesh.bounds().diagonal(),
        })
    }
}

impl Hierarchy for ImpostorCards {
    fn method(&self) -> Method {
        Method::Impostor
    }

    fn diagonal(&self) -> f32 {
        self.diagonal
    }

    fn select(&mut self, _view: &View, _tolerance: Tolerance) -> DrawSet {
        self.set.clone()
    }
}

/// The largest distance (object units) from a pixel only one of the
/// original and the cards covers to the nearest pixel the other covers,
/// over [`CHECK_VIEWS`] directions spread over the sphere (a golden-angle
/// spiral, none of them a frame's), plus half a pixel: the masks' two-sided
/// Hausdorff distance.
fn silhouette_error(
    original: &RayCaster,
    cards: &TriMesh,
    covered: &(dyn Fn(Vec2) -> bool + Sync),
    center: Vec3,
    radius: f32,
) -> f32 {
    let (a, b) = (original, RayCaster::new(cards));
    let uvs = cards.uvs.as_deref().unwrap_or_default();
    // The first card texel the ray meets that the atlas covers.
    let through_cards = |mut origin: Vec3, dir: Vec3| {
        for _ in 0..cards.triangles.len() {
            let Some(Hit {
                distance,
                triangle,
                bary,
            }) = b.cast(origin, dir)
            else {
                return false;
            };
            let tri = cards.triangles[triangle as usize];
            let uv: Vec2 = (0..3).map(|k| uvs[tri[k] as usize] * bary[k]).sum();
            if covered(uv) {
                return true;
            }
            origin += dir * (distance + 1e-4 * radius);
        }
        false
    };
    let pixel = 2.0 * radius / MASK as f32;
    (0..CHECK_VIEWS)
        .into_par_iter()
        .map(|v| {
            let z = 1.0 - (2.0 * v as f32 + 1.0) / CHECK_VIEWS as f32;
            let phi = v as f32 * std::f32::consts::PI * (3.0 - 5f32.sqrt());
            let r = (1.0 - z * z).sqrt();
            let f = Frame::new(Vec3::new(r * phi.cos(), z, r * phi.sin()));
            let side = MASK as u32;
            let mask = |hit: &dyn Fn(Vec3) -> bool| -> Vec<bool> {
                (0..side * side)
                    .map(|p| hit(f.ray(p % side, p / side, side, center, radius)))
                    .collect()
            };
            let original = mask(&|o| a.cast(o, -f.dir).is_some());
            let impostor = mask(&|o| through_cards(o, -f.dir));
            mask_hausdorff(&original, &impostor, MASK) as f32 * pixel + 0.5 * pixel
        })
        .reduce(|| 0.0, f32::max)
}

/// The two-sided Hausdorff distance in pixels between two `side`² masks'
/// covered pixels (0 when they agree; the diagonal when one is empty).
fn mask_hausdorff(a: &[bool], b: &[bool], side: usize) -> f64 {
    let edge = |m: &[bool]| -> Vec<(i64, i64)> {
        // Only pixels at a mask's edge can be nearest to one outside it.
        (0..side * side)
            .filter(|&p| {
                let (x, y) = ((p % side) as i64, (p / side) as i64);
                m[p] && [(-1, 0), (1, 0), (0, -1), (0, 1)].iter().any(|(dx, dy)| {
                    let (i, j) = (x + dx, y + dy);
                    i < 0
                        || j < 0
                        || i >= side as i64
                        || j >= side as i64
                        || !m[j as usize * side + i as usize]
                })
            })
            .map(|p| ((p % side) as i64, (p / side) as i64))
            .collect()
    };
    let one_way = |from: &[bool], to: &[bool]| -> f64 {
        let targets = edge(to);
        let mut worst = 0i64;
        for p in (0..side * side).filter(|&p| from[p] && !to[p]) {
            let (x, y) = ((p % side) as i64, (p / side) as i64);
            let nearest = targets
                .iter()
                .map(|(i, j)| (i - x).pow(2) + (j - y).pow(2))
                .min()
                .unwrap_or((2 * side * side) as i64);
            worst = worst.max(nearest);
        }
        (worst as f64).sqrt()
    };
    one_way(a, b).max(one_way(b, a))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Octahedral cells cover the sphere: every cell's direction is a unit
    /// vector, the map's centre looks from +y, and the nearest cell to any
    /// direction is within the cells' spacing.
    #[test]
    fn octahedral_cells_cover_the_sphere() {
        let n = 8;
        let dirs: Vec<Vec3> = (0..n * n)
            .map(|k| Frame::of_cell(k % n, k / n, n).dir)
            .collect();
        assert!(dirs.iter().all(|d| (d.length() - 1.0).abs() < 1e-5));
        let mut rng = crate::rng::Rng::new(3);
        let mut worst = 1.0f32;
        for _ in 0..2000 {
            let d = Vec3::new(rng.f32() - 0.5, rng.f32() - 0.5, rng.f32() - 0.5).normalize();
            let best = dirs.iter().map(|e| e.dot(d)).fold(-1.0, f32::max);
            worst = worst.min(best);
        }
        assert!(
            worst.acos().to_degrees() < 25.0,
            "{}",
            worst.acos().to_degrees()
        );
        for f in dirs.iter().map(|&d| Frame::new(d)) {
            assert!(f.right.cross(f.up).abs_diff_eq(f.dir, 1e-5));
        }
    }

    /// Two masks a known shift apart are that far apart; equal ones 0.
    #[test]
    fn mask_distance_is_the_shift() {
        let side = 20;
        let square = |x0: usize| -> Vec<bool> {
            (0..side * side)
                .map(|p| (x0..x0 + 6).contains(&(p % side)) && (5..11).contains(&(p / side)))
                .collect()
        };
        assert_eq!(mask_hausdorff(&square(3), &square(3), side), 0.0);
        assert_eq!(mask_hausdorff(&square(3), &square(7), side), 4.0);
    }

    /// A torus's impostor: one card (two triangles) per chosen frame, a
    /// silhouette error measured above zero and under half the bounding
    /// sphere's radius; bad options and an empty mesh are refused, and a
    /// cancelled build stops.
    #[test]
    fn a_torus_impostor_covers_its_silhouette() {
        let torus = crate::builtins::torus(1.0, 0.35, 48, 24);
        let p = Progress::new();
        let opts = |views, texture| ImpostorOptions { views, texture };
        let imp = build(&torus, &opts(4, 256), &p).unwrap();
        let r = &imp.report;
        assert_eq!((r.views, r.frame), (4, 64));
        assert!(r.cards >= 6 && imp.mesh.triangles.len() == 2 * r.cards);
        let radius = 0.5 * torus.bounds().diagonal();
        assert!(
            r.silhouette_error > 0.0 && r.silhouette_error < 0.5 * radius,
            "{r:?} against {radius}"
        );
        assert!(build(&torus, &opts(1, 256), &p).is_err());
        assert!(build(&torus, &opts(32, 256), &p).is_err());
        assert!(build(&TriMesh::default(), &ImpostorOptions::default(), &p).is_err());
        let cancelled = Progress::new();
        cancelled.cancel();
        let e = build(&torus, &ImpostorOptions::default(), &cancelled).err();
        assert_eq!(e, Some(BuildError::Cancelled));
    }
}
