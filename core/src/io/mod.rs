//! Model I/O: format detection (by content, then extension), the readers, gzip,
//! and repair on load.
//!
//! Readers work on bytes and never trust a header count: every count is checked
//! against the bytes that remain before anything is allocated from it.

pub mod appearance;
pub mod asset;
pub mod atlas;
pub mod base_color;
mod compact;
pub mod confine;
pub mod cut_writer;
mod error;
pub mod gltf;
pub mod gltf_writer;
pub mod hierarchy_file;
pub mod image;
pub mod limits;
pub mod meshopt_compression;
pub mod obj;
pub mod off;
pub mod ply;
pub mod rig;
pub mod scene;
pub mod scene_writer;
mod text;
pub mod volume;

use std::path::{Path, PathBuf};

pub use asset::{AssetReport, Dropped};
pub use error::{LoadError, Location, ParseError, ParseResult};
pub use volume::{RawSpec, ScalarType};

pub use crate::geom::Model;
use crate::geom::{RepairOptions, RepairReport, TriMesh};
use crate::progress::Progress;

/// A loaded, repaired model with what was done to it.
#[derive(Debug, Clone)]
pub struct Loaded {
    pub model: Model,
    pub format: Format,
    pub repairs: RepairReport,
    /// The asset around the model and what the outputs leave out of it.
    pub asset: AssetReport,
}

/// File formats lodstudio reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Obj,
    Gltf,
    Glb,
    Ply,
    Off,
    Nrrd,
    Nifti,
    Inr,
    Raw,
    Builtin,
    /// A saved hierarchy (`--save`, the studio), opened as its finest cut.
    Hierarchy,
}

impl Format {
    pub fn name(self) -> &'static str {
        match self {
            Format::Obj => "OBJ",
            Format::Gltf => "glTF",
            Format::Glb => "GLB",
            Format::Ply => "PLY",
            Format::Off => "OFF",
            Format::Nrrd => "NRRD",
            Format::Nifti => "NIfTI-1",
            Format::Inr => "INRIMAGE-4",
            Format::Raw => "raw volume",
            Format::Builtin => "built-in",
            Format::Hierarchy => "saved hierarchy",
        }
    }
}

/// Options for [`load`].
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    pub repair: RepairOptions,
    /// Layout of a headerless raw volume; required to read one.
    pub raw: Option<RawSpec>,
}

/// Loads a model file, detects its format, and repairs meshes (`open::open`
/// also opens `builtin:` names and saved hierarchies).
pub fn load(path: &Path, opts: &LoadOptions, progress: &Progress) -> Result<Loaded, LoadError> {
    let bytes = read_file(path, progress)?;
    load_bytes(path, &bytes, opts, progress)
}

/// A file's bytes, read under the stage "reading file": a regular file
/// within the memory budget (a FIFO, a device or a folder is refused at
/// once, `confine::read_regular`).
pub fn read_file(path: &Path, progress: &Progress) -> Result<Vec<u8>, LoadError> {
    progress.stage("reading file");
    confine::read_regular(path, limits::current().memory_budget)
        .map_err(|e| LoadError::Refused(e.message().to_string()))
}

/// Loads from bytes already in memory; `path` names the file in errors, gives
/// the extension hint and the folder that external glTF buffers are read from.
pub fn load_bytes(
    path: &Path,
    bytes: &[u8],
    opts: &LoadOptions,
    progress: &Progress,
) -> Result<Loaded, LoadError> {
    let malformed = |e: ParseError| LoadError::malformed(path, e);
    let unzipped;
    let mut data = bytes;
    if is_gzip(data) {
        progress.stage("decompressing");
        unzipped = inflate_model(path, data, opts.raw.is_some())?;
        data = &unzipped;
    }
    progress.check()?;
    let format = detect(path, data, opts.raw.is_some())?;
    progress.stage(&format!("parsing {}", format.name()));
    let mut asset = AssetReport::single();
    let model = match format {
        Format::Obj => Model::Mesh(obj::read(data, progress).map_err(malformed)?),
        Format::Gltf | Format::Glb => {
            let base = path.parent().map(Path::to_path_buf);
            let (mesh, report) = gltf::read(data, base.as_deref()).map_err(malformed)?;
            asset = report;
            Model::Mesh(mesh)
        }
        Format::Ply => ply::read(data, progress).map_err(malformed)?,
        Format::Off => off::read(data, progress).map_err(malformed)?,
        Format::Nrrd => Model::Volume(volume::read_nrrd(data).map_err(malformed)?),
        Format::Nifti => Model::Volume(volume::read_nifti(data).map_err(malformed)?),
        Format::Inr => Model::Volume(volume::read_inr(data).map_err(malformed)?),
        Format::Raw => {
            let spec = opts.raw.as_ref().ok_or_else(|| LoadError::UnknownFormat {
                file: path.to_path_buf(),
                why: "a raw volume needs its dimensions and scalar type".into(),
            })?;
            Model::Volume(volume::read_raw(data, spec).map_err(malformed)?)
        }
        Format::Builtin => unreachable!("detect never answers Builtin"),
        // Decoding one takes its method: `open::open` does.
        Format::Hierarchy => {
            return Err(LoadError::UnknownFormat {
                file: path.to_path_buf(),
                why: "a saved hierarchy, which opens through lodstudio_core::open".into(),
            });
        }
    };
    progress.check()?;
    let mut loaded = prepared(path, model, format, opts)?;
    loaded.asset = asset;
    Ok(loaded)
}

/// A model read from `path` in `format`, repaired as loading does, and
/// refused when empty or of absurd extent.
pub fn prepared(
    path: &Path,
    model: Model,
    format: Format,
    opts: &LoadOptions,
) -> Result<Loaded, LoadError> {
    let loaded = finish(model, format, opts);
    check_not_empty(path, &loaded)?;
    check_extent(path, &loaded)?;
    Ok(loaded)
}

fn finish(model: Model, format: Format, opts: &LoadOptions) -> Loaded {
    match model {
        Model::Mesh(mesh) => {
            let (mesh, repairs) = crate::geom::repair::repair_mesh(mesh, &opts.repair);
            Loaded {
                model: Model::Mesh(mesh),
                format,
                repairs,
                asset: AssetReport::single(),
            }
        }
        Model::Points(points) => {
            let (points, repairs) = crate::geom::repair::repair_points(points);
            Loaded {
                model: Model::Points(points),
                format,
                repairs,
                asset: AssetReport::single(),
            }
        }
        Model::Volume(v) => Loaded {
            model: Model::Volume(v),
            format,
            repairs: RepairReport::default(),
            asset: AssetReport::single(),
        },
    }
}

/// Finite coordinates can still span more than f32 holds: a bounding box
/// whose diagonal overflows leaves no tolerance, bound or grid meaningful (a
/// fuzz find: such a mesh broke the hybrid build's invariants).
fn check_extent(path: &Path, loaded: &Loaded) -> Result<(), LoadError> {
    let bounds = match &loaded.model {
        Model::Mesh(m) => m.bounds(),
        Model::Points(p) => p.bounds(),
        Model::Volume(v) => v.bounds(),
    };
    if bounds.diagonal().is_finite() {
        return Ok(());
    }
    Err(LoadError::malformed(
        path,
        ParseError::file(format!(
            "expected coordinates within f32 range of each other, found a bounding box from {} to {} whose diagonal overflows",
            bounds.min, bounds.max
        )),
    ))
}

fn check_not_empty(path: &Path, loaded: &Loaded) -> Result<(), LoadError> {
    let why = match &loaded.model {
        Model::Mesh(m) if m.triangles.is_empty() => "no valid triangles",
        Model::Points(p) if p.positions.is_empty() => "no valid points",
        Model::Volume(v) if v.data.is_empty() => "no voxels",
        _ => return Ok(()),
    };
    Err(LoadError::Empty {
        file: path.to_path_buf(),
        why: why.into(),
    })
}

pub fn is_gzip(data: &[u8]) -> bool {
    data.starts_with(&[0x1f, 0x8b])
}

/// Bytes of a gzip model inflated before its content is checked.
const GZIP_HEAD: u64 = 64 << 10;

/// Inflates a gzipped model: the first [`GZIP_HEAD`] bytes, which must start
/// like a model format (by content, or text for a format named by the
/// extension), then the rest up to the decompression cap. A bomb of zeros is
/// refused after 64 KiB, a well-formed one at the cap, never by exhausting memory.
fn inflate_model(path: &Path, data: &[u8], raw_given: bool) -> Result<Vec<u8>, LoadError> {
    use std::io::Read;
    let malformed = |e: ParseError| LoadError::malformed(path, e);
    let cap = decompression_cap(data.len() as u64);
    let mut dec = flate2::read::MultiGzDecoder::new(data);
    let mut out = Vec::new();
    (&mut dec)
        .take(GZIP_HEAD.min(cap + 1))
        .read_to_end(&mut out)
        .map_err(|e| malformed(bad_gzip(e)))?;
    if !raw_given && detect_content(&out).is_none() {
        let format = detect(path, &out, false)?;
        let text = matches!(format, Format::Obj | Format::Off | Format::Gltf);
        if !text || out.contains(&0) {
            let start: Vec<String> = out.iter().take(8).map(|b| format!("{b:02x}")).collect();
            return Err(malformed(ParseError::file(format!(
                "expected a {} file inside the gzip stream, but its first bytes are {}",
                format.name(),
                start.join(" ")
            ))));
        }
    }
    dec.take(cap + 1 - out.len() as u64)
        .read_to_end(&mut out)
        .map_err(|e| malformed(bad_gzip(e)))?;
    check_cap(out.len() as u64, cap).map_err(malformed)?;
    Ok(out)
}

fn bad_gzip(e: std::io::Error) -> ParseError {
    ParseError::file(format!("expected a valid gzip stream ({e})"))
}

/// How far `compressed` bytes may inflate: the absolute cap, and no more
/// than [`limits::MAX_RATIO`] times their size (models and volumes compress
/// 2–10×; deflate's extreme is about 1000×, a bomb's ratio) above a floor
/// that no real file of that size would need.
pub fn decompression_cap(compressed: u64) -> u64 {
    let limits = limits::current();
    if !limits.ratio_limited {
        return limits.max_decompressed;
    }
    let proportionate = compressed
        .saturating_mul(limits::MAX_RATIO)
        .max(limits::RATIO_FLOOR);
    limits.max_decompressed.min(proportionate)
}

fn check_cap(len: u64, cap: u64) -> ParseResult<()> {
    if len <= cap {
        return Ok(());
    }
    Err(ParseError::file(format!(
        "expected at most {} after decompression, the cap ({}× the compressed size \
         above {}, at most {}; raise it with --max-decompressed or {})",
        limits::format_size(cap),
        limits::MAX_RATIO,
        limits::format_size(limits::RATIO_FLOOR),
        limits::format_size(limits::current().max_decompressed),
        limits::MAX_DECOMPRESSED_ENV
    )))
}

/// Decompresses a gzip stream (inside a file, e.g. NRRD's gzip encoding),
/// refusing to produce more than the decompression cap or `limit`.
pub fn gunzip(data: &[u8], limit: u64) -> ParseResult<Vec<u8>> {
    use std::io::Read;
    let cap = limit.min(decompression_cap(data.len() as u64));
    let mut out = Vec::new();
    flate2::read::MultiGzDecoder::new(data)
        .take(cap + 1)
        .read_to_end(&mut out)
        .map_err(bad_gzip)?;
    check_cap(out.len() as u64, cap)?;
    Ok(out)
}

/// Detects the format by content first, then by extension.
pub fn detect(path: &Path, data: &[u8], raw_given: bool) -> Result<Format, LoadError> {
    let unknown = |why: &str| LoadError::UnknownFormat {
        file: path.to_path_buf(),
        why: why.into(),
    };
    if data.is_empty() {
        return Err(LoadError::Empty {
            file: path.to_path_buf(),
            why: "the file is empty".into(),
        });
    }
    if raw_given {
        return Ok(Format::Raw);
    }
    if let Some(format) = detect_content(data) {
        return Ok(format);
    }
    let ext = extension(path);
    if let Some(&(_, format)) = EXTENSIONS.iter().find(|(e, _)| *e == ext) {
        return Ok(format);
    }
    if obj::looks_like_obj(&data[..data.len().min(4096)]) {
        return Ok(Format::Obj);
    }
    if ext == "raw" {
        return Err(unknown(
            "a raw volume needs --raw-dims and --raw-type (see `lodstudio info --help`)",
        ));
    }
    Err(unknown(
        "not OBJ, glTF/GLB, PLY, OFF, NRRD, NIfTI-1 or INRIMAGE-4 by content or extension",
    ))
}

/// The format `data` announces by its first bytes (a magic, a header token
/// or glTF's JSON), if any.
fn detect_content(data: &[u8]) -> Option<Format> {
    if data.starts_with(b"glTF") {
        return Some(Format::Glb);
    }
    if data.starts_with(b"ply") && matches!(data.get(3), Some(b'\n' | b'\r')) {
        return Some(Format::Ply);
    }
    if data.starts_with(b"NRRD000") {
        return Some(Format::Nrrd);
    }
    if data.starts_with(b"#INRIMAGE-4#{") {
        return Some(Format::Inr);
    }
    if volume::is_nifti(data) {
        return Some(Format::Nifti);
    }
    let head = &data[..data.len().min(4096)];
    let first_token = head
        .split(|b| b.is_ascii_whitespace())
        .find(|t| !t.is_empty() && !t.starts_with(b"#"))
        .unwrap_or(&[]);
    if matches!(
        first_token,
        b"OFF" | b"COFF" | b"NOFF" | b"CNOFF" | b"STOFF" | b"NCOFF"
    ) {
        return Some(Format::Off);
    }
    if hierarchy_file::is_hierarchy(data) {
        return Some(Format::Hierarchy);
    }
    let trimmed = head.trim_ascii_start();
    if trimmed.starts_with(b"{") && head.windows(7).any(|w| w == b"\"asset\"") {
        return Some(Format::Gltf);
    }
    None
}

/// Model formats by file extension (after any `.gz`).
const EXTENSIONS: &[(&str, Format)] = &[
    ("obj", Format::Obj),
    ("off", Format::Off),
    ("gltf", Format::Gltf),
    ("glb", Format::Glb),
    ("ply", Format::Ply),
    ("nrrd", Format::Nrrd),
    ("nhdr", Format::Nrrd),
    ("nii", Format::Nifti),
    ("inr", Format::Inr),
];

/// Whether `path`'s extension names a model format (for folder inputs).
pub fn is_model_path(path: &Path) -> bool {
    let ext = extension(path);
    EXTENSIONS.iter().any(|(e, _)| *e == ext)
}

/// Lower-case extension, skipping a trailing `.gz`.
pub fn extension(path: &Path) -> String {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let name = name.strip_suffix(".gz").unwrap_or(&name);
    Path::new(name)
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// Mesh formats lodstudio writes, chosen by extension.
pub const MESH_WRITE_FORMATS: &str = "obj, ply, glb";

/// Encodes a mesh for `path`'s extension (`obj`, `ply` binary, `glb`).
pub fn encode_mesh(path: &Path, mesh: &TriMesh) -> Result<Vec<u8>, String> {
    // The formats store attributes per vertex: one vertex per wedge.
    let mesh = &mesh.unwelded();
    match extension(path).as_str() {
        "obj" => Ok(obj::write(mesh)),
        "ply" => Ok(ply::write_mesh(mesh, ply::Encoding::BinaryLittleEndian)),
        "glb" => Ok(gltf_writer::write_glb(mesh)),
        other => Err(format!(
            "cannot write {:?}: unknown mesh extension {other:?} (use {MESH_WRITE_FORMATS})",
            path.display().to_string()
        )),
    }
}

/// This process's name for temporary files: its id and a random number
/// drawn once (std's hasher keys are seeded from the OS's randomness).
pub fn process_token() -> &'static str {
    static TOKEN: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TOKEN.get_or_init(|| {
        use std::hash::{BuildHasher, Hasher};
        let random = std::collections::hash_map::RandomState::new()
            .build_hasher()
            .finish();
        format!("{}-{random:016x}", std::process::id())
    })
}

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, then rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let tmp = write_temporary(path, bytes)?;
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

/// Writes `bytes` to a new temporary file beside `path` (synced, named
/// `.NAME.tmpTOKEN-N`), for a rename into place; removed again on failure.
pub fn write_temporary(path: &Path, bytes: &[u8]) -> std::io::Result<PathBuf> {
    use std::io::Write;
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    // Unique per process and per write, so concurrent writes of one path
    // (an autosave and an export, two studios) never share a temporary; the
    // token tells processes apart where their ids are alike (pid 1 in every
    // container of a job writing to one shared volume).
    static WRITES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = WRITES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp: PathBuf = dir.join(format!(".{name}.tmp{}-{n}", process_token()));
    let result = (|| {
        let mut f = std::fs::File::create_new(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()
    })();
    match result {
        Ok(()) => Ok(tmp),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}
