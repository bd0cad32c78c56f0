//! Outputs written whole or not at all: a temporary beside the target, created exclusively under an
//! unpredictable name, renamed into place; the same checks run before any work.

use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use super::dir_of;
use crate::error::{Error, Result};

/// Checks, before any work, that `path` can be written as [`write_atomically`] will: its directory
/// exists and takes a new file (a temporary is made there under an unpredictable name and removed),
/// and what is at `path`, if anything, is a regular file this user may replace (`check_target`).
pub fn check_writable(path: &Path) -> Result<()> {
    check_target(path).map_err(|e| Error::file(path, e))?;
    takes_new_files(dir_of(path)).map_err(|e| Error::file(path, e))
}

/// Whether the directory `dir` takes new files: a temporary is made there under an unpredictable
/// name and removed. The error names the directory and the system's reason.
pub fn takes_new_files(dir: &Path) -> std::result::Result<(), String> {
    Temporary::new(&dir.join("check"))
        .map(drop)
        .map_err(|e| format!("cannot write in {}: {e}", dir.display()))
}

/// What is at `path` may be replaced: nothing, or a regular file whose mode lets this user write it.
/// A directory, a link or a device would be replaced by a file; a read-only file is kept, as `cp`
/// keeps it (its mode is read as written, even by root: whoever made it read-only meant to keep it).
fn check_target(path: &Path) -> std::result::Result<(), String> {
    // `Path` drops a trailing separator from its components: `o/q.png/` would pass as `o/q.png`
    // and fail only at the end of the render.
    if path
        .as_os_str()
        .as_encoded_bytes()
        .ends_with(std::path::MAIN_SEPARATOR_STR.as_bytes())
    {
        return Err("names a directory (it ends in a path separator): expected a file name".into());
    }
    let dir = dir_of(path);
    if !dir.is_dir() {
        return Err(format!("the directory {} does not exist", dir.display()));
    }
    match std::fs::symlink_metadata(path) {
        Ok(m) if !m.file_type().is_file() => {
            Err("is not a regular file (a directory, a link or a device); refusing to replace it".into())
        }
        Ok(m) if !writable_by_mode(&m) => Err(format!(
            "is read-only{}; refusing to replace it: make it writable or remove it first",
            mode_of(&m)
        )),
        _ => Ok(()),
    }
}

/// Whether the permission bits of `m` let this process's user write the file: the owner's bits if it
/// owns it, else the group's if it is in the file's group, else the others'.
#[cfg(unix)]
fn writable_by_mode(m: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    // SAFETY: these calls only read the process's credentials.
    let (uid, gid) = unsafe { (libc::geteuid(), libc::getegid()) };
    let in_group = gid == m.gid() || {
        let mut groups = [0 as libc::gid_t; 256];
        // SAFETY: the buffer holds `groups.len()` entries.
        let n = unsafe { libc::getgroups(groups.len() as libc::c_int, groups.as_mut_ptr()) };
        groups[..usize::try_from(n).unwrap_or(0)].contains(&m.gid())
    };
    let bit = if uid == m.uid() {
        0o200
    } else if in_group {
        0o020
    } else {
        0o002
    };
    m.mode() & bit != 0
}

#[cfg(not(unix))]
fn writable_by_mode(m: &std::fs::Metadata) -> bool {
    !m.permissions().readonly()
}

/// ` (mode 0444, owned by user 1000)`, for a refusal.
#[cfg(unix)]
fn mode_of(m: &std::fs::Metadata) -> String {
    use std::os::unix::fs::MetadataExt;
    format!(" (mode {:04o}, owned by user {})", m.mode() & 0o7777, m.uid())
}

#[cfg(not(unix))]
fn mode_of(_: &std::fs::Metadata) -> String {
    String::new()
}

/// Writes `path` through `write`, which fills a new temporary file beside it (same directory, so the
/// rename is atomic), then renames that into place: a failed or interrupted write never leaves half a
/// file under the real name, and an existing file keeps its permissions (a new one gets the usual
/// `0666` less the umask). Refuses to replace anything but a regular file this user may write. On
/// failure the temporary is removed.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut File) -> std::result::Result<(), String>,
) -> std::result::Result<(), String> {
    check_target(path)?;
    let previous = std::fs::metadata(path).ok().map(|m| m.permissions());
    let mut tmp = Temporary::new(path).map_err(|e| {
        format!(
            "cannot create a temporary file in {}: {e}",
            dir_of(path).display()
        )
    })?;
    write(&mut tmp.file)?;
    tmp.file.flush().map_err(|e| e.to_string())?;
    if let Some(permissions) = previous {
        tmp.file.set_permissions(permissions).map_err(|e| e.to_string())?;
    }
    tmp.persist(path)
}

/// A temporary file beside its target: `.NAME.` then six random characters then `.tmp`, `NAME` the
/// target's name cut to 64 bytes (so that any name a file system takes leaves room for them). Made
/// with `O_CREAT | O_EXCL`, so it is never a file or a link that was there before. Listed in
/// [`LIVE`] while it exists, so that a process ended by a signal removes it
/// ([`remove_temporaries`]); dropped, it is removed.
struct Temporary {
    file: File,
    path: PathBuf,
    /// Renamed to its target: nothing left to remove.
    renamed: bool,
}

/// The temporaries that exist now, for [`remove_temporaries`].
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

impl Temporary {
    fn new(target: &Path) -> std::io::Result<Self> {
        let name = target.file_name().unwrap_or_default().to_string_lossy();
        let mut cut = name.len().min(64);
        while !name.is_char_boundary(cut) {
            cut -= 1;
        }
        let prefix = format!(".{}.", &name[..cut]);
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp").rand_bytes(6);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            builder.permissions(std::fs::Permissions::from_mode(0o666));
        }
        let mut live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
        // Kept from here: a signal's clean-up cannot run between the file's creation and its listing.
        let (file, path) = builder.tempfile_in(dir_of(target))?.keep().map_err(|e| e.error)?;
        live.push(path.clone());
        Ok(Temporary {
            file,
            path,
            renamed: false,
        })
    }

    /// Renames the temporary to `target`.
    fn persist(mut self, target: &Path) -> std::result::Result<(), String> {
        let live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
        std::fs::rename(&self.path, target).map_err(|e| e.to_string())?;
        self.renamed = true;
        drop(live);
        Ok(())
    }
}

impl Drop for Temporary {
    fn drop(&mut self) {
        let mut live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
        if !self.renamed {
            let _ = std::fs::remove_file(&self.path);
        }
        live.retain(|p| *p != self.path);
    }
}

/// Removes every temporary file this process has open: for a process about to end on a signal, which
/// runs no destructors. Holds the list until the process ends, so no new temporary is made after.
pub fn remove_temporaries() {
    let live = LIVE.lock().unwrap_or_else(|e| e.into_inner());
    for path in live.iter() {
        let _ = std::fs::remove_file(path);
    }
    std::mem::forget(live);
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    /// A write that fails after its temporary was created leaves no temporary and no output; an
    /// existing output keeps its permissions when replaced; links, directories and read-only files are
    /// not replaced.
    #[cfg(unix)]
    #[test]
    fn atomic_writes_clean_up_keep_permissions_and_refuse_what_they_must_not_replace() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.png");
        let failed = write_atomically(&out, |file| {
            file.write_all(b"half").unwrap();
            Err("the encoder failed".into())
        });
        assert_eq!(failed.unwrap_err(), "the encoder failed");
        assert_eq!(
            entries(dir.path()),
            Vec::<String>::new(),
            "a temporary was left behind"
        );

        write_atomically(&out, |f| f.write_all(b"one").map_err(|e| e.to_string())).unwrap();
        std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o640)).unwrap();
        write_atomically(&out, |f| f.write_all(b"two").map_err(|e| e.to_string())).unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"two");
        assert_eq!(
            std::fs::metadata(&out).unwrap().permissions().mode() & 0o777,
            0o640
        );

        std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o444)).unwrap();
        let e = write_atomically(&out, |f| f.write_all(b"three").map_err(|e| e.to_string())).unwrap_err();
        assert!(e.starts_with("is read-only (mode 0444, owned by user "), "{e}");
        assert!(
            e.ends_with("refusing to replace it: make it writable or remove it first"),
            "{e}"
        );
        assert_eq!(std::fs::read(&out).unwrap(), b"two");
        let e = check_writable(&out).unwrap_err().to_string();
        assert!(e.contains("is read-only"), "{e}");

        let link = dir.path().join("link.png");
        std::os::unix::fs::symlink(&out, &link).unwrap();
        let e = write_atomically(&link, |_| Ok(())).unwrap_err();
        assert!(e.contains("is not a regular file"), "{e}");
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        let sub = dir.path().join("sub.png");
        std::fs::create_dir(&sub).unwrap();
        assert!(
            write_atomically(&sub, |_| Ok(()))
                .unwrap_err()
                .contains("is not a regular file")
        );
        assert_eq!(
            check_writable(&dir.path().join("nowhere/x.png"))
                .unwrap_err()
                .to_string(),
            format!(
                "{}: the directory {} does not exist",
                dir.path().join("nowhere/x.png").display(),
                dir.path().join("nowhere").display()
            )
        );
        check_writable(&dir.path().join("new.png")).unwrap();
        assert_eq!(entries(dir.path()), ["a.png", "link.png", "sub.png"]);
    }

    /// The temporary is a new file under a name no other writer can hold or predict: a link or a file
    /// planted at any name derived from the target (its process id included) is left alone, two
    /// temporaries of one target in one process (as two containers' processes with the same id) are
    /// apart, and a name of 255 bytes still leaves room for the temporary's.
    #[cfg(unix)]
    #[test]
    fn temporaries_are_new_unpredictable_and_short() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.png");
        let victim = dir.path().join("victim");
        std::fs::write(&victim, b"precious").unwrap();
        let pid = std::process::id();
        for planted in [format!(".out.png.{pid}.tmp.png"), format!(".out.png.{pid}.tmp")] {
            std::os::unix::fs::symlink(&victim, dir.path().join(planted)).unwrap();
        }
        let (a, b) = (Temporary::new(&out).unwrap(), Temporary::new(&out).unwrap());
        assert_ne!(a.path, b.path);
        for t in [&a, &b] {
            let name = t.path.file_name().unwrap().to_str().unwrap();
            assert!(name.starts_with(".out.png.") && name.ends_with(".tmp"), "{name}");
            assert!(!name.contains(&pid.to_string()), "{name}");
        }
        drop((a, b));
        write_atomically(&out, |f| f.write_all(b"image").map_err(|e| e.to_string())).unwrap();
        assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
        assert!(std::fs::symlink_metadata(&out).unwrap().file_type().is_file());

        let long = dir.path().join(format!("{}.png", "n".repeat(251)));
        check_writable(&long).unwrap();
        write_atomically(&long, |f| f.write_all(b"x").map_err(|e| e.to_string())).unwrap();
        assert_eq!(std::fs::read(&long).unwrap(), b"x");
    }

    /// Temporaries are listed while they exist, and [`remove_temporaries`]' list is what a signal
    /// removes.
    #[test]
    fn live_temporaries_are_listed_until_renamed_or_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("x.exr");
        let listed = |p: &Path| LIVE.lock().unwrap().iter().any(|q| q == p);
        let t = Temporary::new(&out).unwrap();
        let path = t.path.clone();
        assert!(listed(&path) && path.exists());
        drop(t);
        assert!(!listed(&path) && !path.exists());
        let t = Temporary::new(&out).unwrap();
        let path = t.path.clone();
        t.persist(&out).unwrap();
        assert!(!listed(&path) && out.exists());
    }
}
