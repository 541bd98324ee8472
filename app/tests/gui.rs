//! The studio driven headlessly through egui_kittest with a real wgpu renderer
//! (llvmpipe or lavapipe on machines without a GPU).

use std::path::PathBuf;
use std::time::{Duration, Instant};

mod common;
#[path = "common/pixels.rs"]
mod pixels;

use common::{save_ppm, studio, wait_while};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use lodstudio::session::{Autosave, Session};
use lodstudio::settings::Method;
use lodstudio::settings::simplify::TargetMode;
use lodstudio::studio::StudioApp;
use lodstudio_core::voxel::Filter;
use pixels::{colourful, viewport_image};

/// Steps frames until the studio has no load running (bounded), then settles.
fn wait_for_load(harness: &mut Harness<'_, StudioApp>) {
    wait_while(harness, "loading", StudioApp::is_loading);
}

/// Steps frames until no build is pending or running (bounded), then settles.
fn wait_for_build(harness: &mut Harness<'_, StudioApp>) {
    wait_while(harness, "building", StudioApp::is_building);
}

/// Cancels the running build and checks that `before` is still the result and
/// is what the viewport draws.
fn cancel_keeps(harness: &mut Harness<'_, StudioApp>, before: &lodstudio_core::TriMesh) {
    harness.get_by_label("Cancel").click();
    harness.step();
    assert!(!harness.state().is_building());
    harness.run();
    let after = harness
        .state()
        .result()
        .expect("previous result kept")
        .mesh();
    assert_eq!(after, before);
    assert_eq!(drawn_triangles(harness), Some(before.triangles.len()));
}

/// The inspector shows the voxel result's rows and its triangle count.
fn assert_voxel_rows(harness: &Harness<'_, StudioApp>, triangles: usize) {
    for label in [
        "Voxel (low-pass + marching cubes)",
        "resolution",
        "filter radius",
        "LOD triangles",
        "LOD components",
        "LOD genus",
        "build time",
    ] {
        assert!(has_label(harness, label), "inspector row {label:?}");
    }
    assert!(has_label(harness, &triangles.to_string()));
}

/// Exports the current result to `out`, waits, and returns the triangle count of
/// the file read back.
fn export_and_reload(harness: &mut Harness<'_, StudioApp>, out: &std::path::Path) -> usize {
    let ctx = harness.ctx.clone();
    harness.state_mut().export_to(out, &ctx);
    wait_while(harness, "exporting", StudioApp::is_exporting);
    let reread = lodstudio_core::io::load(
        out,
        &lodstudio_core::io::LoadOptions::default(),
        &lodstudio_core::Progress::new(),
    )
    .expect("the export loads");
    let lodstudio_core::Model::Mesh(mesh) = reread.model else {
        panic!("the export is a mesh");
    };
    mesh.triangles.len()
}

/// Steps frames while `busy` holds (bounded in frames and time), then settles.
fn has_label(harness: &Harness<'_, StudioApp>, label: &str) -> bool {
    harness.query_all_by_label(label).next().is_some()
}

/// Renders the studio, saves the image as `name`, and measures the viewport:
/// the fraction of its pixels that differ from the background (its corner)
/// and how many distinct colours those have.
fn viewport_pixels(harness: &mut Harness<'_, StudioApp>, name: &str) -> (f32, usize, u64) {
    canvas_pixels(harness, "3D viewport", name)
}

/// Like [`viewport_pixels`], for the canvas labelled `label`.
fn canvas_pixels(
    harness: &mut Harness<'_, StudioApp>,
    label: &str,
    name: &str,
) -> (f32, usize, u64) {
    let rect = harness.get_by_label(label).rect();
    let image = harness.render().expect("render the studio");
    let path = save_ppm(image.width(), image.height(), image.as_raw(), name);
    eprintln!("rendered the studio to {}", path.display());
    let (x0, y0) = (rect.min.x.ceil() as u32 + 2, rect.min.y.ceil() as u32 + 2);
    let (x1, y1) = (rect.max.x.floor() as u32 - 2, rect.max.y.floor() as u32 - 2);
    let background = image.get_pixel(x0, y0).0;
    let mut total = 0usize;
    let mut model: Vec<[u8; 4]> = Vec::new();
    for y in (y0..y1).step_by(2) {
        for x in (x0..x1).step_by(2) {
            total += 1;
            let px = image.get_pixel(x, y).0;
            if px != background {
                model.push(px);
            }
        }
    }
    let covered = model.len() as f32 / total.max(1) as f32;
    // Any change of any pixel (not only of the set of colours) shows in the digest.
    let digest = {
        use std::hash::{Hash as _, Hasher as _};
        let mut h = std::collections::hash_map::DefaultHasher::new();
        model.hash(&mut h);
        h.finish()
    };
    model.sort_unstable();
    model.dedup();
    (covered, model.len(), digest)
}

#[test]
fn default_model_shows_counts_and_is_drawn() {
    let mut harness = studio(None);
    wait_for_load(&mut harness);

    let summary = harness
        .state()
        .summary()
        .expect("the default model loaded")
        .clone();
    assert!(summary.triangles > 0, "default model has triangles");
    assert!(has_label(&harness, "triangles"), "inspector row label");
    let count = summary.triangles.to_string();
    assert!(
        has_label(&harness, &count),
        "inspector shows the triangle count {count}"
    );

    let rect = harness.get_by_label("3D viewport").rect();
    assert!(rect.width() > 200.0 && rect.height() > 200.0, "{rect:?}");

    let (covered, shades, _) = viewport_pixels(&mut harness, "studio_default");
    assert!(
        covered > 0.02,
        "only {:.1}% of the viewport differs from the background",
        covered * 100.0
    );
    // Lit, not flat: the model shows many shades.
    assert!(shades > 20, "only {shades} shades");
}

#[test]
fn missing_file_shows_error_and_keeps_model() {
    let mut harness = studio(Some("builtin:sphere".into()));
    wait_for_load(&mut harness);
    let before = harness.state().summary().expect("sphere loaded").clone();

    harness
        .state_mut()
        .open("/nonexistent/lodstudio-missing-model.obj");
    wait_for_load(&mut harness);

    assert!(has_label(&harness, "Could not open model"), "error window");
    assert!(
        harness
            .query_all_by_label_contains("lodstudio-missing-model.obj")
            .next()
            .is_some(),
        "the error names the file"
    );
    let after = harness.state().summary().expect("previous model kept");
    assert_eq!(after, &before);
    assert!(has_label(&harness, &before.triangles.to_string()));

    // Dismissing the error closes its window; the model stays.
    harness.get_by_label("OK").click();
    harness.run();
    assert!(!has_label(&harness, "Could not open model"));
    assert_eq!(harness.state().summary(), Some(&before));
}

#[test]
fn builtin_button_loads_that_model() {
    let mut harness = studio(Some("builtin:sphere".into()));
    wait_for_load(&mut harness);
    let sphere = harness.state().summary().expect("sphere loaded").triangles;

    harness
        .get_by_role_and_label(egui::Role::Button, "torus")
        .click();
    harness.step();
    assert!(harness.state().is_loading());
    wait_for_load(&mut harness);

    let torus = harness.state().summary().expect("torus loaded");
    assert_ne!(torus.triangles, sphere);
    assert!(has_label(&harness, &torus.triangles.to_string()));
    assert!(
        harness
            .state()
            .log_lines()
            .any(|l| l.contains("builtin:torus")),
        "log names the model"
    );

    // The same through File → Built-in models.
    harness.get_by_label("File").click();
    harness.run();
    // A button in the menu; the left panel's header is a disclosure triangle.
    harness
        .get_by_role_and_label(egui::Role::Button, "Built-in models")
        .hover();
    harness.run();
    let sphere_buttons: Vec<_> = harness
        .get_all_by_role_and_label(egui::Role::Button, "sphere")
        .collect();
    assert_eq!(sphere_buttons.len(), 2, "left panel and submenu");
    // The submenu's button is the one right of the left panel's.
    let in_menu = sphere_buttons
        .iter()
        .max_by(|a, b| a.rect().min.x.total_cmp(&b.rect().min.x))
        .expect("two buttons");
    in_menu.click();
    harness.step();
    wait_for_load(&mut harness);
    assert_eq!(harness.state().summary().map(|s| s.triangles), Some(sphere));
}

#[test]
fn point_set_is_drawn() {
    let mut harness = studio(Some("builtin:octahedron-points".into()));
    wait_for_load(&mut harness);
    let summary = harness.state().summary().expect("points loaded");
    assert!(summary.points > 0);
    assert!(has_label(&harness, &summary.points.to_string()));
    let (covered, shades, _) = viewport_pixels(&mut harness, "studio_points");
    assert!(covered > 0.02, "points cover {:.1}%", covered * 100.0);
    assert!(shades > 4, "only {shades} shades");
}

/// (yaw, pitch, distance, target) of the studio's camera.
fn camera(harness: &Harness<'_, StudioApp>) -> (f32, f32, f32, glam::Vec3) {
    let v = harness.state().viewport().camera;
    (v.yaw, v.pitch, v.distance, v.target)
}

fn press(
    harness: &Harness<'_, StudioApp>,
    pos: egui::Pos2,
    button: egui::PointerButton,
    pressed: bool,
) {
    harness.event(egui::Event::PointerButton {
        pos,
        button,
        pressed,
        modifiers: egui::Modifiers::NONE,
    });
}

/// Drags with `button` from `from` by (60, 30) points, in two moves.
fn drag(harness: &Harness<'_, StudioApp>, from: egui::Pos2, button: egui::PointerButton) {
    harness.hover_at(from);
    press(harness, from, button, true);
    harness.hover_at(from + egui::vec2(30.0, 15.0));
    harness.hover_at(from + egui::vec2(60.0, 30.0));
    press(harness, from + egui::vec2(60.0, 30.0), button, false);
}

#[test]
fn viewport_camera_follows_pointer() {
    use egui::PointerButton::{Primary, Secondary};
    let mut harness = studio(Some("builtin:torus".into()));
    wait_for_load(&mut harness);
    let center = harness.get_by_label("3D viewport").rect().center();
    let (yaw0, pitch0, dist0, target0) = camera(&harness);

    // Left-drag orbits.
    drag(&harness, center, Primary);
    harness.run();
    let (yaw1, pitch1, dist1, target1) = camera(&harness);
    assert!(
        yaw1 < yaw0 && pitch1 > pitch0,
        "orbit: {yaw0},{pitch0} -> {yaw1},{pitch1}"
    );
    assert_eq!((dist1, target1), (dist0, target0));

    // Right-drag pans.
    drag(&harness, center, Secondary);
    harness.run();
    let (_, _, dist2, target2) = camera(&harness);
    assert!(target2.distance(target0) > 1e-3, "pan moved the target");
    assert_eq!(dist2, dist0);

    // Scrolling up zooms in.
    harness.hover_at(center);
    harness.event(egui::Event::MouseWheel {
        unit: egui::MouseWheelUnit::Point,
        delta: egui::vec2(0.0, 120.0),
        phase: egui::TouchPhase::Move,
        source: egui::MouseWheelSource::Wheel,
        modifiers: egui::Modifiers::NONE,
    });
    harness.run();
    let (_, _, dist3, _) = camera(&harness);
    assert!(dist3 < dist0, "zoom: {dist0} -> {dist3}");

    // Double-click frames the model again.
    for _ in 0..2 {
        press(&harness, center, Primary, true);
        press(&harness, center, Primary, false);
    }
    harness.run();
    let (_, _, dist4, target4) = camera(&harness);
    assert!((dist4 - dist0).abs() < 1e-4 * dist0, "{dist4} vs {dist0}");
    assert!(target4.distance(target0) < 1e-5);
}

#[test]
fn runs_without_wgpu() {
    let app = StudioApp::with_render_state(None, Some("builtin:sphere".into()));
    let mut harness = Harness::builder()
        .with_size([1024.0, 700.0])
        .build_ui_state(|ui, app: &mut StudioApp| app.show(ui), app);
    wait_for_load(&mut harness);
    assert!(has_label(&harness, "3D viewport needs wgpu"));
    assert!(has_label(&harness, "3D viewport"));
    assert!(harness.state().summary().is_some());
}

/// A file dropped onto the window, as the winit integration reports it.
#[derive(Debug)]
struct Dropped(PathBuf);

impl egui::DroppedFile for Dropped {
    fn path(&self) -> &std::path::Path {
        &self.0
    }

    fn bytes(&self) -> Result<Vec<u8>, String> {
        std::fs::read(&self.0).map_err(|e| e.to_string())
    }
}

#[test]
fn dropped_file_opens_and_becomes_recent() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join("gui-dropped-tetrahedron.off");
    std::fs::write(
        &file,
        "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n",
    )
    .expect("write the test model");

    let mut harness = studio(Some("builtin:sphere".into()));
    wait_for_load(&mut harness);
    harness
        .input_mut()
        .dropped_files
        .push(std::sync::Arc::new(Dropped(file.clone())));
    // The tiny file may load within the first frame already: wait either way.
    harness.step();
    wait_for_load(&mut harness);

    assert_eq!(harness.state().summary().map(|s| s.triangles), Some(4));
    // Listed under "Recent files" (the model name above it is a plain label).
    assert!(
        harness
            .query_all_by_role_and_label(egui::Role::Button, "gui-dropped-tetrahedron.off")
            .next()
            .is_some()
    );
}

/// A long load (the 871k-triangle dragon) stays in progress until cancelled,
/// and the model shown before it stays.
#[test]
fn cancel_keeps_previous_model() {
    let dragon = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/models/dragon_vrip.ply.gz"
    );
    let mut harness = studio(Some("builtin:sphere".into()));
    wait_for_load(&mut harness);
    let before = harness.state().summary().expect("sphere loaded").clone();

    harness.state_mut().open(dragon);
    harness.step();
    harness.step();
    assert!(harness.state().is_loading());
    harness.get_by_label("Cancel").click();
    harness.step();
    assert!(!harness.state().is_loading());
    harness.run();

    assert_eq!(harness.state().summary(), Some(&before));
    assert!(has_label(&harness, &before.triangles.to_string()));
    assert!(!has_label(&harness, "Could not open model"));
    assert!(
        harness
            .state()
            .log_lines()
            .any(|l| l.starts_with("Cancelled loading dragon_vrip.ply.gz")),
    );
}

/// A FIFO (or a device) is no model: refused at once with a message, never
/// waited on, and the model shown before it stays.
#[cfg(unix)]
#[test]
fn a_fifo_is_refused_at_once_and_the_model_kept() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("gui.fifo");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("run mkfifo");
    assert!(made.success());

    let mut harness = studio(Some("builtin:sphere".into()));
    wait_for_load(&mut harness);
    let before = harness.state().summary().expect("sphere loaded").clone();

    harness.state_mut().open(&fifo);
    wait_for_load(&mut harness);
    assert!(has_label(&harness, "Could not open model"), "error window");
    assert!(
        harness
            .query_all_by_label_contains("a FIFO, not a regular file")
            .next()
            .is_some(),
        "the error says why"
    );
    assert_eq!(harness.state().summary(), Some(&before));
}

/// Triangles the viewport draws now.
fn drawn_triangles(harness: &Harness<'_, StudioApp>) -> Option<usize> {
    harness
        .state()
        .viewport()
        .scene()
        .map(|s| s.triangle_count())
}

#[test]
fn edge_collapse_builds_shows_certificate_and_exports() {
    let mut harness = studio(None);
    wait_for_load(&mut harness);
    assert_eq!(harness.state().summary().map(|s| s.triangles), Some(3714));
    assert!(
        harness.state().methods().auto_rebuild,
        "auto rebuild is on by default"
    );

    // Drag the ratio to 0.25 (as assistive technology sets a slider); auto
    // rebuild starts the build once the parameters have been still a while.
    harness
        .get_by_role_and_label(egui::Role::Slider, "ratio")
        .set_value_accesskit(0.25);
    harness.step();
    assert_eq!(harness.state().methods().edge_collapse.ratio, 0.25);
    assert!(harness.state().is_building(), "a rebuild is scheduled");
    wait_for_build(&mut harness);

    harness.run();
    let built = harness.state().result().expect("the build finished");
    let triangles = built.mesh().triangles.len();
    let live = &built.live;
    let bound = live.stats.error_bound;
    assert!(triangles > 900 && triangles <= 929, "{triangles} triangles");
    assert!(bound.is_finite() && bound > 0.0, "bound {bound}");
    for label in [
        "original triangles",
        "recorded collapses",
        "floor triangles",
        "bound at the floor",
        "build time",
        "cut triangles",
        "cut bound",
    ] {
        assert!(has_label(&harness, label), "inspector row {label:?}");
    }
    assert!(has_label(&harness, &triangles.to_string()));
    let shown = lodstudio::build::length(bound);
    assert!(
        harness.query_all_by_label_contains(&shown).next().is_some(),
        "{shown}"
    );
    assert!(
        harness
            .state()
            .log_lines()
            .any(|l| l.contains("bound at the floor")),
        "the log reports the build"
    );

    // The ratio slider moves the cut within a frame: no rebuild.
    let cuts = live.stats.cuts;
    harness
        .get_by_role_and_label(egui::Role::Slider, "ratio")
        .set_value_accesskit(0.1);
    harness.run();
    assert!(!harness.state().is_building(), "a target is no rebuild");
    let live = &harness.state().result().unwrap().live;
    let coarser = live.stats.triangles;
    assert!(coarser > 350 && coarser <= 371, "{coarser}");
    assert!(live.stats.error_bound >= bound && live.stats.cuts > cuts);
    assert_eq!(drawn_triangles(&harness), Some(coarser));
    harness
        .get_by_role_and_label(egui::Role::Slider, "ratio")
        .set_value_accesskit(0.25);
    harness.run();
    assert_eq!(drawn_triangles(&harness), Some(triangles), "and back");

    // The viewport shows the result; the toggle switches back and forth.
    assert_eq!(drawn_triangles(&harness), Some(triangles));
    harness.get_by_label("Original").click();
    harness.run();
    assert_eq!(drawn_triangles(&harness), Some(3714));
    harness.get_by_label("Simplified").click();
    harness.run();
    assert_eq!(drawn_triangles(&harness), Some(triangles));

    // Colour by the certified bound: a legend explains the colours.
    harness.get_by_label("Colour by certified bound").click();
    harness.run();
    assert!(has_label(&harness, "error bound per primitive"));
    let (covered, shades, _) = viewport_pixels(&mut harness, "studio_heat");
    assert!(covered > 0.02, "covers {:.1}%", covered * 100.0);
    assert!(shades > 20, "only {shades} shades");

    // Export writes a file the loader reads back with the same triangles.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let out = dir.join("gui-export.obj");
    assert_eq!(export_and_reload(&mut harness, &out), triangles);

    // A format the writer does not know is reported, not written.
    let ctx = harness.ctx.clone();
    harness
        .state_mut()
        .export_to(dir.join("gui-export.xyz"), &ctx);
    wait_while(&mut harness, "exporting", StudioApp::is_exporting);
    assert!(
        harness
            .state()
            .log_lines()
            .any(|l| l.starts_with("Export failed") && l.contains("xyz")),
    );
}

#[test]
fn cancelling_a_build_keeps_the_previous_result() {
    let mut harness = studio(Some("builtin:sphereflake".into()));
    wait_for_load(&mut harness);
    let input = harness
        .state()
        .summary()
        .expect("sphereflake loaded")
        .triangles;

    let mut methods = *harness.state().methods();
    methods.auto_rebuild = false;
    methods.edge_collapse.ratio = 0.5;
    harness.state_mut().set_methods(methods);
    harness.step();
    assert!(
        !harness.state().is_building(),
        "no auto rebuild when it is off"
    );
    harness.get_by_label("Build").click();
    wait_for_build(&mut harness);
    let before = harness
        .state()
        .result()
        .expect("first build")
        .mesh()
        .clone();
    assert!(before.triangles.len() <= input / 2);

    // A new sliver guard records the collapses again (seconds): cancel it.
    methods.edge_collapse.min_quality = 0.3;
    harness.state_mut().set_methods(methods);
    harness.state_mut().build();
    harness.step();
    harness.step();
    assert!(
        harness.state().is_building(),
        "the build is still running: {:?}",
        harness.state().log_lines().collect::<Vec<_>>()
    );
    assert!(
        harness
            .query_all_by_label_contains("Edge collapse of builtin:sphereflake: ")
            .next()
            .is_some(),
        "the progress row names the build and its stage"
    );
    cancel_keeps(&mut harness, &before);
    assert!(has_label(&harness, &before.triangles.len().to_string()));
    assert!(harness.state().log_lines().any(
        |l| l == "Cancelled Edge collapse of builtin:sphereflake; the previous result is kept"
    ),);
    assert!(has_label(
        &harness,
        "Parameters changed since the last build."
    ));
}

#[test]
fn build_on_a_point_set_explains_instead_of_failing() {
    let mut harness = studio(Some("builtin:octahedron-points".into()));
    wait_for_load(&mut harness);
    let message =
        "Edge collapse needs a triangle mesh, and this model is a point set (16000 points).";
    assert!(has_label(&harness, message), "the method section says why");

    // Asked anyway (the Build button is disabled): the same message, no result.
    harness.state_mut().build();
    wait_for_build(&mut harness);
    assert!(harness.state().result().is_none());
    assert!(harness.state().log_lines().any(|l| l == message));
    assert!(harness.state().summary().is_some_and(|s| s.points == 16000));

    // Changing parameters schedules nothing for a point set.
    let mut methods = *harness.state().methods();
    methods.edge_collapse.ratio = 0.5;
    harness.state_mut().set_methods(methods);
    assert!(!harness.state().is_building());
}

/// A killed studio (never saved nor dropped: its state is leaked) comes back
/// on the next start with its model, method settings and volume threshold,
/// having lost at most one autosave interval; a damaged session file is
/// reported and the defaults are used.
#[test]
fn autosave_restores_a_killed_session() {
    // Declared first, removed last: the studios below save on drop.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("autosave-killed");
    let interval = Duration::from_millis(100);
    let mut first = studio(Some(SKULL.into()));
    let autosave = Autosave::in_dir(&dir).with_interval(interval);
    let file = autosave.file().expect("autosave on").to_path_buf();
    first.state_mut().resume(autosave, false);
    wait_for_load(&mut first);
    let mut methods = *first.state().methods();
    methods.auto_rebuild = false;
    methods.method = Method::Voxel;
    methods.voxel.filter = Filter::Cone;
    methods.voxel.radius = 3.5;
    methods.voxel.threshold = Some(2.9);
    methods.edge_collapse.mode = TargetMode::Triangles;
    methods.edge_collapse.triangles = 1234;
    first.state_mut().set_methods(methods);
    let changed = Instant::now();
    let saved = |file: &std::path::Path| {
        std::fs::read_to_string(file)
            .ok()
            .and_then(|json| Session::from_json(&json))
            .is_some_and(|s| {
                // The threshold is kept beside its volume, not in the settings.
                let mut saved = s.methods;
                saved.voxel.threshold = s.volume_threshold.map(|(_, t)| t);
                saved == methods
            })
    };
    while !saved(&file) {
        assert!(
            changed.elapsed() < Duration::from_secs(10),
            "never autosaved"
        );
        std::thread::sleep(interval / 4);
        first.step();
    }
    assert!(changed.elapsed() < interval * 4 + Duration::from_secs(1));
    std::mem::forget(first);

    let mut second = studio(None);
    second.state_mut().resume(Autosave::in_dir(&dir), true);
    wait_for_load(&mut second);
    assert!(matches!(
        second.state().loaded().map(|l| &l.model),
        Some(lodstudio_core::Model::Volume(_))
    ));
    assert_eq!(second.state().methods(), &methods, "threshold included");
    assert!(
        second
            .state()
            .log_lines()
            .any(|l| l == "Reopening the last session (skull_2.9.inr)")
    );

    std::fs::write(&file, "{ damaged").unwrap();
    let mut third = studio(Some("builtin:sphere".into()));
    third.state_mut().resume(Autosave::in_dir(&dir), true);
    wait_for_load(&mut third);
    assert_eq!(
        third.state().methods(),
        &lodstudio::settings::MethodSettings::default()
    );
    assert!(third.state().log_lines().any(|l| l.contains("damaged")));
}

/// Genus of the last voxel result.
fn voxel_genus(harness: &Harness<'_, StudioApp>) -> i64 {
    harness
        .state()
        .result()
        .and_then(|b| b.voxel.as_deref())
        .expect("a voxel result")
        .genus
}

/// The value of the result's inspector row `label`.
fn result_row(harness: &Harness<'_, StudioApp>, label: &str) -> String {
    let built = harness.state().result().expect("a result");
    let row = built.rows.iter().find(|r| r.label == label);
    row.map(|r| r.value.clone())
        .unwrap_or_else(|| panic!("no row {label:?}"))
}

#[test]
fn voxel_method_closes_holes_as_the_filter_widens() {
    let mut harness = studio(Some("builtin:csg-part".into()));
    wait_for_load(&mut harness);
    let original = harness
        .state()
        .summary()
        .expect("csg-part loaded")
        .triangles;

    // Select the method in the list, as a user does.
    harness
        .get_by_label("Voxel (low-pass + marching cubes)")
        .click();
    harness.run();
    assert_eq!(harness.state().methods().method, Method::Voxel);
    for label in ["Gaussian", "Cone", "resolution", "filter radius", "iso"] {
        assert!(has_label(&harness, label), "control {label:?}");
    }
    wait_for_build(&mut harness);

    let mut methods = *harness.state().methods();
    methods.voxel.resolution = 48;
    methods.voxel.radius = 1.0;
    harness.state_mut().set_methods(methods);
    harness.step();
    assert!(harness.state().is_building(), "auto rebuild is scheduled");
    wait_for_build(&mut harness);

    assert_eq!(voxel_genus(&harness), 5);
    let built = harness.state().result().expect("built");
    let triangles = built.mesh().triangles.len();
    assert!(triangles > 0);
    assert_eq!(result_row(&harness, "LOD genus"), "5");
    assert_eq!(result_row(&harness, "resolution"), "48");
    assert_voxel_rows(&harness, triangles);
    assert!(
        harness.state().log_lines().any(|l| l
            .starts_with("Voxel (low-pass + marching cubes) of builtin:csg-part: ")
            && l.contains("genus 5")),
        "the log reports the build"
    );

    // The viewport shows the result; the toggle switches back and forth.
    assert_eq!(drawn_triangles(&harness), Some(triangles));
    harness.get_by_label("Original").click();
    harness.run();
    assert_eq!(drawn_triangles(&harness), Some(original));
    harness.get_by_label("Simplified").click();
    harness.run();
    assert_eq!(drawn_triangles(&harness), Some(triangles));
    let (covered, shades, _) = viewport_pixels(&mut harness, "studio_voxel");
    assert!(covered > 0.02, "covers {:.1}%", covered * 100.0);
    assert!(shades > 20, "only {shades} shades");

    // A wide filter closes the small holes.
    methods.voxel.radius = 10.0;
    harness.state_mut().set_methods(methods);
    harness.step();
    wait_for_build(&mut harness);
    let genus = voxel_genus(&harness);
    assert!(genus < 5, "genus {genus} at radius 10");
    assert_eq!(result_row(&harness, "LOD genus"), genus.to_string());

    // Export writes the voxel mesh.
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("gui-voxel-export.ply");
    let wide = harness
        .state()
        .result()
        .expect("built")
        .mesh()
        .triangles
        .len();
    assert_eq!(export_and_reload(&mut harness, &out), wide);
}

#[test]
fn voxel_on_a_point_set_explains_instead_of_building() {
    let mut harness = studio(Some("builtin:octahedron-points".into()));
    wait_for_load(&mut harness);
    harness
        .get_by_label("Voxel (low-pass + marching cubes)")
        .click();
    harness.run();
    assert!(!harness.state().is_building(), "nothing to build");
    let message = "Voxel (low-pass + marching cubes) samples solids (meshes, implicit \
                   built-ins, volumes), and this model is a point set (16000 points).";
    assert!(has_label(&harness, message), "the method section says why");

    // Asked anyway (the Build button is disabled): the same message, no result.
    harness.state_mut().build();
    wait_for_build(&mut harness);
    assert!(harness.state().result().is_none());
    assert!(harness.state().log_lines().any(|l| l == message));

    // Changing parameters schedules nothing.
    let mut methods = *harness.state().methods();
    methods.voxel.radius = 3.0;
    harness.state_mut().set_methods(methods);
    assert!(!harness.state().is_building());
}

#[test]
fn cancelling_a_voxel_build_keeps_the_previous_result() {
    let mut harness = studio(Some("builtin:csg-part".into()));
    wait_for_load(&mut harness);
    let mut methods = *harness.state().methods();
    methods.method = Method::Voxel;
    methods.auto_rebuild = false;
    methods.voxel.resolution = 32;
    methods.voxel.radius = 1.0;
    harness.state_mut().set_methods(methods);
    // The voxel controls move the Build button: lay out the panel first.
    harness.run();
    harness.get_by_label("Build").click();
    wait_for_build(&mut harness);
    let before = harness
        .state()
        .result()
        .expect("first build")
        .mesh()
        .clone();

    // The hyper-cone is not separable: this wide one takes seconds. Cancel it.
    methods.voxel.filter = Filter::Cone;
    methods.voxel.resolution = 64;
    methods.voxel.radius = 16.0;
    harness.state_mut().set_methods(methods);
    harness.get_by_label("Build").click();
    harness.step();
    harness.step();
    assert!(harness.state().is_building(), "the build is still running");
    cancel_keeps(&mut harness, &before);
    assert!(harness.state().log_lines().any(|l| l
        == "Cancelled Voxel (low-pass + marching cubes) of builtin:csg-part; the previous result is kept"));
    assert!(has_label(
        &harness,
        "Parameters changed since the last build."
    ));
}

/// A CT volume (64 x 64 x 64 floats) whose bone surface lies at the value 2.9.
const SKULL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../shared/models/skull_2.9.inr"
);

#[test]
fn voxel_method_builds_a_volume_at_its_threshold() {
    let mut harness = studio(Some(SKULL.into()));
    wait_for_load(&mut harness);
    assert!(matches!(
        harness.state().loaded().map(|l| &l.model),
        Some(lodstudio_core::Model::Volume(_))
    ));

    harness
        .get_by_label("Voxel (low-pass + marching cubes)")
        .click();
    harness.step();
    // The method section explains only what cannot build (the messages of
    // build::voxel_source all start so); a volume can.
    assert!(
        harness
            .query_all_by_label_contains("Voxel simplification")
            .next()
            .is_none(),
        "a volume builds"
    );
    assert!(harness.state().methods().method == Method::Voxel);
    // A volume keeps its grid and has a threshold instead of a resolution; its
    // density surface is always 0.5, so there is no iso control.
    for label in [
        "Gaussian",
        "Cone",
        "grid 64 x 64 x 64 (the volume's own)",
        "threshold",
        "filter radius",
    ] {
        assert!(has_label(&harness, label), "control {label:?}");
    }
    for label in ["resolution", "iso"] {
        assert!(!has_label(&harness, label), "no control {label:?}");
    }
    assert_eq!(
        harness.state().methods().voxel.threshold,
        None,
        "the middle"
    );

    // Set the sliders (as assistive technology does) before the auto rebuild
    // of the selection starts: each change postpones it, so one build runs.
    harness
        .get_by_role_and_label(egui::Role::Slider, "threshold")
        .set_value_accesskit(2.9);
    harness.step();
    harness
        .get_by_role_and_label(egui::Role::Slider, "filter radius")
        .set_value_accesskit(1.0);
    harness.step();
    let voxel = harness.state().methods().voxel;
    assert_eq!((voxel.threshold, voxel.radius), (Some(2.9), 1.0));
    assert!(harness.state().is_building(), "auto rebuild is scheduled");
    wait_for_build(&mut harness);

    let built = harness.state().result().expect("the build finished");
    let triangles = built.mesh().triangles.len();
    assert!(triangles > 1000, "{triangles} triangles");
    assert_eq!(result_row(&harness, "resolution"), "64");
    assert_eq!(result_row(&harness, "threshold"), "2.900");
    assert_eq!(result_row(&harness, "filter radius"), "1.0 voxels");
    assert_voxel_rows(&harness, triangles);
    assert!(!has_label(
        &harness,
        "Parameters changed since the last build."
    ));
    assert!(
        harness
            .state()
            .log_lines()
            .any(|l| l.starts_with("Voxel (low-pass + marching cubes) of skull_2.9.inr: ")),
        "the log reports the build"
    );
    assert_eq!(drawn_triangles(&harness), Some(triangles));

    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("gui-voxel-volume-export.obj");
    assert_eq!(export_and_reload(&mut harness, &out), triangles);

    // The threshold belongs to the volume: reopening it keeps it, another
    // volume starts from the middle of its own value range.
    harness.state_mut().open(SKULL);
    wait_for_load(&mut harness);
    assert_eq!(harness.state().methods().voxel.threshold, Some(2.9));
    let other = tmp.path().join("gui-ramp.nrrd");
    let mut nrrd =
        b"NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 4 4\nencoding: raw\nendian: little\n\n"
            .to_vec();
    nrrd.extend((0..64u8).map(|i| i * 3));
    std::fs::write(&other, nrrd).expect("write the test volume");
    harness.state_mut().open(&other);
    wait_for_load(&mut harness);
    assert_eq!(harness.state().methods().voxel.threshold, None);
    assert!(has_label(&harness, "grid 4 x 4 x 4 (the volume's own)"));
}

/// The triangles of the live cut on screen.
fn cut_stats(harness: &Harness<'_, StudioApp>) -> lodstudio::live_cut::CutStats {
    harness
        .state()
        .result()
        .map(|b| &b.live)
        .expect("a live cut")
        .stats
}

/// Colouring the live cut by its regions (`label`) redraws it differently
/// without re-cutting; clicking again restores the plain colours.
fn colour_by_region_redraws(harness: &mut Harness<'_, StudioApp>, label: &str, name: &str) {
    let cuts = cut_stats(harness).cuts;
    let (_, _, plain) = viewport_pixels(harness, &format!("{name}_plain"));
    harness.get_by_label(label).click();
    harness.run();
    let (covered, _, regions) = viewport_pixels(harness, &format!("{name}_regions"));
    assert!(covered > 0.02, "{label}: drawn");
    assert_ne!(plain, regions, "{label}: the colours changed");
    assert_eq!(cut_stats(harness).cuts, cuts, "{label}: no re-cut");
    harness.get_by_label(label).click();
    harness.run();
    assert_eq!(viewport_pixels(harness, &format!("{name}_again")).2, plain);
}

#[test]
fn merge_tree_refines_live_with_the_threshold_and_the_camera() {
    let mut harness = studio(None);
    wait_for_load(&mut harness);
    harness.get_by_label("Merge tree (view-dependent)").click();
    harness.run();
    if !harness.state().is_building() {
        harness.get_by_label("Build").click();
        harness.step();
    }
    wait_for_build(&mut harness);
    assert!(
        has_label(&harness, "vertices per tree level"),
        "the level plot"
    );
    assert!(has_label(&harness, "tree levels"));
    let fine = cut_stats(&harness);
    assert!(fine.triangles > 0);
    assert_eq!(drawn_triangles(&harness), Some(fine.triangles));

    // A coarser threshold in pixels cuts fewer triangles, at once.
    harness
        .get_by_role_and_label(egui::Role::Slider, "error threshold")
        .set_value_accesskit(24.0);
    harness.run();
    assert!(!harness.state().is_building(), "no rebuild for a threshold");
    let coarse = cut_stats(&harness);
    assert!(coarse.triangles < fine.triangles, "{coarse:?} vs {fine:?}");
    colour_by_region_redraws(
        &mut harness,
        "Colour by merge-tree level",
        "studio_tree_levels",
    );

    // Moving the camera away coarsens further; every move re-cuts.
    let distance = harness.state().viewport().camera.distance;
    harness.state_mut().viewport_mut().camera.distance = distance * 6.0;
    harness.run();
    let far = cut_stats(&harness);
    assert!(far.cuts > coarse.cuts);
    assert!(far.triangles < coarse.triangles, "{far:?} vs {coarse:?}");
    assert_eq!(drawn_triangles(&harness), Some(far.triangles));
    assert!(has_label(&harness, "cut triangles"));

    // Clicking the model inspects the triangle under the pointer.
    let center = harness.get_by_label("3D viewport").rect().center();
    harness.hover_at(center);
    press(&harness, center, egui::PointerButton::Primary, true);
    press(&harness, center, egui::PointerButton::Primary, false);
    harness.run();
    assert!(
        harness
            .query_all_by_label_contains(", level ")
            .next()
            .is_some(),
        "the picked triangle, its bound and its tree level are shown"
    );

    // Criteria switch at run time: no rebuild.
    harness.get_by_label("back faces coarser").click();
    harness.run();
    assert!(!harness.state().is_building());
    assert!(cut_stats(&harness).cuts > far.cuts);
}

/// §3 and §5 in the studio: translucent layers drawn back to front, and the
/// whole pyramid browsed at a continuous position without rebuilding.
#[test]
fn voxel_layers_and_the_pyramid_are_shown_live() {
    let mut harness = studio(Some("builtin:csg-part".into()));
    wait_for_load(&mut harness);
    let mut methods = *harness.state().methods();
    methods.method = Method::Voxel;
    methods.voxel.resolution = 32;
    methods.voxel.radius = 1.0;
    methods.voxel.layers_error = 0.05;
    harness.state_mut().set_methods(methods);
    harness.step();
    wait_for_build(&mut harness);
    let layers: usize = result_row(&harness, "layers").parse().unwrap();
    assert!(layers >= 3, "{layers} layers");
    let stats = cut_stats(&harness);
    assert!(stats.layer_triangles > 0 && stats.triangles == 0);
    assert_eq!(drawn_triangles(&harness), Some(stats.layer_triangles));
    let (covered, _, _) = viewport_pixels(&mut harness, "studio_voxel_layers");
    assert!(
        covered > 0.02,
        "translucent layers drawn: {:.1}%",
        covered * 100.0
    );
    colour_by_region_redraws(
        &mut harness,
        "Colour by voxel layer",
        "studio_voxel_layer_hues",
    );
    // Turning the camera to another slicing axis re-orders them.
    harness.state_mut().viewport_mut().camera.yaw += std::f32::consts::FRAC_PI_2;
    harness.run();
    assert!(cut_stats(&harness).cuts > stats.cuts);

    methods.voxel.layers_error = 0.5;
    methods.voxel.pyramid = true;
    harness.state_mut().set_methods(methods);
    harness.step();
    wait_for_build(&mut harness);
    assert!(has_label(&harness, "genus per pyramid level"));
    let finest = cut_stats(&harness).triangles;
    assert!(finest > 0);
    // The level follows the threshold: a looser one shows a coarser level,
    // each with its certified bound.
    methods.threshold.in_pixels = false;
    methods.threshold.percent = 0.01;
    harness.state_mut().set_methods(methods);
    harness.run();
    assert_eq!(
        cut_stats(&harness).triangles,
        finest,
        "none within: the finest"
    );
    harness
        .get_by_role_and_label(egui::Role::Slider, "error threshold")
        .set_value_accesskit(20.0);
    harness.run();
    assert!(
        !harness.state().is_building(),
        "a threshold needs no rebuild"
    );
    let coarse = cut_stats(&harness);
    assert!(coarse.triangles < finest, "{coarse:?}");
    assert!(coarse.error_bound <= 0.2 * 4.62, "{coarse:?}");
    // The position overrides it, browsing between levels.
    harness.get_by_label("level follows the threshold").click();
    harness.run();
    harness
        .get_by_role_and_label(egui::Role::Slider, "pyramid position")
        .set_value_accesskit(1.5);
    harness.run();
    assert!(!harness.state().is_building(), "browsing needs no rebuild");
    let between = cut_stats(&harness).triangles;
    assert!(between < finest, "{between} < {finest}");
    assert_eq!(drawn_triangles(&harness), Some(between));
}

#[test]
fn hybrid_cut_mixes_triangles_and_points_live() {
    let mut harness = studio(None);
    wait_for_load(&mut harness);
    let mut methods = *harness.state().methods();
    methods.method = Method::Hybrid;
    methods.hybrid.kappa = 4.0;
    methods.hybrid.tau = 5.0;
    methods.threshold.in_pixels = false;
    methods.threshold.percent = 0.5;
    harness.state_mut().set_methods(methods);
    harness.step();
    wait_for_build(&mut harness);
    for label in [
        "κ (kappa)",
        "τ (tau)",
        "primitives vs error",
        "MRG nodes",
        "point replacements",
    ] {
        assert!(has_label(&harness, label), "{label:?}");
    }
    let fine = cut_stats(&harness);
    assert!(fine.triangles > 0);
    assert!(fine.error_bound <= 0.005 * 1.0001 * harness.state().summary().unwrap().bbox_diagonal);
    // A coarser object-space threshold: fewer primitives, points among them.
    harness
        .get_by_role_and_label(egui::Role::Slider, "error threshold")
        .set_value_accesskit(8.0);
    harness.run();
    assert!(!harness.state().is_building());
    let coarse = cut_stats(&harness);
    assert!(coarse.points > 0, "{coarse:?}");
    assert!(coarse.triangles + coarse.points < fine.triangles + fine.points);
    let (covered, _, _) = viewport_pixels(&mut harness, "studio_hybrid");
    assert!(covered > 0.02, "{:.1}%", covered * 100.0);
    // Colour by type: triangles and points in two colours, no re-cut.
    let (_, _, plain) = viewport_pixels(&mut harness, "studio_hybrid_plain");
    harness.get_by_label("Colour by type").click();
    harness.run();
    let (_, _, typed) = viewport_pixels(&mut harness, "studio_hybrid_types");
    assert_ne!(plain, typed);
    assert_eq!(cut_stats(&harness).cuts, coarse.cuts);
    harness.get_by_label("Colour by type").click();
    harness.run();
    // The heat map colours the cut by its bounds without re-cutting it.
    harness.get_by_label("Colour by certified bound").click();
    harness.run();
    assert!(has_label(&harness, "error bound per primitive"), "a legend");
    assert_eq!(cut_stats(&harness).cuts, coarse.cuts);
    let (_, _, heated) = viewport_pixels(&mut harness, "studio_hybrid_heat");
    assert_ne!(plain, heated, "the colours changed");
    // Object-space cuts ignore the camera: orbiting re-cuts nothing.
    harness.state_mut().viewport_mut().camera.yaw += 1.0;
    harness.run();
    assert_eq!(cut_stats(&harness).cuts, coarse.cuts);
    // Export writes the cut's triangles and, beside them, its points.
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("gui-hybrid-cut.obj");
    let points = out.with_extension("points.ply");
    assert_eq!(export_and_reload(&mut harness, &out), coarse.triangles);
    let read = lodstudio_core::io::load(&points, &Default::default(), &Default::default())
        .expect("the points load");
    let lodstudio_core::Model::Points(p) = read.model else {
        panic!("a point set");
    };
    assert_eq!(p.positions.len(), coarse.points);
    assert!(p.radii.is_some_and(|r| r.iter().all(|r| *r > 0.0)));
    assert!(
        harness
            .state()
            .log_lines()
            .any(|l| l.contains("points.ply"))
    );
}

/// A saved hierarchy reopens in the studio as a live cut, with its method and
/// parameters chosen, and without a rebuild.
#[test]
fn saved_hierarchies_reopen_without_rebuilding() {
    let mut harness = studio(None);
    wait_for_load(&mut harness);
    let mut methods = *harness.state().methods();
    methods.method = Method::MergeTree;
    methods.merge_tree.min_vertices = 40;
    // An object-space threshold: the cut does not depend on the panels' widths.
    methods.threshold.in_pixels = false;
    methods.threshold.percent = 1.0;
    harness.state_mut().set_methods(methods);
    harness.step();
    wait_for_build(&mut harness);
    let before = cut_stats(&harness);
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("gui-tree.lodh");
    let ctx = harness.ctx.clone();
    harness.state_mut().save_hierarchy_to(&out, &ctx);
    wait_while(&mut harness, "saving", StudioApp::is_exporting);
    assert!(out.exists(), "the hierarchy was saved");

    let mut reopened = studio(Some(out.clone()));
    wait_for_load(&mut reopened);
    reopened.run();
    assert!(!reopened.state().is_building(), "no rebuild");
    assert_eq!(reopened.state().methods().method, Method::MergeTree);
    assert_eq!(reopened.state().methods().merge_tree.min_vertices, 40);
    let mut shown = *reopened.state().methods();
    shown.threshold = methods.threshold;
    reopened.state_mut().set_methods(shown);
    reopened.run();
    assert!(
        !reopened.state().is_building(),
        "a threshold needs no rebuild"
    );
    let after = cut_stats(&reopened);
    assert_eq!(
        after.triangles, before.triangles,
        "same threshold, same cut"
    );
    assert!(
        reopened
            .state()
            .log_lines()
            .any(|l| l.contains("without rebuilding"))
    );
}

/// AMG domain primitives: textured splats blended by Ψ, the level moved live.
#[test]
fn amg_splats_are_drawn_and_the_level_moves_live() {
    let mut harness = studio(Some("builtin:octahedron-points".into()));
    wait_for_load(&mut harness);
    let mut methods = *harness.state().methods();
    methods.method = Method::Amg;
    methods.amg.level = 3;
    methods.amg.auto_level = false;
    harness.state_mut().set_methods(methods);
    harness.step();
    wait_for_build(&mut harness);
    assert!(has_label(&harness, "unknowns per AMG level"));
    let fine = cut_stats(&harness);
    assert!(fine.splats > 8, "{fine:?}");
    let (covered, shades, splats_look) = viewport_pixels(&mut harness, "studio_splats");
    assert!(covered > 0.05, "splats drawn: {:.1}%", covered * 100.0);
    assert!(shades > 8, "textured, blended colours: {shades}");
    // Outlines (Fig. 12) and colours by type redraw the same cut.
    harness.get_by_label("Splat outlines").click();
    harness.run();
    let (_, _, outlined) = viewport_pixels(&mut harness, "studio_splat_outlines");
    assert_ne!(outlined, splats_look, "outlines drawn");
    assert_eq!(cut_stats(&harness).cuts, fine.cuts, "no re-cut");
    harness.get_by_label("Splat outlines").click();
    harness.run();
    colour_by_region_redraws(&mut harness, "Colour by AMG domain", "studio_splat_domains");
    let last = result_row(&harness, "AMG levels").parse::<usize>().unwrap() - 1;
    harness
        .get_by_role_and_label(egui::Role::Slider, "AMG level")
        .set_value_accesskit(last as f64);
    harness.run();
    assert!(!harness.state().is_building(), "the level needs no rebuild");
    let coarse = cut_stats(&harness);
    assert_eq!(
        coarse.splats, 8,
        "one domain per face at the coarsest level"
    );
    // Export writes the splats: a GLB with their textures in one atlas,
    // blended, one primitive ...
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let ctx = harness.ctx.clone();
    harness.state_mut().export_to(dir.join("gui-amg.glb"), &ctx);
    wait_while(&mut harness, "exporting", StudioApp::is_exporting);
    let glb = std::fs::read(dir.join("gui-amg.glb")).expect("exported");
    let text = String::from_utf8_lossy(&glb);
    assert_eq!(text.matches("\"image/png\"").count(), 1);
    assert_eq!(text.matches("\"BLEND\"").count(), 1);
    assert_eq!(text.matches("\"indices\"").count(), 1);
    // ... and a format that cannot hold them says so instead of dropping them.
    harness.state_mut().export_to(dir.join("gui-amg.obj"), &ctx);
    wait_while(&mut harness, "exporting", StudioApp::is_exporting);
    assert!(!dir.join("gui-amg.obj").exists());
    assert!(
        harness
            .state()
            .log_lines()
            .any(|l| l.starts_with("Export failed") && l.contains("splats need a .glb"))
    );
}

/// Fly mode: W walks the eye forward through the scene, the view direction
/// kept; the camera never orbits the target while flying.
#[test]
fn fly_mode_walks_through_the_scene() {
    let mut harness = studio(None);
    wait_for_load(&mut harness);
    harness.get_by_label("Fly").click();
    harness.run();
    assert!(harness.state().viewport().camera.fly);
    let before = harness.state().viewport().core_view();
    harness.key_down(egui::Key::W);
    for _ in 0..10 {
        harness.step();
    }
    harness.key_up(egui::Key::W);
    harness.step();
    let after = harness.state().viewport().core_view();
    let moved = after.eye - before.eye;
    assert!(moved.length() > 0.0, "the eye moved");
    assert!(
        moved.normalize().dot(before.forward()) > 0.99,
        "straight ahead"
    );
    assert!(
        (after.forward() - before.forward()).length() < 1e-4,
        "still looking the same way"
    );
}

/// Compare: the original on the left and the LOD on the right, both drawn,
/// through one camera (orbiting the original turns the LOD too).
#[test]
fn side_by_side_compares_the_original_with_the_lod_through_one_camera() {
    use egui::PointerButton::Primary;
    let mut harness = studio(None);
    wait_for_load(&mut harness);
    let mut methods = *harness.state().methods();
    methods.method = Method::EdgeCollapse;
    methods.edge_collapse.mode = TargetMode::Ratio;
    methods.edge_collapse.ratio = 0.05;
    harness.state_mut().set_methods(methods);
    harness.step();
    wait_for_build(&mut harness);
    let lod = harness
        .state()
        .result()
        .expect("a LOD")
        .mesh()
        .triangles
        .len();
    assert!(lod < 3714 / 10, "{lod}");
    let single = harness.get_by_label("3D viewport").rect();
    harness.get_by_label("Side by side").click();
    harness.run();
    let (left, right) = (
        harness.get_by_label("original viewport").rect(),
        harness.get_by_label("3D viewport").rect(),
    );
    assert!(left.max.x <= right.min.x + 1.0, "original left of the LOD");
    assert!(right.width() < 0.6 * single.width());
    // The LOD side draws the result, the other the original: different images.
    assert_eq!(drawn_triangles(&harness), Some(lod));
    let (covered_left, _, left_look) =
        canvas_pixels(&mut harness, "original viewport", "studio_compare_left");
    let (covered_right, _, right_look) = viewport_pixels(&mut harness, "studio_compare_right");
    assert!(
        covered_left > 0.02 && covered_right > 0.02,
        "{covered_left} {covered_right}"
    );
    assert_ne!(left_look, right_look, "original and LOD differ");
    // Orbiting the original's side turns the LOD's camera with it.
    let (yaw0, pitch0, _, _) = camera(&harness);
    let center = left.center();
    drag(&harness, center, Primary);
    harness.run();
    let (yaw1, pitch1, _, _) = camera(&harness);
    assert!(
        yaw1 < yaw0 && pitch1 > pitch0,
        "{yaw0},{pitch0} -> {yaw1},{pitch1}"
    );
    // Back to one viewport.
    harness.get_by_label("Simplified").click();
    harness.run();
    assert!(harness.query_by_label("original viewport").is_none());
}

/// One interface in the studio (issue 25): for every method, dragging the
/// error threshold changes what is drawn, without a rebuild.
#[test]
fn the_threshold_moves_every_method_live() {
    let mut harness = studio(None);
    wait_for_load(&mut harness);
    for method in Method::ALL {
        let mut methods = *harness.state().methods();
        methods.method = method;
        methods.auto_rebuild = false;
        methods.edge_collapse.mode = TargetMode::Threshold;
        methods.voxel.pyramid = true;
        methods.voxel.resolution = 32;
        methods.amg.auto_level = true;
        methods.threshold.in_pixels = false;
        methods.threshold.percent = 0.05;
        harness.state_mut().set_methods(methods);
        harness.state_mut().build();
        wait_for_build(&mut harness);
        harness.run();
        let fine = cut_stats(&harness);
        harness
            .get_by_role_and_label(egui::Role::Slider, "error threshold")
            .set_value_accesskit(20.0);
        harness.run();
        assert!(!harness.state().is_building(), "{method:?}: no rebuild");
        let coarse = cut_stats(&harness);
        let drawn = |s: &lodstudio::live_cut::CutStats| {
            s.triangles + s.points + s.splats + s.layer_triangles
        };
        assert!(
            drawn(&coarse) < drawn(&fine),
            "{method:?}: {fine:?} -> {coarse:?}"
        );
        assert!(coarse.error_bound >= fine.error_bound, "{method:?}");
    }
}

/// Every control of the cut is live or visibly not applicable (issues 45,
/// 46): edge collapse's ratio is a unit of the cut section, whose pixels
/// unit hands the cut to the threshold; a pinned AMG level disables the
/// threshold, saying why, until the level follows it again.
#[test]
fn the_threshold_is_live_or_says_why_not() {
    use lodstudio::panels::threshold::not_applicable;
    use lodstudio_core::lod::{Controls, Knob};
    let mut harness = studio(None);
    wait_for_load(&mut harness);
    let threshold = |h: &Harness<'_, StudioApp>| {
        h.query_all_by_role_and_label(egui::Role::Slider, "error threshold")
            .next()
            .map(|n| !egui_kittest::kittest::NodeT::accesskit_node(&n).is_disabled())
    };
    let mut methods = *harness.state().methods();
    methods.method = Method::EdgeCollapse;
    methods.auto_rebuild = false;
    methods.edge_collapse.mode = TargetMode::Ratio;
    harness.state_mut().set_methods(methods);
    harness.state_mut().build();
    wait_for_build(&mut harness);
    harness.run();
    assert!(
        harness
            .query_all_by_role_and_label(egui::Role::Slider, "ratio")
            .next()
            .is_some(),
        "the ratio is the cut's unit"
    );
    assert_eq!(threshold(&harness), None);
    harness.get_by_label("pixels").click();
    harness.run();
    harness.run();
    assert_eq!(
        harness.state().methods().edge_collapse.mode,
        TargetMode::Threshold
    );
    assert_eq!(threshold(&harness), Some(true), "the threshold chooses");

    let pinned = Controls {
        knobs: &[Knob::AmgLevel],
        overridden_by: Some(Knob::AmgLevel),
        has_levels: true,
    };
    let mut methods = *harness.state().methods();
    methods.method = Method::Amg;
    methods.amg.auto_level = false;
    harness.state_mut().set_methods(methods);
    harness.state_mut().build();
    wait_for_build(&mut harness);
    harness.run();
    harness.run();
    assert_eq!(threshold(&harness), Some(false), "the pinned level chooses");
    assert!(has_label(&harness, not_applicable(&pinned)));
    methods.amg.auto_level = true;
    harness.state_mut().set_methods(methods);
    harness.run();
    harness.run();
    assert_eq!(threshold(&harness), Some(true));
    assert!(!harness.state().is_building(), "no rebuild");
}

/// The threshold slider spans its useful range logarithmically (issue 46):
/// its middle is the geometric mean of 0.1 and 64 px (2.5 px), not 32 px.
#[test]
fn the_threshold_slider_is_logarithmic() {
    let mut harness = studio(None);
    wait_for_load(&mut harness);
    let mut methods = *harness.state().methods();
    methods.method = Method::Hybrid;
    methods.auto_rebuild = false;
    methods.threshold.in_pixels = true;
    harness.state_mut().set_methods(methods);
    harness.state_mut().build();
    wait_for_build(&mut harness);
    harness.run();
    harness
        .get_by_role_and_label(egui::Role::Slider, "error threshold")
        .click();
    harness.run();
    let px = harness.state().methods().threshold.pixels;
    assert!(
        (1.5..4.5).contains(&px),
        "the middle of the slider: {px} px"
    );
}

/// The textured milk truck of the shared models.
fn shared_truck() -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/models/CesiumMilkTruck.glb"
    ))
}

/// How far render `b` is from render `a` where either shows the model: the
/// mean of each pixel's largest channel difference (of 255), and the share
/// of pixels off by more than 64.
fn difference(a: &[[u8; 4]], b: &[[u8; 4]]) -> (f32, f32) {
    let background = a[0];
    let (mut model, mut far, mut sum) = (0usize, 0usize, 0u64);
    for (p, q) in a.iter().zip(b) {
        if *p == background && *q == background {
            continue;
        }
        model += 1;
        let d = (0..3).map(|k| p[k].abs_diff(q[k]) as u64).max().unwrap();
        sum += d;
        far += usize::from(d > 64);
    }
    let n = model.max(1) as f32;
    (sum as f32 / n, far as f32 / n)
}

/// Issue 30's render test: the milk truck's base-colour texture is drawn by
/// the studio's own renderer, and its edge-collapse LOD0 (0.5 % of the
/// diagonal) looks like the original through the same camera: few pixels
/// differ by much, where scrambled UVs would move the logo and colours.
#[test]
fn the_textured_truck_and_its_lod_look_alike() {
    let truck = shared_truck();
    let mut harness = studio(Some(truck));
    wait_for_load(&mut harness);
    let mut methods = *harness.state().methods();
    methods.method = Method::EdgeCollapse;
    methods.auto_rebuild = false;
    harness.state_mut().set_methods(methods);
    harness.run();
    let original = viewport_image(&mut harness, "truck-original");
    let textured = colourful(&original);
    methods.edge_collapse.mode = TargetMode::Threshold;
    methods.threshold.in_pixels = false;
    methods.threshold.percent = 0.5;
    harness.state_mut().set_methods(methods);
    harness.state_mut().build();
    wait_for_build(&mut harness);
    assert!(harness.state().view().shows_lod());
    let triangles = harness
        .state()
        .result()
        .expect("a LOD")
        .mesh()
        .triangles
        .len();
    let lod = viewport_image(&mut harness, "truck-lod0");
    let (mean, far) = difference(&original, &lod);
    eprintln!(
        "truck: {textured:.3} colourful, LOD0 {triangles} triangles: mean difference {mean:.2}, {:.2} % of pixels off by > 64",
        100.0 * far
    );
    assert!(textured > 0.05, "the texture is drawn: {textured}");
    assert!(mean < 12.0 && far < 0.05, "mean {mean}, far {far}");
}

/// The wireframe overlay draws every edge of what is shown once, over the
/// original and over the cut, and changes the picture.
#[test]
fn the_wireframe_overlay_draws_every_edge_once() {
    let mut harness = studio(Some("builtin:torus".into()));
    wait_for_load(&mut harness);
    let edges = |mesh: &lodstudio_core::TriMesh| {
        let mut e: Vec<(u32, u32)> = mesh
            .triangles
            .iter()
            .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        e.sort_unstable();
        e.dedup();
        e.len()
    };
    let lines = |h: &Harness<'_, StudioApp>| h.state().viewport().scene().map(|s| s.line_count());
    let (_, _, plain) = viewport_pixels(&mut harness, "studio_torus_plain");
    assert_eq!(lines(&harness), Some(0));
    harness.get_by_label("Wireframe").click();
    harness.run();
    let torus = match &harness.state().loaded().unwrap().model {
        lodstudio_core::Model::Mesh(m) => m.clone(),
        _ => panic!("the torus is a mesh"),
    };
    assert_eq!(lines(&harness), Some(edges(&torus)));
    let (_, _, wired) = viewport_pixels(&mut harness, "studio_torus_wire");
    assert_ne!(plain, wired, "the edges are drawn");
    // Over the cut: the edges of the cut's mesh.
    let mut methods = *harness.state().methods();
    methods.method = Method::EdgeCollapse;
    harness.state_mut().set_methods(methods);
    harness.state_mut().build();
    wait_for_build(&mut harness);
    let cut = harness.state().result().unwrap().mesh().clone();
    assert!(cut.triangles.len() < torus.triangles.len());
    assert_eq!(lines(&harness), Some(edges(&cut)));
}

/// Issue 30, as a client sees the files: the truck's LOD chain exported by
/// `lodstudio export`, each LOD read back from its GLB through the ordinary
/// reader (a client without MSFT_lod draws node 0) and drawn by the studio's
/// renderer through the original's camera, looks like the original: few
/// pixels far off (LOD1 and LOD2 are both the truck's floor, 1,242 triangles).
#[test]
fn the_exported_truck_lods_look_like_the_original() {
    let truck = shared_truck();
    let mut harness = studio(Some(truck.clone()));
    wait_for_load(&mut harness);
    let camera = harness.state().viewport().camera;
    let original = viewport_image(&mut harness, "truck-file-original");
    let tmp = tempfile::tempdir().unwrap();
    for (l, lod) in ["0.5%", "2%", "8%"].iter().enumerate() {
        let out = tmp.path().join(format!("truck-lod{l}.glb"));
        let status = std::process::Command::new(env!("CARGO_BIN_EXE_lodstudio"))
            .args([
                "export",
                truck.to_str().unwrap(),
                "--method",
                "simplify",
                "--lods",
                lod,
                "-o",
            ])
            .arg(&out)
            .arg("--force")
            .output()
            .expect("run lodstudio export");
        assert!(
            status.status.success(),
            "{}",
            String::from_utf8_lossy(&status.stderr)
        );
        harness.state_mut().open(out.clone());
        wait_for_load(&mut harness);
        harness.state_mut().viewport_mut().camera = camera;
        harness.run();
        let image = viewport_image(&mut harness, &format!("truck-file-lod{l}"));
        let (mean, far) = difference(&original, &image);
        eprintln!(
            "truck LOD{l} ({lod}) from its file: mean difference {mean:.2}, {:.2} % off by > 64",
            100.0 * far
        );
        assert!(colourful(&image) > 0.05, "LOD{l}: the texture is drawn");
        // Simplification moves shading (normals) and silhouettes a little;
        // UVs from across a seam would move the logo (a fifth of the body).
        let (most_mean, most_far) = [(10.0, 0.025), (16.0, 0.07), (16.0, 0.07)][l];
        assert!(
            mean < most_mean && far < most_far,
            "LOD{l}: mean {mean}, far {far}"
        );
    }
}
