//! Issue 8's performance figures, measured on the studio itself: headless
//! (egui_kittest on wgpu, lavapipe on a machine without a GPU) at 1280×800,
//! with a real model loaded, for each method:
//!
//! - the frame time (UI step, and step + render) while the build runs on its
//!   worker — the UI must keep its frame rate (goal: under 50 ms);
//! - the live cut's time and the frame time while the error threshold is
//!   dragged across its range, and while the camera orbits (view-dependent
//!   cuts re-select every frame) — the cut must follow within one frame.
//!
//! - issue 26: the same while an LOD chain builds (edge-collapse rows and an
//!   AMG impostor), and while the switch preview moves the camera from near
//!   to far one step a frame (goal: the studio's own CPU time, the UI step,
//!   at most 5 ms).
//!
//! - issue 46: with `-- --ratio [MODEL…]`, the same build through the
//!   studio's frame loop and through the core call in one run (edge
//!   collapse, hybrid, the default chain and the chain with one row edited),
//!   and whether an idle studio asks for frames.
//!
//! - issue 49: with `-- --asset [MODEL…]`, a glTF asset shown as its nodes
//!   place it: the UI step while an animation plays (a new pose each frame)
//!   or, for an asset without one, while the selected node changes each
//!   frame (goal: at most 5 ms of the studio's own CPU).
//!
//! Run with `cargo bench -p lodstudio --bench studio` (horse, engine, dragon)
//! or name models: `cargo bench -p lodstudio --bench studio -- horse.ply`.
//! Prints a Markdown table.

#[path = "../tests/common/mod.rs"]
mod common;

use std::path::PathBuf;
use std::time::Instant;

use common::{save_ppm, studio, wait_while};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use lodstudio::settings::Method;
use lodstudio::studio::StudioApp;

/// Milliseconds of one UI step, and of the step plus rendering the frame.
fn frame(h: &mut Harness<'_, StudioApp>) -> (f64, f64) {
    let t = Instant::now();
    h.step();
    let step = t.elapsed().as_secs_f64() * 1e3;
    h.render().expect("render the studio");
    (step, t.elapsed().as_secs_f64() * 1e3)
}

/// Median and maximum.
fn spread(v: &[f64]) -> String {
    if v.is_empty() {
        return "-".into();
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    format!("{:.1} / {:.1}", s[s.len() / 2], s[s.len() - 1])
}

fn cut_ms(h: &Harness<'_, StudioApp>) -> Option<(f64, u64)> {
    let live = &h.state().result()?.live;
    Some((live.stats.cut_ms as f64, live.stats.cuts))
}

/// One frame after a change: its time, and the cut's when it re-selected.
fn cut_frame(h: &mut Harness<'_, StudioApp>, cuts: &mut Vec<f64>, frames: &mut Vec<f64>) {
    let before = cut_ms(h).map(|c| c.1);
    frames.push(frame(h).1);
    if let Some((ms, n)) = cut_ms(h)
        && Some(n) != before
    {
        cuts.push(ms);
    }
}

/// Runs one method on the loaded model and prints its row.
fn method_row(h: &mut Harness<'_, StudioApp>, model: &str, method: Method) {
    let mut m = *h.state().methods();
    m.method = method;
    m.auto_rebuild = false;
    m.threshold.in_pixels = true;
    m.threshold.pixels = 2.0;
    m.voxel.resolution = 64;
    m.voxel.pyramid = true;
    m.amg.auto_level = true;
    h.state_mut().set_methods(m);
    h.step();
    let start = Instant::now();
    h.state_mut().build();
    let (mut steps, mut frames) = (Vec::new(), Vec::new());
    while h.state().is_building() {
        let (s, f) = frame(h);
        steps.push(s);
        frames.push(f);
    }
    let build_s = start.elapsed().as_secs_f64();
    h.run();
    let (mut drag_cut, mut drag_frame, mut orbit_cut, mut orbit_frame) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    if h.state().result().is_some_and(|b| b.live.has_levels()) {
        // Drag the threshold over its range, one value a frame.
        for i in 0..24 {
            let px = 0.5 * 2f64.powf(i as f64 * 7.0 / 23.0);
            h.get_by_role_and_label(egui::Role::Slider, "error threshold")
                .set_value_accesskit(px);
            cut_frame(h, &mut drag_cut, &mut drag_frame);
        }
        // Orbit at a mid threshold: view-dependent cuts re-select.
        h.get_by_role_and_label(egui::Role::Slider, "error threshold")
            .set_value_accesskit(4.0);
        h.run();
        for _ in 0..24 {
            h.state_mut().viewport_mut().camera.yaw += 0.05;
            cut_frame(h, &mut orbit_cut, &mut orbit_frame);
        }
    }
    let image = h.render().expect("render the studio");
    let shot = save_ppm(
        image.width(),
        image.height(),
        image.as_raw(),
        &format!("bench-{model}-{}", method.name()).replace([' ', '(', ')', '+'], ""),
    );
    eprintln!("{model}, {}: {}", method.name(), shot.display());
    println!(
        "| {model} | {} | {build_s:.1} | {} | {} | {} | {} | {} | {} | {} |",
        method.name(),
        frames.len(),
        spread(&steps),
        spread(&frames),
        spread(&drag_cut),
        spread(&drag_frame),
        spread(&orbit_cut),
        spread(&orbit_frame),
    );
}

/// Issue 46: the same build through the studio's frame loop and through the
/// core call, in one run. The loop draws a frame whenever the studio asks for
/// one (`StudioApp::poll_interval`: 4 Hz, then 1 Hz past 2 s) and renders it
/// through lavapipe, as a window does. Then, idle, how many of 10 frames
/// 100 ms apart the studio asked to repaint.
fn ratio_row(h: &mut Harness<'_, StudioApp>, model: &str, method: Method) {
    let mut m = *h.state().methods();
    m.method = method;
    m.auto_rebuild = false;
    h.state_mut().set_methods(m);
    h.run();
    let params = h.state().methods().params(None);
    let loaded = h.state().loaded().expect("a model").model.clone();
    let t = Instant::now();
    lodstudio_core::lod::build(&params, &loaded, &lodstudio_core::Progress::new())
        .expect("the core builds");
    let core_s = t.elapsed().as_secs_f64();
    h.state_mut().build();
    frame_loop_while(h, StudioApp::is_building);
    let studio_s = f64::from(h.state().result().expect("a result").seconds);
    h.run();
    let mut asked = 0;
    for _ in 0..10 {
        std::thread::sleep(std::time::Duration::from_millis(100));
        h.step();
        asked += usize::from(h.ctx.has_requested_repaint());
    }
    println!(
        "| {model} | {} | {core_s:.2} | {studio_s:.2} | {:.2} | {asked} of 10 |",
        method.name(),
        studio_s / core_s
    );
}

/// Steps and renders the studio as its frame loop would (a frame when it
/// asks for one) while `busy`.
fn frame_loop_while(h: &mut Harness<'_, StudioApp>, busy: fn(&StudioApp) -> bool) {
    h.step();
    while busy(h.state()) {
        let wait = h.state().poll_interval().unwrap_or_default();
        std::thread::sleep(wait);
        h.step();
        h.render().expect("render the studio");
    }
}

/// Builds the chain through the studio's frame loop; the build's seconds
/// from its log line.
fn studio_chain_build(h: &mut Harness<'_, StudioApp>) -> f64 {
    let ctx = h.ctx.clone();
    h.state_mut().build_chain(&ctx);
    frame_loop_while(h, StudioApp::is_building_chain);
    let line = h
        .state()
        .log_lines()
        .filter(|l| l.contains("Built a chain of"))
        .last()
        .expect("the chain's log line")
        .to_string();
    let seconds = line.split(" in ").nth(1).and_then(|t| t.split(' ').next());
    seconds
        .and_then(|s| s.parse().ok())
        .expect("seconds in the log line")
}

/// The default chain through `recipe::build_chain` and through the
/// studio's frame loop (its work kept beside a session, as in use), in one
/// run; then one edge-collapse row edited and the chain built again from
/// what was kept.
fn chain_ratio_row(h: &mut Harness<'_, StudioApp>, model: &str, session: &std::path::Path) {
    use lodstudio_core::recipe::{Recipe, build_chain, parse_lods};
    h.state_mut()
        .resume(lodstudio::session::Autosave::in_dir(session), false);
    let lods = "source,simplify:0.5%,simplify:2%,amg:15%";
    let mut recipe = Recipe::new(parse_lods(lods, None).expect("rows"));
    h.state_mut().set_chain_recipe(recipe.clone());
    let loaded = h.state().loaded().expect("a model").model.clone();
    let t = Instant::now();
    build_chain(&loaded, &recipe, &lodstudio_core::Progress::new()).expect("the core builds");
    let core_s = t.elapsed().as_secs_f64();
    let studio_s = studio_chain_build(h);
    recipe.rows[2] = parse_lods("simplify:4%", None).expect("a row").remove(0);
    h.state_mut().set_chain_recipe(recipe);
    let edited_s = studio_chain_build(h);
    let chain = &h.state().built_chain().expect("a chain").chain;
    let kept = chain.lods.iter().filter(|l| l.reused).count();
    println!(
        "| {model} | chain `{lods}` | {core_s:.2} | {studio_s:.2} | {:.2} | row 2 edited to `simplify:4%`: {edited_s:.2} s, {kept} of {} LODs kept |",
        studio_s / core_s,
        chain.lods.len()
    );
}

/// Builds an LOD chain on the loaded model and runs the switch preview
/// through it; prints the chain table's row.
fn chain_row(h: &mut Harness<'_, StudioApp>, model: &str) {
    let rows =
        lodstudio_core::recipe::parse_lods("simplify:0.5%,simplify:2%,simplify:8%,amg:15%", None)
            .expect("rows");
    h.state_mut()
        .set_chain_recipe(lodstudio_core::recipe::Recipe::new(rows));
    h.step();
    let ctx = h.ctx.clone();
    let start = Instant::now();
    h.state_mut().build_chain(&ctx);
    let (mut steps, mut frames) = (Vec::new(), Vec::new());
    while h.state().is_building_chain() {
        let (s, f) = frame(h);
        steps.push(s);
        frames.push(f);
    }
    let build_s = start.elapsed().as_secs_f64();
    h.run();
    let lods = h.state().built_chain().map_or(0, |b| b.chain.lods.len());
    // Near to far in 48 steps, one a frame, as the dolly moves.
    let (mut preview_steps, mut preview_frames) = (Vec::new(), Vec::new());
    let near = lodstudio::render::camera::distance_at_coverage(1.0);
    let mut seen = std::collections::BTreeSet::new();
    for i in 0..48 {
        let d = near * 1000f32.powf(i as f32 / 47.0);
        h.state_mut().set_switch_distance(Some(d));
        let (s, f) = frame(h);
        preview_steps.push(s);
        preview_frames.push(f);
        seen.extend(h.state().switch_lod().map(|l| l.0));
    }
    h.state_mut().set_switch_distance(None);
    println!(
        "| {model} | {lods} | {build_s:.1} | {} | {} | {} | {} | {} | {} |",
        steps.len(),
        spread(&steps),
        spread(&frames),
        seen.len(),
        spread(&preview_steps),
        spread(&preview_frames),
    );
}

/// An asset shown and moving for 60 frames: playing its first animation,
/// or selecting its outliner's rows one a frame.
fn asset_row(h: &mut Harness<'_, StudioApp>, model: &str) {
    let (mut steps, mut frames) = (Vec::new(), Vec::new());
    let animated = {
        let asset = h.state_mut().asset_mut().expect("a glTF scene");
        asset.show = true;
        asset.playing = true;
        asset.is_moving()
    };
    h.step();
    let rows = h.state().asset().map_or(0, |a| a.outline_labels().count());
    for i in 0..60 {
        if !animated {
            let asset = h.state_mut().asset_mut().expect("a glTF scene");
            asset.selected = Some(i % rows.max(1));
            asset.redraw();
        }
        let (s, f) = frame(h);
        steps.push(s);
        frames.push(f);
    }
    let asset = h.state().asset().expect("a glTF scene");
    println!(
        "| {model} | {} | {} | {} | {} | {} |",
        asset.triangles(0).1,
        if animated { "playing" } else { "selection" },
        steps.len(),
        spread(&steps),
        spread(&frames),
    );
}

/// "Build for every mesh" through the studio's frame loop against
/// `scene::build` on the same scene and rows, in one run (goal: ≤ 1.2×).
fn asset_build_row(h: &mut Harness<'_, StudioApp>, model: &std::path::Path) {
    let recipe = lodstudio_core::recipe::Recipe::new(
        lodstudio_core::recipe::parse_lods("source,simplify:0.5%,simplify:2%", None).expect("rows"),
    );
    let bytes = std::fs::read(model).expect("the asset");
    let scene = lodstudio_core::io::scene::read(&bytes, model.parent()).expect("a scene");
    let mut repair = lodstudio_core::io::LoadOptions::default().repair;
    repair.weld = recipe.weld();
    let start = Instant::now();
    let chains = lodstudio_core::scene::build(
        &scene,
        &recipe,
        &[],
        &repair,
        &lodstudio_core::Progress::new(),
    )
    .expect("chains");
    let core_s = start.elapsed().as_secs_f64();
    let ctx = h.ctx.clone();
    let start = Instant::now();
    h.state_mut()
        .asset_mut()
        .expect("a glTF scene")
        .start_build(&recipe, &ctx);
    frame_loop_while(h, |s| s.asset().is_some_and(|a| a.is_building()));
    // The frame loop above sleeps whole poll intervals (1 s on long
    // builds), where eframe wakes at once: the worker's own time is the
    // build's, the loop's the bound a user could wait.
    let looped_s = start.elapsed().as_secs_f64();
    let studio_s = h
        .state()
        .asset()
        .and_then(|a| a.last_build_seconds)
        .unwrap_or(looped_s);
    let (once, _) = h.state().asset().expect("a glTF scene").triangles(2);
    let core_once: usize = chains
        .chains
        .iter()
        .map(|c| c.lods[2.min(c.lods.len() - 1)].set.mesh.triangles.len())
        .sum();
    let name = model.file_name().unwrap_or_default().to_string_lossy();
    println!(
        "| {name} | {core_once} / {once} | {core_s:.2} | {studio_s:.2} ({looped_s:.2}) | {:.2}× |",
        studio_s / core_s
    );
}

fn main() {
    let shared = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/models");
    if std::env::args().any(|a| a == "--asset") {
        // `cargo bench -p lodstudio --bench studio -- --asset [MODEL...]`
        let assets = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets");
        let mut models: Vec<PathBuf> = std::env::args()
            .skip(1)
            .filter(|a| !a.starts_with('-'))
            .map(|m| shared.join(m))
            .collect();
        if models.is_empty() {
            models = vec![
                assets.join("two-bone-cylinder.glb"),
                shared.join("CesiumMilkTruck.glb"),
                shared.join("2CylinderEngine.gltf"),
            ];
        }
        println!(
            "| asset | triangles drawn | moving by | frames | UI step ms (median / max) | frame ms |"
        );
        println!("|---|---|---|---|---|---|");
        for model in &models {
            let mut h = studio(Some(model.clone()));
            wait_while(&mut h, "loading", StudioApp::is_loading);
            let name = model.file_name().unwrap_or_default().to_string_lossy();
            asset_row(&mut h, &name);
        }
        println!(
            "\n| asset | LOD2 triangles: core / studio | core `scene::build` s | Build for every mesh: worker s (frame loop s) | ratio |"
        );
        println!("|---|---|---|---|---|");
        for model in &models {
            let mut h = studio(Some(model.clone()));
            wait_while(&mut h, "loading", StudioApp::is_loading);
            asset_build_row(&mut h, model);
        }
        return;
    }
    let ratio = std::env::args().any(|a| a == "--ratio");
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let defaults: &[&str] = match ratio {
        true => &["horse.ply"],
        false => &["horse.ply", "2CylinderEngine.gltf", "dragon_vrip.ply.gz"],
    };
    let models: Vec<String> = if args.is_empty() {
        defaults.iter().map(|m| m.to_string()).collect()
    } else {
        args
    };
    if ratio {
        // `cargo bench -p lodstudio --bench studio -- --ratio [MODEL...]`
        println!(
            "| model | method | core `lod::build` s | in the studio's frame loop s | ratio | idle frames asked |"
        );
        println!("|---|---|---|---|---|---|");
        for model in models {
            let mut h = studio(Some(shared.join(&model)));
            wait_while(&mut h, "loading", StudioApp::is_loading);
            for method in [Method::EdgeCollapse, Method::Hybrid] {
                ratio_row(&mut h, &model, method);
            }
            let session = tempfile::tempdir().expect("a session folder");
            chain_ratio_row(&mut h, &model, session.path());
        }
        return;
    }
    println!(
        "| model | method | build s | frames during build | UI step ms (median / max) | frame ms | threshold drag: cut ms | frame ms | orbit: cut ms | frame ms |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut chains = Vec::new();
    for model in models {
        let mut h = studio(Some(shared.join(&model)));
        wait_while(&mut h, "loading", StudioApp::is_loading);
        // The dragon: the view-dependent merge tree (the other methods' builds
        // on 871k triangles are benchmarked in core's benches).
        let methods: &[Method] = if model.starts_with("dragon") {
            &[Method::MergeTree]
        } else {
            &[
                Method::EdgeCollapse,
                Method::Hybrid,
                Method::MergeTree,
                Method::Voxel,
                Method::Amg,
            ]
        };
        for &method in methods {
            method_row(&mut h, &model, method);
        }
        chains.push(model);
    }
    println!(
        "\n| model | chain LODs | build s | frames during build | UI step ms (median / max) | frame ms | switch preview: LODs shown | UI step ms | frame ms |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for model in chains {
        let mut h = studio(Some(shared.join(&model)));
        wait_while(&mut h, "loading", StudioApp::is_loading);
        chain_row(&mut h, &model);
    }
}
