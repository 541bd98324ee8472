//! The multi-resolution pyramid of §2 (Tables 1–3) and its in-between
//! resolutions (§5).
//!
//! Level k samples S at half the resolution of level k−1 and filters it with the
//! same support radius in its own voxels, so the radius doubles in units of the
//! finest grid while the resolution halves: each level removes the next octave of
//! detail, and the genus falls. The filtered densities are kept, so the
//! studio's filter-radius slider can ask for any point between two levels: §5
//! interpolates the two adjacent buffers into an in-between one and extracts it.
//!
//! [`Pyramid::certify`] gives every level a certified two-sided Hausdorff
//! bound against the input surface (the simplifier's certificate), so a cut
//! honours the tolerance and the view like every other method: the coarsest
//! level within it. A level whose surface the filter took away entirely is
//! empty, with no bound, and the pyramid says where the object vanishes.

use glam::Vec3;
use rayon::prelude::*;

use super::{DENSITY_ISO, Filter, PostSimplify, VoxelLevel, level, marching_cubes, post_simplify};
use crate::geom::{TriMesh, Volume};
use crate::implicit::Implicit;
use crate::lod::{DrawSet, Hierarchy};
use crate::progress::{Cancelled, Progress};
use crate::simplify::{BoundOptions, Original, certify_against};
use crate::view::{Tolerance, View};

/// What the pyramid samples.
#[derive(Clone, Copy)]
pub enum Source<'a> {
    /// A solid (implicit function, or a mesh through its winding number).
    Solid(&'a dyn Implicit),
    /// A scalar volume and its iso value: S = (value ≥ iso) on its own grid.
    Volume(&'a Volume, f32),
}

impl<'a> Source<'a> {
    /// The input surface, where the source has one (a mesh's solid).
    pub fn surface(&self) -> Option<&'a TriMesh> {
        match *self {
            Source::Solid(s) => s.surface(),
            Source::Volume(..) => None,
        }
    }
}

/// One level: the filtered density f = h ∗ S on its grid.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PyramidLevel {
    pub density: Volume,
    /// Voxels along the longest side.
    pub resolution: usize,
    /// Filter support in voxels of the finest level.
    pub radius_finest: f32,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Pyramid {
    /// Finest first.
    pub levels: Vec<PyramidLevel>,
    /// Per level, once certified: the certified two-sided Hausdorff bound of
    /// its surface against the reference ([`f32::INFINITY`]: an empty level).
    pub error_bounds: Vec<f32>,
    /// The reference is the input surface (else, for a solid or a volume
    /// given without one, the finest level's surface).
    pub against_input: bool,
    /// Bounding-box diagonal of the reference.
    pub diagonal: f32,
    /// How each extracted level is simplified further (§5).
    pub post: PostSimplify,
}

/// The coarsest grid the pyramid goes down to (Tables 1–3 end near 4–8).
pub const MIN_RESOLUTION: usize = 8;

impl Pyramid {
    /// Builds the levels from `finest` voxels along the longest side down to
    /// [`MIN_RESOLUTION`], each filtered with support `radius` of its own voxels.
    /// A volume's finest level is its own grid (`finest` is ignored).
    pub fn build(
        source: Source,
        finest: usize,
        radius: f32,
        filter: Filter,
        progress: &Progress,
    ) -> Result<Pyramid, Cancelled> {
        let radius = radius.max(0.0);
        let mut levels = Vec::new();
        let finest = match source {
            Source::Solid(_) => finest,
            Source::Volume(v, _) => v.dims.into_iter().max().unwrap_or(0),
        };
        let mut factor = 1;
        while finest / factor >= MIN_RESOLUTION || levels.is_empty() {
            progress.check()?;
            let resolution = finest / factor;
            let density = super::density(source, resolution, factor, radius, filter, progress)?;
            if progress.wants_preview() {
                // Watching the build: each new level as it is filtered.
                progress.publish(crate::lod::DrawSet {
                    mesh: marching_cubes(&density, DENSITY_ISO, progress)?,
                    ..Default::default()
                });
            }
            levels.push(PyramidLevel {
                density,
                resolution,
                radius_finest: radius * factor as f32,
            });
            factor *= 2;
        }
        Ok(Pyramid {
            levels,
            error_bounds: Vec::new(),
            against_input: false,
            diagonal: 0.0,
            post: PostSimplify::HALF_VOXEL,
        })
    }

    /// Certifies every level against `reference` (the input surface), or
    /// without one against the finest level's surface.
    pub fn certify(
        &mut self,
        reference: Option<&TriMesh>,
        progress: &Progress,
    ) -> Result<(), Cancelled> {
        let against_input = reference.is_some();
        let finest;
        let reference = match reference {
            Some(m) => m,
            None => {
                finest = self.level(0, progress)?.mesh;
                &finest
            }
        };
        let original = Original::new(reference);
        let diagonal = reference.bounds().diagonal();
        let opts = BoundOptions::for_diagonal(diagonal);
        let mut bounds = Vec::with_capacity(self.levels.len());
        for i in 0..self.levels.len() {
            let mesh = self.level(i, progress)?.mesh;
            // After the extraction, which names its own stage.
            progress.stage("certifying the levels' bounds");
            bounds.push(level_bound(&original, &mesh, &opts, progress)?);
        }
        self.error_bounds = bounds;
        self.against_input = against_input;
        self.diagonal = diagonal;
        Ok(())
    }

    /// The first level the filter emptied (the object vanishes there).
    pub fn vanishes_at(&self) -> Option<usize> {
        self.error_bounds.iter().position(|b| b.is_infinite())
    }

    /// The coarsest level whose bound `tolerance` accepts for `view` (the
    /// finest when none is certified or none is accepted).
    pub fn level_within(&self, view: &View, tolerance: Tolerance) -> usize {
        let Some(finest) = self.levels.first() else {
            return 0;
        };
        let b = finest.density.bounds();
        let (center, radius) = (b.center(), 0.5 * b.diagonal());
        self.error_bounds
            .iter()
            .rposition(|e| {
                e.is_finite() && tolerance.accepts(view, self.diagonal, *e, center, radius)
            })
            .unwrap_or(0)
    }

    /// The iso-surface of level `i` (clamped to the pyramid).
    pub fn level(&self, i: usize, progress: &Progress) -> Result<VoxelLevel, Cancelled> {
        let l = &self.levels[i.min(self.levels.len() - 1)];
        let mesh = marching_cubes(&l.density, DENSITY_ISO, progress)?;
        let voxel = l.density.spacing.max_element();
        let mesh = post_simplify(mesh, voxel, self.post, progress)?;
        Ok(level(mesh, l.resolution, l.radius_finest))
    }

    /// §5: the level at a continuous position `t` (0 = finest, 1 = the next,
    /// ...): a grid of in-between resolution on which the two adjacent densities
    /// are interpolated trilinearly and blended, then extracted.
    pub fn in_between(&self, t: f32, progress: &Progress) -> Result<VoxelLevel, Cancelled> {
        let last = self.levels.len() - 1;
        let t = if t.is_finite() {
            t.clamp(0.0, last as f32)
        } else {
            0.0
        };
        let i = (t.floor() as usize).min(last);
        let f = t - i as f32;
        if f <= 1e-4 || i == last {
            return self.level(i, progress);
        }
        let (a, b) = (&self.levels[i], &self.levels[i + 1]);
        // The coarser buffer reaches farther (its padding is wider).
        let bounds = b.density.bounds().union(a.density.bounds());
        let lerp = |x: f32, y: f32| x + (y - x) * f;
        let spacing = a.density.spacing.lerp(b.density.spacing, f);
        let dims = [0, 1, 2].map(|k| (bounds.extent()[k] / spacing[k]).ceil() as usize + 1);
        let [nx, ny, _] = dims;
        let mut data = vec![0.0f32; dims[0] * dims[1] * dims[2]];
        data.par_chunks_mut(nx * ny)
            .enumerate()
            .for_each(|(z, slab)| {
                for (j, v) in slab.iter_mut().enumerate() {
                    let p = bounds.min
                        + spacing * Vec3::new((j % nx) as f32, (j / nx) as f32, z as f32);
                    *v = lerp(trilinear(&a.density, p), trilinear(&b.density, p));
                }
            });
        let grid = Volume {
            dims,
            spacing,
            origin: bounds.min,
            data,
        };
        let mesh = marching_cubes(&grid, DENSITY_ISO, progress)?;
        let mesh = post_simplify(mesh, spacing.max_element(), self.post, progress)?;
        Ok(level(
            mesh,
            lerp(a.resolution as f32, b.resolution as f32).round() as usize,
            lerp(a.radius_finest, b.radius_finest),
        ))
    }
}

/// A pyramid cut like every hierarchy: the coarsest certified level within
/// the tolerance, unless a continuous position (§5, the studio's pyramid
/// slider) overrides it and shows the in-between level there.
#[derive(Debug, Clone)]
pub struct PyramidCut {
    pub pyramid: Pyramid,
    /// The explicit override: a continuous position (0 = finest).
    pub position: Option<f32>,
    /// The level last extracted, its position and its bound (re-extracted
    /// and re-certified on a move).
    cached: Option<(f32, TriMesh, f32)>,
    /// The finest level's surface, extracted once: what in-between levels
    /// are certified against.
    finest: Option<TriMesh>,
}

impl PyramidCut {
    pub fn new(pyramid: Pyramid, position: Option<f32>) -> Self {
        PyramidCut {
            pyramid,
            position,
            cached: None,
            finest: None,
        }
    }

    /// A certified bound of the in-between level `mesh` by the triangle
    /// inequality: its certified distance to the finest level, plus the
    /// finest level's own bound (infinite before [`Pyramid::certify`]).
    /// Certifying against the finest level needs no input surface, so
    /// reopened pyramids certify theirs too.
    fn in_between_bound(&mut self, mesh: &TriMesh) -> f32 {
        let Some(&finest_bound) = self.pyramid.error_bounds.first() else {
            return f32::INFINITY;
        };
        let progress = Progress::new();
        let opts = BoundOptions::for_diagonal(self.diagonal());
        let pyramid = &self.pyramid;
        let finest = self.finest.get_or_insert_with(|| {
            pyramid
                .level(0, &progress)
                .map(|l| l.mesh)
                .unwrap_or_default()
        });
        if finest.triangles.is_empty() {
            return f32::INFINITY;
        }
        // Never cancelled here: the bound stands or is infinite.
        level_bound(&Original::new(finest), mesh, &opts, &progress)
            .map_or(f32::INFINITY, |d| d + finest_bound)
    }

    /// The position a cut shows.
    fn position_for(&self, view: &View, tolerance: Tolerance) -> f32 {
        match self.position {
            Some(t) if t.is_finite() => t.clamp(0.0, self.pyramid.levels.len().max(1) as f32 - 1.0),
            _ => self.pyramid.level_within(view, tolerance) as f32,
        }
    }
}

impl Hierarchy for PyramidCut {
    /// The reference surface's, once certified; else the finest grid's.
    fn diagonal(&self) -> f32 {
        if self.pyramid.diagonal > 0.0 {
            return self.pyramid.diagonal;
        }
        self.pyramid
            .levels
            .first()
            .map_or(0.0, |l| l.density.bounds().diagonal())
    }

    fn method(&self) -> crate::lod::Method {
        crate::lod::Method::Voxel
    }

    /// A whole level carries its certified bound; an in-between one is
    /// certified when it is extracted ([`PyramidCut::in_between_bound`]).
    fn select(&mut self, view: &View, tolerance: Tolerance) -> DrawSet {
        let t = self.position_for(view, tolerance);
        if self.cached.as_ref().is_none_or(|(at, ..)| *at != t) {
            // Extraction is never cancelled here; an empty mesh stands in if it were.
            let level = self.pyramid.in_between(t, &Progress::new());
            let mesh = level.map(|l| l.mesh).unwrap_or_default();
            let bound = match self.pyramid.error_bounds.get(t as usize) {
                Some(b) if t.fract() == 0.0 => *b,
                _ => self.in_between_bound(&mesh),
            };
            self.cached = Some((t, mesh, bound));
        }
        let (mesh, error_bound) = self
            .cached
            .as_ref()
            .map_or((TriMesh::default(), f32::INFINITY), |(_, m, b)| {
                (m.clone(), *b)
            });
        DrawSet {
            mesh,
            error_bound,
            ..Default::default()
        }
    }

    /// The cut depends on the position it shows only.
    fn view_key(&self, view: &View, tolerance: Tolerance) -> Option<u64> {
        Some(self.position_for(view, tolerance).to_bits().into())
    }

    fn save(&self, params: &serde_json::Value) -> Option<Vec<u8>> {
        Some(crate::io::hierarchy_file::save(
            crate::lod::Method::Voxel.tag(),
            params,
            &self.pyramid,
        ))
    }

    /// A fixed position chooses the level instead of the tolerance.
    fn controls(&self) -> crate::lod::Controls {
        use crate::lod::Knob;
        crate::lod::Controls {
            knobs: &[Knob::PyramidPosition],
            overridden_by: self.position.map(|_| Knob::PyramidPosition),
            has_levels: true,
        }
    }

    fn set_knobs(&mut self, knobs: &crate::lod::Knobs) -> bool {
        let changed = self.position != knobs.pyramid_position;
        self.position = knobs.pyramid_position;
        changed
    }
}

/// A level's certified bound against `original`; infinite for an empty level.
pub fn level_bound(
    original: &Original,
    mesh: &TriMesh,
    opts: &BoundOptions,
    progress: &Progress,
) -> Result<f32, Cancelled> {
    if mesh.triangles.is_empty() {
        return Ok(f32::INFINITY);
    }
    Ok(certify_against(original, mesh, opts, progress)?.error_bound())
}

/// Trilinear interpolation of `v` at world point `p`; 0 outside the grid.
pub fn trilinear(v: &Volume, p: Vec3) -> f32 {
    let g = (p - v.origin) / v.spacing;
    let [nx, ny, nz] = v.dims;
    if g.min_element() < 0.0
        || g.x > (nx - 1) as f32
        || g.y > (ny - 1) as f32
        || g.z > (nz - 1) as f32
    {
        return 0.0;
    }
    let base = [g.x, g.y, g.z].map(|c| c.floor() as usize);
    let b = [0, 1, 2].map(|k| base[k].min(v.dims[k].saturating_sub(2)));
    let w = g - Vec3::new(b[0] as f32, b[1] as f32, b[2] as f32);
    let mut sum = 0.0;
    for corner in 0..8 {
        let o = [corner & 1, (corner >> 1) & 1, (corner >> 2) & 1];
        let weight = [0, 1, 2]
            .map(|k| if o[k] == 1 { w[k] } else { 1.0 - w[k] })
            .iter()
            .product::<f32>();
        if weight > 0.0 {
            sum += weight * v.value(b[0] + o[0], b[1] + o[1], b[2] + o[2]);
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::csg_part;

    #[test]
    fn levels_halve_and_in_between_levels_sit_between() {
        let part = csg_part();
        let p = Progress::new();
        let pyr = Pyramid::build(Source::Solid(&part), 32, 2.0, Filter::Gaussian, &p).unwrap();
        let res: Vec<usize> = pyr.levels.iter().map(|l| l.resolution).collect();
        assert_eq!(res, [32, 16, 8]);
        let radius: Vec<f32> = pyr.levels.iter().map(|l| l.radius_finest).collect();
        assert_eq!(radius, [2.0, 4.0, 8.0]);
        let (l0, l1) = (pyr.level(0, &p).unwrap(), pyr.level(1, &p).unwrap());
        // At a level, §5's interpolation is that level.
        assert_eq!(pyr.in_between(0.0, &p).unwrap(), l0);
        let mid = pyr.in_between(0.5, &p).unwrap();
        let (lo, hi) = (l1.mesh.triangles.len(), l0.mesh.triangles.len());
        let n = mid.mesh.triangles.len();
        assert!(lo < n && n < hi, "{lo} < {n} < {hi}");
        assert_eq!(mid.resolution, 24);
        let topo = crate::geom::Topology::of(&mid.mesh);
        assert!(topo.is_closed() && topo.is_manifold());
        assert!(mid.genus <= l0.genus && mid.genus >= l1.genus);

        // Saved and reopened, it extracts the very same levels.
        let bytes =
            crate::io::hierarchy_file::save("voxel", &serde_json::json!({"radius": 2}), &pyr);
        let (_, back): (_, Pyramid) = crate::io::hierarchy_file::load(&bytes, "voxel").unwrap();
        assert_eq!(back, pyr);
        assert_eq!(back.in_between(0.5, &p).unwrap(), mid);

        // As a hierarchy, the position moves at run time.
        let mut cut = PyramidCut::new(back, Some(0.0));
        let view = View::orbit(Vec3::ZERO, 5.0, 0.0, 0.0);
        let tol = Tolerance::Relative(0.01);
        assert_eq!(cut.select(&view, tol).mesh, l0.mesh);
        cut.set_knobs(&crate::lod::Knobs {
            pyramid_position: Some(0.5),
            ..Default::default()
        });
        assert_eq!(cut.select(&view, tol).mesh, mid.mesh);
    }

    #[test]
    fn in_between_levels_carry_a_certified_bound() {
        let torus = crate::builtins::torus(1.0, 0.4, 48, 24);
        let solid = crate::implicit::MeshSolid::new(&torus);
        let source = Source::Solid(&solid);
        let p = Progress::new();
        let mut pyr = Pyramid::build(source, 32, 1.5, Filter::Gaussian, &p).unwrap();
        let view = View::orbit(Vec3::ZERO, 4.0, 0.3, 0.2);
        let tol = Tolerance::Pixels(1.0);
        let mut uncertified = PyramidCut::new(pyr.clone(), Some(0.5));
        assert!(uncertified.select(&view, tol).error_bound.is_infinite());
        pyr.certify(source.surface(), &p).unwrap();
        let mut cut = PyramidCut::new(pyr.clone(), Some(0.5));
        let set = cut.select(&view, tol);
        // Between its neighbours' bounds plus the step to the finest level:
        // finite, and at least a dense measurement against the input.
        let opts = crate::distance::SamplingOptions {
            samples: 40_000,
            ..Default::default()
        };
        let measured = crate::distance::hausdorff_mesh_mesh(&torus, &set.mesh, &opts).two_sided();
        assert!(
            set.error_bound.is_finite() && set.error_bound >= measured,
            "bound {} vs measured {measured}",
            set.error_bound
        );
        assert!(set.error_bound >= pyr.error_bounds[0]);
    }

    #[test]
    fn volumes_pool_into_coarser_levels() {
        let n = 32;
        let data = (0..n * n * n)
            .map(|i| {
                let q = Vec3::new((i % n) as f32, (i / n % n) as f32, (i / (n * n)) as f32);
                12.0 - q.distance(Vec3::splat(15.5))
            })
            .collect();
        let v = Volume {
            dims: [n; 3],
            spacing: Vec3::ONE,
            origin: Vec3::ZERO,
            data,
        };
        let p = Progress::new();
        let pyr = Pyramid::build(Source::Volume(&v, 0.0), 0, 1.0, Filter::Gaussian, &p).unwrap();
        let res: Vec<usize> = pyr.levels.iter().map(|l| l.resolution).collect();
        assert_eq!(res, [32, 16, 8]);
        for i in 0..3 {
            let l = pyr.level(i, &p).unwrap();
            assert_eq!((l.components, l.genus), (1, 0), "level {i}");
            // The sphere keeps its size: radius 12 from the centre.
            let m = &l.mesh;
            let mean = m
                .positions
                .iter()
                .map(|q| q.distance(Vec3::splat(15.5)))
                .sum::<f32>()
                / m.positions.len() as f32;
            assert!((mean - 12.0).abs() < 1.0, "level {i}: {mean}");
        }
    }
}
