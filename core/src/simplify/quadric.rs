//! Garland–Heckbert error quadrics: the sum of squared distances to a set of
//! planes, used to order edge collapses and to place the new vertex cheaply.
//! The certified bound (see `bound`) is computed separately; quadrics only rank.

use glam::{DMat3, DVec3, Vec3};

/// Symmetric 4×4 quadric stored as its 10 distinct coefficients (f64: sums over
/// thousands of planes lose too much in f32).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Quadric {
    a: [f64; 6], // xx xy xz yy yz zz
    b: [f64; 3], // linear terms (d·n)
    c: f64,      // d²
}

impl Quadric {
    /// Squared distance to the plane through `p` with unit normal `n`, times `w`.
    pub fn plane(p: Vec3, n: Vec3, w: f64) -> Quadric {
        let n = n.as_dvec3();
        let d = -n.dot(p.as_dvec3());
        Quadric {
            a: [
                w * n.x * n.x,
                w * n.x * n.y,
                w * n.x * n.z,
                w * n.y * n.y,
                w * n.y * n.z,
                w * n.z * n.z,
            ],
            b: [w * d * n.x, w * d * n.y, w * d * n.z],
            c: w * d * d,
        }
    }

    pub fn add(&mut self, o: &Quadric) {
        for i in 0..6 {
            self.a[i] += o.a[i];
        }
        for i in 0..3 {
            self.b[i] += o.b[i];
        }
        self.c += o.c;
    }

    pub fn sum(a: &Quadric, b: &Quadric) -> Quadric {
        let mut q = *a;
        q.add(b);
        q
    }

    /// Total weight of the planes (the trace: each unit normal adds w).
    pub fn weight(&self) -> f64 {
        self.a[0] + self.a[3] + self.a[5]
    }

    fn matrix(&self) -> DMat3 {
        let a = &self.a;
        DMat3::from_cols(
            DVec3::new(a[0], a[1], a[2]),
            DVec3::new(a[1], a[3], a[4]),
            DVec3::new(a[2], a[4], a[5]),
        )
    }

    /// vᵀ Q v for the homogeneous point (p, 1); clamped at 0 against round-off.
    pub fn error(&self, p: Vec3) -> f64 {
        let p = p.as_dvec3();
        let ap = self.matrix() * p;
        (p.dot(ap) + 2.0 * DVec3::from_array(self.b).dot(p) + self.c).max(0.0)
    }

    /// The point minimising the quadric, when the system is well conditioned.
    pub fn optimum(&self) -> Option<Vec3> {
        let m = self.matrix();
        let det = m.determinant();
        let scale = self.a[0].abs() + self.a[3].abs() + self.a[5].abs();
        // NaN determinants fail this too.
        if det.abs().partial_cmp(&(1e-12 * scale.powi(3))) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let p = m.inverse() * -DVec3::from_array(self.b);
        p.is_finite().then(|| p.as_vec3())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_planes_meet_at_their_optimum() {
        let corner = Vec3::new(0.3, -0.2, 0.7);
        let mut q = Quadric::default();
        for n in [Vec3::X, Vec3::Y, Vec3::Z] {
            q.add(&Quadric::plane(corner, n, 1.0));
        }
        assert!(q.optimum().unwrap().distance(corner) < 1e-5);
        assert!(q.error(corner) < 1e-10);
        // Distance 0.5 from each of three orthogonal planes: 3 · 0.25.
        assert!((q.error(corner + Vec3::splat(0.5)) - 0.75).abs() < 1e-6);
        // A single plane has no unique optimum.
        assert!(Quadric::plane(corner, Vec3::Z, 1.0).optimum().is_none());
    }
}
