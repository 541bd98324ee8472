//! Parameters of voxel-based simplification (voxel paper §2) and their
//! controls: sample the solid (or threshold a volume model) into a volume buffer
//! S, low-pass filter it into a density f = h ∗ S, and extract the iso-density
//! surface by marching cubes.

use std::ops::RangeInclusive;

use lodstudio_core::geom::Volume;
use lodstudio_core::voxel::{DENSITY_ISO, Filter};
use serde::{Deserialize, Serialize};

use lodstudio_core::voxel::{RADIUS_RANGE, RESOLUTION_RANGE};
const ISO_RANGE: RangeInclusive<f32> = 0.05..=0.95;
/// Pyramid positions the slider offers (levels beyond the pyramid clamp).
const POSITION_RANGE: RangeInclusive<f32> = 0.0..=6.0;
/// Layers error δ (§3, eq. 6): 0.5 and above is one surface.
const LAYERS_RANGE: RangeInclusive<f32> = 0.01..=0.5;

const FILTER_HINT: &str = "The low-pass filter h of the filtered density f = h * S \
    (voxel paper §2, eq. 1): it removes the high frequencies (small features, holes, \
    tunnels) of the sampled solid S.";
const GAUSSIAN_HINT: &str = "The paper's higher-order filter: a Gaussian with sigma = R/3, \
    truncated at the support radius R. Separable, so wide radii stay fast.";
const CONE_HINT: &str = "The hyper-cone of eq. 3: h(r) = (R - r)·w for r < R and 0 beyond, \
    largest at the centre and falling linearly to zero at the support radius R (w \
    normalises the total weight to one). Not separable: slow for wide radii.";
const RESOLUTION_HINT: &str = "Voxels of the grid overlaid on the object, along the \
    longest side of its bounds. The volume buffer S samples the solid on this grid \
    (3x3x3 sub-samples per voxel near the surface); a finer grid keeps finer detail \
    and gives more triangles.";
const RADIUS_HINT: &str = "The filter's support radius R (in voxels of the grid; for a \
    volume, of its smallest spacing): how far \
    each grid point's filtered density f(i, j, k) gathers the samples of S. A wider \
    filter removes lower frequencies: small holes close and the genus falls. 0 means \
    no filtering.";
const THRESHOLD_HINT: &str = "Samples of the volume at or above this value (in the \
    volume's own units) form the solid S of §2 eq. 2, which is then low-pass filtered. \
    Lower takes in fainter tissue, higher keeps only the densest.";
const GRID_HINT: &str = "A volume keeps its own grid: S is its samples, and the filter \
    radius counts voxels of its smallest spacing. The extracted surface is the density \
    0.5 of the filtered S.";
const LAYERS_HINT: &str = "Multi-layered marching cubes (§3): instead of one surface, \
    several iso-surfaces of the filtered density, increasingly translucent outwards \
    (eq. 4), drawn back to front. The layers error δ bounds the mean density error of \
    their piecewise-constant fit of the density fall-off (eq. 6): smaller gives more \
    layers and smoother edges. 0.5 is a single opaque surface.";
const PYRAMID_HINT: &str = "Build the whole multi-resolution pyramid of §2 (Tables 1-3): \
    each level halves the resolution and doubles the filter radius, and the genus falls \
    level by level. Then browse it with the pyramid position.";
const POSITION_HINT: &str = "Continuous position in the pyramid (0 = finest level, 1 = \
    the next, ...): between two levels the two filtered buffers are interpolated into an \
    in-between resolution and extracted on the fly (§5). No rebuild.";
const FOLLOW_HINT: &str = "Show the coarsest pyramid level whose certified two-sided \
    Hausdorff bound (against the input surface) is within the error threshold, as every \
    other method does. Off: the pyramid position below chooses.";
const ISO_HINT: &str = "The iso-density at which marching cubes extracts the surface \
    f = iso, on the normalised density scale 0 (empty) to 1 (solid). The paper uses \
    0.5; lower grows the object, higher shrinks it.";

/// Which low-pass filter of §2 to apply (as stored in the settings).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum FilterKind {
    #[default]
    Gaussian,
    Cone,
}

impl FilterKind {
    pub fn filter(self) -> Filter {
        match self {
            FilterKind::Gaussian => Filter::Gaussian,
            FilterKind::Cone => Filter::Cone,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            FilterKind::Gaussian => "Gaussian",
            FilterKind::Cone => "Cone",
        }
    }
}

/// Everything voxel simplification needs besides the solid.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct VoxelSettings {
    pub filter: FilterKind,
    /// Voxels along the longest side of the object's bounds.
    pub resolution: usize,
    /// Filter support radius, in voxels of that grid.
    pub radius: f32,
    /// Density of the extracted surface (0..1); implicit solids only (a volume's
    /// surface is always the density 0.5 of its filtered S).
    pub iso: f32,
    /// Volumes only: samples at or above this value, in the volume's own units,
    /// form the solid S. It is model-specific, so it is not persisted: `None`
    /// stands for the middle of the open volume's value range, and the studio
    /// resets it to `None` whenever a different volume opens.
    #[serde(skip)]
    pub threshold: Option<f32>,
    /// Multi-layered surfaces (§3): the mean density error δ of eq. 6 the
    /// layers may leave; 0.5 or more gives the single surface.
    pub layers_error: f32,
    /// Build the whole pyramid (Tables 1–3) and browse it continuously.
    pub pyramid: bool,
    /// Run time: the continuous pyramid position shown (0 = finest, §5) ...
    pub position: f32,
    /// ... unless the pyramid follows the error threshold: the coarsest
    /// level whose certified bound is within it.
    pub follow_threshold: bool,
}

/// What the voxel controls and a volume build need to know of a volume,
/// computed once when it opens (its value range takes a pass over the data).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VolumeGrid {
    pub dims: [usize; 3],
    /// (min, max) of the finite samples; (0, 0) when there are none.
    pub range: (f32, f32),
}

impl VolumeGrid {
    pub fn of(volume: &Volume) -> Self {
        let (lo, hi) = volume.value_range();
        VolumeGrid {
            dims: volume.dims,
            range: if lo <= hi { (lo, hi) } else { (0.0, 0.0) },
        }
    }

    /// The default threshold: the middle of the value range.
    pub fn middle(&self) -> f32 {
        0.5 * (self.range.0 + self.range.1)
    }

    /// `threshold` inside the value range (the middle for `None` or NaN).
    pub fn threshold(&self, threshold: Option<f32>) -> f32 {
        match threshold {
            Some(t) if !t.is_nan() => t.clamp(self.range.0, self.range.1),
            _ => self.middle(),
        }
    }
}

impl Default for VoxelSettings {
    fn default() -> Self {
        VoxelSettings {
            filter: FilterKind::Gaussian,
            resolution: 64,
            radius: 2.0,
            iso: DENSITY_ISO,
            threshold: None,
            layers_error: 0.5,
            pyramid: false,
            position: 0.0,
            follow_threshold: true,
        }
    }
}

/// `value` clamped to `range`, or `fallback` when it is not a number.
fn clamp_or(value: f32, range: RangeInclusive<f32>, fallback: f32) -> f32 {
    if value.is_nan() {
        fallback
    } else {
        value.clamp(*range.start(), *range.end())
    }
}

impl VoxelSettings {
    /// The same settings with every value inside the range its control offers.
    pub fn sanitized(self) -> Self {
        let d = Self::default();
        VoxelSettings {
            filter: self.filter,
            resolution: self
                .resolution
                .clamp(*RESOLUTION_RANGE.start(), *RESOLUTION_RANGE.end()),
            radius: clamp_or(self.radius, RADIUS_RANGE, d.radius),
            iso: clamp_or(self.iso, ISO_RANGE, d.iso),
            threshold: self.threshold.filter(|t| !t.is_nan()),
            layers_error: clamp_or(self.layers_error, LAYERS_RANGE, d.layers_error),
            pyramid: self.pyramid,
            position: clamp_or(self.position, POSITION_RANGE, d.position),
            follow_threshold: self.follow_threshold,
        }
    }

    /// The pyramid position a cut shows: `None` follows the threshold.
    pub fn runtime_position(&self) -> Option<f32> {
        (!self.follow_threshold).then_some(self.sanitized().position)
    }

    /// What a build of an implicit solid depends on: the threshold has no effect.
    pub fn for_implicit(self) -> Self {
        VoxelSettings {
            threshold: None,
            position: 0.0,
            follow_threshold: true,
            ..self.sanitized()
        }
    }

    /// What a build of `grid`'s volume depends on: its threshold (resolved),
    /// filter and radius; resolution and iso have no effect and keep their
    /// defaults, so changing them does not make a volume's result stale.
    pub fn for_volume(self, grid: &VolumeGrid) -> Self {
        let d = Self::default();
        VoxelSettings {
            resolution: d.resolution,
            iso: d.iso,
            threshold: Some(grid.threshold(self.threshold)),
            position: 0.0,
            follow_threshold: true,
            ..self.sanitized()
        }
    }

    /// The controls (for `volume`'s grid when the model is a volume); true
    /// when any value changed.
    pub fn ui(&mut self, ui: &mut egui::Ui, volume: Option<&VolumeGrid>) -> bool {
        let before = *self;
        ui.label("Filter").on_hover_text(FILTER_HINT);
        ui.horizontal(|ui| {
            for (kind, hint) in [
                (FilterKind::Gaussian, GAUSSIAN_HINT),
                (FilterKind::Cone, CONE_HINT),
            ] {
                ui.selectable_value(&mut self.filter, kind, kind.name())
                    .on_hover_text(hint);
            }
        });
        if let Some(grid) = volume {
            let [x, y, z] = grid.dims;
            ui.label(format!("grid {x} x {y} x {z} (the volume's own)"))
                .on_hover_text(GRID_HINT);
            let mut threshold = grid.threshold(self.threshold);
            let (lo, hi) = grid.range;
            let slider = ui
                .add(egui::Slider::new(&mut threshold, lo..=hi).text("threshold"))
                .on_hover_text(THRESHOLD_HINT);
            if slider.changed() {
                self.threshold = Some(threshold);
            }
        } else {
            ui.add(
                egui::Slider::new(&mut self.resolution, RESOLUTION_RANGE)
                    .logarithmic(true)
                    .text("resolution"),
            )
            .on_hover_text(RESOLUTION_HINT);
        }
        ui.add(
            egui::Slider::new(&mut self.radius, RADIUS_RANGE)
                .logarithmic(true)
                .suffix(" vx")
                .text("filter radius"),
        )
        .on_hover_text(RADIUS_HINT);
        if volume.is_none() {
            ui.add(egui::Slider::new(&mut self.iso, ISO_RANGE).text("iso"))
                .on_hover_text(ISO_HINT);
        }
        ui.add(
            egui::Slider::new(&mut self.layers_error, LAYERS_RANGE)
                .logarithmic(true)
                .text("layers error δ"),
        )
        .on_hover_text(LAYERS_HINT);
        ui.checkbox(&mut self.pyramid, "whole pyramid")
            .on_hover_text(PYRAMID_HINT);
        if self.pyramid {
            ui.checkbox(&mut self.follow_threshold, "level follows the threshold")
                .on_hover_text(FOLLOW_HINT);
            ui.add_enabled(
                !self.follow_threshold,
                egui::Slider::new(&mut self.position, POSITION_RANGE).text("pyramid position"),
            )
            .on_hover_text(POSITION_HINT);
        }
        // The position is cut live: it never makes a build stale.
        let build = |s: &VoxelSettings| VoxelSettings {
            position: 0.0,
            follow_threshold: true,
            ..*s
        };
        build(self) != build(&before)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn out_of_range_values_are_replaced() {
        let odd = VoxelSettings {
            filter: FilterKind::Cone,
            resolution: 4,
            radius: f32::NAN,
            iso: 3.0,
            threshold: Some(f32::NAN),
            layers_error: 7.0,
            pyramid: true,
            position: f32::INFINITY,
            follow_threshold: false,
        }
        .sanitized();
        assert_eq!((odd.pyramid, odd.position), (true, 6.0));
        assert_eq!(odd.runtime_position(), Some(6.0));
        assert_eq!(VoxelSettings::default().runtime_position(), None);
        assert_eq!(odd.layers_error, 0.5);
        assert_eq!(odd.threshold, None);
        assert_eq!(odd.filter.filter(), Filter::Cone);
        assert_eq!(odd.resolution, *RESOLUTION_RANGE.start());
        assert_eq!(odd.radius, VoxelSettings::default().radius);
        assert_eq!(odd.iso, 0.95);
        assert_eq!(
            VoxelSettings::default().sanitized(),
            VoxelSettings::default()
        );
    }

    #[test]
    fn volume_builds_depend_only_on_what_has_an_effect() {
        let volume = Volume {
            dims: [2, 1, 1],
            spacing: glam::Vec3::ONE,
            origin: glam::Vec3::ZERO,
            data: vec![-4.0, 10.0],
        };
        let grid = VolumeGrid::of(&volume);
        assert_eq!(
            (grid.dims, grid.range, grid.middle()),
            ([2, 1, 1], (-4.0, 10.0), 3.0)
        );
        let settings = VoxelSettings::default();
        assert_eq!(settings.for_volume(&grid).threshold, Some(3.0));
        let moved = VoxelSettings {
            resolution: 200,
            iso: 0.3,
            threshold: Some(3.0),
            ..settings
        };
        assert_eq!(moved.for_volume(&grid), settings.for_volume(&grid));
        let clamped = VoxelSettings {
            threshold: Some(99.0),
            ..settings
        };
        assert_eq!(clamped.for_volume(&grid).threshold, Some(10.0));
        assert_eq!(clamped.for_implicit(), settings);
    }
}
