//! How the studio views and builds 3D Tiles tilesets: the viewer's maximum
//! screen-space error and the tile budget of a tileset built from a model.

use std::ops::RangeInclusive;

use serde::{Deserialize, Serialize};

use super::clamp_or;

/// Maximum screen-space errors, in pixels: from below a pixel (every tile
/// refined to what the screen can show) to a coarse preview.
pub const SSE_RANGE: RangeInclusive<f32> = 0.25..=64.0;

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TilesSettings {
    /// A tile is refined while its error covers more pixels than this
    /// (CesiumJS's `maximumScreenSpaceError`).
    pub max_sse_px: f32,
    /// Colour each drawn tile by its level rather than its materials.
    pub by_level: bool,
    /// Most original triangles of a leaf when the studio builds a tileset.
    pub tile_triangles: usize,
}

impl Default for TilesSettings {
    fn default() -> Self {
        TilesSettings {
            // CesiumJS's and 3d-tiles-renderer's default.
            max_sse_px: 16.0,
            by_level: true,
            tile_triangles: lodstudio_core::tiles::DEFAULT_TILE_TRIANGLES,
        }
    }
}

impl TilesSettings {
    /// Values out of range (an older or hand-edited session) replaced.
    pub fn sanitized(self) -> Self {
        let d = TilesSettings::default();
        let range = lodstudio_core::tiles::TILE_TRIANGLES;
        TilesSettings {
            max_sse_px: clamp_or(self.max_sse_px, SSE_RANGE, d.max_sse_px),
            by_level: self.by_level,
            tile_triangles: self.tile_triangles.clamp(*range.start(), *range.end()),
        }
    }
}
