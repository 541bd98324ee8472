//! A built hierarchy shown live: the studio asks for its cut every frame with
//! the viewport's camera and the error threshold, and the cut is re-selected
//! only when the hierarchy says the view or the threshold changes it.

use std::sync::Arc;
use std::time::Instant;

use lodstudio_core::lod::{DrawSet, Hierarchy, Method};
use lodstudio_core::view::{Tolerance, View};

use crate::render::{Scene, SceneStyle};

/// How a cut is drawn: coloured by its error bounds (a heat map, first), by
/// primitive type, or by the hierarchy's regions (merge-tree levels, AMG
/// domains, voxel layers), and with splat outlines (AMG paper Fig. 12).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CutStyle {
    pub heat: bool,
    pub by_type: bool,
    pub regions: bool,
    pub outlines: bool,
    /// Triangle edges drawn over the cut.
    pub wireframe: bool,
}

/// Colours of the primitive types (linear RGB); splats keep their textures.
const TRIANGLE_COLOR: glam::Vec3 = glam::Vec3::new(0.85, 0.55, 0.25);
const POINT_COLOR: glam::Vec3 = glam::Vec3::new(0.25, 0.55, 0.95);

/// What the last cut drew and what it cost.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CutStats {
    pub triangles: usize,
    pub points: usize,
    pub splats: usize,
    pub layer_triangles: usize,
    /// Object-space bound of the cut.
    pub error_bound: f32,
    /// The largest error of a seen, front-facing primitive projected at its
    /// own depth, where the cut has errors per primitive: what a pixel
    /// threshold limits in a view-dependent cut (merge tree §5, hybrid §6),
    /// which coarsens far and hidden parts further.
    pub screen_pixels: Option<f32>,
    pub error_bound_kind: lodstudio_core::lod::BoundKind,
    /// Time of the last `select` and scene preparation.
    pub cut_ms: f32,
    /// Cuts taken since the build.
    pub cuts: u64,
}

/// A hierarchy and its current cut.
pub struct LiveCut {
    hierarchy: Box<dyn Hierarchy>,
    last: Option<(Option<u64>, View, Tolerance)>,
    /// Whether knobs were handed over yet (the first ones always re-select).
    knobs_given: bool,
    /// How the cut is coloured and outlined.
    style: CutStyle,
    scene: Arc<Scene>,
    draw: DrawSet,
    pub stats: CutStats,
}

impl LiveCut {
    pub fn new(hierarchy: Box<dyn Hierarchy>, view: &View, tolerance: Tolerance) -> LiveCut {
        let mut live = LiveCut {
            hierarchy,
            last: None,
            knobs_given: false,
            style: CutStyle::default(),
            scene: Arc::new(Scene::from_draw_set(
                &DrawSet::default(),
                &SceneStyle::default(),
            )),
            draw: DrawSet::default(),
            stats: CutStats::default(),
        };
        live.update(view, tolerance);
        live
    }

    pub fn method(&self) -> Method {
        self.hierarchy.method()
    }

    /// The scene of the current cut in the current style.
    fn make_scene(&self) -> Scene {
        styled_scene(&self.draw, self.style)
    }

    /// Whether the cut carries error bounds per triangle or point to colour by.
    pub fn has_errors(&self) -> bool {
        set_has_errors(&self.draw)
    }

    /// Changes how the cut is drawn (rebuilds the scene only, not the cut).
    pub fn set_style(&mut self, style: CutStyle) {
        if style != self.style {
            self.style = style;
            self.scene = Arc::new(self.make_scene());
        }
    }

    /// Hands the hierarchy the run-time knobs; when its cut may change with
    /// them, the next [`LiveCut::update`] re-selects.
    pub fn set_knobs(&mut self, knobs: &lodstudio_core::lod::Knobs) {
        let changed = self.hierarchy.set_knobs(knobs);
        if changed || !self.knobs_given {
            self.knobs_given = true;
            self.last = None;
        }
    }

    /// Re-selects the cut when the view or the tolerance may change it; true
    /// when the scene changed.
    pub fn update(&mut self, view: &View, tolerance: Tolerance) -> bool {
        let key = self.hierarchy.view_key(view, tolerance);
        if let Some((last_key, last_view, last_tolerance)) = &self.last
            && *last_tolerance == tolerance
            && (key.is_some() && key == *last_key || *last_view == *view)
        {
            return false;
        }
        let start = Instant::now();
        self.draw = self.hierarchy.select(view, tolerance);
        self.scene = Arc::new(self.make_scene());
        let d = &self.draw;
        self.stats = CutStats {
            triangles: d.mesh.triangles.len(),
            points: d.points.len(),
            splats: d.splats.len(),
            layer_triangles: d.layers.iter().map(|l| l.mesh.triangles.len()).sum(),
            error_bound: d.error_bound,
            error_bound_kind: d.error_bound_kind,
            screen_pixels: screen_pixels(d, view),
            cut_ms: start.elapsed().as_secs_f32() * 1000.0,
            cuts: self.stats.cuts + 1,
        };
        self.last = Some((key, *view, tolerance));
        true
    }

    /// Whether the hierarchy has levels for the threshold to choose between
    /// (and so something to save).
    pub fn has_levels(&self) -> bool {
        self.hierarchy.has_levels()
    }

    /// Which knobs the cut reads and whether the threshold chooses it now.
    pub fn controls(&self) -> lodstudio_core::lod::Controls {
        self.hierarchy.controls()
    }

    /// The hierarchy as a saved-hierarchy file with `params`, when it saves.
    pub fn save(&self, params: &serde_json::Value) -> Option<Vec<u8>> {
        self.hierarchy.save(params)
    }

    pub fn scene(&self) -> &Arc<Scene> {
        &self.scene
    }

    /// The primitives of the current cut (for export and inspection).
    pub fn draw_set(&self) -> &DrawSet {
        &self.draw
    }
}

/// The scene of `d` drawn in `style` (the live cut's, and a chain LOD's).
/// The heat map needs a bound per primitive: without one, plain colours.
pub fn styled_scene(d: &DrawSet, style: CutStyle) -> Scene {
    let plain = SceneStyle {
        splat_outlines: style.outlines,
        wireframe: style.wireframe,
        ..SceneStyle::default()
    };
    let heat = style.heat && d.triangle_errors.len() == d.mesh.triangles.len();
    if !heat && !style.by_type {
        return match style.regions {
            true => region_scene(d, plain),
            false => Scene::from_draw_set(d, &plain),
        };
    }
    let max = d.error_bound.max(f32::MIN_POSITIVE);
    let colors: Vec<glam::Vec3> = if heat {
        d.triangle_errors
            .iter()
            .map(|e| crate::heatmap::linear(e / max))
            .collect()
    } else {
        vec![TRIANGLE_COLOR; d.mesh.triangles.len()]
    };
    let mut styled = d.clone();
    for p in &mut styled.points {
        p.color = if heat {
            crate::heatmap::linear(p.error / max)
        } else {
            POINT_COLOR
        };
    }
    Scene::from_draw_set(
        &styled,
        &SceneStyle {
            triangle_colors: Some(&colors),
            ..plain
        },
    )
}

/// `d` coloured by region: triangles by level (the ramp, coarsest hottest),
/// splats by AMG domain (the texture's Ψ kept as alpha), layers each in a
/// hue of its own.
fn region_scene(d: &DrawSet, plain: SceneStyle) -> Scene {
    let top = d.triangle_levels.iter().copied().max().unwrap_or(0).max(1) as f32;
    let levels: Vec<glam::Vec3> = d
        .triangle_levels
        .iter()
        .map(|&l| crate::heatmap::linear(l as f32 / top))
        .collect();
    let layers: Vec<glam::Vec3> = (0..d.layers.len())
        .map(crate::heatmap::categorical)
        .collect();
    let mut styled = d.clone();
    for s in &d.splats {
        let rgb = crate::heatmap::categorical(s.domain).map(|c| c.powf(1.0 / 2.2) * 255.0);
        if let Some(t) = styled.textures.get_mut(s.texture) {
            for texel in &mut t.rgba {
                texel[..3].copy_from_slice(&rgb.to_array().map(|c| c as u8));
            }
        }
    }
    Scene::from_draw_set(
        &styled,
        &SceneStyle {
            triangle_colors: (!levels.is_empty()).then_some(&levels[..]),
            layer_colors: Some(&layers),
            ..plain
        },
    )
}

/// Whether `d` carries error bounds per triangle or point to colour by.
pub fn set_has_errors(d: &DrawSet) -> bool {
    !d.triangle_errors.is_empty() || !d.points.is_empty()
}

/// [`CutStats::screen_pixels`]: each triangle's bound at its centroid and
/// each point's at its centre, over those in the view that face the eye.
fn screen_pixels(d: &DrawSet, view: &View) -> Option<f32> {
    let test = view.sphere_test();
    let m = &d.mesh;
    let triangles = (d.triangle_errors.len() == m.triangles.len()).then(|| {
        m.triangles
            .iter()
            .zip(&d.triangle_errors)
            .filter_map(|(t, &e)| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                let centre = (a + b + c) / 3.0;
                let faces = (b - a).cross(c - a).dot(view.eye - centre) > 0.0;
                (faces && test.sees(centre, 0.0)).then(|| test.pixels(e as f64, centre, 0.0))
            })
    });
    let points = d.points.iter().filter_map(|p| {
        let faces = p.normal.dot(view.eye - p.center) >= 0.0;
        (faces && test.sees(p.center, p.radius))
            .then(|| test.pixels(p.error as f64, p.center, p.radius as f64))
    });
    let largest = triangles
        .into_iter()
        .flatten()
        .chain(points)
        .reduce(f64::max);
    largest.map(|px| px as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use lodstudio_core::voxel::layers::Layered;

    #[test]
    fn layered_cuts_are_reselected_only_when_the_slicing_direction_changes() {
        let mesh = lodstudio_core::builtins::torus(1.0, 0.3, 16, 8);
        let layer = |alpha| lodstudio_core::lod::Layer {
            mesh: mesh.clone(),
            alpha,
            isodensity: alpha,
        };
        let h = Layered {
            layers: vec![layer(1.0), layer(0.5)],
            origin: glam::Vec3::splat(-2.0),
            spacing: glam::Vec3::splat(0.1),
            error_bound: f32::INFINITY,
            level: None,
            plan: None,
        };
        let tol = crate::settings::threshold::Threshold::default().tolerance();
        let view = View::orbit(glam::Vec3::ZERO, 4.0, 0.1, 0.1);
        let mut live = LiveCut::new(Box::new(h), &view, tol);
        assert_eq!(live.stats.layer_triangles, 2 * mesh.triangles.len());
        assert_eq!(live.scene().triangle_count(), 2 * mesh.triangles.len());
        // A small turn keeps the slicing axis: nothing to do.
        assert!(!live.update(&View::orbit(glam::Vec3::ZERO, 4.0, 0.15, 0.1), tol));
        // Looking from the side flips to another axis.
        assert!(live.update(&View::orbit(glam::Vec3::ZERO, 4.0, 1.5, 0.1), tol));
        assert_eq!(live.stats.cuts, 2);
    }

    /// A view-dependent cut within t pixels keeps every primitive in view
    /// within t at its own depth (the merge tree's and the hybrid's §5/§6
    /// criteria), while its coarsest bound projected at the target is larger:
    /// the inspector's figure is the one the threshold limits.
    #[test]
    fn view_dependent_cuts_keep_what_is_on_screen_within_the_threshold() {
        use lodstudio_core::lod::{Method, Params, build};
        let mesh = lodstudio_core::builtins::torus(1.0, 0.3, 96, 48);
        let view = View::orbit(glam::Vec3::ZERO, 8.0, 0.4, 0.3);
        for method in [Method::MergeTree, Method::Hybrid] {
            let mut largest = 0.0f32;
            for t in [4.0, 16.0, 64.0] {
                let params = Params::default_for(method);
                let h = build(&params, &mesh, &Default::default()).unwrap();
                let live = LiveCut::new(h, &view, Tolerance::Pixels(t));
                let on_screen = live.stats.screen_pixels.expect("errors per primitive");
                assert!(
                    on_screen <= t * 1.001,
                    "{method:?} at {t} px: {on_screen} px"
                );
                largest = largest.max(on_screen);
            }
            assert!(largest > 0.0, "{method:?} simplified nothing in view");
        }
    }
}
