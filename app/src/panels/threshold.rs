//! The cut threshold's slider and its unit switch.

use lodstudio_core::lod::Knob;

use crate::settings::threshold::{PERCENT_RANGE, PIXELS_RANGE, Threshold};

/// What the panel says instead of the threshold while `knob` chooses the cut.
pub fn overridden(knob: Knob) -> &'static str {
    match knob {
        Knob::CollapseTarget => {
            "The target above chooses the cut; choose \"Threshold\" as the target to cut by the error threshold."
        }
        Knob::AmgLevel => {
            "The level above chooses the cut; tick \"level from the threshold\" to cut by the error threshold."
        }
        Knob::PyramidPosition => {
            "The pyramid position above chooses the level; tick \"level follows the threshold\" to cut by the error threshold."
        }
        Knob::Criteria => "The criteria scale the error threshold.",
    }
}

impl Threshold {
    /// The slider and its unit switch; true when the threshold changed.
    pub fn ui(&mut self, ui: &mut egui::Ui) -> bool {
        let before = *self;
        ui.horizontal(|ui| {
            ui.selectable_value(&mut self.in_pixels, true, "pixels")
                .on_hover_text("Screen-space error: each element's bound, projected through the camera (conservatively, by its bounding sphere), stays within this many pixels.");
            ui.selectable_value(&mut self.in_pixels, false, "% of diagonal")
                .on_hover_text("Object-space error: each element's guaranteed bound stays within this fraction of the bounding-box diagonal.");
        });
        let slider = if self.in_pixels {
            egui::Slider::new(&mut self.pixels, PIXELS_RANGE)
                .logarithmic(true)
                .suffix(" px")
                .text("error threshold")
        } else {
            egui::Slider::new(&mut self.percent, PERCENT_RANGE)
                .logarithmic(true)
                .suffix(" %")
                .text("error threshold")
        };
        ui.add(slider).on_hover_text(
            "Drag to change the cut live: coarser elements are drawn wherever their error bound stays within the threshold.",
        );
        *self != before
    }
}
