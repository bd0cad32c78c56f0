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

use std::io::Read;
use std::ops::Range;
use std::path::Path;

use crate::digest;
use crate::error::{Error, Result};
use crate::files::{open_regular, write_atomically};
use crate::render::Options;
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
pub struct PartSettings {
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

impl PartSettings {
    /// The settings of a render of `scene` (its camera's lens included, after any override) with
    /// `options`, in `passes` passes of `options.spp` samples each.
    pub fn new(scene: &Scene, options: &Options, passes: u32) -> Self {
        PartSettings {
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
    pub fn differences(&self, other: &PartSettings) -> Vec<String> {
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

#[cfg(test)]
impl PartSettings {
    /// The settings of a `width` × `height` test render of 4 passes (scene fingerprint 7, seed 3).
    pub(crate) fn for_tests(width: u32, height: u32) -> Self {
        PartSettings {
            scene: 7,
            width,
            height,
            spp: 1,
            seed: 3,
            max_depth: 6,
            aperture: 0.0,
            focal: 1.0,
            roughness: 0.0,
            passes: 4,
        }
    }
}

/// A part of a frame: some of its tiles over some of its passes.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// The render this is a part of.
    pub settings: PartSettings,
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
    pub fn new(settings: PartSettings, progressive: &Progressive, first: u32, part: (u32, u32)) -> Self {
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
        write_atomically(path, |file| {
            std::io::Write::write_all(file, &self.to_bytes()).map_err(|e| e.to_string())
        })
        .map_err(|e| Error::file(path, format!("cannot write the partial file: {e}")))
    }

    /// Reads and checks a part written by [`Part::write`]. The header and the tile list are read first
    /// and the length they imply is compared with the file's before the pixels are read, so that a
    /// device such as `/dev/zero` (refused by its type), a truncated file or one much longer than its
    /// header describes is named without being read into memory.
    pub fn read(path: &Path) -> Result<Part> {
        read_checked(path).map_err(|message| Error::file(path, message))
    }

    /// Parses and checks a part's bytes; the error says what is wrong.
    pub fn from_bytes(bytes: &[u8]) -> std::result::Result<Part, String> {
        let header = Header::parse(bytes)?;
        let len = header.file_len(&bytes[HEADER..])?;
        check_len(bytes.len(), len)?;
        let body = bytes.len() - 8;
        let stored = u64::from_le_bytes(bytes[body..].try_into().expect("eight bytes"));
        let computed = digest::of_bytes(&bytes[..body]);
        if stored != computed {
            return Err(format!(
                "corrupt: checksum {computed:016x} does not match the stored {stored:016x}; render this part again"
            ));
        }
        let Header {
            settings,
            first,
            end,
            part,
            count,
        } = header;
        if !(first < end && end <= settings.passes) {
            return Err(format!(
                "pass range {first}..{end} is not within the render's {} passes",
                settings.passes
            ));
        }
        if part.0 >= part.1 {
            return Err(format!("part {}/{} is not a valid K/N", part.0, part.1));
        }
        let mut r = Reader { bytes, at: HEADER };
        let tiles: Vec<u32> = (0..count).map(|_| r.u32()).collect();
        let pixels = (len - HEADER - 4 * count - 8) / PIXEL;
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
            settings,
            passes: first..end,
            part,
            tiles,
            sums,
            counts,
        })
    }

    /// The accumulator of this part's tiles and passes, to render more of the same render into.
    pub fn into_progressive(self) -> Progressive {
        let passes = self.passes.end - self.passes.start;
        let PartSettings { width, height, .. } = self.settings;
        Progressive::with_sums(width, height, self.tiles, self.sums, passes)
    }
}

/// [`Part::read`], its error without the path.
fn read_checked(path: &Path) -> std::result::Result<Part, String> {
    let cannot = |e: std::io::Error| format!("cannot read the partial file: {e}");
    let mut file = open_regular(path).map_err(|why| format!("cannot read the partial file: {why}"))?;
    let metadata = file.metadata().map_err(cannot)?;
    let len = usize::try_from(metadata.len()).unwrap_or(usize::MAX);
    // Reads up to `n` more bytes (fewer at the end of the file).
    let mut bytes = Vec::new();
    let mut more = |bytes: &mut Vec<u8>, n: usize| {
        file.by_ref()
            .take(n as u64)
            .read_to_end(bytes)
            .map(drop)
            .map_err(cannot)
    };
    more(&mut bytes, HEADER + 8)?;
    let header = Header::parse(&bytes)?;
    more(&mut bytes, 4 * header.count)?;
    let expected = header.file_len(&bytes[HEADER..])?;
    check_len(len, expected)?;
    let rest = expected - bytes.len();
    more(&mut bytes, rest)?;
    Part::from_bytes(&bytes)
}

/// The fixed header of a `.partial` file: the first [`HEADER`] bytes.
struct Header {
    settings: PartSettings,
    /// The first pass of the part.
    first: u32,
    /// One past its last pass.
    end: u32,
    /// K of N.
    part: (u32, u32),
    /// How many tile indices follow.
    count: usize,
}

impl Header {
    /// Parses the header at the start of `bytes` (which must hold it and the checksum after it) and
    /// checks what can be checked without the rest: the magic, the version, the resolution, the tile
    /// size and the tile count.
    fn parse(bytes: &[u8]) -> std::result::Result<Header, String> {
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
        let tiles = tiles::tiles(width, height).len();
        if count > tiles {
            return Err(format!("{count} tiles, but a {width}x{height} frame has {tiles}"));
        }
        let settings = PartSettings {
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
        };
        Ok(Header {
            settings,
            first,
            end,
            part,
            count,
        })
    }

    /// The length of the whole file, from the header and the tile indices at the start of `rest` (the
    /// bytes after the header), after checking the indices: in the frame and increasing.
    fn file_len(&self, rest: &[u8]) -> std::result::Result<usize, String> {
        let expected = |pixels: usize| HEADER + 4 * self.count + PIXEL * pixels + 8;
        if rest.len() < 4 * self.count + 8 {
            return Err(truncated(HEADER + rest.len(), expected(0)));
        }
        let (width, height) = (self.settings.width, self.settings.height);
        let grid = tiles::tiles(width, height);
        let mut r = Reader { bytes: rest, at: 0 };
        let indices: Vec<u32> = (0..self.count).map(|_| r.u32()).collect();
        if let Some(bad) = indices.iter().find(|&&i| i as usize >= grid.len()) {
            return Err(format!(
                "tile {bad} is outside the {width}x{height} frame's {} tiles",
                grid.len()
            ));
        }
        if indices.windows(2).any(|w| w[0] >= w[1]) {
            return Err("tile indices are not increasing".into());
        }
        Ok(expected(indices.iter().map(|&i| area(grid[i as usize])).sum()))
    }
}

/// A file of `len` bytes whose header describes `expected`.
fn check_len(len: usize, expected: usize) -> std::result::Result<(), String> {
    match len.cmp(&expected) {
        std::cmp::Ordering::Less => Err(truncated(len, expected)),
        std::cmp::Ordering::Greater => Err(format!("{len} bytes, but its header describes {expected}")),
        std::cmp::Ordering::Equal => Ok(()),
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
        let settings = PartSettings::for_tests(20, 18);
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
        let expected = PartSettings {
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
        assert_eq!(PartSettings::new(&scene, &options, 4), expected);
    }

    /// The length the header implies is compared with the file's before its pixels are read: a file
    /// cut short or far too long, a device and a directory are refused by what they are.
    #[cfg(unix)]
    #[test]
    fn reads_the_header_first_and_refuses_by_type_and_length() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("p.partial");
        let bytes = part().to_bytes();
        // Tiles 1 and 2 of 20x18 hold 4 x 16 + 16 x 2 = 96 pixels: 88 + 2 x 4 + 96 x 28 + 8 bytes.
        assert_eq!(bytes.len(), 2792);
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(Part::read(&path).unwrap(), part());
        let refused = |path: &Path| Part::read(path).unwrap_err().to_string();
        std::fs::write(&path, &bytes[..2000]).unwrap();
        assert_eq!(
            refused(&path),
            format!(
                "{}: truncated: 2000 bytes where its header describes 2792",
                path.display()
            )
        );
        std::fs::write(&path, &bytes).unwrap();
        let file = std::fs::File::options().write(true).open(&path).unwrap();
        file.set_len(1 << 36).unwrap();
        assert_eq!(
            refused(&path),
            format!(
                "{}: 68719476736 bytes, but its header describes 2792",
                path.display()
            )
        );
        for (not_a_file, what) in [
            (
                Path::new("/dev/zero"),
                "it is not a regular file (a FIFO, a device or a socket)",
            ),
            (dir.path(), "it is a directory"),
        ] {
            assert_eq!(
                refused(not_a_file),
                format!("{}: cannot read the partial file: {what}", not_a_file.display())
            );
        }
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
