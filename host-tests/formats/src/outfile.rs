//! The files `pfe` commands write (plots, pages, reports): a new file, or one a `pfe` command
//! wrote before, which carries [`MARK`] on its first line. A file of the user's is never
//! replaced unless they say so (`--force`), and no directory is created: an output goes
//! into a directory that exists.
//!
//! ```
//! use pfe_formats::outfile::{write, OutError, MARK};
//! let dir = std::env::temp_dir().join(format!("pfe-outfile-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! let (ours, theirs) = (dir.join("plot.svg"), dir.join("notes.svg"));
//! std::fs::write(&theirs, "<svg>my drawing</svg>")?;
//! write(&ours, "<svg/>", false)?; // new: written, marked
//! write(&ours, "<svg>again</svg>", false)?; // ours: replaced
//! assert!(std::fs::read_to_string(&ours)?.starts_with(MARK));
//! assert!(matches!(write(&theirs, "<svg/>", false), Err(OutError::Exists(_))));
//! assert_eq!(std::fs::read_to_string(&theirs)?, "<svg>my drawing</svg>");
//! std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// The first line of every file a `pfe` command writes: a comment in Markdown, SVG and HTML
/// alike (before an SVG's root element and an HTML page's doctype, where comments may stand).
pub const MARK: &str = "<!-- written by pfe: a later pfe run may replace this file -->";

/// Why a file was not written.
#[derive(Debug)]
pub enum OutError {
    /// The file exists and no `pfe` command wrote it (`--force` replaces it).
    Exists(PathBuf),
    /// The path is a directory or a device other than a character device or a pipe: never
    /// written, whatever `--force` says.
    NotAFile(PathBuf),
    /// The directory the file would go into does not exist (the file, the directory).
    NoDir(PathBuf, PathBuf),
    /// Writing failed.
    Io(PathBuf, std::io::Error),
}

impl OutError {
    /// Whether the user gave a path that cannot or may not be written (bad input), not a
    /// failure of the system.
    pub fn is_refusal(&self) -> bool {
        matches!(self, Self::Exists(_) | Self::NotAFile(_) | Self::NoDir(..))
    }
}

impl std::fmt::Display for OutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Exists(p) => write!(
                f,
                "{}: the file exists and pfe did not write it (not replaced; --force replaces it)",
                p.display()
            ),
            Self::NotAFile(p) => write!(f, "{}: not a file pfe can write", p.display()),
            Self::NoDir(p, d) => write!(
                f,
                "{}: no such directory {} (make it first)",
                p.display(),
                d.display()
            ),
            Self::Io(p, e) => write!(f, "{}: cannot write: {e}", p.display()),
        }
    }
}

impl std::error::Error for OutError {}

/// What is at an output path.
enum Target {
    /// Nothing (nor a dangling link).
    New,
    /// A regular file, possibly through a link: empty, or its first line [`MARK`] or not.
    File { ours: bool, link: bool },
    /// A character device (`/dev/null`) or a pipe: written through, nothing to lose.
    Stream,
    /// A directory, a block device, a socket, a dangling link.
    Other,
}

fn target(path: &Path) -> Target {
    use std::os::unix::fs::FileTypeExt;
    let Ok(meta) = std::fs::metadata(path) else {
        return if path.symlink_metadata().is_err() {
            Target::New
        } else {
            Target::Other
        };
    };
    let kind = meta.file_type();
    if kind.is_file() {
        let mut head = vec![0u8; MARK.len()];
        let marked = std::fs::File::open(path).is_ok_and(|mut f| f.read_exact(&mut head).is_ok())
            && head == MARK.as_bytes();
        let link = path
            .symlink_metadata()
            .is_ok_and(|m| m.file_type().is_symlink());
        Target::File {
            ours: marked || meta.len() == 0,
            link,
        }
    } else if kind.is_char_device() || kind.is_fifo() {
        Target::Stream
    } else {
        Target::Other
    }
}

/// Whether `path` may be written without `--force`: it does not exist, a `pfe` command wrote
/// it (its first line is [`MARK`]), it is empty, or it is no file to lose (a character device
/// such as `/dev/null`, a pipe).
pub fn may_write(path: &Path) -> bool {
    matches!(
        target(path),
        Target::New | Target::Stream | Target::File { ours: true, .. }
    )
}

/// Where a file that goes with the output `path` (a report's plot) is written: beside it, or
/// nowhere when `path` is a stream such as `/dev/null` (the directory is not the user's).
pub fn beside(path: &Path, name: &str) -> Option<PathBuf> {
    (!matches!(target(path), Target::Stream)).then(|| path.with_file_name(name))
}

/// [`OutError::NoDir`] when the directory a new file `path` would go into does not exist
/// (a relative name without a directory goes into the current one).
pub fn check_dir(path: &Path) -> Result<(), OutError> {
    match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) if !dir.is_dir() => Err(OutError::NoDir(path.to_path_buf(), dir.to_path_buf())),
        _ => Ok(()),
    }
}

/// The first of `paths` that may not be written (unless `force`), as an error: check every
/// output of a command before writing any. A new file's directory must exist ([`check_dir`]).
pub fn check<'a>(paths: impl IntoIterator<Item = &'a Path>, force: bool) -> Result<(), OutError> {
    for p in paths {
        match target(p) {
            Target::New => check_dir(p)?,
            Target::Other => return Err(OutError::NotAFile(p.to_path_buf())),
            Target::File { ours: false, .. } if !force => {
                return Err(OutError::Exists(p.to_path_buf()))
            }
            _ => {}
        }
    }
    Ok(())
}

/// Writes [`MARK`], a newline and `body` to `path`, in a directory that exists; refuses a
/// file no `pfe` command wrote unless `force`. A new file is created only if nothing appeared at
/// the path since the check (and removed if the write is cut short); an existing file is
/// replaced whole (a temporary file beside it, renamed over it); a link to a file, a device
/// or a pipe is written through.
pub fn write(path: &Path, body: &str, force: bool) -> Result<(), OutError> {
    check([path], force)?;
    let io = |e| OutError::Io(path.to_path_buf(), e);
    let text = format!("{MARK}\n{body}");
    let (new, through) = match target(path) {
        Target::New => (true, false),
        Target::File { link, .. } => (false, link),
        Target::Stream => (false, true),
        Target::Other => return Err(OutError::NotAFile(path.to_path_buf())),
    };
    if through {
        return std::fs::write(path, text).map_err(io);
    }
    if new {
        // Fails if anything appeared there since the check; removed again if cut short.
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(path)
            .map_err(|e| {
                if e.kind() == std::io::ErrorKind::AlreadyExists {
                    OutError::Exists(path.to_path_buf())
                } else {
                    io(e)
                }
            })?;
        return f.write_all(text.as_bytes()).map_err(|e| {
            let _ = std::fs::remove_file(path);
            io(e)
        });
    }
    let name = path.file_name().map(|n| n.to_string_lossy().to_string());
    let tmp = path.with_file_name(format!(
        ".{}.pfe-{}.tmp",
        name.unwrap_or_default(),
        std::process::id()
    ));
    let done = std::fs::write(&tmp, text).and_then(|()| std::fs::rename(&tmp, path));
    if done.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    done.map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("pfe-outfile-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn a_users_file_is_kept_unless_forced_and_ours_are_replaced() {
        let d = dir("keep");
        let (theirs, ours, short) = (d.join("a.md"), d.join("b.md"), d.join("c.md"));
        std::fs::write(&theirs, "# my notes\n").unwrap();
        // Shorter than the mark: not ours either.
        std::fs::write(&short, "<!--").unwrap();
        assert!(matches!(write(&theirs, "x", false), Err(OutError::Exists(p)) if p == theirs));
        assert!(matches!(
            write(&short, "x", false),
            Err(OutError::Exists(_))
        ));
        assert_eq!(std::fs::read_to_string(&theirs).unwrap(), "# my notes\n");
        write(&ours, "first", false).unwrap();
        write(&ours, "second", false).unwrap();
        assert_eq!(
            std::fs::read_to_string(&ours).unwrap(),
            format!("{MARK}\nsecond")
        );
        write(&theirs, "forced", true).unwrap();
        assert_eq!(
            std::fs::read_to_string(&theirs).unwrap(),
            format!("{MARK}\nforced")
        );
        // A check over several outputs names the first that may not be written.
        std::fs::write(&short, "mine").unwrap();
        let all = [ours.as_path(), short.as_path(), theirs.as_path()];
        assert!(matches!(check(all, false), Err(OutError::Exists(p)) if p == short));
        assert!(check(all, true).is_ok());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn a_directory_in_the_way_is_refused_even_when_forced() {
        let d = dir("dir");
        let sub = d.join("sub");
        std::fs::create_dir_all(&sub).unwrap();
        assert!(matches!(
            write(&sub, "x", false),
            Err(OutError::NotAFile(_))
        ));
        assert!(matches!(write(&sub, "x", true), Err(OutError::NotAFile(_))));
        assert!(sub.is_dir());
        // No directory is created for a new file, even with --force; a device is no file to
        // lose.
        for force in [false, true] {
            let deep = d.join("new/deeper/x.svg");
            assert!(
                matches!(write(&deep, "<svg/>", force), Err(OutError::NoDir(p, q)) if p == deep && q == d.join("new/deeper"))
            );
            assert!(!d.join("new").exists());
        }
        assert!(may_write(Path::new("/dev/null")));
        // A dangling link is not followed into a new file.
        std::os::unix::fs::symlink(d.join("nowhere"), d.join("link")).unwrap();
        assert!(!may_write(&d.join("link")));
        assert!(!d.join("nowhere").exists());
        // An empty file holds nothing to lose (a shell redirection, mktemp).
        let empty = d.join("empty.svg");
        std::fs::write(&empty, "").unwrap();
        write(&empty, "<svg/>", false).unwrap();
        // A link to pfe's file is written through: the link stays a link.
        let ours = d.join("ours.svg");
        write(&ours, "1", false).unwrap();
        let via = d.join("via.svg");
        std::os::unix::fs::symlink(&ours, &via).unwrap();
        write(&via, "2", false).unwrap();
        assert!(via.symlink_metadata().unwrap().file_type().is_symlink());
        assert_eq!(
            std::fs::read_to_string(&ours).unwrap(),
            format!("{MARK}\n2")
        );
        // No temporary file is left behind.
        let names: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .flatten()
            .map(|e| e.file_name())
            .collect();
        assert!(
            names.iter().all(|n| !n.to_string_lossy().ends_with(".tmp")),
            "{names:?}"
        );
        std::fs::remove_dir_all(&d).unwrap();
    }

    /// A report's plots go beside it, but not beside a device: `/dev/null`'s would land in
    /// /dev.
    #[test]
    fn companions_go_beside_a_file_and_nowhere_beside_a_device() {
        let d = dir("beside");
        assert_eq!(beside(&d.join("r.md"), "p.svg"), Some(d.join("p.svg")));
        std::fs::write(d.join("r.md"), "x").unwrap();
        assert_eq!(beside(&d.join("r.md"), "p.svg"), Some(d.join("p.svg")));
        assert_eq!(beside(Path::new("/dev/null"), "p.svg"), None);
        std::fs::remove_dir_all(&d).unwrap();
    }
}
