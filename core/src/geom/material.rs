//! Surface materials carried from the input to the exports: glTF 2.0's
//! metallic–roughness model with its base-colour texture. A mesh keeps one
//! material per part (a part never mixes materials: readers split parts by
//! material), so every method that keeps parts apart keeps its materials.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

/// How a material's alpha is used (glTF `alphaMode`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum AlphaMode {
    #[default]
    Opaque,
    /// Fragments with alpha below the cutoff are discarded.
    Mask(f32),
    Blend,
}

/// An encoded image (PNG or JPEG bytes as the input stored them) and how it is sampled.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Image {
    pub mime_type: String,
    /// Shared: every cut's mesh carries its materials, and copies cost nothing.
    pub bytes: Arc<[u8]>,
    /// glTF sampler enums (`magFilter`, `minFilter`, `wrapS`, `wrapT`); `None`: the default.
    pub mag_filter: Option<u32>,
    pub min_filter: Option<u32>,
    pub wrap_s: u32,
    pub wrap_t: u32,
}

/// The width and height an encoded image declares in its header (PNG's
/// IHDR, a JPEG's start-of-frame), read without decoding anything.
pub fn declared_size(bytes: &[u8]) -> Option<(u32, u32)> {
    let be32 = |at: usize| Some(u32::from_be_bytes(bytes.get(at..at + 4)?.try_into().ok()?));
    let be16 = |at: usize| Some(u16::from_be_bytes(bytes.get(at..at + 2)?.try_into().ok()?) as u32);
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") && bytes.get(12..16) == Some(b"IHDR") {
        return Some((be32(16)?, be32(20)?));
    }
    if !bytes.starts_with(&[0xff, 0xd8]) {
        return None;
    }
    // JPEG: walk the marker segments to the first start-of-frame.
    let mut at = 2;
    while bytes.get(at) == Some(&0xff) {
        let marker = *bytes.get(at + 1)?;
        let len = be16(at + 2)? as usize;
        let sof = matches!(marker, 0xc0..=0xcf) && !matches!(marker, 0xc4 | 0xc8 | 0xcc);
        if sof {
            return Some((be16(at + 7)?, be16(at + 5)?));
        }
        at = at.checked_add(2 + len)?;
    }
    None
}

impl Image {
    /// Its declared width and height ([`declared_size`]).
    pub fn size(&self) -> Option<(u32, u32)> {
        declared_size(&self.bytes)
    }
}

/// Texels per UV unit assumed where a material has no texture (its UVs
/// still map whatever texture a client gives it).
pub const UNTEXTURED_TEXELS: f32 = 1024.0;

/// A metallic–roughness material (glTF 2.0 §3.9.2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Material {
    pub name: Option<String>,
    /// Linear RGBA; it multiplies the texture and the vertex colours.
    pub base_color: [f32; 4],
    pub metallic: f32,
    pub roughness: f32,
    pub emissive: [f32; 3],
    pub alpha_mode: AlphaMode,
    pub double_sided: bool,
    /// Sampled with `TEXCOORD_0`.
    pub base_color_texture: Option<Image>,
    /// A tangent-space normal map sampled with `TEXCOORD_0`, in the frame of
    /// MikkTSpace tangents (glTF's default, [`super::tangents`]), and its
    /// `scale` (glTF 2.0 §3.9.3).
    #[serde(default)]
    pub normal_texture: Option<(Image, f32)>,
    /// The vertex attributes the input gave this material's vertices.
    pub vertex_attributes: VertexAttributes,
}

/// Which optional vertex attributes a material's vertices came with. Parts
/// are merged into one mesh, whose attribute arrays cover every vertex, so
/// exports write a part's `COLOR_0` and `TEXCOORD_0` only where the input had
/// them, never the filler another part's attributes left.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct VertexAttributes {
    pub colors: bool,
    pub uvs: bool,
}

impl Default for VertexAttributes {
    /// Unknown (not read from a glTF primitive): whatever the mesh has.
    fn default() -> Self {
        Self {
            colors: true,
            uvs: true,
        }
    }
}

impl Default for Material {
    /// The look of a mesh that came without materials: matte white clay.
    fn default() -> Self {
        Self {
            name: None,
            base_color: [1.0; 4],
            metallic: 0.0,
            roughness: 0.8,
            emissive: [0.0; 3],
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
            base_color_texture: None,
            normal_texture: None,
            vertex_attributes: VertexAttributes::default(),
        }
    }
}

/// The materials of a mesh's parts: part `p` wears `table[of_part[p]]`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Materials {
    pub table: Vec<Material>,
    pub of_part: Vec<u32>,
}

impl Materials {
    /// Index ranges for triangles of `parts` (for materials read from a saved file).
    pub fn check(&self, parts: &[u32]) -> Result<(), String> {
        super::check_indices("material", self.of_part.iter().copied(), self.table.len())?;
        super::check_indices("part", parts.iter().copied(), self.of_part.len())
    }

    /// One material for a mesh of one part.
    pub fn single(m: Material) -> Self {
        Self {
            table: vec![m],
            of_part: vec![0],
        }
    }

    /// Texels per UV unit on part `p`: its base-colour texture's larger
    /// side (texture errors are counted in these), [`UNTEXTURED_TEXELS`]
    /// without one.
    pub fn texels_per_uv(&self, part: u32) -> f32 {
        self.table
            .get(self.of(part) as usize)
            .and_then(|m| m.base_color_texture.as_ref()?.size())
            .map_or(UNTEXTURED_TEXELS, |(w, h)| w.max(h) as f32)
    }

    /// The material index of part `p` (parts past the list wear the first).
    pub fn of(&self, part: u32) -> u32 {
        self.of_part.get(part as usize).copied().unwrap_or(0)
    }

    /// Index of `m` in the table, adding it when new (tables stay free of copies).
    pub fn intern(&mut self, m: &Material) -> u32 {
        match self.table.iter().position(|t| t == m) {
            Some(i) => i as u32,
            None => {
                self.table.push(m.clone());
                self.table.len() as u32 - 1
            }
        }
    }

    /// Appends the parts of a mesh with `parts` parts wearing `theirs` (or the
    /// default material when it has none), after our `ours` parts.
    pub fn append(&mut self, ours: u32, theirs: Option<&Materials>, parts: u32) {
        self.of_part.resize(ours as usize, 0);
        for p in 0..parts {
            let m = match theirs {
                Some(t) => t.table[t.of(p) as usize].clone(),
                None => Material::default(),
            };
            let i = self.intern(&m);
            self.of_part.push(i);
        }
    }
}
