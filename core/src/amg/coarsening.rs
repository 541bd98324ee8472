//! §2.3: classical Ruge–Stüben algebraic multigrid coarsening — strength of
//! connection, C/F splitting, direct interpolation P and the Galerkin product
//! A_c = Pᵀ A P — repeated until a handful of unknowns remain.

use rayon::prelude::*;
use sprs::CsMat;

use super::sparse::galerkin;

use crate::progress::{Cancelled, Progress};

/// Parameters of the Ruge–Stüben setup. θ = 0.5 rather than the usual 0.25:
/// with it the octahedron's creases stay weak couplings down to one domain per
/// face (§2.3, Fig. 5c); compare with PyAMG at the same θ.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RugeStuben {
    /// j strongly influences i when −a_ij ≥ θ·max_k(−a_ik).
    pub theta: f64,
    /// Stop once a level has at most this many unknowns.
    pub max_coarse: usize,
    pub max_levels: usize,
    pub orphans: Orphans,
}

/// What P does for an F point without a strong C neighbour (one of weight 0
/// in [`cf_splitting`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Orphans {
    /// Stüben's multi-pass interpolation through its strong neighbours, so
    /// that Ψ stays a partition of unity (§2.3).
    MultiPass,
    /// A zero row, as PyAMG's direct interpolation: Ψ vanishes there, and the
    /// levels are PyAMG's `ruge_stuben_solver`'s, unknown for unknown — the
    /// cross-check of the splitting and the Galerkin product.
    Zero,
}

impl Default for RugeStuben {
    fn default() -> Self {
        Self {
            theta: 0.5,
            max_coarse: 8,
            max_levels: 30,
            orphans: Orphans::MultiPass,
        }
    }
}

/// The AMG hierarchy: `operators[0]` = A, `operators[l+1]` = P_lᵀ A_l P_l with
/// `prolongations[l]` mapping level l+1 to level l.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Coarsening {
    pub operators: Vec<CsMat<f64>>,
    pub prolongations: Vec<CsMat<f64>>,
}

impl Coarsening {
    /// Unknowns per level, finest first.
    pub fn level_sizes(&self) -> Vec<usize> {
        self.operators.iter().map(|a| a.rows()).collect()
    }
}

/// Classical strength of connection (Ruge–Stüben's −a_ij form): the strong
/// influencers S_i of every row.
pub fn strength(a: &CsMat<f64>, theta: f64) -> Vec<Vec<u32>> {
    (0..a.rows())
        .into_par_iter()
        .map(|i| {
            let row = a.outer_view(i).expect("row in range");
            let max = row
                .iter()
                .filter(|&(j, _)| j != i)
                .fold(0f64, |m, (_, &v)| m.max(-v));
            if max <= 0.0 {
                return Vec::new();
            }
            row.iter()
                .filter(|&(j, &v)| j != i && -v >= theta * max)
                .map(|(j, _)| j as u32)
                .collect()
        })
        .collect()
}

/// Transposes an adjacency list: `out[j]` holds every i with j ∈ s[i].
fn transpose(s: &[Vec<u32>]) -> Vec<Vec<u32>> {
    let mut t = vec![Vec::new(); s.len()];
    for (i, row) in s.iter().enumerate() {
        for &j in row {
            t[j as usize].push(i as u32);
        }
    }
    t
}

/// The points in order of weight λ for the first pass: `order[start[l]..]`
/// (`len[l]` of them) are the points of weight l, `pos` inverts `order`. A
/// point whose weight rises joins the low end of the next bucket, one whose
/// weight falls the high end of the previous — the order PyAMG's
/// `rs_cf_splitting` picks points in, so that ties go the same way (they
/// decide the coarsest levels), in O(1) per update.
struct Buckets {
    order: Vec<u32>,
    pos: Vec<usize>,
    start: Vec<usize>,
    len: Vec<usize>,
}

impl Buckets {
    fn new(lambda: &[usize]) -> Self {
        let n = lambda.len();
        let size = (2 * lambda.iter().copied().max().unwrap_or(0)).max(n + 1);
        let mut len = vec![0; size];
        for &l in lambda {
            len[l] += 1;
        }
        let mut start = vec![0; size];
        for l in 1..size {
            start[l] = start[l - 1] + len[l - 1];
        }
        let mut next = start.clone();
        let (mut order, mut pos) = (vec![0; n], vec![0; n]);
        for (i, &l) in lambda.iter().enumerate() {
            order[next[l]] = i as u32;
            pos[i] = next[l];
            next[l] += 1;
        }
        Self {
            order,
            pos,
            start,
            len,
        }
    }

    fn swap(&mut self, a: usize, b: usize) {
        self.order.swap(a, b);
        self.pos[self.order[a] as usize] = a;
        self.pos[self.order[b] as usize] = b;
    }

    /// Point k of weight l moves up to weight l + 1.
    fn raise(&mut self, k: usize, l: usize) {
        let to = self.start[l] + self.len[l] - 1;
        self.swap(self.pos[k], to);
        self.len[l] -= 1;
        self.len[l + 1] += 1;
        self.start[l + 1] = to;
    }

    /// Point j of weight l > 0 moves down to weight l − 1.
    fn lower(&mut self, j: usize, l: usize) {
        let to = self.start[l];
        self.swap(self.pos[j], to);
        self.len[l] -= 1;
        self.len[l - 1] += 1;
        self.start[l] += 1;
        self.start[l - 1] = self.start[l] - self.len[l - 1];
    }
}

/// Ruge–Stüben first-pass C/F splitting: repeatedly make the undecided point
/// that strongly influences the most undecided points a C point and the points
/// it strongly influences F points, raising the weight of their other strong
/// influencers. As in PyAMG's `rs_cf_splitting`, a point of weight λ = 0 —
/// nothing undecided depends on it strongly — is not worth a coarse unknown:
/// it is left an F point, initially and once the largest weight is 0 (keeping
/// such points C made every level 5–35% larger than PyAMG's). Such an F point
/// may lack a strong C neighbour: [`direct_interpolation`] reaches it through
/// its strong neighbours. Returns `true` for C points.
pub fn cf_splitting(s: &[Vec<u32>]) -> Vec<bool> {
    #[derive(Clone, Copy, PartialEq)]
    enum State {
        Undecided,
        C,
        F,
    }
    let n = s.len();
    let st = transpose(s);
    let mut lambda: Vec<usize> = st.iter().map(Vec::len).collect();
    let mut buckets = Buckets::new(&lambda);
    let mut state: Vec<State> = lambda
        .iter()
        .map(|&l| if l == 0 { State::F } else { State::Undecided })
        .collect();
    let mut fine: Vec<u32> = Vec::new();
    for top in (0..n).rev() {
        let i = buckets.order[top] as usize;
        buckets.len[lambda[i]] -= 1;
        if lambda[i] == 0 {
            break;
        }
        if state[i] != State::Undecided {
            continue;
        }
        state[i] = State::C;
        fine.clear();
        fine.extend(
            st[i]
                .iter()
                .filter(|&&j| state[j as usize] == State::Undecided),
        );
        for &j in &fine {
            state[j as usize] = State::F;
        }
        for &j in &fine {
            for &k in &s[j as usize] {
                let k = k as usize;
                if state[k] == State::Undecided && lambda[k] + 1 < n {
                    buckets.raise(k, lambda[k]);
                    lambda[k] += 1;
                }
            }
        }
        for &j in &s[i] {
            let j = j as usize;
            if state[j] == State::Undecided && lambda[j] > 0 {
                buckets.lower(j, lambda[j]);
                lambda[j] -= 1;
            }
        }
    }
    state.into_iter().map(|x| x == State::C).collect()
}

/// Whether point i has a strong C neighbour to interpolate from directly.
fn strong_c(s: &[Vec<u32>], is_c: &[bool], i: usize) -> bool {
    s[i].iter().any(|&j| is_c[j as usize])
}

/// Makes C every F point that neither has a strong C neighbour nor a strong
/// neighbour that has one (isolated points, such as a connected component
/// coarsened to one unknown), in index order so that a new C point serves the
/// points after it: every other point is interpolated by
/// [`direct_interpolation`], so every row of P sums to one.
pub fn keep_interpolable(s: &[Vec<u32>], is_c: &mut [bool]) {
    for i in 0..is_c.len() {
        if !is_c[i] && !strong_c(s, is_c, i) && !s[i].iter().any(|&j| strong_c(s, is_c, j as usize))
        {
            is_c[i] = true;
        }
    }
}

/// Stüben's direct-interpolation weights of row i over the points `from`
/// selects: −α a_ij / a_ii (β for positive entries), α and β scaling the
/// selected couplings to all of row i's, so that the weights of a
/// zero-row-sum row sum to one — which keeps Ψ a partition of unity.
fn weights(a: &CsMat<f64>, i: usize, from: impl Fn(usize) -> bool) -> Vec<(usize, f64)> {
    let row = a.outer_view(i).expect("row in range");
    let (mut diag, mut all_neg, mut all_pos, mut c_neg, mut c_pos) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (j, &v) in row.iter() {
        if j == i {
            diag += v;
            continue;
        }
        let c = from(j);
        if v < 0.0 {
            all_neg += v;
            if c {
                c_neg += v;
            }
        } else {
            all_pos += v;
            if c {
                c_pos += v;
            }
        }
    }
    let alpha = if c_neg != 0.0 { all_neg / c_neg } else { 0.0 };
    let beta = if c_pos != 0.0 {
        all_pos / c_pos
    } else {
        diag += all_pos;
        0.0
    };
    if diag == 0.0 {
        return Vec::new();
    }
    row.iter()
        .filter(|&(j, _)| j != i && from(j))
        .map(|(j, &v)| {
            let w = if v < 0.0 { alpha } else { beta };
            (j, -w * v / diag)
        })
        .filter(|&(_, w)| w != 0.0)
        .collect()
}

/// Direct interpolation (Stüben): an F point takes its strong C neighbours'
/// values with the [`weights`] of row i. An F point without a strong C
/// neighbour (one of weight 0, see [`cf_splitting`]) gets what `orphans`
/// says: with [`Orphans::MultiPass`] it is interpolated in a second pass, as
/// in Stüben's multi-pass interpolation, from its strong neighbours that have
/// one, composing their interpolation: it stays inside the strong couplings (a
/// face of the octahedron, not across a crease) where PyAMG gives it a zero
/// row of P, and Ψ stays a partition of unity.
pub fn direct_interpolation(
    a: &CsMat<f64>,
    s: &[Vec<u32>],
    is_c: &[bool],
    orphans: Orphans,
) -> CsMat<f64> {
    let n = a.rows();
    let mut coarse = vec![u32::MAX; n];
    let mut nc = 0u32;
    for i in 0..n {
        if is_c[i] {
            coarse[i] = nc;
            nc += 1;
        }
    }
    let strong = |i: usize, j: usize| s[i].binary_search(&(j as u32)).is_ok();
    let direct: Vec<Vec<(u32, f64)>> = (0..n)
        .into_par_iter()
        .map(|i| {
            if is_c[i] {
                return vec![(coarse[i], 1.0)];
            }
            weights(a, i, |j| is_c[j] && strong(i, j))
                .into_iter()
                .map(|(j, w)| (coarse[j], w))
                .collect()
        })
        .collect();
    let second: Vec<(usize, Vec<(u32, f64)>)> = (0..n)
        .into_par_iter()
        .filter(|&i| orphans == Orphans::MultiPass && !is_c[i] && !strong_c(s, is_c, i))
        .map(|i| {
            let mut row: Vec<(u32, f64)> = weights(a, i, |j| strong(i, j) && strong_c(s, is_c, j))
                .into_iter()
                .flat_map(|(j, w)| direct[j].iter().map(move |&(c, v)| (c, w * v)))
                .collect();
            row.sort_unstable_by_key(|&(c, _)| c);
            row.dedup_by(|next, kept| {
                let same = next.0 == kept.0;
                if same {
                    kept.1 += next.1;
                }
                same
            });
            (i, row)
        })
        .collect();
    let mut rows = direct;
    for (i, row) in second {
        rows[i] = row;
    }
    // Rows are in column order: A's rows are, and `coarse` is increasing.
    let mut indptr = Vec::with_capacity(n + 1);
    indptr.push(0);
    let nnz = rows.iter().map(Vec::len).sum();
    let (mut indices, mut data) = (Vec::with_capacity(nnz), Vec::with_capacity(nnz));
    for row in &rows {
        for &(j, w) in row {
            indices.push(j as usize);
            data.push(w);
        }
        indptr.push(indices.len());
    }
    CsMat::new((n, nc as usize), indptr, indices, data)
}

/// Coarsens A level by level until at most `max_coarse` unknowns remain, the
/// coarsening stalls, or `max_levels` is reached.
pub fn coarsen(
    a: CsMat<f64>,
    opts: &RugeStuben,
    progress: &Progress,
) -> Result<Coarsening, Cancelled> {
    coarsen_watched(a, opts, progress, |_| {})
}

/// [`coarsen`], calling `level_made` with each level's C/F split as it is made
/// (level l + 1's unknowns are level l's C points, in index order).
pub fn coarsen_watched(
    a: CsMat<f64>,
    opts: &RugeStuben,
    progress: &Progress,
    mut level_made: impl FnMut(&[bool]),
) -> Result<Coarsening, Cancelled> {
    let mut operators = vec![a];
    let mut prolongations = Vec::new();
    while operators.len() < opts.max_levels {
        progress.check()?;
        let a = operators.last().expect("the fine level");
        if a.rows() <= opts.max_coarse {
            break;
        }
        let mut s = strength(a, opts.theta);
        s.par_iter_mut().for_each(|r| r.sort_unstable());
        let mut is_c = cf_splitting(&s);
        if opts.orphans == Orphans::MultiPass {
            keep_interpolable(&s, &mut is_c);
        }
        let nc = is_c.iter().filter(|&&c| c).count();
        if nc == 0 || nc == a.rows() {
            break;
        }
        let p = direct_interpolation(a, &s, &is_c, opts.orphans);
        let ac = galerkin(a, &p);
        prolongations.push(p);
        operators.push(ac);
        level_made(&is_c);
        progress.set_fraction(operators.len() as f32 / opts.max_levels as f32);
    }
    Ok(Coarsening {
        operators,
        prolongations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use sprs::TriMat;

    /// The 5-point Laplacian of an m×m grid (Neumann: zero row sums).
    fn grid_laplacian(m: usize) -> CsMat<f64> {
        let mut t = TriMat::new((m * m, m * m));
        for y in 0..m {
            for x in 0..m {
                let i = y * m + x;
                for (dx, dy) in [(1usize, 0usize), (0, 1)] {
                    if x + dx < m && y + dy < m {
                        let j = (y + dy) * m + x + dx;
                        t.add_triplet(i, j, -1.0);
                        t.add_triplet(j, i, -1.0);
                        t.add_triplet(i, i, 1.0);
                        t.add_triplet(j, j, 1.0);
                    }
                }
            }
        }
        t.to_csr()
    }

    #[test]
    fn splitting_is_a_valid_rs_split() {
        let a = grid_laplacian(20);
        let mut s = strength(&a, 0.25);
        s.iter_mut().for_each(|r| r.sort_unstable());
        let mut is_c = cf_splitting(&s);
        keep_interpolable(&s, &mut is_c);
        let nc = is_c.iter().filter(|&&c| c).count();
        // The 5-point stencil coarsens to a red–black-like half.
        assert!((150..=250).contains(&nc), "{nc} C points of 400");
        // Every F point has a strong C neighbour to interpolate from.
        for i in 0..400 {
            if !is_c[i] {
                assert!(
                    s[i].iter().any(|&j| is_c[j as usize]),
                    "F point {i} has no C neighbour"
                );
            }
        }
    }

    #[test]
    fn galerkin_levels_keep_symmetry_and_zero_row_sums_and_shrink() {
        let h = coarsen(grid_laplacian(30), &RugeStuben::default(), &Progress::new()).unwrap();
        let sizes = h.level_sizes();
        assert!(sizes.windows(2).all(|w| w[1] < w[0]), "{sizes:?}");
        assert!(*sizes.last().unwrap() <= 8 && sizes.len() >= 4, "{sizes:?}");
        for (l, a) in h.operators.iter().enumerate() {
            let dense = a.to_dense();
            let scale = dense.iter().fold(0f64, |m, v| m.max(v.abs()));
            for i in 0..a.rows() {
                let sum: f64 = dense.row(i).sum();
                assert!(sum.abs() <= 1e-9 * scale, "level {l} row {i} sums to {sum}");
                for j in 0..a.rows() {
                    assert!((dense[[i, j]] - dense[[j, i]]).abs() <= 1e-9 * scale);
                }
            }
        }
        // Interpolation reproduces constants: every row of P sums to one.
        for p in &h.prolongations {
            for (i, row) in p.outer_iterator().enumerate() {
                let sum: f64 = row.iter().map(|(_, v)| v).sum();
                assert!((sum - 1.0).abs() < 1e-9, "P row {i} sums to {sum}");
            }
        }
    }
}
