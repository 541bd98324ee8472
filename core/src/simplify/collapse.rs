//! Greedy edge collapse driven by a priority queue (hybrid paper §5.2).
//!
//! Collapses keep topology (link condition, no duplicate triangles), reject
//! triangles that flip or fold, optionally reject slivers (merge-tree paper
//! eq. 3 quality), and never join separate parts: part seams, borders and
//! non-manifold edges are constrained edges whose vertices move only along them
//! (or not at all with `lock_borders`). UV and colour seams (edges whose two
//! sides' corners show different surfaces, `geom::wedges`) are constrained the
//! same way, and every corner keeps its own side's wedge through each
//! collapse, so no face ever takes a UV or a colour from across a seam;
//! normals follow their wedges softly. A vertex's payload (skin weights,
//! morph deltas: `geom::payload`) is interpolated like its UVs, in its
//! wedges as in the vertex, and a collapse never joins two vertices that
//! share no joint of their skin (bone boundaries). Each collapse kills both endpoints and
//! every triangle around them and creates a new vertex and new triangles, so a
//! caller building a hierarchy (the hybrid MRG) gets distinct ids for every
//! primitive. The order comes from a caller-supplied cost; by default
//! [`quadric_cost`] at the best legal quadric placement, queued first by its
//! cheap lower bound [`quadric_mean`] and computed in full only when a
//! candidate reaches the front.

mod appearance;

use glam::{Vec2, Vec3};

pub use appearance::{ATTRIBUTE_WEIGHT_RANGE, AttributeWeights};

use super::quadric::Quadric;
use super::queue::CollapseQueue;
use crate::distance::{closest_point_on_segment, closest_point_on_triangle};
use crate::geom::{Adjacency, Materials, MeshArrays, Payload, TriMesh, UNTEXTURED_TEXELS, Wedges};
use crate::lod::Blocker;

/// The sliver and fold guards' range (a quality, a cosine; 0 turns either off).
pub const GUARD_RANGE: std::ops::RangeInclusive<f32> = 0.0..=1.0;

/// Legality rules for collapses.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct CollapseOptions {
    /// Border (and part-seam, non-manifold) vertices never move.
    pub lock_borders: bool,
    /// Sliver guard: reject a collapse that makes a triangle of quality
    /// 4√3·area/(l0²+l1²+l2²) below this (and worse than before). 0 disables.
    pub min_quality: f32,
    /// Fold guard: reject a collapse that turns any triangle's normal by more than
    /// the angle whose cosine this is (0 rejects only flips beyond 90°). The
    /// default 0.7 (about 46°) measured lower Hausdorff errors at 1% on the bunny,
    /// horse and engine than looser guards (BENCHMARKS.md).
    pub min_normal_cos: f32,
    /// Seam crossing: a UV seam's vertex may leave its seam (or two seams
    /// may meet) when every texture coordinate the collapse moves stays
    /// within this many texels of where its chart shows it (module doc of
    /// [`EdgeCollapser`]); 0 keeps every seam.
    pub uv_tolerance: f32,
    /// How much the appearance a collapse loses weighs in the order
    /// (`appearance`); the certified bound stays geometric.
    pub attribute_weights: AttributeWeights,
    /// Part, UV and colour seams constrain nothing, only the mesh's own
    /// borders do: the result's appearance is baked afresh (`bake`), so the
    /// input's charts and materials no longer matter.
    pub free_seams: bool,
}

/// The UV tolerance's range, in texels.
pub const UV_TOLERANCE_RANGE: std::ops::RangeInclusive<f32> = 0.0..=4096.0;

impl Default for CollapseOptions {
    fn default() -> Self {
        Self {
            lock_borders: false,
            min_quality: 0.0,
            min_normal_cos: 0.7,
            uv_tolerance: 1.0,
            attribute_weights: AttributeWeights::default(),
            free_seams: false,
        }
    }
}

impl CollapseOptions {
    /// Both guards inside [`GUARD_RANGE`].
    pub fn validate(&self) -> Result<(), crate::lod::ParamError> {
        use crate::lod::in_range;
        in_range("min_quality", self.min_quality, &GUARD_RANGE)?;
        in_range("min_normal_cos", self.min_normal_cos, &GUARD_RANGE)?;
        in_range("uv_tolerance", self.uv_tolerance, &UV_TOLERANCE_RANGE)?;
        self.attribute_weights.validate()
    }
}

/// What a caller's cost function sees of a candidate collapse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Candidate {
    pub edge: [u32; 2],
    pub position: Vec3,
    /// Quadric error of `position` (sum of squared plane distances, area weighted).
    pub quadric_error: f64,
    /// Total weight of the quadric's planes (their area).
    pub quadric_weight: f64,
    /// Triangles the collapse removes (2 inside, 1 on a border).
    pub triangles_removed: usize,
}

/// Orders candidate collapses (smaller goes first), looking at the working
/// mesh (the star a candidate replaces, via [`EdgeCollapser::star_into`] and
/// [`EdgeCollapser::triangle`]);
/// a non-finite cost takes the candidate out of the queue (the hybrid method
/// does so when a point replacement takes precedence, §5).
pub type StarCostFn = dyn Fn(&Candidate, &EdgeCollapser) -> f64 + Send + Sync;

/// Asked before each collapse whether it may happen, and told of each one
/// that did: an error limit (module `limit`) refuses a collapse whose
/// certified bound would pass it, and the collapse goes on with the others.
pub trait Veto {
    fn allows(&mut self, cand: &Candidate, col: &EdgeCollapser) -> bool;
    fn collapsed(&mut self, col: &EdgeCollapser, c: &Collapse);
}

/// One performed collapse.
#[derive(Debug, Clone, PartialEq)]
pub struct Collapse {
    /// The two vertices merged (both are dead afterwards).
    pub edge: [u32; 2],
    /// The new vertex and its position.
    pub vertex: u32,
    pub position: Vec3,
    /// Triangle ids that died and that were created.
    pub removed: Vec<u32>,
    pub added: Vec<u32>,
    pub cost: f64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Entry {
    cost: f64,
    a: u32,
    b: u32,
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Entry {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.cost
            .total_cmp(&o.cost)
            .then(self.a.cmp(&o.a))
            .then(self.b.cmp(&o.b))
    }
}

/// Relative weight of the constraint planes along borders and seams.
const BORDER_WEIGHT: f64 = 10.0;

/// The working mesh of an edge-collapse simplification. A clone continues
/// exactly as the original would (the cost function is shared), so a search
/// over stopping points resumes from a saved state instead of the input.
#[derive(Clone)]
pub struct EdgeCollapser {
    pos: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    colors: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    payload: Option<Payload>,
    /// Parts keep their materials: collapses never join parts.
    materials: Option<Materials>,
    /// The input's wedges, with `corners` for every triangle ever made.
    wedges: Option<Wedges>,
    /// Per wedge, how far (texels) its UV has moved from where its chart
    /// showed it, summed over the seam crossings it went through.
    wedge_texels: Vec<f32>,
    /// Per part, texels per UV unit (its base-colour texture's larger side).
    texels: Vec<f32>,
    /// Per vertex, how far (texels) the UV seams through it have moved from
    /// the input's, summed over the collapses that moved them.
    seam_texels: Vec<f32>,
    /// Per part, texels per unit of length over the whole part (its
    /// texels per UV unit times √(UV area / area)): the density of a
    /// triangle whose UVs are degenerate is not its own.
    part_density: Vec<f32>,
    tris: Vec<[u32; 3]>,
    tri_part: Vec<u32>,
    tri_alive: Vec<bool>,
    vtris: Vec<Vec<u32>>,
    v_alive: Vec<bool>,
    constrained: Vec<bool>,
    /// On a border of the mesh itself (see [`border_vertices`]).
    border: Vec<bool>,
    quadric: Vec<Quadric>,
    queue: CollapseQueue<Entry>,
    deferred: Vec<(u32, u32)>,
    collapsed_since_retry: bool,
    /// Edges a [`Veto`] refused: out of the queue until
    /// [`EdgeCollapser::readmit_vetoed`] (a raised limit).
    vetoed: Vec<(u32, u32)>,
    /// Per-vertex stamps for neighbourhood tests without allocation.
    mark: std::cell::RefCell<(Vec<u32>, u32)>,
    alive_triangles: usize,
    /// Collapses performed since the input.
    collapses: usize,
    opts: CollapseOptions,
    cost: std::sync::Arc<StarCostFn>,
    /// A cheap lower bound of `cost` to queue candidates by: the full cost is
    /// computed only when one reaches the front, and it is queued again if
    /// that is more (the order stays the full cost's, §5.2 greedy).
    lower_bound: Option<fn(&Candidate) -> f64>,
}

/// Prefetches the `lines` cache lines from `x` on (a hint: no effect on results).
#[inline]
fn prefetch<T>(x: &T, lines: usize) {
    #[cfg(target_arch = "x86_64")]
    for k in 0..lines {
        let p = (x as *const T).cast::<i8>().wrapping_add(64 * k);
        // SAFETY: a prefetch never faults, whatever the address.
        unsafe { std::arch::x86_64::_mm_prefetch::<{ std::arch::x86_64::_MM_HINT_T0 }>(p) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (x, lines);
}

/// Merge-tree paper eq. 3: 4√3·area/(l0²+l1²+l2²), 0 for a degenerate
/// triangle and 1 for an equilateral one.
pub(crate) fn quality(p: [Vec3; 3]) -> f32 {
    let l2 =
        p[0].distance_squared(p[1]) + p[1].distance_squared(p[2]) + p[2].distance_squared(p[0]);
    if l2 <= 0.0 {
        return 0.0;
    }
    4.0 * 3f32.sqrt() * 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length() / l2
}

/// The fold and sliver guards for one triangle moving from `old` to `new`: it
/// neither degenerates, nor turns past `min_normal_cos`, nor becomes a sliver
/// below `min_quality` (unless it already was one).
pub(crate) fn triangle_change_allowed(
    old: [Vec3; 3],
    new: [Vec3; 3],
    opts: &CollapseOptions,
) -> bool {
    let n0 = (old[1] - old[0]).cross(old[2] - old[0]);
    let n1 = (new[1] - new[0]).cross(new[2] - new[0]);
    let (l0, l1) = (n0.length(), n1.length());
    if l1 <= f32::MIN_POSITIVE || n0.dot(n1) < opts.min_normal_cos * l0 * l1 {
        return false;
    }
    if opts.min_quality > 0.0 {
        let q1 = quality(new);
        if q1 < opts.min_quality && q1 < quality(old) {
            return false;
        }
    }
    true
}

/// The placement-independent rules for collapsing edge (a, b), with `shared`
/// triangles on it, over per-vertex triangle lists `vtris`: the link condition (the common
/// neighbours of a and b are exactly the vertices opposite the edge), no
/// tetrahedron folding into duplicate triangles, and at least one triangle
/// left around the new vertex (else a whole tiny component would vanish).
pub(crate) fn link_condition(
    vtris: &[Vec<u32>],
    tris: &[[u32; 3]],
    mark: &mut Vec<u32>,
    stamp: &mut u32,
    [a, b]: [u32; 2],
    shared: usize,
) -> bool {
    if shared == 0 || vtris[a as usize].len() + vtris[b as usize].len() <= 2 * shared {
        return false;
    }
    if mark.len() < vtris.len() {
        mark.resize(vtris.len(), 0);
    }
    // Stamps s (neighbour of a) and s + 1 (already counted as common).
    *stamp = stamp.wrapping_add(2);
    if *stamp < 2 {
        mark.fill(0);
        *stamp = 2;
    }
    let s = *stamp;
    for t in &vtris[a as usize] {
        for w in tris[*t as usize] {
            if w != a {
                mark[w as usize] = s;
            }
        }
    }
    let mut common = 0;
    let mut opposite = [u32::MAX; 2];
    for t in &vtris[b as usize] {
        let tri = tris[*t as usize];
        for w in tri {
            if w != b && mark[w as usize] == s {
                mark[w as usize] = s + 1;
                common += 1;
            }
        }
        if tri.contains(&a) && shared <= 2 {
            let o = tri
                .iter()
                .copied()
                .find(|w| *w != a && *w != b)
                .unwrap_or(u32::MAX);
            opposite[usize::from(opposite[0] != u32::MAX)] = o;
        }
    }
    if common != shared {
        return false;
    }
    // Tetrahedron: (a, o0, o1) and (b, o0, o1) would become one triangle twice.
    let [o0, o1] = opposite;
    let has_face = |v: u32| {
        vtris[v as usize]
            .iter()
            .any(|t| tris[*t as usize].contains(&o0) && tris[*t as usize].contains(&o1))
    };
    !(shared == 2 && o1 != u32::MAX && has_face(a) && has_face(b))
}

/// Whether corner `c` faces a border, part-seam or attribute-seam edge (or a
/// non-manifold one, which the corner table leaves unpaired).
pub(crate) fn constrained_corner(
    mesh: &TriMesh,
    adj: &Adjacency,
    tri_part: &[u32],
    c: usize,
) -> bool {
    let o = adj.opposite[c];
    if o == crate::geom::adjacency::NONE || tri_part[o as usize / 3] != tri_part[c / 3] {
        return true;
    }
    let Some(w) = &mesh.wedges else {
        return false;
    };
    let (t, u) = (c / 3, o as usize / 3);
    let wedge_at = |t: usize, v: u32| {
        let k = mesh.triangles[t].iter().position(|x| *x == v);
        k.map(|k| w.corners[t][k])
    };
    let tri = mesh.triangles[t];
    [tri[(c + 1) % 3], tri[(c + 2) % 3]]
        .iter()
        .any(|&v| match (wedge_at(t, v), wedge_at(u, v)) {
            (Some(x), Some(y)) => !w.same_surface(x, y),
            _ => true,
        })
}

/// Vertices on the mesh's own borders (and non-manifold or mis-oriented
/// edges), part and attribute seams left out. An edge between two of them
/// that is no border edge must not collapse: it would pinch the surface (a
/// seam edge may join two border vertices, so moving only along constrained
/// edges is not enough).
pub(crate) fn border_vertices(mesh: &TriMesh, adj: &Adjacency) -> Vec<bool> {
    corner_vertices(mesh, adj, |c| {
        adj.opposite[c] == crate::geom::adjacency::NONE
    })
}

/// Vertices on constrained edges: borders, part seams, non-manifold and
/// mis-oriented edges. They move only along such edges, if at all.
pub(crate) fn constrained_vertices(mesh: &TriMesh, adj: &Adjacency, tri_part: &[u32]) -> Vec<bool> {
    corner_vertices(mesh, adj, |c| constrained_corner(mesh, adj, tri_part, c))
}

/// The vertices of the edges facing the corners `faces` picks, and of every
/// edge not shared by exactly two triangles.
fn corner_vertices(mesh: &TriMesh, adj: &Adjacency, faces: impl Fn(usize) -> bool) -> Vec<bool> {
    let triangles = &mesh.triangles;
    let mut marked = vec![false; mesh.positions.len()];
    for c in 0..adj.opposite.len() {
        if faces(c) {
            let tri = triangles[c / 3];
            marked[tri[(c + 1) % 3] as usize] = true;
            marked[tri[(c + 2) % 3] as usize] = true;
        }
    }
    for (i, e) in adj.edges.iter().enumerate() {
        if adj.edge_valence[i] != 2 {
            marked[e[0] as usize] = true;
            marked[e[1] as usize] = true;
        }
    }
    marked
}

/// Where `p` projects onto the edge from `pa` (0) to `pb` (1): how the
/// collapsed vertex interpolates the ends' attributes.
fn edge_parameter(pa: Vec3, pb: Vec3, p: Vec3) -> f32 {
    let ab = pb - pa;
    if p == pa || ab.length_squared() == 0.0 {
        0.0
    } else if p == pb {
        1.0
    } else {
        ((p - pa).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    }
}

/// The quadric error over the quadric's weight: the mean squared distance of
/// the placement to the planes (area weighted), a lower bound of [`quadric_cost`].
pub fn quadric_mean(cand: &Candidate) -> f64 {
    cand.quadric_error / cand.quadric_weight.max(f64::MIN_POSITIVE)
}

/// The default order, a squared distance: the larger of [`quadric_mean`] and
/// the collapse's two-way deviation ([`EdgeCollapser::deviation_squared`]).
/// The raw area-weighted quadric let small features (a sharp tip, an ear)
/// move far for little cost, and a mean misses how far a tip moves along its
/// ridge or a new edge bridges a groove; the larger of the two follows the
/// largest error, which is what the certificate and the Hausdorff distance
/// measure (the horse at 10%: 1.01e-3 → 1.7e-4, BENCHMARKS.md). Plus the
/// appearance the collapse loses, as a squared length (`appearance`).
pub fn quadric_cost(cand: &Candidate, col: &EdgeCollapser) -> f64 {
    let mean = quadric_mean(cand);
    let floor = mean as f32;
    let moved = col.deviation_squared(cand, floor);
    let geometric = if moved > floor {
        mean.max(moved as f64)
    } else {
        mean
    };
    // What the collapse loses of the appearance, as a length (`appearance`).
    geometric + f64::from(col.appearance_squared(cand))
}

impl EdgeCollapser {
    /// Starts from `mesh` (expected repaired: no degenerate triangles), ordered
    /// by [`quadric_cost`].
    pub fn new(mesh: &TriMesh, opts: CollapseOptions) -> Self {
        Self::build(mesh, opts, Box::new(quadric_cost), Some(quadric_mean))
    }

    /// Starts with a caller-supplied ordering (the hybrid method's, §5.1).
    pub fn with_star_cost(mesh: &TriMesh, opts: CollapseOptions, cost: Box<StarCostFn>) -> Self {
        Self::build(mesh, opts, cost, None)
    }

    fn build(
        mesh: &TriMesh,
        opts: CollapseOptions,
        cost: Box<StarCostFn>,
        lower_bound: Option<fn(&Candidate) -> f64>,
    ) -> Self {
        let nv = mesh.positions.len();
        let nt = mesh.triangles.len();
        let mut vtris = vec![Vec::new(); nv];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for v in tri {
                vtris[*v as usize].push(t as u32);
            }
        }
        let tri_part: Vec<u32> = (0..nt).map(|t| mesh.part(t)).collect();
        let mut quadric = vec![Quadric::default(); nv];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let [a, b, c] = mesh.triangle(t);
            let n = (b - a).cross(c - a);
            let area = 0.5 * n.length();
            if area > 0.0 {
                let q = Quadric::plane(a, n.normalize(), area as f64);
                for v in tri {
                    quadric[*v as usize].add(&q);
                }
            }
        }
        // Border and seam edges get planes that keep them in place.
        let adj = Adjacency::new(&mesh.triangles);
        let constrained = match opts.free_seams {
            true => border_vertices(mesh, &adj),
            false => constrained_vertices(mesh, &adj, &tri_part),
        };
        // (Free seams keep their planes: they order and place, not forbid.)
        for c in 0..adj.opposite.len() {
            if !constrained_corner(mesh, &adj, &tri_part, c) {
                continue;
            }
            let t = c / 3;
            let tri = mesh.triangles[t];
            let (u, w) = (tri[(c + 1) % 3], tri[(c + 2) % 3]);
            // A plane through the edge, perpendicular to the face, keeps it in place.
            let [a, b, cc] = mesh.triangle(t);
            let face_n = (b - a).cross(cc - a).normalize_or_zero();
            let (pu, pw) = (mesh.positions[u as usize], mesh.positions[w as usize]);
            let e = pw - pu;
            let n = e.cross(face_n).normalize_or_zero();
            if n != Vec3::ZERO {
                let q = Quadric::plane(pu, n, BORDER_WEIGHT * e.length_squared() as f64);
                quadric[u as usize].add(&q);
                quadric[w as usize].add(&q);
            }
        }
        let parts = tri_part.iter().max().map_or(0, |p| *p as usize + 1);
        let texels: Vec<f32> = (0..parts as u32)
            .map(|p| {
                mesh.materials
                    .as_ref()
                    .map_or(UNTEXTURED_TEXELS, |m| m.texels_per_uv(p))
            })
            .collect();
        let mut areas = vec![(0.0f64, 0.0f64); parts];
        if let Some(w) = &mesh.wedges
            && let Some(uvs) = &w.uvs
        {
            for (t, corners) in w.corners.iter().enumerate() {
                let x = mesh.triangle(t);
                let u = corners.map(|c| uvs[c as usize]);
                let a = &mut areas[tri_part[t] as usize];
                a.0 += f64::from((x[1] - x[0]).cross(x[2] - x[0]).length());
                a.1 += f64::from((u[1] - u[0]).perp_dot(u[2] - u[0]).abs());
            }
        }
        let part_density = areas
            .iter()
            .zip(&texels)
            .map(|((area, area_uv), texels)| match *area > 0.0 {
                true => texels * (area_uv / area).sqrt() as f32,
                false => 0.0,
            })
            .collect();
        let mut s = EdgeCollapser {
            pos: mesh.positions.clone(),
            normals: mesh.normals.clone(),
            colors: mesh.colors.clone(),
            materials: mesh.materials.clone(),
            wedges: mesh.wedges.clone(),
            wedge_texels: vec![0.0; mesh.wedges.as_ref().map_or(0, Wedges::len)],
            texels,
            part_density,
            seam_texels: vec![0.0; nv],
            uvs: mesh.uvs.clone(),
            payload: mesh.payload.clone(),
            tris: mesh.triangles.clone(),
            tri_part,
            tri_alive: vec![true; nt],
            vtris,
            v_alive: vec![true; nv],
            constrained,
            border: border_vertices(mesh, &adj),
            quadric,
            queue: CollapseQueue::with_capacity(adj.edges.len()),
            deferred: Vec::new(),
            collapsed_since_retry: false,
            vetoed: Vec::new(),
            mark: std::cell::RefCell::new((vec![0; nv], 0)),
            alive_triangles: nt,
            collapses: 0,
            opts,
            cost: cost.into(),
            lower_bound,
        };
        for e in &adj.edges {
            s.push(e[0], e[1]);
        }
        s
    }

    pub fn triangle_count(&self) -> usize {
        self.alive_triangles
    }

    /// Collapses performed since the input.
    pub fn collapses(&self) -> usize {
        self.collapses
    }

    pub fn position(&self, v: u32) -> Vec3 {
        self.pos[v as usize]
    }

    pub fn triangle(&self, t: u32) -> [u32; 3] {
        self.tris[t as usize]
    }

    pub fn triangle_positions(&self, t: u32) -> [Vec3; 3] {
        self.tris[t as usize].map(|v| self.pos[v as usize])
    }

    /// Vertices ever created (dead ones included; ids never change).
    pub fn vertex_count(&self) -> usize {
        self.pos.len()
    }

    /// Triangles ever created (dead ones included; ids never change).
    pub fn triangle_total(&self) -> usize {
        self.tris.len()
    }

    pub fn color(&self, v: u32) -> Option<Vec3> {
        self.colors.as_ref().map(|c| c[v as usize])
    }

    pub fn normal(&self, v: u32) -> Option<Vec3> {
        self.normals.as_ref().map(|n| n[v as usize])
    }

    pub fn uv(&self, v: u32) -> Option<Vec2> {
        self.uvs.as_ref().map(|u| u[v as usize])
    }

    /// The part of triangle `t` (collapses never join parts).
    pub fn triangle_part(&self, t: u32) -> u32 {
        self.tri_part[t as usize]
    }

    /// The wedges, with the corners of every triangle ever made (ids never change).
    pub fn wedges(&self) -> Option<&Wedges> {
        self.wedges.as_ref()
    }

    /// The input's materials, one per part.
    pub fn materials(&self) -> Option<&Materials> {
        self.materials.as_ref()
    }

    /// The triangles a collapse of `edge` removes (every triangle around either
    /// end), ascending.
    pub fn star(&self, edge: [u32; 2]) -> Vec<u32> {
        let mut s = Vec::new();
        self.star_into(edge, &mut s);
        s.sort_unstable();
        s
    }

    /// The triangles of [`EdgeCollapser::star`] into `out`, each once, in no
    /// particular order: a cost function runs about a dozen times per
    /// collapse, so it reuses its buffer.
    pub fn star_into(&self, edge: [u32; 2], out: &mut Vec<u32>) {
        let [a, b] = edge;
        out.clear();
        out.extend_from_slice(&self.vtris[a as usize]);
        out.extend(
            self.vtris[b as usize]
                .iter()
                .copied()
                .filter(|t| !self.tris[*t as usize].contains(&a)),
        );
    }

    /// Ids of the triangles alive now.
    pub fn alive_triangles(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.tris.len() as u32).filter(|t| self.tri_alive[*t as usize])
    }

    fn push(&mut self, a: u32, b: u32) {
        if let Ok((cand, _)) = self.best_candidate(a, b, false) {
            let cost = match self.lower_bound {
                Some(lower) => lower(&cand),
                None => (self.cost)(&cand, self),
            };
            if cost.is_finite() {
                self.queue.push(Entry { cost, a, b });
            }
        }
    }

    /// Asks for what a candidate at `v` reads. A collapse's neighbours lie
    /// scattered over the arrays (new vertices are appended in cost order):
    /// asked for together, their cache misses overlap instead of queueing.
    fn prefetch_vertex(&self, v: u32) {
        let v = v as usize;
        prefetch(&self.quadric[v], 2);
        prefetch(&self.pos[v], 1);
        prefetch(&self.constrained[v], 1);
    }

    /// Triangles containing both a and b.
    fn shared(&self, a: u32, b: u32) -> impl Iterator<Item = u32> + '_ {
        self.vtris[a as usize]
            .iter()
            .copied()
            .filter(move |t| self.tris[*t as usize].contains(&b))
    }

    fn neighbours(&self, v: u32, out: &mut Vec<u32>) {
        out.clear();
        for t in &self.vtris[v as usize] {
            out.extend(self.tris[*t as usize].iter().copied().filter(|w| *w != v));
        }
        out.sort_unstable();
        out.dedup();
    }

    /// Edge on a border or seam: not exactly two triangles of one part share
    /// it, or their corners hold different wedges at either end.
    fn is_constrained_edge(&self, a: u32, b: u32) -> bool {
        let mut shared = self.shared(a, b);
        match (shared.next(), shared.next(), shared.next()) {
            (Some(_), Some(_), None) if self.opts.free_seams => false,
            (Some(t0), Some(t1), None) => {
                self.tri_part[t0 as usize] != self.tri_part[t1 as usize]
                    || self.wedges.as_ref().is_some_and(|w| {
                        [a, b].iter().any(|&v| {
                            !w.same_surface(self.wedge_at(w, t0, v), self.wedge_at(w, t1, v))
                        })
                    })
            }
            _ => true,
        }
    }

    /// The wedge of triangle `t`'s corner at vertex `v`.
    fn wedge_at(&self, w: &Wedges, t: u32, v: u32) -> u32 {
        let tri = self.tris[t as usize];
        let k = tri.iter().position(|x| *x == v).unwrap_or(0);
        w.corners[t as usize][k]
    }

    /// The wedge pairs (at a, at b) across the triangles on edge (a, b); more
    /// than four (a non-manifold fan) gives `None`.
    fn wedge_pairs(&self, w: &Wedges, a: u32, b: u32) -> Option<([(u32, u32); 4], usize)> {
        let mut pairs = [(u32::MAX, u32::MAX); 4];
        let mut n = 0;
        for t in self.shared(a, b) {
            *pairs.get_mut(n)? = (self.wedge_at(w, t, a), self.wedge_at(w, t, b));
            n += 1;
        }
        Some((pairs, n))
    }

    /// Whether `a`'s corners can slide towards `b`: each of its surfaces
    /// (UV, colour) meets exactly one of b's across the edge, so it knows what
    /// to interpolate with. Where one does not (three seams meet at `a`, or a seam ends at
    /// `a` while the edge's sides differ at `b`), `a` must stay put.
    fn wedges_follow(&self, w: &Wedges, a: u32, b: u32) -> bool {
        let Some((pairs, n)) = self.wedge_pairs(w, a, b) else {
            return false;
        };
        let pairs = &pairs[..n];
        let unique = |wa: u32| {
            let mut partners = pairs
                .iter()
                .filter(|p| w.same_surface(p.0, wa))
                .map(|p| p.1);
            partners
                .next()
                .is_some_and(|first| partners.all(|p| w.same_surface(p, first)))
        };
        self.vtris[a as usize]
            .iter()
            .all(|&t| unique(self.wedge_at(w, t, a)))
    }

    /// The partner of wedge `old` at the edge's end `side` (0: a, 1: b)
    /// among the edge's wedge `pairs`: its own pair's other end first, else
    /// the other end's one wedge of the same surface; `None` when there is
    /// none or several (a seam ends or meets others here).
    fn partner(w: &Wedges, pairs: &[(u32, u32)], side: usize, old: u32) -> Option<u32> {
        let ours = |p: &(u32, u32)| if side == 0 { p.0 } else { p.1 };
        let theirs = |p: &(u32, u32)| if side == 0 { p.1 } else { p.0 };
        if let Some(p) = pairs.iter().find(|p| ours(p) == old) {
            return Some(theirs(p));
        }
        let mut same = pairs.iter().filter(|p| w.same_surface(ours(p), old));
        let first = same.next();
        first
            .filter(|f| same.all(|p| w.same_surface(theirs(p), theirs(f))))
            .map(theirs)
    }

    /// Where wedge `old` of `end` lands when `end` moves to `p` with no
    /// partner to take its UV from (a seam crossing): the UV its own chart
    /// shows nearest to `p` (the closest point of `end`'s triangles on the
    /// wedge's side), and how far from `p` that is in texels of that
    /// triangle's texture density. The distance is Cohen, Olano and
    /// Manocha's texture deviation ("Appearance-preserving simplification",
    /// 1998): how far a texel moves on the surface. Infinite where the
    /// wedge has no UV, or where its colour or payload is not the other
    /// end's (only UV seams are crossed).
    fn chart_uv(&self, w: &Wedges, end: u32, old: u32, p: Vec3) -> (Vec2, f32) {
        let Some(uvs) = &w.uvs else {
            return (Vec2::ZERO, f32::INFINITY);
        };
        let mut best = (Vec2::ZERO, f32::INFINITY, f32::INFINITY);
        for &t in &self.vtris[end as usize] {
            let k = self.tris[t as usize]
                .iter()
                .position(|x| *x == end)
                .unwrap_or(0);
            if !w.same_surface(w.corners[t as usize][k], old) {
                continue;
            }
            let x = self.triangle_positions(t);
            let q = closest_point_on_triangle(p, x[0], x[1], x[2]);
            let d = q.distance(p);
            if d >= best.1 {
                continue;
            }
            let u = w.corners[t as usize].map(|c| uvs[c as usize]);
            let bary = crate::distance::barycentric(q, x[0], x[1], x[2]);
            let uv = u[0] * bary[0] + u[1] * bary[1] + u[2] * bary[2];
            let area = 0.5 * (x[1] - x[0]).cross(x[2] - x[0]).length();
            let area_uv = 0.5 * (u[1] - u[0]).perp_dot(u[2] - u[0]).abs();
            let part = self.tri_part[t as usize] as usize;
            let own = self.texels[part] * (area_uv / area).sqrt();
            let density = own.max(self.part_density[part]);
            // A part whose UVs all coincide has no texel size: its texture
            // moves nowhere without leaving where it was shown.
            let texels = if d > 0.0 && (density.is_nan() || density <= 0.0) {
                f32::INFINITY
            } else {
                d * density
            };
            best = (uv, d, texels);
        }
        (
            best.0,
            if best.2.is_nan() {
                f32::INFINITY
            } else {
                best.2
            },
        )
    }

    /// The largest UV deviation (texels, [`EdgeCollapser::chart_uv`], with
    /// what each wedge carried) the collapse of (a, b) to `p` leaves on the
    /// wedges that cross a seam; 0 when none does, infinite when one may not.
    fn crossing_texels(&self, a: u32, b: u32, p: Vec3) -> f32 {
        let Some(w) = &self.wedges else {
            return f32::INFINITY;
        };
        let Some((pairs, n)) = self.wedge_pairs(w, a, b) else {
            return f32::INFINITY;
        };
        let pairs = &pairs[..n];
        let mut worst = 0.0f32;
        for (end, other, side) in [(a, b, 0), (b, a, 1)] {
            if self.pos[end as usize] == p {
                continue;
            }
            for &t in &self.vtris[end as usize] {
                let old = self.wedge_at(w, t, end);
                if Self::partner(w, pairs, side, old).is_some() {
                    continue;
                }
                // Its surface goes on across the edge, but towards several
                // of the other end's (a seam ends here): no one UV is right
                // for every face.
                let ours = |p: &(u32, u32)| if side == 0 { p.0 } else { p.1 };
                if pairs.iter().any(|p| w.same_surface(ours(p), old)) {
                    return f32::INFINITY;
                }
                let continues = self.vtris[other as usize]
                    .iter()
                    .any(|&u| w.same_but_uv(self.wedge_at(w, u, other), old));
                if !continues {
                    return f32::INFINITY;
                }
                let moved = self.chart_uv(w, end, old, p).1;
                worst = worst.max(self.wedge_texels[old as usize] + moved);
            }
        }
        worst
    }

    /// Whether edge (a, b) is a UV or colour seam: its two triangles'
    /// corners show different surfaces at either end.
    fn is_wedge_seam(&self, a: u32, b: u32) -> bool {
        let Some(w) = &self.wedges else {
            return false;
        };
        let mut shared = self.shared(a, b);
        match (shared.next(), shared.next(), shared.next()) {
            (Some(t0), Some(t1), None) => [a, b]
                .iter()
                .any(|&v| !w.same_surface(self.wedge_at(w, t0, v), self.wedge_at(w, t1, v))),
            _ => false,
        }
    }

    /// The texel density (texels per unit of length) around `v`: the
    /// largest of its triangles' (each its own or its part's, whichever is
    /// larger).
    fn density_around(&self, v: u32) -> f32 {
        let (Some(w), Some(uvs)) = (
            &self.wedges,
            self.wedges.as_ref().and_then(|w| w.uvs.as_ref()),
        ) else {
            return 0.0;
        };
        let mut most = 0.0f32;
        for &t in &self.vtris[v as usize] {
            let x = self.triangle_positions(t);
            let u = w.corners[t as usize].map(|c| uvs[c as usize]);
            let area = 0.5 * (x[1] - x[0]).cross(x[2] - x[0]).length();
            let area_uv = 0.5 * (u[1] - u[0]).perp_dot(u[2] - u[0]).abs();
            let part = self.tri_part[t as usize] as usize;
            let own = self.texels[part] * (area_uv / area).sqrt();
            most = most.max(own.max(self.part_density[part]));
        }
        most
    }

    /// How far (texels, with what the ends carried) the collapse of (a, b)
    /// to `p` moves the UV and colour seams through a moved end: the
    /// distance of each moved end from the seam segments that replace its
    /// own (a seam corner cut off shows as its distance from the new
    /// segment; a straight seam slides at no cost), and of `p` from the old
    /// seam when it is on neither end. A seam moved on the surface moves
    /// the boundary of a texture's chart (Cohen et al.'s deviation again);
    /// a seam through untextured parts only (no texel size) may not move.
    fn seam_shift_texels(&self, a: u32, b: u32, p: Vec3) -> f32 {
        let seam = |e: u32, out: &mut Vec<u32>| {
            self.neighbours(e, out);
            out.retain(|&x| x != a && x != b && self.is_wedge_seam(e, x));
        };
        let (mut na, mut nb) = (Vec::new(), Vec::new());
        seam(a, &mut na);
        seam(b, &mut nb);
        let on_seam_ab = self.is_wedge_seam(a, b);
        let segment = |x: Vec3, s0: Vec3, s1: Vec3| closest_point_on_segment(x, s0, s1).distance(x);
        let mut shift = 0.0f32;
        let mut carried = 0.0f32;
        for (e, own) in [(a, &na), (b, &nb)] {
            let pe = self.pos[e as usize];
            if pe == p || own.is_empty() && !on_seam_ab {
                continue;
            }
            carried = carried.max(self.seam_texels[e as usize]);
            let new = na
                .iter()
                .chain(&nb)
                .map(|&x| segment(pe, p, self.pos[x as usize]))
                .fold(f32::INFINITY, f32::min);
            shift = shift.max(if new.is_finite() { new } else { pe.distance(p) });
        }
        if p != self.pos[a as usize] && p != self.pos[b as usize] {
            let old = [(a, &na), (b, &nb)]
                .iter()
                .flat_map(|(e, own)| own.iter().map(move |&x| (*e, x)))
                .chain(on_seam_ab.then_some((a, b)))
                .map(|(e, x)| segment(p, self.pos[e as usize], self.pos[x as usize]))
                .fold(f32::INFINITY, f32::min);
            if old.is_finite() {
                shift = shift.max(old);
            }
        }
        if shift <= 0.0 {
            return carried;
        }
        let density = self.density_around(a).max(self.density_around(b));
        match density > 0.0 {
            true => carried + shift * density,
            false => f32::INFINITY,
        }
    }

    /// Placements allowed by the border rules, best quadric error first; with
    /// `check`, only legal ones. Returns the best and how many triangles it
    /// removes, or the rule that forbids every placement.
    fn best_candidate(&self, a: u32, b: u32, check: bool) -> Result<(Candidate, usize), Blocker> {
        let (ca, cb) = (self.constrained[a as usize], self.constrained[b as usize]);
        let (pa, pb) = (self.pos[a as usize], self.pos[b as usize]);
        let q = Quadric::sum(&self.quadric[a as usize], &self.quadric[b as usize]);
        let mut places = [(f64::INFINITY, Vec3::ZERO); 4];
        let mut n = 0;
        let mut add = |p: Vec3| {
            places[n] = (q.error(p), p);
            n += 1;
        };
        // A seam crossing's placements: each end whose moved UVs stay
        // within the tolerance.
        let cross = |add: &mut dyn FnMut(Vec3)| {
            for p in [pa, pb] {
                if self.opts.uv_tolerance > 0.0
                    && self.crossing_texels(a, b, p) <= self.opts.uv_tolerance
                {
                    add(p);
                }
            }
        };
        match (ca, cb) {
            (true, true)
                if self.opts.lock_borders
                    || self.border[a as usize]
                        && self.border[b as usize]
                        && self.shared(a, b).count() == 2 =>
            {
                return Err(Blocker::Seams);
            }
            // Two seams joined through the surface: only as a crossing.
            (true, true) if !self.is_constrained_edge(a, b) => cross(&mut add),
            (true, false) => add(pa),
            (false, true) => add(pb),
            _ if self.opts.lock_borders && (ca || cb) => return Err(Blocker::Seams),
            // Seam vertices whose wedges cannot follow the edge stay put, or cross.
            (true, true)
                if !self.opts.free_seams
                    && self.wedges.as_ref().is_some_and(|w| {
                        !self.wedges_follow(w, a, b) || !self.wedges_follow(w, b, a)
                    }) =>
            {
                let w = self.wedges.as_ref().ok_or(Blocker::Seams)?;
                match (self.wedges_follow(w, a, b), self.wedges_follow(w, b, a)) {
                    (false, false) => {}
                    (false, true) => add(pa),
                    _ => add(pb),
                }
                cross(&mut add);
            }
            _ => {
                // The optimum only when it stays near the edge (ill-conditioned otherwise).
                let len = pa.distance(pb);
                if let Some(p) = q
                    .optimum()
                    .filter(|p| p.distance(pa) <= 2.0 * len && p.distance(pb) <= 2.0 * len)
                {
                    add(p);
                }
                add(pa);
                add(pb);
                add((pa + pb) * 0.5);
            }
        }
        // Seams move only within the tolerance (a straight one slides).
        if self.wedges.is_some() && !self.opts.free_seams && (ca || cb) {
            let mut kept = 0;
            for k in 0..n {
                if self.seam_shift_texels(a, b, places[k].1) <= self.opts.uv_tolerance + 1e-3 {
                    places[kept] = places[k];
                    kept += 1;
                }
            }
            n = kept;
        }
        if n == 0 {
            return Err(Blocker::Seams);
        }
        let places = &mut places[..n];
        places.sort_by(|x, y| x.0.total_cmp(&y.0));
        let removed = self.shared(a, b).count();
        if check {
            self.topology_allows(a, b, removed)?;
        }
        let &(err, p) = places
            .iter()
            .find(|(_, p)| !check || self.geometry_allows(a, b, *p))
            .ok_or(Blocker::Guards)?;
        Ok((
            Candidate {
                edge: [a, b],
                position: p,
                quadric_error: err,
                quadric_weight: q.weight(),
                triangles_removed: removed,
            },
            removed,
        ))
    }

    fn topology_allows(&self, a: u32, b: u32, shared: usize) -> Result<(), Blocker> {
        // Bone boundaries: vertices no joint moves together stay apart.
        if self
            .payload
            .as_ref()
            .is_some_and(|p| !p.share_joint(a as usize, b as usize))
        {
            return Err(Blocker::Bones);
        }
        let mut guard = self.mark.borrow_mut();
        let (mark, stamp) = &mut *guard;
        link_condition(&self.vtris, &self.tris, mark, stamp, [a, b], shared)
            .then_some(())
            .ok_or(Blocker::Topology)
    }

    /// No triangle flips or folds past the fold guard, and the sliver guard holds.
    fn geometry_allows(&self, a: u32, b: u32, p: Vec3) -> bool {
        for &v in &[a, b] {
            for &t in &self.vtris[v as usize] {
                let tri = self.tris[t as usize];
                if tri.contains(&a) && tri.contains(&b) {
                    continue;
                }
                let old = tri.map(|w| self.pos[w as usize]);
                let new = tri.map(|w| {
                    if w == a || w == b {
                        p
                    } else {
                        self.pos[w as usize]
                    }
                });
                if !triangle_change_allowed(old, new, &self.opts) {
                    return false;
                }
            }
        }
        true
    }

    /// The larger of `floor` and a squared deviation of the collapse of `cand`
    /// both ways: the collapsed edge's endpoints against the triangles it
    /// would make, and the midpoints of the new vertex's edges against the
    /// triangles it removes. Each scan starts with the nearest fan and stops
    /// as soon as it is below what is already known, so only the points that
    /// raise the result cost a full scan. (The hybrid queue measures more
    /// points with no floor: its cost is the deviation itself, §5.1.)
    pub fn deviation_squared(&self, cand: &Candidate, floor: f32) -> f32 {
        let [a, b] = cand.edge;
        let moved = |w: u32| {
            if w == a || w == b {
                cand.position
            } else {
                self.pos[w as usize]
            }
        };
        let mut worst = floor;
        // x against the triangles of the fans of `first` then `second`, moved or not.
        let mut scan = |x: Vec3, first: u32, second: u32, after: bool| {
            let mut near = f32::INFINITY;
            let fans = [first, second].map(|v| self.vtris[v as usize].as_slice());
            for &t in fans[0].iter().chain(fans[1]) {
                let tri = self.tris[t as usize];
                if after && tri.contains(&a) && tri.contains(&b) {
                    continue;
                }
                let [p, q, r] = if after {
                    tri.map(moved)
                } else {
                    tri.map(|w| self.pos[w as usize])
                };
                near = near.min(closest_point_on_triangle(x, p, q, r).distance_squared(x));
                if near <= worst {
                    return;
                }
            }
            worst = near;
        };
        for (end, other) in [(a, b), (b, a)] {
            scan(self.pos[end as usize], end, other, true);
        }
        // Each spoke once: in the new triangle where it leaves the new vertex.
        for (end, other) in [(a, b), (b, a)] {
            for &t in &self.vtris[end as usize] {
                let tri = self.tris[t as usize];
                if tri.contains(&other) {
                    continue;
                }
                let k = tri.iter().position(|w| *w == end).unwrap_or(0);
                let m = (cand.position + self.pos[tri[(k + 1) % 3] as usize]) * 0.5;
                scan(m, end, other, false);
            }
        }
        worst
    }

    /// Performs the next legal collapse in cost order; `None` when none is left.
    pub fn step(&mut self) -> Option<Collapse> {
        self.step_vetted(None)
    }

    /// [`EdgeCollapser::step`] with only the collapses `veto` allows (and
    /// tells of): a refused edge leaves the queue, the next one is tried.
    pub fn step_vetted(&mut self, mut veto: Option<&mut (dyn Veto + '_)>) -> Option<Collapse> {
        loop {
            let alive = &self.v_alive;
            let Some(e) = self
                .queue
                .pop(|e| alive[e.a as usize] && alive[e.b as usize])
            else {
                // Retry edges that were illegal when they came up, if collapses
                // since then may have changed their neighbourhood.
                if !self.collapsed_since_retry {
                    return None;
                }
                self.collapsed_since_retry = false;
                for (a, b) in std::mem::take(&mut self.deferred) {
                    if self.v_alive[a as usize] && self.v_alive[b as usize] {
                        self.push(a, b);
                    }
                }
                continue;
            };
            if !self.v_alive[e.a as usize] || !self.v_alive[e.b as usize] {
                continue;
            }
            match self.best_candidate(e.a, e.b, true) {
                Ok((cand, _)) => {
                    // The queued cost was for the best placement, legal or not,
                    // or a lower bound: if the real cost is above what is queued
                    // next, the edge waits its real turn.
                    let cost = (self.cost)(&cand, self);
                    // An infinite cost forbids the collapse, even as the last
                    // edge queued (as `push` never queues one).
                    if !cost.is_finite() {
                        continue;
                    }
                    let alive = &self.v_alive;
                    let next = self
                        .queue
                        .peek(|e| alive[e.a as usize] && alive[e.b as usize])
                        .map_or(f64::INFINITY, |n| n.cost);
                    if cost > next * (1.0 + 1e-9) + f64::MIN_POSITIVE {
                        self.queue.push(Entry { cost, ..e });
                        continue;
                    }
                    if let Some(v) = veto.as_deref_mut()
                        && !v.allows(&cand, self)
                    {
                        self.vetoed.push((e.a, e.b));
                        continue;
                    }
                    let c = self.collapse(&cand, cost);
                    if let Some(v) = veto {
                        v.collapsed(self, &c);
                    }
                    return Some(c);
                }
                Err(_) => self.deferred.push((e.a, e.b)),
            }
        }
    }

    /// Collapses until at most `target` triangles remain or nothing can collapse;
    /// `on_step` sees every collapse and may stop the run by returning false.
    pub fn run(&mut self, target: usize, on_step: impl FnMut(&Self, &Collapse) -> bool) {
        self.run_vetted(target, None, on_step);
    }

    /// [`EdgeCollapser::run`] with only the collapses `veto` allows.
    pub fn run_vetted(
        &mut self,
        target: usize,
        mut veto: Option<&mut (dyn Veto + '_)>,
        mut on_step: impl FnMut(&Self, &Collapse) -> bool,
    ) {
        while self.alive_triangles > target {
            let Some(c) = self.step_vetted(veto.as_deref_mut()) else {
                break;
            };
            if !on_step(self, &c) {
                break;
            }
        }
    }

    /// Every edge left and the rule that keeps it, counted (an edge that
    /// only a veto or an infinite cost keeps is not counted): what stops a
    /// run short of its count, most common first.
    pub fn blockers(&self) -> Vec<(Blocker, usize)> {
        let mut counts: Vec<(Blocker, usize)> = Vec::new();
        let mut nbrs = Vec::new();
        for a in (0..self.pos.len() as u32).filter(|v| self.v_alive[*v as usize]) {
            self.neighbours(a, &mut nbrs);
            for &b in nbrs.iter().filter(|b| **b > a) {
                if let Err(blocker) = self.best_candidate(a, b, true) {
                    match counts.iter_mut().find(|c| c.0 == blocker) {
                        Some(c) => c.1 += 1,
                        None => counts.push((blocker, 1)),
                    }
                }
            }
        }
        counts.sort_by(|x, y| y.1.cmp(&x.1).then(x.0.cmp(&y.0)));
        counts
    }

    /// Queues the edges a veto refused again (their veto has changed: a
    /// raised limit), each still alive.
    pub fn readmit_vetoed(&mut self) {
        for (a, b) in std::mem::take(&mut self.vetoed) {
            if self.v_alive[a as usize] && self.v_alive[b as usize] {
                self.push(a, b);
            }
        }
    }

    fn collapse(&mut self, cand: &Candidate, cost: f64) -> Collapse {
        let [a, b] = cand.edge;
        let p = cand.position;
        let c = self.pos.len() as u32;
        self.collapsed_since_retry = true;
        self.collapses += 1;
        let s = edge_parameter(self.pos[a as usize], self.pos[b as usize], p);
        let seam = match self.wedges.is_some()
            && (self.constrained[a as usize] || self.constrained[b as usize])
        {
            true => self.seam_shift_texels(a, b, p),
            false => self.seam_texels[a as usize].max(self.seam_texels[b as usize]),
        };
        self.seam_texels.push(seam);
        let mut wedges = self.wedges.take();
        let mut dev = std::mem::take(&mut self.wedge_texels);
        let mut wedge_map = Vec::new();
        if let Some(w) = &mut wedges {
            self.map_wedges(w, &mut dev, [a, b], (c, p), s, &mut wedge_map);
        }
        self.wedge_texels = dev;
        self.pos.push(p);
        if let Some(n) = &mut self.normals {
            n.push(n[a as usize].lerp(n[b as usize], s).normalize_or_zero());
        }
        if let Some(col) = &mut self.colors {
            col.push(col[a as usize].lerp(col[b as usize], s));
        }
        if let Some(uv) = &mut self.uvs {
            uv.push(uv[a as usize].lerp(uv[b as usize], s));
        }
        if let Some(pl) = &mut self.payload {
            pl.push_lerp(a as usize, b as usize, s);
        }
        let q = Quadric::sum(&self.quadric[a as usize], &self.quadric[b as usize]);
        self.quadric.push(q);
        self.constrained
            .push(self.constrained[a as usize] || self.constrained[b as usize]);
        self.border
            .push(self.border[a as usize] || self.border[b as usize]);
        self.v_alive.push(true);
        self.v_alive[a as usize] = false;
        self.v_alive[b as usize] = false;

        let removed = self.star([a, b]);
        let mut added = Vec::with_capacity(removed.len());
        let mut star = Vec::with_capacity(removed.len());
        for &t in &removed {
            let tri = self.tris[t as usize];
            self.tri_alive[t as usize] = false;
            for w in tri {
                if w != a && w != b {
                    self.vtris[w as usize].retain(|x| *x != t);
                }
            }
            if tri.contains(&a) && tri.contains(&b) {
                continue;
            }
            let id = self.tris.len() as u32;
            let new = tri.map(|w| if w == a || w == b { c } else { w });
            if let Some(w) = &mut wedges {
                let k = tri.iter().position(|v| *v == a || *v == b).unwrap_or(0);
                let mut corners = w.corners[t as usize];
                let old = corners[k];
                corners[k] = wedge_map
                    .iter()
                    .find(|(o, _)| *o == old)
                    .map_or(old, |m| m.1);
                w.corners.push(corners);
            }
            self.tris.push(new);
            self.tri_part.push(self.tri_part[t as usize]);
            self.tri_alive.push(true);
            for w in new {
                if w != c {
                    self.vtris[w as usize].push(id);
                }
            }
            star.push(id);
            added.push(id);
        }
        self.wedges = wedges;
        self.alive_triangles -= removed.len() - added.len();
        self.vtris[a as usize] = Vec::new();
        self.vtris[b as usize] = Vec::new();
        self.vtris.push(star);
        let mut nbrs = Vec::new();
        self.neighbours(c, &mut nbrs);
        for n in &nbrs {
            self.prefetch_vertex(*n);
        }
        for n in nbrs {
            self.push(c, n);
        }
        Collapse {
            edge: [a, b],
            vertex: c,
            position: p,
            removed,
            added,
            cost,
        }
    }

    /// Each wedge at `a` or `b` (old → new, into `map`) becomes one at the new
    /// vertex `c`: interpolated by `s` with its partner across the edge (the
    /// other end's wedge of the same surface), or kept where it has none (a
    /// surface without one is left at its end by `best_candidate`; a normal
    /// without one is kept as it is).
    /// New wedges with equal attributes are one: a seam that ended here closes.
    #[allow(clippy::too_many_arguments)]
    fn map_wedges(
        &self,
        w: &mut Wedges,
        dev: &mut Vec<f32>,
        [a, b]: [u32; 2],
        (c, p): (u32, Vec3),
        s: f32,
        map: &mut Vec<(u32, u32)>,
    ) {
        let (pairs, n) = self
            .wedge_pairs(w, a, b)
            .unwrap_or(([(u32::MAX, u32::MAX); 4], 0));
        let pairs = &pairs[..n];
        let first_new = w.len() as u32;
        for (end, side) in [(a, 0), (b, 1)] {
            for &t in &self.vtris[end as usize] {
                let old = self.wedge_at(w, t, end);
                if map.iter().any(|(o, _)| *o == old) {
                    continue;
                }
                let partner = Self::partner(w, pairs, side, old);
                let (new, texels) = match (partner, side) {
                    (Some(q), 0) => (
                        w.push_lerp(c, old, q, s),
                        dev[old as usize].max(dev[q as usize]),
                    ),
                    (Some(q), _) => (
                        w.push_lerp(c, q, old, s),
                        dev[old as usize].max(dev[q as usize]),
                    ),
                    (None, _) if self.pos[end as usize] == p => {
                        (w.push_lerp(c, old, old, 0.0), dev[old as usize])
                    }
                    (None, _) => {
                        // A crossing: the UV its chart shows where it lands.
                        let (uv, moved) = self.chart_uv(w, end, old, p);
                        let new = w.push_lerp(c, old, old, 0.0);
                        if let Some(u) = &mut w.uvs {
                            u[new as usize] = uv;
                        }
                        (new, dev[old as usize] + moved)
                    }
                };
                let same = (first_new..new).find(|&x| w.same_attributes(x, new));
                let new = match same {
                    Some(x) => {
                        w.pop();
                        dev[x as usize] = dev[x as usize].max(texels);
                        x
                    }
                    None => {
                        dev.push(texels);
                        new
                    }
                };
                map.push((old, new));
            }
        }
    }

    /// Every vertex and triangle ever made, dead ones included (ids as the
    /// collapser's), borrowed.
    pub fn arrays(&self) -> MeshArrays<'_> {
        MeshArrays {
            positions: &self.pos,
            triangles: &self.tris,
            normals: self.normals.as_deref(),
            colors: self.colors.as_deref(),
            uvs: self.uvs.as_deref(),
            parts: Some(&self.tri_part),
            materials: self.materials.as_ref(),
            wedges: self.wedges.as_ref(),
            payload: self.payload.as_ref(),
        }
    }

    /// The current mesh, compacted; also the internal id of each output triangle.
    pub fn mesh(&self) -> (TriMesh, Vec<u32>) {
        let ids: Vec<u32> = self.alive_triangles().collect();
        (self.arrays().gather(ids.iter().copied()), ids)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::builtins::{icosphere, torus};
    use crate::geom::Topology;

    /// A torus whose two halves two joints move: with the skin as payload
    /// no collapse joins the halves' vertices (none weighs both joints),
    /// while the same floats read as no skin are blended across; the
    /// payload's soft float (x) is interpolated with the position.
    #[test]
    fn payload_rides_each_collapse_and_bones_stay_apart() {
        let mut mesh = torus(1.0, 0.35, 48, 24);
        let run = |mesh: &TriMesh| {
            let mut s = EdgeCollapser::new(mesh, CollapseOptions::default());
            s.run(300, |_, _| true);
            s.mesh().0
        };
        let mut payload = Payload::new(3, 2, 2);
        for p in &mesh.positions {
            let left = f32::from(u8::from(p.y >= 0.0));
            payload.values.extend([left, 1.0 - left, p.x]);
        }
        mesh.payload = Some(payload.clone());
        let out = run(&mesh);
        let p = out.payload.as_ref().expect("carried");
        assert_eq!(p.len(), out.positions.len());
        assert!(out.triangles.len() <= 300);
        for (v, pos) in out.positions.iter().enumerate() {
            let x = p.get(v);
            assert!(x[0] == 0.0 || x[1] == 0.0, "vertex {v} weighs both: {x:?}");
            assert!(
                (x[2] - pos.x).abs() < 0.35,
                "x {} carried as {}",
                pos.x,
                x[2]
            );
        }
        payload.weights = 0;
        mesh.payload = Some(payload);
        let out = run(&mesh);
        let p = out.payload.as_ref().unwrap();
        assert!(
            (0..p.len()).any(|v| p.get(v)[0] > 0.0 && p.get(v)[1] > 0.0),
            "without the guard some collapse blends the halves"
        );
    }

    #[test]
    fn collapses_keep_topology_and_report_their_triangles() {
        let mesh = torus(1.0, 0.35, 48, 24);
        let mut s = EdgeCollapser::new(&mesh, CollapseOptions::default());
        let mut steps = 0;
        s.run(200, |s, c| {
            assert!(c.removed.len() > c.added.len());
            assert!(c.added.iter().all(|t| s.triangle(*t).contains(&c.vertex)));
            steps += 1;
            true
        });
        let (out, ids) = s.mesh();
        assert!(out.triangles.len() <= 200 && steps > 0);
        assert_eq!(ids.len(), out.triangles.len());
        let t = Topology::of(&out);
        assert_eq!((t.genus, t.components.len(), t.boundary_loops), (1, 1, 0));
        assert_eq!(t.non_manifold_edges, 0);
        assert_eq!(t.inconsistent_edges, 0);
        assert!(out.normals.is_some() && out.uvs.is_some());
    }

    #[test]
    fn locked_borders_stay_and_parts_stay_apart() {
        // Two parts: a sphere and a torus, glued into one mesh with part ids.
        let mut mesh = icosphere(Vec3::new(3.0, 0.0, 0.0), 1.0, 3);
        mesh.append(&torus(1.0, 0.3, 32, 16));
        let mut s = EdgeCollapser::new(&mesh, CollapseOptions::default());
        s.run(100, |_, _| true);
        let (out, _) = s.mesh();
        let t = Topology::of(&out);
        assert_eq!(t.components.len(), 2);
        assert_eq!(t.genus, 1);
        assert_eq!(out.part_count(), 2);

        // An open grid: with locked borders the border vertices keep their positions.
        let n = 12u32;
        let grid = wavy_grid(n);
        let opts = CollapseOptions {
            lock_borders: true,
            ..Default::default()
        };
        let mut s = EdgeCollapser::new(&grid, opts);
        s.run(0, |_, _| true);
        let (out, _) = s.mesh();
        let border_before = Topology::of(&grid);
        let border_after = Topology::of(&out);
        assert_eq!(border_before.boundary_loops, border_after.boundary_loops);
        let on_border = |p: &Vec3| p.x == 0.0 || p.y == 0.0 || p.x == 1.0 || p.y == 1.0;
        let before = grid.positions.iter().filter(|p| on_border(p)).count();
        let after = out.positions.iter().filter(|p| on_border(p)).count();
        assert_eq!(before, after, "every border vertex kept");
        assert!(out.triangles.len() < grid.triangles.len() / 2);
    }

    /// A hexagonal fan whose centre is raised by `h`: collapsing the centre
    /// onto a rim vertex flattens the tip, so the deviation is the tip's
    /// height (the endpoint against the new star), and 0 when it was flat.
    #[test]
    fn deviation_measures_how_far_a_tip_moves() {
        for h in [0.0f32, 0.3] {
            let mut fan = TriMesh::default();
            fan.positions.push(Vec3::new(0.0, 0.0, h));
            for k in 0..6 {
                let a = k as f32 * std::f32::consts::PI / 3.0;
                fan.positions.push(Vec3::new(a.cos(), a.sin(), 0.0));
            }
            fan.triangles = (0..6u32).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect();
            let s = EdgeCollapser::new(&fan, CollapseOptions::default());
            let cand = Candidate {
                edge: [0, 1],
                position: fan.positions[1],
                quadric_error: 0.0,
                quadric_weight: 1.0,
                triangles_removed: 2,
            };
            let d = s.deviation_squared(&cand, 0.0).sqrt();
            assert!((d - h).abs() < 1e-5, "h {h}: deviation {d}");
            // A floor above the deviation is what comes back.
            assert_eq!(s.deviation_squared(&cand, 1.0), 1.0);
        }
    }

    /// An open (n+1)² grid over the unit square, gently waved: every border
    /// vertex on the mesh's own border.
    pub(crate) fn wavy_grid(n: u32) -> TriMesh {
        height_grid(n, |x, y| 0.05 * (6.0 * x).sin() * (5.0 * y).cos())
    }

    /// An n×n grid over the unit square at heights `z(x, y)`, two
    /// triangles a cell.
    pub(crate) fn height_grid(n: u32, z: impl Fn(f32, f32) -> f32) -> TriMesh {
        let mut grid = TriMesh::default();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
                grid.positions.push(Vec3::new(x, y, z(x, y)));
            }
        }
        for j in 0..n {
            for i in 0..n {
                let v = j * (n + 1) + i;
                grid.triangles.push([v, v + 1, v + n + 2]);
                grid.triangles.push([v, v + n + 2, v + n + 1]);
            }
        }
        grid
    }

    /// A torus read as a textured file stores it: a grid of (n+1) × (m+1)
    /// vertex records, the last row and column repeating the first at u = 1
    /// and v = 1 (a UV seam around each way), welded on load.
    fn seamed_torus(n: u32, m: u32) -> (TriMesh, TriMesh) {
        use crate::geom::{RepairOptions, repair::repair_mesh};
        let mut records = TriMesh::default();
        let mut uvs = Vec::new();
        for i in 0..=n {
            for j in 0..=m {
                let (u, v) = (i as f32 / n as f32, j as f32 / m as f32);
                let (a, b) = (u * std::f32::consts::TAU, v * std::f32::consts::TAU);
                let ring = Vec3::new(a.cos(), a.sin(), 0.0);
                let p = ring * (1.0 + 0.3 * b.cos()) + Vec3::Z * 0.3 * b.sin();
                // Snap the seam's copies onto the first row's bits.
                let (i0, j0) = (i % n, j % m);
                let snap = |k: u32, l: u32| {
                    let (a, b) = (
                        k as f32 / n as f32 * std::f32::consts::TAU,
                        l as f32 / m as f32 * std::f32::consts::TAU,
                    );
                    Vec3::new(a.cos(), a.sin(), 0.0) * (1.0 + 0.3 * b.cos())
                        + Vec3::Z * 0.3 * b.sin()
                };
                records
                    .positions
                    .push(if (i0, j0) != (i, j) { snap(i0, j0) } else { p });
                uvs.push(Vec2::new(u, v));
            }
        }
        for i in 0..n {
            for j in 0..m {
                let at = |i: u32, j: u32| i * (m + 1) + j;
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                records.triangles.extend([[a, b, c], [a, c, d]]);
            }
        }
        records.uvs = Some(uvs);
        let (welded, _) = repair_mesh(records.clone(), &RepairOptions::default());
        (records, welded)
    }

    /// A flat n×n grid on the unit square cut into charts of one atlas,
    /// `chart` giving each cell's UV offset; every chart is mapped by
    /// uv = ½·(x, y) + its offset: 512 texels per unit of length
    /// (untextured: 1024 texels per UV unit).
    fn charted_square(n: u32, chart: impl Fn(u32, u32) -> Vec2) -> (TriMesh, TriMesh) {
        use crate::geom::{RepairOptions, repair::repair_mesh};
        let mut records = TriMesh::default();
        let mut uvs = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let offset = chart(i, j);
                let base = records.positions.len() as u32;
                for (x, y) in [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)] {
                    let (x, y) = (x as f32 / n as f32, y as f32 / n as f32);
                    records.positions.push(Vec3::new(x, y, 0.0));
                    uvs.push(0.5 * Vec2::new(x, y) + offset);
                }
                records
                    .triangles
                    .extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
            }
        }
        records.uvs = Some(uvs);
        let (welded, _) = repair_mesh(records.clone(), &RepairOptions::default());
        (records, welded)
    }

    /// Three charts: the half x < ½, and the right half's bottom and top,
    /// ½ apart in UV; where they meet, at the centre, no collapse along a
    /// seam moves the vertex.
    fn three_chart_square(n: u32) -> (TriMesh, TriMesh) {
        charted_square(n, |i, j| match (2 * i < n, 2 * j < n) {
            (true, _) => Vec2::ZERO,
            (false, true) => Vec2::new(0.5, 0.0),
            (false, false) => Vec2::new(0.0, 0.5),
        })
    }

    /// Only collapses that keep the square (not its corners).
    struct Flat;
    impl Veto for Flat {
        fn allows(&mut self, cand: &Candidate, col: &EdgeCollapser) -> bool {
            col.deviation_squared(cand, 0.0) < 1e-12
        }
        fn collapsed(&mut self, _: &EdgeCollapser, _: &Collapse) {}
    }

    /// Collapses `mesh` as far as [`Flat`] lets it at `uv_tolerance`.
    fn flat_run(mesh: &TriMesh, uv_tolerance: f32) -> EdgeCollapser {
        let opts = CollapseOptions {
            uv_tolerance,
            ..Default::default()
        };
        let mut s = EdgeCollapser::new(mesh, opts);
        s.run_vetted(0, Some(&mut Flat), |_, _| true);
        s
    }

    #[test]
    fn a_seam_slides_along_itself_and_keeps_its_corners_within_the_tolerance() {
        use crate::distance::uv_error;
        // The cells below the diagonal are a chart of their own: a
        // staircase seam, each step a corner a cell (21 texels) wide.
        let n = 24;
        let (records, welded) =
            charted_square(n, |i, j| Vec2::splat(if i + j < n { 0.5 } else { 0.0 }));
        let off = |lod: &TriMesh, texels: f32| {
            uv_error(&records, lod, texels / 512.0).unwrap().max_texels
        };
        let steps = |m: &TriMesh| {
            (1..n)
                .filter(|&k| {
                    m.positions.contains(&Vec3::new(
                        k as f32 / n as f32,
                        (n - k) as f32 / n as f32,
                        0.0,
                    ))
                })
                .count()
        };
        let run = |t: f32| {
            let run = flat_run(&welded, t);
            let tracked = run.seam_texels.iter().fold(0.0f32, |a, b| a.max(*b));
            (run.mesh().0, tracked)
        };
        // Straight runs of the seam slide; every step stays, and so does
        // the texture, below the 15 texels that cutting a step moves it.
        let (kept, tracked) = run(0.0);
        assert_eq!((steps(&kept), tracked), (n as usize - 1, 0.0));
        assert!(off(&kept, 0.0) < 0.01, "{}", off(&kept, 0.0));
        assert_eq!(run(8.0).0.triangles.len(), kept.triangles.len());
        // At 40 texels steps are cut: fewer triangles, the seam moved by at
        // most the tolerance at its vertices, and the texture as measured
        // within the tolerance's reach off by under a tenth of it (the
        // measurement samples faces, the tracking the seam's vertices).
        let (cut, tracked) = run(40.0);
        assert!(
            cut.triangles.len() * 2 < kept.triangles.len(),
            "{}",
            cut.triangles.len()
        );
        assert!(
            steps(&cut) < 12 && tracked > 8.0 && tracked <= 40.0,
            "{tracked}"
        );
        assert!(off(&cut, 40.0) < 4.0, "{}", off(&cut, 40.0));
        assert!(off(&cut, 0.0) > 40.0, "{}", off(&cut, 0.0));
    }

    #[test]
    fn seam_crossings_keep_every_texel_within_the_tolerance() {
        use crate::distance::uv_error;
        let (records, welded) = three_chart_square(24);
        assert!(welded.wedges.is_some());
        let run = |uv_tolerance: f32| {
            let s = flat_run(&welded, uv_tolerance);
            let worst = s.alive_triangles().flat_map(|t| {
                s.wedges.as_ref().unwrap().corners[t as usize].map(|w| s.wedge_texels[w as usize])
            });
            (s.mesh().0, worst.fold(0.0f32, f32::max))
        };
        // Texels a LOD's UVs are off from what the original shows within
        // `texels` of each point (512 texels per unit of length).
        let off = |lod: &TriMesh, texels: f32| {
            uv_error(&records, lod, texels / 512.0).unwrap().max_texels
        };
        // Every chart is affine: kept seams keep the texture exactly, and
        // the centre, where three charts meet, stays.
        let (kept, tracked) = run(0.0);
        assert_eq!((kept.triangles.len(), tracked), (7, 0.0));
        assert!(off(&kept, 0.0) < 0.01, "{}", off(&kept, 0.0));
        // Moving the centre to a corner of the square moves a chart's
        // texels half the square (256 texels): a 100-texel tolerance does
        // not let it, a 300-texel one does, and every texel the LOD shows
        // is then shown by the original within the tracked deviation.
        assert_eq!(run(100.0).0.triangles.len(), 7);
        let (crossed, tracked) = run(300.0);
        assert!(crossed.triangles.len() < 7, "{}", crossed.triangles.len());
        assert!(tracked > 100.0 && tracked <= 300.0, "{tracked}");
        assert!(off(&crossed, tracked) < 0.5, "{}", off(&crossed, tracked));
        // A tighter look does see the texture moved.
        assert!(off(&crossed, 30.0) > 100.0, "{}", off(&crossed, 30.0));
    }

    #[test]
    fn collapses_keep_each_side_of_a_uv_seam() {
        use crate::distance::uv_error;
        let (records, welded) = seamed_torus(48, 24);
        assert_eq!(welded.positions.len(), 48 * 24, "the seams are welded");
        assert!(welded.wedges.is_some());
        let run = |mesh: &TriMesh| {
            let mut s = EdgeCollapser::new(mesh, CollapseOptions::default());
            s.run(mesh.triangles.len() / 8, |_, _| true);
            s.mesh().0
        };
        let out = run(&welded);
        assert!(out.triangles.len() <= welded.triangles.len() / 8 + 8);
        let t = Topology::of(&out);
        assert_eq!((t.genus, t.components.len(), t.boundary_loops), (1, 1, 0));
        // Away from the seams a coarse LOD's interpolated UVs drift a little
        // from the original's at the nearest point; a face across a seam
        // would be off by up to a whole texture (0 against 1).
        let e = uv_error(&records, &out, 0.0).unwrap();
        assert!(e.max < 0.15 && e.area_over_threshold < 0.1, "{e:?}");
        // Without wedges faces along both seams do take the other side's UVs.
        let mut bare = welded.clone();
        bare.wedges = None;
        let e = uv_error(&records, &run(&bare), 0.0).unwrap();
        assert!(e.max > 0.5 && e.area_over_threshold > 0.2, "{e:?}");
    }

    #[test]
    fn sliver_guard_keeps_triangle_quality() {
        let mesh = icosphere(Vec3::ZERO, 1.0, 4);
        let opts = CollapseOptions {
            min_quality: 0.3,
            ..Default::default()
        };
        let mut s = EdgeCollapser::new(&mesh, opts);
        s.run(300, |_, _| true);
        let (out, _) = s.mesh();
        let worst = (0..out.triangles.len())
            .map(|t| quality(out.triangle(t)))
            .fold(1.0, f32::min);
        assert!(worst >= 0.3, "worst quality {worst}");
    }
}
