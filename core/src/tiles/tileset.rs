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
//!
//! [`decode`] reads a tileset back (lodstudio's, or another tool's that
//! uses what lodstudio reads: boxes or spheres, GLB content, no tile
//! transforms); a tileset is input like any other: its content URIs stay
//! inside its folder.

use glam::Vec3;
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

/// One tile of a decoded tileset.
#[derive(Debug, Clone, PartialEq)]
pub struct TileNode {
    /// Its bounding volume as a y-up box (the content's frame).
    pub bounds: Aabb,
    /// `geometricError` (lodstudio's: certified, in the content's units).
    pub error: f32,
    /// Its content, relative to the tileset's folder (a GLB).
    pub content: Option<String>,
    pub children: Vec<usize>,
    pub depth: usize,
    /// `refine: ADD`: the children are drawn with it, not instead of it.
    pub add: bool,
}

/// A tileset as read: tile 0 is the root, children after their parent.
#[derive(Debug, Clone, PartialEq)]
pub struct Tileset {
    pub tiles: Vec<TileNode>,
}

impl Tileset {
    /// Levels from the root to the deepest tile.
    pub fn levels(&self) -> usize {
        self.tiles.iter().map(|t| t.depth + 1).max().unwrap_or(0)
    }
}

/// Reads `tileset.json`; a message says what is refused and where.
pub fn decode(bytes: &[u8]) -> Result<Tileset, String> {
    let doc: Value =
        serde_json::from_slice(bytes).map_err(|e| format!("not a tileset's JSON: {e}"))?;
    let version = doc["asset"]["version"].as_str().unwrap_or("");
    if !matches!(version, "1.0" | "1.1") {
        return Err(format!(
            "asset.version {version:?}: lodstudio reads 3D Tiles 1.0 and 1.1"
        ));
    }
    let mut tiles = Vec::new();
    read_tile(&doc["root"], "root", 0, false, &mut tiles)?;
    Ok(Tileset { tiles })
}

fn read_tile(
    j: &Value,
    at: &str,
    depth: usize,
    parent_add: bool,
    out: &mut Vec<TileNode>,
) -> Result<usize, String> {
    if !j.is_object() {
        return Err(format!("{at}: not a tile"));
    }
    if j.get("transform").is_some_and(|t| !is_identity(t)) {
        return Err(format!("{at}: tile transforms are not read yet"));
    }
    let error = j["geometricError"]
        .as_f64()
        .map(|e| e as f32)
        .filter(|e| e.is_finite() && *e >= 0.0)
        .ok_or_else(|| {
            format!("{at}: geometricError must be a number ≥ 0 (in single precision)")
        })?;
    let bounds = volume(&j["boundingVolume"]).map_err(|e| format!("{at}: {e}"))?;
    let add = match j["refine"].as_str() {
        None => parent_add,
        Some("ADD") => true,
        Some("REPLACE") => false,
        Some(r) => return Err(format!("{at}: refine {r:?} is neither ADD nor REPLACE")),
    };
    let content = match j.get("content") {
        None => None,
        Some(c) => Some(content_uri(c).map_err(|e| format!("{at}.content: {e}"))?),
    };
    let me = out.len();
    out.push(TileNode {
        bounds,
        error,
        content,
        children: Vec::new(),
        depth,
        add,
    });
    if let Some(kids) = j.get("children") {
        let kids = kids
            .as_array()
            .ok_or_else(|| format!("{at}.children: not a list"))?;
        for (k, kid) in kids.iter().enumerate() {
            let i = read_tile(kid, &format!("{at}.children[{k}]"), depth + 1, add, out)?;
            out[me].children.push(i);
        }
    }
    Ok(me)
}

fn is_identity(t: &Value) -> bool {
    let id = [
        1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
    ];
    t.as_array()
        .is_some_and(|a| a.len() == 16 && a.iter().zip(id).all(|(v, e)| v.as_f64() == Some(e)))
}

/// A bounding volume as a y-up box: `box` (an oriented box's enclosing
/// box) or `sphere`; `region` (longitudes and latitudes) is refused.
fn volume(j: &Value) -> Result<Aabb, String> {
    let numbers = |v: &Value, n: usize, what: &str| -> Result<Vec<f64>, String> {
        let a: Vec<f64> = v
            .as_array()
            .map(|a| a.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default();
        if a.len() == n && a.iter().all(|x| x.is_finite()) {
            Ok(a)
        } else {
            Err(format!("boundingVolume.{what} needs {n} finite numbers"))
        }
    };
    let (centre, half) = if let Some(b) = j.get("box") {
        let b = numbers(b, 12, "box")?;
        // Each axis's extent: the sum over the half-axes of their parts along it.
        let half: [f64; 3] =
            std::array::from_fn(|a| b[3 + a].abs() + b[6 + a].abs() + b[9 + a].abs());
        ([b[0], b[1], b[2]], half)
    } else if let Some(s) = j.get("sphere") {
        let s = numbers(s, 4, "sphere")?;
        ([s[0], s[1], s[2]], [s[3].abs(); 3])
    } else if j.get("region").is_some() {
        return Err("boundingVolume.region (geographic) is not read; boxes and spheres are".into());
    } else {
        return Err("boundingVolume: no box or sphere".into());
    };
    // z-up (x, y, z) ↦ y-up (x, z, −y), the inverse of `z_up_box`.
    let c = Vec3::new(centre[0] as f32, centre[2] as f32, -centre[1] as f32);
    let h = Vec3::new(half[0] as f32, half[2] as f32, half[1] as f32);
    let b = Aabb {
        min: c - h,
        max: c + h,
    };
    match b.diagonal().is_finite() {
        true => Ok(b),
        false => Err("boundingVolume: beyond single precision".into()),
    }
}

/// A content URI that stays in the tileset's folder: relative, no `..`, no
/// scheme, a GLB (nested tilesets and b3dm are not read).
fn content_uri(c: &Value) -> Result<String, String> {
    let uri = c["uri"]
        .as_str()
        .or_else(|| c["url"].as_str())
        .ok_or("no uri")?;
    let path = std::path::Path::new(uri);
    let inside = path
        .components()
        .all(|p| matches!(p, std::path::Component::Normal(_)));
    if uri.contains(':') || uri.contains('\\') || !inside {
        return Err(format!(
            "{uri:?} leaves the tileset's folder (only relative paths inside it are read)"
        ));
    }
    if !uri.to_ascii_lowercase().ends_with(".glb") {
        return Err(format!("{uri:?}: only GLB content is read"));
    }
    Ok(uri.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn made(x: f32, error: f32) -> Made {
        Made {
            error,
            covers: 1,
            triangles: 1,
            bounds: Aabb {
                min: Vec3::new(x, 1.0, 2.0),
                max: Vec3::new(x + 1.0, 3.0, 5.0),
            },
        }
    }

    /// What `encode` writes, `decode` reads back: the tree, the errors, the
    /// contents and the boxes (turned z-up and back).
    #[test]
    fn a_written_tileset_reads_back() {
        let plan = Plan {
            key: String::new(),
            tile_triangles: 64,
            input_triangles: 2,
            bbox_diagonal: 1.0,
            children: vec![vec![1, 2], vec![], vec![]],
        };
        let made = [made(0.0, 0.5), made(0.0, 0.0), made(1.0, 0.0)];
        let set = decode(&encode(&plan, &made)).unwrap();
        assert_eq!(set.tiles.len(), 3);
        assert_eq!(set.levels(), 2);
        assert_eq!(set.tiles[0].children, [1, 2]);
        assert_eq!(set.tiles[0].error, 0.5);
        assert_eq!(set.tiles[2].content.as_deref(), Some("tiles/2.glb"));
        assert_eq!(set.tiles[1].bounds, made[1].bounds);
        assert_eq!(set.tiles[0].bounds.min, Vec3::new(0.0, 1.0, 2.0));
        assert_eq!(set.tiles[0].bounds.max, Vec3::new(2.0, 3.0, 5.0));
        assert!(set.tiles.iter().all(|t| !t.add));
    }

    /// Content outside the folder, other content kinds, geographic regions
    /// and transforms are refused with the tile named.
    #[test]
    fn hostile_or_unread_tilesets_are_refused() {
        let with = |root: &str| {
            decode(format!(r#"{{"asset": {{"version": "1.1"}}, "root": {root}}}"#).as_bytes())
        };
        let tile = |extra: &str| {
            format!(
                r#"{{"geometricError": 1, "boundingVolume": {{"box": [0,0,0,1,0,0,0,1,0,0,0,1]}}{extra}}}"#
            )
        };
        assert!(with(&tile("")).is_ok());
        for uri in [
            "../x.glb",
            "/etc/x.glb",
            "http://a/b.glb",
            "a/b.b3dm",
            "c:/x.glb",
        ] {
            let e = with(&tile(&format!(r#", "content": {{"uri": "{uri}"}}"#))).unwrap_err();
            assert!(e.contains("root.content"), "{uri}: {e}");
        }
        let region = r#"{"geometricError": 1, "boundingVolume": {"region": [0,0,1,1,0,1]}}"#;
        assert!(with(region).unwrap_err().contains("region"));
        let moved = tile(r#", "transform": [1,0,0,0,0,1,0,0,0,0,1,0,5,0,0,1]"#);
        assert!(with(&moved).unwrap_err().contains("transform"));
        let nested = tile(&format!(
            r#", "children": [{}]"#,
            tile(r#", "refine": "UP""#)
        ));
        assert!(with(&nested).unwrap_err().contains("root.children[0]"));
        assert!(decode(b"{}").is_err());
    }
}
