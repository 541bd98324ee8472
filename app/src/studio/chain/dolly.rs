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
