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

/// The viewport's direction framing `original` (never from wherever a
/// dolly, a zoom or the switch preview left the camera: a LOD seen from far
/// differs by nothing), then the fixed views around it.
pub(super) fn cameras(camera: Camera, original: &Scene) -> Vec<Camera> {
    let mut framing = camera;
    framing.frame(original.sphere(), SIZE[0] as f32 / SIZE[1] as f32);
    let mut cameras = vec![framing];
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
                wrong_colour: mean(|d| d.wrong_colour),
            },
            image: views[0].image.clone(),
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Wherever the dolly left the camera, the difference is measured from
    /// the same framing view in its direction (issue 46).
    #[test]
    fn the_difference_is_measured_from_the_framing_camera() {
        let original = Scene::from_mesh(&lodstudio_core::builtins::torus(1.0, 0.3, 24, 12));
        let mut near = Camera::default();
        near.frame(original.sphere(), 1.6);
        let mut far = near;
        far.distance *= 60.0;
        let (a, b) = (cameras(near, &original), cameras(far, &original));
        assert_eq!(a.len(), 1 + VIEWS);
        assert!(a[0].same_view(&b[0]), "{:?} vs {:?}", a[0], b[0]);
        assert!(a[0].distance < 10.0 * original.sphere().radius);
        let mut turned = near;
        turned.orbit(glam::Vec2::new(80.0, 0.0));
        assert!(
            !cameras(turned, &original)[0].same_view(&a[0]),
            "its direction kept"
        );
    }
}
