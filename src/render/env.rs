//! What a ray that leaves the scene sees: a cube-map skybox (`env DIR`) or the background colour.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::image::codecs::Decoder;
use crate::scene::Scene;

/// The six faces, in the order of the files `DIR/{right,left,top,bottom,front,back}.jpg`: +x, −x, +y, −y,
/// +z, −z (the OpenGL cube-map convention most skybox sets follow).
pub const FACES: [&str; 6] = ["right", "left", "top", "bottom", "front", "back"];

/// The most texels a face may have on a side, read from its header before it is decoded. A face spans
/// 90 degrees: 8192 texels are 91 a degree, more than a 4K frame (3840 pixels) across a 45-degree field
/// of view shows (85), and six such faces are 1.1 GiB as 8-bit RGB. A larger face is more likely a
/// mistake, or a small file made to claim gigabytes, than a sky.
pub const MAX_FACE: u32 = 8192;

/// A face's file opened and its header read: its path and its decoder.
fn face(dir: &Path, name: &str) -> Result<(PathBuf, Decoder)> {
    let jpg = dir.join(format!("{name}.jpg"));
    let path = if jpg.exists() {
        jpg
    } else {
        dir.join(format!("{name}.png"))
    };
    let file = crate::files::open_regular(&path)
        .map_err(|why| Error::file(&path, format!("cannot open the skybox face: {why}")))?;
    // PNG or JPEG by its first bytes, whatever its extension.
    let decoder = Decoder::open(file, &path).map_err(|e| unreadable(&path, e))?;
    match decoder.dimensions() {
        (0, _) | (_, 0) => Err(Error::file(&path, "the skybox face is empty")),
        (w, h) if w > MAX_FACE || h > MAX_FACE => Err(Error::file(
            &path,
            format!("the skybox face is {w}x{h} texels: at most {MAX_FACE}x{MAX_FACE}"),
        )),
        _ => Ok((path, decoder)),
    }
}

/// The error of a face at `path` that could not be read.
fn unreadable(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::file(path, format!("cannot read the skybox face: {e}"))
}

/// A cube map of linear colour, values taken from the 8-bit images as they are (the course's convention:
/// no gamma anywhere).
#[derive(Clone, Debug)]
pub struct CubeMap {
    faces: Vec<Face>,
}

/// One face: 8-bit RGB texels, row-major.
#[derive(Clone, Debug)]
struct Face {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl CubeMap {
    /// Loads the six faces from `dir` (`.jpg`, or `.png` when no `.jpg` exists). Each must be a regular
    /// file (or a link to one) of at most [`MAX_FACE`] texels a side, which its header says before
    /// anything is decoded.
    pub fn load(dir: &Path) -> Result<Self> {
        let mut faces = Vec::with_capacity(6);
        for name in FACES {
            let (path, decoder) = face(dir, name)?;
            let (width, height) = decoder.dimensions();
            let rgb = decoder.decode_rgb8().map_err(|e| unreadable(&path, e))?;
            if rgb.len() as u64 != 3 * u64::from(width) * u64::from(height) {
                return Err(unreadable(
                    &path,
                    "its pixels do not fill the size its header gives",
                ));
            }
            faces.push(Face { width, height, rgb });
        }
        Ok(CubeMap { faces })
    }

    /// The bytes [`CubeMap::load`] takes at its peak, read from the faces' headers: every face as 8-bit
    /// RGB, and the largest face once more as its decoder gives it (before it becomes 8-bit RGB).
    pub fn bytes(dir: &Path) -> Result<u64> {
        let (mut kept, mut decoded) = (0, 0);
        for name in FACES {
            let (_, decoder) = face(dir, name)?;
            let (w, h) = decoder.dimensions();
            kept += 3 * u64::from(w) * u64::from(h);
            decoded = decoded.max(decoder.decoded_bytes());
        }
        Ok(kept + decoded)
    }

    /// The colour seen in direction `d` (need not be unit length); nearest texel.
    #[inline]
    pub fn lookup(&self, d: Vec3) -> Vec3 {
        // Face selection and (sc, tc) as in the OpenGL specification's cube-map table.
        let a = d.abs();
        let (face, sc, tc, ma) = if a.x >= a.y && a.x >= a.z {
            if d.x > 0.0 {
                (0, -d.z, -d.y, a.x)
            } else {
                (1, d.z, -d.y, a.x)
            }
        } else if a.y >= a.z {
            if d.y > 0.0 {
                (2, d.x, d.z, a.y)
            } else {
                (3, d.x, -d.z, a.y)
            }
        } else if d.z > 0.0 {
            (4, d.x, -d.y, a.z)
        } else {
            (5, -d.x, -d.y, a.z)
        };
        let img = &self.faces[face];
        let s = 0.5 * (sc / ma + 1.0);
        let t = 0.5 * (tc / ma + 1.0);
        let x = ((s * img.width as f32) as u32).min(img.width - 1);
        let y = ((t * img.height as f32) as u32).min(img.height - 1);
        let i = 3 * (y as usize * img.width as usize + x as usize);
        let p = &img.rgb[i..i + 3];
        Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) / 255.0
    }
}

/// The background: a skybox if the scene has one that loads, else a flat colour. A clone shares the
/// skybox's images, so that a renderer per camera (the viewer's) does not copy or reload them.
#[derive(Clone, Debug)]
pub struct Background {
    color: Vec3,
    sky: Option<Arc<CubeMap>>,
}

impl Background {
    /// The scene's background: its skybox (`env DIR`) if that loads, else its colour, with a warning
    /// when a skybox was there but did not load. Needs nothing but the scene (no accelerator, no
    /// renderer), so a viewer loads it once for all its frames.
    pub fn load(scene: &Scene) -> (Self, Option<String>) {
        match &scene.env {
            Some(dir) if dir.is_dir() => match CubeMap::load(dir) {
                Ok(sky) => (Background::sky(scene.background, sky), None),
                Err(e) => (
                    Background::color(scene.background),
                    Some(format!("{e}; using the background colour")),
                ),
            },
            // A missing directory was reported by the loader already.
            _ => (Background::color(scene.background), None),
        }
    }

    /// The bytes loading the scene's skybox takes at its peak ([`CubeMap::bytes`]): 0 when it has none,
    /// or one that will not load (which [`Background::load`] warns of).
    pub fn bytes(scene: &Scene) -> u64 {
        match &scene.env {
            Some(dir) if dir.is_dir() => CubeMap::bytes(dir).unwrap_or(0),
            _ => 0,
        }
    }

    /// A flat colour.
    pub fn color(color: Vec3) -> Self {
        Background { color, sky: None }
    }

    /// A skybox.
    pub fn sky(color: Vec3, sky: CubeMap) -> Self {
        Background {
            color,
            sky: Some(Arc::new(sky)),
        }
    }

    /// The colour of a ray that hits nothing.
    #[inline]
    pub fn sample(&self, d: Vec3) -> Vec3 {
        match &self.sky {
            Some(sky) => sky.lookup(d),
            None => self.color,
        }
    }
}

#[cfg(test)]
mod tests {
    use std::fs::File;

    use super::*;

    /// Writes a PNG of `color` at `depth` with the samples `data`.
    fn save_png(path: &Path, (w, h): (u32, u32), color: png::ColorType, depth: png::BitDepth, data: &[u8]) {
        let mut encoder = png::Encoder::new(std::fs::File::create(path).unwrap(), w, h);
        encoder.set_color(color);
        encoder.set_depth(depth);
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(data).unwrap();
        writer.finish().unwrap();
    }

    /// An 8-bit RGB PNG of one colour.
    fn flat(path: &Path, size: (u32, u32), rgb: [u8; 3]) {
        let data = rgb.repeat((size.0 * size.1) as usize);
        save_png(path, size, png::ColorType::Rgb, png::BitDepth::Eight, &data);
    }

    /// Each face a flat colour of its own: the six axis directions see their six faces.
    #[test]
    fn axis_directions_see_their_faces() {
        let dir = tempfile::tempdir().unwrap();
        for (i, name) in FACES.iter().enumerate() {
            flat(
                &dir.path().join(format!("{name}.png")),
                (4, 4),
                [i as u8 * 40, 0, 0],
            );
        }
        let sky = CubeMap::load(dir.path()).unwrap();
        let dirs = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];
        for (i, d) in dirs.iter().enumerate() {
            assert_eq!(sky.lookup(*d).x, (i as f32 * 40.0) / 255.0, "face {}", FACES[i]);
        }
        assert!(CubeMap::load(&dir.path().join("nowhere")).is_err());
    }

    /// A load's bytes at its peak: the six faces as 8-bit RGB, and the largest face once more as its
    /// decoder gives it (16-bit RGBA: 8 bytes a texel).
    #[test]
    fn bytes_count_the_faces_and_the_largest_as_decoded() {
        let dir = tempfile::tempdir().unwrap();
        for name in FACES {
            flat(&dir.path().join(format!("{name}.png")), (4, 2), [9, 9, 9]);
        }
        assert_eq!(CubeMap::bytes(dir.path()).unwrap(), 6 * 24 + 24);
        let top = dir.path().join("top.png");
        save_png(
            &top,
            (3, 5),
            png::ColorType::Rgba,
            png::BitDepth::Sixteen,
            &[0; 3 * 5 * 8],
        );
        assert_eq!(CubeMap::bytes(dir.path()).unwrap(), 5 * 24 + 45 + 3 * 5 * 8);
        let sky = CubeMap::load(dir.path()).unwrap();
        assert_eq!((sky.faces[2].width, sky.faces[2].height), (3, 5));
    }

    /// Every PNG becomes 8-bit RGB as its samples say: grey replicated, alpha dropped, 16-bit samples
    /// to the nearest of 256 levels (v / 257: 1000 is 3.89, so 4; 0x8080 is 128 exactly), a palette
    /// looked up. And a JPEG, whatever its name, decoded to about its colour.
    #[test]
    fn every_kind_of_face_becomes_8_bit_rgb() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let face = |name: &str| {
            let path = d.join(name);
            let decoder = Decoder::open(File::open(&path).unwrap(), &path).unwrap();
            decoder.decode_rgb8().unwrap()
        };
        use png::{BitDepth, ColorType};
        // A PNG's colour type, depth, size and samples, and the 8-bit RGB it becomes.
        type Case = (ColorType, BitDepth, (u32, u32), &'static [u8], &'static [u8]);
        let cases: [Case; 3] = [
            (
                ColorType::Grayscale,
                BitDepth::Sixteen,
                (2, 1),
                &[3, 232, 0x80, 0x80],
                &[4, 4, 4, 128, 128, 128],
            ),
            (
                ColorType::GrayscaleAlpha,
                BitDepth::Eight,
                (1, 1),
                &[77, 0],
                &[77, 77, 77],
            ),
            (
                ColorType::Rgba,
                BitDepth::Eight,
                (1, 1),
                &[1, 2, 3, 4],
                &[1, 2, 3],
            ),
        ];
        for (i, (color, depth, size, samples, rgb)) in cases.into_iter().enumerate() {
            let name = format!("{i}.png");
            save_png(&d.join(&name), size, color, depth, samples);
            assert_eq!(face(&name), rgb, "{color:?} {depth:?}");
        }
        let mut encoder = png::Encoder::new(File::create(d.join("p.png")).unwrap(), 2, 1);
        encoder.set_color(ColorType::Indexed);
        encoder.set_depth(BitDepth::Eight);
        encoder.set_palette(vec![10, 20, 30, 40, 50, 60]);
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(&[1, 0]).unwrap();
        writer.finish().unwrap();
        assert_eq!(face("p.png"), [40, 50, 60, 10, 20, 30]);
        let jpeg = d.join("j.png");
        crate::image::codecs::write_jpeg(
            &mut File::create(&jpeg).unwrap(),
            8,
            8,
            &[200, 100, 50].repeat(64),
            95,
        )
        .unwrap();
        for p in face("j.png").chunks_exact(3) {
            let near = |a: u8, b: u8| a.abs_diff(b) <= 3;
            assert!(near(p[0], 200) && near(p[1], 100) && near(p[2], 50), "{p:?}");
        }
        std::fs::write(d.join("gif.jpg"), b"GIF89a").unwrap();
        let path = d.join("gif.jpg");
        let err = Decoder::open(File::open(&path).unwrap(), &path).err().unwrap();
        assert_eq!(
            err,
            "neither a PNG nor a JPEG file (its first bytes), whatever gif.jpg says"
        );
    }
}
