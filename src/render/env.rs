//! What a ray that leaves the scene sees: a cube-map skybox (`env DIR`) or the background colour.

use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Vec3;
use image::{DynamicImage, ImageDecoder, ImageFormat, ImageReader};

use crate::error::{Error, Result};
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
fn face(dir: &Path, name: &str) -> Result<(PathBuf, impl ImageDecoder)> {
    let jpg = dir.join(format!("{name}.jpg"));
    let path = if jpg.exists() {
        jpg
    } else {
        dir.join(format!("{name}.png"))
    };
    let file = crate::files::open_regular(&path)
        .map_err(|why| Error::file(&path, format!("cannot open the skybox face: {why}")))?;
    let mut reader = ImageReader::new(BufReader::new(file));
    // Its extension, unless its first bytes say otherwise.
    if let Ok(format) = ImageFormat::from_path(&path) {
        reader.set_format(format);
    }
    let decoder = reader
        .with_guessed_format()
        .map_err(|e| unreadable(&path, e))?
        .into_decoder()
        .map_err(|e| unreadable(&path, e))?;
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
    faces: Vec<image::RgbImage>,
}

impl CubeMap {
    /// Loads the six faces from `dir` (`.jpg`, or `.png` when no `.jpg` exists). Each must be a regular
    /// file (or a link to one) of at most [`MAX_FACE`] texels a side, which its header says before
    /// anything is decoded.
    pub fn load(dir: &Path) -> Result<Self> {
        let mut faces = Vec::with_capacity(6);
        for name in FACES {
            let (path, decoder) = face(dir, name)?;
            let img = DynamicImage::from_decoder(decoder).map_err(|e| unreadable(&path, e))?;
            faces.push(img.into_rgb8());
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
            decoded = decoded.max(decoder.total_bytes());
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
        let x = ((s * img.width() as f32) as u32).min(img.width() - 1);
        let y = ((t * img.height() as f32) as u32).min(img.height() - 1);
        let p = img.get_pixel(x, y).0;
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
    use super::*;

    /// Each face a flat colour of its own: the six axis directions see their six faces.
    #[test]
    fn axis_directions_see_their_faces() {
        let dir = tempfile::tempdir().unwrap();
        for (i, name) in FACES.iter().enumerate() {
            let img = image::RgbImage::from_pixel(4, 4, image::Rgb([i as u8 * 40, 0, 0]));
            img.save(dir.path().join(format!("{name}.png"))).unwrap();
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
            let img = image::RgbImage::from_pixel(4, 2, image::Rgb([9, 9, 9]));
            img.save(dir.path().join(format!("{name}.png"))).unwrap();
        }
        assert_eq!(CubeMap::bytes(dir.path()).unwrap(), 6 * 24 + 24);
        let top = image::ImageBuffer::<image::Rgba<u16>, _>::from_pixel(3, 5, image::Rgba([0; 4]));
        top.save(dir.path().join("top.png")).unwrap();
        assert_eq!(CubeMap::bytes(dir.path()).unwrap(), 5 * 24 + 45 + 3 * 5 * 8);
        let sky = CubeMap::load(dir.path()).unwrap();
        assert_eq!(sky.faces[2].dimensions(), (3, 5));
    }
}
