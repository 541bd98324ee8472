//! §2.1: the moment-based surface classifier (eq. 1–3) and the tangent frames
//! from the eigenvectors of the first moment.

use glam::{DMat3, DVec3, Vec3};
use rayon::prelude::*;

use super::neighbourhood::Neighbourhoods;

/// G(s) = (α + βs²)⁻¹ with the paper's fixed α = 0.01, β = 100 (eq. 3).
pub const ALPHA: f64 = 0.01;
pub const BETA: f64 = 100.0;

/// A local tangent frame: `e0`, `e1` span the tangent plane, `e2` is its normal
/// (eigenvectors of M¹ by decreasing eigenvalue).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub e0: Vec3,
    pub e1: Vec3,
    pub e2: Vec3,
}

/// Classifier value C_ε (eq. 3) and tangent frame of every point.
#[derive(Debug, Clone)]
pub struct Classification {
    pub value: Vec<f32>,
    pub frames: Vec<Frame>,
}

/// Eigenvalues (decreasing) and unit eigenvectors of a symmetric 3×3 matrix,
/// by cyclic Jacobi rotations (glam has no eigensolver).
pub fn symmetric_eigen(m: DMat3) -> ([f64; 3], [DVec3; 3]) {
    let mut a = m.to_cols_array_2d();
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    for _ in 0..32 {
        let off = a[0][1].powi(2) + a[0][2].powi(2) + a[1][2].powi(2);
        let scale = a[0][0].powi(2) + a[1][1].powi(2) + a[2][2].powi(2);
        if off <= 1e-30 * scale.max(1e-300) {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in a.iter_mut() {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (rp, rq) = (a[p], a[q]);
            for k in 0..3 {
                a[p][k] = c * rp[k] - s * rq[k];
                a[q][k] = s * rp[k] + c * rq[k];
            }
            for row in v.iter_mut() {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| a[j][j].total_cmp(&a[i][i]));
    let vec = |c: usize| DVec3::new(v[0][c], v[1][c], v[2][c]).normalize_or(DVec3::Z);
    (
        order.map(|i| a[i][i]),
        [vec(order[0]), vec(order[1]), vec(order[2])],
    )
}

/// Eq. 1–3 on the discrete neighbourhood N ∪ {x}: M⁰ its barycentre, M¹ its
/// covariance, C = G(|M⁰ − x| λ₂ / (ε λ₀)) with ε the neighbourhood radius.
pub fn classify(points: &[Vec3], nb: &Neighbourhoods) -> Classification {
    let (value, frames) = points
        .par_iter()
        .enumerate()
        .map(|(i, x)| {
            let members = || {
                std::iter::once(x.as_dvec3())
                    .chain(nb.lists[i].iter().map(|&j| points[j as usize].as_dvec3()))
            };
            let count = (nb.lists[i].len() + 1) as f64;
            let m0 = members().sum::<DVec3>() / count;
            let mut m1 = DMat3::ZERO;
            for p in members() {
                let d = p - m0;
                m1 += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
            }
            m1 *= 1.0 / count;
            let (lambda, e) = symmetric_eigen(m1);
            let eps = nb.radii[i] as f64;
            let s = if lambda[0] > 0.0 && eps > 0.0 {
                (m0 - x.as_dvec3()).length() * lambda[2].max(0.0) / (eps * lambda[0])
            } else {
                0.0
            };
            let c = 1.0 / (ALPHA + BETA * s * s);
            let frame = Frame {
                e0: e[0].as_vec3(),
                e1: e[1].as_vec3(),
                e2: e[2].as_vec3(),
            };
            (c as f32, frame)
        })
        .unzip();
    Classification { value, frames }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::amg::neighbourhood::neighbourhoods;

    #[test]
    fn eigen_decomposition_reconstructs_the_matrix() {
        let m = DMat3::from_cols_array(&[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 1.0]);
        let (l, e) = symmetric_eigen(m);
        assert!(l[0] >= l[1] && l[1] >= l[2]);
        for k in 0..3 {
            assert!((m * e[k] - e[k] * l[k]).length() < 1e-9);
        }
        assert!(e[0].dot(e[1]).abs() < 1e-9 && e[1].dot(e[2]).abs() < 1e-9);
    }

    #[test]
    fn flat_points_are_smooth_and_creases_are_not() {
        let pts = crate::builtins::octahedron_points(8000, 2);
        let nb = neighbourhoods(&pts.positions, 30, 0.0);
        let c = classify(&pts.positions, &nb);
        // Face centres (far from every edge) are flat: C close to 1/α = 100,
        // with the normal along the face normal; points on a crease are far lower.
        let mut flat = 0;
        let (mut crease, mut crease_sum) = (0, 0.0);
        for (i, p) in pts.positions.iter().enumerate() {
            let a = p.abs();
            let normal = pts.normals.as_ref().unwrap()[i];
            if a.min_element() > 0.25 {
                assert!(c.value[i] > 50.0, "flat point {p} has C = {}", c.value[i]);
                assert!(c.frames[i].e2.dot(normal).abs() > 0.99);
                flat += 1;
            } else if a.min_element() < 0.005 && a.max_element() < 0.8 {
                crease_sum += c.value[i];
                crease += 1;
            }
        }
        assert!(flat > 100 && crease > 10);
        // "One up to several orders of magnitude smaller close to edges" (§2.1).
        let mean = crease_sum / crease as f32;
        assert!(mean < 30.0, "mean C on creases {mean}");
    }
}
