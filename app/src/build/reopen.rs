//! Reopening a saved hierarchy in the studio: its structure is cut live at
//! once, and its parameters become the shown ones, so nothing is rebuilt.

use std::path::Path;

use lodstudio_core::io::{LoadError, Location, ParseError};
use lodstudio_core::lod::Hierarchy;
use lodstudio_core::view::{Tolerance, View};

use super::{Built, Row};
use crate::live_cut::LiveCut;
use crate::settings::{Method, MethodSettings};

/// A saved hierarchy, decoded.
pub struct Reopened {
    method: Method,
    hierarchy: Box<dyn Hierarchy>,
    params: serde_json::Value,
}

/// Reads and decodes the saved hierarchy at `path`.
///
/// # Errors
/// The file cannot be read, or is damaged (a one-line reason).
pub fn reopen(path: &Path) -> Result<Reopened, LoadError> {
    let bytes = lodstudio_core::io::read_file(path, &lodstudio_core::Progress::new())?;
    let bad = |why: String| LoadError::malformed(path, ParseError::new(Location::File, why));
    let (header, hierarchy) =
        lodstudio_core::open::reopen(&bytes).map_err(|e| bad(e.to_string()))?;
    let method = hierarchy.method();
    Ok(Reopened {
        method,
        hierarchy,
        params: header.params,
    })
}

impl Reopened {
    /// `methods` with the saved method chosen and its saved parameters.
    pub fn apply(&self, mut methods: MethodSettings) -> MethodSettings {
        let number = |key: &str| self.params.get(key).and_then(|v| v.as_f64());
        methods.method = self.method;
        match self.method {
            Method::Hybrid => {
                methods.hybrid.kappa =
                    number("kappa").unwrap_or(methods.hybrid.kappa as f64) as f32;
                methods.hybrid.tau = number("tau").unwrap_or(methods.hybrid.tau as f64) as f32;
                methods.hybrid = methods.hybrid.sanitized();
            }
            Method::MergeTree => {
                let mt = &mut methods.merge_tree;
                mt.min_vertices = number("min_vertices").map_or(mt.min_vertices, |v| v as usize);
                mt.min_quality = number("min_quality").unwrap_or(mt.min_quality as f64) as f32;
                methods.merge_tree = methods.merge_tree.sanitized();
            }
            Method::Voxel => {
                let v = &mut methods.voxel;
                v.pyramid = true;
                v.resolution = number("resolution").map_or(v.resolution, |r| r as usize);
                v.radius = number("radius").unwrap_or(v.radius as f64) as f32;
                methods.voxel = methods.voxel.sanitized();
            }
            Method::Amg => {
                methods.amg.k = number("k").map_or(methods.amg.k, |k| k as usize);
                methods.amg = methods.amg.sanitized();
            }
            Method::EdgeCollapse => {
                let ec = &mut methods.edge_collapse;
                ec.lock_borders = self
                    .params
                    .get("lock_borders")
                    .and_then(|v| v.as_bool())
                    .unwrap_or(ec.lock_borders);
                ec.min_quality = number("min_quality").unwrap_or(ec.min_quality as f64) as f32;
                ec.min_normal_cos =
                    number("min_normal_cos").unwrap_or(ec.min_normal_cos as f64) as f32;
                methods.edge_collapse = methods.edge_collapse.sanitized();
            }
        }
        methods
    }

    /// The result the studio shows: the hierarchy cut live, built with
    /// `methods` (as [`Reopened::apply`] made them).
    pub fn built(self, methods: &MethodSettings, view: &View, tolerance: Tolerance) -> Built {
        Built {
            live: LiveCut::new(self.hierarchy, view, tolerance),
            params: methods.params(None),
            seconds: 0.0,
            rows: vec![Row {
                label: "saved with",
                value: self.params.to_string(),
                hint: "The parameters the hierarchy was built with; it was reopened from \
                       its file, not rebuilt.",
            }],
            plots: Vec::new(),
            voxel: None,
        }
    }
}
