//! The files a command writes, checked before any work (before the scene is loaded or the parts are
//! read): a name the result could not be written to is refused at once, not after the render.

use std::path::{Path, PathBuf};

use super::{check_writable, takes_new_files};
use crate::error::{Error, Result};

/// Whether `a` and `b` are one file (the same device and inode, whatever the names; links followed).
pub fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(a), Ok(b)) => (a.dev(), a.ino()) == (b.dev(), b.ino()),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        matches!((std::fs::canonicalize(a), std::fs::canonicalize(b)), (Ok(a), Ok(b)) if a == b)
    }
}

/// Checks that `dir`, the snapshots' directory (`--progressive-out`), is none of the render's `files`
/// (each with what it is: the output image, the stop file, a heatmap's file), nor under one.
pub fn apart(dir: &Path, files: &[(&Path, &str)]) -> Result<()> {
    // Lexically, as the names are written: none may exist yet.
    let same = |other: &Path| match (std::path::absolute(dir), std::path::absolute(other)) {
        (Ok(a), Ok(b)) => a.starts_with(b),
        _ => false,
    };
    match files.iter().find(|(file, _)| same(file)) {
        None => Ok(()),
        Some((_, what)) => Err(Error::file(
            dir,
            format!(
                "--progressive-out names {what}, or a directory under it: expected a directory of its own for the snapshots"
            ),
        )),
    }
}

/// Checks, without creating anything, that the snapshots of `output` (`--progressive-out`, after any
/// of passes 1 to `passes`) can be written in `dir`: it is a directory, or can be made one (it is made
/// at the first snapshot, so that a render refused later leaves nothing behind), and no name a
/// snapshot may take there is held by a directory, a link or a device.
pub fn check_snapshots(dir: &Path, output: &Path, passes: u32) -> Result<()> {
    // The nearest directory that exists: `dir` itself, or where it will be made.
    let mut existing = dir;
    while !existing.as_os_str().is_empty() && std::fs::symlink_metadata(existing).is_err() {
        existing = existing.parent().unwrap_or(Path::new(""));
    }
    let existing = if existing.as_os_str().is_empty() {
        Path::new(".")
    } else {
        existing
    };
    if !existing.is_dir() {
        return Err(Error::file(
            existing,
            "is not a directory: --progressive-out cannot keep its snapshots under it",
        ));
    }
    if existing != dir {
        // Made at the first snapshot: what exists of its path must take new entries.
        return takes_new_files(existing)
            .map_err(|e| Error::file(dir, format!("cannot make the directory: {e}")));
    }
    let entries =
        std::fs::read_dir(dir).map_err(|e| Error::file(dir, format!("cannot read the directory: {e}")))?;
    for entry in entries.flatten() {
        let taken = snapshot_pass(&entry.file_name(), output).is_some_and(|n| (1..=passes).contains(&n));
        if taken {
            check_writable(&entry.path())?;
        }
    }
    check_writable(&snapshot(dir, output, 1))
}

/// The pass of a file name that [`snapshot`] gives `output`, if it is one.
fn snapshot_pass(name: &std::ffi::OsStr, output: &Path) -> Option<u32> {
    let (stem, ext) = stem_and_extension(output);
    let name = name.to_str()?;
    let digits = name
        .strip_prefix(&*stem)?
        .strip_prefix('-')?
        .strip_suffix(&*ext)?
        .strip_suffix('.')?;
    let n: u32 = digits.parse().ok()?;
    (digits.bytes().all(|b| b.is_ascii_digit()) && format!("{n:04}") == digits).then_some(n)
}

fn stem_and_extension(output: &Path) -> (std::borrow::Cow<'_, str>, std::borrow::Cow<'_, str>) {
    (
        output.file_stem().unwrap_or_default().to_string_lossy(),
        output.extension().unwrap_or_default().to_string_lossy(),
    )
}

/// The snapshot of `output` after `passes` passes, in `dir`: `OUT-0004.png` for `OUT.png`.
pub fn snapshot(dir: &Path, output: &Path, passes: u32) -> PathBuf {
    let (stem, ext) = stem_and_extension(output);
    dir.join(format!("{stem}-{passes:04}.{ext}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_snapshots_and_makes_their_directory_only_when_writing() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        assert_eq!(
            snapshot(Path::new("snaps"), Path::new("a/out.png"), 4),
            Path::new("snaps/out-0004.png")
        );
        // A directory to be made is not made until the first snapshot.
        check_snapshots(&d.join("s/t"), Path::new("out.exr"), 4).unwrap();
        assert!(!d.join("s").exists());
        std::fs::write(d.join("file"), "").unwrap();
        let e = check_snapshots(&d.join("file/t"), Path::new("out.png"), 4).unwrap_err();
        assert!(
            e.to_string()
                .ends_with("is not a directory: --progressive-out cannot keep its snapshots under it"),
            "{e}"
        );
    }

    /// The snapshots' directory is not the output or the stop file, and a
    /// snapshot name a directory holds is refused before the render, not after half of it.
    #[test]
    fn refuses_snapshots_that_could_not_be_written() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let (out, stop) = (d.join("x.png"), d.join("x.png.partial"));
        let files = [
            (out.as_path(), "the output image"),
            (stop.as_path(), "the file an interrupted render keeps its sums in"),
        ];
        let e = apart(&out, &files).unwrap_err().to_string();
        assert!(
            e.ends_with(
                "--progressive-out names the output image, or a directory under it: expected a directory of its own for the snapshots"
            ),
            "{e}"
        );
        assert!(!out.exists());
        let e = apart(&d.join("./x.png.partial"), &files).unwrap_err().to_string();
        assert!(
            e.contains("names the file an interrupted render keeps its sums in"),
            "{e}"
        );
        apart(&d.join("pg"), &files).unwrap();
        apart(&d.join("x.png-snaps"), &files).unwrap();
        let e = apart(&d.join("x.png.partial/snaps"), &files)
            .unwrap_err()
            .to_string();
        assert!(e.contains("a directory under it"), "{e}");
        let snaps = d.join("pg");
        std::fs::create_dir_all(snaps.join("x-0002.png")).unwrap();
        let e = check_snapshots(&snaps, &out, 4).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!(
                "{}: is not a regular file",
                snaps.join("x-0002.png").display()
            )),
            "{e}"
        );
        // Not a name a render of 1 pass, or of this output, writes.
        check_snapshots(&snaps, &out, 1).unwrap();
        check_snapshots(&snaps, &d.join("y.png"), 4).unwrap();
        assert_eq!(snapshot_pass("x-0002.png".as_ref(), &out), Some(2));
        assert_eq!(snapshot_pass("x-12345.png".as_ref(), &out), Some(12345));
        for name in [
            "x-002.png",
            "x-00002.png",
            "x-+002.png",
            "x-0002.exr",
            "y-0002.png",
            "x0002.png",
        ] {
            assert_eq!(snapshot_pass(name.as_ref(), &out), None, "{name}");
        }
    }
}
