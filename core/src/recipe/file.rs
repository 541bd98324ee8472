//! The recipe file: a small versioned JSON document with the settings of an
//! LOD chain. The studio saves it, `export --save-recipe` writes it and
//! `export --recipe` replays it; what is not written takes its default.
//!
//! ```json
//! { "format": "lodstudio-recipe", "version": 1,
//!   "pixels": 1.0, "viewport_height": 1080.0, "coverage": 1.0,
//!   "rows": [ { "method": "simplify", "tolerance": "0.5%" },
//!             { "method": "hybrid", "tolerance": "2%", "kappa": 3.0, "tau": 1.0 },
//!             { "method": "amg", "tolerance": "15%" } ] }
//! ```

use serde::{Deserialize, Serialize};

use crate::geom::Weld;
use crate::hybrid::HybridOptions;
use crate::io::gltf_writer::PointsAs;
use crate::io::meshopt_compression::Compression;
use crate::io::scene_writer::Layout;
use crate::lod::{Method, Params};
use crate::simplify::collapse::AttributeWeights;
use crate::simplify::prune::TopologyMode;

use crate::voxel::PostSimplify;
use crate::voxel::VoxelParams;

/// What the `format` field says, so a recipe is told from other JSON.
pub const FORMAT: &str = "lodstudio-recipe";
/// The recipe version this lodstudio writes and reads.
pub const VERSION: u32 = 1;
/// Most rows a chain may have (recipes and `--lods`): far more than any
/// engine switches between, and a bound on what a hostile recipe may make
/// a batch build (100,000 identical rows ran until killed).
pub const MAX_ROWS: usize = 64;
/// Largest recipe file read: 64 rows are a few kilobytes.
pub const MAX_FILE_BYTES: u64 = 1 << 20;

/// The settings of an LOD chain: its rows and how they switch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Recipe {
    pub format: String,
    pub version: u32,
    /// Tolerance in pixels for the switch coverages: an LOD is shown only
    /// where its certified bound projects to at most this many pixels.
    #[serde(default = "one")]
    pub pixels: f32,
    /// Viewport height in pixels, for the coverages and "px" rows.
    #[serde(default = "full_hd")]
    pub viewport_height: f32,
    /// Screen coverage at which "px" rows are converted to object space.
    #[serde(default = "one")]
    pub coverage: f32,
    /// How hybrid points are written.
    #[serde(default)]
    pub points_as: PointsAs,
    /// Keep UV/normal seams: no welding across them, seams and borders fixed.
    #[serde(default)]
    pub keep_seams: bool,
    /// Border, seam and non-manifold vertices never move.
    #[serde(default)]
    pub lock_borders: bool,
    /// How coincident vertices are merged on load.
    #[serde(default)]
    pub weld: WeldSpec,
    /// How a scene's chains are laid out (glTF inputs; written only when
    /// not the default, so older recipes read and write the same).
    #[serde(default, skip_serializing_if = "is_default_layout")]
    pub layout: Layout,
    /// How the exported GLBs store their buffers (written only when not the
    /// default, as `layout`).
    #[serde(default, skip_serializing_if = "is_default_compression")]
    pub compress: Compression,
    /// LOD0…LODn as asked; the chain orders them by certified bound.
    pub rows: Vec<Row>,
}

fn is_default_layout(layout: &Layout) -> bool {
    *layout == Layout::default()
}

fn is_default_compression(c: &Compression) -> bool {
    *c == Compression::default()
}

fn one() -> f32 {
    1.0
}

fn full_hd() -> f32 {
    1080.0
}

/// One row of the chain: a method, its parameters and a tolerance.
/// Parameters apply to their method only (`kappa`, `tau`: hybrid;
/// `resolution`, `post`: voxel).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Row {
    #[serde(with = "method_tag")]
    pub method: Method,
    pub tolerance: RowTolerance,
    /// Hybrid: points per triangle's rendering time (κ).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kappa: Option<f32>,
    /// Hybrid: transition factor τ.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau: Option<f32>,
    /// Voxel: finest pyramid resolution.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub resolution: Option<usize>,
    /// Voxel: how each extracted level is simplified further (paper §5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub post: Option<PostSpec>,
    /// Edge collapse: texels a seam crossing may move a texture coordinate
    /// (`CollapseOptions::uv_tolerance`; unset: its default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uv_tolerance: Option<f32>,
    /// Edge collapse: appearance in the collapse order
    /// (`CollapseOptions::attribute_weights`; unset: its default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub attribute_weights: Option<AttributeWeights>,
    /// The LOD gets its own texture, baked from the model (`bake`; true):
    /// an edge-collapse row's seams then constrain nothing. Unset, a
    /// textured model's edge-collapse row bakes when its seams keep it
    /// short of its triangle budget, or when a count row measures closer to
    /// the model baked (`bake::choice`); false never.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bake: Option<bool>,
    /// The baked texture's (or the impostor's atlas's) side in texels
    /// (unset: `bake::default_size`, the model's texels per triangle kept;
    /// an impostor's 1024).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<u32>,
    /// Impostor: frames per side of its octahedral map of views.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub views: Option<u32>,
    /// Edge collapse: "free" may prune components where that is certified
    /// (`simplify::prune`); unset or "keep": every component stays.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub topology: Option<TopologyMode>,
}

impl Row {
    /// A row of `method` at `tolerance` with its method's default parameters
    /// written out (so a saved recipe says what it ran with).
    pub fn new(method: Method, tolerance: RowTolerance) -> Row {
        let mut row = Row {
            method,
            tolerance,
            kappa: None,
            tau: None,
            resolution: None,
            post: None,
            uv_tolerance: None,
            attribute_weights: None,
            bake: None,
            texture: None,
            views: None,
            topology: None,
        };
        match Params::default_for(method) {
            Params::Hybrid(h) => (row.kappa, row.tau) = (Some(h.kappa), Some(h.tau)),
            Params::Voxel(v) => {
                (row.resolution, row.post) = (Some(v.resolution), Some(v.post.into()))
            }
            Params::Impostor(i) => row.views = Some(i.views),
            _ => {}
        }
        row
    }

    /// What the row builds: its method's defaults with the row's own
    /// fields over them. Voxel rows keep the whole pyramid (their LODs are
    /// its cuts); `lock_borders` is the recipe's, for edge collapse.
    pub fn params(&self, lock_borders: bool) -> Params {
        let mut params = Params::default_for(self.method);
        match &mut params {
            Params::EdgeCollapse(p) => {
                p.collapse.lock_borders = lock_borders;
                // A baked LOD wears a new atlas: the old one's seams stop nothing.
                p.collapse.free_seams = self.bakes();
                p.collapse.uv_tolerance = self.uv_tolerance.unwrap_or(p.collapse.uv_tolerance);
                p.collapse.attribute_weights = self
                    .attribute_weights
                    .unwrap_or(p.collapse.attribute_weights);
            }
            Params::Hybrid(h) => {
                h.kappa = self.kappa.unwrap_or(h.kappa);
                h.tau = self.tau.unwrap_or(h.tau);
            }
            Params::Voxel(v) => {
                v.resolution = self.resolution.unwrap_or(v.resolution);
                v.post = self.post.map_or(v.post, PostSimplify::from);
                v.pyramid = true;
            }
            Params::Impostor(i) => {
                i.views = self.views.unwrap_or(i.views);
                i.texture = self.impostor_texture();
            }
            Params::MergeTree(_) | Params::Amg(_) => {}
        }
        params
    }

    /// κ, τ and the resolution as the row builds with them (the defaults
    /// where it gives none), for the panel's fields.
    pub fn kappa(&self) -> f32 {
        self.kappa.unwrap_or(HybridOptions::default().kappa)
    }
    pub fn tau(&self) -> f32 {
        self.tau.unwrap_or(HybridOptions::default().tau)
    }
    /// Whether the row always bakes its own texture.
    pub fn bakes(&self) -> bool {
        self.bake == Some(true)
    }

    /// The impostor's texture side (the default where the row gives none).
    pub fn impostor_texture(&self) -> u32 {
        self.texture.unwrap_or(crate::bake::DEFAULT_TEXTURE_SIZE)
    }

    pub fn resolution(&self) -> usize {
        self.resolution.unwrap_or(VoxelParams::default().resolution)
    }

    /// The row as `--lods` writes it: "hybrid:2%".
    pub fn label(&self) -> String {
        match self.tolerance {
            RowTolerance::Source => self.tolerance.to_string(),
            t => format!("{}:{t}", self.method.tag()),
        }
    }

    /// Rows that build the same hierarchy (same method, same parameters).
    pub fn same_hierarchy(&self, other: &Row) -> bool {
        self.params(false) == other.params(false) && self.frees_topology() == other.frees_topology()
    }

    /// Whether the row may change topology (`"topology": "free"`).
    pub fn frees_topology(&self) -> bool {
        self.topology == Some(TopologyMode::Free)
    }
}

/// What an LOD row asks for.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "String", into = "String")]
pub enum RowTolerance {
    /// Error bound in percent of the bounding-box diagonal ("1%").
    Percent(f32),
    /// Error bound in pixels ("8px") on the recipe's viewport and coverage.
    Pixels(f32),
    /// Fraction of the input's primitives ("0.25").
    Ratio(f32),
    /// The input itself ("source"): LOD0 as engines expect it, the mesh as
    /// loaded, with a bound of 0.
    Source,
}

impl std::fmt::Display for RowTolerance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RowTolerance::Percent(p) => write!(f, "{p}%"),
            RowTolerance::Pixels(p) => write!(f, "{p}px"),
            RowTolerance::Ratio(r) => write!(f, "{r}"),
            RowTolerance::Source => write!(f, "source"),
        }
    }
}

impl std::str::FromStr for RowTolerance {
    type Err = String;
    fn from_str(item: &str) -> Result<Self, String> {
        let item = item.trim();
        if item == "source" {
            return Ok(RowTolerance::Source);
        }
        let number = |s: &str| {
            s.trim()
                .parse::<f32>()
                .ok()
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or_else(|| {
                    format!("{} is not a number >= 0", crate::io::confine::excerpt(item))
                })
        };
        if let Some(p) = item.strip_suffix('%') {
            Ok(RowTolerance::Percent(number(p)?))
        } else if let Some(p) = item.strip_suffix("px") {
            Ok(RowTolerance::Pixels(number(p)?))
        } else {
            let r = number(item)?;
            if !(r > 0.0 && r <= 1.0) {
                return Err(format!(
                    "{} is not a triangle ratio in (0,1]",
                    crate::io::confine::excerpt(item)
                ));
            }
            Ok(RowTolerance::Ratio(r))
        }
    }
}

impl TryFrom<String> for RowTolerance {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
            .map_err(|e| format!("{e} (expected 1%, 8px, a triangle ratio 0.25 or source)"))
    }
}

impl From<RowTolerance> for String {
    fn from(t: RowTolerance) -> String {
        t.to_string()
    }
}

/// [`PostSimplify`] as the recipe writes it: "off", {"voxels": 0.5} or
/// {"triangles": 5000}.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PostSpec {
    Off,
    Voxels(f32),
    Triangles(usize),
}

impl From<PostSimplify> for PostSpec {
    fn from(p: PostSimplify) -> Self {
        match p {
            PostSimplify::Off => PostSpec::Off,
            PostSimplify::Voxels(v) => PostSpec::Voxels(v),
            PostSimplify::Triangles(n) => PostSpec::Triangles(n),
        }
    }
}

impl From<PostSpec> for PostSimplify {
    fn from(p: PostSpec) -> Self {
        match p {
            PostSpec::Off => PostSimplify::Off,
            PostSpec::Voxels(v) => PostSimplify::Voxels(v),
            PostSpec::Triangles(n) => PostSimplify::Triangles(n),
        }
    }
}

/// [`Weld`] as the recipe writes it: "exact", "off" or {"tolerance": d}.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WeldSpec {
    #[default]
    Exact,
    Off,
    Tolerance(f32),
}

impl From<WeldSpec> for Weld {
    fn from(w: WeldSpec) -> Self {
        match w {
            WeldSpec::Exact => Weld::Exact,
            WeldSpec::Off => Weld::Off,
            WeldSpec::Tolerance(t) => Weld::Tolerance(t),
        }
    }
}

/// `method` as its tag ("simplify", "hybrid", …), the name the CLI uses.
mod method_tag {
    use super::Method;
    use serde::{Deserialize, Deserializer, Serializer, de::Error};

    pub fn serialize<S: Serializer>(m: &Method, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(m.tag())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Method, D::Error> {
        let tag = String::deserialize(d)?;
        Method::from_tag(&tag)
            .ok_or_else(|| D::Error::custom(format!("{tag:?} is not one of {}", Method::tags())))
    }
}

/// A recipe that cannot be used: where (`rows[2].kappa`, `pixels`) and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{field}: {message}")]
pub struct RecipeError {
    /// The JSON path of the bad value, e.g. `rows[2].kappa`.
    pub field: String,
    pub message: String,
}

impl RecipeError {
    fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        RecipeError {
            field: field.into(),
            message: message.into(),
        }
    }
}

impl Recipe {
    /// A recipe of `rows` with every other setting at its default.
    pub fn new(rows: Vec<Row>) -> Recipe {
        Recipe {
            format: FORMAT.into(),
            version: VERSION,
            pixels: 1.0,
            viewport_height: full_hd(),
            coverage: 1.0,
            points_as: PointsAs::default(),
            layout: Layout::default(),
            compress: Compression::default(),
            keep_seams: false,
            lock_borders: false,
            weld: WeldSpec::default(),
            rows,
        }
    }

    /// Reads and checks a recipe; a bad value's error names its field.
    pub fn from_json(bytes: &[u8]) -> Result<Recipe, RecipeError> {
        // serde would read a struct from an array too; a recipe is an object.
        if bytes.trim_ascii_start().first() != Some(&b'{') {
            return Err(RecipeError::new("recipe", "expected a JSON object"));
        }
        let de = &mut serde_json::Deserializer::from_slice(bytes);
        let recipe: Recipe = serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let field = if path == "." { "recipe".into() } else { path };
            RecipeError::new(
                crate::io::confine::shorten(&field),
                crate::io::confine::shorten(&e.inner().to_string()),
            )
        })?;
        recipe.check()?;
        Ok(recipe)
    }

    /// Reads a recipe file (a regular file of at most [`MAX_FILE_BYTES`]); a
    /// bad value's error names the file, the row and the field.
    pub fn read(path: &std::path::Path) -> Result<Recipe, String> {
        let bytes = crate::io::confine::read_regular(path, MAX_FILE_BYTES)
            .map_err(|e| e.message().to_string())?;
        Recipe::from_json(&bytes).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// The recipe as written to a file (stable: fields in declaration order).
    pub fn to_json(&self) -> Vec<u8> {
        let mut bytes = serde_json::to_vec_pretty(self).expect("a recipe serializes");
        bytes.push(b'\n');
        bytes
    }

    /// Every value in range, every parameter on a row of its method.
    pub fn check(&self) -> Result<(), RecipeError> {
        if self.format != FORMAT {
            return Err(RecipeError::new(
                "format",
                format!(
                    "{:?} is not {FORMAT:?}: not a lodstudio recipe",
                    self.format
                ),
            ));
        }
        if self.version == 0 || self.version > VERSION {
            return Err(RecipeError::new(
                "version",
                format!(
                    "version {} is not one this lodstudio reads (1..={VERSION})",
                    self.version
                ),
            ));
        }
        for (name, v) in [
            ("pixels", self.pixels),
            ("viewport_height", self.viewport_height),
            ("coverage", self.coverage),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(RecipeError::new(
                    name,
                    format!("must be a finite number > 0, got {v}"),
                ));
            }
        }
        if let WeldSpec::Tolerance(t) = self.weld
            && !(t.is_finite() && t >= 0.0)
        {
            return Err(RecipeError::new(
                "weld.tolerance",
                format!("must be a finite distance >= 0, got {t}"),
            ));
        }
        if self.rows.is_empty() {
            return Err(RecipeError::new("rows", "a chain needs at least one row"));
        }
        if self.rows.len() > MAX_ROWS {
            return Err(RecipeError::new(
                "rows",
                format!("{} rows, at most {MAX_ROWS}", self.rows.len()),
            ));
        }
        for (i, row) in self.rows.iter().enumerate() {
            row.check().map_err(|(field, message)| {
                RecipeError::new(format!("rows[{i}].{field}"), message)
            })?;
        }
        Ok(())
    }

    /// How models are loaded for this chain.
    pub fn weld(&self) -> Weld {
        if self.keep_seams {
            Weld::Off
        } else {
            self.weld.into()
        }
    }

    /// Borders stay where they are (asked for, or implied by keeping seams).
    pub fn locks_borders(&self) -> bool {
        self.lock_borders || self.keep_seams
    }

    /// What row `j` builds (see [`Row::params`]).
    pub fn row_params(&self, j: usize) -> Params {
        self.rows[j].params(self.locks_borders())
    }
}

impl Row {
    /// The first bad field of the row and why.
    fn check(&self) -> Result<(), (&'static str, String)> {
        let m = self.method;
        let only = |field: &'static str, given: bool, for_method: Method| {
            if given && m != for_method {
                Err((
                    field,
                    format!(
                        "applies to {} rows only, this row is {}",
                        for_method.tag(),
                        m.tag()
                    ),
                ))
            } else {
                Ok(())
            }
        };
        only("kappa", self.kappa.is_some(), Method::Hybrid)?;
        only("tau", self.tau.is_some(), Method::Hybrid)?;
        only("resolution", self.resolution.is_some(), Method::Voxel)?;
        only("post", self.post.is_some(), Method::Voxel)?;
        only("views", self.views.is_some(), Method::Impostor)?;
        if m == Method::Impostor && self.bake.is_some() {
            return Err((
                "bake",
                "an impostor row's cards wear their own atlas: give \"texture\", not \"bake\""
                    .into(),
            ));
        }
        only(
            "uv_tolerance",
            self.uv_tolerance.is_some(),
            Method::EdgeCollapse,
        )?;
        only(
            "attribute_weights",
            self.attribute_weights.is_some(),
            Method::EdgeCollapse,
        )?;
        only("topology", self.topology.is_some(), Method::EdgeCollapse)?;
        if self.texture.is_some() && self.bake == Some(false) && m != Method::Impostor {
            return Err((
                "texture",
                "applies to rows that bake (\"bake\": true, or unset: when short of the budget)"
                    .into(),
            ));
        }
        if let Some(size) = self.texture
            && !crate::bake::TEXTURE_SIZE_RANGE.contains(&size)
        {
            let r = crate::bake::TEXTURE_SIZE_RANGE;
            return Err((
                "texture",
                format!("must be in {}..={}, got {size}", r.start(), r.end()),
            ));
        }
        let value = match self.tolerance {
            RowTolerance::Percent(v) | RowTolerance::Pixels(v) => v.is_finite() && v >= 0.0,
            RowTolerance::Ratio(r) => r > 0.0 && r <= 1.0,
            RowTolerance::Source => true,
        };
        if !value {
            return Err(("tolerance", format!("{} is out of range", self.tolerance)));
        }
        // Fields of other methods were refused above: what the row builds
        // is what is checked.
        self.params(false)
            .validate()
            .map_err(|e| (e.field, e.message))
    }
}

/// Parses `export --lods`: comma-separated items `1%`, `8px` or a triangle
/// ratio in (0,1], each optionally naming its method (`amg:15%`); a bare
/// item is a row of `method`.
pub fn parse_lods(list: &str, method: Option<Method>) -> Result<Vec<Row>, String> {
    let bad = |item: &str, why: &str| {
        format!(
            "--lods: {} {why} (expected items like source, 1%, 8px, a triangle ratio 0.25, or METHOD:1%)",
            crate::io::confine::excerpt(item)
        )
    };
    let items = list.split(',').count();
    if items > MAX_ROWS {
        return Err(format!("--lods: {items} items, at most {MAX_ROWS}"));
    }
    let mut rows = Vec::new();
    for item in list.split(',').map(str::trim) {
        if item.is_empty() {
            return Err(bad(list, "has an empty item"));
        }
        if item == "source" {
            // The input itself: no method builds it.
            rows.push(Row::new(Method::EdgeCollapse, RowTolerance::Source));
            continue;
        }
        let (m, tolerance) = match item.split_once(':') {
            Some((tag, t)) => {
                let m = Method::from_tag(tag.trim()).ok_or_else(|| {
                    bad(
                        item,
                        &format!("names no method (one of {})", Method::tags()),
                    )
                })?;
                (m, t)
            }
            None => {
                let m =
                    method.ok_or_else(|| bad(item, "names no method and no --method was given"))?;
                (m, item)
            }
        };
        let tolerance = tolerance.parse::<RowTolerance>().map_err(|e| {
            format!(
                "--lods: {} (expected items like source, 1%, 8px, a triangle ratio 0.25, or METHOD:1%)",
                crate::io::confine::shorten(&e)
            )
        })?;
        rows.push(Row::new(m, tolerance));
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lod_lists_parse_percentages_pixels_ratios_and_methods() {
        let rows = parse_lods(" 1%, 8px ,0.25,amg:15%", Some(Method::EdgeCollapse)).unwrap();
        let got: Vec<(Method, RowTolerance)> =
            rows.iter().map(|r| (r.method, r.tolerance)).collect();
        assert_eq!(
            got,
            [
                (Method::EdgeCollapse, RowTolerance::Percent(1.0)),
                (Method::EdgeCollapse, RowTolerance::Pixels(8.0)),
                (Method::EdgeCollapse, RowTolerance::Ratio(0.25)),
                (Method::Amg, RowTolerance::Percent(15.0)),
            ]
        );
        assert_eq!(rows[1].tolerance.to_string(), "8px");
        assert_eq!(rows[3].label(), "amg:15%");
        for bad in [
            "",
            "1%,",
            "abc",
            "-1%",
            "2",
            "0",
            "xpx",
            "nan%",
            "1%%",
            "voxels:1%",
            ":1%",
        ] {
            assert!(parse_lods(bad, Some(Method::Hybrid)).is_err(), "{bad:?}");
        }
        // A bare item needs --method; named items do not.
        assert!(parse_lods("1%", None).is_err());
        assert!(parse_lods("simplify:1%,hybrid:2%", None).is_ok());
    }

    #[test]
    fn a_recipe_round_trips_through_its_file() {
        let mut rows = parse_lods(
            "simplify:0.5%,hybrid:2%,voxel:4%,amg:15%,0.1",
            Some(Method::EdgeCollapse),
        )
        .unwrap();
        rows[0].uv_tolerance = Some(16.0);
        rows[1].bake = Some(true);
        rows[1].texture = Some(512);
        rows[1].kappa = Some(5.0);
        rows[2].post = Some(PostSpec::Triangles(900));
        let mut recipe = Recipe::new(rows);
        recipe.pixels = 2.0;
        recipe.weld = WeldSpec::Tolerance(1e-4);
        recipe.points_as = PointsAs::Discs;
        let plain = recipe.to_json();
        assert!(
            !String::from_utf8_lossy(&plain).contains("compress"),
            "a default left out"
        );
        recipe.layout = Layout::Nodes;
        recipe.compress = Compression::Meshopt;
        let bytes = recipe.to_json();
        let back = Recipe::from_json(&bytes).unwrap();
        assert_eq!(back, recipe);
        // The row builds with its own tolerance (rows of two tolerances are
        // two hierarchies).
        match back.row_params(0) {
            Params::EdgeCollapse(p) => assert_eq!(p.collapse.uv_tolerance, 16.0),
            other => panic!("{other:?}"),
        }
        assert!(
            !back.rows[0]
                .same_hierarchy(&Row::new(Method::EdgeCollapse, RowTolerance::Percent(0.5)))
        );
        assert_eq!(back.to_json(), bytes, "byte-identical when written again");
        // What is left out takes its default.
        let short = br#"{"format":"lodstudio-recipe","version":1,"rows":[{"method":"hybrid","tolerance":"2%"}]}"#;
        let r = Recipe::from_json(short).unwrap();
        assert_eq!(
            (r.pixels, r.viewport_height, r.rows[0].kappa()),
            (1.0, 1080.0, 3.0)
        );
    }

    #[test]
    fn bad_recipes_name_the_row_and_the_field() {
        let with_row = |row: &str| {
            format!(
                r#"{{"format":"lodstudio-recipe","version":1,"rows":[{{"method":"simplify","tolerance":"1%"}},{row}]}}"#
            )
        };
        let cases = [
            (
                with_row(r#"{"method":"hybrid","tolerance":"2%","kappa":99}"#),
                "rows[1].kappa",
            ),
            (
                with_row(r#"{"method":"hybrid","tolerance":"2%","tau":0}"#),
                "rows[1].tau",
            ),
            (
                with_row(r#"{"method":"simplify","tolerance":"2%","kappa":3}"#),
                "rows[1].kappa",
            ),
            (
                with_row(r#"{"method":"voxel","tolerance":"2%","resolution":3}"#),
                "rows[1].resolution",
            ),
            (
                with_row(r#"{"method":"simplify","tolerance":"2%","uv_tolerance":-1}"#),
                "rows[1].uv_tolerance",
            ),
            (
                with_row(r#"{"method":"hybrid","tolerance":"2%","uv_tolerance":4}"#),
                "rows[1].uv_tolerance",
            ),
            (
                with_row(
                    r#"{"method":"hybrid","tolerance":"2%","attribute_weights":{"normal":1}}"#,
                ),
                "rows[1].attribute_weights",
            ),
            (
                with_row(r#"{"method":"simplify","tolerance":"2%","bake":false,"texture":512}"#),
                "rows[1].texture",
            ),
            (
                with_row(r#"{"method":"simplify","tolerance":"2%","bake":true,"texture":9}"#),
                "rows[1].texture",
            ),
            (
                with_row(r#"{"method":"voxel","tolerance":"2%","post":{"voxels":-1}}"#),
                "rows[1].post",
            ),
            (
                with_row(r#"{"method":"simplify","tolerance":"2%","views":8}"#),
                "rows[1].views",
            ),
            (
                with_row(r#"{"method":"impostor","tolerance":"8px","bake":true}"#),
                "rows[1].bake",
            ),
            (
                with_row(r#"{"method":"voxels","tolerance":"2%"}"#),
                "rows[1].method",
            ),
            (
                with_row(r#"{"method":"amg","tolerance":"2"}"#),
                "rows[1].tolerance",
            ),
            (
                with_row(r#"{"method":"amg","tolerance":"2%","colour":1}"#),
                "rows[1]",
            ),
            (
                r#"{"format":"lodstudio-recipe","version":9,"rows":[]}"#.into(),
                "version",
            ),
            (
                r#"{"format":"lodstudio-recipe","version":1,"rows":[]}"#.into(),
                "rows",
            ),
            (
                r#"{"format":"lodstudio-recipe","version":1,"pixels":-1,"rows":[]}"#.into(),
                "pixels",
            ),
            (
                r#"{"format":"other","version":1,"rows":[]}"#.into(),
                "format",
            ),
            (r#"[1,2]"#.into(), "recipe"),
        ];
        for (json, field) in cases {
            let e = Recipe::from_json(json.as_bytes()).expect_err(&json);
            assert!(e.field.starts_with(field), "{json}: {e}");
        }
    }
}
