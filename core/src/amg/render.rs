//! §4, Fig. 10: the CPU reference renderer of domain primitives. Primitives
//! are taken front to back by the distance of their centres; each one facing
//! the camera is blended additively (colour·Ψ, Ψ) together with its not yet
//! rendered facing domain neighbours, then written to the depth buffer, which
//! locks its pixels against every primitive behind it.

use glam::Vec3;

use crate::io::image::decode_srgb;
use crate::lod::DrawSet;
use crate::view::View;

/// Additively blended linear RGB (premultiplied by Ψ) and the summed Ψ per pixel,
/// row 0 at the top.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

/// The camera basis and pixel-ray set-up of a view.
struct Camera {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_y: f32,
    tan_x: f32,
    width: u32,
    height: u32,
}

impl Camera {
    fn new(view: &View) -> Camera {
        let forward = view.forward();
        let right = forward.cross(view.up).normalize_or(Vec3::X);
        let tan_y = (0.5 * view.fov_y).tan();
        Camera {
            eye: view.eye,
            forward,
            right,
            up: right.cross(forward),
            tan_y,
            tan_x: tan_y * view.aspect(),
            width: view.width.max(1),
            height: view.height.max(1),
        }
    }

    /// Ray direction through a pixel centre, scaled to unit view depth.
    fn ray(&self, x: u32, y: u32) -> Vec3 {
        let sx = (2.0 * (x as f32 + 0.5) / self.width as f32 - 1.0) * self.tan_x;
        let sy = (1.0 - 2.0 * (y as f32 + 0.5) / self.height as f32) * self.tan_y;
        self.forward + self.right * sx + self.up * sy
    }

    /// Pixel bounds of a set of points (the whole viewport if one is behind the eye).
    fn pixel_bounds(&self, corners: &[Vec3]) -> (u32, u32, u32, u32) {
        let (mut x0, mut y0, mut x1, mut y1) = (
            f32::INFINITY,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NEG_INFINITY,
        );
        for c in corners {
            let d = *c - self.eye;
            let depth = d.dot(self.forward);
            if depth <= 1e-6 {
                return (0, 0, self.width, self.height);
            }
            let px = (d.dot(self.right) / (depth * self.tan_x) + 1.0) * 0.5 * self.width as f32;
            let py = (1.0 - d.dot(self.up) / (depth * self.tan_y)) * 0.5 * self.height as f32;
            x0 = x0.min(px);
            x1 = x1.max(px);
            y0 = y0.min(py);
            y1 = y1.max(py);
        }
        let clamp = |v: f32, max: u32| v.clamp(0.0, max as f32) as u32;
        (
            clamp(x0.floor(), self.width),
            clamp(y0.floor(), self.height),
            clamp(x1.ceil() + 1.0, self.width),
            clamp(y1.ceil() + 1.0, self.height),
        )
    }
}

/// Renders the splats of `set` for `view` with the algorithm of Fig. 10.
pub fn render(set: &DrawSet, view: &View) -> Image {
    let cam = Camera::new(view);
    let (w, h) = (cam.width, cam.height);
    let mut color = vec![[0f32; 4]; (w * h) as usize];
    let mut depth = vec![f32::INFINITY; (w * h) as usize];
    let mut order: Vec<usize> = (0..set.splats.len()).collect();
    order.sort_by(|&a, &b| {
        let d = |i: usize| set.splats[i].center.distance_squared(cam.eye);
        d(a).total_cmp(&d(b))
    });
    let facing = |i: usize| {
        let s = &set.splats[i];
        s.normal.dot(cam.eye - s.center) > 0.0
    };
    let mut rendered = vec![false; set.splats.len()];
    for &i in &order {
        if !facing(i) {
            continue;
        }
        let blend_with_neighbours =
            std::iter::once(i).chain(set.splats[i].neighbours.iter().copied());
        for j in blend_with_neighbours {
            if j < rendered.len() && !rendered[j] && facing(j) {
                raster(set, j, &cam, &depth, |p, _, rgba| {
                    let c = &mut color[p];
                    let a = rgba[3];
                    for k in 0..3 {
                        c[k] += rgba[k] * a;
                    }
                    c[3] += a;
                });
                rendered[j] = true;
            }
        }
        // Lock i's pixels: later (farther) primitives fail the depth test there.
        let mut lock = Vec::new();
        raster(set, i, &cam, &depth, |p, z, _| lock.push((p, z)));
        for (p, z) in lock {
            depth[p] = depth[p].min(z);
        }
    }
    Image {
        width: w,
        height: h,
        pixels: color,
    }
}

/// Calls `frag(pixel, depth, linear rgba)` for every fragment of splat `i`
/// with Ψ > 0 that passes the depth test.
fn raster(
    set: &DrawSet,
    i: usize,
    cam: &Camera,
    depth: &[f32],
    mut frag: impl FnMut(usize, f32, [f32; 4]),
) {
    let s = &set.splats[i];
    let Some(tex) = set.textures.get(s.texture) else {
        return;
    };
    let (a0, a1) = (s.axes[0], s.axes[1]);
    let (l0, l1) = (a0.length_squared(), a1.length_squared());
    if tex.width == 0 || tex.height == 0 || l0 <= 0.0 || l1 <= 0.0 {
        return;
    }
    let (x0, y0, x1, y1) = cam.pixel_bounds(&s.corners());
    let to_plane = s.normal.dot(s.center - cam.eye);
    for y in y0..y1 {
        for x in x0..x1 {
            let dir = cam.ray(x, y);
            let along = s.normal.dot(dir);
            if along.abs() < 1e-12 {
                continue;
            }
            let t = to_plane / along;
            if t <= 0.0 {
                continue;
            }
            let p = (y * cam.width + x) as usize;
            if t >= depth[p] {
                continue;
            }
            let rel = cam.eye + dir * t - s.center;
            let (u, v) = (rel.dot(a0) / l0, rel.dot(a1) / l1);
            if u.abs() > 1.0 || v.abs() > 1.0 {
                continue;
            }
            let tx = (((u + 1.0) * 0.5 * tex.width as f32) as u32).min(tex.width - 1);
            let ty = (((v + 1.0) * 0.5 * tex.height as f32) as u32).min(tex.height - 1);
            let texel = tex.rgba[(ty * tex.width + tx) as usize];
            if texel[3] == 0 {
                continue;
            }
            let rgba = [
                decode_srgb(texel[0]),
                decode_srgb(texel[1]),
                decode_srgb(texel[2]),
                texel[3] as f32 / 255.0,
            ];
            frag(p, t, rgba);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::amg::{AmgOptions, decompose, primitives};
    use crate::builtins::octahedron_points;
    use crate::progress::Progress;

    /// The face of the true octahedron |x|+|y|+|z| = 1 a ray hits first
    /// (bit k set when coordinate k is negative, as the builtin numbers them).
    fn hit_face(eye: Vec3, dir: Vec3) -> Option<usize> {
        let mut best: Option<(f32, usize)> = None;
        for f in 0..8 {
            let s = Vec3::new(
                if f & 1 == 0 { 1.0 } else { -1.0 },
                if f & 2 == 0 { 1.0 } else { -1.0 },
                if f & 4 == 0 { 1.0 } else { -1.0 },
            );
            let t = (1.0 - s.dot(eye)) / s.dot(dir);
            let p = eye + dir * t;
            if t > 0.0 && (p * s).min_element() >= -1e-5 && best.is_none_or(|(bt, _)| t < bt) {
                best = Some((t, f));
            }
        }
        best.map(|(_, f)| f)
    }

    #[test]
    fn octahedron_image_covers_its_silhouette_once_in_face_colours() {
        let pts = octahedron_points(16_000, 1);
        let ms = decompose(&pts, &AmgOptions::default(), &Progress::new()).unwrap();
        let level = (0..ms.levels())
            .find(|&l| ms.domains(l).len() == 8)
            .unwrap();
        let prims = primitives(&ms, level, 0.02, &Progress::new()).unwrap();
        let mut view = View::orbit(Vec3::ZERO, 2.6, 0.6, 0.45);
        (view.width, view.height) = (160, 120);
        let set = prims.draw_set(Some(view.eye));
        let image = render(&set, &view);
        let cam = Camera::new(&view);
        let colors = pts.colors.as_ref().unwrap();
        let (mut inside, mut covered, mut right_colour, mut outside, mut empty) = (0, 0, 0, 0, 0);
        for y in 0..cam.height {
            for x in 0..cam.width {
                let px = image.pixels[(y * cam.width + x) as usize];
                let dir = cam.ray(x, y);
                match hit_face(cam.eye, dir) {
                    Some(f) => {
                        // Skip pixels near an edge of the true faces: blending and
                        // the projection error (§5) live there.
                        let near_edge = [(-0.5, 0.0), (0.5, 0.0), (0.0, -0.5), (0.0, 0.5)]
                            .iter()
                            .any(|&(dx, dy)| {
                                let d = cam.ray(x, y)
                                    + cam.right * (dx * 3.0 * 2.0 * cam.tan_x / cam.width as f32)
                                    + cam.up * (dy * 3.0 * 2.0 * cam.tan_y / cam.height as f32);
                                hit_face(cam.eye, d) != Some(f)
                            });
                        if near_edge {
                            continue;
                        }
                        inside += 1;

                        if (0.8..=1.25).contains(&px[3]) {
                            covered += 1;
                            let c = Vec3::new(px[0], px[1], px[2]) / px[3];
                            if c.distance(colors[f]) < 0.1 {
                                right_colour += 1;
                            }
                        }
                    }
                    None => {
                        outside += 1;
                        empty += (px[3] == 0.0) as usize;
                    }
                }
            }
        }
        assert!(inside > 2000, "{inside} pixels inside");
        assert!(
            covered as f32 > 0.95 * inside as f32,
            "Ψ sums to ~1 on {covered} of {inside} pixels"
        );
        assert!(
            right_colour as f32 > 0.95 * inside as f32,
            "face colour on {right_colour} of {inside}"
        );
        assert!(
            empty as f32 > 0.98 * outside as f32,
            "{empty} of {outside} outside pixels empty"
        );
    }
}
