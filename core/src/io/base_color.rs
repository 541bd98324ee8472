//! The colour a textured surface shows (glTF 2.0 §3.9.2): the material's
//! base-colour factor × its texture at the corner's UV × the vertex colour,
//! linear. Methods that make a new surface from the vertices (AMG's splats,
//! issue 50 item 5) take their colours from here, so an impostor of a
//! textured model wears its texture, not white clay.

use glam::{Vec2, Vec3};

use super::image::{CLAMP_TO_EDGE, MIRRORED_REPEAT, Rgba, decode_rgba, decode_srgb};
use crate::geom::{Image, TriMesh};

/// A mesh's materials with their textures decoded: the colour the surface
/// shows at any point of a triangle.
pub struct SurfaceColor<'a> {
    mesh: &'a TriMesh,
    materials: &'a crate::geom::Materials,
    /// Per material, its decoded texture (one that does not decode, JPEG or
    /// damaged, leaves its factor).
    textures: Vec<Option<(Rgba, &'a Image)>>,
}

impl<'a> SurfaceColor<'a> {
    /// `None` when the mesh has no materials.
    pub fn new(mesh: &'a TriMesh) -> Option<SurfaceColor<'a>> {
        let materials = mesh.materials.as_ref()?;
        let textures = materials
            .table
            .iter()
            .map(|m| {
                let image = m.base_color_texture.as_ref()?;
                decode_rgba(image).ok().map(|rgba| (rgba, image))
            })
            .collect();
        Some(SurfaceColor {
            mesh,
            materials,
            textures,
        })
    }

    /// Whether the materials add nothing to the vertex colours (no texture,
    /// white factors).
    fn plain(&self) -> bool {
        self.materials
            .table
            .iter()
            .all(|m| m.base_color_texture.is_none() && m.base_color[..3] == [1.0; 3])
    }

    /// The linear colour at barycentric `bary` of triangle `t`: its
    /// material's factor × its texture at the interpolated UV × the
    /// interpolated vertex colour.
    pub fn at(&self, t: usize, bary: [f32; 3]) -> Vec3 {
        let mesh = self.mesh;
        let part = mesh.parts.as_ref().map_or(0, |p| p[t]);
        let m = self.materials.of(part) as usize;
        let Some(material) = self.materials.table.get(m) else {
            return Vec3::ONE;
        };
        let tri = mesh.triangles[t];
        let wedges = mesh.wedges.as_ref();
        // A corner's attribute: its wedge's, else its vertex's.
        let corner =
            |k: usize, per_wedge: Option<&Vec<Vec3>>, per_vertex: Option<&Vec<Vec3>>| match (
                wedges, per_wedge,
            ) {
                (Some(w), Some(a)) => a.get(w.corners[t][k] as usize).copied(),
                _ => per_vertex.and_then(|a| a.get(tri[k] as usize).copied()),
            };
        let mut colour = Vec3::from_slice(&material.base_color[..3]);
        if material.vertex_attributes.uvs
            && let Some((rgba, image)) = &self.textures[m]
        {
            let uv_of = |k: usize| match (wedges, wedges.and_then(|w| w.uvs.as_ref())) {
                (Some(w), Some(u)) => u.get(w.corners[t][k] as usize).copied(),
                _ => mesh
                    .uvs
                    .as_ref()
                    .and_then(|u| u.get(tri[k] as usize).copied()),
            };
            if let (Some(a), Some(b), Some(c)) = (uv_of(0), uv_of(1), uv_of(2)) {
                let uv = a * bary[0] + b * bary[1] + c * bary[2];
                colour *= bilinear(rgba, image, uv, decode_srgb);
            }
        }
        if material.vertex_attributes.colors {
            let c = |k| {
                corner(
                    k,
                    wedges.and_then(|w| w.colors.as_ref()),
                    mesh.colors.as_ref(),
                )
            };
            if let (Some(a), Some(b), Some(d)) = (c(0), c(1), c(2)) {
                colour *= a * bary[0] + b * bary[1] + d * bary[2];
            }
        }
        colour
    }
}

/// Each vertex's surface colour, its corners' colours weighted by their
/// triangles' areas; `None` when the materials add nothing to the vertex
/// colours (no texture, white factors) or there are none.
pub fn vertex_colors(mesh: &TriMesh) -> Option<Vec<Vec3>> {
    let surface = SurfaceColor::new(mesh)?;
    if surface.plain() {
        return None;
    }
    let mut sum = vec![Vec3::ZERO; mesh.positions.len()];
    let mut weight = vec![0.0f32; mesh.positions.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|v| mesh.positions[v as usize]);
        let area = 0.5 * (b - a).cross(c - a).length();
        for (k, &v) in tri.iter().enumerate() {
            let mut bary = [0.0; 3];
            bary[k] = 1.0;
            // A degenerate triangle still speaks for an isolated corner.
            let w = area.max(f32::MIN_POSITIVE);
            sum[v as usize] += w * surface.at(t, bary);
            weight[v as usize] += w;
        }
    }
    Some(
        sum.iter()
            .zip(&weight)
            .map(|(s, &w)| if w > 0.0 { *s / w } else { Vec3::ONE })
            .collect(),
    )
}

/// The texture's colour at `uv`, each channel read by `decode` (sRGB for
/// colours, linear for normal maps), bilinear, under the image's wrap
/// modes (glTF's UV origin is the image's top left).
pub(super) fn bilinear(rgba: &Rgba, image: &Image, uv: Vec2, decode: fn(u8) -> f32) -> Vec3 {
    let (w, h) = (rgba.width as i64, rgba.height as i64);
    if !uv.is_finite() || w == 0 || h == 0 {
        return Vec3::ONE;
    }
    let x = uv.x as f64 * w as f64 - 0.5;
    let y = uv.y as f64 * h as f64 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
    let texel = |i: i64, j: i64| {
        let (i, j) = (wrap(i, w, image.wrap_s), wrap(j, h, image.wrap_t));
        let [r, g, b, _] = rgba.texels[(j * w + i) as usize];
        Vec3::new(decode(r), decode(g), decode(b))
    };
    let (i, j) = (x0 as i64, y0 as i64);
    let top = texel(i, j).lerp(texel(i + 1, j), fx);
    let bottom = texel(i, j + 1).lerp(texel(i + 1, j + 1), fx);
    top.lerp(bottom, fy)
}

/// Texel index `i` of `n` under a glTF wrap mode (repeat by default).
fn wrap(i: i64, n: i64, mode: u32) -> i64 {
    match mode {
        CLAMP_TO_EDGE => i.clamp(0, n - 1),
        MIRRORED_REPEAT => {
            let m = i.rem_euclid(2 * n);
            if m < n { m } else { 2 * n - 1 - m }
        }
        _ => i.rem_euclid(n),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Material, Materials};
    use crate::io::image::{REPEAT, png_image};
    use crate::lod::Texture;

    /// A quad whose corners sit on the four texel centres of a 2×2 texture:
    /// each vertex wears its texel × the factor × its vertex colour; a UV a
    /// whole turn away repeats, and a clamped one stays at the edge.
    #[test]
    fn vertices_wear_their_texels_times_factor_and_colour() {
        let texels = [
            [255, 0, 0, 255],
            [0, 255, 0, 255],
            [0, 0, 255, 255],
            [255, 255, 255, 255],
        ];
        let texture = Texture {
            width: 2,
            height: 2,
            rgba: texels.to_vec(),
        };
        let image = png_image(&texture, REPEAT);
        let material = Material {
            base_color: [0.5, 1.0, 1.0, 1.0],
            base_color_texture: Some(image),
            ..Material::default()
        };
        let mut mesh = TriMesh::new(
            vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
            ],
            vec![[0, 1, 2], [1, 3, 2]],
        );
        mesh.uvs = Some(vec![
            Vec2::new(0.25, 0.25),
            Vec2::new(1.75, 0.25),
            Vec2::new(0.25, 0.75),
            Vec2::new(0.75, 0.75),
        ]);
        mesh.colors = Some(vec![
            Vec3::ONE,
            Vec3::ONE,
            Vec3::ONE,
            Vec3::new(1.0, 0.5, 0.25),
        ]);
        mesh.materials = Some(Materials::single(material));
        let colours = vertex_colors(&mesh).expect("a textured material");
        let want = [
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.5, 0.5, 0.25),
        ];
        for (v, (got, want)) in colours.iter().zip(want).enumerate() {
            assert!(
                (*got - want).abs().max_element() < 1e-3,
                "vertex {v}: {got} vs {want}"
            );
        }
        // Clamped, the UV past the right edge reads the right column, halfway
        // between its rows: green and white.
        let mut clamped = mesh.clone();
        let m = &mut clamped.materials.as_mut().unwrap().table[0];
        m.base_color_texture.as_mut().unwrap().wrap_s = CLAMP_TO_EDGE;
        m.base_color = [1.0; 4];
        clamped.uvs.as_mut().unwrap()[1] = Vec2::new(3.0, 0.5);
        let c = vertex_colors(&clamped).unwrap()[1];
        assert!(
            (c - Vec3::new(0.5, 1.0, 0.5)).abs().max_element() < 1e-3,
            "{c}"
        );
        // White clay adds nothing to the vertex colours.
        mesh.materials = Some(Materials::single(Material::default()));
        assert!(vertex_colors(&mesh).is_none());
    }
}
