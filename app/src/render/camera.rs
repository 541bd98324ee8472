//! The orbit camera (with a fly mode): where the eye is, the matrices and
//! rays it gives, and how drags, scrolls and keys move it. Plain math on
//! glam types, so it is tested without a window or a GPU.

use glam::{Mat4, Vec2, Vec3};

/// Vertical field of view.
pub const FOV_Y: f32 = std::f32::consts::FRAC_PI_4;
/// The screen coverage (the bounding sphere's projected height over the
/// viewport's) seen from `distance` bounding radii: `r / (d tan(θ/2))`, what
/// `MSFT_screencoverage` thresholds compare with.
pub fn coverage_at_distance(distance: f32) -> f32 {
    1.0 / (distance * (0.5 * FOV_Y).tan())
}

/// The distance (in bounding radii) at which the coverage is `coverage`.
pub fn distance_at_coverage(coverage: f32) -> f32 {
    1.0 / (coverage * (0.5 * FOV_Y).tan())
}

/// Pitch stays short of the poles so the view's up vector is never parallel to it.
const MAX_PITCH: f32 = 1.55;
/// The direction a newly opened model is seen from.
const DEFAULT_YAW: f32 = 0.6;
const DEFAULT_PITCH: f32 = 0.4;
/// Elevation of [`Camera::views_around`]: alternately this far above and below.
const AROUND_PITCH: f32 = 0.35;

/// A sphere around what is shown: the near and far planes hug it, framing
/// fits it, and zoom limits and walking speeds scale with it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Sphere {
    /// The unit sphere, for an empty scene.
    pub const UNIT: Sphere = Sphere {
        center: Vec3::ZERO,
        radius: 1.0,
    };

    /// The smallest sphere holding both (so one set of clip planes fits two models).
    pub fn enclosing(self, other: Sphere) -> Sphere {
        let (big, small) = match self.radius >= other.radius {
            true => (self, other),
            false => (other, self),
        };
        let d = big.center.distance(small.center);
        if d + small.radius <= big.radius {
            return big;
        }
        let radius = (d + big.radius + small.radius) * 0.5;
        let towards = (small.center - big.center) / d;
        Sphere {
            center: big.center + towards * (radius - big.radius),
            radius,
        }
    }
}

/// An eye orbiting a target at a distance, by yaw and pitch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Point the camera orbits around and looks at.
    pub target: Vec3,
    /// Distance from the camera to `target`.
    pub distance: f32,
    /// Rotation about the vertical axis, radians.
    pub yaw: f32,
    /// Elevation above the horizontal plane, radians.
    pub pitch: f32,
    /// Fly mode: keys walk the camera through the scene and dragging looks
    /// around the eye instead of orbiting the target.
    pub fly: bool,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            target: Vec3::ZERO,
            distance: 3.0,
            yaw: DEFAULT_YAW,
            pitch: DEFAULT_PITCH,
            fly: false,
        }
    }
}

impl Camera {
    pub fn eye(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        self.target + self.distance * Vec3::new(cp * sy, sp, cp * cy)
    }

    /// Whether `other` looks from the same eye at the same target (fly mode aside).
    pub fn same_view(&self, other: &Camera) -> bool {
        (self.target, self.distance, self.yaw, self.pitch)
            == (other.target, other.distance, other.yaw, other.pitch)
    }

    /// Camera right and up vectors in world space.
    pub fn basis(&self) -> (Vec3, Vec3) {
        let forward = self.forward();
        let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
        (right, right.cross(forward))
    }

    fn forward(&self) -> Vec3 {
        (self.target - self.eye()).normalize_or(Vec3::NEG_Z)
    }

    /// View-projection matrix (depth 0..1) with near and far planes hugging `scene`.
    pub fn view_proj(&self, aspect: f32, scene: Sphere) -> Mat4 {
        let eye = self.eye();
        let d = eye.distance(scene.center);
        let far = (d + scene.radius * 1.05).max(1e-4);
        let near = (d - scene.radius * 1.05).clamp(far * 1e-4, far * 0.5);
        let proj = glam::camera::rh::proj::directx::perspective(FOV_Y, aspect, near, far);
        let view = glam::camera::rh::view::look_at_mat4(eye, self.target, Vec3::Y);
        proj * view
    }

    /// Focal length in pixels for an image `height_px` tall.
    pub fn focal_px(height_px: u32) -> f32 {
        height_px as f32 * 0.5 / (FOV_Y * 0.5).tan()
    }

    /// The camera as the core's cuts see it, for an image of `size_px`; the
    /// light comes from the eye.
    pub fn core_view(&self, size_px: [u32; 2]) -> lodstudio_core::view::View {
        let eye = self.eye();
        lodstudio_core::view::View {
            eye,
            target: self.target,
            up: Vec3::Y,
            fov_y: FOV_Y,
            width: size_px[0],
            height: size_px[1],
            light_dir: (eye - self.target).normalize_or(Vec3::Z),
        }
    }

    /// Looks from the default direction, then frames `scene`.
    pub fn reset(&mut self, scene: Sphere, aspect: f32) {
        self.yaw = DEFAULT_YAW;
        self.pitch = DEFAULT_PITCH;
        self.frame(scene, aspect);
    }

    /// `n` cameras evenly spaced in azimuth around `scene` (from the default
    /// direction on), alternately above and below it, each framing it for
    /// an image of `aspect`: fixed views, so that two models rendered from
    /// them compare pixel for pixel.
    pub fn views_around(scene: Sphere, n: usize, aspect: f32) -> Vec<Camera> {
        (0..n)
            .map(|i| {
                let mut camera = Camera {
                    yaw: DEFAULT_YAW + std::f32::consts::TAU * i as f32 / n as f32,
                    pitch: if i % 2 == 0 {
                        AROUND_PITCH
                    } else {
                        -AROUND_PITCH
                    },
                    ..Camera::default()
                };
                camera.frame(scene, aspect);
                camera
            })
            .collect()
    }

    /// Centres `scene` and moves back until it fits the narrower field of view.
    pub fn frame(&mut self, scene: Sphere, aspect: f32) {
        let half_fov_x = ((FOV_Y * 0.5).tan() * aspect).atan();
        let half_fov = half_fov_x.clamp(0.05, FOV_Y * 0.5);
        self.target = scene.center;
        self.distance = scene.radius / half_fov.sin() * 1.05;
    }

    /// Rotates about the target by a drag of `delta` points.
    pub fn orbit(&mut self, delta: Vec2) {
        self.yaw -= delta.x * 0.01;
        self.pitch = (self.pitch + delta.y * 0.01).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Moves the target so the scene follows the pointer across a view
    /// `height_points` tall.
    pub fn pan(&mut self, delta: Vec2, height_points: f32) {
        let world_per_point = 2.0 * self.distance * (FOV_Y * 0.5).tan() / height_points.max(1.0);
        let (right, up) = self.basis();
        self.target += (up * delta.y - right * delta.x) * world_per_point;
    }

    /// Moves towards (factor < 1) or away from the target, staying within
    /// 10⁻³..10³ radii of `scene`.
    pub fn zoom(&mut self, factor: f32, scene: Sphere) {
        if factor.is_finite() && factor > 0.0 {
            let r = scene.radius;
            self.distance = (self.distance * factor).clamp(r * 1e-3, r * 1e3);
        }
    }

    /// Turns the view about the eye (fly mode's look), keeping the eye still.
    pub fn look(&mut self, delta: Vec2) {
        let eye = self.eye();
        self.orbit(-delta);
        self.target = eye - (self.eye() - self.target);
    }

    /// Fly mode's walk: `dir` in camera axes (right, up, forward), at half
    /// `scene`'s radius per second (`fast`: four times that).
    pub fn walk(&mut self, dir: Vec3, seconds: f32, fast: bool, scene: Sphere) {
        let forward = self.forward();
        let (right, up) = self.basis();
        let speed = 0.5 * scene.radius * if fast { 4.0 } else { 1.0 };
        self.target += (right * dir.x + up * dir.y + forward * dir.z) * speed * seconds;
    }

    /// The ray (eye, unit direction) through `ndc` (−1..1, y up) of the image.
    pub fn ray(&self, ndc: Vec2, aspect: f32, scene: Sphere) -> (Vec3, Vec3) {
        let inverse = self.view_proj(aspect, scene).inverse();
        let near = inverse.project_point3(ndc.extend(0.0));
        let far = inverse.project_point3(ndc.extend(1.0));
        (self.eye(), (far - near).normalize_or(Vec3::NEG_Z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCENE: Sphere = Sphere {
        center: Vec3::new(1.0, 2.0, 3.0),
        radius: 0.5,
    };

    fn close(a: Vec3, b: Vec3) -> bool {
        a.distance(b) < 1e-4
    }

    #[test]
    fn the_eye_orbits_the_target_and_the_centre_ray_hits_it() {
        let mut camera = Camera::default();
        camera.reset(SCENE, 1.6);
        assert!((camera.eye().distance(SCENE.center) - camera.distance).abs() < 1e-4);
        let (eye, dir) = camera.ray(Vec2::ZERO, 1.6, SCENE);
        assert!(close(eye, camera.eye()));
        assert!(close(dir, (SCENE.center - eye).normalize()), "{dir}");
        // A ray to the right of the centre turns right.
        let (_, right_dir) = camera.ray(Vec2::new(0.5, 0.0), 1.6, SCENE);
        assert!(right_dir.dot(camera.basis().0) > 0.1);
    }

    #[test]
    fn framing_fits_the_sphere_in_both_directions() {
        for aspect in [0.5, 1.0, 2.0] {
            let mut camera = Camera::default();
            camera.reset(SCENE, aspect);
            let m = camera.view_proj(aspect, SCENE);
            let (right, up) = camera.basis();
            for offset in [right, -right, up, -up] {
                let p = m.project_point3(SCENE.center + offset * SCENE.radius);
                assert!(p.x.abs() <= 1.0 && p.y.abs() <= 1.0, "{aspect}: {p}");
                assert!((0.0..=1.0).contains(&p.z), "inside the depth range: {p}");
            }
        }
    }

    #[test]
    fn views_around_circle_the_sphere_and_frame_it() {
        let views = Camera::views_around(SCENE, 8, 1.0);
        assert_eq!(views.len(), 8);
        assert_eq!(views, Camera::views_around(SCENE, 8, 1.0), "deterministic");
        let mut framed = Camera::default();
        framed.frame(SCENE, 1.0);
        for (i, v) in views.iter().enumerate() {
            assert_eq!((v.target, v.distance), (framed.target, framed.distance));
            assert_eq!(v.pitch > 0.0, i % 2 == 0, "alternately above and below");
        }
        // Opposite views look from opposite sides.
        let (a, b) = (views[0].eye() - SCENE.center, views[4].eye() - SCENE.center);
        assert!((a.x + b.x).abs() < 1e-4 && (a.z + b.z).abs() < 1e-4);
    }

    #[test]
    fn the_enclosing_sphere_holds_both() {
        let other = Sphere {
            center: Vec3::new(3.0, 2.0, 3.0),
            radius: 1.0,
        };
        let s = SCENE.enclosing(other);
        for (c, r) in [(SCENE.center, SCENE.radius), (other.center, other.radius)] {
            assert!(s.center.distance(c) + r <= s.radius + 1e-5);
        }
        assert!((s.radius - 1.75).abs() < 1e-5, "{}", s.radius);
        let inside = Sphere {
            radius: 0.1,
            ..SCENE
        };
        assert_eq!(SCENE.enclosing(inside), SCENE);
        assert_eq!(inside.enclosing(SCENE), SCENE);
    }

    #[test]
    fn look_keeps_the_eye_and_pitch_stops_short_of_the_poles() {
        let mut camera = Camera::default();
        let eye = camera.eye();
        camera.look(Vec2::new(30.0, -20.0));
        assert!(close(camera.eye(), eye));
        camera.orbit(Vec2::new(0.0, 1e6));
        assert_eq!(camera.pitch, MAX_PITCH);
        assert!(camera.basis().1.is_finite());
    }

    #[test]
    fn zoom_and_walk_scale_with_the_scene() {
        let mut camera = Camera::default();
        camera.zoom(1e-9, SCENE);
        assert_eq!(camera.distance, SCENE.radius * 1e-3);
        camera.zoom(f32::NAN, SCENE);
        assert_eq!(camera.distance, SCENE.radius * 1e-3);
        let before = camera.target;
        camera.walk(Vec3::Z, 2.0, false, SCENE);
        assert!((camera.target.distance(before) - SCENE.radius).abs() < 1e-5);
        let view = camera.core_view([640, 480]);
        assert_eq!((view.width, view.height, view.fov_y), (640, 480, FOV_Y));
        assert!((Camera::focal_px(480) - 240.0 / (FOV_Y * 0.5).tan()).abs() < 1e-3);
    }
}
