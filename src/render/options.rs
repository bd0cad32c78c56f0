//! What to render beyond the scene itself, and the ranges in which it renders at all.

use crate::error::{Error, Result};
use crate::scene::{Scene, check_resolution};

/// How camera rays are traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// One ray at a time.
    Single,
    /// Camera rays in packets of 8 (4x2 pixels), their hits' shadow rays in packets per light sample,
    /// and their reflected and refracted rays in packets per kind while they stay coherent
    /// ([`crate::accel::Accel::intersect_packet`]: the wide BVHs trace them together, the other
    /// structures ray by ray). The image is identical to `Single`'s.
    Packet,
}

impl Kernel {
    /// Every kernel (they render the same image).
    pub const ALL: [Kernel; 2] = [Kernel::Single, Kernel::Packet];

    /// What the kernel is called on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Single => "single",
            Kernel::Packet => "packet",
        }
    }

    /// The other kernel (the viewer's key): single, packet, single.
    pub fn next(self) -> Kernel {
        match self {
            Kernel::Single => Kernel::Packet,
            Kernel::Packet => Kernel::Single,
        }
    }
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

/// The most samples per pixel in one pass: 256 × 256. A worker keeps the sample patterns of eight
/// pixels (a packet), 16 bytes a sample each: 8 MiB at this bound. More samples than that belong in
/// progressive passes (`--passes`), which cost no memory per sample.
pub const MAX_SPP: u32 = 256 * 256;

/// The most bounces after the primary hit. Shading recurses once per bounce, the packet kernel with
/// eight rays' state per level: 64 levels among nested glass spheres fit in 512 KiB of stack (and
/// overflow 256 KiB), a quarter of a rayon worker's 2 MiB (`tests/render/limits.rs` renders them on such a
/// worker); the 3,000 bounces once accepted needed about 50 times that. However deep a tree may go, it
/// cannot grow past a fixed number of rays (the integrator's split budget, `whitted.rs`).
pub const MAX_DEPTH: u32 = 64;

/// The bounce limit unless one is asked for (the course's renderers stop at 6).
pub const DEFAULT_DEPTH: u32 = 6;

/// What to render, beyond the scene itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Options {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Most bounces after the primary hit, at most [`MAX_DEPTH`]; at the limit only the local colour is
    /// computed.
    pub max_depth: u32,
    /// Single rays or packets for the camera rays.
    pub kernel: Kernel,
    /// Samples per pixel: 0 for one ray through the centre; otherwise n × n jittered samples (a count
    /// that is not a square is rounded up to the next one), at most [`MAX_SPP`].
    pub spp: u32,
    /// Seed of every random number of the frame.
    pub seed: u64,
    /// Roughness of the materials whose `f` line does not give one: finite and at least 0.
    pub roughness: f32,
    /// The Standard Procedural Databases' test procedure ([`super::spd`]): camera rays through pixel
    /// corners instead of centres, so the frame's `width` × `height` samples are the corners of a
    /// (`width` − 1) × (`height` − 1) image ([`super::spd::corners_to_pixels`] averages them into it),
    /// and a total internal reflection spawns its mirror ray whatever the material's `Ks`. Needs spp 0.
    pub spd: bool,
    /// Count each ray's steps (nodes visited, primitives tested) into [`super::RayCounts::steps`],
    /// through the accelerator's counting verbs ([`crate::accel::Accel::counting`]).
    pub count_steps: bool,
}

impl Options {
    /// The samples per pixel a side of the jittered grid: `spp` rounded up to a square's side (0 for
    /// one ray through the centre).
    pub fn side(&self) -> u32 {
        (self.spp as f64).sqrt().ceil() as u32
    }

    /// The samples per pixel actually taken: [`Options::side`] squared (`spp` when it is a square).
    pub fn spp_taken(&self) -> u32 {
        self.side() * self.side()
    }

    /// The scene's own resolution and samples per pixel, 6 bounces, seed 0, mirrors sharp.
    pub fn new(scene: &Scene) -> Self {
        Options {
            width: scene.camera.width,
            height: scene.camera.height,
            max_depth: DEFAULT_DEPTH,
            kernel: Kernel::Packet,
            spp: scene.spp,
            seed: 0,
            roughness: 0.0,
            spd: false,
            count_steps: false,
        }
    }

    /// Checks that every field is in its range (the resolution as a scene file's is), so that options
    /// set from a command line or in code are refused with a message rather than rendered wrongly.
    pub fn validate(&self) -> Result<()> {
        check_resolution(self.width, self.height).map_err(Error::msg)?;
        if self.spp > MAX_SPP {
            return Err(Error::msg(format!(
                "{} samples per pixel is more than the most, {MAX_SPP} (256 x 256); for more, average \
                 progressive passes (--passes)",
                self.spp
            )));
        }
        if self.max_depth > MAX_DEPTH {
            return Err(Error::msg(format!(
                "a depth of {} bounces is more than the most, {MAX_DEPTH}",
                self.max_depth
            )));
        }
        if self.spd && (self.spp != 0 || self.width < 2 || self.height < 2) {
            return Err(Error::msg(format!(
                "the SPD procedure needs spp 0 and at least 2 x 2 corners, found spp {} and {}x{}",
                self.spp, self.width, self.height
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

    /// Each kernel is parsed back from its name, and the viewer's key visits all three in turn.
    #[test]
    fn kernels_by_name_and_in_turn() {
        for k in Kernel::ALL {
            assert_eq!(k.name().parse::<Kernel>(), Ok(k));
        }
        assert_eq!(Kernel::Single.next(), Kernel::Packet);
        assert_eq!(Kernel::Packet.next(), Kernel::Single);
        assert!("wavefront".parse::<Kernel>().is_err());
    }

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
                max_depth: MAX_DEPTH,
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
            "65537 samples per pixel is more than the most, 65536 (256 x 256); for more, average \
             progressive passes (--passes)"
        );
        let o = Options {
            spp: u32::MAX,
            ..options()
        };
        assert!(error(o).starts_with("4294967295 samples per pixel is more than the most"));
    }

    #[test]
    fn refuses_more_bounces_than_the_stack_is_sized_for() {
        for depth in [65, 3000, u32::MAX] {
            let o = Options {
                max_depth: depth,
                ..options()
            };
            assert_eq!(
                error(o),
                format!("a depth of {depth} bounces is more than the most, 64")
            );
        }
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
