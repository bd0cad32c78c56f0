//! What to render beyond the scene itself, and the ranges in which it renders at all.

use crate::error::{Error, Result};
use crate::scene::{Scene, check_resolution};

/// How camera rays are traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// One ray at a time.
    Single,
    /// Camera rays in packets of 8 (4x2 pixels) through the wide BVHs' packet kernel, and their hits'
    /// shadow rays in packets per light sample; other accelerators, and the reflected and refracted
    /// rays, go one at a time. The image is identical to `Single`'s.
    Packet,
}

impl std::str::FromStr for Kernel {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "single" => Ok(Kernel::Single),
            "packet" => Ok(Kernel::Packet),
            _ => Err(format!("unknown kernel \"{s}\": expected single or packet")),
        }
    }
}

/// The most samples per pixel: the largest n × n whose count fits in a `u32`, since a count that is not
/// a square is rounded up to the next one.
const MAX_SPP: u32 = 65535 * 65535;

/// What to render, beyond the scene itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Most bounces after the primary hit; at the limit only the local colour is computed. Any count is
    /// accepted for now: a bound on it is a change of behaviour of its own.
    pub max_depth: u32,
    /// Single rays or packets for the camera rays.
    pub kernel: Kernel,
    /// Samples per pixel: 0 for one ray through the centre; otherwise n × n jittered samples (a count
    /// that is not a square is rounded up to the next one), at most 65535², the largest square in a `u32`.
    pub spp: u32,
    /// Seed of every random number of the frame.
    pub seed: u64,
    /// Roughness of the materials whose `f` line does not give one: finite and at least 0.
    pub roughness: f32,
}

impl Options {
    /// The scene's own resolution and samples per pixel, 6 bounces, seed 0, mirrors sharp.
    pub fn new(scene: &Scene) -> Self {
        Options {
            width: scene.camera.width,
            height: scene.camera.height,
            max_depth: 6,
            kernel: Kernel::Packet,
            spp: scene.spp,
            seed: 0,
            roughness: 0.0,
        }
    }

    /// Checks that every field is in its range (the resolution as a scene file's is), so that options
    /// set from a command line or in code are refused with a message rather than rendered wrongly.
    pub fn validate(&self) -> Result<()> {
        check_resolution(self.width, self.height).map_err(Error::msg)?;
        if self.spp > MAX_SPP {
            return Err(Error::msg(format!(
                "{} samples per pixel is more than the most, {MAX_SPP} (65535 x 65535)",
                self.spp
            )));
        }
        if !(self.roughness.is_finite() && self.roughness >= 0.0) {
            return Err(Error::msg(format!(
                "roughness must be a finite number of at least 0, found {}",
                self.roughness
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;
    use glam::Vec3;

    fn options() -> Options {
        let camera = Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 32, 24);
        Options::new(&Scene::new(camera))
    }

    fn error(options: Options) -> String {
        options.validate().unwrap_err().to_string()
    }

    #[test]
    fn accepts_the_scene_defaults_and_the_extremes_of_each_range() {
        options().validate().unwrap();
        for o in [
            Options {
                max_depth: u32::MAX,
                ..options()
            },
            Options {
                spp: MAX_SPP,
                ..options()
            },
            Options {
                roughness: f32::MAX,
                ..options()
            },
        ] {
            o.validate().unwrap();
        }
    }

    #[test]
    fn refuses_a_resolution_as_a_scene_file_does() {
        let o = Options {
            width: 0,
            ..options()
        };
        assert_eq!(error(o), check_resolution(0, 24).unwrap_err());
    }

    #[test]
    fn refuses_more_samples_than_a_square_can_round_up_to() {
        let o = Options {
            spp: MAX_SPP + 1,
            ..options()
        };
        assert_eq!(
            error(o),
            "4294836226 samples per pixel is more than the most, 4294836225 (65535 x 65535)"
        );
    }

    #[test]
    fn refuses_a_negative_or_not_finite_roughness() {
        for (r, shown) in [(-0.5, "-0.5"), (f32::NAN, "NaN"), (f32::INFINITY, "inf")] {
            let o = Options {
                roughness: r,
                ..options()
            };
            assert_eq!(
                error(o),
                format!("roughness must be a finite number of at least 0, found {shown}")
            );
        }
    }
}
