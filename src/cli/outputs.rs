//! The files a command writes, checked before any work (before the scene is loaded or the parts are
//! read): a name the result could not be written to is refused at once, not after the render.

use std::path::{Path, PathBuf};

use whitted::render::film::{ImageFormat, check_writable};

/// Checks that `path` names an image format (or, with `partial`, takes a `.partial` file) and can be
/// written as the render will write it ([`check_writable`]).
pub fn check(path: &Path, partial: bool) -> whitted::Result<()> {
    if !partial {
        ImageFormat::of(path)?;
    }
    check_writable(path)
}

/// Creates `dir` for the snapshots of `output` (`--progressive-out`) and checks that they can be
/// written in it.
pub fn check_snapshots(dir: &Path, output: &Path) -> whitted::Result<()> {
    std::fs::create_dir_all(dir)
        .map_err(|e| whitted::Error::file(dir, format!("cannot create the directory: {e}")))?;
    check_writable(&snapshot(dir, output, 1))
}

/// The snapshot of `output` after `passes` passes, in `dir`: `OUT-0004.png` for `OUT.png`.
pub fn snapshot(dir: &Path, output: &Path, passes: u32) -> PathBuf {
    let stem = output.file_stem().unwrap_or_default().to_string_lossy();
    let ext = output.extension().unwrap_or_default().to_string_lossy();
    dir.join(format!("{stem}-{passes:04}.{ext}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_unknown_formats_and_missing_directories_and_names_snapshots() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        assert_eq!(
            check(&d.join("out.gif"), false).unwrap_err().to_string(),
            format!(
                "{}: unknown image format: expected a .png, .ppm, .jpg, .jpeg or .exr file name",
                d.join("out.gif").display()
            )
        );
        check(&d.join("out.gif"), true).unwrap();
        check(&d.join("out.JPG"), false).unwrap();
        assert_eq!(
            check(&d.join("missing/out.png"), false).unwrap_err().to_string(),
            format!(
                "{}: the directory {} does not exist",
                d.join("missing/out.png").display(),
                d.join("missing").display()
            )
        );
        assert_eq!(
            snapshot(Path::new("snaps"), Path::new("a/out.png"), 4),
            Path::new("snaps/out-0004.png")
        );
        check_snapshots(&d.join("s/t"), Path::new("out.exr")).unwrap();
        assert!(d.join("s/t").is_dir());
        assert_eq!(std::fs::read_dir(d.join("s/t")).unwrap().count(), 0);
        std::fs::write(d.join("file"), "").unwrap();
        let e = check_snapshots(&d.join("file"), Path::new("out.png")).unwrap_err();
        assert!(e.to_string().contains("cannot create the directory"), "{e}");
    }
}
