//! Where whitted meets the filesystem. Inputs are opened only when they are regular files, without
//! blocking on a FIFO or reading a device without end. Every file a command writes is checked before
//! any work (`outputs.rs`: its directory and what it would replace, the snapshots' names, outputs apart
//! from each other and from the inputs; an image's format is `crate::image`'s to check) and written to a temporary beside the target, created exclusively
//! under an unpredictable name (so a link planted there is never followed and two writers never share
//! one), then renamed into place (`write.rs`): a failed, interrupted or killed write never leaves half
//! a file under the real name, nor a temporary behind.

use std::fs::File;
use std::io;
use std::path::Path;

mod outputs;
mod write;

pub use outputs::{apart, check_snapshots, same_file, snapshot};
pub use write::{check_writable, remove_temporaries, takes_new_files, write_atomically};

/// Opens `path` for reading if it is a regular file (a link to one is), else says why not. A device
/// may never end, and a FIFO would wait for a writer: it is opened without waiting (`O_NONBLOCK`, which
/// changes nothing for a regular file) and refused, as what was opened is checked, not the name.
pub fn open_regular(path: &Path) -> std::result::Result<File, String> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(&mut options, libc::O_NONBLOCK);
    let kind = |m: std::fs::Metadata| match m.file_type() {
        k if k.is_dir() => Err("it is a directory".to_string()),
        k if !k.is_file() => Err("it is not a regular file (a FIFO, a device or a socket)".to_string()),
        _ => Ok(()),
    };
    let file = options.open(path).map_err(|e| {
        // A socket cannot be opened at all: say what it is rather than why the opening failed.
        match std::fs::metadata(path).map(kind) {
            Ok(Err(what)) => what,
            _ => io_reason(&e),
        }
    })?;
    kind(file.metadata().map_err(|e| io_reason(&e))?)?;
    Ok(file)
}

/// The text of an I/O error without Rust's "(os error 2)" suffix.
pub fn io_reason(e: &io::Error) -> String {
    let s = e.to_string();
    match s.find(" (os error") {
        Some(i) => s[..i].to_string(),
        None => s,
    }
}

/// The directory a path's file goes in.
pub fn dir_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A FIFO is refused at once rather than waited on; a regular file behind a link is read.
    #[cfg(unix)]
    #[test]
    fn opens_regular_files_only_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo");
        let c = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).unwrap();
        // SAFETY: a valid C string.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        assert_eq!(
            open_regular(&fifo).unwrap_err(),
            "it is not a regular file (a FIFO, a device or a socket)"
        );
        assert!(open_regular(Path::new("/dev/zero")).is_err());
        assert_eq!(open_regular(dir.path()).unwrap_err(), "it is a directory");
        let file = dir.path().join("f");
        std::fs::write(&file, b"abc").unwrap();
        std::os::unix::fs::symlink(&file, dir.path().join("l")).unwrap();
        let mut text = String::new();
        std::io::Read::read_to_string(&mut open_regular(&dir.path().join("l")).unwrap(), &mut text).unwrap();
        assert_eq!(text, "abc");
    }
}
