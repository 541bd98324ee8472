//! The visual difference: every LOD of the chain against the original,
//! rendered off-screen by the viewport's renderer.

use std::sync::Arc;

use lodstudio_core::Progress;
use lodstudio_core::distance::visual::Difference;
use lodstudio_core::lod::Texture;

use super::ChainError;
use crate::render::{Camera, Offscreen, Scene};

/// The fixed views around the model, and the size of every view.
const VIEWS: usize = 8;
const SIZE: [u32; 2] = [256, 256];

/// One LOD against the original, rendered by the viewport's renderer from
/// the camera and from the fixed views around the model.
#[derive(Debug, Clone)]
pub struct LodDifference {
    /// From the viewport's camera.
    pub here: Difference,
    /// The means over the fixed views.
    pub around: Difference,
    /// Where they differ from the viewport's camera (red: only the original
    /// covers, green: only the LOD, else the shading's difference × 4).
    pub image: Texture,
}

/// The viewport's camera, then the fixed views around `original`.
pub(super) fn cameras(camera: Camera, original: &Scene) -> Vec<Camera> {
    let mut cameras = vec![camera];
    cameras.extend(Camera::views_around(original.sphere(), VIEWS, 1.0));
    cameras
}

/// Compares each of `lods` with `original` from `cameras` (see [`cameras`]).
pub(super) fn measure(
    offscreen: &mut Offscreen,
    original: &Scene,
    lods: &[Arc<Scene>],
    cameras: &[Camera],
    progress: &Progress,
) -> Result<Vec<LodDifference>, ChainError> {
    progress.stage("visual difference");
    let mut out = Vec::with_capacity(lods.len());
    for (k, lod) in lods.iter().enumerate() {
        progress.check()?;
        progress.set_fraction(k as f32 / lods.len() as f32);
        let views = offscreen.compare(original, lod, cameras, SIZE)?;
        let around = &views[1..];
        let mean = |f: fn(&Difference) -> f64| {
            around.iter().map(|v| f(&v.difference)).sum::<f64>() / around.len() as f64
        };
        out.push(LodDifference {
            here: views[0].difference,
            around: Difference {
                silhouette: mean(|d| d.silhouette),
                psnr: mean(|d| d.psnr),
            },
            image: views[0].image.clone(),
        });
    }
    Ok(out)
}
