//! Image files read back by decoders apart from the writers under test: PNG through the `png` crate,
//! JPEG through `zune-jpeg`, binary PPM by its Netpbm header, OpenEXR through the `exr` crate. Shared by
//! the integration tests (as `common::images`) and the library's unit tests (`image/codecs.rs`).

use std::path::Path;

/// An image's pixels as 8-bit RGB, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct Rgb8 {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u8>,
}

impl Rgb8 {
    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    pub fn dimensions(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The pixel at column `x`, row `y`.
    pub fn get_pixel(&self, x: u32, y: u32) -> [u8; 3] {
        assert!(
            x < self.width && y < self.height,
            "({x}, {y}) outside {}x{}",
            self.width,
            self.height
        );
        let i = 3 * (y as usize * self.width as usize + x as usize);
        [self.data[i], self.data[i + 1], self.data[i + 2]]
    }

    /// The pixels, row by row.
    pub fn pixels(&self) -> impl Iterator<Item = [u8; 3]> + '_ {
        self.data.chunks_exact(3).map(|p| [p[0], p[1], p[2]])
    }
}

/// An 8-bit image file's pixels (PNG, JPEG or binary PPM, by its first bytes), read by decoders apart
/// from the command's writers: the `png` and `zune-jpeg` crates' decoders, Netpbm's header here.
pub fn rgb(path: &Path) -> Rgb8 {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    decode_rgb8(&bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// [`rgb`] of bytes in memory.
pub fn decode_rgb8(bytes: &[u8]) -> Result<Rgb8, String> {
    if bytes.starts_with(b"\x89PNG") {
        let reader = png::Decoder::new(std::io::Cursor::new(bytes));
        let mut reader = reader.read_info().map_err(|e| e.to_string())?;
        let mut data = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut data).map_err(|e| e.to_string())?;
        if (info.color_type, info.bit_depth) != (png::ColorType::Rgb, png::BitDepth::Eight) {
            return Err(format!(
                "not 8-bit RGB: {:?} {:?}",
                info.color_type, info.bit_depth
            ));
        }
        data.truncate(info.buffer_size());
        Ok(Rgb8 {
            width: info.width,
            height: info.height,
            data,
        })
    } else if bytes.starts_with(&[0xff, 0xd8]) {
        use zune_jpeg::zune_core::{bytestream::ZCursor, colorspace::ColorSpace, options::DecoderOptions};
        let options = DecoderOptions::default().jpeg_set_out_colorspace(ColorSpace::RGB);
        let mut decoder = zune_jpeg::JpegDecoder::new_with_options(ZCursor::new(bytes), options);
        let data = decoder.decode().map_err(|e| e.to_string())?;
        let (w, h) = decoder.dimensions().unwrap();
        Ok(Rgb8 {
            width: w as u32,
            height: h as u32,
            data,
        })
    } else if bytes.starts_with(b"P6") {
        // "P6", width, height and maxval as decimal words between white space, one white-space byte,
        // then the samples (the command writes no comments).
        let mut fields = Vec::new();
        let mut at = 2;
        while fields.len() < 3 {
            while bytes[at].is_ascii_whitespace() {
                at += 1;
            }
            let start = at;
            while bytes[at].is_ascii_digit() {
                at += 1;
            }
            fields.push(
                std::str::from_utf8(&bytes[start..at])
                    .unwrap()
                    .parse::<u32>()
                    .unwrap(),
            );
        }
        assert_eq!(fields[2], 255, "maxval");
        let data = bytes[at + 1..].to_vec();
        assert_eq!(data.len(), 3 * fields[0] as usize * fields[1] as usize, "samples");
        Ok(Rgb8 {
            width: fields[0],
            height: fields[1],
            data,
        })
    } else {
        Err("neither PNG, JPEG nor P6 PPM".into())
    }
}

/// An OpenEXR file's linear RGB, row-major, read by the `exr` crate: (width, height, pixels).
pub fn exr(path: &Path) -> (u32, u32, Vec<[f32; 3]>) {
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |size, _| (size.width(), vec![[0.0; 3]; size.area()]),
        |(width, pixels), at, (r, g, b, _): (f32, f32, f32, f32)| {
            pixels[at.y() * *width + at.x()] = [r, g, b]
        },
    )
    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let size = image.layer_data.size;
    (
        size.width() as u32,
        size.height() as u32,
        image.layer_data.channel_data.pixels.1,
    )
}
