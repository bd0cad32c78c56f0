//! Cost heatmaps: per-pixel counts (BVH nodes visited, primitive tests, rays traced, summed over every
//! ray a pixel sends) written as a false-colour PNG with a legend, and as raw float EXR.
//!
//! The colours are viridis (S. van der Walt and N. Smith, matplotlib's default colour map, 2015):
//! perceptually uniform, so that equal steps of cost read as equal steps of colour, legible to colour
//! blind readers and in grey; from `colorous::VIRIDIS`, d3-scale-chromatic's copy of the published
//! 256-entry table, not from colours tuned here.
//!
//! Costs are skewed: on the dragon scene the median pixel visits 6 BVH nodes and the costliest 258, so
//! a linear map to the largest count leaves nearly the whole image in viridis's darkest tenth. The
//! [`Scale`] says how counts reach the colours: by default log(1 + count), up to the 99th percentile.
//!
//! The legend is drawn with the public-domain 8×8 glyphs of `font8x8`: a PNG that says what it counts
//! and how its scale runs is readable without the command line that made it.

use std::fmt;
use std::path::Path;
use std::str::FromStr;

use glam::Vec3;

pub mod cost;

use crate::error::{Error, Result};
use crate::image::film::{Film, ImageFormat, write_png_rgb8};

/// Viridis at `t` (0 the bottom of the map, 1 the top; clamped, NaN is 0), as sRGB bytes.
pub fn viridis(t: f32) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let c = colorous::VIRIDIS.eval_continuous(f64::from(t));
    [c.r, c.g, c.b]
}

/// The index of the `p`th percentile, by nearest rank, among `n` sorted values (`n` at least 1): the
/// value with `ceil(p * n / 100)` values at or below it.
pub fn nearest_rank(n: usize, p: u32) -> usize {
    (p as usize * n).div_ceil(100).clamp(1, n) - 1
}

/// How a heatmap's counts map to its colour bar: the count itself or log(1 + count), from 0 at the
/// bottom to the largest count, or to a percentile of the counts, higher counts taking the top colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Scale {
    /// The bar is linear in log(1 + count) rather than in the count.
    pub log: bool,
    /// The percentile (1 to 99, nearest rank) at the top of the bar; `None` for the largest count.
    pub percentile: Option<u32>,
}

impl Default for Scale {
    /// `log:p99`. A percentile alone is not enough: on the dragon scene the p99 is 89 nodes and the
    /// median 6, still in the darkest tenth; the log puts the median at 0.43 of the bar, and the clamp
    /// keeps a few outliers from squeezing the rest.
    fn default() -> Self {
        Scale {
            log: true,
            percentile: Some(99),
        }
    }
}

impl FromStr for Scale {
    type Err = String;

    /// `linear`, `log`, `pNN` or `log:pNN`, NN a whole percentile from 1 to 99.
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || {
            format!(
                "unknown heatmap scale \"{s}\": expected linear, log, pNN or log:pNN, NN a percentile \
                 from 1 to 99 (such as p99; the default is log:p99)"
            )
        };
        let (log, top) = match s {
            "linear" => (false, None),
            "log" => (true, None),
            _ => match s.strip_prefix("log:") {
                Some(top) => (true, Some(top)),
                None => (false, Some(s)),
            },
        };
        let percentile = match top {
            None => None,
            Some(top) => {
                let digits = top
                    .strip_prefix('p')
                    .filter(|d| !d.is_empty() && d.len() <= 2 && d.bytes().all(|b| b.is_ascii_digit()));
                let p = digits.and_then(|d| d.parse::<u32>().ok());
                Some(p.filter(|p| (1..=99).contains(p)).ok_or_else(bad)?)
            }
        };
        Ok(Scale { log, percentile })
    }
}

impl fmt::Display for Scale {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match (self.log, self.percentile) {
            (false, None) => write!(f, "linear"),
            (true, None) => write!(f, "log"),
            (false, Some(p)) => write!(f, "p{p}"),
            (true, Some(p)) => write!(f, "log:p{p}"),
        }
    }
}

/// A [`Scale`] fitted to one map's values: the count at the top of the colour bar.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ramp {
    /// The scale asked for.
    pub scale: Scale,
    /// The scale's percentile of the values, if it has one.
    pub clamp: Option<f32>,
    /// The count at the top of the bar: the percentile, or the largest count where there is none or
    /// it is 0 (fewer than 1 pixel in 100 counts anything: clamped, every counted pixel would take the
    /// top colour).
    pub top: f32,
    /// The largest value.
    pub max: f32,
}

impl Ramp {
    /// `scale` fitted to `values`, non-finite and negative ones counting as 0.
    pub fn new(scale: Scale, values: &[f32]) -> Ramp {
        let mut values: Vec<f32> = values
            .iter()
            .map(|&v| if v.is_finite() { v.max(0.0) } else { 0.0 })
            .collect();
        let max = values.iter().copied().fold(0.0, f32::max);
        let clamp = scale.percentile.filter(|_| !values.is_empty()).map(|p| {
            let k = nearest_rank(values.len(), p);
            *values.select_nth_unstable_by(k, f32::total_cmp).1
        });
        let top = clamp.filter(|&c| c > 0.0).unwrap_or(max);
        Ramp {
            scale,
            clamp,
            top,
            max,
        }
    }

    /// Where `v` lies on the colour bar: 0 at the bottom (non-finite and negative values too), 1 at the
    /// top and above it.
    pub fn position(&self, v: f32) -> f32 {
        let v = if v.is_finite() { v.max(0.0) } else { 0.0 };
        if self.top <= 0.0 {
            return 0.0;
        }
        let t = if self.scale.log {
            v.ln_1p() / self.top.ln_1p()
        } else {
            v / self.top
        };
        t.min(1.0)
    }

    /// The count at `t` along the bar (0 to 1), the inverse of [`Ramp::position`] below the top.
    fn count_at(&self, t: f64) -> f64 {
        let top = f64::from(self.top);
        if self.scale.log {
            (t * top.ln_1p()).exp_m1()
        } else {
            t * top
        }
    }

    /// Whether values above the top take its colour.
    pub fn clamps(&self) -> bool {
        self.top < self.max
    }

    /// The numbers printed under the legend's ticks, the counts at 0, 1/4, 1/2, 3/4 and all of the
    /// bar: integers as integers, fractions with up to 3 decimals (3 significant digits below 1), those
    /// inside a log bar to 2 significant digits (its ticks fall between round counts); the top one
    /// `>=N` where higher counts take its colour.
    pub fn labels(&self) -> Vec<String> {
        (0..=4u32)
            .map(|k| match k {
                4 if self.clamps() => format!(">={}", format_label(f64::from(self.top))),
                4 => format_label(f64::from(self.top)),
                _ if self.scale.log => format_label(significant(self.count_at(f64::from(k) / 4.0), 2)),
                _ => format_label(self.count_at(f64::from(k) / 4.0)),
            })
            .collect()
    }

    /// The scale in the legend's words: "log scale to p99, max 258".
    pub fn describe(&self) -> String {
        let curve = if self.scale.log { "log" } else { "linear" };
        match (self.scale.percentile, self.clamp) {
            (Some(p), Some(c)) if c > 0.0 && self.clamps() => {
                format!("{curve} scale to p{p}, max {}", format_label(f64::from(self.max)))
            }
            (Some(p), Some(c)) if c > 0.0 => format!("{curve} scale to p{p} (the max)"),
            (Some(p), _) => format!("{curve} scale to the max (p{p} is 0)"),
            (None, _) => format!("{curve} scale to the max"),
        }
    }
}

/// Per-pixel costs of one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Heatmap {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// One value per pixel, row-major, top row first: a count, or a mean over samples.
    pub values: Vec<f32>,
    /// What the values are, printed in the legend: "BVH nodes tested per pixel", say.
    pub what: String,
    /// How the values map to colours.
    pub scale: Scale,
}

/// The legend's background, also the padding beside an image too narrow for the legend's text: a
/// neutral grey rather than black, since viridis's bottom is nearly black and a zero-cost pixel must not
/// look like padding.
const BACKGROUND: [u8; 3] = [64, 64, 64];
/// The legend's text and tick marks.
const INK: [u8; 3] = [240, 240, 240];

/// The legend's vertical layout in font pixels (one font pixel is `s` image pixels): margin, colour
/// bar, ticks, gap, numbers, gap, what is counted, gap, the scale, margin.
const MARGIN: u32 = 4;
const BAR: u32 = 12;
const TICK: u32 = 4;
const GAP: u32 = 2;
const GLYPH: u32 = 8;
const LINE_GAP: u32 = 4;
const LEGEND_HEIGHT: u32 = MARGIN + BAR + TICK + GAP + 3 * GLYPH + 2 * LINE_GAP + MARGIN;
/// The narrowest colour bar, in font pixels: narrower and the ramp is a few blocks.
const MIN_BAR: u32 = 64;
/// Images wider than this get the legend's font at twice the size, so that it stays legible when the
/// image is viewed scaled down to fit a screen.
const LARGE_IMAGE: u32 = 800;

impl Heatmap {
    /// The map's [`Scale`] fitted to its values.
    pub fn ramp(&self) -> Ramp {
        Ramp::new(self.scale, &self.values)
    }

    /// Writes the map in false colour (viridis along the [`Heatmap::ramp`]) with a legend strip below
    /// it: the colour bar, ticks and numbers at 0, 1/4, 1/2, 3/4 and its top, [`Heatmap::what`], and
    /// the scale ([`Ramp::describe`]). An image too narrow for the legend is centred on a wider canvas.
    /// `path` must name a `.png` file; it is written atomically, with an sRGB chunk (viridis's colours
    /// are sRGB), by the film's PNG writer.
    pub fn write_png(&self, path: &Path) -> Result<()> {
        self.check(path, ImageFormat::Png, "png")?;
        let (width, height, rgb) = self.to_rgb8();
        write_png_rgb8(path, width, height, rgb.as_flattened(), true)
    }

    /// Writes the raw values as a 32-bit float EXR, the value in all three channels, atomically:
    /// for tools that want the numbers rather than the picture. `path` must name a `.exr` file.
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        self.check(path, ImageFormat::Exr, "exr")?;
        let film = Film {
            width: self.width,
            height: self.height,
            pixels: self.values.iter().map(|&v| Vec3::splat(v)).collect(),
        };
        film.write(path, false)
    }

    /// The file name has the format's extension and the map is not empty and has one value per pixel.
    fn check(&self, path: &Path, format: ImageFormat, ext: &str) -> Result<()> {
        if ImageFormat::of(path).ok() != Some(format) {
            return Err(Error::file(
                path,
                format!("a heatmap is written here as .{ext}: expected a .{ext} file name"),
            ));
        }
        let pixels = self.width as usize * self.height as usize;
        if pixels == 0 || self.values.len() != pixels {
            return Err(Error::file(
                path,
                format!(
                    "cannot write a heatmap of {} values as a {}x{} image",
                    self.values.len(),
                    self.width,
                    self.height
                ),
            ));
        }
        Ok(())
    }

    /// The false-colour image at its own size with the legend drawn over its bottom rows (clipped where
    /// the image is narrower than the legend): sRGB pixels, row-major; for the viewer's window.
    pub fn overlaid(&self) -> Vec<[u8; 3]> {
        self.draw(true).2
    }

    /// The false-colour image with its legend below it: canvas width, height and sRGB pixels, row-major.
    fn to_rgb8(&self) -> (u32, u32, Vec<[u8; 3]>) {
        self.draw(false)
    }

    /// The image and its legend, below it on a canvas wide enough for it, or over its bottom rows.
    fn draw(&self, overlay: bool) -> (u32, u32, Vec<[u8; 3]>) {
        let s = if self.width > LARGE_IMAGE { 2 } else { 1 };
        let ramp = self.ramp();
        let labels = ramp.labels();
        let scale = ramp.describe();
        let margin = MARGIN * s;
        let glyph = GLYPH * s;
        let text_width = |t: &str| t.chars().count() as u32 * glyph;
        let w: Vec<u32> = labels.iter().map(|l| text_width(l)).collect();
        // Each quarter of the bar holds what its two ticks' numbers take of it (the end numbers are
        // aligned with the bar's ends, the others centred on their tick) and a character of space.
        let quarter = (0..4)
            .map(|k| {
                let left = if k == 0 { w[0] } else { w[k].div_ceil(2) };
                let right = if k == 3 { w[4] } else { w[k + 1].div_ceil(2) };
                left + right + glyph
            })
            .max()
            .unwrap_or(0);
        let bar_width = (4 * quarter).max(MIN_BAR * s);
        let (width, height, legend_y) = if overlay {
            let top = self.height.saturating_sub(LEGEND_HEIGHT * s);
            (self.width, self.height, top)
        } else {
            let width = self
                .width
                .max(bar_width + 2 * margin)
                .max(text_width(&self.what) + 2 * margin)
                .max(text_width(&scale) + 2 * margin);
            (width, self.height + LEGEND_HEIGHT * s, self.height)
        };
        let mut canvas = Canvas {
            width,
            height,
            pixels: vec![BACKGROUND; width as usize * height as usize],
        };

        // The image, centred.
        let x0 = (width - self.width) / 2;
        for (y, row) in self.values.chunks_exact(self.width as usize).enumerate() {
            for (x, &v) in row.iter().enumerate() {
                canvas.set(x0 + x as u32, y as u32, viridis(ramp.position(v)));
            }
        }

        // The colour bar, its ticks, their numbers, and the labels (over a strip of background).
        canvas.fill(0, legend_y, width, LEGEND_HEIGHT * s, BACKGROUND);
        let bar_x = margin;
        let bar_width = width.saturating_sub(2 * margin).max(1);
        let mut y = legend_y + margin;
        for x in 0..bar_width {
            let c = viridis(x as f32 / (bar_width - 1).max(1) as f32);
            canvas.fill(bar_x + x, y, 1, BAR * s, c);
        }
        y += BAR * s;
        for (k, (label, &lw)) in labels.iter().zip(&w).enumerate() {
            let tick = bar_x + (k as u32 * (bar_width - 1)) / 4;
            canvas.fill(
                tick.saturating_sub(s / 2).min(bar_x + bar_width - s),
                y,
                s,
                TICK * s,
                INK,
            );
            let x = match k {
                0 => bar_x,
                4 => bar_x + bar_width - lw,
                _ => tick.saturating_sub(lw / 2),
            };
            canvas.text(x, y + (TICK + GAP) * s, s, label);
        }
        y += (TICK + GAP + GLYPH + LINE_GAP) * s;
        for line in [&self.what, &scale] {
            canvas.text(width.saturating_sub(text_width(line)) / 2, y, s, line);
            y += (GLYPH + LINE_GAP) * s;
        }
        (width, height, canvas.pixels)
    }
}

/// An sRGB image being drawn; writes outside it are dropped.
struct Canvas {
    width: u32,
    height: u32,
    pixels: Vec<[u8; 3]>,
}

impl Canvas {
    fn set(&mut self, x: u32, y: u32, c: [u8; 3]) {
        if x < self.width && y < self.height {
            self.pixels[(y * self.width + x) as usize] = c;
        }
    }

    fn fill(&mut self, x: u32, y: u32, w: u32, h: u32, c: [u8; 3]) {
        for yy in y..y + h {
            for xx in x..x + w {
                self.set(xx, yy, c);
            }
        }
    }

    /// `text` from its top-left corner, each font pixel `s` × `s` image pixels; a character the font
    /// lacks (it has ASCII) is a `?`.
    fn text(&mut self, x: u32, y: u32, s: u32, text: &str) {
        for (i, ch) in text.chars().enumerate() {
            let code = if ch.is_ascii() { ch as usize } else { '?' as usize };
            let glyph = font8x8::legacy::BASIC_LEGACY[code];
            let gx = x + i as u32 * GLYPH * s;
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8 {
                    // Bit 0 is the leftmost pixel.
                    if bits >> col & 1 == 1 {
                        self.fill(gx + col * s, y + row as u32 * s, s, s, INK);
                    }
                }
            }
        }
    }
}

/// `v` rounded to `digits` significant digits.
fn significant(v: f64, digits: i32) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let scale = 10f64.powi(digits - 1 - v.abs().log10().floor() as i32);
    (v * scale).round() / scale
}

/// A legend number: an integer as one; otherwise rounded to 3 decimals, or to 3 significant digits
/// below 1, trailing zeros dropped.
fn format_label(v: f64) -> String {
    if !v.is_finite() {
        return v.to_string();
    }
    if v.abs() >= 1e15 {
        return format!("{v:.3e}");
    }
    if v == v.round() {
        return format!("{}", v as i64);
    }
    let decimals = if v.abs() >= 1.0 {
        3
    } else {
        (2 - v.abs().log10().floor() as i32).clamp(3, 12) as usize
    };
    let s = format!("{v:.decimals$}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::codecs::read_back;

    /// matplotlib's published viridis table (`_viridis_data`, van der Walt and Smith 2015): entries 0
    /// and 255, and the mean of entries 127 and 128 (0.5 lies between them), as 0..1 sRGB values.
    const PUBLISHED_0: [f32; 3] = [0.267004, 0.004874, 0.329415];
    const PUBLISHED_HALF: [f32; 3] = [
        (0.128729 + 0.127568) / 2.0,
        (0.563265 + 0.566949) / 2.0,
        (0.551229 + 0.550556) / 2.0,
    ];
    const PUBLISHED_1: [f32; 3] = [0.993248, 0.906157, 0.143936];

    /// Viridis against the published table at 0, 0.5 and 1, within one 8-bit step.
    #[test]
    fn viridis_is_the_published_table() {
        for (t, want) in [(0.0, PUBLISHED_0), (0.5, PUBLISHED_HALF), (1.0, PUBLISHED_1)] {
            let got = viridis(t);
            for c in 0..3 {
                let want = want[c] * 255.0;
                assert!(
                    (f32::from(got[c]) - want).abs() <= 1.0,
                    "viridis({t}) = {got:?}, channel {c}: want {want:.2}"
                );
            }
        }
        assert_eq!(viridis(-1.0), viridis(0.0));
        assert_eq!(viridis(f32::NAN), viridis(0.0));
        assert_eq!(viridis(7.0), viridis(1.0));
    }

    const LINEAR: Scale = Scale {
        log: false,
        percentile: None,
    };

    /// A map of rows running from 0 to `max`, on the linear scale.
    fn gradient(width: u32, height: u32, max: f32, what: &str) -> Heatmap {
        let values = (0..height)
            .flat_map(|_| (0..width).map(move |x| max * x as f32 / (width - 1).max(1) as f32))
            .collect();
        Heatmap {
            width,
            height,
            values,
            what: what.into(),
            scale: LINEAR,
        }
    }

    /// A one-row map of `values`, on `scale`.
    fn row(values: Vec<f32>, scale: Scale) -> Heatmap {
        Heatmap {
            width: values.len() as u32,
            height: 1,
            values,
            what: "x".into(),
            scale,
        }
    }

    fn scale(s: &str) -> Scale {
        s.parse().unwrap()
    }

    #[test]
    fn scales_parse_print_and_refuse_with_the_accepted_forms() {
        for (text, log, percentile) in [
            ("linear", false, None),
            ("log", true, None),
            ("p99", false, Some(99)),
            ("p1", false, Some(1)),
            ("log:p95", true, Some(95)),
        ] {
            assert_eq!(scale(text), Scale { log, percentile }, "{text}");
            assert_eq!(scale(text).to_string(), text);
        }
        assert_eq!(Scale::default().to_string(), "log:p99");
        for bad in [
            "",
            "p",
            "p0",
            "p100",
            "p+5",
            "p9.5",
            "99",
            "log:",
            "log:linear",
            "logp99",
            "Linear",
        ] {
            let e = bad.parse::<Scale>().unwrap_err();
            assert!(
                e.starts_with(&format!(
                    "unknown heatmap scale \"{bad}\": expected linear, log, pNN or log:pNN"
                )),
                "{e}"
            );
        }
    }

    #[test]
    fn a_percentile_scale_ends_at_the_nearest_rank_and_clamps_above_it() {
        // 1..=100: the nearest-rank p99 is 99, the 99th value; only 100 lies above it.
        let map = row((1..=100).map(|v| v as f32).collect(), scale("p99"));
        let ramp = map.ramp();
        assert_eq!((ramp.clamp, ramp.top, ramp.max), (Some(99.0), 99.0, 100.0));
        assert!(ramp.clamps());
        assert_eq!(ramp.position(49.5), 0.5);
        assert_eq!(ramp.position(99.0), 1.0);
        assert_eq!(ramp.position(100.0), 1.0);
        assert_eq!(ramp.labels(), ["0", "24.75", "49.5", "74.25", ">=99"]);
        assert_eq!(ramp.describe(), "linear scale to p99, max 100");
        // 990 pixels at 10 and 10 at 1000: the p99 is 10, the costly tenth of a percent is clamped.
        let values = [vec![10.0; 990], vec![1000.0; 10]].concat();
        let ramp = row(values, scale("p99")).ramp();
        assert_eq!(
            (ramp.top, ramp.position(5.0), ramp.position(1000.0)),
            (10.0, 0.5, 1.0)
        );
        // The median of 1, 2, 3, 4: the 2nd value.
        assert_eq!(row(vec![4.0, 3.0, 2.0, 1.0], scale("p50")).ramp().top, 2.0);
        // Where the percentile is the max, nothing is clamped and the top is a plain number.
        let ramp = row(vec![7.0; 10], scale("p99")).ramp();
        assert!(!ramp.clamps());
        assert_eq!(ramp.labels()[4], "7");
        assert_eq!(ramp.describe(), "linear scale to p99 (the max)");
        // A percentile of 0 would draw every counted pixel at the top: the bar ends at the max.
        let values = [vec![0.0; 995], vec![7.0; 5]].concat();
        let ramp = row(values, scale("p99")).ramp();
        assert_eq!((ramp.clamp, ramp.top), (Some(0.0), 7.0));
        assert_eq!(ramp.describe(), "linear scale to the max (p99 is 0)");
        assert_eq!(nearest_rank(100, 99), 98);
        assert_eq!(nearest_rank(1000, 50), 499);
        assert_eq!(nearest_rank(1, 1), 0);
    }

    #[test]
    fn a_log_scale_is_linear_in_log_of_one_plus_the_count() {
        // To the max 99: log(1 + 9) is half of log(1 + 99), 10^(1/2) - 1 a quarter, 10^(3/2) - 1
        // three quarters.
        let map = row(vec![0.0, 9.0, 99.0], scale("log"));
        let ramp = map.ramp();
        assert_eq!((ramp.top, ramp.position(0.0)), (99.0, 0.0));
        assert!((ramp.position(9.0) - 0.5).abs() < 1e-6);
        assert_eq!(ramp.position(99.0), 1.0);
        assert_eq!(ramp.labels(), ["0", "2.2", "9", "31", "99"]);
        assert_eq!(ramp.describe(), "log scale to the max");
        // Clamped at the p50 of 0, 3, 9, 99: 3, whose log(1 + 3) is twice log(1 + 1).
        let map = row(vec![0.0, 3.0, 9.0, 99.0], scale("log:p50"));
        let ramp = map.ramp();
        assert_eq!(ramp.top, 3.0);
        assert!((ramp.position(1.0) - 0.5).abs() < 1e-6);
        assert_eq!((ramp.position(9.0), ramp.position(99.0)), (1.0, 1.0));
        assert_eq!(ramp.labels(), ["0", "0.41", "1", "1.8", ">=3"]);
        assert_eq!(ramp.describe(), "log scale to p50, max 99");
    }

    #[test]
    fn the_linear_scale_runs_from_0_to_the_max() {
        let map = row(vec![0.0, 25.0, 40.0, 100.0, f32::NAN, -3.0], LINEAR);
        let ramp = map.ramp();
        assert_eq!((ramp.clamp, ramp.top, ramp.max), (None, 100.0, 100.0));
        assert!(!ramp.clamps());
        let at = |v: f32| ramp.position(v);
        assert_eq!([at(0.0), at(25.0), at(40.0), at(100.0)], [0.0, 0.25, 0.4, 1.0]);
        assert_eq!([at(f32::NAN), at(-3.0), at(f32::INFINITY)], [0.0; 3]);
        assert_eq!(ramp.labels(), ["0", "25", "50", "75", "100"]);
        assert_eq!(ramp.describe(), "linear scale to the max");
    }

    /// The PNG's pixels are viridis at the ramp's positions: of 10, 20, 30, 40 on a p50 scale (20),
    /// half way, then the top; on the default scale (to 40), log(1 + count) / log(41) of the way.
    #[test]
    fn the_png_is_coloured_along_the_ramp() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.png");
        let log = |v: f32| (1.0 + v).ln() / 41f32.ln();
        for (s, want) in [
            ("p50", [0.5, 1.0, 1.0, 1.0]),
            ("log:p99", [log(10.0), log(20.0), log(30.0), 1.0]),
        ] {
            let map = row(vec![10.0, 20.0, 30.0, 40.0], scale(s));
            map.write_png(&path).unwrap();
            let img = read_back::rgb(&path);
            let x0 = (img.width() - 4) / 2;
            let ramp = map.ramp();
            for (x, (&v, t)) in map.values.iter().zip(want).enumerate() {
                assert!((ramp.position(v) - t).abs() < 1e-6, "{s}, {v}");
                assert_eq!(
                    img.get_pixel(x0 + x as u32, 0),
                    viridis(ramp.position(v)),
                    "{s}, {v}"
                );
            }
        }
    }

    fn read_exr_max(path: &Path) -> f32 {
        read_back::exr(path).2.iter().map(|p| p[0]).fold(0.0, f32::max)
    }

    #[test]
    fn labels_format_integers_as_integers_and_fractions_briefly() {
        assert_eq!(format_label(0.0), "0");
        assert_eq!(format_label(1234.0), "1234");
        assert_eq!(format_label(308.5), "308.5");
        assert_eq!(format_label(12.345_678), "12.346");
        assert_eq!(format_label(0.5), "0.5");
        assert_eq!(format_label(0.001_234_5), "0.00123");
        assert_eq!(format_label(0.999_96), "1");
        let map = gradient(5, 1, 1234.0, "nodes");
        assert_eq!(map.ramp().labels(), ["0", "308.5", "617", "925.5", "1234"]);
    }

    #[test]
    fn the_legends_last_label_is_the_max_in_the_exr() {
        let dir = tempfile::tempdir().unwrap();
        // Integer counts: the label is the integer itself.
        let mut map = gradient(64, 16, 1234.0, "BVH nodes tested per pixel");
        map.values[17] = 5000.0;
        let exr = dir.path().join("nodes.exr");
        map.write_exr(&exr).unwrap();
        let exr_max = read_exr_max(&exr);
        assert_eq!(exr_max, 5000.0);
        assert_eq!(
            map.ramp().labels().last().unwrap(),
            &format!("{}", exr_max as u64)
        );
        // A mean over samples: the label is the max to 3 decimals.
        let map = gradient(8, 8, 3.141_73, "primitive tests per pixel (shadow rays)");
        let exr = dir.path().join("mean.exr");
        map.write_exr(&exr).unwrap();
        let label: f32 = map.ramp().labels().last().unwrap().parse().unwrap();
        assert!((label - read_exr_max(&exr)).abs() <= 0.0005, "{label}");
        assert_eq!(map.ramp().labels().last().unwrap(), "3.142");
    }

    #[test]
    fn the_png_is_the_image_and_the_legend_strip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("g.png");
        gradient(640, 480, 1000.0, "BVH nodes tested per pixel")
            .write_png(&path)
            .unwrap();
        let img = read_back::rgb(&path);
        assert_eq!(img.dimensions(), (640, 480 + LEGEND_HEIGHT));
        // Wide images get the font at twice the size.
        gradient(1024, 8, 10.0, "rays traced per pixel")
            .write_png(&path)
            .unwrap();
        let img = read_back::rgb(&path);
        assert_eq!(img.dimensions(), (1024, 8 + 2 * LEGEND_HEIGHT));
        assert_eq!(
            std::fs::read_dir(dir.path()).unwrap().count(),
            1,
            "no temporary left behind"
        );
    }

    #[test]
    fn zero_is_the_maps_bottom_and_the_max_its_top() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("halves.png");
        let (w, h) = (20, 10);
        let values = (0..h)
            .flat_map(|_| (0..w).map(|x| if x < w / 2 { 0.0 } else { 77.0 }))
            .collect();
        let map = Heatmap {
            width: w,
            height: h,
            values,
            what: "x".into(),
            scale: LINEAR,
        };
        map.write_png(&path).unwrap();
        let img = read_back::rgb(&path);
        // The canvas is wider than the image (the legend's numbers need room): the image is centred.
        let x0 = (img.width() - w) / 2;
        assert!(img.width() > w);
        assert_eq!(
            img.get_pixel(x0, h - 1),
            viridis(0.0),
            "bottom-left of the zero half"
        );
        assert_eq!(img.get_pixel(x0 + w - 1, 0), viridis(1.0), "a max-valued pixel");
        assert_eq!(img.get_pixel(0, 0), BACKGROUND, "padding");
        // The colour bar runs from the bottom to the top.
        let bar_y = h + MARGIN + BAR / 2;
        assert_eq!(img.get_pixel(MARGIN, bar_y), viridis(0.0));
        assert_eq!(img.get_pixel(img.width() - MARGIN - 1, bar_y), viridis(1.0));
        assert_eq!(map.ramp().labels(), ["0", "19.25", "38.5", "57.75", "77"]);
    }

    #[test]
    fn an_all_zero_map_writes_at_the_bottom_colour() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("zero.png");
        let map = Heatmap {
            width: 40,
            height: 30,
            values: vec![0.0; 1200],
            what: "primitive tests per pixel".into(),
            scale: Scale::default(),
        };
        map.write_png(&path).unwrap();
        assert_eq!(map.ramp().labels(), ["0"; 5]);
        let img = read_back::rgb(&path);
        let x0 = (img.width() - 40) / 2;
        for y in 0..30 {
            for x in x0..x0 + 40 {
                assert_eq!(img.get_pixel(x, y), viridis(0.0));
            }
        }
        map.write_exr(&dir.path().join("zero.exr")).unwrap();
    }

    /// The rows of the canvas, from `y0` on, that hold text (light pixels).
    fn text_rows(img: &read_back::Rgb8, y0: u32) -> Vec<u32> {
        (y0..img.height())
            .filter(|&y| (0..img.width()).any(|x| img.get_pixel(x, y) == INK))
            .collect()
    }

    #[test]
    fn tiny_maps_widen_the_canvas_to_keep_the_legend_legible() {
        let dir = tempfile::tempdir().unwrap();
        for (w, h) in [(1, 1), (32, 8)] {
            let what = "BVH nodes tested per pixel";
            let mut map = gradient(w, h, 12345.0, what);
            map.values[0] = 12345.0;
            map.scale = Scale::default();
            let path = dir.path().join(format!("{w}x{h}.png"));
            map.write_png(&path).unwrap();
            let img = read_back::rgb(&path);
            assert_eq!(img.height(), h + LEGEND_HEIGHT);
            // The label fits at full 8-pixel size with a margin, and the five numbers side by side.
            assert!(
                img.width() >= what.len() as u32 * GLYPH + 2 * MARGIN,
                "{}",
                img.width()
            );
            let numbers: u32 = map.ramp().labels().iter().map(|l| l.len() as u32 * GLYPH).sum();
            assert!(img.width() >= numbers + 2 * MARGIN, "{}", img.width());
            // Ticks, numbers, the label and the scale are drawn, each its own band of rows.
            let rows = text_rows(&img, h + MARGIN + BAR);
            assert!(rows.len() >= TICK as usize + 3 * 6, "{rows:?}");
            assert_eq!(
                *rows.last().unwrap(),
                h + LEGEND_HEIGHT - MARGIN - 1,
                "the descenders of the scale's \"p99\""
            );
        }
    }

    #[test]
    fn bad_names_and_sizes_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let map = gradient(4, 4, 1.0, "x");
        let e = map.write_png(&dir.path().join("a.jpg")).unwrap_err().to_string();
        assert!(e.contains("expected a .png file name"), "{e}");
        let e = map.write_exr(&dir.path().join("a.png")).unwrap_err().to_string();
        assert!(e.contains("expected a .exr file name"), "{e}");
        let short = Heatmap {
            values: vec![0.0; 3],
            ..map.clone()
        };
        let e = short
            .write_png(&dir.path().join("a.png"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("cannot write a heatmap of 3 values as a 4x4 image"),
            "{e}"
        );
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}
