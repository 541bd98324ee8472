//! Parameters of voxel-based simplification (voxel paper §2) and their
//! controls: sample the solid into a volume buffer S, low-pass filter it into a
//! density f = h ∗ S, and extract the iso-density surface by marching cubes.

use std::ops::RangeInclusive;

use lodstudio_core::voxel::{DENSITY_ISO, Filter};
use serde::{Deserialize, Serialize};

const RESOLUTION_RANGE: RangeInclusive<usize> = 16..=256;
/// Filter support radius R, in voxels of the sampling grid.
const RADIUS_RANGE: RangeInclusive<f32> = 0.0..=16.0;
const ISO_RANGE: RangeInclusive<f32> = 0.05..=0.95;

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
const RADIUS_HINT: &str = "The filter's support radius R (in voxels of the grid): how far \
    each grid point's filtered density f(i, j, k) gathers the samples of S. A wider \
    filter removes lower frequencies: small holes close and the genus falls. 0 means \
    no filtering.";
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
    /// Density of the extracted surface (0..1).
    pub iso: f32,
}

impl Default for VoxelSettings {
    fn default() -> Self {
        VoxelSettings {
            filter: FilterKind::Gaussian,
            resolution: 64,
            radius: 2.0,
            iso: DENSITY_ISO,
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
        }
    }

    /// The controls; true when any value changed.
    pub fn ui(&mut self, ui: &mut egui::Ui) -> bool {
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
        ui.add(egui::Slider::new(&mut self.resolution, RESOLUTION_RANGE).text("resolution"))
            .on_hover_text(RESOLUTION_HINT);
        ui.add(
            egui::Slider::new(&mut self.radius, RADIUS_RANGE)
                .suffix(" vx")
                .text("filter radius"),
        )
        .on_hover_text(RADIUS_HINT);
        ui.add(egui::Slider::new(&mut self.iso, ISO_RANGE).text("iso"))
            .on_hover_text(ISO_HINT);
        *self != before
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
        }
        .sanitized();
        assert_eq!(odd.filter.filter(), Filter::Cone);
        assert_eq!(odd.resolution, 16);
        assert_eq!(odd.radius, VoxelSettings::default().radius);
        assert_eq!(odd.iso, 0.95);
        assert_eq!(
            VoxelSettings::default().sanitized(),
            VoxelSettings::default()
        );
    }
}
