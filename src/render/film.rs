//! The film: linear `f32` RGB, turned into 8 bits (clamped, optionally sRGB-encoded) only when written.
//! Files are written to a temporary name beside the target and renamed, so a failed or interrupted write
//! never leaves half an image under the real name.

use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::error::{Error, Result};

/// A width × height image of linear RGB.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major pixels, top row first.
    pub pixels: Vec<Vec3>,
}

/// The sRGB transfer function (IEC 61966-2-1) of a linear value in [0, 1].
pub fn srgb_encode(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// A linear value to 8 bits: clamp to [0, 1], optionally sRGB-encode, × 255, round.
pub fn to_u8(v: f32, srgb: bool) -> u8 {
    // NaN (never produced by the shader, but cheap to guard) becomes black.
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    let v = if srgb { srgb_encode(v) } else { v };
    (v * 255.0).round() as u8
}

impl Film {
    /// A black film.
    pub fn new(width: u32, height: u32) -> Self {
        Film {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    /// The pixel at column `x`, row `y`.
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[(y * self.width + x) as usize]
    }

    /// 8-bit RGB bytes, row-major.
    pub fn to_rgb8(&self, srgb: bool) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| [to_u8(p.x, srgb), to_u8(p.y, srgb), to_u8(p.z, srgb)])
            .collect()
    }

    /// Writes the image in the format its extension names ([`ImageFormat`]), atomically
    /// ([`write_atomically`]). PNG records its colour space: an sRGB chunk with `srgb`, else a gAMA
    /// chunk of 1.0 (linear values), so viewers show what the numbers mean.
    pub fn write(&self, path: &Path, srgb: bool) -> Result<()> {
        let format = ImageFormat::of(path)?;
        write_atomically(path, |tmp| {
            let file = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
            let out = std::io::BufWriter::new(file);
            match format {
                ImageFormat::Png => self.write_png(out, srgb).map_err(|e| e.to_string()),
                ImageFormat::Ppm => {
                    // A binary P6 pixmap: the image crate's default PNM flavour is PAM (P7), which
                    // few viewers read under a .ppm name.
                    use image::codecs::pnm::{PnmEncoder, PnmSubtype, SampleEncoding};
                    PnmEncoder::new(out)
                        .with_subtype(PnmSubtype::Pixmap(SampleEncoding::Binary))
                        .encode(
                            &self.to_rgb8(srgb)[..],
                            self.width,
                            self.height,
                            image::ExtendedColorType::Rgb8,
                        )
                        .map_err(|e| e.to_string())
                }
                ImageFormat::Jpeg => image::codecs::jpeg::JpegEncoder::new_with_quality(out, JPEG_QUALITY)
                    .encode(
                        &self.to_rgb8(srgb),
                        self.width,
                        self.height,
                        image::ExtendedColorType::Rgb8,
                    )
                    .map_err(|e| e.to_string()),
                ImageFormat::Exr => {
                    let data: Vec<f32> = self.pixels.iter().flat_map(|p| p.to_array()).collect();
                    image::Rgb32FImage::from_raw(self.width, self.height, data)
                        .expect("buffer size matches")
                        .write_with_encoder(image::codecs::openexr::OpenExrEncoder::new(out))
                        .map_err(|e| e.to_string())
                }
            }
        })
        .map_err(|e| Error::file(path, format!("cannot write the image: {e}")))
    }

    /// 8-bit RGB PNG with its colour space recorded.
    fn write_png(&self, out: impl std::io::Write, srgb: bool) -> std::result::Result<(), png::EncodingError> {
        encode_png(out, self.width, self.height, &self.to_rgb8(srgb), srgb)
    }
}

/// Writes `rgb` (8-bit RGB bytes of a `width` × `height` image, row-major) as a PNG, atomically
/// ([`write_atomically`]), its colour space recorded as [`Film::write`] records it: for images made
/// as bytes (a heatmap's colours), which need no film.
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8], srgb: bool) -> Result<()> {
    write_atomically(path, |tmp| {
        let file = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
        encode_png(std::io::BufWriter::new(file), width, height, rgb, srgb).map_err(|e| e.to_string())
    })
    .map_err(|e| Error::file(path, format!("cannot write the image: {e}")))
}

/// `rgb` as an 8-bit RGB PNG with its colour space: an sRGB chunk with `srgb`, else a gAMA chunk of
/// 1.0 (linear values).
fn encode_png(
    out: impl std::io::Write,
    width: u32,
    height: u32,
    rgb: &[u8],
    srgb: bool,
) -> std::result::Result<(), png::EncodingError> {
    let mut encoder = png::Encoder::new(out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    if srgb {
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    } else {
        encoder.set_source_gamma(png::ScaledFloat::new(1.0));
    }
    let mut writer = encoder.write_header()?;
    writer.write_image_data(rgb)?;
    writer.finish()
}

/// JPEG quality (of 100): high enough that the 8-bit rounding, not the codec, dominates the error.
const JPEG_QUALITY: u8 = 95;

/// The image formats the film is written in, named by the output's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// `.png`: 8-bit RGB with its colour space recorded.
    Png,
    /// `.ppm`: 8-bit binary pixmap (P6).
    Ppm,
    /// `.jpg`, `.jpeg`: 8-bit, lossy.
    Jpeg,
    /// `.exr`: linear, unclamped 32-bit float (`--srgb` does not apply).
    Exr,
}

impl ImageFormat {
    /// The format `path`'s extension names, or an error that lists the known ones.
    pub fn of(path: &Path) -> Result<Self> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("ppm") => Ok(ImageFormat::Ppm),
            Some("jpg" | "jpeg") => Ok(ImageFormat::Jpeg),
            Some("exr") => Ok(ImageFormat::Exr),
            _ => Err(Error::file(
                path,
                "unknown image format: expected a .png, .ppm, .jpg, .jpeg or .exr file name",
            )),
        }
    }
}

/// Checks, before any work, that `path` can be written as [`write_atomically`] will: its directory
/// exists and takes a new file (one is created there and removed), and what is at `path`, if
/// anything, is a regular file it may replace.
pub fn check_writable(path: &Path) -> Result<()> {
    check_target(path).map_err(|e| Error::file(path, e))?;
    let tmp = temporary_name(path);
    std::fs::File::create(&tmp)
        .and_then(|_| std::fs::remove_file(&tmp))
        .map_err(|e| Error::file(path, format!("cannot write in {}: {e}", dir_of(path).display())))
}

/// The directory a path's file goes in.
fn dir_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// What is at `path` may be replaced: nothing, or a regular file (not a directory, a link or a device,
/// which a rename would replace by a file).
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
        _ => Ok(()),
    }
}

/// Writes `path` through `write`, which fills a temporary file beside it (same directory, so the
/// rename is atomic), then renames that into place: a failed or interrupted write never leaves half a
/// file under the real name, and an existing file keeps its permissions. Refuses to replace anything
/// but a regular file. On failure the temporary is removed.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> std::result::Result<(), String>,
) -> std::result::Result<(), String> {
    check_target(path)?;
    let previous = std::fs::metadata(path).ok().map(|m| m.permissions());
    let tmp = temporary_name(path);
    let result = write(&tmp).and_then(|()| {
        if let Some(permissions) = previous {
            std::fs::set_permissions(&tmp, permissions).map_err(|e| e.to_string())?;
        }
        std::fs::rename(&tmp, path).map_err(|e| e.to_string())
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// `dir/.name.PID.tmp.ext`: in the same directory (so the rename is atomic), hidden, unique per process.
fn temporary_name(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    // Keep the real extension last: the encoder is chosen explicitly, but tools that glance at the
    // directory should still see what the file is.
    path.with_file_name(format!(".{name}.{}.tmp.{ext}", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eight_bit_conversion() {
        assert_eq!(to_u8(0.5, false), 128);
        assert_eq!(to_u8(2.0, false), 255);
        assert_eq!(to_u8(-1.0, false), 0);
        assert_eq!(to_u8(f32::NAN, false), 0);
        assert_eq!(to_u8(0.5, true), 188);
    }

    #[test]
    fn writes_atomically_and_reads_back() {
        let dir = tempfile::tempdir().unwrap();
        let mut film = Film::new(3, 2);
        film.pixels[4] = Vec3::new(1.0, 0.5, 0.0);
        let out = dir.path().join("a.png");
        film.write(&out, false).unwrap();
        let img = image::open(&out).unwrap().to_rgb8();
        assert_eq!(img.get_pixel(1, 1).0, [255, 128, 0]);
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no temporary left behind"
        );
        let bad = dir.path().join("missing-dir").join("b.png");
        assert!(film.write(&bad, false).is_err());
        assert!(film.write(&dir.path().join("c.gif"), false).is_err());
        // JPEG: lossy, but close at 95.
        let jpg = dir.path().join("f.JPEG");
        film.write(&jpg, false).unwrap();
        let px = image::open(&jpg).unwrap().to_rgb8().get_pixel(1, 1).0;
        assert!(px[0] > 200 && (100..160).contains(&px[1]) && px[2] < 60, "{px:?}");
        // PPM is a binary P6 pixmap; EXR keeps the linear, unclamped floats.
        let ppm = dir.path().join("d.ppm");
        film.write(&ppm, false).unwrap();
        assert!(std::fs::read(&ppm).unwrap().starts_with(b"P6"));
        assert_eq!(
            image::open(&ppm).unwrap().to_rgb8().get_pixel(1, 1).0,
            [255, 128, 0]
        );
        film.pixels[0] = Vec3::new(2.5, 0.0, 0.0);
        let exr = dir.path().join("e.exr");
        film.write(&exr, false).unwrap();
        assert_eq!(
            image::open(&exr).unwrap().to_rgb32f().get_pixel(0, 0).0,
            [2.5, 0.0, 0.0]
        );
    }

    /// PNG says what its numbers mean: gAMA 1.0 for the linear default, an sRGB chunk with `--srgb`.
    #[test]
    fn png_records_its_colour_space() {
        let dir = tempfile::tempdir().unwrap();
        let film = Film::new(2, 2);
        for (srgb, name) in [(false, "linear.png"), (true, "srgb.png")] {
            let path = dir.path().join(name);
            film.write(&path, srgb).unwrap();
            let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
            let reader = decoder.read_info().unwrap();
            let info = reader.info();
            if srgb {
                assert_eq!(info.srgb, Some(png::SrgbRenderingIntent::Perceptual));
            } else {
                assert_eq!(info.srgb, None);
                assert_eq!(info.gama_chunk, Some(png::ScaledFloat::new(1.0)));
            }
        }
    }

    /// A write that fails after its temporary file was created leaves no temporary and no output; an
    /// existing output keeps its permissions when replaced; links and directories are not replaced.
    #[cfg(unix)]
    #[test]
    fn atomic_writes_clean_up_keep_permissions_and_refuse_non_files() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("a.png");
        let failed = write_atomically(&out, |tmp| {
            std::fs::write(tmp, b"half").unwrap();
            Err("the encoder failed".into())
        });
        assert_eq!(failed.unwrap_err(), "the encoder failed");
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            0,
            "a temporary was left behind"
        );

        let film = Film::new(2, 1);
        film.write(&out, false).unwrap();
        std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o444)).unwrap();
        film.write(&out, true).unwrap();
        assert_eq!(
            std::fs::metadata(&out).unwrap().permissions().mode() & 0o777,
            0o444
        );

        let link = dir.path().join("link.png");
        std::os::unix::fs::symlink(&out, &link).unwrap();
        let e = film.write(&link, false).unwrap_err().to_string();
        assert!(e.contains("is not a regular file"), "{e}");
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        let sub = dir.path().join("sub.png");
        std::fs::create_dir(&sub).unwrap();
        assert!(
            film.write(&sub, false)
                .unwrap_err()
                .to_string()
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
        assert!(!dir.path().join("new.png").exists());
        assert_eq!(
            ImageFormat::of(Path::new("x.gif")).unwrap_err().to_string(),
            "x.gif: unknown image format: expected a .png, .ppm, .jpg, .jpeg or .exr file name"
        );
        assert_eq!(ImageFormat::of(Path::new("x.JPG")).unwrap(), ImageFormat::Jpeg);
    }
}
