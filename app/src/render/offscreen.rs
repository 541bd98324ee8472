//! Renders of a scene read back to the CPU, through the viewport's own
//! pipelines and shaders (`gpu`'s `ViewportResources`), so that what is measured is
//! what the studio shows: on the studio's device (eframe's render state), or
//! on a device of its own for the command line. Two scenes rendered from the
//! same cameras are compared pixel for pixel ([`Offscreen::compare`]).
//!
//! Coverage comes from alpha: the target is cleared to the viewport's
//! background with alpha 0 and surfaces write alpha 1, so after the
//! multisample resolve a pixel's alpha is the share of it the model covers; a
//! pixel counts as covered from one half on (what a single sample at its
//! centre would say). Translucent voxel layers add their own alpha.

use egui_wgpu::wgpu;
use lodstudio_core::distance::visual::{self, Difference, Render};
use lodstudio_core::lod::Texture;

use super::camera::{Camera, Sphere};
use super::gpu::{BACKGROUND, COLOR_FORMAT, FrameUniforms, ViewportResources};
use super::scene::Scene;

/// Rows of a texture-to-buffer copy are padded to this many bytes.
const ROW_ALIGN: u32 = wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;

/// A device and a set of the viewport's pipelines for rendering into memory.
pub struct Offscreen {
    device: wgpu::Device,
    queue: wgpu::Queue,
    resources: ViewportResources,
}

/// One view of two scenes compared.
#[derive(Debug, Clone)]
pub struct ViewComparison {
    pub camera: Camera,
    pub difference: Difference,
    /// Where they differ ([`visual::difference_image`]).
    pub image: Texture,
    /// The two renders and their difference, side by side.
    pub side_by_side: Texture,
}

/// Why an off-screen render did not give images.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RenderError {
    #[error("no GPU adapter to render with ({0}); WGPU_BACKEND chooses one")]
    NoAdapter(String),
    #[error("cannot open the GPU device ({0})")]
    NoDevice(String),
    #[error("the model is too large for this GPU's buffers")]
    TooLarge,
    #[error("no render target")]
    NoTarget,
    #[error("the GPU did not finish ({0})")]
    Unfinished(String),
    #[error("cannot read the render back ({0})")]
    ReadBack(String),
}

impl Offscreen {
    /// On the studio's device; its pipelines are its own, so the viewports'
    /// uploads and images are left alone.
    pub fn new(render_state: &egui_wgpu::RenderState) -> Self {
        Offscreen::on(
            render_state.device.clone(),
            render_state.queue.clone(),
            &render_state.adapter,
        )
    }

    /// On a device of its own (`WGPU_BACKEND` and `WGPU_POWER_PREF` choose as
    /// they do for the studio, which prefers a high-performance GPU too).
    ///
    /// # Errors
    /// When no adapter or device is available, saying so.
    pub fn headless() -> Result<Self, RenderError> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter =
            pollster::block_on(
                instance.request_adapter(&wgpu::RequestAdapterOptions {
                    power_preference: wgpu::PowerPreference::from_env()
                        .unwrap_or(wgpu::PowerPreference::HighPerformance),
                    ..Default::default()
                }),
            )
            .map_err(|e| RenderError::NoAdapter(e.to_string()))?;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("lodstudio offscreen"),
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| RenderError::NoDevice(e.to_string()))?;
        Ok(Offscreen::on(device, queue, &adapter))
    }

    fn on(device: wgpu::Device, queue: wgpu::Queue, adapter: &wgpu::Adapter) -> Self {
        // Nothing is blitted: the blit's format is moot.
        let resources = ViewportResources::new(&device, adapter, COLOR_FORMAT);
        Offscreen {
            device,
            queue,
            resources,
        }
    }

    /// `scene` seen by each of `cameras` in images of `size` pixels, with the
    /// near and far planes around `clip` (give two scenes that are compared
    /// the same one). Waits for the GPU: the studio calls it from a worker.
    ///
    /// # Errors
    /// When the scene does not fit the device's buffers, or a read-back fails.
    pub fn render(
        &mut self,
        scene: &Scene,
        cameras: &[Camera],
        clip: Sphere,
        size: [u32; 2],
    ) -> Result<Vec<Render>, RenderError> {
        let (device, queue, res) = (&self.device, &self.queue, &mut self.resources);
        res.ensure_target(device, size);
        if !res.upload(device, queue, Some(scene)) {
            return Err(RenderError::TooLarge);
        }
        let Some(target) = &res.target else {
            return Err(RenderError::NoTarget);
        };
        let [w, h] = target.size;
        let row = (4 * w).next_multiple_of(ROW_ALIGN);
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("offscreen read-back"),
            size: u64::from(row) * u64::from(h),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let transparent = wgpu::Color {
            a: 0.0,
            ..BACKGROUND
        };
        let aspect = w as f32 / h as f32;
        let mut renders = Vec::with_capacity(cameras.len());
        for camera in cameras {
            let uniforms = FrameUniforms::new(camera, aspect, clip, [w, h], 1.0);
            queue.write_buffer(&res.uniform_buffer, 0, bytemuck::bytes_of(&uniforms));
            let mut encoder = device.create_command_encoder(&Default::default());
            res.render(&mut encoder, transparent);
            encoder.copy_texture_to_buffer(
                target.color.texture().as_image_copy(),
                wgpu::TexelCopyBufferInfo {
                    buffer: &readback,
                    layout: wgpu::TexelCopyBufferLayout {
                        offset: 0,
                        bytes_per_row: Some(row),
                        rows_per_image: Some(h),
                    },
                },
                wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
            );
            queue.submit([encoder.finish()]);
            renders.push(read_back(device, &readback, [w, h], row)?);
        }
        Ok(renders)
    }

    /// Scenes `a` and `b` rendered from the same `cameras` (near and far
    /// planes around both) and compared view by view.
    ///
    /// # Errors
    /// As [`Offscreen::render`].
    pub fn compare(
        &mut self,
        a: &Scene,
        b: &Scene,
        cameras: &[Camera],
        size: [u32; 2],
    ) -> Result<Vec<ViewComparison>, RenderError> {
        let clip = a.sphere().enclosing(b.sphere());
        let first = self.render(a, cameras, clip, size)?;
        let second = self.render(b, cameras, clip, size)?;
        Ok(cameras
            .iter()
            .zip(first.iter().zip(&second))
            .map(|(camera, (x, y))| {
                let image = visual::difference_image(x, y);
                ViewComparison {
                    camera: *camera,
                    difference: visual::difference(x, y),
                    side_by_side: beside(&[&x.image, &y.image, &image]),
                    image,
                }
            })
            .collect())
    }
}

/// Images of one height side by side, left to right.
fn beside(images: &[&Texture]) -> Texture {
    let height = images.iter().map(|t| t.height).max().unwrap_or(0);
    let width = images.iter().map(|t| t.width).sum();
    let mut rgba = Vec::with_capacity((width * height) as usize);
    for y in 0..height {
        for t in images {
            let start = (y * t.width) as usize;
            match t.rgba.get(start..start + t.width as usize) {
                Some(row) => rgba.extend_from_slice(row),
                None => rgba.extend(std::iter::repeat_n([0, 0, 0, 255], t.width as usize)),
            }
        }
    }
    Texture {
        width,
        height,
        rgba,
    }
}

/// The mapped image in `buffer` (rows `row` bytes apart) as a render: opaque
/// pixels, and coverage from alpha.
fn read_back(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    [w, h]: [u32; 2],
    row: u32,
) -> Result<Render, RenderError> {
    let (tx, rx) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |r| {
        let _ = tx.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| RenderError::Unfinished(e.to_string()))?;
    rx.recv()
        .map_err(|e| e.to_string())
        .and_then(|r| r.map_err(|e| e.to_string()))
        .map_err(RenderError::ReadBack)?;
    let mut rgba = Vec::with_capacity((w * h) as usize);
    let mut coverage = Vec::with_capacity((w * h) as usize);
    {
        let bytes = buffer
            .get_mapped_range(..)
            .map_err(|e| RenderError::ReadBack(e.to_string()))?;
        for line in bytes.chunks_exact(row as usize) {
            for p in line[..(4 * w) as usize].chunks_exact(4) {
                rgba.push([p[0], p[1], p[2], 255]);
                coverage.push(p[3] >= 128);
            }
        }
    }
    buffer.unmap();
    Ok(Render {
        image: Texture {
            width: w,
            height: h,
            rgba,
        },
        coverage,
    })
}
