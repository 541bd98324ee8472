//! What an untrusted file may make lodstudio read: the one policy every
//! reader (glTF buffers and images), the batch cache's list of dependencies
//! and manifests go through.
//!
//! A reference resolves only to a regular file **inside the asset root**: the
//! model's (or manifest's) own folder, or the folder the user names with
//! `--asset-root`. `data:` URIs are fine. Absolute paths, `file:` and any other
//! scheme, `..` that climbs out, symlinks that point out (the check is made on
//! the canonical path, after every link is followed), devices, FIFOs and
//! folders are refused with an error naming the item. This is how trusted web
//! pipelines resolve glTF URIs (against the asset's base only; a browser
//! cannot read a local path at all). `--allow-outside-uris` turns the folder
//! check off for trusted local use; special files stay refused.
//!
//! Every file is opened non-blocking (a FIFO never blocks the open), checked
//! to be a regular file on the opened handle (no swap between check and
//! read), and read up to a limit (`/dev/zero` never fills memory).
//!
//! Process-wide, like [`super::limits`]: the CLI sets it once.

use std::io::Read;
use std::path::{Component, Path, PathBuf};
use std::sync::RwLock;

/// Where references may lead.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Policy {
    /// The folder references must stay in; `None`: the folder of the file
    /// that names them.
    pub asset_root: Option<PathBuf>,
    /// Follow references anywhere (trusted local use only).
    pub allow_outside: bool,
}

static POLICY: RwLock<Option<Policy>> = RwLock::new(None);

/// Puts `policy` in force for the rest of the process.
pub fn set(policy: Policy) {
    if let Ok(mut p) = POLICY.write() {
        *p = Some(policy);
    }
}

/// The policy in force (the default: each file's own folder, nothing outside).
pub fn current() -> Policy {
    POLICY
        .read()
        .ok()
        .and_then(|p| p.clone())
        .unwrap_or_default()
}

/// A reference that cannot be followed, or a file that cannot be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Refused {
    /// Bad input: the file names something it may not (exit 2).
    #[error("{0}")]
    Input(String),
    /// The environment failed (a permission, an I/O error: exit 1).
    #[error("{0}")]
    Io(String),
}

impl Refused {
    pub fn message(&self) -> &str {
        match self {
            Refused::Input(m) | Refused::Io(m) => m,
        }
    }
}

/// At most this many characters of a value are quoted in a message, so a
/// 200 MB string never becomes a 200 MB error line.
pub const EXCERPT_CHARS: usize = 80;

/// `value` as quoted in messages: whole when short, else its start and its length.
pub fn excerpt(value: &str) -> String {
    let count = value.chars().count();
    if count <= EXCERPT_CHARS {
        return format!("{value:?}");
    }
    let head: String = value.chars().take(EXCERPT_CHARS).collect();
    format!("{head:?}… ({count} characters)")
}

/// A message cut to a few hundred characters (a parser's message may quote
/// the whole bad value).
pub fn shorten(message: &str) -> String {
    const MAX: usize = 4 * EXCERPT_CHARS;
    let count = message.chars().count();
    if count <= MAX {
        return message.to_string();
    }
    let head: String = message.chars().take(MAX).collect();
    format!("{head}… ({count} characters)")
}

/// The root that references from a file in `folder` must stay in, canonical.
pub fn root_for(folder: &Path) -> Result<PathBuf, Refused> {
    let policy = current();
    let root = policy.asset_root.as_deref().unwrap_or(folder);
    let root = if root.as_os_str().is_empty() {
        Path::new(".")
    } else {
        root
    };
    root.canonicalize().map_err(|e| {
        Refused::Input(format!(
            "asset folder {}: cannot be resolved ({e})",
            root.display()
        ))
    })
}

/// What a URI stands for.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Target {
    /// A `data:` URI (decoded by its reader).
    Data,
    /// A regular file inside the root, canonical.
    File(PathBuf),
}

/// Resolves a glTF-style URI named by `what` (e.g. `image 0`) in a file of
/// `folder`: `data:` as is; a relative path, percent-decoded, under `folder`,
/// which must then lie inside the root. Everything else is refused.
pub fn resolve_uri(folder: &Path, uri: &str, what: &str) -> Result<Target, Refused> {
    if uri.starts_with("data:") {
        return Ok(Target::Data);
    }
    let outside = |why: &str| {
        Refused::Input(format!(
            "{what}: uri {} is outside the asset folder ({why})",
            excerpt(uri)
        ))
    };
    // A scheme: letters, digits, + - . before the first ':' (RFC 3986 §3.1).
    if let Some((scheme, _)) = uri.split_once(':')
        && !scheme.is_empty()
        && scheme
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    {
        if current().allow_outside && scheme.eq_ignore_ascii_case("file") {
            let rest = uri[5..].trim_start_matches("//");
            let path = urlencoding::decode(rest)
                .map_err(|_| outside("its path does not percent-decode to UTF-8"))?;
            return resolve_path(folder, Path::new(&*path), what).map(Target::File);
        }
        return Err(outside(&format!(
            "only relative paths and data: URIs are read, not {scheme}:"
        )));
    }
    let decoded =
        urlencoding::decode(uri).map_err(|_| outside("it does not percent-decode to UTF-8"))?;
    resolve_path(folder, Path::new(&*decoded), what).map(Target::File)
}

/// Resolves `path` (relative to `folder`, or absolute) named by `what` to
/// a canonical regular file inside the root: an absolute path or one
/// that leaves the root after its links are followed is refused (unless
/// the policy allows outside references), as are special files.
pub fn resolve_path(folder: &Path, path: &Path, what: &str) -> Result<PathBuf, Refused> {
    let policy = current();
    let shown = excerpt(&path.to_string_lossy());
    let outside = |why: &str| {
        Refused::Input(format!(
            "{what}: uri {shown} is outside the asset folder ({why})"
        ))
    };
    if path.is_absolute() && !policy.allow_outside {
        let root = root_for(folder)?;
        // An absolute path is taken only where it already lies inside the root.
        match path.canonicalize() {
            Ok(p) if p.starts_with(&root) => return check_file(p, what, &shown),
            _ => return Err(outside("an absolute path")),
        }
    }
    if path.as_os_str().is_empty() {
        return Err(Refused::Input(format!(
            "{what}: expected a file name, found an empty uri"
        )));
    }
    let joined = folder.join(path);
    let canonical = joined.canonicalize().map_err(|e| {
        // A path that climbs out is refused as such, even when it names nothing.
        if !policy.allow_outside && climbs_out(path) {
            outside("it climbs out with ..")
        } else {
            Refused::Input(format!("{what}: cannot open {shown} ({e})"))
        }
    })?;
    if !policy.allow_outside {
        let root = root_for(folder)?;
        if !canonical.starts_with(&root) {
            return Err(outside(
                if joined.components().any(|c| c == Component::ParentDir) {
                    "it climbs out with .."
                } else {
                    "a link leads out of it"
                },
            ));
        }
    }
    check_file(canonical, what, &shown)
}

/// Whether a relative path's `..` climb above its start at some point.
fn climbs_out(path: &Path) -> bool {
    let mut depth = 0i64;
    for c in path.components() {
        match c {
            Component::ParentDir => depth -= 1,
            Component::Normal(_) => depth += 1,
            _ => {}
        }
        if depth < 0 {
            return true;
        }
    }
    false
}

fn check_file(path: PathBuf, what: &str, shown: &str) -> Result<PathBuf, Refused> {
    match std::fs::metadata(&path) {
        Ok(m) if m.is_file() => Ok(path),
        Ok(m) => Err(Refused::Input(format!(
            "{what}: {shown} is {}, not a regular file",
            kind(&m)
        ))),
        Err(e) => Err(Refused::Input(format!("{what}: cannot open {shown} ({e})"))),
    }
}

/// "a folder", "a FIFO", "a device" …
fn kind(m: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = m.file_type();
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if m.is_dir() { "a folder" } else { "not a file" }
}

/// Reads a regular file of at most `limit` bytes: opened without blocking
/// (a FIFO answers at once), checked on the open handle (a device, FIFO or
/// folder is refused, bad input), and read no further than the limit.
/// What the file is called in messages: `path` as given.
pub fn read_regular(path: &Path, limit: u64) -> Result<Vec<u8>, Refused> {
    let shown = path.display();
    let file = open_nonblocking(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound | std::io::ErrorKind::InvalidInput => {
            Refused::Input(format!("{shown}: cannot read: {e}"))
        }
        _ => Refused::Io(format!("{shown}: cannot read: {e}")),
    })?;
    let meta = file
        .metadata()
        .map_err(|e| Refused::Io(format!("{shown}: cannot read: {e}")))?;
    if !meta.is_file() {
        return Err(Refused::Input(format!(
            "{shown}: is {}, not a regular file",
            kind(&meta)
        )));
    }
    if meta.len() > limit {
        return Err(Refused::Input(format!(
            "{shown}: {} is over the {} a file of this kind may have",
            super::limits::format_size(meta.len()),
            super::limits::format_size(limit)
        )));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| Refused::Io(format!("{shown}: cannot read: {e}")))?;
    if bytes.len() as u64 > limit {
        return Err(Refused::Input(format!(
            "{shown}: grew past the {} this file may have while it was read",
            super::limits::format_size(limit)
        )));
    }
    Ok(bytes)
}

fn open_nonblocking(path: &Path) -> std::io::Result<std::fs::File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    options.open(path)
}

/// Opens a regular file for reading as [`read_regular`] does (without
/// blocking, checked on the handle), for readers that stream it.
pub fn open_regular(path: &Path) -> std::io::Result<std::fs::File> {
    let file = open_nonblocking(path)?;
    if file.metadata()?.is_file() {
        Ok(file)
    } else {
        Err(std::io::Error::other("not a regular file"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree() -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        std::fs::create_dir_all(root.join("model/sub")).unwrap();
        std::fs::write(root.join("model/a.bin"), b"a").unwrap();
        std::fs::write(root.join("model/sub/b c.bin"), b"b").unwrap();
        std::fs::write(root.join("secret.bin"), b"s").unwrap();
        #[cfg(unix)]
        std::os::unix::fs::symlink(root.join("secret.bin"), root.join("model/link.bin")).unwrap();
        dir
    }

    #[test]
    fn references_stay_in_the_model_folder() {
        let dir = tree();
        let m = dir.path().join("model");
        let file = |p: &str| Target::File(dir.path().join(p).canonicalize().unwrap());
        assert_eq!(
            resolve_uri(&m, "a.bin", "buffer 0"),
            Ok(file("model/a.bin"))
        );
        assert_eq!(
            resolve_uri(&m, "sub/b%20c.bin", "buffer 0"),
            Ok(file("model/sub/b c.bin"))
        );
        assert_eq!(
            resolve_uri(&m, "sub/../a.bin", "buffer 0"),
            Ok(file("model/a.bin"))
        );
        assert_eq!(
            resolve_uri(&m, "data:application/octet-stream;base64,AA==", "b"),
            Ok(Target::Data)
        );
        let secret = dir.path().join("secret.bin");
        for (uri, why) in [
            ("../secret.bin", "climbs out"),
            ("../missing.bin", "climbs out"),
            ("link.bin", "a link leads out"),
            (secret.to_str().unwrap(), "an absolute path"),
            ("/etc/passwd", "an absolute path"),
            ("file:///etc/passwd", "not file:"),
            ("http://example.invalid/a.bin", "not http:"),
        ] {
            let e = resolve_uri(&m, uri, "image 0").unwrap_err();
            let Refused::Input(text) = &e else {
                panic!("{e:?}")
            };
            assert!(
                text.starts_with("image 0: uri") && text.contains("outside the asset folder"),
                "{text}"
            );
            assert!(text.contains(why), "{uri}: {text}");
        }
        for (uri, what) in [("sub", "a folder"), ("missing.bin", "cannot open")] {
            let e = resolve_uri(&m, uri, "image 0").unwrap_err();
            assert!(e.message().contains(what), "{e}");
        }
    }

    #[test]
    fn special_files_and_oversized_ones_are_refused_without_blocking() {
        let dir = tree();
        for dev in ["/dev/zero", "/dev/null"] {
            let e = read_regular(Path::new(dev), 1 << 20).unwrap_err();
            assert!(
                matches!(&e, Refused::Input(m) if m.contains("a device")),
                "{e:?}"
            );
        }
        let e = read_regular(dir.path(), 1 << 20).unwrap_err();
        assert!(e.message().contains("a folder"), "{e}");
        #[cfg(unix)]
        {
            let fifo = dir.path().join("fifo");
            let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
            // SAFETY: a valid C string; mkfifo only creates a file.
            assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
            let e = read_regular(&fifo, 1 << 20).unwrap_err();
            assert!(e.message().contains("a FIFO"), "{e}");
        }
        let a = dir.path().join("model/a.bin");
        assert_eq!(read_regular(&a, 1), Ok(b"a".to_vec()));
        assert!(
            read_regular(&a, 0)
                .unwrap_err()
                .message()
                .contains("over the")
        );
        assert_eq!(excerpt("short"), "\"short\"");
        let long = "x".repeat(10_000);
        assert!(excerpt(&long).len() < 120 && excerpt(&long).contains("10000 characters"));
        assert!(shorten(&long).len() < 400 && shorten("short") == "short");
    }
}
