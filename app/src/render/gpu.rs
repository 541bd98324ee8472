//! The GPU side of the viewport: pipelines and buffers per viewport slot,
//! uploads when the scene's version changes, and the render into an offscreen
//! target that egui's pass then shows (and that [`super::offscreen`] reads back).
//!
//! egui's render pass has no depth buffer, so [`CallbackTrait::prepare`] renders
//! the scene into an offscreen colour + depth target of our own (sized to the
//! viewport in physical pixels, multisampled where the adapter allows), and
//! [`CallbackTrait::paint`] copies that image into egui's pass with a
//! full-screen triangle. GPU resources live in the renderer's
//! `callback_resources` (created once by [`init`]); geometry is uploaded only
//! when the scene's version changes, into buffers that grow but are reused.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use bytemuck::{Pod, Zeroable};
use egui_wgpu::{CallbackResources, CallbackTrait, ScreenDescriptor, wgpu};

use super::camera::{Camera, Sphere};
use super::scene::{
    Atlas, Geometry, MeshVertex, PointInstance, Scene, SplatVertex, TexturedVertex,
};
use super::viewport::SLOTS;

/// Background of the viewport (linear RGB).
pub(super) const BACKGROUND: wgpu::Color = wgpu::Color {
    r: 0.045,
    g: 0.050,
    b: 0.060,
    a: 1.0,
};

/// On-screen radius of points that carry no radius of their own.
const POINT_RADIUS_PX: f32 = 2.5;

pub(super) const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// Per-frame uniforms; the layout matches `Frame` in the shader.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub(super) struct FrameUniforms {
    view_proj: [[f32; 4]; 4],
    /// xyz: camera position.
    eye: [f32; 4],
    /// Viewport width and height in pixels, focal length in pixels, default point radius.
    viewport: [f32; 4],
}

impl FrameUniforms {
    /// What the shaders need of `camera` for an image of `size_px` showing
    /// `scene` at `pixels_per_point`.
    pub(super) fn new(
        camera: &Camera,
        aspect: f32,
        scene: Sphere,
        size_px: [u32; 2],
        pixels_per_point: f32,
    ) -> Self {
        FrameUniforms {
            view_proj: camera.view_proj(aspect, scene).to_cols_array_2d(),
            eye: camera.eye().extend(1.0).to_array(),
            viewport: [
                size_px[0] as f32,
                size_px[1] as f32,
                Camera::focal_px(size_px[1]),
                POINT_RADIUS_PX * pixels_per_point,
            ],
        }
    }
}

/// The GPU resources of each viewport slot.
struct Slots(Vec<ViewportResources>);

/// Creates the viewports' pipelines in `render_state`; call once at start-up.
pub fn init(render_state: &egui_wgpu::RenderState) {
    let slots = Slots(
        (0..SLOTS)
            .map(|_| {
                ViewportResources::new(
                    &render_state.device,
                    &render_state.adapter,
                    render_state.target_format,
                )
            })
            .collect(),
    );
    render_state
        .renderer
        .write()
        .callback_resources
        .insert(slots);
}

/// What one frame of the viewport needs on the GPU side.
pub(super) struct ViewportCallback {
    pub(super) slot: usize,
    pub(super) uniforms: FrameUniforms,
    pub(super) scene: Option<Arc<Scene>>,
    pub(super) version: u64,
    pub(super) size_px: [u32; 2],
    pub(super) too_large: Arc<AtomicBool>,
}

impl CallbackTrait for ViewportCallback {
    fn prepare(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        _screen_descriptor: &ScreenDescriptor,
        egui_encoder: &mut wgpu::CommandEncoder,
        callback_resources: &mut CallbackResources,
    ) -> Vec<wgpu::CommandBuffer> {
        if let Some(res) = callback_resources
            .get_mut::<Slots>()
            .and_then(|s| s.0.get_mut(self.slot))
        {
            res.ensure_target(device, self.size_px);
            if res.uploaded_version != Some(self.version) {
                let fits = res.upload(device, queue, self.scene.as_deref());
                self.too_large.store(!fits, Ordering::Relaxed);
                res.uploaded_version = Some(self.version);
            }
            // The same scene through the same camera into the same target: the
            // last image stands (frames that only change the panels, such as a
            // build's progress, cost no 3D rendering).
            let frame = (self.uniforms, self.version, self.size_px);
            let unchanged = res.rendered.is_some_and(|(u, v, s)| {
                bytemuck::bytes_of(&u) == bytemuck::bytes_of(&frame.0)
                    && (v, s) == (frame.1, frame.2)
            });
            if !unchanged {
                queue.write_buffer(&res.uniform_buffer, 0, bytemuck::bytes_of(&self.uniforms));
                res.render(egui_encoder, BACKGROUND);
                res.rendered = Some(frame);
            }
        }
        Vec::new()
    }

    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        render_pass: &mut wgpu::RenderPass<'static>,
        callback_resources: &CallbackResources,
    ) {
        let Some(res) = callback_resources
            .get::<Slots>()
            .and_then(|s| s.0.get(self.slot))
        else {
            return;
        };
        let Some(target) = &res.target else {
            return;
        };
        // egui has set the viewport to our rect: one triangle covers it.
        render_pass.set_pipeline(&res.blit_pipeline);
        render_pass.set_bind_group(0, &target.blit_bind_group, &[]);
        render_pass.draw(0..3, 0..1);
    }
}

/// A GPU buffer that is reused and only reallocated when data outgrows it.
struct GrowBuffer {
    buffer: Option<wgpu::Buffer>,
    usage: wgpu::BufferUsages,
    label: &'static str,
}

impl GrowBuffer {
    fn new(label: &'static str, usage: wgpu::BufferUsages) -> Self {
        GrowBuffer {
            buffer: None,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            label,
        }
    }

    /// Writes `data` at the start; false when it exceeds the device's buffer limit.
    fn write(&mut self, device: &wgpu::Device, queue: &wgpu::Queue, data: &[u8]) -> bool {
        let len = data.len() as u64;
        if len == 0 {
            return true;
        }
        if self.buffer.as_ref().is_none_or(|b| b.size() < len) {
            let max = device.limits().max_buffer_size;
            if len > max {
                return false;
            }
            let size = len
                .checked_next_power_of_two()
                .unwrap_or(len)
                .min(max)
                .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
            self.buffer = Some(device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(self.label),
                size,
                usage: self.usage,
                mapped_at_creation: false,
            }));
        }
        if let Some(buffer) = &self.buffer {
            queue.write_buffer(buffer, 0, data);
        }
        true
    }
}

/// What is uploaded and how to draw it.
#[derive(Clone, Copy)]
enum Drawn {
    Triangles { indices: u32 },
    Points { instances: u32 },
    Lines { vertices: u32 },
    Translucent { indices: u32 },
    Textured { indices: u32 },
    Splats { indices: u32 },
}

/// One uploaded part of the scene.
struct PartGpu {
    vertices: GrowBuffer,
    indices: GrowBuffer,
    drawn: Option<Drawn>,
    /// The part's images bound as group 1 (splats, textured meshes), and the
    /// material's texels they were uploaded from (re-used while they are
    /// shared; none for splats, whose atlas is the part's own).
    image: Option<(Vec<Arc<Atlas>>, wgpu::BindGroup)>,
}

impl PartGpu {
    fn new() -> Self {
        PartGpu {
            vertices: GrowBuffer::new("viewport vertices", wgpu::BufferUsages::VERTEX),
            indices: GrowBuffer::new("viewport indices", wgpu::BufferUsages::INDEX),
            drawn: None,
            image: None,
        }
    }
}

/// The offscreen image the scene is rendered into, at the viewport's pixel size.
pub(super) struct Target {
    pub(super) size: [u32; 2],
    /// Resolved (or single-sample) colour, read by the blit (and copied out
    /// by [`super::offscreen`]).
    pub(super) color: wgpu::TextureView,
    /// Multisampled colour, when MSAA is on.
    msaa: Option<wgpu::TextureView>,
    depth: wgpu::TextureView,
    blit_bind_group: wgpu::BindGroup,
}

/// Pipelines, buffers and target of one view; the viewport's slots and the
/// off-screen renders each own a set.
pub(super) struct ViewportResources {
    mesh_pipeline: wgpu::RenderPipeline,
    line_pipeline: wgpu::RenderPipeline,
    point_pipeline: wgpu::RenderPipeline,
    translucent_pipeline: wgpu::RenderPipeline,
    /// AMG §4 on the GPU: a depth pre-pass locks the nearest surface, then
    /// every splat adds colour·Ψ where it lies on that surface, so the
    /// overlapping neighbours of a domain blend into their partition of unity.
    splat_depth_pipeline: wgpu::RenderPipeline,
    splat_pipeline: wgpu::RenderPipeline,
    /// Base-colour textured meshes (glTF materials).
    textured_pipeline: wgpu::RenderPipeline,
    /// An image and its sampler, bound as group 1 (splat atlas).
    atlas_layout: wgpu::BindGroupLayout,
    /// A material's base colour (sRGB), sampler and normal map (linear).
    material_layout: wgpu::BindGroupLayout,
    /// The normal map of materials without one: +z, the surface's own
    /// normal (uploaded with the first textured part).
    flat_normal: Option<wgpu::TextureView>,
    /// Splat atlases clamp; base-colour textures repeat (glTF's default wrap).
    atlas_sampler: wgpu::Sampler,
    repeat_sampler: wgpu::Sampler,
    blit_pipeline: wgpu::RenderPipeline,
    blit_layout: wgpu::BindGroupLayout,
    pub(super) uniform_buffer: wgpu::Buffer,
    frame_bind_group: wgpu::BindGroup,
    parts: Vec<PartGpu>,
    uploaded_version: Option<u64>,
    /// What the target holds: the uniforms, scene version and size it was drawn with.
    rendered: Option<(FrameUniforms, u64, [u32; 2])>,
    sample_count: u32,
    pub(super) target: Option<Target>,
}

impl ViewportResources {
    /// The pipelines on `device`, the blit writing `target_format` (egui's pass).
    pub(super) fn new(
        device: &wgpu::Device,
        adapter: &wgpu::Adapter,
        target_format: wgpu::TextureFormat,
    ) -> Self {
        // 4× MSAA where the GPU has it; a software renderer (lavapipe,
        // llvmpipe) would spend most of a frame on it, so it draws single-sampled.
        let software = adapter.get_info().device_type == wgpu::DeviceType::Cpu;
        let multisampled = |format| supports_4x(device, adapter, format);
        let sample_count = if !software && multisampled(COLOR_FORMAT) && multisampled(DEPTH_FORMAT)
        {
            4
        } else {
            1
        };
        let scene_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("viewport scene"),
            source: wgpu::ShaderSource::Wgsl(SCENE_SHADER.into()),
        });
        let blit_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("viewport blit"),
            source: wgpu::ShaderSource::Wgsl(BLIT_SHADER.into()),
        });

        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("viewport frame"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: wgpu::BufferSize::new(
                        std::mem::size_of::<FrameUniforms>() as u64
                    ),
                },
                count: None,
            }],
        });
        let uniform_buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("viewport frame"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("viewport frame"),
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniform_buffer.as_entire_binding(),
            }],
        });
        let scene_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewport scene"),
            bind_group_layouts: &[Some(&frame_layout)],
            immediate_size: 0,
        });

        const MESH_ATTRS: [wgpu::VertexAttribute; 3] =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4];
        const POINT_ATTRS: [wgpu::VertexAttribute; 4] = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32, 2 => Float32x3, 3 => Float32x3
        ];
        let mesh_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<MeshVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &MESH_ATTRS,
        })];
        let point_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<PointInstance>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &POINT_ATTRS,
        })];
        // A fragment shader's image (filterable or not) and its sampler.
        let image_entry = |binding, filterable| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let sampler_entry = wgpu::BindGroupLayoutEntry {
            binding: 1,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            count: None,
        };
        let atlas_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("viewport splat atlas"),
            entries: &[image_entry(0, true), sampler_entry],
        });
        let material_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("viewport material"),
            entries: &[image_entry(0, true), sampler_entry, image_entry(2, true)],
        });
        let textured_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewport textured meshes"),
            bind_group_layouts: &[Some(&frame_layout), Some(&material_layout)],
            immediate_size: 0,
        });
        let splat_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewport splats"),
            bind_group_layouts: &[Some(&frame_layout), Some(&atlas_layout)],
            immediate_size: 0,
        });
        let atlas_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("viewport splat atlas"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        let repeat_sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("viewport base colour"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            ..Default::default()
        });
        const TEXTURED_ATTRS: [wgpu::VertexAttribute; 6] = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Float32x4, 3 => Float32x2, 4 => Float32x4,
            5 => Float32
        ];
        let textured_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<TexturedVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &TEXTURED_ATTRS,
        })];
        const SPLAT_ATTRS: [wgpu::VertexAttribute; 3] =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2];
        let splat_buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<SplatVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &SPLAT_ATTRS,
        })];
        let additive = wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent::OVER,
        };
        // Opaque by default; `Some(blend)` draws without writing depth.
        struct Style<'a> {
            layout: &'a wgpu::PipelineLayout,
            blend: Option<wgpu::BlendState>,
            depth_bias: i32,
        }
        let opaque = Style {
            layout: &scene_layout,
            blend: None,
            depth_bias: 0,
        };
        let scene_pipeline = |label: &str,
                              vs: &str,
                              fs: &str,
                              buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
                              topology: wgpu::PrimitiveTopology,
                              style: &Style| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(style.layout),
                vertex: wgpu::VertexState {
                    module: &scene_module,
                    entry_point: Some(vs),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(style.blend.is_none()),
                    depth_compare: Some(wgpu::CompareFunction::LessEqual),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState {
                        constant: style.depth_bias,
                        slope_scale: if style.depth_bias != 0 { 1.0 } else { 0.0 },
                        clamp: 0.0,
                    },
                }),
                multisample: wgpu::MultisampleState {
                    count: sample_count,
                    mask: !0,
                    alpha_to_coverage_enabled: false,
                },
                fragment: Some(wgpu::FragmentState {
                    module: &scene_module,
                    entry_point: Some(fs),
                    compilation_options: wgpu::PipelineCompilationOptions::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: COLOR_FORMAT,
                        blend: style.blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let mesh_pipeline = scene_pipeline(
            "viewport mesh",
            "vs_mesh",
            "fs_mesh",
            &mesh_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            &opaque,
        );
        let textured_pipeline = scene_pipeline(
            "viewport textured mesh",
            "vs_textured",
            "fs_textured",
            &textured_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            &Style {
                layout: &textured_layout,
                blend: None,
                depth_bias: 0,
            },
        );
        let line_pipeline = scene_pipeline(
            "viewport lines",
            "vs_line",
            "fs_unlit",
            &mesh_buffers,
            wgpu::PrimitiveTopology::LineList,
            &opaque,
        );
        let point_pipeline = scene_pipeline(
            "viewport points",
            "vs_points",
            "fs_points",
            &point_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            &opaque,
        );
        let translucent_pipeline = scene_pipeline(
            "viewport translucent layers",
            "vs_mesh",
            "fs_mesh",
            &mesh_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            &Style {
                layout: &scene_layout,
                blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                depth_bias: 0,
            },
        );
        // The pre-pass writes depth slightly behind the splats (a positive
        // bias), so splats on the same surface pass the test and blend.
        let splat_depth_pipeline = scene_pipeline(
            "viewport splat depth",
            "vs_splat",
            "fs_splat_depth",
            &splat_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            &Style {
                layout: &splat_layout,
                blend: None,
                depth_bias: 2000,
            },
        );
        let splat_pipeline = scene_pipeline(
            "viewport splats",
            "vs_splat",
            "fs_splat",
            &splat_buffers,
            wgpu::PrimitiveTopology::TriangleList,
            &Style {
                layout: &splat_layout,
                blend: Some(additive),
                depth_bias: 0,
            },
        );

        let blit_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("viewport blit"),
            entries: &[image_entry(0, false)],
        });
        let blit_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("viewport blit"),
            bind_group_layouts: &[Some(&blit_layout)],
            immediate_size: 0,
        });
        // egui's pass (as run_studio and the tests configure it) has one sample
        // and no depth; its target may or may not be sRGB-encoding.
        let blit_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("viewport blit"),
            layout: Some(&blit_pipeline_layout),
            vertex: wgpu::VertexState {
                module: &blit_module,
                entry_point: Some("vs_blit"),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &blit_module,
                entry_point: Some(if target_format.is_srgb() {
                    "fs_blit_linear"
                } else {
                    "fs_blit_gamma"
                }),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                targets: &[Some(target_format.into())],
            }),
            multiview_mask: None,
            cache: None,
        });

        ViewportResources {
            mesh_pipeline,
            line_pipeline,
            point_pipeline,
            translucent_pipeline,
            splat_depth_pipeline,
            splat_pipeline,
            textured_pipeline,
            atlas_layout,
            material_layout,
            flat_normal: None,
            atlas_sampler,
            repeat_sampler,
            blit_pipeline,
            blit_layout,
            uniform_buffer,
            frame_bind_group,
            parts: Vec::new(),
            uploaded_version: None,
            rendered: None,
            sample_count,
            target: None,
        }
    }

    /// (Re)creates the offscreen target when the viewport's pixel size changed.
    pub(super) fn ensure_target(&mut self, device: &wgpu::Device, size: [u32; 2]) {
        let max = device.limits().max_texture_dimension_2d.max(1);
        let size = size.map(|s| s.clamp(1, max));
        if self.target.as_ref().is_some_and(|t| t.size == size) {
            return;
        }
        let texture = |label: &str, format, samples, usage| {
            device
                .create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: size[0],
                        height: size[1],
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: samples,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                })
                .create_view(&wgpu::TextureViewDescriptor::default())
        };
        let attach = wgpu::TextureUsages::RENDER_ATTACHMENT;
        let color = texture(
            "viewport colour",
            COLOR_FORMAT,
            1,
            attach | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC,
        );
        let msaa = (self.sample_count > 1).then(|| {
            texture(
                "viewport colour (msaa)",
                COLOR_FORMAT,
                self.sample_count,
                attach,
            )
        });
        let depth = texture("viewport depth", DEPTH_FORMAT, self.sample_count, attach);
        let blit_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("viewport blit"),
            layout: &self.blit_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&color),
            }],
        });
        self.target = Some(Target {
            size,
            color,
            msaa,
            depth,
            blit_bind_group,
        });
    }

    /// Uploads the scene's geometry; false (and that part not drawn) when a
    /// part does not fit.
    pub(super) fn upload(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        scene: Option<&Scene>,
    ) -> bool {
        let parts = scene.map_or(&[][..], |s| &s.parts[..]);
        while self.parts.len() < parts.len() {
            self.parts.push(PartGpu::new());
        }
        let count = |n: usize| u32::try_from(n).ok();
        let mut fits = true;
        for (gpu, part) in self.parts.iter_mut().zip(parts) {
            let PartGpu {
                vertices: vb,
                indices: ib,
                image,
                ..
            } = gpu;
            let mut indexed = |vertices: &[u8], indices: &[u32]| {
                count(indices.len()).filter(|_| {
                    vb.write(device, queue, vertices)
                        && ib.write(device, queue, bytemuck::cast_slice(indices))
                })
            };
            gpu.drawn = match part {
                Geometry::Triangles { vertices, indices } => {
                    indexed(bytemuck::cast_slice(vertices), indices)
                        .map(|indices| Drawn::Triangles { indices })
                }
                Geometry::Translucent { vertices, indices } => {
                    indexed(bytemuck::cast_slice(vertices), indices)
                        .map(|indices| Drawn::Translucent { indices })
                }
                Geometry::Textured {
                    vertices,
                    indices,
                    texture,
                    normal_map,
                } => {
                    let sources: Vec<Arc<Atlas>> = std::iter::once(texture)
                        .chain(normal_map)
                        .cloned()
                        .collect();
                    let uploaded = image.as_ref().is_some_and(|(from, _)| {
                        from.len() == sources.len()
                            && from.iter().zip(&sources).all(|(a, b)| Arc::ptr_eq(a, b))
                    });
                    if !uploaded {
                        let base = upload_texture(
                            device,
                            queue,
                            texture,
                            wgpu::TextureFormat::Rgba8UnormSrgb,
                        );
                        let linear = wgpu::TextureFormat::Rgba8Unorm;
                        let own = normal_map
                            .as_ref()
                            .map(|n| upload_texture(device, queue, n, linear));
                        let flat = self.flat_normal.get_or_insert_with(|| {
                            let up = Atlas {
                                width: 1,
                                height: 1,
                                rgba: vec![[128, 128, 255, 255]],
                            };
                            upload_texture(device, queue, &up, linear)
                        });
                        let views = [&base, own.as_ref().unwrap_or(flat)];
                        let group = bind_images(
                            device,
                            &self.material_layout,
                            &self.repeat_sampler,
                            &views,
                        );
                        *image = Some((sources, group));
                    }
                    indexed(bytemuck::cast_slice(vertices), indices)
                        .map(|indices| Drawn::Textured { indices })
                }
                Geometry::Splats {
                    vertices,
                    indices,
                    atlas,
                } => {
                    let view =
                        upload_texture(device, queue, atlas, wgpu::TextureFormat::Rgba8UnormSrgb);
                    let group =
                        bind_images(device, &self.atlas_layout, &self.atlas_sampler, &[&view]);
                    *image = Some((Vec::new(), group));
                    indexed(bytemuck::cast_slice(vertices), indices)
                        .map(|indices| Drawn::Splats { indices })
                }
                Geometry::Points(points) => count(points.len())
                    .filter(|_| vb.write(device, queue, bytemuck::cast_slice(points)))
                    .map(|instances| Drawn::Points { instances }),
                Geometry::Lines(lines) => count(lines.len())
                    .filter(|_| vb.write(device, queue, bytemuck::cast_slice(lines)))
                    .map(|vertices| Drawn::Lines { vertices }),
            };
            fits &= gpu.drawn.is_some();
        }
        for gpu in self.parts.iter_mut().skip(parts.len()) {
            gpu.drawn = None;
        }
        fits
    }

    /// Clears the offscreen target to `clear` and draws the uploaded geometry into it.
    pub(super) fn render(&self, encoder: &mut wgpu::CommandEncoder, clear: wgpu::Color) {
        let Some(target) = &self.target else {
            return;
        };
        let (view, resolve_target, store) = match &target.msaa {
            Some(msaa) => (msaa, Some(&target.color), wgpu::StoreOp::Discard),
            None => (&target.color, None, wgpu::StoreOp::Store),
        };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("viewport scene"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                resolve_target,
                depth_slice: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear),
                    store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &target.depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            ..Default::default()
        });
        pass.set_bind_group(0, &self.frame_bind_group, &[]);
        for part in &self.parts {
            let (Some(drawn), Some(vertices)) = (part.drawn, &part.vertices.buffer) else {
                continue;
            };
            pass.set_vertex_buffer(0, vertices.slice(..));
            let index_buffer = part.indices.buffer.as_ref();
            let indexed = |pass: &mut wgpu::RenderPass, pipeline: &wgpu::RenderPipeline, n: u32| {
                if let Some(ib) = index_buffer {
                    pass.set_pipeline(pipeline);
                    pass.set_index_buffer(ib.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..n, 0, 0..1);
                }
            };
            match drawn {
                Drawn::Triangles { indices } => indexed(&mut pass, &self.mesh_pipeline, indices),
                Drawn::Translucent { indices } => {
                    indexed(&mut pass, &self.translucent_pipeline, indices)
                }
                Drawn::Textured { indices } => {
                    if let Some((_, image)) = &part.image {
                        pass.set_bind_group(1, image, &[]);
                        indexed(&mut pass, &self.textured_pipeline, indices);
                    }
                }
                Drawn::Splats { indices } => {
                    if let Some((_, atlas)) = &part.image {
                        pass.set_bind_group(1, atlas, &[]);
                        indexed(&mut pass, &self.splat_depth_pipeline, indices);
                        indexed(&mut pass, &self.splat_pipeline, indices);
                    }
                }
                Drawn::Points { instances } => {
                    pass.set_pipeline(&self.point_pipeline);
                    pass.draw(0..6, 0..instances);
                }
                Drawn::Lines { vertices: n } => {
                    pass.set_pipeline(&self.line_pipeline);
                    pass.draw(0..n, 0..1);
                }
            }
        }
    }
}

/// `atlas`'s texels as a texture of `format` (sRGB colour, or linear
/// data such as a normal map), clamped to the device's largest size.
fn upload_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    atlas: &Atlas,
    format: wgpu::TextureFormat,
) -> wgpu::TextureView {
    let max = device.limits().max_texture_dimension_2d;
    let size = wgpu::Extent3d {
        width: atlas.width.clamp(1, max),
        height: atlas.height.clamp(1, max),
        depth_or_array_layers: 1,
    };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("viewport image"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let rows = (atlas.rgba.len() as u32 / atlas.width.max(1)).min(size.height);
    if rows > 0 && atlas.width <= max {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&atlas.rgba[..(rows * atlas.width) as usize]),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * atlas.width),
                rows_per_image: Some(rows),
            },
            wgpu::Extent3d {
                height: rows,
                ..size
            },
        );
    }
    texture.create_view(&wgpu::TextureViewDescriptor::default())
}

/// Group 1 of `layout`: the first image at binding 0, the sampler at 1,
/// the rest from binding 2 on.
fn bind_images(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    sampler: &wgpu::Sampler,
    views: &[&wgpu::TextureView],
) -> wgpu::BindGroup {
    let mut entries = vec![wgpu::BindGroupEntry {
        binding: 1,
        resource: wgpu::BindingResource::Sampler(sampler),
    }];
    for (k, view) in views.iter().enumerate() {
        entries.push(wgpu::BindGroupEntry {
            binding: if k == 0 { 0 } else { k as u32 + 1 },
            resource: wgpu::BindingResource::TextureView(view),
        });
    }
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("viewport images"),
        layout,
        entries: &entries,
    })
}

/// Whether `format` can be rendered with 4x MSAA on this device.
fn supports_4x(
    device: &wgpu::Device,
    adapter: &wgpu::Adapter,
    format: wgpu::TextureFormat,
) -> bool {
    let features = device.features();
    let flags = if features.contains(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES) {
        adapter.get_texture_format_features(format).flags
    } else {
        format.guaranteed_format_features(features).flags
    };
    flags.sample_count_supported(4)
}

/// Every scene pipeline's shaders, one module: the frame's uniforms and
/// shading written once (`frame.wgsl`), lit meshes, lines and point discs
/// and translucent layers (`scene.wgsl`), splats (`splat.wgsl`, which
/// declares the image bindings) and base-colour textured meshes (`textured.wgsl`).
const SCENE_SHADER: &str = concat!(
    include_str!("shaders/frame.wgsl"),
    include_str!("shaders/scene.wgsl"),
    include_str!("shaders/splat.wgsl"),
    include_str!("shaders/textured.wgsl"),
);

/// Copies the offscreen image 1:1 into egui's pass, encoding to sRGB when the
/// target does not do it itself.
const BLIT_SHADER: &str = include_str!("shaders/blit.wgsl");
