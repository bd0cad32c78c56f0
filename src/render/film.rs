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

    /// Writes the image; the format follows the extension: `.png`, `.ppm` (8-bit) or `.exr` (linear,
    /// unclamped 32-bit float, where `srgb` does not apply).
    pub fn write(&self, path: &Path, srgb: bool) -> Result<()> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        let format = match ext.as_str() {
            "png" => image::ImageFormat::Png,
            "ppm" => image::ImageFormat::Pnm,
            "exr" => image::ImageFormat::OpenExr,
            _ => {
                return Err(Error::file(
                    path,
                    "unknown image format: expected a .png, .ppm or .exr file name",
                ));
            }
        };
        let tmp = temporary_name(path);
        let result = match format {
            image::ImageFormat::OpenExr => {
                let data: Vec<f32> = self.pixels.iter().flat_map(|p| p.to_array()).collect();
                image::Rgb32FImage::from_raw(self.width, self.height, data)
                    .expect("buffer size matches")
                    .save_with_format(&tmp, format)
            }
            image::ImageFormat::Pnm => {
                // A binary P6 pixmap: the image crate's default PNM flavour is PAM (P7), which few
                // viewers read under a .ppm name.
                use image::codecs::pnm::{PnmEncoder, PnmSubtype, SampleEncoding};
                std::fs::File::create(&tmp)
                    .map_err(image::ImageError::IoError)
                    .and_then(|file| {
                        PnmEncoder::new(std::io::BufWriter::new(file))
                            .with_subtype(PnmSubtype::Pixmap(SampleEncoding::Binary))
                            .encode(
                                &self.to_rgb8(srgb)[..],
                                self.width,
                                self.height,
                                image::ExtendedColorType::Rgb8,
                            )
                    })
            }
            _ => image::RgbImage::from_raw(self.width, self.height, self.to_rgb8(srgb))
                .expect("buffer size matches")
                .save_with_format(&tmp, format),
        };
        let result = result
            .map_err(|e| e.to_string())
            .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
        result.map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            Error::file(path, format!("cannot write the image: {e}"))
        })
    }
}

/// `dir/.name.PID.tmp`: in the same directory (so the rename is atomic), hidden, unique per process.
pub(crate) fn temporary_name(path: &Path) -> PathBuf {
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
}
