//! A tile tree as OGC 3D Tiles 1.1: `tileset.json` and one GLB per tile
//! (`tiles/N.glb`, N the tile's index), `refine: REPLACE` (a parent's
//! children stand for it whole), each tile's `geometricError` its certified
//! bound.
//!
//! Frames: glTF content is y-up and clients turn it z-up (3D Tiles 1.1,
//! "glTF transforms": (x, y, z) ↦ (x, −z, y)), while bounding volumes are
//! in the tileset's z-up frame; so each box is turned the same way here.
//! A tile's box holds its content and its descendants' boxes, as the
//! specification asks of bounding volumes.

use glam::Vec3;
use serde_json::{Value, json};

use super::TileTree;
use crate::geom::Aabb;
use crate::io::gltf_writer::write_glb;

/// The path, inside the tileset's folder, of tile `i`'s content.
pub fn content_path(i: usize) -> String {
    format!("tiles/{i}.glb")
}

/// `tileset.json` and every tile's content, as (relative path, bytes);
/// `tileset.json` first.
pub fn encode(tree: &TileTree) -> Vec<(String, Vec<u8>)> {
    let boxes = enclosing_boxes(tree);
    let root_box = boxes.first().copied().unwrap_or(Aabb {
        min: Vec3::ZERO,
        max: Vec3::ZERO,
    });
    let tileset = json!({
        "asset": {"version": "1.1", "generator": concat!("lodstudio ", env!("CARGO_PKG_VERSION"))},
        // With nothing drawn, every point of the model is missing: the
        // root's box diagonal is the error that asks for the root at once
        // when the model covers more than a few pixels.
        "geometricError": root_box.diagonal().max(tree.tiles.first().map_or(0.0, |t| t.error)),
        "root": tile_json(tree, &boxes, 0),
    });
    let mut files = vec![(
        "tileset.json".to_string(),
        serde_json::to_vec_pretty(&tileset).expect("JSON of numbers and strings"),
    )];
    files.extend(
        tree.tiles
            .iter()
            .enumerate()
            .map(|(i, t)| (content_path(i), write_glb(&t.mesh))),
    );
    files
}

fn tile_json(tree: &TileTree, boxes: &[Aabb], i: usize) -> Value {
    let tile = &tree.tiles[i];
    let mut j = json!({
        "boundingVolume": {"box": z_up_box(&boxes[i])},
        "geometricError": tile.error,
        "content": {"uri": content_path(i)},
    });
    if i == 0 {
        j["refine"] = json!("REPLACE");
    }
    if !tile.children.is_empty() {
        j["children"] = tile
            .children
            .iter()
            .map(|k| tile_json(tree, boxes, *k))
            .collect();
    }
    j
}

/// Each tile's box around its content and its descendants' boxes
/// (children come after their parent in the tree's order).
fn enclosing_boxes(tree: &TileTree) -> Vec<Aabb> {
    let mut boxes: Vec<Aabb> = tree.tiles.iter().map(|t| t.mesh.bounds()).collect();
    for i in (0..tree.tiles.len()).rev() {
        for k in &tree.tiles[i].children {
            let (lo, hi) = (boxes[*k].min, boxes[*k].max);
            boxes[i].min = boxes[i].min.min(lo);
            boxes[i].max = boxes[i].max.max(hi);
        }
    }
    boxes
}

/// A y-up box as 3D Tiles' `box` (centre, then three half-axes) in the z-up frame.
pub fn z_up_box(b: &Aabb) -> [f64; 12] {
    let (c, h) = (b.center().as_dvec3(), ((b.max - b.min) * 0.5).as_dvec3());
    // (x, y, z) ↦ (x, −z, y); half-axes are lengths, so their signs do not matter.
    [c.x, -c.z, c.y, h.x, 0.0, 0.0, 0.0, h.z, 0.0, 0.0, 0.0, h.y]
}
