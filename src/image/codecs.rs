//! The image files the renderer reads (skybox faces: PNG, JPEG) and writes (PNG, PPM, JPEG, OpenEXR).
//! PNG and JPEG go through the crates made for each (`png`, `zune-jpeg`, `jpeg-encoder`); PPM and
//! OpenEXR's uncompressed scanlines are a header and the samples, written here. The `image` crate,
//! which wraps the same codecs, brought colour management and every other format into the build for
//! none of this (a third of a fresh clone's dependency compile, `docs/testing.md`).

use std::fs::File;
use std::io::{self, BufReader, Write};
use std::path::Path;

use glam::Vec3;

/// An image file opened and its header read, not yet decoded: what the skybox checks before it decodes.
pub(crate) enum Decoder {
    /// A PNG, expanded to 8 or 16 bits a sample (palettes to RGB, transparency to alpha).
    Png(Box<png::Reader<BufReader<File>>>),
    /// A JPEG, decoded to 8-bit RGB.
    Jpeg(Box<zune_jpeg::JpegDecoder<BufReader<File>>>, (u32, u32)),
}

impl Decoder {
    /// Reads the header of the image in `file`, PNG or JPEG by its first bytes (`path` names it in
    /// errors only).
    pub(crate) fn open(file: File, path: &Path) -> Result<Self, String> {
        let mut file = BufReader::new(file);
        let magic = io::BufRead::fill_buf(&mut file).map_err(|e| e.to_string())?;
        if magic.starts_with(b"\x89PNG") {
            let mut decoder = png::Decoder::new(file);
            decoder.set_transformations(png::Transformations::EXPAND);
            let reader = decoder.read_info().map_err(|e| e.to_string())?;
            Ok(Decoder::Png(Box::new(reader)))
        } else if magic.starts_with(&[0xff, 0xd8]) {
            let options = zune_jpeg::zune_core::options::DecoderOptions::default()
                .jpeg_set_out_colorspace(zune_jpeg::zune_core::colorspace::ColorSpace::RGB)
                .set_strict_mode(false)
                .set_max_width(usize::MAX)
                .set_max_height(usize::MAX);
            let mut decoder = zune_jpeg::JpegDecoder::new_with_options(file, options);
            decoder.decode_headers().map_err(|e| e.to_string())?;
            let (w, h) = decoder.dimensions().ok_or("a JPEG without a frame header")?;
            Ok(Decoder::Jpeg(Box::new(decoder), (w as u32, h as u32)))
        } else {
            Err(format!(
                "neither a PNG nor a JPEG file (its first bytes), whatever {} says",
                path.file_name()
                    .map_or("its name".into(), |n| n.to_string_lossy())
            ))
        }
    }

    /// Width and height in pixels, from the header.
    pub(crate) fn dimensions(&self) -> (u32, u32) {
        match self {
            Decoder::Png(reader) => (reader.info().width, reader.info().height),
            Decoder::Jpeg(_, size) => *size,
        }
    }

    /// The bytes of the decoded image as the decoder gives it, before it becomes 8-bit RGB.
    pub(crate) fn decoded_bytes(&self) -> u64 {
        let (w, h) = self.dimensions();
        match self {
            Decoder::Png(reader) => {
                let (color, depth) = reader.output_color_type();
                let bytes = color.samples() * if depth == png::BitDepth::Sixteen { 2 } else { 1 };
                bytes as u64 * u64::from(w) * u64::from(h)
            }
            Decoder::Jpeg(..) => 3 * u64::from(w) * u64::from(h),
        }
    }

    /// The pixels as 8-bit RGB, row-major: grey replicated, alpha dropped, 16-bit samples rounded to 8
    /// (v / 257, to nearest).
    pub(crate) fn decode_rgb8(self) -> Result<Vec<u8>, String> {
        match self {
            Decoder::Jpeg(mut decoder, _) => decoder.decode().map_err(|e| e.to_string()),
            Decoder::Png(mut reader) => {
                let (color, depth) = reader.output_color_type();
                let mut buf = vec![0; reader.output_buffer_size().ok_or("a PNG too large to decode")?];
                reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
                let wide = depth == png::BitDepth::Sixteen;
                let size = if wide { 2 } else { 1 };
                let sample = |s: &[u8]| {
                    if wide {
                        ((u32::from(u16::from_be_bytes([s[0], s[1]])) + 128) / 257) as u8
                    } else {
                        s[0]
                    }
                };
                let texel = color.samples() * size;
                let grey = matches!(color, png::ColorType::Grayscale | png::ColorType::GrayscaleAlpha);
                Ok(buf
                    .chunks_exact(texel)
                    .flat_map(|t| {
                        if grey {
                            [sample(t); 3]
                        } else {
                            [sample(t), sample(&t[size..]), sample(&t[2 * size..])]
                        }
                    })
                    .collect())
            }
        }
    }
}

/// `rgb` (8-bit RGB, row-major) as a PNG with its colour space: an sRGB chunk with `srgb`, else a gAMA
/// chunk of 1.0 (linear values), so viewers show what the numbers mean.
pub(crate) fn write_png(
    out: &mut dyn Write,
    width: u32,
    height: u32,
    rgb: &[u8],
    srgb: bool,
) -> Result<(), String> {
    let mut encoder = png::Encoder::new(out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    if srgb {
        encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
    } else {
        encoder.set_source_gamma(png::ScaledFloat::new(1.0));
    }
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    writer.write_image_data(rgb).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())
}

/// `rgb` as a binary pixmap (Netpbm's P6, maxval 255), which every viewer reads under a `.ppm` name.
pub(crate) fn write_ppm(out: &mut dyn Write, width: u32, height: u32, rgb: &[u8]) -> io::Result<()> {
    write!(out, "P6\n{width} {height}\n255\n")?;
    out.write_all(rgb)
}

/// `rgb` as a baseline JPEG of `quality` (of 100). JPEG's sides are 16-bit: a larger image is an error.
pub(crate) fn write_jpeg(
    out: &mut dyn Write,
    width: u32,
    height: u32,
    rgb: &[u8],
    quality: u8,
) -> Result<(), String> {
    let side =
        |v: u32| u16::try_from(v).map_err(|_| format!("a JPEG holds at most 65535 pixels a side, not {v}"));
    let (width, height) = (side(width)?, side(height)?);
    let need = 3 * usize::from(width) * usize::from(height);
    if rgb.len() != need {
        return Err(format!(
            "{} bytes of RGB for {width}x{height} pixels, not {need}",
            rgb.len()
        ));
    }
    jpeg_encoder::Encoder::new(out, quality)
        .encode_image(Rgb8 { rgb, width, height })
        .map_err(|e| e.to_string())
}

/// 8-bit RGB rows for the JPEG encoder, which takes them converted to Y'CbCr a line at a time. The
/// encoder's own `encode` instantiates itself for each of its nine pixel layouts; this is the one used.
struct Rgb8<'a> {
    rgb: &'a [u8],
    width: u16,
    height: u16,
}

impl jpeg_encoder::ImageBuffer for Rgb8<'_> {
    fn get_jpeg_color_type(&self) -> jpeg_encoder::JpegColorType {
        jpeg_encoder::JpegColorType::Ycbcr
    }

    fn width(&self) -> u16 {
        self.width
    }

    fn height(&self) -> u16 {
        self.height
    }

    fn fill_buffers(&self, y: u16, buffers: &mut [Vec<u8>; 4]) {
        let row = 3 * usize::from(self.width);
        let start = usize::from(y) * row;
        for p in self.rgb[start..start + row].chunks_exact(3) {
            // ITU-T T.871's conversion, in the encoder's fixed point.
            let (luma, cb, cr) = jpeg_encoder::rgb_to_ycbcr(p[0], p[1], p[2]);
            buffers[0].push(luma);
            buffers[1].push(cb);
            buffers[2].push(cr);
        }
    }
}

/// `pixels` (row-major, top row first) as a single-part OpenEXR file of uncompressed scanlines, the
/// channels B, G, R (the format orders them by name) as 32-bit floats: linear and unclamped (OpenEXR
/// File Layout, openexr.com: magic, version, header attributes, the offset table, one line a chunk).
pub(crate) fn write_exr(out: &mut dyn Write, width: u32, height: u32, pixels: &[Vec3]) -> io::Result<()> {
    const FLOAT: i32 = 2;
    // The header's sizes are 32-bit signed.
    let line = 3 * 4 * u64::from(width);
    if line > i32::MAX as u64 || height > i32::MAX as u32 {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            "an image too large for OpenEXR's sizes",
        ));
    }
    let mut head = Vec::new();
    head.extend(20_000_630u32.to_le_bytes());
    head.extend(2u32.to_le_bytes());
    let mut attribute = |name: &str, kind: &str, value: &[u8]| {
        for text in [name, kind] {
            head.extend(text.as_bytes());
            head.push(0);
        }
        head.extend((value.len() as i32).to_le_bytes());
        head.extend(value);
    };
    let mut channels = Vec::new();
    for name in [b'B', b'G', b'R'] {
        channels.extend([name, 0]);
        channels.extend(FLOAT.to_le_bytes());
        channels.extend([0; 4]); // pLinear and three reserved bytes
        channels.extend(1i32.to_le_bytes()); // x sampling
        channels.extend(1i32.to_le_bytes()); // y sampling
    }
    channels.push(0);
    attribute("channels", "chlist", &channels);
    attribute("compression", "compression", &[0]);
    let window: Vec<u8> = [0, 0, width as i32 - 1, height as i32 - 1]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    attribute("dataWindow", "box2i", &window);
    attribute("displayWindow", "box2i", &window);
    attribute("lineOrder", "lineOrder", &[0]);
    attribute("pixelAspectRatio", "float", &1f32.to_le_bytes());
    attribute("screenWindowCenter", "v2f", &[0; 8]);
    attribute("screenWindowWidth", "float", &1f32.to_le_bytes());
    head.push(0);
    // A chunk: its line's y, its size, then each channel's samples of the line.
    let first = head.len() as u64 + 8 * u64::from(height);
    for y in 0..u64::from(height) {
        head.extend((first + y * (8 + line)).to_le_bytes());
    }
    out.write_all(&head)?;
    let mut chunk = Vec::with_capacity(8 + line as usize);
    for (y, row) in pixels.chunks_exact(width as usize).enumerate() {
        chunk.clear();
        chunk.extend((y as i32).to_le_bytes());
        chunk.extend((line as i32).to_le_bytes());
        for c in [2, 1, 0] {
            chunk.extend(row.iter().flat_map(|p| p[c].to_le_bytes()));
        }
        out.write_all(&chunk)?;
    }
    Ok(())
}

/// Images read back in tests, by the integration tests' decoders (apart from these writers).
#[cfg(test)]
#[path = "../../tests/common/images.rs"]
#[allow(dead_code)] // Each test uses a part.
pub(crate) mod read_back;
