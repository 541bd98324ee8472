//! Parameters of extreme point-set simplification with algebraic multigrid
//! (AMG paper): the neighbourhood size k (§2.1), the level drawn (§2.3) and
//! the texel size of the domain primitives' textures (§3.2).

use std::ops::RangeInclusive;

use lodstudio_core::amg::K_RANGE;
use serde::{Deserialize, Serialize};

use super::clamp_or;

pub const TEXEL_RANGE: RangeInclusive<f32> = 0.25..=8.0;
pub const LEVEL_RANGE: RangeInclusive<usize> = 0..=24;

/// Everything the AMG decomposition needs besides the points.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AmgSettings {
    pub k: usize,
    /// Texel size in median point spacings.
    pub texel: f32,
    /// Run time: the level drawn, unless the threshold chooses it.
    pub level: usize,
    pub auto_level: bool,
}

impl Default for AmgSettings {
    fn default() -> Self {
        AmgSettings {
            k: lodstudio_core::amg::AmgOptions::default().k,
            texel: 1.0,
            level: 3,
            auto_level: false,
        }
    }
}

impl AmgSettings {
    pub fn sanitized(self) -> Self {
        let d = Self::default();
        AmgSettings {
            k: self.k.clamp(*K_RANGE.start(), *K_RANGE.end()),
            texel: clamp_or(self.texel, TEXEL_RANGE, d.texel),
            level: self.level.min(*LEVEL_RANGE.end()),
            auto_level: self.auto_level,
        }
    }

    /// What a build depends on (the level is chosen at run time).
    pub fn build_params(self) -> Self {
        AmgSettings {
            level: 0,
            auto_level: false,
            ..self.sanitized()
        }
    }

    /// The level to draw (`None`: the threshold chooses), the live cut's knob.
    pub fn runtime_level(&self) -> Option<usize> {
        (!self.auto_level).then_some(self.level)
    }
}
