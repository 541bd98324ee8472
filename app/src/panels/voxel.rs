//! Controls of voxel-based simplification: filter, grid, iso, layers and
//! the pyramid, explained in the paper's terms.

use lodstudio_core::voxel::{Filter, RADIUS_RANGE, RESOLUTION_RANGE};

use crate::settings::voxel::{ISO_RANGE, LAYERS_RANGE, POSITION_RANGE, VolumeGrid, VoxelSettings};

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

const SIMPLIFY_HINT: &str = "§5: the voxel method is \"the first stage\"; a \
    topology-preserving simplification then reduces the triangles. Each extracted level is \
    collapsed with the certified edge collapse to half a voxel (genus and components kept); \
    the level's bound is measured on the collapsed surface. Off: the raw marching cubes.";

const ISO_HINT: &str = "The iso-density at which marching cubes extracts the surface \
    f = iso, on the normalised density scale 0 (empty) to 1 (solid). The paper uses \
    0.5; lower grows the object, higher shrinks it.";

impl VoxelSettings {
    /// The controls (for `volume`'s grid when the model is a volume); true
    /// when any value changed.
    pub fn ui(&mut self, ui: &mut egui::Ui, volume: Option<&VolumeGrid>) -> bool {
        let before = *self;
        ui.label("Filter").on_hover_text(FILTER_HINT);
        ui.horizontal(|ui| {
            for (kind, hint) in [(Filter::Gaussian, GAUSSIAN_HINT), (Filter::Cone, CONE_HINT)] {
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
        ui.checkbox(&mut self.simplify, "simplify each level (½ voxel)")
            .on_hover_text(SIMPLIFY_HINT);
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
