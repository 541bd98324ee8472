//! The colour scales of the inspector: for per-triangle values (certified
//! error bounds, hierarchy levels) a perceptually ordered dark-blue → teal →
//! yellow ramp, so "hotter" always reads as "larger", with a legend bar that
//! explains it; for regions without an order (AMG domains, voxel layers)
//! well-separated hues.

use glam::Vec3;

/// Ramp stops in sRGB (viridis-like), evenly spaced over 0..=1.
const STOPS: [[u8; 3]; 5] = [
    [68, 1, 84],
    [59, 82, 139],
    [33, 145, 140],
    [94, 201, 98],
    [253, 231, 37],
];

/// The ramp's sRGB colour at `t` (clamped to 0..=1; NaN reads as 0).
pub fn color32(t: f32) -> egui::Color32 {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let x = t * (STOPS.len() - 1) as f32;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f32;
    let [a, b] = [STOPS[i], STOPS[i + 1]];
    let mix = |k: usize| (a[k] as f32 + (b[k] as f32 - a[k] as f32) * f).round() as u8;
    egui::Color32::from_rgb(mix(0), mix(1), mix(2))
}

/// The ramp's colour at `t` in linear RGB, as the viewport's shader expects.
pub fn linear(t: f32) -> Vec3 {
    let [r, g, b, _] = egui::Rgba::from(color32(t)).to_array();
    Vec3::new(r, g, b)
}

/// A distinct colour for region `id` (linear RGB): hues a golden angle apart,
/// so neighbouring ids never look alike.
pub fn categorical(id: usize) -> Vec3 {
    let hue = (id as f32 * 0.618_034).fract() * 6.0;
    let x = 1.0 - (hue % 2.0 - 1.0).abs();
    let [r, g, b] = match hue as u32 {
        0 => [1.0, x, 0.0],
        1 => [x, 1.0, 0.0],
        2 => [0.0, 1.0, x],
        3 => [0.0, x, 1.0],
        4 => [x, 0.0, 1.0],
        _ => [1.0, 0.0, x],
    };
    // Saturation 0.65, value 0.9: bright enough to shade, never white.
    Vec3::new(r, g, b)
        .map(|c| 0.9 * (0.35 + 0.65 * c))
        .powf(2.2)
}

/// A horizontal bar of the ramp labelled with the value range `0 ..= max`.
pub fn legend(ui: &mut egui::Ui, max_label: &str) {
    let width = ui.available_width().clamp(60.0, 220.0);
    let (rect, _) = ui.allocate_exact_size(egui::vec2(width, 12.0), egui::Sense::hover());
    let steps = 32;
    let mut mesh = egui::Mesh::default();
    for k in 0..=steps {
        let t = k as f32 / steps as f32;
        let x = rect.left() + rect.width() * t;
        let color = color32(t);
        mesh.colored_vertex(egui::pos2(x, rect.top()), color);
        mesh.colored_vertex(egui::pos2(x, rect.bottom()), color);
        if k > 0 {
            let i = 2 * k as u32;
            mesh.add_triangle(i - 2, i - 1, i);
            mesh.add_triangle(i - 1, i + 1, i);
        }
    }
    ui.painter().add(mesh);
    ui.horizontal(|ui| {
        ui.set_width(width);
        ui.weak("0");
        ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
            ui.weak(max_label);
        });
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn categorical_colours_of_neighbouring_ids_differ() {
        for id in 0..64 {
            let (a, b) = (categorical(id), categorical(id + 1));
            assert!(a.distance(b) > 0.2, "{id}: {a} vs {b}");
            assert!(a.max_element() <= 1.0 && a.min_element() >= 0.0);
        }
    }

    #[test]
    fn ramp_is_ordered_and_clamped() {
        assert_eq!(color32(-1.0), color32(0.0));
        assert_eq!(color32(2.0), color32(1.0));
        assert_eq!(color32(f32::NAN), color32(0.0));
        // Luminance grows along the ramp.
        let luma = |t: f32| {
            let c = linear(t);
            0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
        };
        for k in 0..10 {
            let t = k as f32 / 10.0;
            assert!(luma(t) < luma(t + 0.1), "at {t}");
        }
    }
}
