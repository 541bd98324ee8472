//! Reopening a saved hierarchy in the studio: its structure is cut live at
//! once, and its parameters become the shown ones, so nothing is rebuilt.

use std::path::Path;

use lodstudio_core::io::{LoadError, Location, ParseError};
use lodstudio_core::lod::{Hierarchy, Params};
use lodstudio_core::view::{Tolerance, View};
use lodstudio_core::voxel::VoxelParams;

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
        methods.method = self.method;
        methods.set_params(&self.saved_params());
        methods
    }

    /// The saved parameters over the method's defaults: each field the file
    /// names with a value of the default's kind (a CLI save names a few; the
    /// AMG texel it names in model units, which the studio's spacings do not
    /// take, keeps its default). A saved voxel hierarchy is its pyramid.
    fn saved_params(&self) -> Params {
        let defaults = Params::default_for(self.method);
        let mut merged = serde_json::to_value(defaults).unwrap_or_default();
        if let (Some(fields), Some(saved)) = (merged.as_object_mut(), self.params.as_object()) {
            for (key, value) in saved {
                if let Some(field) = fields.get_mut(key)
                    && key != "method"
                    && std::mem::discriminant(field) == std::mem::discriminant(value)
                {
                    *field = value.clone();
                }
            }
        }
        match serde_json::from_value(merged).unwrap_or(defaults) {
            Params::Voxel(v) => Params::Voxel(VoxelParams { pyramid: true, ..v }),
            params => params,
        }
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
