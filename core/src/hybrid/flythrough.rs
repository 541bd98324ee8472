//! The fly-through of Fig. 10–11: N instances of a model laid out over the
//! ground, a camera that starts far away and flies through the scene, and per
//! frame the primitives (triangles + points/κ) of screen-space cuts.
//! Instances are translated copies, so each one's cut is taken for the camera
//! moved into its own frame; every instance keeps its cut between frames
//! (incremental adaptation). An instance outside the view frustum is not
//! drawn at all (scene-level culling), so it counts no primitives.

use std::sync::Arc;

use glam::Vec3;

use super::cut::HybridCut;
use super::mrg::Mrg;
use crate::geom::Aabb;
use crate::view::{Tolerance, View};

/// Offsets of `instances` copies of a model with bounds `b` on a square grid
/// over the ground (the XZ plane, Y up), 1.5 model widths apart.
pub fn layout(b: &Aabb, instances: usize) -> Vec<Vec3> {
    let side = (instances as f64).sqrt().ceil().max(1.0) as usize;
    let e = b.extent();
    let spacing = 1.5 * e.x.max(e.z).max(1e-6);
    (0..instances)
        .map(|i| {
            Vec3::new(
                (i % side) as f32 * spacing,
                0.0,
                (i / side) as f32 * spacing,
            )
        })
        .collect()
}

/// A camera path of `frames` views: it starts four scene widths in front of
/// the scene and flies straight along +Z at half the model's height, between
/// two columns of instances, into the scene up to just past its middle
/// (where the viewer is surrounded by it).
pub fn camera_path(b: &Aabb, offsets: &[Vec3], frames: usize) -> Vec<View> {
    let scene = offsets.iter().fold(Aabb::EMPTY, |s, o| {
        s.union(Aabb {
            min: b.min + *o,
            max: b.max + *o,
        })
    });
    let width = scene.extent().x.max(scene.extent().z);
    let side = (offsets.len() as f64).sqrt().ceil().max(1.0) as usize;
    let spacing = if offsets.len() > 1 {
        offsets[1].x - offsets[0].x
    } else {
        width
    };
    // Between two columns near the middle of the scene.
    let x = b.center().x + ((side.saturating_sub(1)) / 2) as f32 * spacing + 0.5 * spacing;
    let y = b.min.y + 0.5 * b.extent().y;
    let (z0, z1) = (
        scene.min.z - 4.0 * width,
        scene.center().z + 0.1 * scene.extent().z,
    );
    (0..frames)
        .map(|i| {
            let t = i as f32 / frames.saturating_sub(1).max(1) as f32;
            let eye = Vec3::new(x, y, z0 + (z1 - z0) * t);
            let mut v = View::orbit(eye, 1.0, 0.0, 0.0);
            v.eye = eye;
            v.target = eye + Vec3::new(0.0, -0.05, 1.0);
            v.light_dir = Vec3::Y;
            v
        })
        .collect()
}

/// Primitives of one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameCount {
    pub triangles: usize,
    pub points: usize,
    /// triangles + points/κ (§5.3).
    pub primitives: f64,
}

/// Per frame, the primitives of every instance's cut at `pixels`.
pub fn frame_counts(
    mrg: &Arc<Mrg>,
    offsets: &[Vec3],
    views: &[View],
    pixels: f32,
) -> Vec<FrameCount> {
    let mut cuts: Vec<HybridCut> = offsets
        .iter()
        .map(|_| HybridCut::new(Arc::clone(mrg)))
        .collect();
    views
        .iter()
        .map(|view| {
            let mut f = FrameCount {
                triangles: 0,
                points: 0,
                primitives: 0.0,
            };
            let sphere = mrg.nodes[mrg.source() as usize].sphere;
            for (cut, o) in cuts.iter_mut().zip(offsets) {
                if !view.sees_sphere(sphere.center + *o, sphere.radius) {
                    continue;
                }
                let local = View {
                    eye: view.eye - *o,
                    target: view.target - *o,
                    ..*view
                };
                cut.adapt(&local, Tolerance::Pixels(pixels));
                let (t, p) = cut.counts();
                f.triangles += t;
                f.points += p;
            }
            f.primitives = f.triangles as f64 + f.points as f64 / mrg.kappa.max(1.0) as f64;
            f
        })
        .collect()
}

/// Mean, min and max of `a[i] / b[i]` over the frames.
pub fn ratios(a: &[FrameCount], b: &[FrameCount]) -> (f64, f64, f64) {
    let r: Vec<f64> = a
        .iter()
        .zip(b)
        .map(|(x, y)| x.primitives / y.primitives.max(1e-9))
        .collect();
    let mean = r.iter().sum::<f64>() / r.len().max(1) as f64;
    let min = r.iter().copied().fold(f64::INFINITY, f64::min);
    let max = r.iter().copied().fold(0.0, f64::max);
    (mean, min, max)
}
