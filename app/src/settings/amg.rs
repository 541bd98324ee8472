//! Parameters of extreme point-set simplification with algebraic multigrid
//! (AMG paper): the neighbourhood size k (§2.1), the level drawn (§2.3) and
//! the texel size of the domain primitives' textures (§3.2).

use std::ops::RangeInclusive;

pub use lodstudio_core::amg::TEXEL_SCALE_RANGE as TEXEL_RANGE;
use lodstudio_core::amg::{AmgParams, DEFAULT_TEXEL_SPACINGS, K_RANGE, Texel};
use serde::{Deserialize, Serialize};

use super::clamp_or;

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
            k: AmgParams::default().k,
            texel: DEFAULT_TEXEL_SPACINGS,
            level: 3,
            // The threshold chooses the level unless the user pins one.
            auto_level: true,
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
    pub fn params(&self) -> AmgParams {
        let s = self.sanitized();
        AmgParams {
            k: s.k,
            texel: Texel::Spacings(s.texel),
            ..Default::default()
        }
    }

    /// The level to draw (`None`: the threshold chooses), the live cut's knob.
    pub fn runtime_level(&self) -> Option<usize> {
        (!self.auto_level).then_some(self.level)
    }
}
