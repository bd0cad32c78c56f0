//! What a ray that leaves the scene sees: a cube-map skybox (`env DIR`) or the background colour.

use std::path::Path;
use std::sync::Arc;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::scene::Scene;

/// The six faces, in the order of the files `DIR/{right,left,top,bottom,front,back}.jpg`: +x, −x, +y, −y,
/// +z, −z (the OpenGL cube-map convention most skybox sets follow).
pub const FACES: [&str; 6] = ["right", "left", "top", "bottom", "front", "back"];

/// A cube map of linear colour, values taken from the 8-bit images as they are (the course's convention:
/// no gamma anywhere).
#[derive(Clone, Debug)]
pub struct CubeMap {
    faces: Vec<image::RgbImage>,
}

impl CubeMap {
    /// Loads the six faces from `dir` (`.jpg`, or `.png` when no `.jpg` exists).
    pub fn load(dir: &Path) -> Result<Self> {
        let mut faces = Vec::with_capacity(6);
        for name in FACES {
            let jpg = dir.join(format!("{name}.jpg"));
            let path = if jpg.exists() {
                jpg
            } else {
                dir.join(format!("{name}.png"))
            };
            let img = image::open(&path)
                .map_err(|e| Error::file(&path, format!("cannot read the skybox face: {e}")))?
                .to_rgb8();
            if img.width() == 0 || img.height() == 0 {
                return Err(Error::file(&path, "the skybox face is empty"));
            }
            faces.push(img);
        }
        Ok(CubeMap { faces })
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
}
