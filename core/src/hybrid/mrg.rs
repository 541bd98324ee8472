//! The multi-resolution graph (§4): a DAG from a drain (the original
//! triangles) to a source, whose nodes are simplification operations with their
//! error bounds and whose arcs carry primitives (triangles, points) with a
//! bounding sphere. A node's child arcs hold what it consumes, its parent arcs
//! what it produces (created lazily when a later node consumes them, §5).
//!
//! Errors are guaranteed two-sided Hausdorff bounds of a node's primitives
//! against the part of the original surface they stand for; they never
//! decrease going up. Each node also has a sphere that contains everything it
//! produces and the spheres of its (non-drain) children, so a cut's refinement
//! test is monotone (a node that must be refined has parents that must be too)
//! and incremental adaptation reaches the same cut as a fresh traversal.

use glam::{DVec3, Vec2, Vec3};

use crate::geom::{Materials, Wedges};

/// A ball.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Sphere {
    /// A tight ball containing every ball of `balls` (Bădoiu–Clarkson iterations
    /// towards the minimal enclosing ball, then the exact radius for the centre
    /// found, so containment always holds). Empty input gives a zero ball.
    pub fn enclose(balls: &[Sphere]) -> Sphere {
        let Some(first) = balls.first() else {
            return Sphere::default();
        };
        let far = |c: Vec3| {
            balls
                .iter()
                .map(|b| (c.distance(b.center) + b.radius, b))
                .fold((0.0f32, first), |x, y| if y.0 > x.0 { y } else { x })
        };
        let centroid = balls.iter().map(|b| b.center).sum::<Vec3>() / balls.len() as f32;
        let mut c = centroid;
        if balls.len() > 1 {
            for k in 1..=48 {
                let (_, b) = far(c);
                let dir = (c - b.center).normalize_or_zero();
                let extreme = b.center - dir * b.radius;
                c += (extreme - c) / (k + 1) as f32;
            }
        }
        if far(centroid).0 < far(c).0 {
            c = centroid;
        }
        let radius = far(c).0;
        // Round-off margin: containment must hold when tested in f32.
        Sphere {
            center: c,
            radius: radius * (1.0 + 1e-5) + 1e-7 * c.abs().max_element(),
        }
    }

    /// A ball containing every ball of `balls`, for the graph's arcs and
    /// nodes (a collapse makes several): the exact minimal ball (Welzl's
    /// algorithm, expected linear time) when they are points, as the
    /// vertices of an arc of triangles are; otherwise [`Sphere::enclose`]
    /// (a node's children's spheres: growing the centres' ball to reach
    /// them made the top nodes' spheres up to 45% larger, and a cut at 10 px
    /// took 9× the primitives).
    pub fn bounding(balls: &[Sphere]) -> Sphere {
        if balls.is_empty() || balls.iter().any(|b| b.radius > 0.0) {
            return Sphere::enclose(balls);
        }
        let centres: Vec<DVec3> = balls.iter().map(|b| b.center.as_dvec3()).collect();
        let (c, _) = min_ball(&centres);
        // The exact radius for the centre found, so containment always holds.
        let c = c.as_vec3();
        let radius = balls
            .iter()
            .map(|b| c.distance(b.center))
            .fold(0.0, f32::max);
        Sphere {
            center: c,
            radius: radius * (1.0 + 1e-5) + 1e-7 * c.abs().max_element(),
        }
    }

    /// Whether `o` lies inside (within round-off).
    pub fn contains(&self, o: &Sphere) -> bool {
        self.center.distance(o.center) + o.radius <= self.radius * (1.0 + 1e-4) + 1e-6
    }
}

/// The minimal ball around `points` (centre, radius): Welzl's algorithm as
/// nested loops, each point on the boundary of the ball of the points before
/// it when outside it. The order is shuffled (a fixed sequence, so results
/// repeat) because sorted vertices are the slow case.
fn min_ball(points: &[DVec3]) -> (DVec3, f64) {
    let mut order: Vec<usize> = (0..points.len()).collect();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    for i in (1..order.len()).rev() {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        order.swap(i, (state >> 33) as usize % (i + 1));
    }
    let p = |i: usize| points[order[i]];
    let outside = |x: DVec3, (c, r): (DVec3, f64)| x.distance_squared(c) > r * r * (1.0 + 1e-12);
    let mut ball = (p(0), 0.0);
    for i in 1..points.len() {
        if !outside(p(i), ball) {
            continue;
        }
        ball = (p(i), 0.0);
        for j in 0..i {
            if !outside(p(j), ball) {
                continue;
            }
            ball = ball_through(&[p(i), p(j)]);
            for k in 0..j {
                if !outside(p(k), ball) {
                    continue;
                }
                ball = ball_through(&[p(i), p(j), p(k)]);
                for l in 0..k {
                    if outside(p(l), ball) {
                        ball = ball_through(&[p(i), p(j), p(k), p(l)]);
                    }
                }
            }
        }
    }
    ball
}

/// The smallest ball with 2, 3 or 4 points on its boundary (their
/// circumsphere within their span); degenerate sets fall back to the ball of
/// a subset grown to reach the rest, which still contains them all.
fn ball_through(q: &[DVec3]) -> (DVec3, f64) {
    let a = q[0];
    let grow = |c: DVec3| (c, q.iter().map(|x| x.distance(c)).fold(0.0, f64::max));
    match q.len() {
        2 => (0.5 * (a + q[1]), 0.5 * a.distance(q[1])),
        3 => {
            let (u, v) = (q[1] - a, q[2] - a);
            let n = u.cross(v);
            let nn = n.length_squared();
            if nn <= 1e-24 * u.length_squared() * v.length_squared() {
                let far = [(q[0], q[1]), (q[1], q[2]), (q[0], q[2])]
                    .into_iter()
                    .max_by(|x, y| x.0.distance(x.1).total_cmp(&y.0.distance(y.1)))
                    .unwrap_or((a, a));
                return grow(0.5 * (far.0 + far.1));
            }
            let c = a
                + (v.cross(n) * u.length_squared() + n.cross(u) * v.length_squared()) / (2.0 * nn);
            grow(c)
        }
        _ => {
            let (u, v, w) = (q[1] - a, q[2] - a, q[3] - a);
            let det = u.dot(v.cross(w));
            let scale = u.length() * v.length() * w.length();
            if det.abs() <= 1e-12 * scale {
                let (c, _) = ball_through(&q[..3]);
                return grow(c);
            }
            let c = a
                + (v.cross(w) * u.length_squared()
                    + w.cross(u) * v.length_squared()
                    + u.cross(v) * w.length_squared())
                    / (2.0 * det);
            grow(c)
        }
    }
}

/// The three operations of §3, plus the graph's ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum NodeKind {
    Drain,
    /// TS: an edge collapse.
    TriangleSimplification,
    /// PR: one triangle → at most ⌊κ⌋ points.
    PointReplacement,
    /// PS: up to 8 points → 1.
    PointSimplification,
    Source,
}

#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Node {
    pub kind: NodeKind,
    /// Guaranteed error bound of the primitives it produces (object space).
    pub error: f32,
    /// Contains what it produces and its non-drain children's spheres.
    pub sphere: Sphere,
    /// Arcs to the nodes that produced what it consumes.
    pub children: Vec<u32>,
    /// Arcs to the nodes that consume what it produces.
    pub parents: Vec<u32>,
}

/// Primitives produced by `producer` (the arc's end node, below) and consumed
/// by `consumer` (its start node, above).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Arc {
    pub producer: u32,
    pub consumer: u32,
    pub triangles: Vec<u32>,
    pub points: Vec<u32>,
    pub sphere: Sphere,
}

/// A point primitive (§5.3): a ball over part of a triangle, or a merge of such.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Point {
    pub center: Vec3,
    pub radius: f32,
    pub color: Vec3,
    pub normal: Vec3,
    /// Surface area it covers (colour weights, §5.4).
    pub area: f32,
    /// Bound on the distance from `center` to the original surface.
    pub center_error: f32,
}

/// The graph with its primitive tables.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct Mrg {
    /// Every vertex ever made (the collapser's ids).
    pub positions: Vec<Vec3>,
    pub colors: Option<Vec<Vec3>>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    /// What every vertex carries for its asset (`geom::payload`).
    pub payload: Option<crate::geom::Payload>,
    /// Every triangle ever made (the collapser's ids); the first
    /// `input_triangles` are the original ones.
    pub triangles: Vec<[u32; 3]>,
    /// The part of every triangle (parts keep the input's materials).
    pub parts: Vec<u32>,
    pub materials: Option<Materials>,
    /// The collapser's wedges: every triangle's corners keep their own
    /// side's UVs and colours (`geom::wedges`).
    pub wedges: Option<Wedges>,
    pub points: Vec<Point>,
    pub nodes: Vec<Node>,
    pub arcs: Vec<Arc>,
    pub input_triangles: usize,
    /// Bounding-box diagonal of the input (object-space tolerances are fractions of it).
    pub diagonal: f32,
    /// The performance ratio κ it was built for (primitives = triangles + points/κ).
    pub kappa: f32,
}

pub const DRAIN: u32 = 0;

impl Mrg {
    pub fn source(&self) -> u32 {
        self.nodes.len() as u32 - 1
    }

    pub fn count(&self, kind: NodeKind) -> usize {
        self.nodes.iter().filter(|n| n.kind == kind).count()
    }

    pub fn triangle_positions(&self, t: u32) -> [Vec3; 3] {
        self.triangles[t as usize].map(|v| self.positions[v as usize])
    }

    /// Primitive weight of an arc: triangles + points/κ (§5.3); κ ≤ 1 counts points fully.
    pub fn arc_primitives(&self, a: &Arc) -> f64 {
        a.triangles.len() as f64 + a.points.len() as f64 / self.kappa.max(1.0) as f64
    }

    pub(crate) fn add_node(&mut self, kind: NodeKind, error: f32, sphere: Sphere) -> u32 {
        self.nodes.push(Node {
            kind,
            error,
            sphere,
            children: Vec::new(),
            parents: Vec::new(),
        });
        self.nodes.len() as u32 - 1
    }

    /// Makes `node` consume primitives: one child arc per producer, created now
    /// (the producers' parent arcs, §5). `producer_of` gives the producing node.
    pub(crate) fn consume(
        &mut self,
        node: u32,
        triangles: &[u32],
        points: &[u32],
        tri_producer: &[u32],
        point_producer: &[u32],
    ) {
        let mut by: Vec<(u32, bool, u32)> = triangles
            .iter()
            .map(|t| (tri_producer[*t as usize], true, *t))
            .chain(
                points
                    .iter()
                    .map(|p| (point_producer[*p as usize], false, *p)),
            )
            .collect();
        by.sort_unstable();
        for group in by.chunk_by(|x, y| x.0 == y.0) {
            let producer = group[0].0;
            let tris: Vec<u32> = group.iter().filter(|x| x.1).map(|x| x.2).collect();
            let pts: Vec<u32> = group.iter().filter(|x| !x.1).map(|x| x.2).collect();
            let sphere = Sphere::bounding(&self.balls(&tris, &pts));
            let id = self.arcs.len() as u32;
            self.arcs.push(Arc {
                producer,
                consumer: node,
                triangles: tris,
                points: pts,
                sphere,
            });
            self.nodes[node as usize].children.push(id);
            self.nodes[producer as usize].parents.push(id);
        }
    }

    /// Balls bounding primitives: triangle vertices (each once: neighbouring
    /// triangles share them, and the enclosing sphere's cost follows the
    /// count) and point spheres.
    pub(crate) fn balls(&self, triangles: &[u32], points: &[u32]) -> Vec<Sphere> {
        let mut vertices: Vec<u32> = triangles
            .iter()
            .flat_map(|t| self.triangles[*t as usize])
            .collect();
        vertices.sort_unstable();
        vertices.dedup();
        let mut out: Vec<Sphere> = vertices
            .iter()
            .map(|v| Sphere {
                center: self.positions[*v as usize],
                radius: 0.0,
            })
            .collect();
        out.extend(points.iter().map(|p| {
            let p = &self.points[*p as usize];
            Sphere {
                center: p.center,
                radius: p.radius,
            }
        }));
        out
    }

    /// Nodes that produced what `n` consumes.
    pub fn child_nodes(&self, n: u32) -> impl Iterator<Item = u32> + '_ {
        self.nodes[n as usize]
            .children
            .iter()
            .map(|a| self.arcs[*a as usize].producer)
    }

    /// Nodes that consume what `n` produces.
    pub fn parent_nodes(&self, n: u32) -> impl Iterator<Item = u32> + '_ {
        self.nodes[n as usize]
            .parents
            .iter()
            .map(|a| self.arcs[*a as usize].consumer)
    }

    /// How much of the original surface each primitive stands for, given a
    /// weight per original triangle: each node shares the weight it consumes
    /// among what it produces in proportion to area. A cut covers the surface
    /// exactly once iff its primitives' shares add up to the total weight for
    /// any weights. Returns (per triangle, per point).
    pub fn represented(&self, weights: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let mut tri = vec![0.0; self.triangles.len()];
        let mut pts = vec![0.0; self.points.len()];
        tri[..self.input_triangles].copy_from_slice(&weights[..self.input_triangles]);
        let area = |t: u32| {
            let p = self.triangle_positions(t);
            0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length() as f64
        };
        for node in &self.nodes[1..] {
            let mut total = 0.0;
            for a in &node.children {
                let a = &self.arcs[*a as usize];
                total += a.triangles.iter().map(|t| tri[*t as usize]).sum::<f64>();
                total += a.points.iter().map(|p| pts[*p as usize]).sum::<f64>();
            }
            let out = |a: &Arc| {
                a.triangles.iter().map(|t| area(*t)).sum::<f64>()
                    + a.points
                        .iter()
                        .map(|p| self.points[*p as usize].area as f64)
                        .sum::<f64>()
            };
            let sum: f64 = node
                .parents
                .iter()
                .map(|a| out(&self.arcs[*a as usize]))
                .sum();
            let count: usize = node
                .parents
                .iter()
                .map(|a| {
                    self.arcs[*a as usize].triangles.len() + self.arcs[*a as usize].points.len()
                })
                .sum();
            let share = |x: f64| {
                if sum > 0.0 {
                    total * x / sum
                } else {
                    total / count as f64
                }
            };
            for a in &node.parents {
                let a = &self.arcs[*a as usize];
                for t in &a.triangles {
                    tri[*t as usize] = share(area(*t));
                }
                for p in &a.points {
                    pts[*p as usize] = share(self.points[*p as usize].area as f64);
                }
            }
        }
        (tri, pts)
    }

    /// Checks the graph's invariants; the first violation found, if any:
    /// one drain (node 0) and one source (last), arcs consistent with their
    /// nodes and pointing upwards (producers built before consumers), every
    /// primitive produced and consumed exactly once, the original triangles
    /// produced by the drain, errors not decreasing upwards, node spheres
    /// containing their children's and arc spheres their primitives.
    pub fn check(&self) -> Result<(), String> {
        self.check_ranges()?;
        let n = self.nodes.len();
        if n < 2 || self.nodes[0].kind != NodeKind::Drain {
            return Err("node 0 is not the drain".into());
        }
        let source = self.source() as usize;
        for (i, node) in self.nodes.iter().enumerate() {
            let is_end = i == 0 || i == source;
            if is_end != matches!(node.kind, NodeKind::Drain | NodeKind::Source) {
                return Err(format!("node {i}: {:?} in the wrong place", node.kind));
            }
            if (i == 0) != node.children.is_empty() || (i == source) != node.parents.is_empty() {
                return Err(format!("node {i}: missing arcs"));
            }
        }
        let mut tri_seen = vec![[0u8; 2]; self.triangles.len()];
        let mut pt_seen = vec![[0u8; 2]; self.points.len()];
        for (id, a) in self.arcs.iter().enumerate() {
            let (p, c) = (a.producer as usize, a.consumer as usize);
            if p >= c || c >= n {
                return Err(format!("arc {id} does not point upwards ({p} → {c})"));
            }
            if !self.nodes[p].parents.contains(&(id as u32))
                || !self.nodes[c].children.contains(&(id as u32))
            {
                return Err(format!("arc {id} is not linked to its nodes"));
            }
            if a.triangles.is_empty() && a.points.is_empty() {
                return Err(format!("arc {id} is empty"));
            }
            let (ep, ec) = (self.nodes[p].error, self.nodes[c].error);
            if ec < ep {
                return Err(format!("arc {id}: error decreases upwards ({ep} → {ec})"));
            }
            if p != 0 && !self.nodes[c].sphere.contains(&self.nodes[p].sphere) {
                return Err(format!("node {c}'s sphere does not contain node {p}'s"));
            }
            for b in self.balls(&a.triangles, &a.points) {
                if !a.sphere.contains(&b) || (p != 0 && !self.nodes[p].sphere.contains(&b)) {
                    return Err(format!("arc {id}: a primitive outside its spheres"));
                }
            }
            for t in &a.triangles {
                let s = &mut tri_seen[*t as usize];
                s[0] += 1;
                s[1] += u8::from((*t as usize) < self.input_triangles) ^ u8::from(p == 0);
            }
            for q in &a.points {
                pt_seen[*q as usize][0] += 1;
            }
        }
        if let Some(t) = tri_seen.iter().position(|s| s[0] > 1 || s[1] != 0) {
            return Err(format!(
                "triangle {t} on several arcs, or not from the drain"
            ));
        }
        if let Some(t) = (0..self.input_triangles).find(|t| tri_seen[*t][0] != 1) {
            return Err(format!("original triangle {t} on no arc"));
        }
        if let Some(q) = pt_seen.iter().position(|s| s[0] != 1) {
            return Err(format!("point {q} on {} arcs", pt_seen[q][0]));
        }
        Ok(())
    }

    /// Every index in range and every attribute the size of what it
    /// describes, before [`Mrg::check`] follows any of them.
    fn check_ranges(&self) -> Result<(), String> {
        use crate::geom::{check_indices, check_len};
        let (nv, nt) = (self.positions.len(), self.triangles.len());
        check_len("colours", self.colors.as_ref(), nv)?;
        check_len("normals", self.normals.as_ref(), nv)?;
        check_len("UVs", self.uvs.as_ref(), nv)?;
        if let Some(p) = &self.payload {
            p.check("payload", nv)?;
        }
        check_indices("vertex", self.triangles.iter().flatten().copied(), nv)?;
        // No parts: every triangle is in part 0.
        if !self.parts.is_empty() {
            check_len("parts", Some(&self.parts), nt)?;
        }
        if let Some(m) = &self.materials {
            m.check(if self.parts.is_empty() {
                &[0]
            } else {
                &self.parts
            })?;
        }
        if let Some(w) = &self.wedges {
            w.check(nt, nv)?;
        }
        if self.input_triangles > nt {
            return Err(format!("{} input triangles of {nt}", self.input_triangles));
        }
        for a in &self.arcs {
            check_indices("triangle", a.triangles.iter().copied(), nt)?;
            check_indices("point", a.points.iter().copied(), self.points.len())?;
            check_indices("node", [a.producer, a.consumer], self.nodes.len())?;
        }
        let arcs = self
            .nodes
            .iter()
            .flat_map(|n| n.children.iter().chain(&n.parents));
        check_indices("arc", arcs.copied(), self.arcs.len())?;
        if !(self.diagonal.is_finite() && self.diagonal >= 0.0 && self.kappa.is_finite()) {
            return Err("diagonal or kappa not finite".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// The bounding ball of points is their minimal ball: it contains them,
    /// and no ball found by the slower iteration is smaller; with radii it
    /// still contains every ball.
    #[test]
    fn bounding_sphere_of_points_is_minimal() {
        let mut rng = Rng::new(9);
        for round in 0..300 {
            let k = 1 + rng.below(40);
            let mut balls: Vec<Sphere> = (0..k)
                .map(|_| Sphere {
                    center: Vec3::new(rng.f32(), rng.f32(), rng.f32() * 0.2) * 2.0,
                    radius: 0.0,
                })
                .collect();
            if round % 3 == 0 {
                // Sorted, coplanar and repeated points: the hard cases.
                balls.sort_by(|a, b| a.center.x.total_cmp(&b.center.x));
                for b in &mut balls {
                    b.center.z = 0.5;
                }
                balls.push(balls[0]);
            }
            let fast = Sphere::bounding(&balls);
            let slow = Sphere::enclose(&balls);
            assert!(balls.iter().all(|b| fast.contains(b)));
            assert!(
                fast.radius <= slow.radius * 1.0001 + 1e-6,
                "{} > {}",
                fast.radius,
                slow.radius
            );
            for b in &mut balls {
                b.radius = rng.f32() * 0.3;
            }
            let grown = Sphere::bounding(&balls);
            assert!(balls.iter().all(|b| grown.contains(b)));
        }
    }

    #[test]
    fn enclosing_sphere_contains_every_ball_and_is_tight() {
        let mut rng = Rng::new(4);
        for _ in 0..200 {
            let k = 1 + rng.below(8);
            let balls: Vec<Sphere> = (0..k)
                .map(|_| Sphere {
                    center: Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0,
                    radius: rng.f32() * 0.3,
                })
                .collect();
            let s = Sphere::enclose(&balls);
            assert!(balls.iter().all(|b| s.contains(b)));
            // At least as large as half the largest pairwise extent; at most 1.1× the
            // simple bound-of-bounds heuristic around the centroid.
            let naive = {
                let c = balls.iter().map(|b| b.center).sum::<Vec3>() / k as f32;
                balls
                    .iter()
                    .map(|b| c.distance(b.center) + b.radius)
                    .fold(0.0, f32::max)
            };
            assert!(s.radius <= naive * 1.001 + 1e-6, "{} > {naive}", s.radius);
            for a in &balls {
                for b in &balls {
                    let need = 0.5 * (a.center.distance(b.center) + a.radius + b.radius);
                    assert!(s.radius >= need * 0.999);
                }
            }
        }
    }
}
