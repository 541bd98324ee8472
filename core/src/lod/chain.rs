//! The LOD chain: which cut each LOD is, and where each takes over. Any
//! hierarchy gives an LOD for an error (its coarsest cut within it) or for a
//! primitive budget (its finest cut within it); an LOD's switch point comes
//! from its certified bound: it is shown while the next coarser LOD's bound
//! would project to more than the tolerance in pixels (`MSFT_screencoverage`
//! in the exported GLB).

use super::{DrawSet, Hierarchy};
use crate::view::{Tolerance, View};

/// What one LOD of a chain asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ChainItem {
    /// An error bound, as a fraction of the bounding-box diagonal.
    Error(f32),
    /// At most this many primitives.
    Primitives(usize),
}

/// The LOD `item` asks of `hierarchy` (cut for `view`): the hierarchy's own
/// choice within an error; within a budget, its own where its cuts form one
/// sequence (edge collapse), else the cut at the least relative tolerance
/// that keeps to it.
pub fn choose(hierarchy: &mut dyn Hierarchy, view: &View, item: ChainItem) -> DrawSet {
    match item {
        ChainItem::Error(f) => hierarchy.select(view, Tolerance::Relative(f)),
        ChainItem::Primitives(n) => match hierarchy.select_triangles(n) {
            Some(set) => set,
            None => finest_within(hierarchy, view, |s| s.primitive_count() <= n),
        },
    }
}

/// The cut at the least relative tolerance whose cut `fits` (bisected to
/// 2⁻²⁴ of the diagonal), or the coarsest cut if none does.
pub(super) fn finest_within(
    hierarchy: &mut dyn Hierarchy,
    view: &View,
    fits: impl Fn(&DrawSet) -> bool,
) -> DrawSet {
    let mut cut = |f: f32| hierarchy.select(view, Tolerance::Relative(f));
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    let mut best = cut(hi);
    if !fits(&best) {
        return best;
    }
    for _ in 0..24 {
        let mid = 0.5 * (lo + hi);
        let set = cut(mid);
        if fits(&set) {
            (hi, best) = (mid, set);
        } else {
            lo = mid;
        }
    }
    best
}

/// The `MSFT_screencoverage` thresholds of an LOD chain.
///
/// `error_bounds[i]` is LOD i's guaranteed (object-space) error bound, in
/// increasing order; `radius` is the object's bounding-sphere radius; the
/// tolerance is `pixels` on a viewport `viewport_height` pixels high.
///
/// The screen coverage `c` is the object's projected height (its bounding
/// sphere's diameter) as a fraction of the viewport height. With a vertical
/// field of view θ at distance d, a length `l` covers `l·H / (2 d tan(θ/2))`
/// pixels, so `c = 2r / (2 d tan(θ/2))` and an error bound `e` covers
/// `e·H·c / (2r)` pixels: it stays within `p` pixels exactly while
///
/// ```text
/// c <= c(e) = 2 r p / (e H)        (independent of θ and d)
/// ```
///
/// A loader shows LOD i while the coverage is at least `coverages[i]` (and
/// below `coverages[i-1]`), so LOD i+1 may take over once LOD i+1's bound
/// projects within the tolerance: `coverages[i] = c(e[i+1])`. The last value is
/// `p / H`, where the whole object spans `p` pixels (below it, leaving the
/// object out stays within the tolerance). Values are clamped to (0, 1] and
/// made strictly decreasing by lowering, never raising, a value, which only
/// keeps a finer LOD longer; so every shown LOD's bound projects to at most
/// `p` pixels (LOD0 excepted above `c(e[0])`, as nothing finer exists).
pub fn lod_screen_coverages(
    error_bounds: &[f32],
    radius: f32,
    pixels: f32,
    viewport_height: f32,
) -> Vec<f32> {
    let n = error_bounds.len();
    let mut out: Vec<f32> = Vec::with_capacity(n);
    for i in 0..n {
        let raw = switch_out(error_bounds, i, radius, pixels, viewport_height);
        let mut c = raw as f32;
        if let Some(&prev) = out.last() {
            c = c.min(prev * (1.0 - 1e-4));
        }
        if c.is_nan() || c <= 0.0 {
            // Degenerate input (zero radius or pixels): keep the order positive.
            c = out.last().map_or(1.0, |prev| prev * 0.5);
        }
        out.push(c);
    }
    out
}

/// `c(e) = 2 r p / (e H)` ([`lod_screen_coverages`]), clamped to [0, 1]:
/// a loader's thresholds end at the object filling the viewport.
fn coverage(e: f32, radius: f32, pixels: f32, viewport_height: f32) -> f64 {
    let c = 2.0 * radius as f64 * pixels as f64 / (e as f64 * viewport_height as f64);
    if c.is_nan() { 1.0 } else { c.clamp(0.0, 1.0) }
}

/// Where LOD `i` would switch out before the thresholds are made strictly
/// decreasing: `c(e[i+1])`, or `p / H` for the last.
fn switch_out(error_bounds: &[f32], i: usize, radius: f32, pixels: f32, height: f32) -> f64 {
    match error_bounds.get(i + 1) {
        Some(&e) => coverage(e, radius, pixels, height),
        None => (pixels as f64 / height as f64).clamp(0.0, 1.0),
    }
}

/// Which LODs of a chain no loader ever shows ([`lod_screen_coverages`]'s
/// arguments): LOD i > 0 takes over at `c(e[i])` and hands over at
/// `c(e[i+1])`, so it is never drawn when these are equal: the next LOD's
/// bound is no larger (the same within the clamp to a full viewport), or,
/// for the last, its bound spans the whole object (`e >= 2r`: leaving the
/// object out is as good). The strict thresholds still give such an LOD a
/// sliver of coverage (1e-4 of it), not a place a viewer can see.
pub fn never_shown(
    error_bounds: &[f32],
    radius: f32,
    pixels: f32,
    viewport_height: f32,
) -> Vec<bool> {
    (0..error_bounds.len())
        .map(|i| {
            i > 0 && {
                let switch_in = coverage(error_bounds[i], radius, pixels, viewport_height);
                switch_in <= switch_out(error_bounds, i, radius, pixels, viewport_height)
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A budget takes the finest cut within it; an error the coarsest.
    #[test]
    fn budgets_and_errors_choose_from_any_hierarchy() {
        let mesh = crate::builtins::torus(1.0, 0.3, 32, 16);
        let p = crate::simplify::progressive::record(
            &mesh,
            Default::default(),
            50,
            &Default::default(),
        );
        let mut h =
            crate::simplify::progressive::ProgressiveCut::new(std::sync::Arc::new(p.unwrap()));
        let view = View::orbit(glam::Vec3::ZERO, 4.0, 0.2, 0.3);
        let within = choose(&mut h, &view, ChainItem::Primitives(300));
        assert!(within.primitive_count() <= 300 && within.primitive_count() > 150);
        let coarse = choose(&mut h, &view, ChainItem::Error(0.05));
        assert!(coarse.error_bound <= 0.05 * h.diagonal());
        let finer = choose(&mut h, &view, ChainItem::Error(0.01));
        assert!(finer.primitive_count() > coarse.primitive_count());
    }

    #[test]
    fn screen_coverage_is_where_the_next_bound_projects_to_the_tolerance() {
        // r = 1, p = 2 px, H = 1000: c(e) = 2·1·2 / (e·1000) = 0.004 / e.
        let c = lod_screen_coverages(&[0.001, 0.01, 0.1], 1.0, 2.0, 1000.0);
        assert_eq!(c.len(), 3);
        assert!((c[0] - 0.4).abs() < 1e-6, "{c:?}");
        assert!((c[1] - 0.04).abs() < 1e-6, "{c:?}");
        assert!((c[2] - 0.002).abs() < 1e-6, "{c:?}");
        // At coverage c[0], LOD1's bound projects to exactly p pixels:
        // pixels = e·H·c / (2r).
        assert!((0.01 * 1000.0 * c[0] / 2.0 - 2.0).abs() < 1e-4);
        // Zero bounds, equal bounds and huge bounds: clamped, strictly decreasing, positive.
        let c = lod_screen_coverages(&[0.0, 0.0, 0.5, 0.5, 1e9], 1.0, 1.0, 1080.0);
        assert!(c.iter().all(|v| *v > 0.0 && *v <= 1.0), "{c:?}");
        assert!(c.windows(2).all(|w| w[1] < w[0]), "{c:?}");
        // LODs 1 and 3 hand over where they take over (3: its bound spans the object).
        let never = never_shown(&[0.0, 0.5, 0.5, 3.0], 1.0, 1.0, 1080.0);
        assert_eq!(never, [false, true, false, true]);
        // Both within the clamp to a full viewport (c(e) = 2/(e·1080) > 1).
        assert_eq!(
            never_shown(&[0.0, 1e-4, 1e-3], 1.0, 1.0, 1080.0),
            [false, true, false]
        );
        // Each LOD that is shown keeps a coverage interval a viewer can reach.
        let bounds = [0.0, 0.01, 0.02, 0.5];
        let c = lod_screen_coverages(&bounds, 1.0, 1.0, 1080.0);
        for (k, never) in never_shown(&bounds, 1.0, 1.0, 1080.0)
            .into_iter()
            .enumerate()
        {
            assert!(never || k == 0 || c[k - 1] / c[k] > 1.01, "{k}: {c:?}");
        }
        let c = lod_screen_coverages(&[0.1, 0.2], 0.0, 1.0, 1080.0);
        assert!(
            c.iter().all(|v| *v > 0.0 && *v <= 1.0) && c[1] < c[0],
            "{c:?}"
        );
    }
}
