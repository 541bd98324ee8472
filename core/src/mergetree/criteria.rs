//! §3, §5.1: when a node must be refined for a view. Each criterion only
//! depends on a node's sphere, switch distance and normal cone, and only ever
//! asks for more refinement as those grow; since a node's ranges hold those of
//! the nodes below it, a node that must be refined has ancestors that must be
//! too, so the walk down from the display vertices finds every one.

use std::f32::consts::PI;

use glam::Vec3;

use super::Node;
use crate::view::{Projector, Tolerance, View};

/// A cone of directions: every normal within `half_angle` of `axis` (§4.2).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NormalCone {
    pub axis: Vec3,
    /// Radians; negative for the empty cone.
    pub half_angle: f32,
    /// Cosine and sine of `half_angle`, so that per-frame tests need no
    /// trigonometry.
    cos_half: f32,
    sin_half: f32,
}

/// Slack added to every union so containment survives rounding.
const ANGLE_SLACK: f32 = 1e-5;

fn angle(a: Vec3, b: Vec3) -> f32 {
    a.dot(b).clamp(-1.0, 1.0).acos()
}

/// A cosine (clamped) and the sine of the same angle in 0..π.
fn cos_sin(c: f32) -> (f32, f32) {
    let c = c.clamp(-1.0, 1.0);
    (c, (1.0 - c * c).max(0.0).sqrt())
}

impl NormalCone {
    pub const EMPTY: NormalCone = NormalCone {
        axis: Vec3::Z,
        half_angle: -1.0,
        cos_half: 1.0,
        sin_half: 0.0,
    };

    /// The directions within `half_angle` (radians, at most π) of `axis` (unit).
    pub fn new(axis: Vec3, half_angle: f32) -> NormalCone {
        let half_angle = half_angle.min(PI);
        NormalCone {
            axis,
            half_angle,
            cos_half: half_angle.cos(),
            sin_half: half_angle.sin(),
        }
    }

    /// The cone of one direction (none for a zero vector).
    pub fn of(n: Vec3) -> NormalCone {
        match n.try_normalize() {
            Some(axis) => NormalCone::new(axis, 0.0),
            None => NormalCone::EMPTY,
        }
    }

    pub fn is_empty(&self) -> bool {
        self.half_angle < 0.0
    }

    /// The smallest cone holding both.
    pub fn union(self, o: NormalCone) -> NormalCone {
        if o.is_empty() {
            return self;
        }
        if self.is_empty() {
            return o;
        }
        let d = angle(self.axis, o.axis);
        if d + o.half_angle <= self.half_angle {
            return self;
        }
        if d + self.half_angle <= o.half_angle {
            return o;
        }
        let half = 0.5 * (d + self.half_angle + o.half_angle) + ANGLE_SLACK;
        let s = d.sin();
        if half >= PI || s < 1e-6 {
            return NormalCone::new(self.axis, PI);
        }
        // Turn our axis towards the other's by the growth of our half angle.
        let t = (half - self.half_angle).clamp(0.0, d);
        let axis = (self.axis * (d - t).sin() + o.axis * t.sin()) / s;
        NormalCone::new(axis.normalize_or(self.axis), half)
    }

    /// The range of `n · dir` over the cone (`dir` normalised): the cosines of
    /// the angle to the axis plus and minus the half angle, clamped to 0..π.
    fn dot_range(&self, dir: Vec3) -> (f32, f32) {
        let (c, s) = cos_sin(self.axis.dot(dir));
        let (ch, sh) = (self.cos_half, self.sin_half);
        // γ + θ ≥ π ⇔ cos γ ≤ −cos θ; γ ≤ θ ⇔ cos γ ≥ cos θ.
        let lo = if c <= -ch { -1.0 } else { c * ch - s * sh };
        let hi = if c >= ch { 1.0 } else { c * ch + s * sh };
        (lo, hi)
    }
}

pub use crate::lod::Criteria;

/// Threshold factor for invisible nodes.
pub const BACKFACE_FACTOR: f32 = 8.0;
/// Threshold factor for silhouette nodes.
pub const SILHOUETTE_FACTOR: f32 = 0.5;
/// Threshold divisor 1 + this × the spread of n·L over a node.
pub const LIGHTING_WEIGHT: f32 = 1.0;

/// How a node's triangles face the eye.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Facing {
    Front,
    Back,
    Straddle,
}

/// The directions from the eye into the node's sphere form a cone of half
/// angle α about d; the node faces one way if the angle β between d and the
/// normal cone's axis stays more than α + θ away from 90°. With |d| = D,
/// sin α = r/D and cos α = √(D² − r²)/D, so every term is compared times D:
/// one square root, no division, no branch (see [`Frame::refine_flags`]).
#[inline(always)]
fn facing(node: &Node, eye: Vec3) -> Facing {
    let cone = &node.cone;
    let d = node.center - eye;
    let (dd, r) = (d.length_squared(), node.radius);
    let q = (dd - r * r).max(0.0).sqrt(); // D cos α
    let cos_spread = q * cone.cos_half - r * cone.sin_half; // D cos(α + θ)
    let sin_spread = r * cone.cos_half + q * cone.sin_half; // D sin(α + θ)
    let cos_beta = cone.axis.dot(d); // D cos β
    let undecided = (dd <= r * r) | cone.is_empty() | (cos_spread <= 0.0);
    let back = !undecided & (cos_beta > sin_spread);
    let front = !undecided & (cos_beta < -sin_spread);
    if back {
        Facing::Back
    } else if front {
        Facing::Front
    } else {
        Facing::Straddle
    }
}

impl Criteria {
    /// Whether `node` is too coarse for `view` within `tolerance`; `diagonal`
    /// scales a relative tolerance (which ignores the view-dependent criteria).
    pub fn must_refine(
        &self,
        node: &Node,
        view: &View,
        tolerance: Tolerance,
        diagonal: f32,
    ) -> bool {
        self.frame(view, tolerance, diagonal).must_refine(node)
    }

    /// The criteria with one view's constants computed once.
    pub(crate) fn frame(&self, view: &View, tolerance: Tolerance, diagonal: f32) -> Frame {
        Frame {
            criteria: *self,
            eye: view.eye,
            projector: view.projector(),
            planes: view.side_planes(),
            forward: view.forward(),
            light: view.light_dir.normalize_or(Vec3::Z),
            tolerance,
            diagonal,
        }
    }
}

/// [`Criteria`] for one view.
pub(crate) struct Frame {
    criteria: Criteria,
    eye: Vec3,
    projector: Projector,
    planes: [Vec3; 4],
    forward: Vec3,
    light: Vec3,
    tolerance: Tolerance,
    diagonal: f32,
}

impl Frame {
    /// §3: whether `node` is too coarse.
    pub(crate) fn must_refine(&self, node: &Node) -> bool {
        match self.tolerance {
            Tolerance::Relative(f) => node.downswitch > f * self.diagonal,
            Tolerance::Pixels(t) => self.too_many_pixels(node, t),
        }
    }

    /// [`Frame::must_refine`] of every node in `nodes`, as 0/1 in `flags`.
    /// §5.1's walk tests every display vertex each frame; without branches on
    /// the node the test runs as one vector loop ([`crate::simd::wide`]).
    pub(crate) fn refine_flags(&self, nodes: &[Node], flags: &mut Vec<u8>) {
        flags.clear();
        flags.resize(nodes.len(), 0);
        let t = match self.tolerance {
            Tolerance::Relative(_) => {
                for (o, n) in flags.iter_mut().zip(nodes) {
                    *o = u8::from(self.must_refine(n));
                }
                return;
            }
            Tolerance::Pixels(t) => t,
        };
        crate::simd::wide(
            nodes,
            flags,
            #[inline(always)]
            |nodes, flags| {
                for (o, n) in flags.iter_mut().zip(nodes) {
                    *o = u8::from(self.too_many_pixels(n, t));
                }
            },
        );
    }

    /// The screen-space test with its threshold `t` scaled by the other
    /// criteria. Branch-free on the node.
    #[inline(always)]
    fn too_many_pixels(&self, node: &Node, t: f32) -> bool {
        let c = &self.criteria;
        let d = node.center - self.eye;
        let f = facing(node, self.eye);
        let r = -node.radius;
        let [p0, p1, p2, p3] = self.planes;
        let seen = (d.dot(self.forward) >= r)
            & (d.dot(p0) >= r)
            & (d.dot(p1) >= r)
            & (d.dot(p2) >= r)
            & (d.dot(p3) >= r);
        let hidden = c.backface & ((f == Facing::Back) | !seen);
        let silhouette = c.silhouette & (f == Facing::Straddle);
        let factor = if hidden {
            BACKFACE_FACTOR
        } else if silhouette {
            SILHOUETTE_FACTOR
        } else {
            1.0
        };
        let (lo, hi) = node.cone.dot_range(self.light);
        let spread = if c.lighting & !node.cone.is_empty() {
            hi.max(0.0) - lo.max(0.0)
        } else {
            0.0
        };
        // px > t·factor / (1 + w·spread), without dividing.
        let length = node.downswitch * (1.0 + LIGHTING_WEIGHT * spread);
        (self.projector).exceeds(length, node.center, node.radius, t * factor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn random_unit(rng: &mut Rng) -> Vec3 {
        loop {
            let v = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0;
            if (1e-3..=1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }

    #[test]
    fn union_holds_every_normal_it_was_built_from() {
        let mut rng = Rng::new(7);
        for spread in [0.1f32, 0.6, 2.0] {
            let base = random_unit(&mut rng);
            let normals: Vec<Vec3> = (0..40)
                .map(|_| (base + random_unit(&mut rng) * spread).normalize())
                .collect();
            let cone = normals
                .iter()
                .fold(NormalCone::EMPTY, |c, n| c.union(NormalCone::of(*n)));
            let dir = random_unit(&mut rng);
            let (lo, hi) = cone.dot_range(dir);
            for n in &normals {
                assert!(angle(cone.axis, *n) <= cone.half_angle + 1e-4);
                assert!((lo - 1e-4..=hi + 1e-4).contains(&n.dot(dir)));
            }
            assert!(cone.half_angle <= PI);
        }
    }

    #[test]
    fn facing_of_a_flat_patch_follows_the_eye() {
        let node = Node {
            center: Vec3::ZERO,
            radius: 0.1,
            downswitch: 0.01,
            upswitch: f32::INFINITY,
            cone: NormalCone::new(Vec3::Z, 0.2),
        };
        assert_eq!(facing(&node, Vec3::Z * 5.0), Facing::Front);
        assert_eq!(facing(&node, -Vec3::Z * 5.0), Facing::Back);
        assert_eq!(facing(&node, Vec3::X * 5.0), Facing::Straddle);
    }
}
