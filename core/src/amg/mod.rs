//! AMG extreme point-set simplification (Reniers & Telea): a moment-based
//! surface classifier (§2.1) encoded in a finite-element stiffness matrix
//! (§2.2), coarsened by Ruge–Stüben algebraic multigrid into a multiscale of
//! quasi-flat domains (§2.3), each drawn as a textured domain primitive (§3)
//! blended with its domain neighbours (§4).
//!
//! Paper: D. Reniers, A. Telea, "Extreme simplification and rendering of
//! point sets using algebraic multigrid", Computing and Visualization in
//! Science, Springer (accepted 2006) (the "AMG paper" in this tree's docs).

pub mod basis;
pub mod classifier;
pub mod coarsening;
pub mod neighbourhood;
pub mod primitive;
pub mod render;
pub mod sparse;
pub mod stiffness;

use std::collections::HashMap;

use glam::Vec3;
use sprs::CsMat;

use crate::lod::{DrawSet, Hierarchy};
use crate::view::{Tolerance, View};

use crate::geom::PointSet;
use crate::io::Model;
use crate::progress::{Cancelled, Progress};
pub use coarsening::RugeStuben;
pub use primitive::{Primitives, primitives};

/// The neighbourhood sizes k a decomposition accepts (§2.1: the paper uses
/// 50–100; fewer than 3 neighbours span no plane).
pub const K_RANGE: std::ops::RangeInclusive<usize> = 3..=1000;

/// User parameters of the decomposition (§6: neighbourhood size; τ and the
/// neighbour fraction are the paper's fixed values).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AmgOptions {
    /// k_min of §2.1 (the paper uses 50–100).
    pub k: usize,
    /// Minimal feature size ε of §2.1 (0: plain k nearest neighbours).
    pub epsilon: f32,
    /// Exponent applied to the triangle classifier C(T) in eq. 5 (1 = the paper).
    /// The literal classifier is only ~5× lower on the octahedron's 109° creases
    /// than on its faces, which a relative strength of connection does not see as
    /// a cut; raising it to the 4th power gives the "several orders of magnitude"
    /// the paper describes (§2.1) and one domain per face.
    pub contrast: f64,
    /// Domain threshold τ of eq. 8.
    pub tau: f64,
    /// Shared-point fraction above which two domains are neighbours (§4).
    pub neighbour_fraction: f64,
    pub coarsening: RugeStuben,
}

impl Default for AmgOptions {
    fn default() -> Self {
        Self {
            k: 50,
            epsilon: 0.0,
            contrast: 4.0,
            tau: 0.05,
            neighbour_fraction: 0.05,
            coarsening: RugeStuben::default(),
        }
    }
}

/// Texel sizes a build may ask for, in multiples of the default (the median
/// point radius, §3.2): finer than a quarter spacing only costs memory,
/// coarser than eight blurs the domains' alpha away.
pub const TEXEL_SCALE_RANGE: std::ops::RangeInclusive<f32> = 0.25..=8.0;
/// The texel unless told otherwise: one median point radius.
pub const DEFAULT_TEXEL_SPACINGS: f32 = 1.0;
/// Lengths a texel given in model units may have.
const TEXEL_LENGTH_RANGE: std::ops::RangeInclusive<f32> = f32::MIN_POSITIVE..=f32::MAX;

/// The texel size of the domain primitives' textures (§3.2).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Texel {
    /// A multiple of the median point radius, so about one point spacing
    /// per texel at 1 (the studio's slider).
    Spacings(f32),
    /// A length in model units (the CLI's `--texel`).
    Length(f32),
}

/// What an AMG build is made with: the decomposition's user parameters
/// (§2.1) and the texel of its primitives (§3.2).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct AmgParams {
    pub k: usize,
    pub epsilon: f32,
    pub texel: Texel,
}

impl Default for AmgParams {
    fn default() -> Self {
        let o = AmgOptions::default();
        AmgParams {
            k: o.k,
            epsilon: o.epsilon,
            texel: Texel::Spacings(DEFAULT_TEXEL_SPACINGS),
        }
    }
}

impl AmgParams {
    pub fn validate(&self) -> Result<(), crate::lod::ParamError> {
        use crate::lod::in_range;
        in_range("k", self.k, &K_RANGE)?;
        in_range("epsilon", self.epsilon, &(0.0..=f32::MAX))?;
        match self.texel {
            Texel::Spacings(s) => in_range("texel", s, &TEXEL_SCALE_RANGE),
            Texel::Length(t) => in_range("texel", t, &TEXEL_LENGTH_RANGE),
        }
    }

    pub fn options(&self) -> AmgOptions {
        AmgOptions {
            k: self.k,
            epsilon: self.epsilon,
            ..AmgOptions::default()
        }
    }

    /// Decomposes `points` (§2) into a hierarchy of domain primitives.
    pub fn build(&self, points: &PointSet, progress: &Progress) -> Result<AmgHierarchy, AmgError> {
        let ms = decompose(points, &self.options(), progress)?;
        let texel = match self.texel {
            Texel::Spacings(s) => s * ms.default_texel(),
            Texel::Length(t) => t,
        };
        Ok(AmgHierarchy::new(ms, texel))
    }
}

/// Why a decomposition did not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AmgError {
    #[error("{0}")]
    BadInput(String),
    #[error("cancelled")]
    Cancelled,
}

impl From<Cancelled> for AmgError {
    fn from(_: Cancelled) -> Self {
        AmgError::Cancelled
    }
}

/// The built multiscale: the points, their classifier values, the stiffness
/// matrix and the AMG hierarchy.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Multiscale {
    pub points: PointSet,
    /// C_ε of every point (eq. 3), for colouring.
    pub classifier: Vec<f32>,
    /// Point radius (the input's, at least the distance to the 6th nearest neighbour):
    /// the concavity test and radial fall-off of §3.2.
    pub radii: Vec<f32>,
    pub coarsening: coarsening::Coarsening,
    pub options: AmgOptions,
}

impl Multiscale {
    /// The texel size splats get unless told otherwise: the median point
    /// radius (§3.2), so a texel is about one point's spacing; 0 without points.
    pub fn default_texel(&self) -> f32 {
        let mut r = self.radii.clone();
        r.sort_by(f32::total_cmp);
        r.get(r.len() / 2).copied().unwrap_or(0.0)
    }

    /// The stiffness matrix A (eq. 5–7).
    pub fn stiffness(&self) -> &CsMat<f64> {
        &self.coarsening.operators[0]
    }

    /// Basis functions per level, finest (the points) first.
    pub fn level_sizes(&self) -> Vec<usize> {
        self.coarsening.level_sizes()
    }

    pub fn levels(&self) -> usize {
        self.coarsening.operators.len()
    }

    /// The paper's default level L − 5 (§2.3), L the coarsest.
    pub fn default_level(&self) -> usize {
        self.levels().saturating_sub(6)
    }

    /// Non-empty domains D^{l,i} (eq. 8) of `level`, with their Ψ values.
    pub fn domains(&self, level: usize) -> Vec<Vec<(u32, f32)>> {
        let psi = basis::basis(&self.coarsening, level);
        basis::domains(&psi, self.options.tau)
            .into_iter()
            .filter(|d| !d.is_empty())
            .collect()
    }
}

/// Writes the stiffness matrix A as MatrixMarket (for cross-checks with PyAMG).
pub fn write_matrix_market(ms: &Multiscale, out: &mut impl std::io::Write) -> std::io::Result<()> {
    sprs::io::write_matrix_market_to_bufwrite(out, ms.stiffness())
}

/// The point set of a model: a point set as is, or a mesh's vertices with
/// their colours and normals.
pub fn point_set(model: &Model) -> Option<PointSet> {
    match model {
        Model::Points(p) => Some(p.clone()),
        Model::Mesh(m) => Some(mesh_points(m)),
        _ => None,
    }
}

/// A mesh's vertices as the points AMG decomposes (their radii follow
/// from their neighbours), each wearing the colour its surface shows
/// there: texture × factor × vertex colour (`io::base_color`).
pub fn mesh_points(mesh: &crate::geom::TriMesh) -> PointSet {
    PointSet {
        positions: mesh.positions.clone(),
        normals: mesh.normals.clone(),
        colors: crate::io::base_color::vertex_colors(mesh).or_else(|| mesh.colors.clone()),
        radii: None,
    }
}

/// Checks a point set and options before a decomposition.
pub fn validate(points: &PointSet, opts: &AmgOptions) -> Result<(), AmgError> {
    let bad = |m: String| Err(AmgError::BadInput(m));
    if !K_RANGE.contains(&opts.k) {
        return bad(format!(
            "k must be between {} and {}, got {}",
            K_RANGE.start(),
            K_RANGE.end(),
            opts.k
        ));
    }
    if !(opts.contrast.is_finite() && (0.0..=8.0).contains(&opts.contrast)) {
        return bad(format!("contrast must be in 0..=8, got {}", opts.contrast));
    }
    if !(opts.tau > 0.0 && opts.tau < 1.0) {
        return bad(format!("tau must be in (0, 1), got {}", opts.tau));
    }
    if !(opts.epsilon.is_finite() && opts.epsilon >= 0.0) {
        return bad(format!(
            "epsilon must be finite and >= 0, got {}",
            opts.epsilon
        ));
    }
    if points.positions.len() <= opts.k {
        return bad(format!(
            "{} points are too few for k = {} neighbours",
            points.positions.len(),
            opts.k
        ));
    }
    if let Some(i) = points.positions.iter().position(|p| !p.is_finite()) {
        return bad(format!("point {i} is not finite"));
    }
    if points.bounds().diagonal() <= 0.0 {
        return bad("all points coincide".into());
    }
    Ok(())
}

/// §2: neighbourhoods, classifier, stiffness matrix and AMG coarsening.
pub fn decompose(
    points: &PointSet,
    opts: &AmgOptions,
    progress: &Progress,
) -> Result<Multiscale, AmgError> {
    validate(points, opts)?;
    let pos = &points.positions;
    progress.stage("neighbourhoods");
    let nb = neighbourhood::neighbourhoods(pos, opts.k, opts.epsilon);
    progress.check()?;
    progress.stage("classifier");
    let class = classifier::classify(pos, &nb);
    progress.check()?;
    progress.stage("stiffness matrix");
    let a = stiffness::stiffness(pos, &nb, &class, opts.contrast, progress)?;
    progress.stage("AMG coarsening");
    // Watching the build: each new level's unknowns, drawn at the points they
    // stand for (a C point keeps its fine point), as they are made.
    let mut kept: Vec<u32> = (0..pos.len() as u32).collect();
    let diagonal = points.bounds().diagonal();
    let coarsening = coarsening::coarsen_watched(a, &opts.coarsening, progress, |is_c| {
        kept = kept
            .iter()
            .zip(is_c)
            .filter_map(|(&p, &c)| c.then_some(p))
            .collect();
        if progress.wants_preview() {
            progress.publish(level_preview(points, &kept, diagonal));
        }
    })?;
    // §3.2's point radius: at least the distance to the 6th nearest neighbour,
    // so randomly sampled flat regions are not cut by the concavity test.
    let radii = nb
        .lists
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let sixth = pos[i].distance(pos[l[l.len().min(6) - 1] as usize]);
            let given = points.radii.as_ref().and_then(|r| r.get(i)).copied();
            given
                .filter(|r| r.is_finite())
                .map_or(sixth, |r| r.max(sixth))
        })
        .collect();
    Ok(Multiscale {
        points: points.clone(),
        classifier: class.value,
        radii,
        coarsening,
        options: *opts,
    })
}

/// One AMG level as points: `kept` (the points its unknowns stand for) as
/// discs about as wide as their spacing on a surface of the set's extent.
fn level_preview(points: &PointSet, kept: &[u32], diagonal: f32) -> crate::lod::DrawSet {
    let radius = 0.5 * diagonal / (kept.len().max(1) as f32).sqrt();
    crate::lod::DrawSet {
        points: kept
            .iter()
            .map(|&i| crate::lod::CutPoint {
                center: points.positions[i as usize],
                radius,
                color: points
                    .colors
                    .as_ref()
                    .map_or(Vec3::splat(0.8), |c| c[i as usize]),
                normal: points
                    .normals
                    .as_ref()
                    .map_or(Vec3::ZERO, |n| n[i as usize]),
                error: 0.0,
            })
            .collect(),
        ..Default::default()
    }
}

/// The centre of a point set's bounds, towards which normals of sets without
/// normals are oriented away.
fn centre(points: &[Vec3]) -> Vec3 {
    crate::geom::Aabb::from_points(points).center()
}

/// The built multiscale as a [`Hierarchy`]: `select` draws the coarsest level
/// whose every primitive's plane error meets the tolerance, or the level fixed
/// with [`AmgHierarchy::set_level`], sorted front to back (§4).
pub struct AmgHierarchy {
    multiscale: Multiscale,
    texel: f32,
    level: Option<usize>,
    built: HashMap<usize, Primitives>,
}

impl AmgHierarchy {
    pub fn new(multiscale: Multiscale, texel: f32) -> Self {
        Self {
            multiscale,
            texel,
            level: None,
            built: HashMap::new(),
        }
    }

    pub fn multiscale(&self) -> &Multiscale {
        &self.multiscale
    }

    /// The texel size of its primitives, in model units.
    pub fn texel(&self) -> f32 {
        self.texel
    }

    /// Fixes the drawn level (`None`: chosen by the tolerance).
    pub fn set_level(&mut self, level: Option<usize>) {
        self.level = level.map(|l| l.min(self.multiscale.levels() - 1));
    }

    /// Builds the primitives of every level the threshold can choose (1 and
    /// up) and of `also`, so that cuts never build them (a studio worker calls
    /// this, keeping the build's cost off the UI thread).
    pub fn build_levels(
        &mut self,
        also: Option<usize>,
        progress: &Progress,
    ) -> Result<(), Cancelled> {
        let levels = self.multiscale.levels();
        for level in (1..levels).chain(also.filter(|&l| l < levels)) {
            if !self.built.contains_key(&level) {
                progress.set_fraction(level as f32 / levels as f32);
                let p = primitives(&self.multiscale, level, self.texel, progress)?;
                self.built.insert(level, p);
            }
        }
        Ok(())
    }

    /// The primitives of `level`, built once.
    pub fn primitives(&mut self, level: usize) -> &Primitives {
        let (ms, texel) = (&self.multiscale, self.texel);
        self.built.entry(level).or_insert_with(|| {
            primitives(ms, level, texel, &Progress::new()).expect("never cancelled")
        })
    }
}

impl Multiscale {
    /// Whether the parts agree in size (a reopened file's is checked before use).
    pub fn is_consistent(&self) -> bool {
        let n = self.points.positions.len();
        let ops = &self.coarsening.operators;
        let pro = &self.coarsening.prolongations;
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        n > 0
            && self.points.positions.iter().all(|p| p.is_finite())
            && self.radii.iter().all(|r| r.is_finite() && *r >= 0.0)
            && ops.iter().chain(pro).all(|a| finite(a.data()))
            && self.radii.len() == n
            && self.classifier.len() == n
            && ops.first().is_some_and(|a| a.rows() == n)
            && ops.iter().all(|a| a.rows() == a.cols())
            && pro.len() + 1 == ops.len()
            && pro
                .iter()
                .zip(ops.windows(2))
                .all(|(p, a)| p.rows() == a[0].rows() && p.cols() == a[1].rows())
    }
}

impl Hierarchy for AmgHierarchy {
    fn diagonal(&self) -> f32 {
        self.multiscale.points.bounds().diagonal()
    }

    fn method(&self) -> crate::lod::Method {
        crate::lod::Method::Amg
    }

    fn save(&self, params: &serde_json::Value) -> Option<Vec<u8>> {
        let mut params = params.clone();
        params["texel"] = serde_json::json!(self.texel);
        Some(crate::io::hierarchy_file::save(
            crate::lod::Method::Amg.tag(),
            &params,
            &self.multiscale,
        ))
    }

    fn select(&mut self, view: &View, tolerance: Tolerance) -> DrawSet {
        let diagonal = self.multiscale.points.bounds().diagonal();
        let level = match self.level {
            Some(l) => l,
            // Coarsest first: the first level whose primitives all pass.
            None => (1..self.multiscale.levels())
                .rev()
                .find(|&l| {
                    let p = self.primitives(l);
                    (0..p.splats.len()).all(|k| {
                        tolerance.accepts(
                            view,
                            diagonal,
                            p.errors[k],
                            p.splats[k].center,
                            p.bounds[k],
                        )
                    })
                })
                .unwrap_or(1),
        };
        self.primitives(level).draw_set(Some(view.eye))
    }

    /// A fixed level draws the same primitives from every view (only their
    /// front-to-back order changes, which order-independent blending ignores).
    fn view_key(&self, _view: &View, _tolerance: Tolerance) -> Option<u64> {
        self.level.map(|l| l as u64)
    }

    /// A fixed level chooses the cut instead of the tolerance.
    fn controls(&self) -> crate::lod::Controls {
        use crate::lod::Knob;
        crate::lod::Controls {
            knobs: &[Knob::AmgLevel],
            overridden_by: self.level.map(|_| Knob::AmgLevel),
            has_levels: true,
        }
    }

    fn set_knobs(&mut self, knobs: &crate::lod::Knobs) -> bool {
        let before = self.level;
        self.set_level(knobs.amg_level);
        self.level != before
    }
}

#[cfg(test)]
mod tests {
    use std::sync::OnceLock;

    use super::*;
    use crate::builtins::octahedron_points;

    /// The octahedron of Fig. 1 (16,000 points), decomposed once for all tests.
    fn octahedron() -> &'static (PointSet, Multiscale) {
        static MS: OnceLock<(PointSet, Multiscale)> = OnceLock::new();
        MS.get_or_init(|| {
            let pts = octahedron_points(16_000, 1);
            let ms = decompose(&pts, &AmgOptions::default(), &Progress::new()).unwrap();
            (pts, ms)
        })
    }

    fn eight_face_level(ms: &Multiscale) -> usize {
        (0..ms.levels())
            .find(|&l| ms.domains(l).len() == 8)
            .unwrap_or_else(|| panic!("no level with 8 domains: {:?}", ms.level_sizes()))
    }

    #[test]
    fn octahedron_has_a_level_of_eight_face_domains() {
        let (pts, ms) = octahedron();
        let sizes = ms.level_sizes();
        assert!(sizes.windows(2).all(|w| w[1] < w[0]), "{sizes:?}");
        let level = eight_face_level(ms);
        let prims = primitives(ms, level, 0.02, &Progress::new()).unwrap();
        let mut faces: Vec<usize> = prims
            .splats
            .iter()
            .map(|s| {
                // The face normal (±1, ±1, ±1)/√3 it should match, within 5°.
                let f = Vec3::new(
                    s.normal.x.signum(),
                    s.normal.y.signum(),
                    s.normal.z.signum(),
                );
                let angle = s.normal.angle_between(f.normalize()).to_degrees();
                assert!(angle < 5.0, "normal {} is {angle}° off its face", s.normal);
                ((f.x > 0.0) as usize) | ((f.y > 0.0) as usize) << 1 | ((f.z > 0.0) as usize) << 2
            })
            .collect();
        faces.sort();
        faces.dedup();
        assert_eq!(faces.len(), 8, "one domain per face");
        // Nearly no overlap (Fig. 5c): few points lie in two domains.
        let mut count = vec![0u8; pts.positions.len()];
        for d in ms.domains(level) {
            for (i, _) in d {
                count[i as usize] += 1;
            }
        }
        let shared = count.iter().filter(|&&c| c > 1).count();
        assert!(
            shared * 10 < pts.positions.len(),
            "{shared} points in several domains"
        );
        assert!(count.iter().all(|&c| c > 0), "every point is in a domain");
    }

    /// PyAMG 5.4.1's `ruge_stuben_solver` on the octahedron's stiffness matrix
    /// (`lodstudio amg builtin:octahedron-points --matrix-out oct.mtx`, then
    /// `scripts/amg_pyamg.sh oct.mtx`): its level sizes.
    const PYAMG_OCTAHEDRON: [usize; 9] = [16000, 6405, 2315, 750, 243, 80, 31, 9, 3];

    #[test]
    fn coarsening_equals_pyamg_with_its_zero_rows_and_stays_near_it_with_multipass() {
        let (_, ms) = octahedron();
        let opts = RugeStuben {
            orphans: coarsening::Orphans::Zero,
            ..ms.options.coarsening
        };
        let a = ms.coarsening.operators[0].clone();
        let pyamg_like = coarsening::coarsen(a, &opts, &Progress::new()).unwrap();
        assert_eq!(pyamg_like.level_sizes(), PYAMG_OCTAHEDRON);
        // The default keeps Ψ a partition of unity, which moves the levels
        // a little: within ±25% of PyAMG's at every level of ≥ 33 unknowns.
        for (l, (&ours, &theirs)) in ms.level_sizes().iter().zip(&PYAMG_OCTAHEDRON).enumerate() {
            if theirs >= 33 {
                let r = ours as f64 / theirs as f64;
                assert!((0.75..=1.25).contains(&r), "level {l}: {ours} vs {theirs}");
            }
        }
    }

    #[test]
    fn basis_functions_are_a_partition_of_unity() {
        let (_, ms) = octahedron();
        for level in 0..ms.levels() {
            let psi = basis::basis(&ms.coarsening, level);
            for (i, row) in psi.outer_iterator().enumerate() {
                let sum: f64 = row.iter().map(|(_, v)| v).sum();
                assert!(
                    (sum - 1.0).abs() < 1e-6,
                    "level {level} point {i}: ΣΨ = {sum}"
                );
            }
        }
    }

    #[test]
    fn stiffness_is_symmetric_with_zero_row_sums() {
        let (_, ms) = octahedron();
        let a = ms.stiffness();
        let t: CsMat<f64> = a.transpose_view().to_csr();
        let mut negative = 0usize;
        let mut off = 0usize;
        for (i, row) in a.outer_iterator().enumerate() {
            let scale = row.iter().fold(0f64, |m, (_, v)| m.max(v.abs()));
            assert!(scale > 0.0, "row {i} is empty");
            let sum: f64 = row.iter().map(|(_, v)| v).sum();
            assert!(sum.abs() <= 1e-9 * scale, "row {i} sums to {sum}");
            for (j, &v) in row.iter() {
                let vt = t.get(i, j).copied().unwrap_or(0.0);
                assert!(
                    (v - vt).abs() <= 1e-12 * scale,
                    "A[{i},{j}] = {v} but A[{j},{i}] = {vt}"
                );
                if i != j {
                    off += 1;
                    negative += (v < 0.0) as usize;
                }
            }
        }
        // A stiffness matrix: fans of 5–10 triangles, nearly all couplings negative.
        let per_row = off as f64 / a.rows() as f64;
        assert!(
            (4.0..=14.0).contains(&per_row),
            "{per_row} neighbours per point"
        );
        assert!(negative as f64 > 0.95 * off as f64);
    }

    #[test]
    fn hierarchy_selects_by_plane_error_and_sorts_front_to_back() {
        let (_, ms) = octahedron();
        let eight = eight_face_level(ms);
        let mut h = AmgHierarchy::new(ms.clone(), 0.05);
        let view = View::orbit(Vec3::ZERO, 3.0, 0.4, 0.3);
        // Coarse tolerance: the coarsest level whose planes all pass.
        let coarse = h.select(&view, Tolerance::Relative(0.05));
        let fine = h.select(&view, Tolerance::Relative(0.002));
        assert!(coarse.splats.len() <= 8 + 1, "{}", coarse.splats.len());
        assert!(coarse.error_bound <= 0.05 * ms.points.bounds().diagonal());
        assert!(fine.splats.len() > 8 * coarse.splats.len());
        assert!(fine.error_bound <= 0.002 * ms.points.bounds().diagonal());
        h.set_level(Some(eight));
        let fixed = h.select(&view, Tolerance::Relative(0.0));
        assert_eq!(fixed.splats.len(), 8);
        let d: Vec<f32> = fixed
            .splats
            .iter()
            .map(|s| s.center.distance(view.eye))
            .collect();
        assert!(d.windows(2).all(|w| w[0] <= w[1]), "front to back: {d:?}");
        for (i, s) in fixed.splats.iter().enumerate() {
            for &j in &s.neighbours {
                assert!(
                    fixed.splats[j].neighbours.contains(&i),
                    "neighbours are symmetric"
                );
            }
        }
    }

    /// A watched build publishes an AMG level as it is made: as many points as
    /// that level has unknowns, each at an input point.
    #[test]
    fn watched_builds_publish_each_new_level() {
        let pts = octahedron_points(2_000, 3);
        let progress = Progress::new();
        progress.watch();
        let ms = decompose(&pts, &AmgOptions::default(), &progress).unwrap();
        let state = progress.take_preview().expect("a level");
        let n = state.points.len();
        assert!(
            ms.level_sizes()[1..].contains(&n),
            "{n} of {:?}",
            ms.level_sizes()
        );
        for p in &state.points {
            assert!(pts.positions.contains(&p.center));
        }
    }

    #[test]
    fn bad_inputs_are_refused() {
        let mut pts = octahedron_points(40, 1);
        let opts = AmgOptions::default();
        assert!(matches!(
            decompose(&pts, &opts, &Progress::new()),
            Err(AmgError::BadInput(_))
        ));
        let few = AmgOptions { k: 10, ..opts };
        pts.positions[3].x = f32::NAN;
        assert!(matches!(
            decompose(&pts, &few, &Progress::new()),
            Err(AmgError::BadInput(_))
        ));
        let cancelled = Progress::new();
        cancelled.cancel();
        let ok = octahedron_points(500, 1);
        assert_eq!(
            decompose(&ok, &few, &cancelled).unwrap_err(),
            AmgError::Cancelled
        );
    }
}
