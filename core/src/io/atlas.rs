//! Textures packed into atlases (issue 50, item 4): an AMG LOD's splats,
//! one texture each, are written as one primitive with one material per
//! atlas, a handful of draw calls where there were two per splat.
//!
//! Rectangles are placed by `guillotiere` (WebRender's atlas allocator),
//! largest first, in an atlas of the least power-of-two size that holds
//! them, up to [`MAX_ATLAS`] a side; what does not fit starts another. Each
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
        let largest = left.iter().map(|&i| {
            let (w, h) = padded(textures[i]);
            w.max(h)
        });
        let limit = MAX_ATLAS.max(largest.max().unwrap_or(1).next_power_of_two());
        let area: u64 = left
            .iter()
            .map(|&i| {
                let (w, h) = padded(textures[i]);
                w as u64 * h as u64
            })
            .sum();
        let mut side = ((area as f64).sqrt().ceil() as u32)
            .next_power_of_two()
            .min(limit);
        let (placed, rest) = loop {
            let (placed, rest) = place(textures, &left, side);
            if rest.is_empty() || side >= limit {
                break (placed, rest);
            }
            side *= 2;
        };
        atlases.push(blit(textures, &placed, side));
        left = rest;
    }
    atlases
}

/// Places `order` in a `side`² atlas: each placed one with its padded
/// rectangle's corner, and those that did not fit.
fn place(
    textures: &[&Texture],
    order: &[usize],
    side: u32,
) -> (Vec<(usize, [u32; 2])>, Vec<usize>) {
    let mut allocator = AtlasAllocator::new(size2(side as i32, side as i32));
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
fn blit(textures: &[&Texture], placed: &[(usize, [u32; 2])], side: u32) -> Atlas {
    let s = side as usize;
    let mut rgba = vec![[0u8; 4]; s * s];
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
        let side = side as f32;
        members.push((
            i,
            [
                u0 as f32 / side,
                v0 as f32 / side,
                (u0 + t.width) as f32 / side,
                (v0 + t.height) as f32 / side,
            ],
        ));
    }
    members.sort_by_key(|m| m.0);
    Atlas {
        texture: Texture {
            width: side,
            height: side,
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
        assert!(a.texture.width <= 1024, "{}", a.texture.width);
        assert_eq!(a.members.len(), 300);
        let side = a.texture.width as f32;
        let mut cover = vec![false; a.texture.rgba.len()];
        for &(i, [u0, v0, u1, v1]) in &a.members {
            let t = &textures[i];
            let (x0, y0) = ((u0 * side) as usize, (v0 * side) as usize);
            assert_eq!(
                ((u1 * side) as usize - x0, (v1 * side) as usize - y0),
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
