//! The studio's 3D view, by concept:
//!
//! - [`scene`]: models, cuts and previews as GPU-ready geometry (CPU only, tested);
//! - `texture`: materials' base-colour images, decoded once per image;
//! - [`camera`]: the orbit / fly camera, its matrices and rays (tested);
//! - [`gpu`]: pipelines, buffers, uploads and the offscreen render;
//! - [`offscreen`]: the same render read back to memory, and two scenes compared;
//! - [`viewport`]: the egui widget that ties them together;
//! - `shaders/`: the WGSL, with the frame's uniforms and shading written once.

pub mod camera;
mod gpu;
pub mod offscreen;
pub mod scene;
mod texture;
pub mod viewport;

pub use camera::Camera;
pub use gpu::init;
pub use offscreen::{Offscreen, ViewComparison};
pub use scene::{Scene, SceneStyle};
pub use viewport::Viewport;
