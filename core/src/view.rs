//! The camera every view-dependent cut is taken for, and the projection of an
//! object-space error to pixels (hybrid paper §6, merge-tree paper §5.1).

use glam::{Mat4, Vec3};

/// A perspective camera with its viewport and a light, as a cut needs it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in radians.
    pub fov_y: f32,
    /// Viewport size in pixels.
    pub width: u32,
    pub height: u32,
    /// Direction towards the light (normalised), for the lighting criterion.
    pub light_dir: Vec3,
}

/// Nearest depth used when projecting, so a primitive at the eye gets a large
/// but finite pixel size.
const NEAR: f32 = 1e-4;

impl View {
    /// A camera on a sphere around `center` looking at it: `azimuth` about +Y,
    /// `elevation` above the XZ plane (radians), light from the eye.
    pub fn orbit(center: Vec3, distance: f32, azimuth: f32, elevation: f32) -> View {
        let dir = Vec3::new(
            elevation.cos() * azimuth.sin(),
            elevation.sin(),
            elevation.cos() * azimuth.cos(),
        );
        View {
            eye: center + dir * distance,
            target: center,
            up: Vec3::Y,
            fov_y: 60f32.to_radians(),
            width: 1024,
            height: 768,
            light_dir: dir,
        }
    }

    /// Unit vector from the eye towards the target.
    pub fn forward(&self) -> Vec3 {
        (self.target - self.eye).normalize_or(Vec3::NEG_Z)
    }

    pub fn aspect(&self) -> f32 {
        self.width.max(1) as f32 / self.height.max(1) as f32
    }

    pub fn view_matrix(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.eye, self.target, self.up)
    }

    /// Perspective projection (wgpu depth range 0..1).
    pub fn projection(&self, near: f32, far: f32) -> Mat4 {
        glam::camera::rh::proj::directx::perspective(self.fov_y, self.aspect(), near, far)
    }

    /// Pixels covered by a unit length seen face-on at depth 1.
    pub fn focal_pixels(&self) -> f32 {
        self.height.max(1) as f32 / (2.0 * (0.5 * self.fov_y).tan())
    }

    /// A conservative pixel size of an object-space length anywhere in the
    /// sphere (`center`, `radius`): projected at the sphere's nearest depth, and
    /// enlarged by the worst off-axis stretch at the viewport's corner.
    pub fn pixels(&self, length: f32, center: Vec3, radius: f32) -> f32 {
        self.pixels_f64(length as f64, center, radius as f64) as f32
    }

    /// [`View::pixels`] in double precision: monotone in the sphere (a
    /// containing sphere never projects smaller) even where f32 round-off
    /// would break ties, as incremental cuts need (hybrid paper §6).
    pub fn pixels_f64(&self, length: f64, center: Vec3, radius: f64) -> f64 {
        self.sphere_test().pixels(length, center, radius)
    }

    /// tan(fov_y / 2), which the frustum's planes and the stretch share.
    fn half_tan(&self) -> f64 {
        (0.5 * self.fov_y as f64).tan()
    }

    /// The worst off-axis stretch of a length, at the viewport's corner
    /// (`half_h` = [`View::half_tan`]).
    fn corner_stretch(&self, half_h: f64) -> f64 {
        let aspect = self.aspect() as f64;
        (1.0 + half_h * half_h * (1.0 + aspect * aspect)).sqrt()
    }

    /// [`View::pixels`] with its per-view constants computed once, in single
    /// precision, for callers projecting many lengths per frame (merge trees).
    pub fn projector(&self) -> Projector {
        Projector {
            eye: self.eye,
            forward: self.forward(),
            scale: self.focal_pixels() * self.corner_stretch(self.half_tan()) as f32,
        }
    }

    /// Whether the sphere can be seen at all (inside the view frustum, any depth
    /// in front of the eye).
    /// Computed in double precision, so that a containing sphere is never
    /// culled while one inside it is seen.
    pub fn sees_sphere(&self, center: Vec3, radius: f32) -> bool {
        self.sphere_test().sees(center, radius)
    }

    /// [`View::sees_sphere`] and [`View::pixels_f64`] with the view's
    /// constants (a tangent, square roots, five normalisations) computed once,
    /// for callers testing many spheres per frame (hybrid cuts).
    pub fn sphere_test(&self) -> SphereTest {
        self.sphere_test_after(None)
    }

    /// [`View::sphere_test`], taking the lens's constants from the previous
    /// frame's test `before` where the field of view and viewport are the
    /// same: per frame, only two square roots remain.
    pub fn sphere_test_after(&self, before: Option<&SphereTest>) -> SphereTest {
        let key = (self.fov_y.to_bits(), self.width, self.height);
        let lens = match before {
            Some(b) if b.lens.key == key => b.lens,
            _ => self.lens(key),
        };
        // In double precision throughout, unit to its round-off: a normal
        // longer than 1 by f32's round-off could cull a containing sphere
        // while a contained one is seen.
        let forward = (self.target - self.eye)
            .as_dvec3()
            .normalize_or(glam::DVec3::NEG_Z);
        SphereTest {
            eye: self.eye.as_dvec3(),
            forward,
            planes: self.side_planes_f64(forward, &lens),
            lens,
        }
    }

    fn lens(&self, key: (u32, u32, u32)) -> Lens {
        let ty = self.half_tan();
        let tx = ty * self.aspect() as f64;
        Lens {
            key,
            half_tan: [ty, tx],
            unit: [ty, tx].map(|t| 1.0 / (1.0 + t * t).sqrt()),
            focal: self.focal_pixels() as f64,
            stretch: self.corner_stretch(ty),
        }
    }

    /// Inward unit normals of the frustum's four side planes through the eye
    /// (callers testing many spheres per frame compute them once).
    pub fn side_planes(&self) -> [Vec3; 4] {
        let test = self.sphere_test();
        test.planes.map(|n| n.as_vec3())
    }

    /// The side planes from the unit forward direction `f`: `f·t ± u` for the
    /// orthonormal up and right vectors `u` and the half tangents `t`, whose
    /// lengths √(1 + t²) the lens divides out.
    fn side_planes_f64(&self, f: glam::DVec3, lens: &Lens) -> [glam::DVec3; 4] {
        let right = f.cross(self.up.as_dvec3()).normalize_or(glam::DVec3::X);
        let up = right.cross(f);
        let ([ty, tx], [ky, kx]) = (lens.half_tan, lens.unit);
        [
            (f * ty - up) * ky,
            (f * ty + up) * ky,
            (f * tx - right) * kx,
            (f * tx + right) * kx,
        ]
    }
}

/// What a view's projection takes from its field of view and viewport
/// alone, kept from frame to frame while they stay the same.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Lens {
    /// The field of view's bits and the viewport.
    key: (u32, u32, u32),
    /// tan of half the vertical and horizontal fields of view.
    half_tan: [f64; 2],
    /// 1 / √(1 + t²) of each, which makes the side planes' normals unit.
    unit: [f64; 2],
    focal: f64,
    stretch: f64,
}

/// The per-view constants of [`View::sees_sphere`] and [`View::pixels_f64`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereTest {
    eye: glam::DVec3,
    forward: glam::DVec3,
    planes: [glam::DVec3; 4],
    lens: Lens,
}

impl SphereTest {
    /// This test in single precision ([`NarrowTest`]).
    pub fn narrow(&self) -> NarrowTest {
        let [p0, p1, p2, p3] = self.planes;
        NarrowTest {
            eye: self.eye.as_vec3(),
            normals: [self.forward, p0, p1, p2, p3].map(|n| n.as_vec3()),
            scale: (self.lens.focal * self.lens.stretch) as f32,
        }
    }

    /// See [`View::sees_sphere`].
    #[inline(always)]
    pub fn sees(&self, center: Vec3, radius: f32) -> bool {
        let radius = radius as f64;
        let v = center.as_dvec3() - self.eye;
        let [p0, p1, p2, p3] = self.planes;
        // `&`, not `&&`: branch-free, so that tests over many spheres vectorise.
        (v.dot(self.forward) >= -radius)
            & (v.dot(p0) >= -radius)
            & (v.dot(p1) >= -radius)
            & (v.dot(p2) >= -radius)
            & (v.dot(p3) >= -radius)
    }

    /// See [`View::pixels_f64`].
    #[inline(always)]
    pub fn pixels(&self, length: f64, center: Vec3, radius: f64) -> f64 {
        length * self.lens.focal * self.lens.stretch / self.depth(center, radius)
    }

    /// Whether `length` projects to more than `pixels` ([`SphereTest::pixels`]
    /// without its division, for passes over many nodes).
    #[inline(always)]
    pub fn exceeds(&self, length: f64, center: Vec3, radius: f64, pixels: f64) -> bool {
        length * self.lens.focal * self.lens.stretch > pixels * self.depth(center, radius)
    }

    /// The sphere's nearest depth, at least the near distance.
    #[inline(always)]
    fn depth(&self, center: Vec3, radius: f64) -> f64 {
        ((center.as_dvec3() - self.eye).dot(self.forward) - radius).max(NEAR as f64)
    }
}

/// [`SphereTest`] in single precision, for passes over many spheres (eight
/// per AVX2 instruction instead of four). A comparison counts only outside a
/// band wider than the round-off of both precisions (at most about `7u` of
/// the numbers compared, `u` = 2⁻²⁴; the band is `≈ 67u`): the answer is sure
/// when one comparison is surely false or all are surely true, and otherwise
/// [`NarrowTest::UNSURE`], for [`SphereTest`] to settle. So the two never
/// disagree, and a cut taken with both is the cut taken with the exact test.
#[derive(Debug, Clone, Copy)]
pub struct NarrowTest {
    eye: Vec3,
    /// Forward, then the four side planes' inward normals.
    normals: [Vec3; 5],
    scale: f32,
}

/// The round-off band's width relative to the numbers compared.
const BAND: f32 = 4e-6;

impl NarrowTest {
    /// The answer of [`NarrowTest::refines`] when the single-precision
    /// numbers cannot settle it.
    pub const UNSURE: u8 = 2;

    /// `sees(center, reach) & exceeds(length, center, reach, pixels)` of the
    /// [`SphereTest`] it was made from, as 0 or 1, or [`NarrowTest::UNSURE`].
    /// Plain scalar arithmetic without branches, so that a pass over many
    /// spheres vectorises across them.
    #[inline(always)]
    pub fn refines(&self, [x, y, z]: [f32; 3], reach: f32, length: f32, pixels: f32) -> u8 {
        let v = [x - self.eye.x, y - self.eye.y, z - self.eye.z];
        let size = v[0].abs() + v[1].abs() + v[2].abs() + reach.abs();
        let band = BAND * size;
        let side = |n: Vec3| v[0] * n.x + v[1] * n.y + v[2] * n.z;
        // Certainly inside every side, or certainly outside one.
        let (mut inside, mut outside) = (true, false);
        for n in self.normals {
            let held = side(n) + reach;
            inside &= held > band;
            outside |= held < -band;
        }
        let depth = (side(self.normals[0]) - reach).max(NEAR);
        let (projected, allowed) = (length * self.scale, pixels * depth);
        let band = BAND * (projected.abs() + pixels.abs() * (size + NEAR));
        let (exceeds, within) = (projected - allowed > band, projected - allowed < -band);
        let no = outside | within;
        let yes = inside & exceeds;
        (u8::from(!no & !yes) * Self::UNSURE) | u8::from(!no & yes)
    }
}

/// The per-view constants of [`View::pixels`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Projector {
    eye: Vec3,
    forward: Vec3,
    scale: f32,
}

impl Projector {
    /// Whether `length` projects to more than `pixels` ([`View::pixels`]
    /// without its division, for tests over many nodes per frame).
    #[inline(always)]
    pub fn exceeds(&self, length: f32, center: Vec3, radius: f32, pixels: f32) -> bool {
        length * self.scale > pixels * self.depth(center, radius)
    }

    /// The nearest depth of the sphere, at least the near distance.
    #[inline(always)]
    fn depth(&self, center: Vec3, radius: f32) -> f32 {
        ((center - self.eye).dot(self.forward) - radius).max(NEAR)
    }
}

/// An error tolerance for a cut.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tolerance {
    /// Object space, as a fraction of the bounding-box diagonal.
    Relative(f32),
    /// Screen space, in pixels of the view.
    Pixels(f32),
}

impl Tolerance {
    /// Whether an element with error bound `error` (object space) inside the
    /// sphere (`center`, `radius`) is fine enough for `view`; `diagonal` is the
    /// model's bounding-box diagonal.
    pub fn accepts(
        &self,
        view: &View,
        diagonal: f32,
        error: f32,
        center: Vec3,
        radius: f32,
    ) -> bool {
        match *self {
            Tolerance::Relative(f) => error <= f * diagonal,
            Tolerance::Pixels(p) => view.pixels(error, center, radius) <= p,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit(rng: &mut crate::rng::Rng) -> Vec3 {
        loop {
            let v = Vec3::new(rng.f32(), rng.f32(), rng.f32()) * 2.0 - 1.0;
            if (1e-3..=1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }

    #[test]
    fn pixels_bound_the_true_projection_everywhere_in_the_sphere() {
        let view = View::orbit(Vec3::ZERO, 5.0, 0.7, 0.3);
        let vp = view.projection(0.01, 100.0) * view.view_matrix();
        let to_px = |p: Vec3| {
            let c = vp.project_point3(p);
            glam::Vec2::new(
                c.x * 0.5 * view.width as f32,
                c.y * 0.5 * view.height as f32,
            )
        };
        let mut rng = crate::rng::Rng::new(3);
        let (center, radius, len) = (Vec3::new(0.3, -0.2, 0.1), 1.0, 0.01);
        let bound = view.pixels(len, center, radius);
        for _ in 0..2000 {
            let p = center + unit(&mut rng) * radius * rng.f32();
            let d = unit(&mut rng) * len;
            let seen = to_px(p).distance(to_px(p + d));
            assert!(seen <= bound * 1.001, "{seen} > {bound}");
        }
    }

    #[test]
    fn frustum_keeps_the_target_and_drops_what_is_behind() {
        let view = View::orbit(Vec3::ZERO, 5.0, 0.0, 0.0);
        assert!(view.sees_sphere(Vec3::ZERO, 0.1));
        assert!(!view.sees_sphere(view.eye - view.forward() * 3.0, 0.5));
        assert!(!view.sees_sphere(Vec3::new(100.0, 0.0, 0.0), 1.0));
    }

    /// The single-precision test never contradicts the double-precision one,
    /// even for spheres placed on one of its six boundaries to the last bit,
    /// and is unsure only there.
    #[test]
    fn narrow_test_agrees_with_the_exact_one_or_says_unsure() {
        let mut rng = crate::rng::Rng::new(8);
        let (mut unsure, mut decided, mut random_unsure) = (0, 0, 0);
        for k in 0..20_000 {
            let scale = 10f32.powf(rng.f32() * 6.0 - 3.0);
            let center = (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * scale;
            let dist = scale * (0.1 + 5.0 * rng.f32());
            let view = View::orbit(center, dist, rng.f32() * 6.3, rng.f32() * 3.0 - 1.5);
            let test = view.sphere_test();
            let narrow = test.narrow();
            let mut c = center + (Vec3::new(rng.f32(), rng.f32(), rng.f32()) - 0.5) * dist;
            let reach = scale * 0.1 * rng.f32();
            let pixels = 0.5 + 20.0 * rng.f32();
            let depth = |c: Vec3| ((c - view.eye).dot(view.forward()) - reach).max(NEAR);
            let mut length =
                pixels * depth(c) / (test.lens.focal * test.lens.stretch) as f32 * rng.f32() * 2.0;
            let random = k % 3 == 0;
            if !random {
                // Onto one boundary: a side plane, or the projected length's.
                let which = rng.below(6);
                if which < 5 {
                    let n = [
                        test.forward,
                        test.planes[0],
                        test.planes[1],
                        test.planes[2],
                        test.planes[3],
                    ][which];
                    let s = (c.as_dvec3() - test.eye).dot(n) + reach as f64;
                    c = (c.as_dvec3() - n * s).as_vec3();
                } else {
                    length = (pixels as f64 * depth(c) as f64
                        / (test.lens.focal * test.lens.stretch))
                        as f32;
                }
            }
            let exact =
                test.sees(c, reach) & test.exceeds(length as f64, c, reach as f64, pixels as f64);
            match narrow.refines(c.to_array(), reach, length, pixels) {
                NarrowTest::UNSURE => {
                    unsure += 1;
                    random_unsure += usize::from(random);
                }
                answer => {
                    decided += 1;
                    assert_eq!(
                        answer,
                        u8::from(exact),
                        "view {view:?}, sphere {c} {reach}, length {length}"
                    );
                }
            }
        }
        assert!(
            unsure > 5_000 && decided > 6_000,
            "{unsure} unsure, {decided} decided"
        );
        assert!(random_unsure <= 10, "{random_unsure} random spheres unsure");
    }
}
