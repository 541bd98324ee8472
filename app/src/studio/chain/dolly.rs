//! The switch preview's dolly: the camera from near to far through every
//! switch of the chain, as a function of time alone (so frames that come
//! late skip ahead rather than slow it down).

use crate::render::camera::distance_at_coverage;

/// Seconds the dolly takes from near to far.
pub const SECONDS: f64 = 6.0;

/// The preview's distances (bounding radii) for a chain switching at
/// `coverages`: from filling the screen to twice as far as the last switch.
pub fn range(coverages: &[f32]) -> (f32, f32) {
    let near = distance_at_coverage(1.0);
    let last = coverages.last().copied().unwrap_or(1.0);
    (near, distance_at_coverage(0.5 * last).max(2.0 * near))
}

/// The dolly's distance (bounding radii) `elapsed` seconds after it started,
/// geometric from near to far so each switch takes its share of the time,
/// and whether it has arrived.
pub fn distance(elapsed: f64, (near, far): (f32, f32)) -> (f32, bool) {
    let t = (elapsed / SECONDS).clamp(0.0, 1.0) as f32;
    (near * (far / near).powf(t), t >= 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// From near at the start to far at [`SECONDS`], always moving away,
    /// arriving only at the end, and staying within its range outside it.
    #[test]
    fn the_dolly_moves_away_from_near_to_far_in_its_time() {
        let (near, far) = range(&[0.5, 0.1, 0.02]);
        assert!(near < far);
        assert_eq!(distance(0.0, (near, far)), (near, false));
        assert_eq!(distance(-1.0, (near, far)), (near, false));
        let mut last = near;
        for step in 1..60 {
            let (d, arrived) = distance(SECONDS * step as f64 / 60.0, (near, far));
            assert!(d > last && d < far && !arrived, "step {step}: {d}");
            last = d;
        }
        let (end, arrived) = distance(SECONDS, (near, far));
        assert!(arrived && (end - far).abs() <= 1e-5 * far, "{end} vs {far}");
        assert_eq!(distance(2.0 * SECONDS, (near, far)), (end, true));
    }

    /// The far end lies beyond the last switch, where a loader leaves the
    /// model out, so the dolly shows every LOD.
    #[test]
    fn the_range_passes_the_last_switch() {
        let coverages = [0.5, 0.1, 0.02];
        let (near, far) = range(&coverages);
        assert!(far > distance_at_coverage(0.02));
        assert!(near <= distance_at_coverage(0.5));
    }
}
