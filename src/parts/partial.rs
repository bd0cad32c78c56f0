//! The `.partial` file: one part's sums of its passes, headed by every setting that changes the image,
//! so that parts of different renders are never merged.
//!
//! # Version 1
//! Little-endian throughout:
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `WHTPART\n` |
//! | 4 + 4 | format version (1), reserved (0) |
//! | 8 | the scene's fingerprint ([`crate::scene::Scene::fingerprint`], after command-line overrides) |
//! | 4 × 4 | width, height, tile side (16), samples per pixel and pass |
//! | 8 | seed |
//! | 4 × 4 | most bounces, aperture (f32), focal ratio (f32), default roughness (f32) |
//! | 4 × 3 | passes of the whole render, first pass, one past the last pass of this part |
//! | 4 × 2 | part K of N (as given on the command line; the tiles below are what count) |
//! | 4 | number of tiles T, then T × 4: their indices into the row-major tile grid, increasing |
//! | 28 × pixels | per pixel of those tiles (tile after tile, each row-major): the sums of its passes' linear R, G, B (f64), and how many passes they sum (u32) |
//! | 8 | a [`crate::digest`] of every byte before it |
//!
//! Reading checks the magic, the version, the length the header implies, the checksum and every
//! field's range, so a truncated, bit-flipped or foreign file is named and refused, never half-used.

use std::ops::Range;
use std::path::Path;

use crate::digest;
use crate::error::{Error, Result};
use crate::render::Options;
use crate::render::film::write_atomically;
use crate::render::progressive::{Progressive, area};
use crate::render::tiles::{self, TILE};
use crate::scene::{Scene, check_resolution};

const MAGIC: &[u8; 8] = b"WHTPART\n";
const VERSION: u32 = 1;
/// Bytes before the tile indices.
const HEADER: usize = 88;
/// Bytes per pixel: three f64 sums and a u32 count.
const PIXEL: usize = 28;

/// What every part of one render must agree on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// The scene's fingerprint.
    pub scene: u64,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel in each pass.
    pub spp: u32,
    /// Seed of the random numbers.
    pub seed: u64,
    /// Most bounces.
    pub max_depth: u32,
    /// Lens aperture.
    pub aperture: f32,
    /// Focal ratio.
    pub focal: f32,
    /// Roughness of materials that give none.
    pub roughness: f32,
    /// Passes of the whole render.
    pub passes: u32,
}

impl Settings {
    /// The settings of a render of `scene` (its camera's lens included, after any override) with
    /// `options`, in `passes` passes of `options.spp` samples each.
    pub fn new(scene: &Scene, options: &Options, passes: u32) -> Self {
        Settings {
            scene: scene.fingerprint(),
            width: options.width,
            height: options.height,
            spp: options.spp,
            seed: options.seed,
            max_depth: options.max_depth,
            aperture: scene.camera.aperture,
            focal: scene.camera.focal,
            roughness: options.roughness,
            passes,
        }
    }

    /// The fields in which `self` and `other` differ, as `name a vs b`.
    pub(super) fn differences(&self, other: &Settings) -> Vec<String> {
        let mut out = Vec::new();
        let mut check = |name: &str, a: String, b: String| {
            if a != b {
                out.push(format!("{name} {a} vs {b}"));
            }
        };
        check(
            "scene fingerprint",
            format!("{:016x}", self.scene),
            format!("{:016x}", other.scene),
        );
        check(
            "resolution",
            format!("{}x{}", self.width, self.height),
            format!("{}x{}", other.width, other.height),
        );
        check("spp", self.spp.to_string(), other.spp.to_string());
        check("seed", self.seed.to_string(), other.seed.to_string());
        check(
            "max depth",
            self.max_depth.to_string(),
            other.max_depth.to_string(),
        );
        check("total passes", self.passes.to_string(), other.passes.to_string());
        // Bit patterns: a setting is the same only if it renders the same.
        for (name, a, b) in [
            ("aperture", self.aperture, other.aperture),
            ("focal", self.focal, other.focal),
            ("roughness", self.roughness, other.roughness),
        ] {
            if a.to_bits() != b.to_bits() {
                check(
                    name,
                    format!("{a} ({:08x})", a.to_bits()),
                    format!("{b} ({:08x})", b.to_bits()),
                );
            }
        }
        out
    }
}

/// A part of a frame: some of its tiles over some of its passes.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// The render this is a part of.
    pub settings: Settings,
    /// The passes summed, from 0.
    pub passes: Range<u32>,
    /// K of N, as the part was asked for.
    pub part: (u32, u32),
    /// Indices of the tiles covered, increasing.
    pub tiles: Vec<u32>,
    /// Per pixel of those tiles: the sums of R, G, B over the passes.
    pub sums: Vec<[f64; 3]>,
    /// Per pixel: how many passes its sums hold.
    pub counts: Vec<u32>,
}

impl Part {
    /// The part that `progressive` holds: its tiles, over the passes from `first` on.
    pub fn new(settings: Settings, progressive: &Progressive, first: u32, part: (u32, u32)) -> Self {
        let sums = progressive.sums().to_vec();
        Part {
            settings,
            passes: first..first + progressive.passes(),
            part,
            tiles: progressive.tile_indices().to_vec(),
            counts: vec![progressive.passes(); sums.len()],
            sums,
        }
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let s = &self.settings;
        let mut out = Vec::with_capacity(HEADER + 4 * self.tiles.len() + PIXEL * self.sums.len() + 8);
        out.extend_from_slice(MAGIC);
        for v in [VERSION, 0] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&s.scene.to_le_bytes());
        for v in [s.width, s.height, TILE, s.spp] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&s.seed.to_le_bytes());
        out.extend_from_slice(&s.max_depth.to_le_bytes());
        for v in [s.aperture, s.focal, s.roughness] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        for v in [
            s.passes,
            self.passes.start,
            self.passes.end,
            self.part.0,
            self.part.1,
            self.tiles.len() as u32,
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        debug_assert_eq!(out.len(), HEADER);
        for t in &self.tiles {
            out.extend_from_slice(&t.to_le_bytes());
        }
        for (sum, count) in self.sums.iter().zip(&self.counts) {
            for v in sum {
                out.extend_from_slice(&v.to_le_bytes());
            }
            out.extend_from_slice(&count.to_le_bytes());
        }
        let check = digest::of_bytes(&out);
        out.extend_from_slice(&check.to_le_bytes());
        out
    }

    /// Writes the part to `path` (under a temporary name first, then renamed: never half a file).
    pub fn write(&self, path: &Path) -> Result<()> {
        write_atomically(path, |tmp| {
            std::fs::write(tmp, self.to_bytes()).map_err(|e| e.to_string())
        })
        .map_err(|e| Error::file(path, format!("cannot write the partial file: {e}")))
    }

    /// Reads and checks a part written by [`Part::write`].
    pub fn read(path: &Path) -> Result<Part> {
        let bytes = std::fs::read(path)
            .map_err(|e| Error::file(path, format!("cannot read the partial file: {e}")))?;
        Part::from_bytes(&bytes).map_err(|message| Error::file(path, message))
    }

    /// Parses and checks a part's bytes; the error says what is wrong.
    pub fn from_bytes(bytes: &[u8]) -> std::result::Result<Part, String> {
        if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
            return Err("not a whitted partial file (it does not start with \"WHTPART\")".into());
        }
        if bytes.len() < HEADER + 8 {
            return Err(format!(
                "truncated: {} bytes, shorter than the {}-byte header",
                bytes.len(),
                HEADER + 8
            ));
        }
        let mut r = Reader { bytes, at: 8 };
        let version = r.u32();
        if version != VERSION {
            return Err(format!(
                "partial format version {version}; this whitted reads version {VERSION}"
            ));
        }
        r.u32();
        let scene = r.u64();
        let (width, height, tile, spp) = (r.u32(), r.u32(), r.u32(), r.u32());
        let seed = r.u64();
        let max_depth = r.u32();
        let (aperture, focal, roughness) = (r.f32(), r.f32(), r.f32());
        let (passes, first, end) = (r.u32(), r.u32(), r.u32());
        let part = (r.u32(), r.u32());
        let count = r.u32() as usize;
        check_resolution(width, height)?;
        if tile != TILE {
            return Err(format!(
                "tiles of {tile} pixels; this whitted renders tiles of {TILE}"
            ));
        }
        let grid = tiles::tiles(width, height);
        if count > grid.len() {
            return Err(format!(
                "{count} tiles, but a {width}x{height} frame has {}",
                grid.len()
            ));
        }
        // Everything the header says, checked for size before anything is read by it.
        let expected = |pixels: usize| HEADER + 4 * count + PIXEL * pixels + 8;
        if bytes.len() < expected(0) {
            return Err(truncated(bytes.len(), expected(0)));
        }
        let indices: Vec<u32> = (0..count).map(|_| r.u32()).collect();
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= grid.len()) {
            return Err(format!(
                "tile {bad} is outside the {width}x{height} frame's {} tiles",
                grid.len()
            ));
        }
        if indices.windows(2).any(|w| w[0] >= w[1]) {
            return Err("tile indices are not increasing".into());
        }
        let pixels: usize = indices.iter().map(|&i| area(grid[i as usize])).sum();
        if bytes.len() != expected(pixels) {
            return Err(if bytes.len() < expected(pixels) {
                truncated(bytes.len(), expected(pixels))
            } else {
                format!(
                    "{} bytes, but its header describes {}",
                    bytes.len(),
                    expected(pixels)
                )
            });
        }
        let body = bytes.len() - 8;
        let stored = u64::from_le_bytes(bytes[body..].try_into().expect("eight bytes"));
        let computed = digest::of_bytes(&bytes[..body]);
        if stored != computed {
            return Err(format!(
                "corrupt: checksum {computed:016x} does not match the stored {stored:016x}; render this part again"
            ));
        }
        if !(first < end && end <= passes) {
            return Err(format!(
                "pass range {first}..{end} is not within the render's {passes} passes"
            ));
        }
        if part.0 >= part.1 {
            return Err(format!("part {}/{} is not a valid K/N", part.0, part.1));
        }
        let mut sums = Vec::with_capacity(pixels);
        let mut counts = Vec::with_capacity(pixels);
        for _ in 0..pixels {
            sums.push([r.f64(), r.f64(), r.f64()]);
            counts.push(r.u32());
        }
        if counts.iter().any(|&c| c != end - first) {
            return Err(format!(
                "a pixel's pass count differs from its pass range {first}..{end}"
            ));
        }
        Ok(Part {
            settings: Settings {
                scene,
                width,
                height,
                spp,
                seed,
                max_depth,
                aperture,
                focal,
                roughness,
                passes,
            },
            passes: first..end,
            part,
            tiles: indices,
            sums,
            counts,
        })
    }
}

fn truncated(len: usize, expected: usize) -> String {
    format!("truncated: {len} bytes where its header describes {expected}")
}

/// Little-endian fields in order (lengths are checked before reading).
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let v = self.bytes[self.at..self.at + N]
            .try_into()
            .expect("length checked");
        self.at += N;
        v
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
    }
    fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.take())
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take())
    }
    fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;
    use glam::Vec3;

    fn part() -> Part {
        let settings = Settings {
            scene: 7,
            width: 20,
            height: 18,
            spp: 1,
            seed: 3,
            max_depth: 6,
            aperture: 0.0,
            focal: 1.0,
            roughness: 0.0,
            passes: 4,
        };
        let tiles = vec![1, 2];
        // A 20x18 frame has tiles of 16x16, 4x16, 16x2 and 4x2 pixels.
        let pixels = 4 * 16 + 16 * 2;
        Part {
            settings,
            passes: 1..3,
            part: (1, 2),
            tiles,
            sums: (0..pixels).map(|i| [i as f64, 0.5, -1.0]).collect(),
            counts: vec![2; pixels],
        }
    }

    #[test]
    fn settings_take_the_options_and_the_camera_lens() {
        let mut scene = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        (scene.camera.aperture, scene.camera.focal) = (2.5, 0.75);
        let options = Options {
            width: 20,
            height: 18,
            spp: 1,
            seed: 3,
            roughness: 0.25,
            ..Options::new(&scene)
        };
        let expected = Settings {
            scene: scene.fingerprint(),
            width: 20,
            height: 18,
            spp: 1,
            seed: 3,
            max_depth: 6,
            aperture: 2.5,
            focal: 0.75,
            roughness: 0.25,
            passes: 4,
        };
        assert_eq!(Settings::new(&scene, &options, 4), expected);
    }

    #[test]
    fn round_trips_and_refuses_damage() {
        let p = part();
        let bytes = p.to_bytes();
        assert_eq!(Part::from_bytes(&bytes).unwrap(), p);
        for at in [0, 9, 20, 60, HEADER + 2, bytes.len() / 2, bytes.len() - 1] {
            let mut bad = bytes.clone();
            bad[at] ^= 0x10;
            assert!(Part::from_bytes(&bad).is_err(), "flipped byte {at}");
        }
        for len in [0, 5, 40, HEADER + 8, bytes.len() - 1] {
            let err = Part::from_bytes(&bytes[..len]).unwrap_err();
            assert!(
                err.contains("truncated") || err.contains("not a whitted"),
                "{len}: {err}"
            );
        }
        let mut longer = bytes.clone();
        longer.push(0);
        assert!(Part::from_bytes(&longer).is_err());
    }
}
