//! A uniform grid: the scene's box cut into equal cells, each listing the primitives whose bounding box
//! overlaps it, walked cell by cell along the ray with the 3D-DDA of J. Amanatides, A. Woo, "A Fast Voxel
//! Traversal Algorithm for Ray Tracing", *Eurographics* 1987.
//!
//! The cell lists are stored flat, CSR-like: `refs[cell_start[c]..cell_start[c + 1]]` are the ids in cell
//! `c`, filled by a counting pass and then a fill pass, so a build makes three allocations whatever the
//! scene.

use std::fmt;

use glam::Vec3;

use super::counters;
use super::policy::HitPolicy;
use super::prims::{Hit, Prims};
use super::structure::Structure;
use crate::geometry::{aabb::Aabb, cuboid, ray::Ray};

/// Cells per primitive the resolution aims at (the `density` of the cube-root rule): most of the gain
/// for its memory, which grows linearly with it (`profiles/README.md`, tuned constants).
const DENSITY: f64 = 4.0;
/// Most cells along one axis.
const MAX_AXIS_CELLS: u32 = 512;
/// Most cells, and most references, before the resolution is lowered: 64 Mi of each (256 MiB apiece)
/// bounds the grid's memory whatever the primitives' sizes.
const MAX_ENTRIES: u64 = 64 << 20;
/// Ids remembered per ray, direct-mapped on the id's low bits (a power of two).
const MAILBOX: usize = 32;
/// Relative slack on the walk's stopping test: a hit's `t` and a cell boundary's `t` carry a few ulps of
/// rounding each, so the walk goes on one cell further while the closest hit is within this of the boundary.
const T_SLACK: f32 = 1e-5;

/// The cells' geometry: where the grid lies and how it is cut.
#[derive(Clone, Copy, Debug)]
struct Lattice {
    /// The grid's box (the primitives' union, padded).
    bounds: Aabb,
    /// Cells per axis.
    res: [u32; 3],
    /// Edge lengths of a cell.
    size: Vec3,
    /// Their reciprocals.
    inv_size: Vec3,
}

impl Lattice {
    fn new(bounds: Aabb, res: [u32; 3]) -> Self {
        let size = bounds.extent() / Vec3::from_array(res.map(|n| n as f32));
        Lattice {
            bounds,
            res,
            size,
            inv_size: size.recip(),
        }
    }

    fn cells(&self) -> u64 {
        self.res.iter().map(|&n| n as u64).product()
    }

    /// The cell containing `p`, clamped to the grid (NaN lands in cell 0).
    #[inline]
    fn cell_of(&self, p: Vec3) -> [u32; 3] {
        let c = ((p - self.bounds.min) * self.inv_size).floor();
        std::array::from_fn(|a| (c[a] as i64).clamp(0, self.res[a] as i64 - 1) as u32)
    }

    /// The linear index of cell `c`, x fastest.
    fn index(&self, c: [u32; 3]) -> usize {
        c[0] as usize + self.res[0] as usize * (c[1] as usize + self.res[1] as usize * c[2] as usize)
    }

    /// The coordinate of the `j`-th cell boundary plane on axis `a`, computed the same way for the walk as
    /// for the cells' extents.
    #[inline]
    fn plane(&self, a: usize, j: i32) -> f32 {
        self.bounds.min[a] + j as f32 * self.size[a]
    }

    /// The inclusive cell ranges overlapped by `b` grown by `slack`.
    fn range(&self, b: &Aabb, slack: Vec3) -> ([u32; 3], [u32; 3]) {
        (self.cell_of(b.min - slack), self.cell_of(b.max + slack))
    }
}

/// The number of cells in the inclusive range `lo..=hi`.
fn range_cells(lo: [u32; 3], hi: [u32; 3]) -> u64 {
    (0..3).map(|a| (hi[a] - lo[a] + 1) as u64).product()
}

/// Cells per axis by the cube-root rule (Cleary & Wyvill 1988, Woo 1992):
/// `n_i = extent_i * cbrt(density * count / volume)`. An axis that would get less than one cell (a flat or
/// thin scene) gets one, and the rule is solved again over the other axes with the same cell budget, so a
/// flat scene is cut as a square grid of about `density * count` cells rather than a single row. In f64:
/// the padded extent of a point-like scene is ~1e-30, whose cube underflows an f32.
fn resolution(extent: Vec3, count: usize, density: f64) -> [u32; 3] {
    let extent = extent.as_dvec3();
    let budget = density * count as f64;
    let mut free = [true; 3];
    let mut scale = 0.0;
    for _ in 0..3 {
        let k = free.iter().filter(|&&f| f).count();
        if k == 0 {
            break;
        }
        let measure: f64 = (0..3).filter(|&a| free[a]).map(|a| extent[a]).product();
        scale = (budget / measure).powf(1.0 / k as f64);
        let mut changed = false;
        for a in 0..3 {
            if free[a] && extent[a] * scale < 1.0 {
                free[a] = false;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    std::array::from_fn(|a| {
        if free[a] {
            ((extent[a] * scale).round() as u32).clamp(1, MAX_AXIS_CELLS)
        } else {
            1
        }
    })
}

/// The smallest `f32` above `t` (`f32::next_up` needs Rust 1.86; the crate supports 1.85). `t` is finite.
#[inline]
fn next_up(t: f32) -> f32 {
    if t == 0.0 {
        f32::from_bits(1)
    } else if t > 0.0 {
        f32::from_bits(t.to_bits() + 1)
    } else {
        f32::from_bits(t.to_bits() - 1)
    }
}

/// A uniform grid over the bounded primitives; planes are tested beside it.
#[derive(Clone)]
pub struct Grid<'a> {
    prims: Prims<'a>,
    lattice: Lattice,
    /// `cell_start[c]..cell_start[c + 1]` indexes `refs` for cell `c`; one entry per cell plus one.
    cell_start: Vec<u32>,
    /// Primitive ids, cell after cell, ascending within a cell.
    refs: Vec<u32>,
    /// Bounded primitives whose bounds are not finite (overflowed or NaN coordinates): they cannot be
    /// placed in cells, so every ray tests them, like the planes, and results stay those of brute force.
    loose: Vec<u32>,
}

/// Size figures of a built grid, for `whitted info`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridStats {
    /// Cells per axis (all zero when there is nothing to grid).
    pub resolution: [u32; 3],
    /// Number of cells.
    pub cells: u64,
    /// Primitive references, summed over cells.
    pub references: u64,
    /// Cells referencing nothing.
    pub empty_cells: u64,
    /// Bounded primitives with non-finite bounds, tested by every ray.
    pub loose: u32,
}

impl fmt::Display for GridStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let [x, y, z] = self.resolution;
        write!(
            f,
            "grid {x}x{y}x{z}: {} cells ({} empty), {} references ({:.2} per non-empty cell)",
            self.cells,
            self.empty_cells,
            self.references,
            self.references as f64 / (self.cells - self.empty_cells).max(1) as f64
        )?;
        if self.loose > 0 {
            write!(f, ", {} primitives outside the grid", self.loose)?;
        }
        Ok(())
    }
}

impl fmt::Debug for Grid<'_> {
    /// The figures, not the millions of references.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Grid")
            .field("stats", &self.stats())
            .finish_non_exhaustive()
    }
}

impl<'a> Grid<'a> {
    /// The scene's primitives.
    pub fn prims(&self) -> Prims<'a> {
        self.prims
    }

    /// Builds the grid over the bounded primitives' boxes.
    pub fn build(prims: Prims<'a>) -> Self {
        let mut boxes = Vec::with_capacity(prims.bounded() as usize);
        let mut loose = Vec::new();
        let mut union = Aabb::EMPTY;
        for id in 0..prims.bounded() {
            let b = prims.bounds(id);
            if b.min.is_finite() && b.max.is_finite() && b.min.cmple(b.max).all() {
                union = union.union(b);
                boxes.push((id, b));
            } else {
                loose.push(id);
            }
        }
        if boxes.is_empty() {
            // Nothing to grid: every query tests the planes and loose primitives only.
            return Grid {
                prims,
                lattice: Lattice::new(Aabb::EMPTY, [0; 3]),
                cell_start: vec![0],
                refs: Vec::new(),
                loose,
            };
        }

        // Rounding tolerances, from the scene's extent and from the magnitude of its coordinates (which
        // bounds the absolute error of every point and plane computed in world space).
        let magnitude = union.min.abs().max(union.max.abs()).max_element();
        let ulps = 64.0 * f32::EPSILON * magnitude;
        // Padding gives a flat scene's thin axis a non-zero extent (one cell), and keeps hit points
        // rounded slightly off a primitive on the boundary inside the grid.
        let pad = (1e-4 * union.extent().max_element()).max(ulps).max(1e-30);
        let bounds = Aabb::new(union.min - pad, union.max + pad);

        let mut lattice = Lattice::new(bounds, resolution(bounds.extent(), boxes.len(), DENSITY));
        // A primitive is placed in every cell its box comes within `slack` of, so that a hit point or a
        // cell boundary a few ulps off still finds it in the cell the walk visits.
        let slack_of = |l: &Lattice| l.size * 1e-3 + Vec3::splat(ulps / 2.0);
        let mut slack = slack_of(&lattice);
        // Huge primitives overlap many cells each: lower the resolution until the grid fits its budget.
        loop {
            let references: u64 = boxes
                .iter()
                .map(|(_, b)| {
                    let (lo, hi) = lattice.range(b, slack);
                    range_cells(lo, hi)
                })
                .sum();
            if (references <= MAX_ENTRIES && lattice.cells() <= MAX_ENTRIES) || lattice.res == [1; 3] {
                break;
            }
            lattice = Lattice::new(bounds, lattice.res.map(|n| ((n as f32 * 0.8) as u32).max(1)));
            slack = slack_of(&lattice);
        }

        // Counting pass: cell_start[c] counts cell c's references, then becomes the end of its run.
        let cells = lattice.cells() as usize;
        let mut cell_start = vec![0u32; cells + 1];
        let for_each_cell = |lo: [u32; 3], hi: [u32; 3], f: &mut dyn FnMut(usize)| {
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    let row = lattice.index([0, y, z]);
                    for x in lo[0]..=hi[0] {
                        f(row + x as usize);
                    }
                }
            }
        };
        for (_, b) in &boxes {
            let (lo, hi) = lattice.range(b, slack);
            for_each_cell(lo, hi, &mut |c| cell_start[c] += 1);
        }
        let mut total = 0u32;
        for s in &mut cell_start[..cells] {
            total += *s;
            *s = total;
        }
        cell_start[cells] = total;
        // Fill pass, ids in descending order, each written just below its cell's end: every run ends up
        // ascending and cell_start[c] moves back to the run's start.
        let mut refs = vec![0u32; total as usize];
        for &(id, b) in boxes.iter().rev() {
            let (lo, hi) = lattice.range(&b, slack);
            for_each_cell(lo, hi, &mut |c| {
                cell_start[c] -= 1;
                refs[cell_start[c] as usize] = id;
            });
        }

        Grid {
            prims,
            lattice,
            cell_start,
            refs,
            loose,
        }
    }

    /// Size figures of the grid.
    pub fn stats(&self) -> GridStats {
        GridStats {
            resolution: self.lattice.res,
            cells: self.lattice.cells(),
            references: self.refs.len() as u64,
            empty_cells: self.cell_start.windows(2).filter(|w| w[0] == w[1]).count() as u64,
            loose: self.loose.len() as u32,
        }
    }

    /// Tests primitive `id`, updating `hit`; true if it was taken.
    ///
    /// Brute force keeps the lowest id among hits at equal `t`; cells visit ids in another order, so once
    /// this traversal holds a hit, a hit at exactly the same `t` replaces it when its id is lower. `found`
    /// says whether `hit` is this traversal's (the caller's limit stays exclusive).
    #[inline(always)]
    fn test(&self, id: u32, ray: &Ray, t_min: f32, hit: &mut Hit, found: &mut bool) -> bool {
        let limit = if *found { next_up(hit.t) } else { hit.t };
        match self.prims.intersect(id, ray, t_min, limit) {
            Some((t, u, v)) if t < hit.t || id < hit.prim => {
                *hit = Hit { t, prim: id, u, v };
                *found = true;
                true
            }
            _ => false,
        }
    }

    /// Finds the closest hit with `t` in `(t_min, hit.t)` and updates `hit`, or with `P::ANY` returns at
    /// the first hit; true if there was one. The same contract and results as brute force.
    #[inline]
    pub fn traverse<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        // Planes first: a near floor shortens the walk; ties with bounded ids are settled in `test`.
        let mut found = self.prims.intersect_planes::<P>(ray, t_min, hit);
        if P::ANY && found {
            return true;
        }
        for &id in &self.loose {
            if self.test(id, ray, t_min, hit, &mut found) && P::ANY {
                return true;
            }
        }
        if self.refs.is_empty() {
            return found;
        }
        let l = &self.lattice;
        let inv = ray.dir.recip();
        let Some((t_enter, t_exit)) = cuboid::slab(l.bounds.min, l.bounds.max, ray.origin, inv, t_min, hit.t)
        else {
            return found;
        };

        // DDA set-up: the entry cell, and per axis the step, the index of the next boundary plane and the
        // `t` at which the ray crosses it. A zero direction component never crosses a plane on that axis
        // (infinite `t`, never stepped). The crossing is recomputed from the plane's index at each step
        // rather than accumulated by adding `t_delta`: over 512 cells the sums can drift by hundreds of ulps,
        // beyond the slack the stopping test allows, while this costs one multiply-add more per step.
        let mut cell = l.cell_of(ray.at(t_enter)).map(|c| c as i32);
        let mut index = l.index(cell.map(|c| c as u32));
        let stride = [1, l.res[0] as isize, l.res[0] as isize * l.res[1] as isize];
        let mut step = [0i32; 3];
        let mut plane = [0i32; 3];
        let mut t_next = [f32::INFINITY; 3];
        for a in 0..3 {
            if ray.dir[a] > 0.0 {
                (step[a], plane[a]) = (1, cell[a] + 1);
            } else if ray.dir[a] < 0.0 {
                (step[a], plane[a]) = (-1, cell[a]);
            } else {
                continue;
            }
            t_next[a] = (l.plane(a, plane[a]) - ray.origin[a]) * inv[a];
        }

        // Ids tested so far by this ray. A test's outcome is final for the ray: every hit in the window is
        // taken (not only those inside the current cell), and the window only shrinks, so a primitive
        // seen again in a later cell need not be tested again.
        let mut mailbox = [u32::MAX; MAILBOX];
        loop {
            let axis = if t_next[0] < t_next[1] {
                if t_next[0] < t_next[2] { 0 } else { 2 }
            } else if t_next[1] < t_next[2] {
                1
            } else {
                2
            };
            let cell_exit = t_next[axis];
            // A cell walked is a node visited; a primitive the mailbox skips is not tested.
            counters::node::<P>();
            let run = self.cell_start[index] as usize..self.cell_start[index + 1] as usize;
            for &id in &self.refs[run] {
                let slot = &mut mailbox[id as usize & (MAILBOX - 1)];
                if *slot == id {
                    continue;
                }
                *slot = id;
                counters::prims::<P>(1);
                if self.test(id, ray, t_min, hit, &mut found) && P::ANY {
                    return true;
                }
            }
            // Every primitive with a hit before this cell's exit lies in a cell visited by now, so the walk
            // ends once the closest hit (or the end of the clipped segment) is before that exit. A hit is
            // taken wherever it lies, not only within the cell: it can only shorten the window.
            let end = hit.t.min(t_exit);
            if end + T_SLACK * end.abs() < cell_exit || cell_exit == f32::INFINITY {
                break;
            }
            cell[axis] += step[axis];
            if cell[axis] as u32 >= l.res[axis] {
                break;
            }
            index = index.wrapping_add_signed(step[axis] as isize * stride[axis]);
            plane[axis] += step[axis];
            t_next[axis] = (l.plane(axis, plane[axis]) - ray.origin[axis]) * inv[axis];
        }
        found
    }
}

impl<'a> Structure<'a> for Grid<'a> {
    fn prims(&self) -> Prims<'a> {
        self.prims
    }

    fn describe(&self) -> String {
        self.stats().to_string()
    }

    #[inline(always)]
    fn traverse<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        Grid::traverse::<P>(self, ray, t_min, hit)
    }
}

#[cfg(test)]
mod tests;
