//! What the front reads, and how: only regular files, each within a size limit checked before a
//! byte is read and again while reading (a file may grow), so that `/dev/zero`, a FIFO, a
//! directory or a file of a gigabyte is a clear error at once, never a hang or the machine's
//! memory. The MCP server reads only under its roots (`Roots`): a path is resolved, symlinks
//! included, before it is checked, and a refusal echoes nothing of the file.

use std::io::Read;
use std::os::unix::fs::{FileTypeExt, OpenOptionsExt};
use std::path::{Component, Path, PathBuf};

/// The largest file of each kind the front reads, in bytes, unless a flag raises it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limits {
    /// A `.lagra` source (also an inline `scene` string).
    pub scene: u64,
    /// A certificate (also a trace: an `mse:` target, what `lagra view` plays).
    pub certificate: u64,
    /// A state file.
    pub states: u64,
}

impl Default for Limits {
    fn default() -> Self {
        // a scene is text a person writes (the largest shipped one is a few kilobytes); a
        // certificate holds a line per checkpoint; a state file every state the checker saw
        Limits { scene: 16 << 20, certificate: 1 << 30, states: 16 << 30 }
    }
}

impl Limits {
    /// The defaults, each raised (or lowered) by its environment variable where one is set:
    /// `LAGRA_MAX_SCENE_BYTES`, `LAGRA_MAX_CERTIFICATE_BYTES`, `LAGRA_MAX_STATES_BYTES`.
    pub fn from_env() -> Limits {
        let d = Limits::default();
        let read =
            |name: &str, default: u64| std::env::var(name).ok().and_then(|v| v.trim().parse().ok()).unwrap_or(default);
        Limits {
            scene: read("LAGRA_MAX_SCENE_BYTES", d.scene),
            certificate: read("LAGRA_MAX_CERTIFICATE_BYTES", d.certificate),
            states: read("LAGRA_MAX_STATES_BYTES", d.states),
        }
    }
}

/// `n` bytes as a person reads it.
fn size(n: u64) -> String {
    match n {
        n if n >= 1 << 30 => format!("{:.1} GiB", n as f64 / (1u64 << 30) as f64),
        n if n >= 1 << 20 => format!("{:.1} MiB", n as f64 / (1u64 << 20) as f64),
        n => format!("{n} bytes"),
    }
}

/// Opens `path` for reading if it is a regular file of at most `limit` bytes. It is opened
/// without blocking (a FIFO would otherwise wait for a writer) and judged by what was opened,
/// so a file swapped after a check cannot slip through.
fn open(path: &Path, limit: u64) -> Result<std::fs::File, String> {
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let meta = file.metadata().map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let kind = meta.file_type();
    let not = |what: &str| Err(format!("cannot read {}: it is {what}, not a regular file", path.display()));
    match () {
        _ if kind.is_file() => {}
        _ if kind.is_dir() => return not("a directory"),
        _ if kind.is_fifo() => return not("a FIFO"),
        _ if kind.is_char_device() || kind.is_block_device() => return not("a device"),
        _ if kind.is_socket() => return not("a socket"),
        _ => return not("something else"),
    }
    if meta.len() > limit {
        return Err(format!(
            "cannot read {}: it is {}, over the limit of {} for this kind of file",
            path.display(),
            size(meta.len()),
            size(limit)
        ));
    }
    Ok(file)
}

/// Whether `path` is a regular file of at most `limit` bytes (for a reader that opens it itself).
pub fn regular(path: &Path, limit: u64) -> Result<(), String> {
    open(path, limit).map(drop)
}

/// The bytes of a regular file of at most `limit` bytes.
pub fn bytes(path: &Path, limit: u64) -> Result<Vec<u8>, String> {
    let mut out = vec![];
    open(path, limit)?
        .take(limit.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    if out.len() as u64 > limit {
        return Err(format!("cannot read {}: it grew past the limit of {} while read", path.display(), size(limit)));
    }
    Ok(out)
}

/// The text of a regular file of at most `limit` bytes.
pub fn text(path: &Path, limit: u64) -> Result<String, String> {
    String::from_utf8(bytes(path, limit)?).map_err(|_| format!("cannot read {}: it is not UTF-8 text", path.display()))
}

/// Text given inline (an MCP `scene` string), held to the same limit as a file of its kind.
pub fn inline<'a>(what: &str, text: &'a str, limit: u64) -> Result<&'a str, String> {
    if text.len() as u64 > limit {
        return Err(format!("`{what}` is {}, over the limit of {}", size(text.len() as u64), size(limit)));
    }
    Ok(text)
}

/// The folders a server may read under: its own (`--root`, the folder it started in by
/// default), narrowed to the client's where the client names some (`roots/list`).
#[derive(Clone, Debug)]
pub struct Roots {
    own: Vec<PathBuf>,
    client: Option<Vec<PathBuf>>,
    /// Relative paths are taken from here (the server's working folder).
    base: PathBuf,
}

/// `p` joined to `base` and with `.` and `..` taken out by the names alone.
fn lexical(base: &Path, p: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in base.join(p).components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

impl Roots {
    /// The server's roots, each resolved (it must exist and be a folder).
    pub fn new(dirs: &[PathBuf]) -> Result<Roots, String> {
        let base = std::env::current_dir().map_err(|e| format!("the working folder: {e}"))?;
        let own = dirs
            .iter()
            .map(|d| match std::fs::canonicalize(d) {
                Ok(c) if c.is_dir() => Ok(c),
                Ok(_) => Err(format!("root {}: not a folder", d.display())),
                Err(e) => Err(format!("root {}: {e}", d.display())),
            })
            .collect::<Result<_, _>>()?;
        Ok(Roots { own, client: None, base })
    }

    /// Narrows the roots to the client's (`file://` URIs; others are ignored). A client root
    /// that does not exist allows nothing.
    pub fn narrow(&mut self, uris: &[String]) {
        let dirs = uris
            .iter()
            .filter_map(|u| u.strip_prefix("file://"))
            .filter_map(|p| std::fs::canonicalize(percent_decoded(p)).ok())
            .collect();
        self.client = Some(dirs);
    }

    fn allows(&self, p: &Path) -> bool {
        let under = |roots: &[PathBuf]| roots.iter().any(|r| p.starts_with(r));
        under(&self.own) && self.client.as_deref().is_none_or(under)
    }

    /// The roots, for a message.
    pub fn describe(&self) -> String {
        let show = |r: &[PathBuf]| r.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ");
        match &self.client {
            None => show(&self.own),
            Some(c) => format!("{} (narrowed by the client to {})", show(&self.own), show(c)),
        }
    }

    /// `path` resolved, symlinks included, if it lies under the roots. The refusal is the same
    /// whether the file exists or not, so it tells nothing of what lies outside.
    pub fn resolve(&self, path: &str) -> Result<PathBuf, String> {
        let outside = || format!("{path} is outside the server's roots ({}): it reads nothing there", self.describe());
        let named = lexical(&self.base, Path::new(path));
        if !self.allows(&named) {
            return Err(outside());
        }
        let real = std::fs::canonicalize(&named).map_err(|e| format!("cannot read {path}: {e}"))?;
        if !self.allows(&real) {
            return Err(outside());
        }
        Ok(real)
    }
}

/// A `file://` URI's path with its `%XX` escapes decoded.
fn percent_decoded(p: &str) -> String {
    let b = p.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        match (b[i], b.get(i + 1).copied().and_then(hex), b.get(i + 2).copied().and_then(hex)) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (c, _, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// `sha256:` and the hex digest of a scene's source: what a certificate and a restart file name.
pub fn source_digest(source: &str) -> String {
    use sha2::{Digest, Sha256};
    let hex: String = Sha256::digest(source.as_bytes()).iter().map(|b| format!("{b:02x}")).collect();
    format!("sha256:{hex}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_is_not_a_regular_file_is_refused_at_once() {
        assert!(text(Path::new("/dev/zero"), 100).unwrap_err().ends_with("it is a device, not a regular file"));
        assert!(text(Path::new("/tmp"), 100).unwrap_err().contains("a directory"));
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
        assert!(text(&fifo, 100).unwrap_err().contains("a FIFO"));
    }

    #[test]
    fn a_file_over_its_limit_is_refused_before_it_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let big = dir.path().join("big.lagra");
        // sparse: a gigabyte that takes no disk
        std::fs::File::create(&big).unwrap().set_len(1 << 30).unwrap();
        let e = text(&big, Limits::default().scene).unwrap_err();
        assert!(e.ends_with("it is 1.0 GiB, over the limit of 16.0 MiB for this kind of file"), "{e}");
        std::fs::write(&big, "scene").unwrap();
        assert_eq!(text(&big, 5).unwrap(), "scene");
        assert!(text(&big, 4).is_err());
        assert!(inline("scene", "scene", 4).unwrap_err().contains("over the limit of 4 bytes"));
    }

    #[test]
    fn only_paths_under_the_roots_resolve() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().join("root");
        std::fs::create_dir(&root).unwrap();
        std::fs::write(root.join("a.lagra"), "x").unwrap();
        std::fs::write(dir.path().join("secret"), "x").unwrap();
        std::os::unix::fs::symlink(dir.path().join("secret"), root.join("link")).unwrap();
        let mut roots = Roots::new(&[root.clone()]).unwrap();
        let inside = root.join("a.lagra");
        assert_eq!(roots.resolve(inside.to_str().unwrap()).unwrap(), std::fs::canonicalize(&inside).unwrap());
        for p in [
            dir.path().join("secret"),
            root.join("../secret"),
            root.join("link"),
            root.join("../no-such-file"),
            PathBuf::from("/etc/passwd"),
        ] {
            let e = roots.resolve(p.to_str().unwrap()).unwrap_err();
            assert!(e.contains("outside the server's roots"), "{}: {e}", p.display());
        }
        // a client that names another folder narrows the roots to nothing here
        roots.narrow(&[format!("file://{}", dir.path().join("elsewhere%20too").display())]);
        assert!(roots.resolve(inside.to_str().unwrap()).is_err());
        roots.narrow(&[format!("file://{}", root.display())]);
        assert!(roots.resolve(inside.to_str().unwrap()).is_ok());
        assert_eq!(percent_decoded("/a%20b/%41"), "/a b/A");
    }
}
