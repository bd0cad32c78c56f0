//! Merging the parts of a frame: they must be parts of one render and cover each pixel's passes exactly
//! once; their sums are then added up in a fixed order, so the image does not depend on the split.

use std::ops::Range;
use std::path::{Path, PathBuf};

use super::partial::{Part, PartSettings};
use crate::error::{Error, Result};
use crate::image::film::Film;
use crate::render::memory;
use crate::render::progressive::mean;
use crate::render::tiles::{self, Tile};

/// Reads the parts and merges them into the frame, after checking that they are parts of one render
/// and cover each pixel's passes exactly once; every error names the file(s) at fault. One part is in
/// memory at a time: each is read once to be checked (its sums then dropped) and once to be added,
/// after the memory the merge needs was found available ([`memory::check_merge`]).
pub fn merge(paths: &[PathBuf]) -> Result<Film> {
    let Some(first_path) = paths.first() else {
        return Err(Error::msg("no partial files to merge"));
    };
    let mut parts = Vec::with_capacity(paths.len());
    for path in paths {
        parts.push((path.as_path(), layout(&Part::read(path)?)));
    }
    let settings = parts[0].1.settings;
    for (path, part) in &parts[1..] {
        let diff = settings.differences(&part.settings);
        if !diff.is_empty() {
            return Err(Error::file(
                path,
                format!(
                    "not a part of the same render as {}: {}",
                    first_path.display(),
                    diff.join(", ")
                ),
            ));
        }
    }
    check_coverage(&parts, &settings)?;
    let (w, h) = (settings.width, settings.height);
    memory::check_merge(w, h).map_err(Error::msg)?;

    // Sum in pass order (then tile order), whatever order the files were named in, so that the
    // result does not depend on it.
    parts.sort_by_key(|(_, p)| (p.passes.start, p.tiles.first().copied()));
    let grid = tiles::tiles(w, h);
    let mut sums = vec![[0.0f64; 3]; w as usize * h as usize];
    let mut counts = vec![0u32; sums.len()];
    for (path, checked) in &parts {
        let part = Part::read(path)?;
        if layout(&part) != *checked {
            return Err(Error::file(path, "changed while the parts were merged"));
        }
        let mut at = 0;
        for &i in &part.tiles {
            let t = grid[i as usize];
            for y in t.y0..t.y1 {
                for x in t.x0..t.x1 {
                    let p = (y * w + x) as usize;
                    for (s, v) in sums[p].iter_mut().zip(part.sums[at]) {
                        *s += v;
                    }
                    counts[p] += part.counts[at];
                    at += 1;
                }
            }
        }
    }
    let mut film = Film::new(w, h);
    for ((pixel, sum), n) in film.pixels.iter_mut().zip(&sums).zip(&counts) {
        *pixel = mean(*sum, f64::from(*n));
    }
    Ok(film)
}

/// A part without its pixels: what the checks need of it.
fn layout(part: &Part) -> Part {
    Part {
        settings: part.settings,
        passes: part.passes.clone(),
        part: part.part,
        tiles: part.tiles.clone(),
        sums: Vec::new(),
        counts: Vec::new(),
    }
}

/// Checks that every tile's passes `0..settings.passes` are covered by exactly one part each.
fn check_coverage(parts: &[(&Path, Part)], settings: &PartSettings) -> Result<()> {
    let grid = tiles::tiles(settings.width, settings.height);
    // Per tile, the pass ranges covering it and the part each came from.
    let mut cover: Vec<Vec<(Range<u32>, usize)>> = vec![Vec::new(); grid.len()];
    for (k, (_, part)) in parts.iter().enumerate() {
        for &i in &part.tiles {
            cover[i as usize].push((part.passes.clone(), k));
        }
    }
    let mut overlaps: Vec<(usize, usize, Range<u32>)> = Vec::new();
    // Missing pass ranges, with the tiles they are missing from.
    let mut gaps: Vec<(Range<u32>, Vec<Tile>)> = Vec::new();
    for (tile, ranges) in grid.iter().zip(&mut cover) {
        ranges.sort_by_key(|(r, _)| (r.start, r.end));
        let mut next = 0;
        let mut last: Option<usize> = None;
        let mut missing = |range: Range<u32>| match gaps.iter_mut().find(|(r, _)| *r == range) {
            Some((_, tiles)) => tiles.push(*tile),
            None => gaps.push((range, vec![*tile])),
        };
        for (range, k) in ranges.iter() {
            if range.start < next {
                let pair = (
                    last.expect("a range before"),
                    *k,
                    range.start..next.min(range.end),
                );
                if !overlaps.iter().any(|(a, b, _)| (*a, *b) == (pair.0, pair.1)) {
                    overlaps.push(pair);
                }
            } else if range.start > next {
                missing(next..range.start);
            }
            if range.end > next {
                next = range.end;
                last = Some(*k);
            }
        }
        if next < settings.passes {
            missing(next..settings.passes);
        }
    }
    if overlaps.is_empty() && gaps.is_empty() {
        return Ok(());
    }
    let mut problems = Vec::new();
    for (a, b, range) in overlaps.iter().take(4) {
        problems.push(format!(
            "{} and {} overlap (both render passes {}..{} of some tiles)",
            parts[*a].0.display(),
            parts[*b].0.display(),
            range.start,
            range.end
        ));
    }
    for (range, tiles) in gaps.iter().take(4) {
        let t = tiles[0];
        problems.push(format!(
            "no part renders passes {}..{} of {} tile(s), e.g. pixels x {}..{}, y {}..{}",
            range.start,
            range.end,
            tiles.len(),
            t.x0,
            t.x1,
            t.y0,
            t.y1
        ));
    }
    let more = overlaps.len().saturating_sub(4) + gaps.len().saturating_sub(4);
    if more > 0 {
        problems.push(format!("and {more} more"));
    }
    // With every part of one K/N split, name the missing parts: that is what to render again.
    let n = parts[0].1.part.1;
    if !gaps.is_empty() && n > 1 && parts.iter().all(|(_, p)| p.part.1 == n) {
        let missing: Vec<String> = (0..n)
            .filter(|k| !parts.iter().any(|(_, p)| p.part.0 == *k))
            .map(|k| format!("{k}/{n}"))
            .collect();
        if !missing.is_empty() {
            problems.push(format!("missing part(s) --tiles {}", missing.join(", ")));
        }
    }
    problems.extend(interrupted(parts, settings, &gaps));
    Err(Error::msg(format!(
        "the parts do not cover the frame exactly once: {}; nothing written",
        problems.join("; ")
    )))
}

/// The parts that look interrupted, given the `gaps` in the cover: one that holds fewer tiles than its
/// `K/N` deals it (Ctrl-C in its first pass keeps the tiles finished), or whose passes end where a gap
/// begins over its tiles (Ctrl-C after whole passes keeps those): the file to finish with `--resume`.
fn interrupted(
    parts: &[(&Path, Part)],
    settings: &PartSettings,
    gaps: &[(Range<u32>, Vec<Tile>)],
) -> Vec<String> {
    let (w, h) = (settings.width, settings.height);
    let index = |t: &Tile| (t.y0 / tiles::TILE) * w.div_ceil(tiles::TILE) + t.x0 / tiles::TILE;
    let resume = "interrupted? the same render command with --resume finishes it";
    let mut out = Vec::new();
    for (path, part) in parts {
        let (k, n) = part.part;
        let dealt = tiles::part(w, h, k, n).len();
        if part.tiles.len() < dealt {
            out.push(format!(
                "{} holds {} of the {dealt} tiles of part {k}/{n} ({resume})",
                path.display(),
                part.tiles.len()
            ));
            continue;
        }
        let ends_at_gap = gaps.iter().any(|(range, missing)| {
            range.start == part.passes.end
                && missing
                    .iter()
                    .any(|t| part.tiles.binary_search(&index(t)).is_ok())
        });
        if ends_at_gap {
            out.push(format!(
                "{} holds passes {}..{} and the next are missing ({resume})",
                path.display(),
                part.passes.start,
                part.passes.end
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Part `part` of a 40 x 20 frame of 4 passes, holding `tiles` (whose areas are 256, 256, 128,
    /// 64, 64 and 32 pixels) over `passes`.
    fn part(part: (u32, u32), tiles: &[u32], passes: Range<u32>) -> Part {
        let settings = PartSettings::for_tests(40, 20);
        let area = [256, 256, 128, 64, 64, 32];
        let pixels: usize = tiles.iter().map(|&t| area[t as usize]).sum();
        Part {
            settings,
            part,
            tiles: tiles.to_vec(),
            sums: vec![[1.0; 3]; pixels],
            counts: vec![passes.len() as u32; pixels],
            passes,
        }
    }

    fn merged(parts: &[(&str, Part)]) -> String {
        let dir = tempfile::tempdir().unwrap();
        let paths: Vec<PathBuf> = parts
            .iter()
            .map(|(name, part)| {
                let path = dir.path().join(name);
                part.write(&path).unwrap();
                path
            })
            .collect();
        let e = merge(&paths).unwrap_err().to_string();
        e.replace(&format!("{}/", dir.path().display()), "")
    }

    /// The merge names the part an interrupted render left, not only the tiles or
    /// passes missing.
    #[test]
    fn an_interrupted_part_is_named() {
        // Part 1/2 deals tiles 1, 3 and 5; Ctrl-C in its pass kept 1 and 3.
        let e = merged(&[
            ("d0.partial", part((0, 2), &[0, 2, 4], 0..4)),
            ("d1.partial", part((1, 2), &[1, 3], 0..4)),
        ]);
        assert_eq!(
            e,
            "the parts do not cover the frame exactly once: no part renders passes 0..4 of 1 tile(s), \
             e.g. pixels x 32..40, y 16..20; d1.partial holds 2 of the 3 tiles of part 1/2 \
             (interrupted? the same render command with --resume finishes it); nothing written"
        );
        // Ctrl-C after two whole passes of 0..4.
        let e = merged(&[
            ("d0.partial", part((0, 2), &[0, 2, 4], 0..4)),
            ("d1.partial", part((1, 2), &[1, 3, 5], 0..2)),
        ]);
        assert!(
            e.ends_with(
                "d1.partial holds passes 0..2 and the next are missing (interrupted? the same render \
                 command with --resume finishes it); nothing written"
            ),
            "{e}"
        );
        // A part merely left out is not called interrupted.
        let e = merged(&[("d0.partial", part((0, 2), &[0, 2, 4], 0..4))]);
        assert!(!e.contains("interrupted"), "{e}");
        assert!(e.contains("missing part(s) --tiles 1/2"), "{e}");
    }
}
