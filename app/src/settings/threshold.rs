//! The error threshold of live cuts: pixels through the camera, or a
//! fraction of the bounding-box diagonal (DESIGN.md's tolerance).

use std::ops::RangeInclusive;

use lodstudio_core::view::Tolerance;
use serde::{Deserialize, Serialize};

use super::clamp_or;

/// Screen-space thresholds, in pixels: the slider is logarithmic, so its
/// travel spans what is useful (below a tenth of a pixel no cut differs
/// from the finest on screen).
pub const PIXELS_RANGE: RangeInclusive<f32> = 0.1..=64.0;
/// Object-space thresholds, in percent of the bounding-box diagonal (the
/// finest certified bounds are about 0.01 %).
pub const PERCENT_RANGE: RangeInclusive<f32> = 0.01..=20.0;

/// The error threshold of a cut, as the slider sets it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Threshold {
    /// Screen space (pixels) rather than object space (% of the diagonal).
    pub in_pixels: bool,
    pub percent: f32,
    pub pixels: f32,
}

impl Default for Threshold {
    fn default() -> Self {
        Threshold {
            in_pixels: true,
            percent: 1.0,
            pixels: 2.0,
        }
    }
}

impl Threshold {
    /// The tolerance a cut is selected with.
    pub fn tolerance(&self) -> Tolerance {
        if self.in_pixels {
            Tolerance::Pixels(self.pixels)
        } else {
            Tolerance::Relative(self.percent / 100.0)
        }
    }

    /// Values out of range (an older or hand-edited settings file) replaced.
    pub fn sanitized(self) -> Self {
        let d = Threshold::default();
        Threshold {
            in_pixels: self.in_pixels,
            percent: clamp_or(self.percent, PERCENT_RANGE, d.percent),
            pixels: clamp_or(self.pixels, PIXELS_RANGE, d.pixels),
        }
    }
}
