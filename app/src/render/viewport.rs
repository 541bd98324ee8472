//! The viewport widget: one scene seen through a [`Camera`], drawn by the
//! GPU side ([`super::gpu`]) through egui's paint callback, with the camera
//! driven by the pointer and keys.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::{Vec2, Vec3};
use lodstudio_core::geom::{PointSet, TriMesh, Volume};

use super::camera::{Camera, Sphere};
use super::gpu::{FrameUniforms, ViewportCallback, init};
use super::scene::Scene;

/// Viewports that can be on screen at once (the side-by-side compare).
pub(super) const SLOTS: usize = 2;

/// The 3D view of one scene.
pub struct Viewport {
    /// Where it looks from (public for scripted sessions and tests).
    pub camera: Camera,
    scene: Option<Arc<Scene>>,
    /// Bumped on every scene change; the GPU side re-uploads when it differs.
    version: u64,
    /// Width / height of the last shown rect, for framing.
    aspect: f32,
    has_wgpu: bool,
    /// Set by the GPU side when the scene does not fit in its buffers.
    too_large: Arc<AtomicBool>,
    /// Pixel size of the last shown rect (what cuts are taken for).
    size_px: [u32; 2],
    /// The ray (eye, direction) under the last click, until taken.
    click: Option<(Vec3, Vec3)>,
    /// Which of the [`SLOTS`] GPU resource sets draws this viewport.
    slot: usize,
    /// Its accessibility label.
    label: &'static str,
}

/// egui's vector as glam's.
fn vec2(v: egui::Vec2) -> Vec2 {
    Vec2::new(v.x, v.y)
}

impl Viewport {
    /// A viewport drawing with `render_state` (after [`init`] on it), or a
    /// placeholder message when there is none.
    pub fn new(render_state: Option<&egui_wgpu::RenderState>) -> Self {
        if let Some(rs) = render_state {
            init(rs);
        }
        Viewport {
            camera: Camera::default(),
            scene: None,
            version: 0,
            aspect: 1.0,
            has_wgpu: render_state.is_some(),
            too_large: Arc::new(AtomicBool::new(false)),
            size_px: [1024, 768],
            click: None,
            slot: 0,
            label: "3D viewport",
        }
    }

    /// A second viewport drawing beside the first (after [`Viewport::new`]
    /// made the GPU resources), with its own label and resources.
    pub fn second(render_state: Option<&egui_wgpu::RenderState>, label: &'static str) -> Self {
        let mut v = Viewport::new(None);
        v.has_wgpu = render_state.is_some();
        v.slot = 1;
        v.label = label;
        v
    }

    /// Takes `other`'s camera (target, distance, orbit angles and fly mode).
    pub fn follow(&mut self, other: &Viewport) {
        self.camera = other.camera;
    }

    /// Whether both viewports look from the same camera.
    pub fn same_camera(&self, other: &Viewport) -> bool {
        self.camera.same_view(&other.camera)
    }

    /// Shows `scene` from the default direction, framed to fit.
    pub fn set_scene(&mut self, scene: Scene) {
        self.frame_scene(Arc::new(scene));
    }

    /// Shows a shared `scene` (a newly opened model) from the default
    /// direction, framed to fit.
    pub fn frame_scene(&mut self, scene: Arc<Scene>) {
        self.replace_scene(scene);
        self.camera.reset(self.sphere(), self.aspect);
    }

    /// Shows `scene` through the current camera, so switching between versions
    /// of one model (original, simplified, colour-coded) keeps the view.
    /// Showing the scene already on screen uploads nothing.
    pub fn swap_scene(&mut self, scene: &Arc<Scene>) {
        if !self.scene.as_ref().is_some_and(|s| Arc::ptr_eq(s, scene)) {
            self.replace_scene(Arc::clone(scene));
        }
    }

    fn replace_scene(&mut self, scene: Arc<Scene>) {
        self.scene = Some(scene);
        self.version += 1;
        self.too_large.store(false, Ordering::Relaxed);
    }

    /// The scene on screen.
    pub fn scene(&self) -> Option<&Scene> {
        self.scene.as_deref()
    }

    /// Shows a mesh (builds its GPU geometry here, on the calling thread).
    pub fn set_mesh(&mut self, mesh: &TriMesh) {
        self.set_scene(Scene::from_mesh(mesh));
    }

    /// Shows a point set (builds its GPU geometry here, on the calling thread).
    pub fn set_points(&mut self, points: &PointSet) {
        self.set_scene(Scene::from_points(points));
    }

    /// Shows a volume's bounding box.
    pub fn set_volume(&mut self, volume: &Volume) {
        self.set_scene(Scene::from_volume(volume));
    }

    /// The camera as the core's cuts see it, at the viewport's size in pixels.
    pub fn core_view(&self) -> lodstudio_core::view::View {
        self.camera.core_view(self.size_px)
    }

    /// Centres the scene and moves the camera back until its bounding sphere fits.
    pub fn frame_all(&mut self) {
        self.camera.frame(self.sphere(), self.aspect);
    }

    /// The scene's bounding sphere (the unit sphere when there is none).
    fn sphere(&self) -> Sphere {
        self.scene.as_deref().map_or(Sphere::UNIT, Scene::sphere)
    }

    /// Draws the viewport into all remaining space and handles camera input:
    /// left-drag orbits, right/middle/shift+left-drag pans, scroll or pinch zooms,
    /// double-click frames the whole scene.
    pub fn show(&mut self, ui: &mut egui::Ui) -> egui::Response {
        let size = ui.available_size().max(egui::vec2(1.0, 1.0));
        let (rect, response) = ui.allocate_exact_size(size, egui::Sense::click_and_drag());
        let label = self.label;
        response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Canvas, true, label));
        self.aspect = rect.width() / rect.height().max(1.0);

        if !self.has_wgpu {
            ui.painter()
                .rect_filled(rect, 0.0, ui.visuals().extreme_bg_color);
            ui.put(rect, egui::Label::new("3D viewport needs wgpu"));
            return response;
        }

        self.handle_input(ui, &response, rect);

        let ppp = ui.ctx().pixels_per_point();
        let size_px = [
            (rect.width() * ppp).round().max(1.0) as u32,
            (rect.height() * ppp).round().max(1.0) as u32,
        ];
        self.size_px = size_px;
        let uniforms = FrameUniforms::new(&self.camera, self.aspect, self.sphere(), size_px, ppp);
        ui.painter().add(egui_wgpu::Callback::new_paint_callback(
            rect,
            ViewportCallback {
                slot: self.slot,
                uniforms,
                scene: self.scene.clone(),
                version: self.version,
                size_px,
                too_large: Arc::clone(&self.too_large),
            },
        ));
        if self.too_large.load(Ordering::Relaxed) {
            ui.put(
                rect,
                egui::Label::new(
                    egui::RichText::new("model too large for this GPU's buffers")
                        .color(ui.visuals().warn_fg_color),
                ),
            );
        }
        response
    }

    /// The ray under the last click in the viewport (taken once).
    pub fn take_click(&mut self) -> Option<(Vec3, Vec3)> {
        self.click.take()
    }

    /// The ray through the point `pos` of the viewport `rect`.
    fn ray(&self, pos: egui::Pos2, rect: egui::Rect) -> (Vec3, Vec3) {
        let ndc = Vec2::new(
            (pos.x - rect.min.x) / rect.width().max(1.0) * 2.0 - 1.0,
            1.0 - (pos.y - rect.min.y) / rect.height().max(1.0) * 2.0,
        );
        self.camera.ray(ndc, self.aspect, self.sphere())
    }

    fn handle_input(&mut self, ui: &egui::Ui, response: &egui::Response, rect: egui::Rect) {
        use egui::PointerButton::{Middle, Primary, Secondary};
        let delta = vec2(response.drag_delta());
        let shift = ui.input(|i| i.modifiers.shift);
        if response.dragged_by(Secondary)
            || response.dragged_by(Middle)
            || (response.dragged_by(Primary) && shift)
        {
            self.camera.pan(delta, rect.height());
        } else if response.dragged_by(Primary) {
            if self.camera.fly {
                self.camera.look(delta);
            } else {
                self.camera.orbit(delta);
            }
        }
        // Keys walk unless a text field has the keyboard.
        if self.camera.fly && ui.memory(|m| m.focused().is_none()) {
            let (dir, dt) = ui.input(|i| {
                let key = |k: egui::Key| if i.key_down(k) { 1.0 } else { 0.0 };
                let dir = Vec3::new(
                    key(egui::Key::D) - key(egui::Key::A),
                    key(egui::Key::E) - key(egui::Key::Q),
                    key(egui::Key::W) - key(egui::Key::S),
                );
                (dir, i.stable_dt.min(0.1))
            });
            if dir != Vec3::ZERO {
                self.camera.walk(dir, dt, shift, self.sphere());
                ui.ctx().request_repaint();
            }
        }
        if response.hovered() {
            let (scroll, pinch) = ui.input(|i| (i.smooth_scroll_delta.y, i.zoom_delta()));
            if scroll != 0.0 {
                self.camera.zoom((-scroll * 0.002).exp(), self.sphere());
            }
            if pinch != 1.0 {
                self.camera.zoom(1.0 / pinch, self.sphere());
            }
        }
        if response.double_clicked() {
            self.frame_all();
        } else if response.clicked()
            && let Some(pos) = response.interact_pointer_pos()
        {
            self.click = Some(self.ray(pos, rect));
        }
    }
}
