//! Images: the film a frame renders into (linear RGB), the file formats it is written in (PNG, PPM,
//! JPEG, OpenEXR; `film.rs` chooses by the file's name and writes through a temporary name, never half
//! an image under the real one) and the codecs that read and write them (`codecs.rs`).

pub(crate) mod codecs;
pub mod film;

pub use film::{Film, ImageFormat};

use std::path::Path;

use crate::error::Result;

/// Checks, before any work, that `path` names an image format (or, with `partial`, takes a `.partial`
/// file) and can be written as the render will write it ([`crate::files::check_writable`]).
pub fn check_output(path: &Path, partial: bool) -> Result<()> {
    if !partial {
        ImageFormat::of(path)?;
    }
    crate::files::check_writable(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_unknown_formats_and_missing_directories() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        assert_eq!(
            check_output(&d.join("out.gif"), false).unwrap_err().to_string(),
            format!(
                "{}: unknown image format: expected a .png, .ppm, .jpg, .jpeg or .exr file name",
                d.join("out.gif").display()
            )
        );
        check_output(&d.join("out.gif"), true).unwrap();
        check_output(&d.join("out.JPG"), false).unwrap();
        assert_eq!(
            check_output(&d.join("missing/out.png"), false)
                .unwrap_err()
                .to_string(),
            format!(
                "{}: the directory {} does not exist",
                d.join("missing/out.png").display(),
                d.join("missing").display()
            )
        );
    }
}
