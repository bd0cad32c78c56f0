//! The Standard Procedural Databases' test procedure (E. Haines, "A Proposal for Standard Graphics
//! Environments", *IEEE CG&A* 7(11), 1987, and the SPD's Readme), so that a renderer's ray counts can be
//! compared with the table the Readme gives for each database at its default size:
//!
//! - 512 × 512 pixels; one eye ray through each of the 513 × 513 pixel corners, each pixel the mean of
//!   its four corners ([`Options::spd`], [`corners_to_pixels`]);
//! - the eye ray is depth 1 and the ray tree stops at depth 5, i.e. four bounces after the eye ray;
//! - every hit on a reflective (`Ks` > 0) or transmitting (`T` > 0) surface spawns its rays whatever
//!   their weight (rules 8 and 9; this renderer has no adaptive cutoff). "All transmitters in the SPD
//!   are also reflective": a transmitter spawns its reflection ray even where `Ks` is 0, as in gears'
//!   glass (`f r g b 0.2 0 100000 0.8 1.1`), with weight 0, so the image is the same; and its
//!   refraction ray unless the light is totally internally reflected, when the reflection ray carries
//!   all of it.
//!
//! Shadow rays are those toward each light that lies in front of the surface, as always (rule 10).
//! With these rules the seven databases at their default sizes (`scenes/spd/*_default.nff[.gz]`) come
//! within 1% of the Readme's counts, but for gears' refraction rays (3% fewer; `docs/performance.md`).

use super::lanes::{Fx, Lanes, full};
use super::options::Options;
use super::stats::RayCounts;
use crate::image::Film;
use crate::scene::Scene;

/// Image side of the procedure.
pub const SIZE: u32 = 512;
/// Bounces after the eye ray: the tree stops at depth 5 with the eye ray at depth 1.
pub const SPD_DEPTH: u32 = 4;

/// The options of the procedure for `scene`: 513 × 513 corner rays, four bounces, spp 0.
pub fn options(scene: &Scene) -> Options {
    Options {
        width: SIZE + 1,
        height: SIZE + 1,
        max_depth: SPD_DEPTH,
        spp: 0,
        spd: true,
        ..Options::new(scene)
    }
}

/// Which of a hit's secondary rays are spawned, chosen once per frame from [`Options::spd`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Spawning {
    /// A ray is spawned where its weight is positive.
    ByWeight,
    /// The procedure's rules 8 and 9: a transmitter spawns both its rays whatever their weight (but
    /// the refracted one under a total internal reflection, whose light the mirror ray carries).
    Procedure,
}

impl Spawning {
    pub(crate) fn of(options: &Options) -> Self {
        if options.spd {
            Spawning::Procedure
        } else {
            Spawning::ByWeight
        }
    }

    /// The lanes whose refracted ray of `weight` is spawned (among those that refract at all).
    #[inline(always)]
    pub(crate) fn refracted<L: Lanes<N>, const N: usize>(self, weight: Fx<L, N>) -> u32 {
        match self {
            Spawning::ByWeight => weight.positive(),
            Spawning::Procedure => full::<N>(),
        }
    }

    /// The mirror rays' weights and the lanes that spawn one, from each hit's `ks`, Fresnel
    /// reflectance `kr`, `transmission`, its lanes of total internal reflection and of transmitters.
    #[inline(always)]
    pub(crate) fn reflected<L: Lanes<N>, const N: usize>(
        self,
        ks: Fx<L, N>,
        kr: Fx<L, N>,
        transmission: Fx<L, N>,
        total: u32,
        transmits: u32,
    ) -> (Fx<L, N>, u32) {
        match self {
            Spawning::ByWeight => {
                let weight = ks * kr;
                (weight, weight.positive())
            }
            Spawning::Procedure => {
                let weight = Fx::blend(total, ks + transmission, ks * kr);
                (weight, weight.positive() | transmits)
            }
        }
    }
}

/// A frame of `w + 1` × `h + 1` corner samples as the `w` × `h` image whose pixels are the means of
/// their four corners.
pub fn corners_to_pixels(corners: &Film) -> Film {
    let (w, h) = (corners.width - 1, corners.height - 1);
    let mut film = Film::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let sum =
                corners.get(x, y) + corners.get(x + 1, y) + corners.get(x, y + 1) + corners.get(x + 1, y + 1);
            film.pixels[(y * w + x) as usize] = sum * 0.25;
        }
    }
    film
}

/// What the Readme's table counts for one database.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Counts {
    /// Eye rays that hit something.
    pub eye_hits: u64,
    /// Reflection rays.
    pub reflected: u64,
    /// Refraction rays.
    pub refracted: u64,
    /// Shadow rays.
    pub shadow: u64,
}

impl Counts {
    /// The counts of a frame's rays.
    pub fn of(rays: &RayCounts) -> Self {
        Counts {
            eye_hits: rays.primary_hits,
            reflected: rays.reflected,
            refracted: rays.refracted,
            shadow: rays.shadow,
        }
    }

    /// True if every count is within `tolerance` (relative) of `want`'s, and zero where `want`'s is.
    pub fn within(&self, want: &Counts, tolerance: f64) -> bool {
        let close = |got: u64, want: u64| (got as f64 - want as f64).abs() <= tolerance * want as f64;
        close(self.eye_hits, want.eye_hits)
            && close(self.reflected, want.reflected)
            && close(self.refracted, want.refracted)
            && close(self.shadow, want.shadow)
    }
}

/// The Readme's table: each database at its default size, with the procedure above.
pub const README: [(&str, Counts); 7] = [
    ("balls", counts(263_169, 175_095, 0, 954_368)),
    ("gears", counts(245_086, 304_643, 207_564, 2_246_955)),
    ("mount", counts(173_125, 354_769, 354_769, 412_922)),
    ("rings", counts(263_169, 315_236, 0, 1_085_002)),
    ("teapot", counts(161_120, 225_248, 0, 407_656)),
    ("tetra", counts(49_788, 0, 0, 46_112)),
    ("tree", counts(169_836, 0, 0, 1_097_419)),
];

const fn counts(eye_hits: u64, reflected: u64, refracted: u64, shadow: u64) -> Counts {
    Counts {
        eye_hits,
        reflected,
        refracted,
        shadow,
    }
}

/// The Readme's counts for the database a file is named after (`teapot_default.nff` → teapot); they
/// hold only for the default sizes.
pub fn readme_counts(file_name: &str) -> Option<Counts> {
    README
        .iter()
        .find(|(name, _)| file_name.starts_with(name))
        .map(|(_, c)| *c)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn a_pixel_is_the_mean_of_its_four_corners() {
        let mut corners = Film::new(3, 2);
        for (i, p) in corners.pixels.iter_mut().enumerate() {
            *p = Vec3::splat(i as f32);
        }
        // Corners 0 1 2 / 3 4 5: pixel 0 = (0+1+3+4)/4 = 2, pixel 1 = (1+2+4+5)/4 = 3.
        let film = corners_to_pixels(&corners);
        assert_eq!((film.width, film.height), (2, 1));
        assert_eq!(film.pixels, [Vec3::splat(2.0), Vec3::splat(3.0)]);
    }

    #[test]
    fn counts_match_within_a_tolerance_and_zero_means_zero() {
        let want = readme_counts("tetra_default.nff").unwrap();
        let near = counts(49_788 + 4_000, 0, 0, 46_112 - 4_000);
        assert!(near.within(&want, 0.1));
        assert!(!counts(49_788, 1, 0, 46_112).within(&want, 0.1));
        assert!(!counts(40_000, 0, 0, 46_112).within(&want, 0.1));
        assert_eq!(readme_counts("jacks_1.nff"), None);
    }
}
