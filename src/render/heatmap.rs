//! Cost heatmaps: per-pixel counts (BVH nodes visited, primitive tests, rays traced, summed over every
//! ray a pixel sends) written as a false-colour PNG with a legend, and as raw float EXR.
//!
//! The colours are viridis (S. van der Walt and N. Smith, matplotlib's default colour map, 2015):
//! perceptually uniform, so that equal steps of cost read as equal steps of colour, legible to colour
//! blind readers and in grey; from `colorous::VIRIDIS`, d3-scale-chromatic's copy of the published
//! 256-entry table, not from colours tuned here.
//!
//! The legend is drawn with the public-domain 8×8 glyphs of `font8x8`: a PNG that says what it counts
//! and where its scale ends is readable without the command line that made it.

use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::render::film::{Film, ImageFormat, write_png_rgb8};

/// Viridis at `t` (0 the bottom of the map, 1 the top; clamped, NaN is 0), as sRGB bytes.
pub fn viridis(t: f32) -> [u8; 3] {
    let t = if t.is_nan() { 0.0 } else { t.clamp(0.0, 1.0) };
    let c = colorous::VIRIDIS.eval_continuous(f64::from(t));
    [c.r, c.g, c.b]
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
}

/// The legend's background, also the padding beside an image too narrow for the legend's text: a
/// neutral grey rather than black, since viridis's bottom is nearly black and a zero-cost pixel must not
/// look like padding.
const BACKGROUND: [u8; 3] = [64, 64, 64];
/// The legend's text and tick marks.
const INK: [u8; 3] = [240, 240, 240];

/// The legend's vertical layout in font pixels (one font pixel is `scale` image pixels): margin, colour
/// bar, ticks, gap, numbers, gap, label, margin.
const MARGIN: u32 = 4;
const BAR: u32 = 12;
const TICK: u32 = 4;
const GAP: u32 = 2;
const GLYPH: u32 = 8;
const LINE_GAP: u32 = 4;
const LEGEND_HEIGHT: u32 = MARGIN + BAR + TICK + GAP + GLYPH + LINE_GAP + GLYPH + MARGIN;
/// The narrowest colour bar, in font pixels: narrower and the ramp is a few blocks.
const MIN_BAR: u32 = 64;
/// Images wider than this get the legend's font at twice the size, so that it stays legible when the
/// image is viewed scaled down to fit a screen.
const LARGE_IMAGE: u32 = 800;

impl Heatmap {
    /// The largest finite value, or 0 when there is none above 0: the top of the map.
    pub fn max(&self) -> f32 {
        self.values
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0, f32::max)
    }

    /// The numbers printed under the legend's ticks, at 0, 1/4, 1/2, 3/4 and all of [`Heatmap::max`]:
    /// integers as integers, fractions with up to 3 decimals (3 significant digits below 1).
    pub fn legend_labels(&self) -> Vec<String> {
        let max = f64::from(self.max());
        (0..=4u32)
            .map(|k| format_label(max * f64::from(k) / 4.0))
            .collect()
    }

    /// Writes the map in false colour (viridis, linear from 0 at the bottom to [`Heatmap::max`] at the
    /// top; non-finite and negative values count as 0) with a legend strip below it: the colour ramp,
    /// ticks and numbers at 0, 1/4, 1/2, 3/4 and the maximum, and [`Heatmap::what`]. An image too
    /// narrow for the legend is centred on a wider canvas. `path` must name a `.png` file; it is
    /// written atomically, with an sRGB chunk (viridis's colours are sRGB), by the film's PNG writer.
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
        let labels = self.legend_labels();
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
                .max(text_width(&self.what) + 2 * margin);
            (width, self.height + LEGEND_HEIGHT * s, self.height)
        };
        let mut canvas = Canvas {
            width,
            height,
            pixels: vec![BACKGROUND; width as usize * height as usize],
        };

        // The image, centred.
        let max = self.max();
        let x0 = (width - self.width) / 2;
        for (y, row) in self.values.chunks_exact(self.width as usize).enumerate() {
            for (x, &v) in row.iter().enumerate() {
                let t = if max > 0.0 && v.is_finite() { v / max } else { 0.0 };
                canvas.set(x0 + x as u32, y as u32, viridis(t));
            }
        }

        // The colour bar, its ticks, their numbers, and the label (over a strip of background).
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
        canvas.text((width - text_width(&self.what)) / 2, y, s, &self.what);
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

    fn gradient(width: u32, height: u32, max: f32, what: &str) -> Heatmap {
        let values = (0..height)
            .flat_map(|_| (0..width).map(move |x| max * x as f32 / (width - 1).max(1) as f32))
            .collect();
        Heatmap {
            width,
            height,
            values,
            what: what.into(),
        }
    }

    fn read_exr_max(path: &Path) -> f32 {
        let img = image::open(path).unwrap().to_rgb32f();
        img.pixels().map(|p| p.0[0]).fold(0.0, f32::max)
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
        assert_eq!(map.legend_labels(), ["0", "308.5", "617", "925.5", "1234"]);
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
            map.legend_labels().last().unwrap(),
            &format!("{}", exr_max as u64)
        );
        // A mean over samples: the label is the max to 3 decimals.
        let map = gradient(8, 8, 3.141_73, "primitive tests per pixel (shadow rays)");
        let exr = dir.path().join("mean.exr");
        map.write_exr(&exr).unwrap();
        let label: f32 = map.legend_labels().last().unwrap().parse().unwrap();
        assert!((label - read_exr_max(&exr)).abs() <= 0.0005, "{label}");
        assert_eq!(map.legend_labels().last().unwrap(), "3.142");
    }

    #[test]
    fn the_png_is_the_image_and_the_legend_strip() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("g.png");
        gradient(640, 480, 1000.0, "BVH nodes tested per pixel")
            .write_png(&path)
            .unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (640, 480 + LEGEND_HEIGHT));
        // Wide images get the font at twice the size.
        gradient(1024, 8, 10.0, "rays traced per pixel")
            .write_png(&path)
            .unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
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
        };
        map.write_png(&path).unwrap();
        let img = image::open(&path).unwrap().to_rgb8();
        // The canvas is wider than the image (the legend's numbers need room): the image is centred.
        let x0 = (img.width() - w) / 2;
        assert!(img.width() > w);
        assert_eq!(
            img.get_pixel(x0, h - 1).0,
            viridis(0.0),
            "bottom-left of the zero half"
        );
        assert_eq!(img.get_pixel(x0 + w - 1, 0).0, viridis(1.0), "a max-valued pixel");
        assert_eq!(img.get_pixel(0, 0).0, BACKGROUND, "padding");
        // The colour bar runs from the bottom to the top.
        let bar_y = h + MARGIN + BAR / 2;
        assert_eq!(img.get_pixel(MARGIN, bar_y).0, viridis(0.0));
        assert_eq!(img.get_pixel(img.width() - MARGIN - 1, bar_y).0, viridis(1.0));
        assert_eq!(map.legend_labels(), ["0", "19.25", "38.5", "57.75", "77"]);
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
        };
        map.write_png(&path).unwrap();
        assert_eq!(map.legend_labels(), ["0"; 5]);
        let img = image::open(&path).unwrap().to_rgb8();
        let x0 = (img.width() - 40) / 2;
        for y in 0..30 {
            for x in x0..x0 + 40 {
                assert_eq!(img.get_pixel(x, y).0, viridis(0.0));
            }
        }
        map.write_exr(&dir.path().join("zero.exr")).unwrap();
    }

    /// The rows of the canvas, from `y0` on, that hold text (light pixels).
    fn text_rows(img: &image::RgbImage, y0: u32) -> Vec<u32> {
        (y0..img.height())
            .filter(|&y| (0..img.width()).any(|x| img.get_pixel(x, y).0 == INK))
            .collect()
    }

    #[test]
    fn tiny_maps_widen_the_canvas_to_keep_the_legend_legible() {
        let dir = tempfile::tempdir().unwrap();
        for (w, h) in [(1, 1), (32, 8)] {
            let what = "BVH nodes tested per pixel";
            let mut map = gradient(w, h, 12345.0, what);
            map.values[0] = 12345.0;
            let path = dir.path().join(format!("{w}x{h}.png"));
            map.write_png(&path).unwrap();
            let img = image::open(&path).unwrap().to_rgb8();
            assert_eq!(img.height(), h + LEGEND_HEIGHT);
            // The label fits at full 8-pixel size with a margin, and the five numbers side by side.
            assert!(
                img.width() >= what.len() as u32 * GLYPH + 2 * MARGIN,
                "{}",
                img.width()
            );
            let numbers: u32 = map.legend_labels().iter().map(|l| l.len() as u32 * GLYPH).sum();
            assert!(img.width() >= numbers + 2 * MARGIN, "{}", img.width());
            // Ticks, numbers and the label are drawn, each its own band of rows.
            let rows = text_rows(&img, h + MARGIN + BAR);
            assert!(rows.len() >= TICK as usize + 2 * 6, "{rows:?}");
            assert_eq!(
                *rows.last().unwrap(),
                h + LEGEND_HEIGHT - MARGIN - 1,
                "the label's descenders"
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
