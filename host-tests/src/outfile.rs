//! The files `pfe` commands write (plots, pages, reports): a new file, or one a `pfe` command
//! wrote before, which carries [`MARK`] on its first line. A file of the user's is never
//! replaced unless they say so (`--force`).
//!
//! ```
//! use host_tests::outfile::{write, OutError, MARK};
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

use std::io::Read;
use std::path::{Path, PathBuf};

/// The first line of every file a `pfe` command writes: a comment in Markdown, SVG and HTML
/// alike (before an SVG's root element and an HTML page's doctype, where comments may stand).
pub const MARK: &str = "<!-- written by pfe: a later pfe run may replace this file -->";

/// Why a file was not written.
#[derive(Debug)]
pub enum OutError {
    /// The file exists and no `pfe` command wrote it.
    Exists(PathBuf),
    /// Writing failed.
    Io(PathBuf, std::io::Error),
}

impl std::fmt::Display for OutError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Exists(p) => write!(
                f,
                "{}: the file exists and pfe did not write it (not replaced; --force replaces it)",
                p.display()
            ),
            Self::Io(p, e) => write!(f, "{}: cannot write: {e}", p.display()),
        }
    }
}

impl std::error::Error for OutError {}

/// Whether `path` may be written without `--force`: it does not exist, a `pfe` command wrote
/// it (its first line is [`MARK`]), or it is no file to lose (a device such as `/dev/null`, a
/// pipe).
pub fn may_write(path: &Path) -> bool {
    let Ok(meta) = std::fs::metadata(path) else {
        return path.symlink_metadata().is_err();
    };
    if meta.is_dir() {
        return false;
    }
    if !meta.is_file() {
        return true;
    }
    let mut head = vec![0u8; MARK.len()];
    std::fs::File::open(path).is_ok_and(|mut f| f.read_exact(&mut head).is_ok())
        && head == MARK.as_bytes()
}

/// `Err(Exists)` for the first of `paths` that may not be written (unless `force`): check
/// every output of a command before writing any.
pub fn check<'a>(paths: impl IntoIterator<Item = &'a Path>, force: bool) -> Result<(), OutError> {
    match paths.into_iter().find(|p| !force && !may_write(p)) {
        Some(p) => Err(OutError::Exists(p.to_path_buf())),
        None => Ok(()),
    }
}

/// Writes [`MARK`], a newline and `body` to `path`, creating its directory; refuses a file
/// no `pfe` command wrote unless `force`.
pub fn write(path: &Path, body: &str, force: bool) -> Result<(), OutError> {
    check([path], force)?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| OutError::Io(dir.to_path_buf(), e))?;
    }
    std::fs::write(path, format!("{MARK}\n{body}")).map_err(|e| OutError::Io(path.into(), e))
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
    fn a_directory_in_the_way_is_an_error_not_a_panic() {
        let d = dir("dir");
        let sub = d.join("sub");
        std::fs::create_dir_all(&sub).unwrap();
        assert!(write(&sub, "x", false).is_err());
        assert!(write(&sub, "x", true).is_err());
        // A new file in a new directory; a device is no file to lose.
        write(&d.join("new/deeper/x.svg"), "<svg/>", false).unwrap();
        assert!(may_write(Path::new("/dev/null")));
        // A dangling link is not followed into a new file.
        std::os::unix::fs::symlink(d.join("nowhere"), d.join("link")).unwrap();
        assert!(!may_write(&d.join("link")));
        std::fs::remove_dir_all(&d).unwrap();
    }
}
