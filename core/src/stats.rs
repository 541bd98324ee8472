//! One summary of a loaded model, shared by `lodstudio info` and the studio's
//! inspector so both always show the same counts.

use serde_json::json;

use crate::geom::{RepairReport, Topology};
use crate::io::{AssetReport, Format, Loaded, Model};

#[derive(Debug, Clone, PartialEq)]
pub struct ModelSummary {
    pub kind: &'static str,
    pub format: Format,
    pub vertices: usize,
    pub triangles: usize,
    pub points: usize,
    pub parts: u32,
    /// Distinct materials of the input (0 when it had none), textured ones apart.
    pub materials: usize,
    pub textured_materials: usize,
    pub components: usize,
    pub boundary_loops: usize,
    pub non_manifold_edges: usize,
    pub genus: i64,
    pub bbox_diagonal: f32,
    /// Volumes only: grid size, voxel spacing and value range.
    pub grid: Option<[usize; 3]>,
    pub spacing: Option<[f32; 3]>,
    pub value_range: Option<(f32, f32)>,
    pub repairs: RepairReport,
    /// The asset around the model (a glTF's scene) and what is not carried.
    pub asset: AssetReport,
}

impl ModelSummary {
    pub fn of(loaded: &Loaded) -> ModelSummary {
        let mut s = ModelSummary {
            kind: loaded.model.kind(),
            format: loaded.format,
            vertices: 0,
            triangles: 0,
            points: 0,
            parts: 0,
            materials: 0,
            textured_materials: 0,
            components: 0,
            boundary_loops: 0,
            non_manifold_edges: 0,
            genus: 0,
            bbox_diagonal: 0.0,
            grid: None,
            spacing: None,
            value_range: None,
            repairs: loaded.repairs.clone(),
            asset: loaded.asset.clone(),
        };
        match &loaded.model {
            Model::Mesh(m) => {
                let t = Topology::of(m);
                s.vertices = t.vertices;
                s.triangles = t.triangles;
                s.parts = m.part_count();
                if let Some(ms) = &m.materials {
                    s.materials = ms.table.len();
                    s.textured_materials = ms
                        .table
                        .iter()
                        .filter(|m| m.base_color_texture.is_some())
                        .count();
                }
                s.components = t.components.len();
                s.boundary_loops = t.boundary_loops;
                s.non_manifold_edges = t.non_manifold_edges;
                s.genus = t.genus;
                s.bbox_diagonal = m.bounds().diagonal();
            }
            Model::Points(p) => {
                s.points = p.positions.len();
                s.bbox_diagonal = p.bounds().diagonal();
            }
            Model::Volume(v) => {
                s.grid = Some(v.dims);
                s.spacing = Some(v.spacing.to_array());
                s.value_range = Some(v.value_range());
                s.bbox_diagonal = v.bounds().diagonal();
            }
        }
        s
    }

    /// The `info --json` object (DESIGN.md keys first, extras after).
    pub fn to_json(&self) -> serde_json::Value {
        let mut v = json!({
            "vertices": self.vertices,
            "triangles": self.triangles,
            "points": self.points,
            "components": self.components,
            "genus": self.genus,
            "bbox_diagonal": self.bbox_diagonal,
            "repairs": self.repairs.to_json(),
            "kind": self.kind,
            "format": self.format.name(),
            "parts": self.parts,
            "materials": self.materials,
            "textured_materials": self.textured_materials,
            "boundary_loops": self.boundary_loops,
            "non_manifold_edges": self.non_manifold_edges,
        });
        let a = &self.asset;
        for (key, value) in [
            ("nodes", json!(a.nodes)),
            ("meshes", json!(a.meshes)),
            ("instances", json!(a.instances)),
            ("skins", json!(a.skins)),
            ("animations", json!(a.animations)),
            ("morph_targets", json!(a.morph_targets)),
            ("extensions", json!(a.extensions)),
            ("dropped", json!(a.dropped)),
        ] {
            v[key] = value;
        }
        if let (Some(g), Some(sp), Some((lo, hi))) = (self.grid, self.spacing, self.value_range) {
            v["grid"] = json!(g);
            v["spacing"] = json!(sp);
            v["value_range"] = json!([lo, hi]);
        }
        v
    }

    /// Human-readable lines, label and value.
    pub fn lines(&self) -> Vec<(String, String)> {
        let mut out = vec![(
            "format".to_string(),
            format!("{} ({})", self.format.name(), self.kind),
        )];
        match self.grid {
            Some(g) => {
                out.push(("grid".into(), format!("{} x {} x {}", g[0], g[1], g[2])));
                if let Some(sp) = self.spacing {
                    out.push((
                        "spacing".into(),
                        format!("{} x {} x {}", sp[0], sp[1], sp[2]),
                    ));
                }
                if let Some((lo, hi)) = self.value_range {
                    out.push(("values".into(), format!("{lo} .. {hi}")));
                }
            }
            None if self.kind == "points" => {
                out.push(("points".into(), self.points.to_string()));
            }
            None => {
                out.push(("vertices".into(), self.vertices.to_string()));
                out.push(("triangles".into(), self.triangles.to_string()));
                out.push(("parts".into(), self.parts.to_string()));
                if self.materials > 0 {
                    out.push((
                        "materials".into(),
                        format!("{} ({} textured)", self.materials, self.textured_materials),
                    ));
                }
                out.push(("components".into(), self.components.to_string()));
                out.push(("boundary loops".into(), self.boundary_loops.to_string()));
                out.push(("genus".into(), self.genus.to_string()));
                out.push((
                    "non-manifold edges".into(),
                    self.non_manifold_edges.to_string(),
                ));
            }
        }
        out.push(("bbox diagonal".into(), format!("{:.6}", self.bbox_diagonal)));
        for (what, n) in self.repairs.applied() {
            out.push((format!("repair: {}", what.replace('_', " ")), n.to_string()));
        }
        out
    }
}
