//! The LOD chain in the studio (issue 26), driven headlessly through
//! egui_kittest: a mixed chain built from its panel matches the core API row
//! for row, the switch preview names and draws the LOD for its distance, the
//! chain exports as the CLI writes it (byte for byte from the same recipe),
//! recipes round-trip, and the chain (its rows and what they built) survives
//! a restart.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

mod common;
#[path = "common/pixels.rs"]
mod pixels;

use common::{save_ppm, studio, wait_while};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use lodstudio::render::camera::distance_at_coverage;
use lodstudio::session::{Autosave, Session};
use lodstudio::studio::StudioApp;
use lodstudio_core::lod::Method;
use lodstudio_core::recipe::{Recipe, RowTolerance, build_chain, parse_lods};
use pixels::{colourful, viewport_image};

fn shared(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/models")
        .join(name)
}

/// The JSON chunk of a GLB.
fn glb_json(glb: &[u8]) -> serde_json::Value {
    assert_eq!(&glb[0..4], b"glTF");
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&glb[20..20 + len]).expect("glTF JSON chunk")
}

/// Clicks the first widget labelled `label`, scrolled into view first (the
/// chain panel scrolls under the viewport).
fn click(harness: &mut Harness<'_, StudioApp>, label: &str) {
    harness
        .get_all_by_label(label)
        .next()
        .expect(label)
        .scroll_to_me();
    harness.run();
    harness.get_all_by_label(label).next().expect(label).click();
}

fn built_chain(harness: &mut Harness<'_, StudioApp>) {
    click(harness, "Build chain");
    harness.step();
    assert!(harness.state().is_building_chain());
    wait_while(harness, "building the chain", StudioApp::is_building_chain);
}

/// Two edge-collapse LODs and an AMG impostor on the bones: the panel's
/// chain equals `build_chain` on the same model, the preview moves through
/// the LODs with the distance, and the export is the CLI's, byte for byte.
#[test]
fn a_mixed_chain_builds_previews_and_exports_as_the_cli_does() {
    let tmp = tempfile::tempdir().unwrap();
    let bones = shared("bones.off");
    let mut harness = studio(Some(bones.clone()));
    wait_while(&mut harness, "loading", StudioApp::is_loading);
    let recipe = Recipe::new(parse_lods("simplify:0.5%,simplify:2%,amg:15%", None).unwrap());
    harness.state_mut().set_chain_recipe(recipe.clone());
    built_chain(&mut harness);

    // Row for row what the core API builds.
    let loaded =
        lodstudio_core::io::load(&bones, &Default::default(), &Default::default()).unwrap();
    let expected = build_chain(&loaded.model, &recipe, &Default::default()).unwrap();
    let chain = harness
        .state()
        .built_chain()
        .expect("a chain")
        .chain
        .clone();
    assert_eq!(chain.lods.len(), 3);
    let methods: Vec<Method> = chain.lods.iter().map(|l| l.method).collect();
    assert_eq!(
        methods,
        [Method::EdgeCollapse, Method::EdgeCollapse, Method::Amg]
    );
    for (got, want) in chain.lods.iter().zip(&expected.lods) {
        assert_eq!(got.set.mesh.triangles.len(), want.set.mesh.triangles.len());
        assert_eq!(got.set.splats.len(), want.set.splats.len());
        assert_eq!(got.bound(), want.bound());
    }
    assert_eq!(chain.coverages, expected.coverages);
    assert!(chain.lods[0].bound() <= 0.005 * chain.diagonal);
    assert!(chain.lods[1].bound() <= 0.02 * chain.diagonal);
    assert!(!chain.lods[2].set.splats.is_empty());
    // The table names each row's LOD.
    harness.run();
    for label in ["0: LOD0", "1: LOD1", "2: LOD2"] {
        assert!(harness.query_by_label(label).is_some(), "{label}");
    }

    // The visual difference of every LOD against the original: LOD0 nearly
    // none, the impostor most (off-screen, by the viewport's renderer).
    click(&mut harness, "Visual difference");
    harness.step();
    wait_while(
        &mut harness,
        "measuring",
        StudioApp::is_measuring_difference,
    );
    let d = harness
        .state()
        .chain_differences()
        .expect("measured")
        .to_vec();
    assert_eq!(d.len(), 3);
    for l in &d {
        assert!(l.here.silhouette >= 0.0 && l.here.psnr > 0.0 && l.here.psnr <= 100.0);
        assert_eq!(l.image.rgba.len(), 256 * 256);
    }
    assert!(d[0].around.silhouette < d[2].around.silhouette, "{d:?}");
    assert!(d[0].around.psnr > d[2].around.psnr, "{d:?}");
    assert!(harness.query_by_label("silhouette, 8 views").is_some());

    // The switch preview: the LOD for each distance, drawn and named.
    let c = &chain.coverages;
    let at = |harness: &mut Harness<'_, StudioApp>, d: f32| {
        harness.state_mut().set_switch_distance(Some(d));
        harness.run();
        let (k, name) = harness.state().switch_lod().expect("a preview");
        let scene = harness.state().viewport().scene().expect("a scene");
        (
            k,
            name,
            scene.triangle_count(),
            scene.point_and_splat_counts().1,
        )
    };
    let near = at(&mut harness, distance_at_coverage(1.0));
    assert_eq!(
        (near.0, near.2),
        (0, chain.lods[0].set.mesh.triangles.len())
    );
    assert!(near.1.contains("simplify:0.5%"), "{}", near.1);
    let middle = at(&mut harness, distance_at_coverage((c[0] * c[1]).sqrt()));
    assert_eq!(
        (middle.0, middle.2),
        (1, chain.lods[1].set.mesh.triangles.len())
    );
    let far = at(&mut harness, distance_at_coverage(0.5 * (c[1] + c[2])));
    assert_eq!(far.0, 2);
    assert!(far.1.contains("amg:15%") && far.3 > 0, "{far:?}");
    assert!(
        harness.query_by_label("bound at switch").is_some(),
        "the inspector's row"
    );
    // The viewport names the LOD drawn, its triangles and its screen size.
    let overlay = format!(
        "{} · {} triangles · screen size",
        far.1,
        chain.lods[2].set.mesh.triangles.len()
    );
    assert!(
        harness.query_by_label_contains(&overlay).is_some(),
        "the overlay says {overlay}"
    );
    // For a human: the studio with the impostor previewed (target/tmp).
    let image = harness.render().expect("render the studio");
    save_ppm(
        image.width(),
        image.height(),
        image.as_raw(),
        "chain-impostor",
    );
    // The dolly runs from near to far by itself.
    click(&mut harness, "Dolly");
    harness.step();
    let first = harness.state().switch_lod().unwrap().0;
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(20) && harness.state().switch_lod().unwrap().0 < 2 {
        harness.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!((first, harness.state().switch_lod().unwrap().0), (0, 2));
    harness.state_mut().set_switch_distance(None);

    // Export, read back: three nodes, MSFT_lod ids, the LODs' primitives.
    let out = tmp.path().join("bones-chain.glb");
    let ctx = harness.ctx.clone();
    harness.state_mut().export_chain_to(&out, &ctx);
    wait_while(&mut harness, "exporting", StudioApp::is_exporting);
    let glb = std::fs::read(&out).expect("the chain was written");
    let doc = glb_json(&glb);
    assert_eq!(doc["nodes"].as_array().unwrap().len(), 3);
    assert_eq!(
        doc["nodes"][0]["extensions"]["MSFT_lod"]["ids"],
        serde_json::json!([1, 2])
    );
    let coverage = &doc["nodes"][0]["extras"]["MSFT_screencoverage"];
    assert_eq!(coverage.as_array().unwrap().len(), 3);
    let lod0 = lodstudio_core::io::load(&out, &Default::default(), &Default::default()).unwrap();
    let lodstudio_core::Model::Mesh(mesh0) = lod0.model else {
        panic!("LOD0 is a mesh")
    };
    assert_eq!(
        mesh0.triangles.len(),
        chain.lods[0].set.mesh.triangles.len()
    );

    // The recipe saved from the studio replays in the CLI byte for byte.
    let recipe_file = tmp.path().join("bones-recipe.json");
    harness.state_mut().save_recipe_to(&recipe_file, &ctx);
    wait_while(&mut harness, "saving", StudioApp::is_exporting);
    let cli_out = tmp.path().join("bones-cli.glb");
    let cli = std::process::Command::new(env!("CARGO_BIN_EXE_lodstudio"))
        .args(["export"])
        .arg(&bones)
        .arg("--recipe")
        .arg(&recipe_file)
        .arg("-o")
        .arg(&cli_out)
        .output()
        .unwrap();
    assert!(
        cli.status.success(),
        "{}",
        String::from_utf8_lossy(&cli.stderr)
    );
    assert!(
        std::fs::read(&cli_out).unwrap() == glb,
        "studio and CLI write the same bytes"
    );
    // ... and opens again as the same chain.
    harness
        .state_mut()
        .set_chain_recipe(Recipe::new(parse_lods("hybrid:1%", None).unwrap()));
    harness.state_mut().open_recipe(&recipe_file);
    assert_eq!(harness.state().chain_settings().recipe, recipe);
}

/// Rows are added, duplicated and removed from the panel; Auto chain fills
/// it by its rule and builds it; a bad recipe file is refused naming the row and the field.
#[test]
fn the_panel_edits_rows_and_refuses_bad_recipes() {
    let tmp = tempfile::tempdir().unwrap();
    let mut harness = studio(Some("builtin:torus".into()));
    wait_while(&mut harness, "loading", StudioApp::is_loading);
    let rows = |h: &Harness<'_, StudioApp>| h.state().chain_settings().recipe.rows.len();
    let before = rows(&harness);
    click(&mut harness, "Add row");
    harness.run();
    assert_eq!(rows(&harness), before + 1);
    // Each row's moves are in its Edit menu.
    click(&mut harness, "Edit");
    harness.run();
    click(&mut harness, "Duplicate");
    harness.run();
    assert_eq!(rows(&harness), before + 2);
    click(&mut harness, "Edit");
    harness.run();
    click(&mut harness, "Remove");
    harness.run();
    assert_eq!(rows(&harness), before + 1);
    // The last row bakes its own texture from its Edit menu (a source row
    // offers no such thing).
    harness
        .get_all_by_label("Edit")
        .last()
        .expect("Edit")
        .click();
    harness.run();
    click(&mut harness, "Bake its own texture");
    harness.run();
    let last = |h: &Harness<'_, StudioApp>| {
        h.state()
            .chain_settings()
            .recipe
            .rows
            .last()
            .cloned()
            .unwrap()
    };
    assert!(last(&harness).bakes() && last(&harness).texture == Some(1024));
    let bakes: Vec<bool> = harness
        .state()
        .chain_settings()
        .recipe
        .rows
        .iter()
        .map(|r| r.bakes())
        .collect();
    assert_eq!(bakes.iter().filter(|b| **b).count(), 1, "{bakes:?}");
    // An edge-collapse row's Edit menu frees its topology ("topology":
    // "free"); other methods' menus do not offer it.
    assert!(harness.query_by_label("Free topology").is_none());
    let collapse = harness
        .state()
        .chain_settings()
        .recipe
        .rows
        .iter()
        .position(|r| r.method == Method::EdgeCollapse && r.tolerance != RowTolerance::Source)
        .expect("an edge-collapse row");
    harness
        .get_all_by_label("Edit")
        .nth(collapse)
        .expect("Edit")
        .click();
    harness.run();
    click(&mut harness, "Free topology");
    harness.run();
    let rows_now = &harness.state().chain_settings().recipe.rows;
    assert!(rows_now[collapse].frees_topology());
    assert_eq!(rows_now.iter().filter(|r| r.frees_topology()).count(), 1);
    assert!(harness.state().chain_settings().recipe.check().is_ok());
    // Auto chain replaces the rows and builds them.
    click(&mut harness, "Auto chain");
    harness.step();
    assert!(harness.state().is_building_chain());
    wait_while(&mut harness, "auto chain", StudioApp::is_building_chain);
    let labels: Vec<String> = harness
        .state()
        .chain_settings()
        .recipe
        .rows
        .iter()
        .map(|r| r.label())
        .collect();
    assert_eq!(
        labels,
        ["source", "simplify:0.5", "simplify:0.25", "simplify:0.125"],
        "LOD0 is the source (issue 46)"
    );
    let chain = &harness.state().built_chain().unwrap().chain;
    let triangles: Vec<usize> = chain
        .lods
        .iter()
        .map(|l| l.set.mesh.triangles.len())
        .collect();
    assert!(triangles.windows(2).all(|w| w[1] < w[0]), "{triangles:?}");
    let source = harness.state().summary().map(|s| s.triangles);
    assert_eq!(Some(triangles[0]), source, "LOD0 has every triangle");
    assert_eq!(chain.lods[0].bound(), 0.0);

    let bad = tmp.path().join("bad-recipe.json");
    std::fs::write(
        &bad,
        r#"{"format":"lodstudio-recipe","version":1,"rows":[{"method":"simplify","tolerance":"1%"},{"method":"voxel","tolerance":"2%","resolution":2}]}"#,
    )
    .unwrap();
    let kept = harness.state().chain_settings().recipe.clone();
    harness.state_mut().open_recipe(&bad);
    assert_eq!(
        harness.state().chain_settings().recipe,
        kept,
        "nothing lost"
    );
    assert!(
        harness
            .state()
            .log_lines()
            .any(|l| l.contains("rows[1].resolution"))
    );
}

/// The chain on the panel (saved or not), the recent recipes and the built
/// chain survive a restart through the autosave: the chain without a build.
#[test]
fn an_unsaved_chain_survives_a_restart() {
    // Declared first, removed last: the studio below saves on drop.
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("autosave-chain");
    let interval = Duration::from_millis(100);
    let mut first = studio(Some("builtin:torus".into()));
    let autosave = Autosave::in_dir(&dir).with_interval(interval);
    let file = autosave.file().unwrap().to_path_buf();
    first.state_mut().resume(autosave, false);
    wait_while(&mut first, "loading", StudioApp::is_loading);
    let recipe = Recipe::new(parse_lods("hybrid:1%,voxel:5%,amg:20%", None).unwrap());
    first.state_mut().set_chain_recipe(recipe.clone());
    let saved = |file: &Path| {
        std::fs::read_to_string(file)
            .ok()
            .and_then(|j| Session::from_json(&j))
            .is_some_and(|s| s.chain.recipe == recipe)
    };
    let start = Instant::now();
    while !saved(&file) {
        assert!(start.elapsed() < Duration::from_secs(10), "never autosaved");
        std::thread::sleep(interval / 4);
        first.step();
    }
    built_chain(&mut first);
    let glb = first.state().built_chain().unwrap().chain.glb();
    std::mem::forget(first);
    let mut second = studio(None);
    second.state_mut().resume(Autosave::in_dir(&dir), true);
    assert_eq!(second.state().chain_settings().recipe, recipe);
    // The built chain is back with the model, and nothing was built for it.
    second.step();
    wait_while(&mut second, "reopening", |s| {
        s.is_loading() || s.is_building_chain()
    });
    let chain = &second
        .state()
        .built_chain()
        .expect("the chain reopened")
        .chain;
    assert!(chain.lods.iter().all(|l| l.reused));
    assert_eq!(chain.glb(), glb);
    assert!(
        second
            .state()
            .log_lines()
            .any(|l| l.contains("Reopened the last session's chain of 3 LODs"))
    );
}

/// A chain of the textured milk truck: each edge-collapse row is drawn with
/// its base-colour texture when clicked, and the exported chain carries the
/// materials into its LODs.
#[test]
fn the_truck_chain_is_drawn_textured_row_by_row() {
    let tmp = tempfile::tempdir().unwrap();
    let truck = shared("CesiumMilkTruck.glb");
    let mut harness = studio(Some(truck));
    wait_while(&mut harness, "loading", StudioApp::is_loading);
    harness.run();
    let original = colourful(&viewport_image(&mut harness, "truck-chain-original"));
    let recipe =
        Recipe::new(parse_lods("simplify:0.5%,impostor:8px,simplify:2%,amg:15%", None).unwrap());
    harness.state_mut().set_chain_recipe(recipe);
    // A method's result too: its live cut is not what a chain row shows.
    harness.state_mut().build();
    wait_while(&mut harness, "building", StudioApp::is_building);
    assert!(harness.query_by_label("cut triangles").is_some());
    built_chain(&mut harness);
    // The impostor's cards are drawn textured like the rows.
    let lods = &harness.state().built_chain().unwrap().chain.lods;
    assert_eq!(lods.len(), 4);
    let impostor = lods.iter().position(|l| l.method == Method::Impostor);
    let impostor = impostor.expect("an impostor LOD");
    // Buttons say "recipe row: LOD" (the first two rows are in view).
    for (recipe_row, row) in [(0, 0), (1, impostor)] {
        harness
            .get_by_label(&format!("{recipe_row}: LOD{row}"))
            .click();
        harness.run();
        let lod = harness.state().built_chain().unwrap().chain.lods[row]
            .set
            .mesh
            .triangles
            .len();
        assert_eq!(
            harness
                .state()
                .viewport()
                .scene()
                .map(|s| s.triangle_count()),
            Some(lod),
            "row {row} is drawn"
        );
        // The inspector describes what is drawn: the LOD, not a live cut.
        assert!(
            harness.query_by_label("cut triangles").is_none(),
            "row {row}: no live cut described"
        );
        let shown = harness.get_by_label("LOD triangles");
        let value = harness
            .get_all_by_label(&lod.to_string())
            .any(|n| n.rect().center().y == shown.rect().center().y);
        assert!(value, "row {row}: the inspector says {lod} triangles");
        let textured = colourful(&viewport_image(
            &mut harness,
            &format!("truck-chain-lod{row}"),
        ));
        eprintln!(
            "truck: original {original:.3} colourful, LOD{row} ({lod} triangles) {textured:.3}"
        );
        assert!(
            textured > 0.5 * original && textured > 0.05,
            "LOD{row}: {textured} vs {original}"
        );
    }
    let out = tmp.path().join("truck-chain.glb");
    let ctx = harness.ctx.clone();
    harness.state_mut().export_chain_to(&out, &ctx);
    wait_while(&mut harness, "exporting", StudioApp::is_exporting);
    let doc = glb_json(&std::fs::read(&out).unwrap());
    assert!(
        doc["images"].as_array().is_some_and(|i| !i.is_empty()),
        "the texture travels"
    );
    assert!(doc["materials"].as_array().is_some_and(|m| m.len() >= 2));
    // 5 % of the truck is past its seams' floor: unasked, the row bakes its
    // own texture and meets its budget; told never to bake, its triangle
    // cell is flagged (its hover says why) and the log line counts it.
    let mut recipe = Recipe::new(parse_lods("simplify:0.5%,simplify:0.05", None).unwrap());
    harness.state_mut().set_chain_recipe(recipe.clone());
    built_chain(&mut harness);
    let far = &harness.state().built_chain().unwrap().chain.lods[1];
    assert!(far.set.unmet.is_none(), "{:?}", far.set.unmet);
    assert!(far.baked.as_ref().is_some_and(|b| b.automatic));
    // The table says so (its hover says why).
    harness.run();
    assert!(harness.query_by_label("baked 1024²").is_some());
    recipe.rows[1].bake = Some(false);
    harness.state_mut().set_chain_recipe(recipe);
    built_chain(&mut harness);
    harness.run();
    let far = harness.state().built_chain().unwrap().chain.lods[1]
        .set
        .clone();
    let unmet = far.unmet.expect("the seams stop the collapse");
    assert!(unmet.why.starts_with("borders and seams stay"), "{unmet:?}");
    let flagged = format!("!{}", far.mesh.triangles.len());
    assert!(harness.query_by_label(&flagged).is_some(), "{flagged}");
    assert!(
        harness
            .query_by_label_contains("1 short of the triangle budget")
            .is_some()
    );
}

/// Rows that do not earn their place are flagged in the table's flags
/// column (its hover says why) and counted in the log; "Auto chain"
/// replaces the rows by its rule's and builds them, none flagged.
#[test]
fn flagged_rows_show_in_the_table_and_auto_chain_builds_none() {
    let mut harness = studio(Some(PathBuf::from("builtin:torus")));
    wait_while(&mut harness, "loading", StudioApp::is_loading);
    let rows = "source,simplify:0.05%,simplify:0.08%,simplify:0.25,simplify:0.002,simplify:0.001";
    let recipe = Recipe::new(parse_lods(rows, None).unwrap());
    harness.state_mut().set_chain_recipe(recipe);
    built_chain(&mut harness);
    harness.run();
    for word in ["never shown", "same LOD"] {
        assert_eq!(harness.get_all_by_label(word).count(), 1, "{word}");
    }
    assert!(harness.query_by_label_contains("2 rows flagged").is_some());

    click(&mut harness, "Auto chain");
    harness.step();
    wait_while(&mut harness, "auto chain", StudioApp::is_building_chain);
    harness.run();
    let settings = harness.state().chain_settings();
    assert_eq!(
        settings.recipe.rows,
        settings.auto.make(),
        "the rule's rows"
    );
    let built = harness.state().built_chain().expect("built");
    assert_eq!(built.recipe(), &settings.recipe);
    assert!(built.chain.flags().iter().all(Vec::is_empty));
    for word in ["never shown", "same LOD", "costlier"] {
        assert!(harness.query_by_label(word).is_none(), "{word}");
    }
}
