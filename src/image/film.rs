//! The film: linear `f32` RGB, turned into 8 bits (clamped, optionally sRGB-encoded) only when written.
//! Files are written through [`write_atomically`]: never half an image under the real name.

use std::path::Path;

use glam::Vec3;

use super::codecs;
use crate::error::{Error, Result};
use crate::files::write_atomically;

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
        write_atomically(path, |file| {
            let mut out = Recorded::new(std::io::BufWriter::new(file));
            let encoded = self.encode(&mut out, format, srgb);
            out.finish(encoded)
        })
        .map_err(|e| Error::file(path, format!("cannot write the image: {e}")))
    }

    /// The image's bytes in `format`, as [`Film::write`] writes them (for standard output).
    pub fn encoded(&self, format: ImageFormat, srgb: bool) -> std::result::Result<Vec<u8>, String> {
        let mut out = Vec::new();
        self.encode(&mut out, format, srgb)?;
        Ok(out)
    }

    /// Encodes the image in `format` into `out`.
    fn encode(
        &self,
        out: &mut dyn std::io::Write,
        format: ImageFormat,
        srgb: bool,
    ) -> std::result::Result<(), String> {
        let (w, h) = (self.width, self.height);
        match format {
            ImageFormat::Png => codecs::write_png(out, w, h, &self.to_rgb8(srgb), srgb),
            ImageFormat::Ppm => codecs::write_ppm(out, w, h, &self.to_rgb8(srgb)).map_err(|e| e.to_string()),
            ImageFormat::Jpeg => codecs::write_jpeg(out, w, h, &self.to_rgb8(srgb), JPEG_QUALITY),
            ImageFormat::Exr => codecs::write_exr(out, w, h, &self.pixels).map_err(|e| e.to_string()),
        }
    }
}

/// Writes `rgb` (8-bit RGB bytes of a `width` × `height` image, row-major) as a PNG, atomically
/// ([`write_atomically`]), its colour space recorded as [`Film::write`] records it: for images made
/// as bytes (a heatmap's colours), which need no film.
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, rgb: &[u8], srgb: bool) -> Result<()> {
    write_atomically(path, |file| {
        let mut out = Recorded::new(std::io::BufWriter::new(file));
        let encoded = codecs::write_png(&mut out, width, height, rgb, srgb);
        out.finish(encoded)
    })
    .map_err(|e| Error::file(path, format!("cannot write the image: {e}")))
}

/// A writer that keeps the first I/O error it met: encoders wrap such errors in their own words, and
/// the user needs the system's ("File too large", "No space left on device").
struct Recorded<W> {
    inner: W,
    error: Option<std::io::Error>,
}

impl<W: std::io::Write> Recorded<W> {
    fn new(inner: W) -> Self {
        Recorded { inner, error: None }
    }

    /// The encoder's result, its output flushed: the system's error where one was met, else the
    /// encoder's.
    fn finish(mut self, encoded: std::result::Result<(), String>) -> std::result::Result<(), String> {
        let flushed = encoded.and_then(|()| std::io::Write::flush(&mut self).map_err(|e| e.to_string()));
        match self.error {
            Some(e) if flushed.is_err() => Err(e.to_string()),
            _ => flushed,
        }
    }

    fn record<T>(&mut self, result: std::io::Result<T>) -> std::io::Result<T> {
        if let Err(e) = &result
            && self.error.is_none()
        {
            self.error = Some(std::io::Error::new(e.kind(), e.to_string()));
        }
        result
    }
}

impl<W: std::io::Write> std::io::Write for Recorded<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let written = self.inner.write(buf);
        self.record(written)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        let flushed = self.inner.flush();
        self.record(flushed)
    }
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
        // A name that is only an extension (`.png`) is a hidden file of that format, though `Path`
        // sees no extension in it.
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        let ext = name.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase());
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::codecs::read_back;

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
        assert_eq!(read_back::rgb(&out).get_pixel(1, 1), [255, 128, 0]);
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
        let px = read_back::rgb(&jpg).get_pixel(1, 1);
        assert!(px[0] > 200 && (100..160).contains(&px[1]) && px[2] < 60, "{px:?}");
        // PPM is a binary P6 pixmap; EXR keeps the linear, unclamped floats.
        let ppm = dir.path().join("d.ppm");
        film.write(&ppm, false).unwrap();
        assert!(std::fs::read(&ppm).unwrap().starts_with(b"P6"));
        assert_eq!(read_back::rgb(&ppm).get_pixel(1, 1), [255, 128, 0]);
        film.pixels[0] = Vec3::new(2.5, 0.0, 0.0);
        let exr = dir.path().join("e.exr");
        film.write(&exr, false).unwrap();
        let (.., pixels) = read_back::exr(&exr);
        assert_eq!(
            (pixels.len(), pixels[0], pixels[4]),
            (6, [2.5, 0.0, 0.0], [1.0, 0.5, 0.0])
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
}
