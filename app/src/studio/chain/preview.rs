//! The switch preview: the camera's distance (in bounding radii) picks the
//! LOD a loader would draw there, set by hand, by the dolly, or by clicking
//! a row's LOD.

use std::sync::Arc;

use lodstudio_core::lod::DrawSet;

use super::{ChainState, dolly};
use crate::live_cut::CutStyle;
use crate::render::camera::coverage_at_distance;
use crate::render::{Camera, Scene};
use crate::studio::View;

impl ChainState {
    /// The built chain's radius, never zero (distances are in radii).
    pub(super) fn radius(&self) -> Option<f32> {
        self.built
            .as_ref()
            .map(|b| b.chain.radius().max(f32::MIN_POSITIVE))
    }

    /// Turns the switch preview on at `distance` bounding radii from the
    /// target, moving `camera` there (off with `None`).
    pub fn set_switch_distance(
        &mut self,
        distance: Option<f32>,
        camera: &mut Camera,
        view: &mut View,
    ) {
        self.set_preview(distance.is_some(), view);
        self.preview.dolly_from = None;
        if let (Some(d), Some(r)) = (distance, self.radius()) {
            camera.distance = d * r;
        }
    }

    /// Turns the switch preview on or off; on, `view` shows LODs (not the
    /// original).
    pub(super) fn set_preview(&mut self, on: bool, view: &mut View) {
        self.preview.on = on;
        self.selected = None;
        if on {
            show_lods(view);
        }
    }

    /// Shows the LOD of recipe row `row` (ending the switch preview).
    pub(super) fn select_row(&mut self, row: usize, view: &mut View) {
        self.selected = Some(row);
        self.preview.on = false;
        show_lods(view);
    }

    /// The LOD the switch preview draws with the camera at `camera_distance`,
    /// and its name ("LOD1 simplify:2%"); `None` without a preview.
    pub fn switch_lod(&self, camera_distance: f32) -> Option<(usize, String)> {
        let built = self.built.as_ref().filter(|_| self.preview.on)?;
        let r = self.radius()?;
        let c = coverage_at_distance(camera_distance / r);
        let chain = &built.chain;
        let k = chain.lod_at_coverage(c).unwrap_or(chain.lods.len() - 1);
        Some((k, format!("LOD{k} {}", chain.lods[k].labels.join(","))))
    }

    /// What the viewport's overlay says during the switch preview: the LOD
    /// drawn, its triangles and its screen size (the bounding sphere's height
    /// over the viewport's, as engines give it).
    pub fn overlay(&self, camera_distance: f32) -> Option<String> {
        let (k, name) = self.switch_lod(camera_distance)?;
        let r = self.radius()?;
        let built = self.built.as_ref()?;
        let c = coverage_at_distance(camera_distance / r);
        let set = &built.chain.lods[k].set;
        Some(format!(
            "{name} · {} triangles · screen size {:.1} %",
            set.mesh.triangles.len(),
            100.0 * c
        ))
    }

    /// The LOD on screen: the switch preview's, else the clicked row's.
    pub fn shown_lod(&self, camera_distance: f32) -> Option<usize> {
        match (self.switch_lod(camera_distance), self.selected) {
            (Some((k, _)), _) => Some(k),
            (None, Some(row)) => Some(self.built.as_ref()?.figures.get(row)?.lod),
            (None, None) => None,
        }
    }

    /// The scene a chain row or the switch preview shows, if any, drawn in
    /// the view's `style`.
    pub fn scene(&self, camera_distance: f32, style: CutStyle) -> Option<Arc<Scene>> {
        let k = self.shown_lod(camera_distance)?;
        self.built.as_ref()?.scene(k, style)
    }

    /// The primitives of the LOD a chain row or the switch preview shows
    /// (what the view bar colours and a click picks).
    pub fn shown_set(&self, camera_distance: f32) -> Option<&DrawSet> {
        let k = self.shown_lod(camera_distance)?;
        Some(&self.built.as_ref()?.chain.lods.get(k)?.set)
    }

    /// Starts the dolly at egui time `now`: the preview, from near to far.
    pub(super) fn start_dolly(&mut self, now: f64) {
        self.preview.dolly_from = Some(now);
    }

    /// Moves `camera` along a running dolly to where it is at egui time
    /// `now`; true while it still runs (the studio draws another frame).
    pub fn step_dolly(&mut self, now: f64, camera: &mut Camera) -> bool {
        let (Some(from), Some(r), Some(built)) =
            (self.preview.dolly_from, self.radius(), &self.built)
        else {
            return false;
        };
        let (distance, arrived) = dolly::distance(now - from, dolly::range(&built.chain.coverages));
        camera.distance = r * distance;
        if arrived {
            self.preview.dolly_from = None;
        }
        !arrived
    }
}

/// Switches `view` from the original to the LODs.
fn show_lods(view: &mut View) {
    if *view == View::Original {
        *view = View::Simplified;
    }
}
