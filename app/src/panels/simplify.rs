//! Parameters of edge-collapse simplification (hybrid paper §5.2) and their
//! controls, explained in the papers' terms. The build records the collapses
//! once, down to a floor (`simplify::progressive`); the target only chooses
//! a prefix, live.

use lodstudio_core::lod::PrefixTarget;
use lodstudio_core::simplify::CollapseOptions;
use serde::{Deserialize, Serialize};

/// Which prefix of the recorded collapses is shown; each mode keeps its own
/// value so switching back restores it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum TargetMode {
    #[default]
    Ratio,
    Triangles,
    Error,
    /// The view's error threshold, as for every other hierarchy.
    Threshold,
}

const RATIO_RANGE: std::ops::RangeInclusive<f32> = 0.001..=1.0;
/// Error targets as a percentage of the bounding-box diagonal.
const ERROR_PERCENT_RANGE: std::ops::RangeInclusive<f32> = 0.001..=10.0;
/// DragValue needs a finite upper end; no model comes close.
const MAX_TRIANGLES: usize = 1_000_000_000;

const TARGET_HINT: &str = "Where to stop collapsing edges. Edges collapse in order of \
    quadric error; each collapse merges an edge's two vertices into one and removes the \
    triangles on that edge. The build records every collapse down to 0.1 % of the \
    triangles, each step with its certified bound, so moving the target needs no rebuild.";
const RATIO_HINT: &str = "Keep this fraction of the input's triangles.";
const TRIANGLES_HINT: &str = "Collapse until at most this many triangles remain (fewer \
    are possible only if no legal collapse is left).";
const ERROR_HINT: &str = "As few triangles as possible while the certified two-sided \
    Hausdorff bound stays within this percentage of the bounding-box diagonal.";
const THRESHOLD_HINT: &str = "Follow the view's error threshold (object space, or pixels \
    at the camera) like every other hierarchy: the coarsest step within it.";
const LOCK_HINT: &str = "Border vertices never move, so open boundaries, seams between \
    parts and non-manifold edges keep their exact shape. Off: they may still only slide \
    along the border, never off it.";
const QUALITY_HINT: &str = "Sliver guard: reject a collapse that creates a triangle of \
    quality q = 4√3·area / (l0² + l1² + l2²) below this (merge-tree paper, eq. 3; q = 1 \
    for an equilateral triangle, 0 for a degenerate one), unless the triangle was already \
    worse. 0 turns the guard off.";
const FOLD_HINT: &str = "Fold guard: reject a collapse that turns any triangle's normal \
    by more than the angle whose cosine this is, so the surface does not fold over \
    itself. 0 rejects only turns beyond 90°; higher is stricter.";

/// Everything edge collapse needs besides the mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct EdgeCollapseSettings {
    pub mode: TargetMode,
    /// Fraction of the input's triangles to keep.
    pub ratio: f32,
    pub triangles: usize,
    /// Largest certified error, in percent of the bounding-box diagonal.
    pub error_percent: f32,
    pub lock_borders: bool,
    /// Smallest triangle quality a collapse may create (0 disables the guard).
    pub min_quality: f32,
    /// Smallest cosine between a triangle's normals before and after a collapse.
    pub min_normal_cos: f32,
}

impl Default for EdgeCollapseSettings {
    fn default() -> Self {
        let collapse = CollapseOptions::default();
        EdgeCollapseSettings {
            mode: TargetMode::Ratio,
            ratio: 0.1,
            triangles: 1000,
            error_percent: 0.5,
            lock_borders: collapse.lock_borders,
            min_quality: collapse.min_quality,
            min_normal_cos: collapse.min_normal_cos,
        }
    }
}

/// `value` clamped to `range`, or `fallback` when it is not a number.
fn clamp_or(value: f32, range: std::ops::RangeInclusive<f32>, fallback: f32) -> f32 {
    if value.is_nan() {
        fallback
    } else {
        value.clamp(*range.start(), *range.end())
    }
}

impl EdgeCollapseSettings {
    /// The same settings with every value inside the range its control offers.
    pub fn sanitized(self) -> Self {
        let d = Self::default();
        EdgeCollapseSettings {
            mode: self.mode,
            ratio: clamp_or(self.ratio, RATIO_RANGE, d.ratio),
            triangles: self.triangles.clamp(1, MAX_TRIANGLES),
            error_percent: clamp_or(self.error_percent, ERROR_PERCENT_RANGE, d.error_percent),
            lock_borders: self.lock_borders,
            min_quality: clamp_or(self.min_quality, 0.0..=1.0, d.min_quality),
            min_normal_cos: clamp_or(self.min_normal_cos, 0.0..=1.0, d.min_normal_cos),
        }
    }

    /// What the build depends on: the collapses' legality rules.
    pub fn collapse(&self) -> CollapseOptions {
        let s = self.sanitized();
        CollapseOptions {
            lock_borders: s.lock_borders,
            min_quality: s.min_quality,
            min_normal_cos: s.min_normal_cos,
        }
    }

    /// The triangles a build records collapses down to, for `input` triangles:
    /// the ratio slider's low end.
    pub fn floor(input: usize) -> usize {
        (f64::from(*RATIO_RANGE.start()) * input as f64) as usize
    }

    /// The run-time choice of a recorded collapse's prefix (the live cut's
    /// knob): `None` follows the view's threshold.
    pub fn runtime(&self, input_triangles: usize) -> Option<PrefixTarget> {
        let s = self.sanitized();
        match s.mode {
            TargetMode::Ratio => {
                let n = (f64::from(s.ratio) * input_triangles as f64).round();
                Some(PrefixTarget::Triangles(n as usize))
            }
            TargetMode::Triangles => Some(PrefixTarget::Triangles(s.triangles)),
            TargetMode::Error => Some(PrefixTarget::RelativeError(s.error_percent / 100.0)),
            TargetMode::Threshold => None,
        }
    }

    /// The controls; `input_triangles` (the open mesh's count) turns a ratio
    /// into the count it means. True when any value changed.
    pub fn ui(&mut self, ui: &mut egui::Ui, input_triangles: Option<usize>) -> bool {
        let before = *self;
        ui.label("Target").on_hover_text(TARGET_HINT);
        ui.horizontal(|ui| {
            for (mode, name, hint) in [
                (TargetMode::Ratio, "Ratio", RATIO_HINT),
                (TargetMode::Triangles, "Triangles", TRIANGLES_HINT),
                (TargetMode::Error, "Error", ERROR_HINT),
                (TargetMode::Threshold, "Threshold", THRESHOLD_HINT),
            ] {
                ui.selectable_value(&mut self.mode, mode, name)
                    .on_hover_text(hint);
            }
        });
        match self.mode {
            TargetMode::Ratio => {
                ui.add(
                    egui::Slider::new(&mut self.ratio, RATIO_RANGE)
                        .logarithmic(true)
                        .text("ratio"),
                )
                .on_hover_text(RATIO_HINT);
                if let Some(n) = input_triangles {
                    let kept = (f64::from(self.ratio) * n as f64).round() as usize;
                    ui.weak(format!("≈ {kept} of {n} triangles"));
                }
            }
            TargetMode::Triangles => {
                ui.horizontal(|ui| {
                    ui.add(
                        egui::DragValue::new(&mut self.triangles)
                            .range(1..=MAX_TRIANGLES)
                            .speed(10.0),
                    )
                    .on_hover_text(TRIANGLES_HINT);
                    match input_triangles {
                        Some(n) => ui.weak(format!("of {n} triangles")),
                        None => ui.weak("triangles"),
                    };
                });
            }
            TargetMode::Error => {
                ui.add(
                    egui::Slider::new(&mut self.error_percent, ERROR_PERCENT_RANGE)
                        .logarithmic(true)
                        .suffix(" %")
                        .text("error"),
                )
                .on_hover_text(ERROR_HINT);
                ui.weak("of the bounding-box diagonal");
            }
            TargetMode::Threshold => {
                ui.weak("the error threshold below chooses");
            }
        }
        ui.checkbox(&mut self.lock_borders, "Lock borders")
            .on_hover_text(LOCK_HINT);
        ui.add(egui::Slider::new(&mut self.min_quality, 0.0..=1.0).text("sliver guard"))
            .on_hover_text(QUALITY_HINT);
        ui.add(egui::Slider::new(&mut self.min_normal_cos, 0.0..=1.0).text("fold guard"))
            .on_hover_text(FOLD_HINT);
        let degrees = self.min_normal_cos.clamp(-1.0, 1.0).acos().to_degrees();
        ui.weak(format!("normals may turn up to {degrees:.0}°"));
        *self != before
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mode_chooses_the_prefix_and_only_legality_rebuilds() {
        let mut s = EdgeCollapseSettings {
            ratio: 0.25,
            triangles: 500,
            error_percent: 1.0,
            ..Default::default()
        };
        assert_eq!(s.runtime(1000), Some(PrefixTarget::Triangles(250)));
        s.mode = TargetMode::Triangles;
        assert_eq!(s.runtime(1000), Some(PrefixTarget::Triangles(500)));
        s.mode = TargetMode::Error;
        assert_eq!(s.runtime(1000), Some(PrefixTarget::RelativeError(0.01)));
        s.mode = TargetMode::Threshold;
        assert_eq!(s.runtime(1000), None);
        let moved = EdgeCollapseSettings { ratio: 0.5, ..s };
        assert_eq!(moved.collapse(), s.collapse(), "a target is no rebuild");
        s.min_normal_cos = f32::NAN;
        assert_eq!(
            s.collapse().min_normal_cos,
            CollapseOptions::default().min_normal_cos
        );
        assert_eq!(EdgeCollapseSettings::floor(100_000), 100);
    }
}
