//! Textures packed into atlases (issue 50, item 4): an AMG LOD's splats,
//! one texture each, are written as one primitive with one material per
//! atlas, a handful of draw calls where there were two per splat.
//!
//! Rectangles are placed by `guillotiere` (WebRender's atlas allocator),
//! tallest first, in the smallest power-of-two atlas (square, or twice as
//! wide as high) that holds them, up to [`MAX_ATLAS`] a side; what does not
//! fit starts another. Each
//! texture is surrounded by [`MARGIN`] texels repeating its edge, so a
//! bilinear sample at its border reads what clamp-to-edge read before, and
//! its quad maps onto its texels exactly.

use guillotiere::{AtlasAllocator, size2};

use crate::lod::Texture;

/// An atlas side at most (texels), unless one texture alone is larger.
pub const MAX_ATLAS: u32 = 4096;
/// Texels around each texture repeating its edge.
pub const MARGIN: u32 = 2;

/// One atlas and where each of its textures lies in it.
pub struct Atlas {
    pub texture: Texture,
    /// (the texture's index in the input, its texels as a UV rectangle
    /// `[u0, v0, u1, v1]` of the atlas).
    pub members: Vec<(usize, [f32; 4])>,
}

/// Packs `textures` into as few atlases as hold them; every texture lies
/// in exactly one. The same input gives the same atlases.
pub fn pack(textures: &[&Texture]) -> Vec<Atlas> {
    let padded = |t: &Texture| (t.width.max(1) + 2 * MARGIN, t.height.max(1) + 2 * MARGIN);
    // Tall first, then wide: shelves fill evenly.
    let mut left: Vec<usize> = (0..textures.len()).collect();
    left.sort_by_key(|&i| {
        let (w, h) = padded(textures[i]);
        (std::cmp::Reverse(h), std::cmp::Reverse(w), i)
    });
    let mut atlases = Vec::new();
    while !left.is_empty() {
        let largest_pow2 = |left: &[usize]| {
            let sides = left.iter().map(|&i| {
                let (w, h) = padded(textures[i]);
                w.max(h)
            });
            sides.max().unwrap_or(1).next_power_of_two()
        };
        let limit = MAX_ATLAS.max(largest_pow2(&left));
        let area: u64 = left
            .iter()
            .map(|&i| {
                let (w, h) = padded(textures[i]);
                w as u64 * h as u64
            })
            .sum();
        // From the power-of-two square under the area, doubling the width
        // then the height: the first size that holds them all.
        let root = ((area as f64).sqrt() as u32).max(1);
        let start = (1u32 << (31 - root.leading_zeros())).max(largest_pow2(&left));
        let mut size = [start.min(limit); 2];
        let (placed, rest) = loop {
            let (placed, rest) = place(textures, &left, size);
            if rest.is_empty() || size == [limit; 2] {
                break (placed, rest);
            }
            let grow = usize::from(size[0] > size[1] || size[0] >= limit);
            size[grow] = (2 * size[grow]).min(limit);
        };
        atlases.push(blit(textures, &placed, size));
        left = rest;
    }
    atlases
}

/// Places `order` in an atlas of `size` (width, height): each placed one
/// with its padded rectangle's corner, and those that did not fit.
fn place(
    textures: &[&Texture],
    order: &[usize],
    size: [u32; 2],
) -> (Vec<(usize, [u32; 2])>, Vec<usize>) {
    let mut allocator = AtlasAllocator::new(size2(size[0] as i32, size[1] as i32));
    let (mut placed, mut rest) = (Vec::new(), Vec::new());
    for &i in order {
        let t = textures[i];
        let size = size2(
            (t.width.max(1) + 2 * MARGIN) as i32,
            (t.height.max(1) + 2 * MARGIN) as i32,
        );
        match allocator.allocate(size) {
            Some(a) => placed.push((i, [a.rectangle.min.x as u32, a.rectangle.min.y as u32])),
            None => rest.push(i),
        }
    }
    (placed, rest)
}

/// The atlas of `placed`: each texture's texels, ringed by its repeated
/// edge; the rest transparent.
fn blit(textures: &[&Texture], placed: &[(usize, [u32; 2])], size: [u32; 2]) -> Atlas {
    let s = size[0] as usize;
    let mut rgba = vec![[0u8; 4]; s * size[1] as usize];
    let mut members = Vec::with_capacity(placed.len());
    for &(i, [x0, y0]) in placed {
        let t = textures[i];
        let (w, h) = (t.width as i64, t.height as i64);
        let m = MARGIN as i64;
        for y in -m..h.max(1) + m {
            for x in -m..w.max(1) + m {
                let texel = match (w, h) {
                    (0, _) | (_, 0) => [0; 4],
                    _ => {
                        let (sx, sy) = (x.clamp(0, w - 1), y.clamp(0, h - 1));
                        t.rgba
                            .get((sy * w + sx) as usize)
                            .copied()
                            .unwrap_or([0; 4])
                    }
                };
                let (ax, ay) = ((x0 as i64 + m + x) as usize, (y0 as i64 + m + y) as usize);
                rgba[ay * s + ax] = texel;
            }
        }
        let (u0, v0) = (x0 + MARGIN, y0 + MARGIN);
        let [w, h] = size.map(|s| s as f32);
        members.push((
            i,
            [
                u0 as f32 / w,
                v0 as f32 / h,
                (u0 + t.width) as f32 / w,
                (v0 + t.height) as f32 / h,
            ],
        ));
    }
    members.sort_by_key(|m| m.0);
    Atlas {
        texture: Texture {
            width: size[0],
            height: size[1],
            rgba,
        },
        members,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(w: u32, h: u32, seed: u32) -> Texture {
        Texture {
            width: w,
            height: h,
            rgba: (0..w * h)
                .map(|i| {
                    let v = i.wrapping_mul(2_654_435_761).wrapping_add(seed);
                    v.to_le_bytes()
                })
                .collect(),
        }
    }

    /// Every texel of every texture is in its atlas where its rectangle
    /// says, its edge repeated around it; rectangles do not overlap; many
    /// textures share an atlas, and an oversized set spills into more.
    #[test]
    fn every_texel_lands_where_its_rectangle_says() {
        let textures: Vec<Texture> = (0..300)
            .map(|i| texture(1 + (i * 7) % 61, 1 + (i * 13) % 37, i))
            .collect();
        let refs: Vec<&Texture> = textures.iter().collect();
        let atlases = pack(&refs);
        assert_eq!(atlases.len(), 1, "300 small textures share one atlas");
        let a = &atlases[0];
        let (w, h) = (a.texture.width, a.texture.height);
        assert!(w <= 1024 && (w == h || w == 2 * h), "{w}×{h}");
        // The padded textures fill over a quarter of it.
        let padded: u32 = textures
            .iter()
            .map(|t| (t.width + 2 * MARGIN) * (t.height + 2 * MARGIN))
            .sum();
        assert!(4 * padded > w * h, "{padded} texels in {w}×{h}");
        assert_eq!(a.members.len(), 300);
        let (w, h) = (w as f32, h as f32);
        let mut cover = vec![false; a.texture.rgba.len()];
        for &(i, [u0, v0, u1, v1]) in &a.members {
            let t = &textures[i];
            let (x0, y0) = ((u0 * w) as usize, (v0 * h) as usize);
            assert_eq!(
                ((u1 * w) as usize - x0, (v1 * h) as usize - y0),
                (t.width as usize, t.height as usize)
            );
            for y in 0..t.height as usize {
                for x in 0..t.width as usize {
                    let at = (y0 + y) * a.texture.width as usize + x0 + x;
                    assert_eq!(a.texture.rgba[at], t.rgba[y * t.width as usize + x]);
                    assert!(!cover[at], "texture {i} overlaps another");
                    cover[at] = true;
                }
            }
            // The margin repeats the edge: left of (0, 0) is (0, 0).
            let m = MARGIN as usize;
            assert_eq!(
                a.texture.rgba[(y0 - m) * a.texture.width as usize + x0 - m],
                t.rgba[0]
            );
        }
        let again = pack(&refs);
        assert_eq!(again[0].texture, a.texture, "the same bytes every time");

        let big: Vec<Texture> = (0..5).map(|i| texture(2000, 2000, i)).collect();
        let refs: Vec<&Texture> = big.iter().collect();
        let atlases = pack(&refs);
        assert!(atlases.len() > 1 && atlases.len() <= 5, "{}", atlases.len());
        let mut all: Vec<usize> = atlases
            .iter()
            .flat_map(|a| a.members.iter().map(|m| m.0))
            .collect();
        all.sort_unstable();
        assert_eq!(all, [0, 1, 2, 3, 4], "each in exactly one atlas");
        assert!(atlases.iter().all(|a| a.texture.width <= MAX_ATLAS));
    }
}
