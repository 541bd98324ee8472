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

use serde_json::{Value, json};

use super::store::{Made, Plan, content_path};
use crate::geom::Aabb;

/// `tileset.json` of a planned tree whose every tile is made.
pub fn encode(plan: &Plan, made: &[Made]) -> Vec<u8> {
    let boxes = enclosing_boxes(plan, made);
    let tileset = json!({
        "asset": {"version": "1.1", "generator": concat!("lodstudio ", env!("CARGO_PKG_VERSION"))},
        // With nothing drawn, every point of the model is missing: the
        // root's box diagonal is the error that asks for the root at once
        // when the model covers more than a few pixels.
        "geometricError": boxes[0].diagonal().max(made[0].error),
        "root": tile_json(plan, made, &boxes, 0),
    });
    serde_json::to_vec_pretty(&tileset).expect("JSON of numbers and strings")
}

fn tile_json(plan: &Plan, made: &[Made], boxes: &[Aabb], i: usize) -> Value {
    let mut j = json!({
        "boundingVolume": {"box": z_up_box(&boxes[i])},
        "geometricError": made[i].error,
        "content": {"uri": content_path(i)},
    });
    if i == 0 {
        j["refine"] = json!("REPLACE");
    }
    let kids = &plan.children[i];
    if !kids.is_empty() {
        j["children"] = kids
            .iter()
            .map(|k| tile_json(plan, made, boxes, *k))
            .collect();
    }
    j
}

/// Each tile's box around its content and its descendants' boxes
/// (children come after their parent in the plan's order).
fn enclosing_boxes(plan: &Plan, made: &[Made]) -> Vec<Aabb> {
    let mut boxes: Vec<Aabb> = made.iter().map(|m| m.bounds).collect();
    for i in (0..boxes.len()).rev() {
        for k in &plan.children[i] {
            boxes[i] = boxes[i].union(boxes[*k]);
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
