//! §2.3: the multiscale basis functions Ψ^{l,i} (columns of the products of
//! the prolongations), their domains D^{l,i} = {x : Ψ^{l,i}(x) > τ} (eq. 8) and
//! the domain-neighbour relation of §4.

use std::collections::HashMap;

use sprs::CsMat;

use super::coarsening::Coarsening;
use super::sparse::product;

/// Entries below this are dropped from the products: far under any τ, and
/// they move a row sum by less than 1e-9 per level.
const PRUNE: f64 = 1e-12;

/// Ψ^l = P_0 P_1 ⋯ P_{l−1}: one row per point, one column per basis function
/// of level l (level 0 is the identity).
pub fn basis(c: &Coarsening, level: usize) -> CsMat<f64> {
    let n = c.operators[0].rows();
    let mut psi = CsMat::<f64>::eye(n);
    for p in &c.prolongations[..level] {
        psi = product(&psi, p, PRUNE);
    }
    psi
}

/// The domain of every basis function: the points where it exceeds τ (eq. 8),
/// with their values. A basis function that nowhere exceeds τ has an empty domain.
pub fn domains(psi: &CsMat<f64>, tau: f64) -> Vec<Vec<(u32, f32)>> {
    let mut out = vec![Vec::new(); psi.cols()];
    for (i, row) in psi.outer_iterator().enumerate() {
        for (j, &v) in row.iter() {
            if v > tau {
                out[j].push((i as u32, v as f32));
            }
        }
    }
    out
}

/// §4: two domains are neighbours when their common points exceed `fraction`
/// of the points of at least one of them (the paper uses 0.05).
pub fn domain_neighbours(
    domains: &[Vec<(u32, f32)>],
    points: usize,
    fraction: f64,
) -> Vec<Vec<u32>> {
    let mut of_point: Vec<Vec<u32>> = vec![Vec::new(); points];
    for (d, members) in domains.iter().enumerate() {
        for &(i, _) in members {
            of_point[i as usize].push(d as u32);
        }
    }
    let mut common: HashMap<(u32, u32), usize> = HashMap::new();
    for ds in &of_point {
        for (k, &a) in ds.iter().enumerate() {
            for &b in &ds[k + 1..] {
                *common.entry((a, b)).or_default() += 1;
            }
        }
    }
    let mut out = vec![Vec::new(); domains.len()];
    for ((a, b), n) in common {
        let (na, nb) = (domains[a as usize].len(), domains[b as usize].len());
        if n as f64 > fraction * na as f64 || n as f64 > fraction * nb as f64 {
            out[a as usize].push(b);
            out[b as usize].push(a);
        }
    }
    out.iter_mut().for_each(|l| l.sort_unstable());
    out
}
