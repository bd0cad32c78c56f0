//! Random numbers for distribution ray tracing (Cook, Porter, Carpenter 1984, "Distributed Ray
//! Tracing"), reproducible bit for bit: every generator is seeded from `(seed, pass, pixel, stream)`,
//! never from a thread or from the order tiles are scheduled in, so the image does not depend on either.
//!
//! Per pixel, [`PixelPattern`] holds the n × n jittered sub-pixel positions (one uniform point in each
//! cell of an n × n grid over the pixel) and a second, independent jittered n × n set on the unit square
//! for the area lights, shuffled (Fisher–Yates) so that sub-pixel cell `s` is paired with a random light
//! cell rather than the same corner of the light every time (the course's decorrelation). Per sample,
//! a [`Sampler`] supplies the lens point and the fuzzy-reflection perturbations.

use glam::{Vec2, Vec3};

use crate::digest::{SPLITMIX_STEP, mix};

/// Streams of one pixel: the pattern, then each sample's own.
const PATTERN_STREAM: u32 = 0;

/// A pixel's part of its generators' seeds: the render's seed (mixed once a frame, [`mix`]) mixed with
/// the pixel's row-major index.
#[derive(Clone, Copy, Debug)]
pub struct PixelKey(u64);

impl PixelKey {
    /// The key of pixel `pixel` in a render whose seed mixes to `seed_key`.
    #[inline]
    pub fn new(seed_key: u64, pixel: u64) -> Self {
        PixelKey(mix(seed_key ^ pixel))
    }
}

/// A generator of uniform numbers for one pixel sample (or one pixel's pattern).
pub struct Sampler {
    rng: Xoshiro256pp,
}

impl Sampler {
    /// The generator of `stream` (0: the pattern, `1 + s`: sample `s`) of pixel `pixel` (row-major
    /// index) in pass `pass` of a render seeded with `seed`.
    #[inline]
    pub fn new(seed: u64, pass: u32, pixel: u64, stream: u32) -> Self {
        Sampler::of_pixel(PixelKey::new(mix(seed), pixel), pass, stream)
    }

    /// [`Sampler::new`] from the pixel's key: the streams of one pixel share it, so a frame mixes the
    /// seed once and each pixel's index once, whatever the streams drawn.
    #[inline]
    pub fn of_pixel(pixel: PixelKey, pass: u32, stream: u32) -> Self {
        let key = mix(pixel.0 ^ (u64::from(pass) << 32 | u64::from(stream)));
        // `Xoshiro256PlusPlus::seed_from_u64(key)`'s state: four SplitMix64 outputs.
        let word = |i: u64| mix(key.wrapping_add(SPLITMIX_STEP.wrapping_mul(i)));
        Sampler {
            rng: Xoshiro256pp {
                s: [word(1), word(2), word(3), word(4)],
            },
        }
    }

    /// A generator for a pixel sample that never draws (no lens, no rough mirror), not seeded: its
    /// numbers would be those of a fixed state, the same for every sample.
    #[inline]
    pub fn unused() -> Self {
        Sampler {
            rng: Xoshiro256pp { s: [1, 2, 3, 4] },
        }
    }

    /// Uniform in [0, 1): the top 24 bits of the next output, so every value is exact in `f32`.
    #[inline]
    pub fn uniform(&mut self) -> f32 {
        (self.rng.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// Two uniform numbers.
    #[inline]
    pub fn next2(&mut self) -> Vec2 {
        let x = self.uniform();
        Vec2::new(x, self.uniform())
    }

    /// A uniform point in the unit disc, by Shirley and Chiu's concentric map ("A Low Distortion Map
    /// Between Disk and Square", 1997): two numbers per point, no rejection.
    pub fn in_unit_disc(&mut self) -> Vec2 {
        let p = self.next2() * 2.0 - 1.0;
        if p == Vec2::ZERO {
            return p;
        }
        let (r, theta) = if p.x.abs() > p.y.abs() {
            (p.x, std::f32::consts::FRAC_PI_4 * (p.y / p.x))
        } else {
            (
                p.y,
                std::f32::consts::FRAC_PI_2 - std::f32::consts::FRAC_PI_4 * (p.x / p.y),
            )
        };
        r * Vec2::new(theta.cos(), theta.sin())
    }

    /// A uniform point in the unit ball (rejection from the cube: 52% of draws accepted).
    pub fn in_unit_ball(&mut self) -> Vec3 {
        loop {
            let p = Vec3::new(self.uniform(), self.uniform(), self.uniform()) * 2.0 - 1.0;
            if p.length_squared() <= 1.0 {
                return p;
            }
        }
    }

    /// An index in `0..n` (n > 0), by Lemire's multiply-shift (bias below 2⁻³² · n).
    fn below(&mut self, n: usize) -> usize {
        ((u64::from(self.rng.next_u32()) * n as u64) >> 32) as usize
    }
}

/// xoshiro256++ (Blackman and Vigna 2018, "Scrambled Linear Pseudorandom Number Generators"), the
/// numbers of `rand_xoshiro`'s `Xoshiro256PlusPlus`, its state seeded as words: the crate takes a seed
/// only as bytes, and the round trip through them showed in every camera ray (`profiles/README.md`).
/// Its state is never all zero (the crate's fallback): the four words are a bijective mix of four
/// distinct numbers, of which at most one mixes to zero.
#[derive(Clone, Debug)]
struct Xoshiro256pp {
    s: [u64; 4],
}

impl Xoshiro256pp {
    #[inline]
    fn next_u64(&mut self) -> u64 {
        let s = &mut self.s;
        let out = s[0].wrapping_add(s[3]).rotate_left(23).wrapping_add(s[0]);
        let t = s[1] << 17;
        s[2] ^= s[0];
        s[3] ^= s[1];
        s[1] ^= s[2];
        s[0] ^= s[3];
        s[2] ^= t;
        s[3] = s[3].rotate_left(45);
        out
    }

    /// The upper half of the next output, as the crate's `next_u32` (the lower bits are weaker).
    #[inline]
    fn next_u32(&mut self) -> u32 {
        (self.next_u64() >> 32) as u32
    }
}

/// One pixel's n × n jittered sub-pixel positions and their shuffled jittered light samples. The
/// buffers are reused from pixel to pixel (no allocation per pixel once grown).
#[derive(Clone, Debug, Default)]
pub struct PixelPattern {
    /// Offsets in the pixel, in [0, 1)², cell by cell, row by row.
    pub pixel: Vec<Vec2>,
    /// Light samples in [0, 1)², paired with `pixel` by index.
    pub light: Vec<Vec2>,
}

impl PixelPattern {
    /// Fills the pattern of pixel `pixel` for `n × n` samples (`n ≥ 1`).
    pub fn fill(&mut self, n: u32, pixel: PixelKey, pass: u32) {
        let mut rng = Sampler::of_pixel(pixel, pass, PATTERN_STREAM);
        let cells = (n * n) as usize;
        let inv = 1.0 / n as f32;
        let jittered = |out: &mut Vec<Vec2>, rng: &mut Sampler| {
            out.clear();
            for j in 0..n {
                for i in 0..n {
                    let cell = Vec2::new(i as f32, j as f32);
                    out.push((cell + rng.next2()) * inv);
                }
            }
        };
        jittered(&mut self.pixel, &mut rng);
        jittered(&mut self.light, &mut rng);
        // Fisher–Yates (Durstenfeld's in-place form).
        for i in (1..cells).rev() {
            let j = rng.below(i + 1);
            self.light.swap(i, j);
        }
    }

    /// The one sample of a 1 × 1 pattern, [`fill`](Self::fill)'s numbers without its buffers: the
    /// offset in the pixel and the light point (cell 0 scaled by 1: the numbers themselves, bit for
    /// bit). Without `quads` to sample, the light point is not drawn (the centre stands in: nothing
    /// reads it, and the pattern's generator draws nothing after it).
    #[inline]
    pub fn single(pixel: PixelKey, pass: u32, quads: bool) -> (Vec2, Vec2) {
        let mut rng = Sampler::of_pixel(pixel, pass, PATTERN_STREAM);
        let offset = rng.next2();
        (offset, if quads { rng.next2() } else { Vec2::splat(0.5) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The generator gives `rand_xoshiro`'s numbers from the same seed (SplitMix64 words, as its
    /// `seed_from_u64`), and the reference implementation's from the crate's test seed.
    #[test]
    fn xoshiro_is_the_crates() {
        use rand_xoshiro::Xoshiro256PlusPlus;
        use rand_xoshiro::rand_core::{Rng, SeedableRng};
        for key in [0u64, 1, 42, u64::MAX, 0x9e37_79b9_7f4a_7c15] {
            let mut ours = Sampler::of_pixel(PixelKey(key), 0, 0).rng;
            let mut theirs = Xoshiro256PlusPlus::seed_from_u64(mix(key));
            for _ in 0..100 {
                assert_eq!(ours.next_u64(), theirs.next_u64());
                assert_eq!(ours.next_u32(), theirs.next_u32());
            }
        }
        // http://xoshiro.di.unimi.it/xoshiro256plusplus.c from state (1, 2, 3, 4).
        let mut reference = Xoshiro256pp { s: [1, 2, 3, 4] };
        let first: Vec<u64> = (0..4).map(|_| reference.next_u64()).collect();
        assert_eq!(first, [41943041, 58720359, 3588806011781223, 3591011842654386]);
    }

    #[test]
    fn streams_are_reproducible_and_distinct() {
        let a: Vec<f32> = (0..8)
            .map(|_| 0.0)
            .scan(Sampler::new(7, 1, 42, 3), |s, _| Some(s.uniform()))
            .collect();
        let b: Vec<f32> = (0..8)
            .map(|_| 0.0)
            .scan(Sampler::new(7, 1, 42, 3), |s, _| Some(s.uniform()))
            .collect();
        assert_eq!(a, b);
        for (seed, pass, pixel, stream) in [(8, 1, 42, 3), (7, 2, 42, 3), (7, 1, 43, 3), (7, 1, 42, 4)] {
            let mut s = Sampler::new(seed, pass, pixel, stream);
            let c: Vec<f32> = (0..8).map(|_| s.uniform()).collect();
            assert_ne!(a, c, "{seed} {pass} {pixel} {stream}");
        }
        assert!(a.iter().all(|&x| (0.0..1.0).contains(&x)));
    }

    /// One sample in every cell, for the pixel and for the light; the light set is a permutation of a
    /// jittered set, not paired cell for cell with the pixel's.
    #[test]
    fn jittered_and_shuffled() {
        let mut p = PixelPattern::default();
        for n in [1u32, 2, 3, 7] {
            let mut paired_same_cell = 0;
            for pixel in 0..50u64 {
                p.fill(n, PixelKey::new(mix(1), pixel), 1);
                for set in [&p.pixel, &p.light] {
                    let mut seen = vec![false; (n * n) as usize];
                    for s in set {
                        assert!(s.min_element() >= 0.0 && s.max_element() < 1.0);
                        let c = (s.y * n as f32) as u32 * n + (s.x * n as f32) as u32;
                        assert!(!seen[c as usize], "two samples in cell {c}");
                        seen[c as usize] = true;
                    }
                }
                let cell = |s: Vec2| ((s.x * n as f32) as u32, (s.y * n as f32) as u32);
                paired_same_cell += p
                    .pixel
                    .iter()
                    .zip(&p.light)
                    .filter(|(a, b)| cell(**a) == cell(**b))
                    .count();
            }
            if n >= 3 {
                // A random pairing puts about 1 of n² pairs in the same cell: far from all of them.
                assert!(
                    paired_same_cell < 50 * (n * n) as usize / 2,
                    "n {n}: {paired_same_cell}"
                );
            }
        }
    }

    /// A 1 × 1 pattern without its buffers draws the same numbers, and a pixel's key gives the
    /// generators the seed and index give.
    #[test]
    fn the_single_sample_is_the_patterns() {
        let mut p = PixelPattern::default();
        for pixel in 0..100u64 {
            let key = PixelKey::new(mix(9), pixel);
            p.fill(1, key, 3);
            let (offset, light) = PixelPattern::single(key, 3, true);
            assert_eq!((offset, light), (p.pixel[0], p.light[0]));
            assert_eq!(PixelPattern::single(key, 3, false).0, offset);
            let (mut a, mut b) = (Sampler::new(9, 3, pixel, 5), Sampler::of_pixel(key, 3, 5));
            assert_eq!(a.rng.next_u64(), b.rng.next_u64());
        }
        // The numbers themselves: in [0, 1), and not the same for every pixel.
        let single = |pixel| PixelPattern::single(PixelKey::new(mix(9), pixel), 3, true);
        let (a, b) = (single(0), single(1));
        assert_ne!(a.0, b.0);
        assert!(a.0.min_element() >= 0.0 && a.1.max_element() < 1.0);
    }

    #[test]
    fn disc_and_ball_are_uniform() {
        let mut s = Sampler::new(3, 1, 0, 1);
        let n = 200_000;
        let (mut inner_disc, mut inner_ball) = (0, 0);
        let mut mean = Vec3::ZERO;
        for _ in 0..n {
            let d = s.in_unit_disc();
            assert!(d.length() <= 1.0 + 1e-6);
            inner_disc += (d.length() < 0.5) as u32;
            let b = s.in_unit_ball();
            assert!(b.length() <= 1.0);
            inner_ball += (b.length() < 0.5) as u32;
            mean += b;
        }
        // Area within radius 1/2: a quarter of the disc; volume: an eighth of the ball.
        assert!((inner_disc as f32 / n as f32 - 0.25).abs() < 0.005);
        assert!((inner_ball as f32 / n as f32 - 0.125).abs() < 0.005);
        assert!((mean / n as f32).length() < 0.01);
    }
}
