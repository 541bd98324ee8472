//! How different two renders of the same view look: the share of pixels that
//! only one of them covers (what a LOD switch makes pop at the outline), the
//! PSNR of their shaded images (what it changes inside), and a picture of
//! where they differ. Pure pixel code, so the GPU that rendered them is
//! someone else's concern.

use crate::lod::Texture;

/// PSNR of identical images, in dB: the true value is infinite, which JSON
/// cannot carry and a mean over views cannot use. Only invisible differences
/// come near it: one unit off in one channel of one pixel is 89 dB in a 64²
/// image, and 101 dB in a 256² one, reported as the cap.
pub const PSNR_CAP_DB: f64 = 100.0;

/// Amplification of the per-channel difference in [`difference_image`], so
/// that small shading changes are visible.
const AMPLIFY: u16 = 4;

/// Pixels only the first render covers, and only the second, in the difference image.
const ONLY_A: [u8; 4] = [230, 40, 40, 255];
const ONLY_B: [u8; 4] = [40, 200, 60, 255];

/// A render read back from the GPU: the shaded image (opaque RGBA8, sRGB, rows
/// from the top) and which of its pixels the model covers.
#[derive(Debug, Clone, PartialEq)]
pub struct Render {
    pub image: Texture,
    /// One per pixel, in the image's order.
    pub coverage: Vec<bool>,
}

/// The two measures for one view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Difference {
    /// Fraction of all pixels covered by exactly one of the two renders.
    pub silhouette: f64,
    /// Of the shaded RGB images, in dB, capped at [`PSNR_CAP_DB`].
    pub psnr: f64,
    /// Of the pixels both cover, the fraction that shows another colour
    /// ([`wrong_colour`]): a texture bled across a seam, a chart stretched.
    pub wrong_colour: f64,
}

/// A chromaticity difference (each channel's share of r + g + b) past which
/// a pixel shows another colour, not the same colour shaded differently
/// (shading scales all three channels, which leaves their shares alone).
pub const WRONG_COLOUR: f32 = 0.08;

/// Pixels darker than this sum of channels have no reliable hue.
const DARK: u32 = 60;

/// Both measures of `a` against `b`.
///
/// # Panics
/// If the renders differ in size.
pub fn difference(a: &Render, b: &Render) -> Difference {
    Difference {
        silhouette: silhouette_difference(a, b),
        psnr: psnr(&a.image, &b.image),
        wrong_colour: wrong_colour(a, b),
    }
}

/// Of the pixels both `a` and `b` cover and show bright enough to have a
/// hue, the fraction whose chromaticities differ by more than
/// [`WRONG_COLOUR`] (0 where they share none).
///
/// # Panics
/// If the renders differ in size.
pub fn wrong_colour(a: &Render, b: &Render) -> f64 {
    assert_eq!(a.coverage.len(), b.coverage.len(), "renders of one size");
    let (mut both, mut wrong) = (0usize, 0usize);
    for ((p, q), (x, y)) in a
        .image
        .rgba
        .iter()
        .zip(&b.image.rgba)
        .zip(a.coverage.iter().zip(&b.coverage))
    {
        let sum = |p: &[u8; 4]| p[..3].iter().map(|&c| u32::from(c)).sum::<u32>();
        if *x && *y && sum(p) >= DARK && sum(q) >= DARK {
            both += 1;
            let share = |p: &[u8; 4], c: usize| f32::from(p[c]) / sum(p) as f32;
            wrong += usize::from((0..3).any(|c| (share(p, c) - share(q, c)).abs() > WRONG_COLOUR));
        }
    }
    if both == 0 {
        0.0
    } else {
        wrong as f64 / both as f64
    }
}

/// The fraction of pixels covered by exactly one of `a` and `b` (0 for the
/// same silhouette, 1 when they share no pixel and cover all of them).
///
/// # Panics
/// If the renders differ in size.
pub fn silhouette_difference(a: &Render, b: &Render) -> f64 {
    assert_eq!(a.coverage.len(), b.coverage.len(), "renders of one size");
    if a.coverage.is_empty() {
        return 0.0;
    }
    let differ = a
        .coverage
        .iter()
        .zip(&b.coverage)
        .filter(|(x, y)| x != y)
        .count();
    differ as f64 / a.coverage.len() as f64
}

/// Peak signal-to-noise ratio of the RGB channels in dB (mean squared error
/// over all pixels, peak 255), [`PSNR_CAP_DB`] at most.
///
/// # Panics
/// If the images differ in size.
pub fn psnr(a: &Texture, b: &Texture) -> f64 {
    assert_eq!(
        (a.width, a.height, a.rgba.len()),
        (b.width, b.height, b.rgba.len()),
        "images of one size"
    );
    let squared: u64 = a
        .rgba
        .iter()
        .zip(&b.rgba)
        .flat_map(|(p, q)| (0..3).map(move |c| (i64::from(p[c]) - i64::from(q[c])).pow(2) as u64))
        .sum();
    let samples = 3 * a.rgba.len() as u64;
    if squared == 0 || samples == 0 {
        return PSNR_CAP_DB;
    }
    let mse = squared as f64 / samples as f64;
    (10.0 * (255.0f64 * 255.0 / mse).log10()).min(PSNR_CAP_DB)
}

/// Where `a` and `b` differ, as an opaque image of their size: pixels only
/// `a` covers in red, only `b` in green, and elsewhere their per-channel
/// difference amplified fourfold (black where they agree).
///
/// # Panics
/// If the renders differ in size.
pub fn difference_image(a: &Render, b: &Render) -> Texture {
    assert_eq!(a.coverage.len(), b.coverage.len(), "renders of one size");
    let rgba = a
        .image
        .rgba
        .iter()
        .zip(&b.image.rgba)
        .zip(a.coverage.iter().zip(&b.coverage))
        .map(|((p, q), covered)| match covered {
            (true, false) => ONLY_A,
            (false, true) => ONLY_B,
            _ => {
                let d = |c: usize| (u16::from(p[c].abs_diff(q[c])) * AMPLIFY).min(255) as u8;
                [d(0), d(1), d(2), 255]
            }
        })
        .collect();
    Texture {
        width: a.image.width,
        height: a.image.height,
        rgba,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w`×`h` render of a grey square covering columns `x0..x1` on a dark background.
    fn square(w: u32, h: u32, x0: u32, x1: u32) -> Render {
        let coverage: Vec<bool> = (0..w * h).map(|i| (x0..x1).contains(&(i % w))).collect();
        let rgba = coverage
            .iter()
            .map(|&c| {
                if c {
                    [200, 180, 160, 255]
                } else {
                    [10, 12, 15, 255]
                }
            })
            .collect();
        Render {
            image: Texture {
                width: w,
                height: h,
                rgba,
            },
            coverage,
        }
    }

    /// The same square shaded darker shows no other colour; a quarter of
    /// it bled blue does, and only pixels both cover count.
    #[test]
    fn another_colour_is_not_the_same_colour_shaded() {
        let a = square(16, 8, 4, 12);
        let mut shaded = a.clone();
        for p in shaded.image.rgba.iter_mut() {
            *p = [p[0] / 2 + 1, p[1] / 2, p[2] / 2, 255];
        }
        assert!(wrong_colour(&a, &shaded) < 1e-9);
        let mut bled = a.clone();
        for (i, p) in bled.image.rgba.iter_mut().enumerate() {
            if (4..6).contains(&(i % 16)) {
                *p = [60, 90, 200, 255];
            }
        }
        assert_eq!(wrong_colour(&a, &bled), 0.25);
        let wider = square(16, 8, 0, 16);
        assert_eq!(wrong_colour(&a, &wider), 0.0, "only where both cover");
        assert_eq!(difference(&a, &bled).wrong_colour, 0.25);
    }

    #[test]
    fn identical_renders_differ_by_nothing_and_give_the_capped_psnr() {
        let a = square(16, 8, 4, 10);
        let d = difference(&a, &a.clone());
        assert_eq!(d.silhouette, 0.0);
        assert_eq!(d.psnr, PSNR_CAP_DB);
        let image = difference_image(&a, &a);
        assert!(image.rgba.iter().all(|&p| p == [0, 0, 0, 255]));
        // An empty image is no difference either.
        let empty = square(0, 0, 0, 0);
        assert_eq!(difference(&empty, &empty).silhouette, 0.0);
    }

    #[test]
    fn a_shifted_silhouette_differs_by_the_pixels_it_uncovers_and_covers() {
        // Six columns wide, shifted by two: two columns on each side of 16.
        let (a, b) = (square(16, 8, 4, 10), square(16, 8, 6, 12));
        let d = difference(&a, &b);
        assert_eq!(d.silhouette, 4.0 / 16.0);
        assert_eq!(silhouette_difference(&b, &a), d.silhouette, "symmetric");
        // Four of sixteen columns differ by (190, 168, 145) in RGB.
        let mse = (190f64.powi(2) + 168f64.powi(2) + 145f64.powi(2)) / 3.0 * 4.0 / 16.0;
        let want = 10.0 * (255.0f64.powi(2) / mse).log10();
        assert!((d.psnr - want).abs() < 1e-9, "{} vs {want}", d.psnr);
        // A larger shift differs more, in both measures.
        let far = difference(&a, &square(16, 8, 8, 14));
        assert!(far.silhouette > d.silhouette && far.psnr < d.psnr);
        let image = difference_image(&a, &b);
        assert_eq!(image.rgba[4], ONLY_A);
        assert_eq!(image.rgba[11], ONLY_B);
        assert_eq!(image.rgba[7], [0, 0, 0, 255]);
    }

    #[test]
    fn one_unit_off_stays_under_the_cap_and_shading_shows_amplified() {
        let a = square(4, 4, 0, 4);
        let mut b = a.clone();
        b.image.rgba[0][1] += 1;
        let p = psnr(&a.image, &b.image);
        assert!(p < PSNR_CAP_DB && p > 55.0, "{p}");
        assert_eq!(silhouette_difference(&a, &b), 0.0);
        assert_eq!(difference_image(&a, &b).rgba[0], [0, 4, 0, 255]);
    }
}
