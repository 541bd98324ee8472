//! The cut section: the error threshold's slider and its units (pixels, %
//! of the diagonal, and for edge collapse its budgets: a ratio, a triangle
//! count), disabled with the reason where nothing is left for it to choose.

use lodstudio_core::lod::{Controls, Knob};

use crate::settings::simplify::{EdgeCollapseSettings, TargetMode};
use crate::settings::threshold::{PERCENT_RANGE, PIXELS_RANGE, Threshold};

/// Why the threshold does not choose the cut now (its slider's tooltip).
pub fn not_applicable(controls: &Controls) -> &'static str {
    match controls.overridden_by {
        _ if !controls.has_levels => {
            "A single level: there is no cut to choose. Build the whole pyramid to browse its levels."
        }
        Some(Knob::AmgLevel) => {
            "The pinned level chooses the cut; tick \"level from the threshold\" to cut by the error threshold."
        }
        Some(Knob::PyramidPosition) => {
            "The pyramid position chooses the level; tick \"level follows the threshold\" to cut by the error threshold."
        }
        Some(Knob::CollapseTarget) => "The budget chooses the cut.",
        Some(Knob::Criteria) | None => "The error threshold chooses the cut.",
    }
}

/// The section's unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Unit {
    Pixels,
    Percent,
    Ratio,
    Triangles,
}

/// The threshold's units, slider and reason, with `collapse` (the edge
/// collapse settings and the open mesh's triangles) where the cut reads a
/// collapse target: its ratio and triangle budgets are the section's other
/// units, not an override of the threshold. True when anything changed.
pub fn cut_ui(
    ui: &mut egui::Ui,
    threshold: &mut Threshold,
    collapse: Option<(&mut EdgeCollapseSettings, Option<usize>)>,
    controls: &Controls,
) -> bool {
    let before = (*threshold, collapse.as_ref().map(|(c, _)| **c));
    let mut collapse = collapse;
    let mut unit = match before.1.map(|c| c.mode) {
        Some(TargetMode::Ratio) => Unit::Ratio,
        Some(TargetMode::Triangles) => Unit::Triangles,
        _ if threshold.in_pixels => Unit::Pixels,
        _ => Unit::Percent,
    };
    ui.horizontal_wrapped(|ui| {
        ui.selectable_value(&mut unit, Unit::Pixels, "pixels")
            .on_hover_text("Screen-space error: each element's bound, projected through the camera (conservatively, by its bounding sphere), stays within this many pixels.");
        ui.selectable_value(&mut unit, Unit::Percent, "% of diagonal")
            .on_hover_text("Object-space error: each element's guaranteed bound stays within this fraction of the bounding-box diagonal.");
        if collapse.is_some() {
            ui.selectable_value(&mut unit, Unit::Ratio, "ratio")
                .on_hover_text(super::simplify::RATIO_HINT);
            ui.selectable_value(&mut unit, Unit::Triangles, "triangles")
                .on_hover_text(super::simplify::TRIANGLES_HINT);
        }
    });
    match unit {
        Unit::Pixels => threshold.in_pixels = true,
        Unit::Percent => threshold.in_pixels = false,
        Unit::Ratio | Unit::Triangles => {}
    }
    let budget = matches!(unit, Unit::Ratio | Unit::Triangles);
    if let Some((settings, input_triangles)) = &mut collapse {
        settings.mode = match unit {
            Unit::Ratio => TargetMode::Ratio,
            Unit::Triangles => TargetMode::Triangles,
            Unit::Pixels | Unit::Percent => TargetMode::Threshold,
        };
        if budget {
            settings.budget_ui(ui, *input_triangles);
        }
    }
    if !budget {
        threshold_ui(ui, threshold, controls);
    }
    (*threshold, collapse.map(|(c, _)| *c)) != before
}

/// The threshold's slider, disabled with the reason where it chooses nothing.
fn threshold_ui(ui: &mut egui::Ui, threshold: &mut Threshold, controls: &Controls) {
    // A collapse target is this section's own unit: the next frame hands it
    // over, so it never blocks the slider.
    let live = controls.follows_tolerance()
        || (controls.has_levels && controls.overridden_by == Some(Knob::CollapseTarget));
    let slider = if threshold.in_pixels {
        egui::Slider::new(&mut threshold.pixels, PIXELS_RANGE)
            .logarithmic(true)
            .suffix(" px")
    } else {
        egui::Slider::new(&mut threshold.percent, PERCENT_RANGE)
            .logarithmic(true)
            .suffix(" %")
    };
    // The name above the slider, so every unit's row is as narrow and the
    // panel keeps its width as units and values change.
    let name = ui.add_enabled(live, egui::Label::new("error threshold"));
    ui.add_enabled(live, slider)
        .labelled_by(name.id)
        .on_hover_text(
            "Drag to change the cut live: coarser elements are drawn wherever their error bound stays within the threshold.",
        )
        .on_disabled_hover_text(not_applicable(controls));
    if !live {
        ui.weak(not_applicable(controls));
    }
}
