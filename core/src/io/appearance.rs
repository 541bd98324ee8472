//! What a surface shows a light at any point: its colour (`base_color`:
//! factor × texture × vertex colour) and its shading normal, the
//! interpolated vertex normal bent by the material's normal map (glTF 2.0
//! §3.9.3: tangent space, x and y scaled by the map's `scale`, in the
//! MikkTSpace frame clients rebuild, `geom::tangents`). Bakes transfer both
//! from the original, and the choice to bake measures both on its
//! candidates.

use glam::{Vec2, Vec3, Vec4};

use super::base_color::{SurfaceColor, bilinear};
use super::image::{Rgba, decode_rgba};
use crate::geom::normals::ShadingNormals;
use crate::geom::tangents::TangentFrame;
use crate::geom::{Image, TriMesh};

/// A mesh's colours and normals, its textures decoded.
pub struct Appearance<'a> {
    mesh: &'a TriMesh,
    color: Option<SurfaceColor<'a>>,
    normals: ShadingNormals<'a>,
    /// Per material, its decoded normal map and scale (one that does not
    /// decode, JPEG or damaged, leaves the interpolated normal).
    maps: Vec<Option<(Rgba, &'a Image, f32)>>,
    /// Per triangle, its corners' (normal, tangent) and UVs, the frame its
    /// map is read in; empty when no material has a map.
    frames: Vec<CornerFrames>,
}

/// A triangle's corners' (normal, tangent) and UVs.
type CornerFrames = ([(Vec3, Vec4); 3], [Vec2; 3]);

impl<'a> Appearance<'a> {
    pub fn new(mesh: &'a TriMesh) -> Appearance<'a> {
        let maps: Vec<_> = mesh.materials.as_ref().map_or(Vec::new(), |m| {
            m.table
                .iter()
                .map(|m| {
                    let (image, scale) = m.normal_texture.as_ref()?;
                    let rgba = decode_rgba(image).ok()?;
                    Some((rgba, image, *scale))
                })
                .collect()
        });
        // The frames of the mesh as a client stores it: one vertex per
        // wedge, in the same triangle order.
        let frames = match maps.iter().any(Option::is_some) {
            true => mesh
                .unwelded()
                .with_tangents()
                .map(|(records, tangents)| {
                    let normals = records.normals.as_deref().unwrap_or_default();
                    let uvs = records.uvs.as_deref().unwrap_or_default();
                    records
                        .triangles
                        .iter()
                        .map(|tri| {
                            let v = tri.map(|v| v as usize);
                            (v.map(|v| (normals[v], tangents[v])), v.map(|v| uvs[v]))
                        })
                        .collect()
                })
                .unwrap_or_default(),
            false => Vec::new(),
        };
        Appearance {
            mesh,
            color: SurfaceColor::new(mesh),
            normals: ShadingNormals::new(mesh),
            maps,
            frames,
        }
    }

    /// The linear colour at barycentric `b` of triangle `t` (white without
    /// materials).
    pub fn color(&self, t: usize, b: [f32; 3]) -> Vec3 {
        self.color.as_ref().map_or(Vec3::ONE, |s| s.at(t, b))
    }

    /// The unit shading normal at barycentric `b` of triangle `t`.
    pub fn normal(&self, t: usize, b: [f32; 3]) -> Vec3 {
        let interpolated = self.normals.at(t, b);
        let mesh = self.mesh;
        let material = mesh.materials.as_ref().map(|m| m.of(mesh.part(t)) as usize);
        let (Some(Some((rgba, image, scale))), Some((corners, uvs))) =
            (material.and_then(|m| self.maps.get(m)), self.frames.get(t))
        else {
            return interpolated;
        };
        let Some(frame) = TangentFrame::at(*corners, b) else {
            return interpolated;
        };
        let uv = uvs[0] * b[0] + uvs[1] * b[1] + uvs[2] * b[2];
        let texel = bilinear(rgba, image, uv, |v| v as f32 / 255.0) * 2.0 - Vec3::ONE;
        let local = (texel * Vec3::new(*scale, *scale, 1.0)).normalize_or(Vec3::Z);
        frame.world(local).normalize_or(interpolated)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::{Material, Materials};
    use crate::io::image::{REPEAT, png_image};
    use crate::lod::Texture;

    /// A flat square facing +z with UVs along x and y and a normal map of
    /// one texel tilting towards +u: its normal leans towards +x (the
    /// MikkTSpace tangent), by the texel's angle, and twice as far in x and
    /// y at scale 2; without the map it is +z.
    #[test]
    fn normal_maps_bend_the_normal_in_the_tangent_frame() {
        let texel = Vec3::new(0.5, 0.0, 0.866);
        let encode = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
        let texture = Texture {
            width: 1,
            height: 1,
            rgba: vec![[encode(texel.x), encode(texel.y), encode(texel.z), 255]],
        };
        let image = png_image(&texture, REPEAT);
        let mut square = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            vec![[0, 1, 2], [0, 2, 3]],
        );
        square.normals = Some(vec![Vec3::Z; 4]);
        square.uvs = Some(square.positions.iter().map(|p| p.truncate()).collect());
        let plain = Appearance::new(&square).normal(1, [0.2, 0.3, 0.5]);
        assert!(plain.abs_diff_eq(Vec3::Z, 1e-6), "{plain}");
        for (scale, want) in [(1.0, texel), (2.0, Vec3::new(1.0, 0.0, 0.866))] {
            let mut mapped = square.clone();
            mapped.materials = Some(Materials::single(Material {
                normal_texture: Some((image.clone(), scale)),
                ..Material::default()
            }));
            let want = want.normalize();
            for t in 0..2 {
                let got = Appearance::new(&mapped).normal(t, [0.2, 0.3, 0.5]);
                assert!(
                    got.angle_between(want) < 0.01,
                    "scale {scale}: {got} vs {want}"
                );
            }
        }
    }
}
