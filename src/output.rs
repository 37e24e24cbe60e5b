//! Where a command's output goes, and writing it there: the one implementation behind every
//! `-o` of the CLI.
//!
//! What a path names decides how it is written ([`Destination::of`]):
//! - `-` is standard output, streamed;
//! - a path naming an open descriptor (`/dev/stdout`, `/dev/stderr`, `/dev/fd/N`,
//!   `/proc/self/fd/N`) is opened and appended to, whatever is behind it: a shell's `> file`
//!   keeps its file, nothing is renamed over it;
//! - a device, FIFO or other file that is not a regular file (`/dev/null`, a named pipe, a
//!   terminal) is opened and written directly, streamed;
//! - a regular file, or a path that does not exist yet, is written whole to a temporary file
//!   beside it and renamed over it, so it appears complete or not at all and a failure keeps
//!   the earlier file. A symbolic link is followed to its final target, which is the file
//!   replaced: the link stays a link. The replaced file keeps its permissions; a new file gets
//!   0644 less the umask. (A hard link's other names keep the old content, as with any
//!   rename.)
//!
//! A stream cannot be taken back: the commands compute everything before they write, so only a
//! failure of the stream itself (a reader that went away) can cut an output short. Side files
//! that a command writes beside its main output (a plan's `.txt`, identify's `.json`) are
//! written only when the main output is a file; see [`Destination::is_file`].

use std::io::{self, Write};
use std::path::{Path, PathBuf};

/// The `-o` value that means standard output.
pub const STDOUT: &str = "-";

/// How many symbolic links are followed before giving up (Linux's own limit).
const MAX_LINKS: usize = 40;

/// Where an output path leads.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Destination {
    /// `-`: standard output.
    Stdout,
    /// A descriptor path, device, FIFO or socket: opened and written directly. `append` is set
    /// for descriptor paths, so that a regular file behind one is appended to, as the shell
    /// left it, rather than overwritten from its start.
    Stream {
        /// The path as given (opened through any links).
        path: PathBuf,
        /// Whether to open it for appending.
        append: bool,
    },
    /// A regular file or a new one: written to a temporary file beside `target` and renamed
    /// over it.
    File {
        /// The path as given.
        path: PathBuf,
        /// The file that is replaced: `path` with every symbolic link followed.
        target: PathBuf,
    },
}

impl Destination {
    /// What `path` names, looked at now. Fails for a folder, a loop of links, or a path that
    /// cannot be looked at.
    pub fn of(path: &Path) -> io::Result<Self> {
        if path.as_os_str() == STDOUT {
            return Ok(Destination::Stdout);
        }
        if names_descriptor(path) {
            return Ok(Destination::Stream { path: path.to_path_buf(), append: true });
        }
        match std::fs::metadata(path) {
            Ok(m) if m.is_dir() => Err(io::Error::other("is a folder, not a file")),
            Ok(m) if !m.is_file() => Ok(Destination::Stream { path: path.to_path_buf(), append: false }),
            Ok(_) => Ok(Destination::File { path: path.to_path_buf(), target: follow_links(path)? }),
            Err(e) if e.kind() == io::ErrorKind::NotFound => {
                Ok(Destination::File { path: path.to_path_buf(), target: follow_links(path)? })
            }
            Err(e) => Err(e),
        }
    }

    /// Whether the output is a file (new, regular, or reached through links), beside which
    /// side files can go; false for standard output, devices, FIFOs and descriptor paths.
    pub fn is_file(&self) -> bool {
        matches!(self, Destination::File { .. })
    }
}

/// Whether `path` is `-` (standard output).
pub fn is_stdout(path: &Path) -> bool {
    path.as_os_str() == STDOUT
}

/// `path` for messages: "standard output" for `-`, else the path.
pub fn describe(path: &Path) -> String {
    if is_stdout(path) {
        "standard output".to_owned()
    } else {
        path.display().to_string()
    }
}

/// Whether `path` is spelled as one of the kernel's names for an open descriptor.
fn names_descriptor(path: &Path) -> bool {
    let Some(text) = path.to_str() else { return false };
    if matches!(text, "/dev/stdin" | "/dev/stdout" | "/dev/stderr") {
        return true;
    }
    let numbered = |prefix: &str| text.strip_prefix(prefix).is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()));
    numbered("/dev/fd/") || numbered("/proc/self/fd/") || numbered("/proc/thread-self/fd/")
}

/// `path` with every symbolic link of its last component followed (the folders on the way
/// are left as they are: the rename happens in the target's own folder). A dangling link
/// gives the path it points to, which will be created.
pub fn follow_links(path: &Path) -> io::Result<PathBuf> {
    let mut current = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match std::fs::symlink_metadata(&current) {
            Ok(m) if m.file_type().is_symlink() => {
                let points_to = std::fs::read_link(&current)?;
                current = if points_to.is_absolute() { points_to } else { folder_of(&current).join(points_to) };
            }
            Ok(_) => return Ok(current),
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(current),
            Err(e) => return Err(e),
        }
    }
    Err(io::Error::other(format!("more than {MAX_LINKS} symbolic links to follow (a loop?)")))
}

/// The folder holding `path` (`.` for a bare name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// Writes an output to `path` as its [`Destination`] says: `write` gets a buffered writer and
/// writes the content; it is flushed (and, for a file, synced and renamed into place) after.
/// On failure a file destination is left as it was.
pub fn write_output(path: &Path, write: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<()> {
    match Destination::of(path)? {
        Destination::Stdout => {
            let mut out = io::BufWriter::new(io::stdout().lock());
            write(&mut out)?;
            out.flush()
        }
        Destination::Stream { path, append } => {
            let file = std::fs::OpenOptions::new().write(true).append(append).open(&path)?;
            let mut out = io::BufWriter::new(file);
            write(&mut out)?;
            out.flush()
        }
        Destination::File { target, .. } => replace_file(&target, write),
    }
}

/// Writes `bytes` to `path` as [`write_output`] does.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_output(path, |out| out.write_all(bytes))
}

/// Writes `target` through a temporary file beside it, renamed over it once complete.
fn replace_file(target: &Path, write: impl FnOnce(&mut dyn Write) -> io::Result<()>) -> io::Result<()> {
    let dir = folder_of(target);
    if !dir.is_dir() {
        let problem = if dir.exists() { "is not a folder" } else { "does not exist" };
        return Err(io::Error::new(io::ErrorKind::NotFound, format!("folder {} {problem}", dir.display())));
    }
    // A replaced file keeps its mode; a new one gets what a plain create would (0644 less the
    // umask), not the temporary file's 0600.
    let kept = std::fs::metadata(target).ok().map(|m| m.permissions());
    let tmp = crate::table::readable_temp_file().prefix(".neurarm-").suffix(".tmp").tempfile_in(dir)?;
    if let Some(mode) = kept {
        tmp.as_file().set_permissions(mode)?;
    }
    {
        let mut out = io::BufWriter::new(tmp.as_file());
        write(&mut out)?;
        out.flush()?;
    }
    tmp.as_file().sync_all()?;
    tmp.persist(target).map_err(|e| e.error)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptor_paths_are_recognised_by_spelling() {
        for p in ["/dev/stdout", "/dev/stderr", "/dev/fd/1", "/proc/self/fd/12"] {
            assert!(names_descriptor(Path::new(p)), "{p}");
        }
        for p in ["/dev/null", "/dev/fd/", "/dev/fd/x", "/proc/self/fdinfo/1", "stdout", "-"] {
            assert!(!names_descriptor(Path::new(p)), "{p}");
        }
    }

    #[test]
    fn links_are_followed_to_the_end_and_loops_refused() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("sub")).unwrap();
        std::fs::write(d.join("sub/real.csv"), "x").unwrap();
        std::os::unix::fs::symlink("sub/real.csv", d.join("one")).unwrap();
        std::os::unix::fs::symlink(d.join("one"), d.join("two")).unwrap();
        std::os::unix::fs::symlink("missing.csv", d.join("sub/dangling")).unwrap();
        assert_eq!(follow_links(&d.join("two")).unwrap(), d.join("sub/real.csv"));
        assert_eq!(follow_links(&d.join("sub/dangling")).unwrap(), d.join("sub/missing.csv"));
        assert_eq!(follow_links(&d.join("new.csv")).unwrap(), d.join("new.csv"));
        std::os::unix::fs::symlink("loop_b", d.join("loop_a")).unwrap();
        std::os::unix::fs::symlink("loop_a", d.join("loop_b")).unwrap();
        assert!(follow_links(&d.join("loop_a")).unwrap_err().to_string().contains("symbolic links"));
    }

    #[test]
    fn destinations_by_kind() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        assert_eq!(Destination::of(Path::new("-")).unwrap(), Destination::Stdout);
        assert!(matches!(Destination::of(Path::new("/dev/null")).unwrap(), Destination::Stream { append: false, .. }));
        assert!(matches!(Destination::of(Path::new("/dev/stdout")).unwrap(), Destination::Stream { append: true, .. }));
        assert_eq!(Destination::of(d).unwrap_err().to_string(), "is a folder, not a file");
        let new = d.join("new.csv");
        assert_eq!(Destination::of(&new).unwrap(), Destination::File { path: new.clone(), target: new.clone() });
        assert!(Destination::of(&new).unwrap().is_file());
        assert!(!Destination::of(Path::new("/dev/null")).unwrap().is_file());
    }

    #[test]
    fn a_failed_write_keeps_the_file_and_leaves_no_temporary() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("out.txt");
        std::fs::write(&path, "before").unwrap();
        let e = write_output(&path, |w| {
            w.write_all(b"half")?;
            Err(io::Error::other("stopped"))
        })
        .unwrap_err();
        assert_eq!(e.to_string(), "stopped");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "before");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn a_replaced_file_keeps_its_mode() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("secret.csv");
        std::fs::write(&path, "old").unwrap();
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).unwrap();
        write_bytes(&path, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&path).unwrap(), "new");
        assert_eq!(std::fs::metadata(&path).unwrap().permissions().mode() & 0o777, 0o600);
    }

    #[test]
    fn a_missing_folder_is_named() {
        let dir = tempfile::tempdir().unwrap();
        let e = write_bytes(&dir.path().join("no/such/out.csv"), b"x").unwrap_err();
        assert!(e.to_string().contains("does not exist") && e.to_string().contains("no/such"), "{e}");
    }
}
