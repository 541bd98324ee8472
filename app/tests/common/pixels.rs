//! The viewport's pixels read from a rendered studio, for the render tests
//! (included by the test files that look at pixels; the bench does not).

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use lodstudio::studio::StudioApp;

use crate::common::save_ppm;

/// The viewport's pixels (RGBA) inside its rect, every other row and column.
pub fn viewport_image(harness: &mut Harness<'_, StudioApp>, name: &str) -> Vec<[u8; 4]> {
    let rect = harness.get_by_label("3D viewport").rect();
    let image = harness.render().expect("render the studio");
    save_ppm(image.width(), image.height(), image.as_raw(), name);
    let (x0, y0) = (rect.min.x.ceil() as u32 + 2, rect.min.y.ceil() as u32 + 2);
    let (x1, y1) = (rect.max.x.floor() as u32 - 2, rect.max.y.floor() as u32 - 2);
    let mut out = Vec::new();
    for y in (y0..y1).step_by(2) {
        for x in (x0..x1).step_by(2) {
            out.push(image.get_pixel(x, y).0);
        }
    }
    out
}

/// How colourful a render is: the share of its non-background pixels whose
/// channels spread by more than 60 of 255 (the truck's white body and dark
/// glass are grey; its logo and wheels' texture are not).
pub fn colourful(pixels: &[[u8; 4]]) -> f32 {
    let background = pixels[0];
    let model: Vec<&[u8; 4]> = pixels.iter().filter(|p| **p != background).collect();
    let spread = |p: &[u8; 4]| p[..3].iter().max().unwrap() - p[..3].iter().min().unwrap();
    model.iter().filter(|p| spread(p) > 60).count() as f32 / model.len().max(1) as f32
}
