//! A glTF asset in the studio (issue 49, item 7), driven headlessly through
//! egui_kittest: the outliner lists the engine's nodes by name and a click
//! highlights the node's instances in the viewport's drawing of the scene;
//! the skinned two-bone cylinder's chain is built for every mesh from the
//! chain panel's rows, exported as the CLI exports it, and its LOD moves
//! when its animation plays.

use std::path::PathBuf;

mod common;
#[path = "common/pixels.rs"]
#[allow(dead_code)] // `colourful` is the texture tests' measure, not used here.
mod pixels;

use common::{studio, wait_while};
use egui_kittest::kittest::Queryable as _;
use lodstudio::studio::StudioApp;
use lodstudio_core::recipe::{Recipe, parse_lods};
use pixels::viewport_image;

fn shared(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/models")
        .join(name)
}

/// Every node of the engine has its row, by name; clicking one shows the
/// asset as its nodes place it (the same bounds as the flattened model)
/// with that node's triangles highlighted.
#[test]
fn the_outliner_lists_the_engines_nodes_by_name() {
    let path = shared("2CylinderEngine.gltf");
    let doc: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    let mut harness = studio(Some(path));
    wait_while(&mut harness, "loading", StudioApp::is_loading);
    let labels: Vec<String> = harness
        .state()
        .asset()
        .expect("the engine opens as a scene")
        .outline_labels()
        .map(str::to_string)
        .collect();
    let nodes = doc["nodes"].as_array().unwrap();
    assert_eq!(labels.len(), nodes.len(), "one row per node");
    // The engine names its meshes, not its nodes: a row is the node's name
    // (else "node N") with the mesh it draws.
    let meshes = doc["meshes"].as_array().unwrap();
    for (i, node) in nodes.iter().enumerate() {
        let name = node["name"]
            .as_str()
            .map_or(format!("node {i}"), str::to_string);
        let row = labels.iter().find(|l| {
            l.strip_prefix(&name)
                .is_some_and(|rest| rest.is_empty() || rest.starts_with(' '))
        });
        let row = row.unwrap_or_else(|| panic!("{name}: no row"));
        if let Some(m) = node["mesh"].as_u64() {
            let mesh = meshes[m as usize]["name"].as_str().unwrap();
            assert!(row.contains(mesh), "{row} names {mesh}");
        }
    }
    // The first rows are on screen, as the outliner draws them.
    let first = labels[0].clone();
    assert!(harness.query_by_label_contains(&first).is_some(), "{first}");
    harness.get_by_label(&first).click();
    harness.run();
    let asset = harness.state_mut().asset_mut().unwrap();
    assert!(asset.show && asset.selected == Some(0));
    let total = asset.triangles(0).1;
    let drawn = asset.drawn().clone();
    let flat = match &harness.state().loaded().unwrap().model {
        lodstudio_core::io::Model::Mesh(m) => m,
        _ => panic!("a mesh"),
    };
    // Every instance drawn (the flattened model has fewer: loading drops
    // the engine's degenerate triangles).
    assert_eq!(drawn.triangles.len(), total);
    assert!(drawn.triangles.len() >= flat.triangles.len());
    let (a, b) = (drawn.bounds(), flat.bounds());
    assert!(
        a.min.distance(b.min) < 1e-3 * b.diagonal() && a.max.distance(b.max) < 1e-3 * b.diagonal(),
        "{a:?} / {b:?}"
    );
}

/// The two-bone cylinder (`assets/`): "Build for every mesh" builds the chain panel's rows
/// (`source,simplify:1%`), Export scene… writes the CLI's bytes, LOD1 is
/// drawn with its own triangles, and Play moves its vertices, on screen too.
#[test]
fn a_skinned_lod_moves_when_its_animation_plays() {
    let cylinder =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/two-bone-cylinder.glb");
    let mut harness = studio(Some(cylinder.clone()));
    wait_while(&mut harness, "loading", StudioApp::is_loading);
    harness
        .state_mut()
        .set_chain_recipe(Recipe::new(parse_lods("source,simplify:1%", None).unwrap()));
    harness.run();
    harness.get_by_label("Build for every mesh").click();
    harness.step();
    wait_while(&mut harness, "building the asset's chains", |s| {
        s.asset().is_some_and(|a| a.is_building())
    });
    assert_eq!(harness.state().asset().unwrap().levels(), 2);
    // Export scene… writes what `lodstudio export` writes, byte for byte.
    let tmp = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let (studio_glb, cli_glb) = (tmp.join("asset-studio.glb"), tmp.join("asset-cli.glb"));
    let ctx = harness.ctx.clone();
    harness.state_mut().export_asset_to(&studio_glb, &ctx);
    wait_while(&mut harness, "exporting", StudioApp::is_exporting);
    let cli = std::process::Command::new(env!("CARGO_BIN_EXE_lodstudio"))
        .args(["export", cylinder.to_str().unwrap()])
        .args([
            "--lods",
            "source,simplify:1%",
            "--force",
            "-o",
            cli_glb.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(
        cli.status.success(),
        "{}",
        String::from_utf8_lossy(&cli.stderr)
    );
    assert!(std::fs::read(&studio_glb).unwrap() == std::fs::read(&cli_glb).unwrap());
    harness.get_by_label("LOD1").click();
    harness.run();
    let rest = harness.state_mut().asset_mut().unwrap().drawn().clone();
    let original = harness.state().summary().unwrap().triangles;
    assert!(
        !rest.triangles.is_empty() && rest.triangles.len() < original,
        "LOD1 has {} of {original} triangles",
        rest.triangles.len()
    );
    let still = viewport_image(&mut harness, "asset-cylinder-lod1-rest");
    harness.get_by_label("Play").click();
    let mut moved = 0.0f32;
    // 1 s of the 2 s loop: the upper joint at its 60°.
    for _ in 0..60 {
        harness.step();
        let now = harness.state_mut().asset_mut().unwrap().drawn();
        assert_eq!(now.triangles, rest.triangles);
        let most = (now.positions.iter().zip(&rest.positions))
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f32::max);
        moved = moved.max(most);
    }
    assert!(moved > 0.1, "the LOD moved at most {moved}");
    harness.get_by_label("Pause").click();
    harness.run();
    let time = harness.state().asset().unwrap().time;
    assert!(time > 0.0 && !harness.state().asset().unwrap().is_moving());
    // On screen too (both images are saved for a person to look at).
    let posed = viewport_image(&mut harness, "asset-cylinder-lod1-posed");
    let differ = still.iter().zip(&posed).filter(|(a, b)| a != b).count();
    assert!(differ > 100, "{differ} pixels changed at t = {time} s");
}
