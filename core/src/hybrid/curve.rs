//! Primitives versus error (Fig. 7–9): for every object-space tolerance e,
//! the primitives (triangles + points/κ) on the cut at e. Errors never
//! decrease upwards, so an arc is on that cut exactly while its producer's
//! error ≤ e < its consumer's: the curve is a step function swept from the
//! arcs' intervals, exact at every node error.

use super::mrg::Mrg;

/// `(error, primitives)` at each error where the count changes, increasing in
/// error: the primitives hold from that error up to the next one.
pub fn curve(mrg: &Mrg) -> Vec<(f32, f64)> {
    let mut events: Vec<(f32, f64)> = Vec::with_capacity(2 * mrg.arcs.len());
    for a in &mrg.arcs {
        let (lo, hi) = (
            mrg.nodes[a.producer as usize].error,
            mrg.nodes[a.consumer as usize].error,
        );
        if lo < hi {
            let w = mrg.arc_primitives(a);
            events.push((lo, w));
            if hi.is_finite() {
                events.push((hi, -w));
            }
        }
    }
    events.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut out: Vec<(f32, f64)> = Vec::new();
    let mut total = 0.0;
    for group in events.chunk_by(|x, y| x.0 == y.0) {
        total += group.iter().map(|e| e.1).sum::<f64>();
        out.push((group[0].0, total.max(0.0)));
    }
    out
}

/// Primitives at tolerance `error` (the input's count below the first step).
pub fn primitives_at(curve: &[(f32, f64)], error: f32, input: f64) -> f64 {
    match curve.partition_point(|p| p.0 <= error) {
        0 => input,
        i => curve[i - 1].1,
    }
}

/// At most about `steps` points for output: a point is kept when the count
/// moved by more than `1/steps` of the log range since the last one kept.
pub fn thin(curve: &[(f32, f64)], steps: usize) -> Vec<[f64; 2]> {
    let (Some(first), Some(last)) = (curve.first(), curve.last()) else {
        return Vec::new();
    };
    let range = (first.1.max(1.0) / last.1.max(1.0)).ln().abs().max(1e-9);
    let step = range / steps.max(1) as f64;
    let mut out = vec![[first.0 as f64, first.1]];
    for p in &curve[1..] {
        let prev = out[out.len() - 1][1];
        if (prev.max(1e-9) / p.1.max(1e-9)).ln().abs() >= step {
            out.push([p.0 as f64, p.1]);
        }
    }
    if out[out.len() - 1][0] != last.0 as f64 {
        out.push([last.0 as f64, last.1]);
    }
    out
}

/// Largest ratio of `a`'s primitives over `b`'s at any error where both are
/// defined (`a` nowhere above `b` by more than this factor).
pub fn worst_ratio(a: &[(f32, f64)], b: &[(f32, f64)], input: f64) -> f64 {
    a.iter()
        .chain(b)
        .map(|(e, _)| primitives_at(a, *e, input) / primitives_at(b, *e, input).max(1e-9))
        .fold(0.0, f64::max)
}
