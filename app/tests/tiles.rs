//! 3D Tiles in the studio (issue 47, item 4), driven headlessly through
//! egui_kittest: a tileset built from the model on screen opens and draws
//! the cut a viewer draws (the root alone from afar, finer tiles near, every
//! drawn tile within the screen-space error unless it is a leaf; its scene
//! made on a worker), coloured by level, with each drawn tile's certified bound in the inspector; a
//! tileset naming content outside its folder is refused with a message.

use std::path::PathBuf;

mod common;
#[path = "common/pixels.rs"]
mod pixels;

use common::{save_ppm, studio, wait_while};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable as _;
use lodstudio::studio::StudioApp;
use pixels::{colourful, viewport_image};

fn bones() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/models/bones.off")
}

/// Frames until the cut's scene (made on a worker) is on screen.
fn settle(h: &mut Harness<'_, StudioApp>) {
    h.run();
    wait_while(h, "making the cut's scene", |s| {
        s.tileset().is_some_and(|t| t.is_making())
    });
}

/// The drawn tiles and the triangles the viewport draws.
fn cut(h: &Harness<'_, StudioApp>) -> (Vec<usize>, usize) {
    let view = h.state().tileset().expect("a tileset on screen");
    let tiles = view.drawn().iter().map(|d| d.tile).collect();
    (
        tiles,
        h.state()
            .viewport()
            .scene()
            .map_or(0, |s| s.triangle_count()),
    )
}

#[test]
fn a_tileset_built_in_the_studio_draws_the_viewers_cut_by_level() {
    let tmp = tempfile::tempdir().unwrap();
    let mut h = studio(Some(bones()));
    wait_while(&mut h, "loading", StudioApp::is_loading);
    h.state_mut().tiles_mut().tile_triangles = 512;
    let path = tmp.path().join("tileset.json");
    let ctx = h.ctx.clone();
    h.state_mut().build_tileset(Some(path.clone()), &ctx);
    wait_while(&mut h, "building the tileset", StudioApp::is_loading);
    h.run();
    wait_while(&mut h, "opening the tileset", StudioApp::is_loading);
    let view = h.state().tileset().expect("the built tileset opened");
    assert_eq!(view.path, path);
    assert_eq!((view.set.tiles.len(), view.set.levels()), (31, 5));
    let root_triangles = view.triangles(0);
    let leaves: usize = (0..31)
        .filter(|i| view.set.tiles[*i].children.is_empty())
        .map(|i| view.triangles(i))
        .sum();
    assert_eq!(leaves, 4204, "the leaves are the original triangles");
    assert!(
        h.query_by_label("Drawn tiles").is_some(),
        "the inspector's table"
    );

    // Far away: the root alone.
    let framed = h.state().viewport().camera.distance;
    h.state_mut().viewport_mut().camera.distance = framed * 200.0;
    settle(&mut h);
    assert_eq!(cut(&h), (vec![0], root_triangles));

    // Near: finer tiles, several levels, each within the threshold unless
    // a leaf, and the viewport draws exactly their triangles.
    h.state_mut().viewport_mut().camera.distance = framed * 0.5;
    h.state_mut().tiles_mut().max_sse_px = 16.0;
    settle(&mut h);
    let view = h.state().tileset().unwrap();
    let drawn = view.drawn().to_vec();
    let levels: std::collections::BTreeSet<usize> =
        drawn.iter().map(|d| view.set.tiles[d.tile].depth).collect();
    assert!(levels.len() >= 2 && !levels.contains(&0), "{levels:?}");
    for d in &drawn {
        let t = &view.set.tiles[d.tile];
        assert!(d.sse_px <= 16.0 || t.children.is_empty(), "{d:?}");
    }
    let triangles: usize = drawn.iter().map(|d| view.triangles(d.tile)).sum();
    assert_eq!(cut(&h).1, triangles);
    assert!(triangles > root_triangles);

    // Coloured by level on screen, and not in the materials' clay.
    let by_level = colourful(&viewport_image(&mut h, "tileset-cut-by-level"));
    let image = h.render().unwrap();
    let shot = save_ppm(image.width(), image.height(), image.as_raw(), "tileset-cut");
    println!("studio screenshot: {}", shot.display());
    h.state_mut().tiles_mut().by_level = false;
    settle(&mut h);
    let plain = colourful(&viewport_image(&mut h, "tileset-cut-plain"));
    assert!(by_level > 2.0 * plain.max(0.01), "{by_level} vs {plain}");
}

#[test]
fn a_tileset_naming_content_outside_its_folder_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("set");
    std::fs::create_dir(&dir).unwrap();
    std::fs::write(tmp.path().join("outside.glb"), b"glTF").unwrap();
    std::fs::write(
        dir.join("tileset.json"),
        r#"{"asset": {"version": "1.1"}, "root": {"geometricError": 1,
            "boundingVolume": {"box": [0,0,0,1,0,0,0,1,0,0,0,1]},
            "content": {"uri": "../outside.glb"}}}"#,
    )
    .unwrap();
    let mut h = studio(Some(dir.clone()));
    wait_while(&mut h, "loading", StudioApp::is_loading);
    assert!(h.state().tileset().is_none());
    assert!(
        h.state()
            .log_lines()
            .any(|l| l.contains("leaves the tileset's folder")),
        "{:?}",
        h.state().log_lines().collect::<Vec<_>>()
    );
}
