//! The chain's state transitions without a window: builds on the built-in
//! torus run on real workers, polled as the studio polls them.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use lodstudio_core::Progress;
use lodstudio_core::io::LoadOptions;
use lodstudio_core::recipe::{Recipe, build_chain, parse_lods};

use super::*;
use crate::export::Saved;
use crate::live_cut::CutStyle;
use crate::render::camera::distance_at_coverage;
use crate::studio::View;
use crate::studio::loading::absolute;

/// Three rows whose cuts differ on the torus: three LODs.
const ROWS: &str = "simplify:1%,simplify:4%,simplify:16%";

fn torus() -> Source {
    let path = PathBuf::from("builtin:torus");
    let loaded = lodstudio_core::open::open(&path, &LoadOptions::default(), &Progress::new())
        .expect("the torus");
    Source {
        loaded: Arc::new(loaded),
        path,
    }
}

fn recipe(lods: &str) -> Recipe {
    Recipe::new(parse_lods(lods, None).expect("rows"))
}

/// Polls as the studio does until the build ends; what it logged.
fn finish(state: &mut ChainState) -> Vec<ChainEvent> {
    let start = Instant::now();
    let mut events = Vec::new();
    while state.is_building() {
        assert!(start.elapsed() < Duration::from_secs(120), "still building");
        std::thread::sleep(Duration::from_millis(5));
        events.extend(state.poll());
    }
    events
}

/// Builds the rows `lods` on `source`; what the build logged.
fn build(state: &mut ChainState, lods: &str, source: Source) -> Vec<ChainEvent> {
    state.set_recipe(recipe(lods));
    assert!(
        state
            .start_build(Some(source), &egui::Context::default())
            .is_none()
    );
    assert!(state.is_building());
    finish(state)
}

/// A state with the chain of [`ROWS`] on the torus built.
fn built() -> ChainState {
    let mut state = ChainState::default();
    let events = build(&mut state, ROWS, torus());
    assert!(
        matches!(events[..], [ChainEvent::Built { lods: 3, .. }]),
        "{events:?}"
    );
    state
}

fn chain_of(state: &ChainState) -> Arc<lodstudio_core::recipe::Chain> {
    Arc::clone(&state.built().expect("a chain").chain)
}

/// The worker builds what the core builds for the rows, one LOD per row
/// here, each row's table cells naming its LOD, and nothing noted.
#[test]
fn a_build_polled_to_its_end_is_the_chain_of_its_rows() {
    let state = built();
    let built = state.built().unwrap();
    assert_eq!(built.recipe(), &recipe(ROWS));
    let expected = build_chain(&torus().loaded.model, &recipe(ROWS), &Progress::new()).unwrap();
    let triangles = |c: &lodstudio_core::recipe::Chain| -> Vec<usize> {
        c.lods.iter().map(|l| l.set.mesh.triangles.len()).collect()
    };
    assert_eq!(triangles(&built.chain), triangles(&expected));
    assert_eq!(built.chain.coverages, expected.coverages);
    assert!(
        triangles(&built.chain).windows(2).all(|w| w[1] < w[0]),
        "{:?}",
        triangles(&built.chain)
    );
    let lods: Vec<usize> = built.figures.iter().map(|f| f.lod).collect();
    assert_eq!(lods, [0, 1, 2]);
    assert_eq!(built.scenes.len(), 3);
    assert!(state.fresh().is_some() && state.note.is_none());
}

/// A row whose triangle budget the collapse cannot reach (the torus keeps
/// its handle) is flagged in its table cell with why, and the log line
/// counts it; met rows are not flagged.
#[test]
fn a_row_short_of_its_budget_says_why() {
    let mut state = ChainState::default();
    let events = build(&mut state, "simplify:0.25,simplify:0.001", torus());
    assert!(
        matches!(events[..], [ChainEvent::Built { short: 1, .. }]),
        "{events:?}"
    );
    assert!(
        events[0]
            .to_string()
            .contains("1 short of the triangle budget")
    );
    let figures = &state.built().unwrap().figures;
    assert!(figures[0].unmet.is_none());
    let why = figures[1].unmet.as_deref().expect("the far row is flagged");
    assert!(why.contains("topology kept"), "{why}");
}

/// Rows that do not earn their place on the torus: 0.05 % never shown
/// (0.08 % is within a pixel too where the torus fills the viewport) and
/// 0.001 past the topology floor, where 0.002 already stopped.
const FLAGGED: &str =
    "source,simplify:0.05%,simplify:0.08%,simplify:0.25,simplify:0.002,simplify:0.001";

/// Flagged rows are named in the table with why and counted in the log
/// line; Auto chain builds its rule's rows less the rows the chain flags,
/// and the rows kept replace the rule's.
#[test]
fn flagged_rows_are_named_and_auto_chain_leaves_them_out() {
    let mut state = ChainState::default();
    let events = build(&mut state, FLAGGED, torus());
    assert!(
        matches!(
            events[..],
            [ChainEvent::Built {
                flagged: 2,
                left_out: 0,
                ..
            }]
        ),
        "{events:?}"
    );
    assert!(
        events[0].to_string().contains("2 rows flagged"),
        "{}",
        events[0]
    );
    let figures = &state.built().unwrap().figures;
    let words: Vec<Option<&str>> = figures
        .iter()
        .map(|f| f.flags.as_ref().map(|(w, _)| w.as_str()))
        .collect();
    assert_eq!(
        words,
        [
            None,
            Some("never shown"),
            None,
            None,
            None,
            Some("same LOD")
        ]
    );
    let (_, why) = figures[5].flags.as_ref().unwrap();
    assert!(why.contains("as row 4 (simplify:0.002)"), "{why}");

    // Halving from 1 % of the torus' 4,096 triangles: 41, 20, 10, 5; the
    // collapse stops at its floor past 41.
    state.settings.auto = crate::settings::chain::AutoChain {
        first: 0.01,
        rows: 5,
        ..Default::default()
    };
    assert!(
        state
            .start_auto(Some(torus()), &egui::Context::default())
            .is_none()
    );
    let events = finish(&mut state);
    let [
        ChainEvent::Built {
            flagged: 0,
            left_out,
            ..
        },
    ] = events[..]
    else {
        panic!("{events:?}")
    };
    assert!(left_out >= 2, "{events:?}");
    assert!(events[0].to_string().contains("Auto chain left out"));
    let built = state.built().unwrap();
    assert_eq!(
        built.recipe(),
        &state.settings.recipe,
        "the rows kept replace the rule's"
    );
    assert_eq!(state.settings.recipe.rows.len(), 5 - left_out);
    assert!(state.fresh().is_some());
    assert!(built.figures.iter().all(|f| f.flags.is_none()));
}

#[test]
fn a_build_without_a_model_notes_why_and_starts_nothing() {
    let mut state = ChainState::default();
    assert!(state.start_build(None, &egui::Context::default()).is_none());
    assert!(!state.is_building());
    assert_eq!(state.note.as_deref(), Some("Open a model first"));
}

/// A new model's panel shows nothing of the last model's chain, not even
/// a build of it that was still running.
#[test]
fn forgetting_drops_the_chain_its_preview_and_a_running_build() {
    let mut state = built();
    let (mut camera, mut view) = (Camera::default(), View::Original);
    state.set_switch_distance(Some(distance_at_coverage(1.0)), &mut camera, &mut view);
    assert!(state.switch_lod(camera.distance).is_some());
    state.forget();
    assert!(state.built().is_none());
    assert!(state.switch_lod(camera.distance).is_none());
    assert!(state.scene(camera.distance, CutStyle::default()).is_none());

    let ctx = egui::Context::default();
    assert!(state.start_build(Some(torus()), &ctx).is_none());
    state.forget();
    assert!(!state.is_building());
    std::thread::sleep(Duration::from_millis(300));
    assert!(state.poll().is_empty());
    assert!(state.built().is_none());
}

/// Editing the rows keeps the last chain (the preview still draws it) but
/// it is no longer theirs: a clicked row's LOD is no longer shown, and its
/// export is refused until it is built again.
#[test]
fn changed_rows_leave_the_chain_built_but_stale() {
    let mut state = built();
    let before = chain_of(&state);
    let mut view = View::Original;
    state.select_row(1, &mut view);
    assert_eq!(view, View::Simplified);
    let shown = state
        .scene(0.0, CutStyle::default())
        .expect("the row's LOD");
    assert!(Arc::ptr_eq(&shown, &state.built().unwrap().scenes[1]));
    state.set_recipe(recipe("simplify:2%"));
    assert!(
        state.scene(0.0, CutStyle::default()).is_none(),
        "row 1 is another row now"
    );
    assert!(Arc::ptr_eq(&chain_of(&state), &before));
    assert!(state.fresh().is_none());
    let refused = state.export(Target::File("unused.glb".into()));
    assert!(matches!(refused, Err(ChainError::Stale)));
    assert_eq!(
        ChainEvent::Failed(refused.err().unwrap()).to_string(),
        "Build the chain first (its rows changed since the last build)"
    );
    let events = build(&mut state, "simplify:2%", torus());
    assert!(matches!(events[..], [ChainEvent::Built { lods: 1, .. }]));
    assert!(state.fresh().is_some());
    assert!(state.export(Target::File("unused.glb".into())).is_ok());
}

#[test]
fn a_cancelled_build_keeps_the_previous_chain() {
    let mut state = built();
    let before = chain_of(&state);
    state.set_recipe(recipe("simplify:2%"));
    assert!(
        state
            .start_build(Some(torus()), &egui::Context::default())
            .is_none()
    );
    assert!(matches!(state.cancel_build(), ChainEvent::BuildStopped));
    assert!(!state.is_building());
    for _ in 0..30 {
        assert!(state.poll().is_empty(), "a cancelled build never lands");
        std::thread::sleep(Duration::from_millis(10));
    }
    assert!(Arc::ptr_eq(&chain_of(&state), &before));
}

/// A recipe that welds otherwise reopens the model from its file; when that
/// fails the reason is logged and noted, and the last chain stays.
#[test]
fn a_failed_build_keeps_the_previous_chain_and_notes_why() {
    let mut state = built();
    let before = chain_of(&state);
    let mut keep_seams = recipe(ROWS);
    keep_seams.keep_seams = true;
    state.set_recipe(keep_seams);
    let gone = Source {
        path: "/nonexistent/torus.obj".into(),
        ..torus()
    };
    assert!(
        state
            .start_build(Some(gone), &egui::Context::default())
            .is_none()
    );
    let events = finish(&mut state);
    let [ChainEvent::NotBuilt(ChainError::Reload(e))] = &events[..] else {
        panic!("{events:?}")
    };
    let note = state.note.clone().expect("noted");
    assert!(note.contains("/nonexistent/torus.obj"), "{note}");
    assert_eq!(note, e.to_string());
    assert_eq!(events[0].to_string(), format!("Chain not built: {note}"));
    assert!(Arc::ptr_eq(&chain_of(&state), &before));
}

/// At a distance inside LOD k's coverage range (between its switch in and
/// its switch out) the preview draws LOD k; beyond the last switch, the
/// coarsest.
#[test]
fn the_switch_distance_picks_the_lod_whose_coverage_range_holds_it() {
    let mut state = built();
    let chain = chain_of(&state);
    let (mut camera, mut view) = (Camera::default(), View::Original);
    for k in 0..chain.lods.len() {
        let c = (chain.coverage_in(k) * chain.coverages[k]).sqrt();
        let d = distance_at_coverage(c);
        state.set_switch_distance(Some(d), &mut camera, &mut view);
        assert_eq!(view, View::Simplified, "the preview shows LODs");
        assert!((camera.distance - d * chain.radius()).abs() <= 1e-4 * camera.distance);
        let (shown, name) = state.switch_lod(camera.distance).expect("a preview");
        assert_eq!(shown, k, "coverage {c} in {:?}", chain.coverages);
        assert!(name.starts_with(&format!("LOD{k} simplify:")), "{name}");
        let scene = (state.scene(camera.distance, CutStyle::default())).expect("a scene");
        assert!(Arc::ptr_eq(&scene, &state.built().unwrap().scenes[k]));
        // The wireframe draws every edge of the LOD shown once, over it.
        let wire = CutStyle {
            wireframe: true,
            ..CutStyle::default()
        };
        let wire = state.scene(camera.distance, wire).expect("a scene");
        let lod = &chain.lods[k].set.mesh;
        let mut edges: Vec<(u32, u32)> = lod
            .triangles
            .iter()
            .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        assert_eq!(
            wire.line_count(),
            scene.line_count() + edges.len(),
            "LOD{k}"
        );
        assert_eq!(wire.triangle_count(), scene.triangle_count());
    }
    let beyond = distance_at_coverage(0.5 * chain.coverages[2]);
    state.set_switch_distance(Some(beyond), &mut camera, &mut view);
    assert_eq!(state.switch_lod(camera.distance).unwrap().0, 2);
    state.set_switch_distance(None, &mut camera, &mut view);
    assert!(state.switch_lod(camera.distance).is_none());
    assert!(state.scene(camera.distance, CutStyle::default()).is_none());
}

/// The dolly takes the camera from near to far through every LOD in order,
/// then stops and leaves the camera alone; choosing a distance stops it.
#[test]
fn the_dolly_runs_through_every_lod_and_stops() {
    let mut state = built();
    let chain = chain_of(&state);
    let (near, far) = dolly::range(&chain.coverages);
    let (mut camera, mut view) = (Camera::default(), View::Original);
    state.set_switch_distance(Some(near), &mut camera, &mut view);
    state.start_dolly(10.0);
    let mut shown = Vec::new();
    for step in 0..=60 {
        let running = state.step_dolly(10.0 + dolly::SECONDS * step as f64 / 60.0, &mut camera);
        assert_eq!(running, step < 60, "step {step}");
        let k = state.switch_lod(camera.distance).unwrap().0;
        if shown.last() != Some(&k) {
            shown.push(k);
        }
    }
    assert_eq!(shown, [0, 1, 2]);
    assert!((camera.distance - far * chain.radius()).abs() <= 1e-4 * camera.distance);
    camera.distance = 1.0;
    assert!(!state.step_dolly(100.0, &mut camera));
    assert_eq!(camera.distance, 1.0, "a finished dolly leaves the camera");

    state.start_dolly(0.0);
    state.set_switch_distance(Some(near), &mut camera, &mut view);
    assert!(
        !state.step_dolly(1.0, &mut camera),
        "a chosen distance stops it"
    );
}

/// A bad recipe file leaves the rows and the recent list as they were and
/// says which row and field; a good one replaces the rows and is remembered.
#[test]
fn a_recipe_that_does_not_open_leaves_the_rows_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad-recipe.json");
    std::fs::write(
        &bad,
        r#"{"format":"lodstudio-recipe","version":1,"rows":[{"method":"simplify","tolerance":"1%"},{"method":"voxel","tolerance":"2%","resolution":2}]}"#,
    )
    .unwrap();
    let mut state = ChainState::default();
    let kept = state.settings.clone();
    let event = state.open_recipe(&bad);
    let ChainEvent::RecipeNotOpened(ChainError::Recipe(message)) = &event else {
        panic!("{event:?}")
    };
    assert!(message.contains("rows[1].resolution"), "{message}");
    assert!(event.is_error());
    assert!(event.to_string().starts_with("Recipe not opened: "));
    assert_eq!(state.settings, kept);
    assert!(state.recent_recipes.is_empty());

    let good = dir.path().join("good-recipe.json");
    std::fs::write(&good, recipe("simplify:2%").to_json()).unwrap();
    assert!(matches!(
        state.open_recipe(&good),
        ChainEvent::RecipeOpened(_)
    ));
    assert_eq!(state.settings.recipe, recipe("simplify:2%"));
    assert_eq!(state.recent_recipes, [absolute(&good)]);
}

/// Saves to named files write the built chain's GLB and the rows' recipe;
/// a saved recipe goes first in the recent list, once.
#[test]
fn named_saves_write_the_chain_and_remember_the_recipe() {
    let dir = tempfile::tempdir().unwrap();
    let mut state = built();
    let out = dir.path().join("torus-chain.glb");
    let export = state.export(Target::File(out.clone())).unwrap();
    assert!(matches!(export(), Saved::Written { .. }));
    assert!(std::fs::read(&out).unwrap() == chain_of(&state).glb());

    let (first, second) = (dir.path().join("a.json"), dir.path().join("b.json"));
    for path in [&first, &second, &first] {
        let save = state.save_recipe(Target::File(path.clone()));
        assert!(matches!(save(), Saved::Written { .. }));
    }
    assert_eq!(std::fs::read(&first).unwrap(), recipe(ROWS).to_json());
    assert_eq!(state.recent_recipes, [absolute(&first), absolute(&second)]);
}

/// Rows of three groups: one collapse, one hybrid, one voxel hierarchy.
const GROUPS: &str = "simplify:1%,hybrid:2%,voxel:5%";

fn reused(state: &ChainState) -> Vec<bool> {
    let chain = chain_of(state);
    let mut by_row = vec![false; chain.recipe.rows.len()];
    for lod in &chain.lods {
        for &r in &lod.rows {
            by_row[r] = lod.reused;
        }
    }
    by_row
}

/// An edited row rebuilds its own group alone: the others' LODs are kept,
/// the table says so, and the chain is the one a fresh build makes.
#[test]
fn an_edited_row_rebuilds_alone() {
    let mut state = ChainState::default();
    build(&mut state, GROUPS, torus());
    assert_eq!(reused(&state), [false, false, false]);
    let events = build(&mut state, "simplify:2%,hybrid:2%,voxel:5%", torus());
    assert!(
        matches!(
            events[..],
            [ChainEvent::Built {
                lods: 3,
                kept: 2,
                ..
            }]
        ),
        "{events:?}"
    );
    assert_eq!(reused(&state), [false, true, true]);
    let cells: Vec<&str> = (state.built().unwrap().figures.iter())
        .map(|f| f.cells[6].as_str())
        .collect();
    assert_eq!(cells[1..], ["kept", "kept"]);
    let fresh = build_chain(
        &torus().loaded.model,
        &recipe("simplify:2%,hybrid:2%,voxel:5%"),
        &Progress::new(),
    )
    .unwrap();
    assert_eq!(chain_of(&state).glb(), fresh.glb());
}

/// The work kept beside the session reopens the last chain in a new studio
/// without building anything; rows edited since reopen nothing but rebuild
/// only their own group; a damaged file is no cache.
#[test]
fn kept_work_reopens_the_chain_after_a_restart() {
    let tmp = tempfile::tempdir().unwrap();
    let file = tmp.path().join(kept::FILE_NAME);
    let ctx = egui::Context::default();
    let mut first = ChainState::default();
    first.keep_in(Some(file.clone()));
    build(&mut first, GROUPS, torus());
    let built = chain_of(&first);

    let mut second = ChainState::default();
    second.keep_in(Some(file.clone()));
    second.set_recipe(recipe(GROUPS));
    assert!(second.reopen(torus(), &ctx).is_none());
    let events = finish(&mut second);
    assert!(
        matches!(
            events[..],
            [ChainEvent::Built {
                lods: 3,
                kept: 3,
                reopened: true,
                not_saved: None,
                ..
            }]
        ),
        "{events:?}"
    );
    assert_eq!(chain_of(&second).glb(), built.glb());

    let mut edited = ChainState::default();
    edited.keep_in(Some(file.clone()));
    edited.set_recipe(recipe("simplify:4%,hybrid:2%,voxel:5%"));
    assert!(edited.reopen(torus(), &ctx).is_none());
    assert!(
        finish(&mut edited).is_empty(),
        "another chain: nothing reopened"
    );
    assert!(edited.built().is_none());
    build(&mut edited, "simplify:4%,hybrid:2%,voxel:5%", torus());
    assert_eq!(reused(&edited), [false, true, true]);

    std::fs::write(&file, b"LODSTHRY damaged").unwrap();
    let mut damaged = ChainState::default();
    damaged.keep_in(Some(file));
    damaged.set_recipe(recipe(GROUPS));
    assert!(damaged.reopen(torus(), &ctx).is_none());
    assert!(finish(&mut damaged).is_empty());
    build(&mut damaged, GROUPS, torus());
    assert_eq!(reused(&damaged), [false, false, false]);
}

/// The view bar's colour modes and a click work on the chain LOD shown, as
/// on a live cut: by type colours a hybrid LOD's triangles and points, by
/// region an AMG LOD's domains; a style's scene is made once; the set a
/// click picks in is the LOD's own.
#[test]
fn colour_modes_and_picking_apply_to_the_chain_lod_shown() {
    let mut state = ChainState::default();
    build(&mut state, "hybrid:2%,amg:20%", torus());
    let chain = chain_of(&state);
    let mut view = View::Original;
    for (row, region) in [(0, None), (1, Some("AMG domain"))] {
        state.select_row(row, &mut view);
        let k = state.shown_lod(0.0).expect("the row's LOD");
        let set = state.shown_set(0.0).expect("its primitives");
        assert!(std::ptr::eq(set, &chain.lods[k].set));
        assert_eq!(set.regions(), region, "row {row}");
        let plain = state.scene(0.0, CutStyle::default()).unwrap();
        let style = match region {
            None => CutStyle {
                by_type: true,
                ..CutStyle::default()
            },
            Some(_) => CutStyle {
                regions: true,
                ..CutStyle::default()
            },
        };
        let styled = state.scene(0.0, style).unwrap();
        assert_ne!(
            format!("{plain:?}"),
            format!("{styled:?}"),
            "row {row} recoloured"
        );
        assert!(
            Arc::ptr_eq(&styled, &state.scene(0.0, style).unwrap()),
            "made once"
        );
        assert!(Arc::ptr_eq(
            &plain,
            &state.scene(0.0, CutStyle::default()).unwrap()
        ));
    }
}
