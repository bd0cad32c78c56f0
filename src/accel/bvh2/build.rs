//! Top-down BVH builders: midpoint split and binned SAH (Wald 2007, "On fast Construction of SAH-based
//! Bounding Volume Hierarchies"). Both move one array of primitive references (box, id, kind: 32 bytes)
//! in place, as Embree's builders move their `PrimRef`s, so a node's primitives are always a contiguous
//! range read front to back: with ids into a side table, every pass near the root gathered from 40 MB at
//! random. A node's box and its centroids' box come from its parent's partition, so each node reads its
//! primitives twice, once to bin and once to partition. Large subtrees are built in parallel with
//! `rayon::join`, each into its own node array, merged once at the top levels; the nodes above them,
//! which hold most of the scene, bin and partition in parallel too.

use glam::{Vec3, Vec3A};
use rayon::prelude::*;

use super::{BLOCK_COST, INTERSECTION_COST, Node, TRAVERSAL_COST};
use crate::accel::prims::{PrimKind, Prims};
use crate::geometry::aabb::Aabb;

/// How to choose each split.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builder {
    /// Split at the midpoint of the centroids' extent on its longest axis; leaves of up to 4.
    Midpoint,
    /// Binned surface area heuristic over all three axes with this many bins (12 is the usual choice).
    Sah {
        /// Bins per axis (2..=64).
        bins: usize,
    },
}

/// The most primitives a leaf may hold: one SIMD-width pair of four.
pub const MAX_LEAF: usize = 8;
/// Midpoint leaves.
const MIDPOINT_LEAF: usize = 4;
/// Below this many primitives a subtree is built on the current thread.
const PARALLEL_THRESHOLD: usize = 16 * 1024;
/// A node of at least `PARALLEL_NODE` primitives bins in chunks of `PARALLEL_CHUNK`, and partitions its
/// halves, in parallel (the root and the levels just below it, where `rayon::join` has not yet given
/// every thread a subtree of its own).
const PARALLEL_CHUNK: usize = 64 * 1024;
const PARALLEL_NODE: usize = 2 * PARALLEL_CHUNK;
/// A node slot reserved before the builder knows what goes in it.
const PLACEHOLDER: Node = Node {
    bounds: Aabb::EMPTY,
    first: 0,
    count: 0,
};
/// Past this depth splits are by count (median), which bounds the depth by log2(n) more levels: a run of
/// lopsided SAH splits, or midpoint splits of clustered centroids, cannot make the tree arbitrarily deep.
const MAX_FREE_DEPTH: usize = 64;
/// The deepest a built tree can be: `MAX_FREE_DEPTH` levels, then halvings of at most 2³² primitives.
/// The traversal stacks are sized from it.
pub const MAX_TREE_DEPTH: usize = MAX_FREE_DEPTH + 32;

/// One primitive as the builders move it: its box, its id, and whether it is a triangle (leaves hold
/// one kind only, so a BVH4 leaf of triangles is a block the SIMD kernel tests as a whole). Two to a
/// cache line.
#[derive(Clone, Copy)]
#[repr(C, align(32))]
struct PrimRef {
    min: Vec3,
    id: u32,
    max: Vec3,
    triangle: bool,
}

impl PrimRef {
    #[inline(always)]
    fn bounds(&self) -> Box3 {
        Box3 {
            min: self.min.into(),
            max: self.max.into(),
        }
    }

    /// The box's centre, as `Aabb::center` computes it.
    #[inline(always)]
    fn centroid(&self) -> Vec3A {
        (Vec3A::from(self.min) + Vec3A::from(self.max)) * 0.5
    }
}

/// The builder's box: an [`Aabb`] in SIMD registers (glam's `Vec3A`), one instruction for each min or
/// max where an `Aabb`'s `Vec3` takes three; the arithmetic, lane by lane, is the same.
#[derive(Clone, Copy)]
struct Box3 {
    min: Vec3A,
    max: Vec3A,
}

impl Box3 {
    const EMPTY: Box3 = Box3 {
        min: Vec3A::INFINITY,
        max: Vec3A::NEG_INFINITY,
    };

    #[inline(always)]
    fn union(self, other: Box3) -> Box3 {
        Box3 {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    #[inline(always)]
    fn grow(&mut self, p: Vec3A) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// [`Aabb::area`] of a box that holds something (the SAH's sweeps call it only where one does).
    #[inline(always)]
    fn area(&self) -> f32 {
        let e = self.max - self.min;
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    fn aabb(&self) -> Aabb {
        Aabb::new(self.min.into(), self.max.into())
    }
}

/// What a node needs to know of its primitives before it splits: their box and their centroids' box.
#[derive(Clone, Copy)]
struct Extent {
    bounds: Box3,
    centroids: Box3,
}

impl Extent {
    const EMPTY: Extent = Extent {
        bounds: Box3::EMPTY,
        centroids: Box3::EMPTY,
    };

    #[inline(always)]
    fn add(&mut self, r: &PrimRef) {
        self.bounds = self.bounds.union(r.bounds());
        self.centroids.grow(r.centroid());
    }

    fn merge(self, other: Extent) -> Extent {
        Extent {
            bounds: self.bounds.union(other.bounds),
            centroids: self.centroids.union(other.centroids),
        }
    }

    fn of(refs: &[PrimRef]) -> Extent {
        refs.iter().fold(Extent::EMPTY, |mut e, r| {
            e.add(r);
            e
        })
    }
}

/// A node's split: how many primitives go left (they are now first), and each side's extent.
type Split = (usize, Extent, Extent);

/// Builds the nodes and the reordered ids of a BVH over the bounded primitives. `block` is how many
/// primitives a leaf tests at the cost of one (4 for the BVH4's SIMD leaves, 1 for scalar leaves; a
/// power of two, others round up): the
/// SAH then charges a leaf ⌈n / block⌉ tests, which favours leaves that fill their lanes, each at
/// [`BLOCK_COST`] where `block > 1`.
pub fn build(prims: &Prims, builder: Builder, block: usize) -> (Vec<Node>, Vec<u32>) {
    let n = prims.bounded();
    if n == 0 {
        return (Vec::new(), Vec::new());
    }
    let mut refs: Vec<PrimRef> = (0..n)
        .into_par_iter()
        .map(|id| {
            let bounds = prims.bounds(id);
            PrimRef {
                min: bounds.min,
                id,
                max: bounds.max,
                triangle: matches!(prims.kind(id), PrimKind::Triangle(_)),
            }
        })
        .collect();
    let extent = refs
        .par_chunks(PARALLEL_CHUNK)
        .map(Extent::of)
        .reduce(|| Extent::EMPTY, Extent::merge);
    let ctx = Ctx {
        builder: match builder {
            Builder::Sah { bins } => Builder::Sah {
                bins: bins.clamp(2, 64),
            },
            b => b,
        },
        block_shift: block.max(1).next_power_of_two().trailing_zeros(),
    };
    let nodes = ctx.subtree(&mut refs, extent, 0, 0);
    let ids = refs.par_iter().map(|r| r.id).collect();
    (nodes, ids)
}

struct Ctx {
    builder: Builder,
    /// log2 of the leaf block (a power of two, so ⌈n / block⌉ is a shift, not a division per plane).
    block_shift: u32,
}

impl Ctx {
    /// A subtree over `refs` (which start at `base` in the final id array) as its own node array, root
    /// first, child indices relative to it. Large ones build their halves in parallel and merge.
    fn subtree(&self, refs: &mut [PrimRef], extent: Extent, base: u32, depth: usize) -> Vec<Node> {
        if refs.len() < PARALLEL_THRESHOLD {
            let mut nodes = Vec::with_capacity(2 * refs.len().div_ceil(2));
            nodes.push(PLACEHOLDER);
            self.fill(&mut nodes, 0, refs, extent, base, depth);
            return nodes;
        }
        let Some((mid, left_extent, right_extent)) = self.split(refs, &extent, depth) else {
            return vec![leaf(refs, &extent, base)];
        };
        let (left_refs, right_refs) = refs.split_at_mut(mid);
        let (left, right) = rayon::join(
            || self.subtree(left_refs, left_extent, base, depth + 1),
            || self.subtree(right_refs, right_extent, base + mid as u32, depth + 1),
        );
        // [root, left root, right root, rest of left, rest of right]: each subtree's node i > 0 moves to
        // a fixed offset, and its children (pairs, never index 0) move with it.
        let (nl, nr) = (left.len(), right.len());
        let mut nodes = Vec::with_capacity(1 + nl + nr);
        nodes.push(Node {
            bounds: extent.bounds.aabb(),
            first: 1,
            count: 0,
        });
        let place = |n: &Node, offset: usize| {
            let mut n = *n;
            if !n.is_leaf() {
                n.first = (offset + n.first as usize - 1) as u32;
            }
            n
        };
        nodes.push(place(&left[0], 3));
        nodes.push(place(&right[0], 3 + nl - 1));
        nodes.extend(left[1..].iter().map(|n| place(n, 3)));
        nodes.extend(right[1..].iter().map(|n| place(n, 3 + nl - 1)));
        nodes
    }

    /// Turns `nodes[at]` into the subtree over `refs`, appending children as adjacent pairs.
    fn fill(
        &self,
        nodes: &mut Vec<Node>,
        at: usize,
        refs: &mut [PrimRef],
        extent: Extent,
        base: u32,
        depth: usize,
    ) {
        let Some((mid, left, right)) = self.split(refs, &extent, depth) else {
            nodes[at] = leaf(refs, &extent, base);
            return;
        };
        let first = nodes.len();
        nodes[at] = Node {
            bounds: extent.bounds.aabb(),
            first: first as u32,
            count: 0,
        };
        nodes.extend([PLACEHOLDER, PLACEHOLDER]);
        let (l, r) = refs.split_at_mut(mid);
        self.fill(nodes, first, l, left, base, depth + 1);
        self.fill(nodes, first + 1, r, right, base + mid as u32, depth + 1);
    }

    /// The split of a node over `refs` after partitioning them, or `None` where it should be a leaf.
    fn split(&self, refs: &mut [PrimRef], extent: &Extent, depth: usize) -> Option<Split> {
        let n = refs.len();
        let centroids = &extent.centroids;
        let split = match self.builder {
            Builder::Midpoint if n <= MIDPOINT_LEAF => None,
            Builder::Midpoint if depth >= MAX_FREE_DEPTH => Some(median(refs, centroids)),
            Builder::Midpoint => Some(midpoint(refs, centroids)),
            Builder::Sah { .. } if n == 1 => None,
            Builder::Sah { .. } if depth >= MAX_FREE_DEPTH => (n > MAX_LEAF).then(|| median(refs, centroids)),
            Builder::Sah { bins } => self.sah(refs, extent, bins),
        };
        // A leaf of mixed kinds splits once more, triangles from the rest.
        split.or_else(|| {
            let mixed = refs.iter().any(|r| r.triangle != refs[0].triangle);
            mixed.then(|| partition(refs, |r| r.triangle))
        })
    }

    /// How many leaf tests `n` primitives take: ⌈n / block⌉.
    #[inline(always)]
    fn tests(&self, n: usize) -> f32 {
        ((n + (1 << self.block_shift) - 1) >> self.block_shift) as f32
    }

    /// The cost of one leaf test: a SIMD block's where leaves are blocks.
    fn test_cost(&self) -> f32 {
        if self.block_shift > 0 {
            BLOCK_COST
        } else {
            INTERSECTION_COST
        }
    }

    /// The cost of a leaf of `n` primitives.
    fn leaf_cost(&self, n: usize) -> f32 {
        self.test_cost() * self.tests(n)
    }

    /// The cheapest binned-SAH split over the three axes, cost c = c_t + (S_L/S_P)·n_L·c_i +
    /// (S_R/S_P)·n_R·c_i; `None` (a leaf) when that costs more than testing the primitives directly and
    /// the node is small enough to be a leaf.
    fn sah(&self, refs: &mut [PrimRef], extent: &Extent, bins: usize) -> Option<Split> {
        // Any split costs at least the traversal step, so a node that may be a leaf and whose leaf costs
        // no more is one without binning: with four-triangle blocks, every node of up to 8 (half the
        // nodes the binning saw).
        let n = refs.len();
        if n <= MAX_LEAF && self.leaf_cost(n) <= TRAVERSAL_COST {
            return None;
        }
        // The bin arrays live on the stack and are cleared at every node: size them to the bin count
        // (clearing 64 bins per node was 5% of a dragon.p3f render's instructions).
        match bins {
            0..=12 => self.sah_with::<12>(refs, extent, bins),
            13..=16 => self.sah_with::<16>(refs, extent, bins),
            17..=32 => self.sah_with::<32>(refs, extent, bins),
            _ => self.sah_with::<64>(refs, extent, bins),
        }
    }

    // Not inlined: the leaves' early return above would otherwise pay for clearing the bins.
    #[inline(never)]
    fn sah_with<const B: usize>(&self, refs: &mut [PrimRef], extent: &Extent, bins: usize) -> Option<Split> {
        let n = refs.len();
        let centroids = &extent.centroids;
        let size = centroids.max - centroids.min;
        if size.max_element() <= 0.0 {
            // Every centroid at one point: no plane separates them.
            return (n > MAX_LEAF).then(|| median(refs, centroids));
        }
        let binner = Binner {
            origin: centroids.min,
            scale: Vec3A::select(size.cmpgt(Vec3A::ZERO), bins as f32 / size, Vec3A::ZERO),
            last: Vec3A::splat((bins - 1) as f32),
        };
        let binned = if n >= PARALLEL_NODE {
            refs.par_chunks(PARALLEL_CHUNK)
                .map(|chunk| Bins::<B>::of(chunk, &binner))
                .reduce(|| Bins::EMPTY, Bins::merge)
        } else {
            Bins::<B>::of(refs, &binner)
        };
        let mut best = (f32::INFINITY, 0usize, 0usize);
        for axis in 0..3 {
            if size[axis] <= 0.0 {
                continue;
            }
            let (count, boxes) = (&binned.count[axis], &binned.boxes[axis]);
            // Sweep from the right for the right-hand areas, then from the left evaluating each plane.
            // A side with nothing in it has no area to ask for (its box is empty), and a plane past an
            // empty bin splits as the one before it did, so only planes past a filled bin count.
            let mut right_cost = [0f32; B];
            let mut right_count = [0u32; B];
            let (mut b, mut c) = (Box3::EMPTY, 0);
            for k in (1..bins).rev() {
                b = b.union(boxes[k]);
                c += count[k];
                right_count[k] = c;
                if c > 0 && count[k - 1] > 0 {
                    right_cost[k] = b.area() * self.tests(c as usize);
                }
            }
            let (mut b, mut c) = (Box3::EMPTY, 0);
            for k in 0..bins - 1 {
                if count[k] == 0 {
                    continue;
                }
                b = b.union(boxes[k]);
                c += count[k];
                if right_count[k + 1] > 0 {
                    let cost = b.area() * self.tests(c as usize) + right_cost[k + 1];
                    if cost < best.0 {
                        best = (cost, axis, k);
                    }
                }
            }
        }
        let area = extent.bounds.area().max(f32::MIN_POSITIVE);
        let split_cost = TRAVERSAL_COST + self.test_cost() * best.0 / area;
        if best.0.is_infinite() {
            return (n > MAX_LEAF).then(|| median(refs, centroids));
        }
        if split_cost >= self.leaf_cost(n) && n <= MAX_LEAF {
            return None;
        }
        let (_, axis, k) = best;
        let split = partition(refs, |r| binner.bins(r.centroid())[axis] <= k);
        debug_assert!(split.0 > 0 && split.0 < n);
        Some(split)
    }
}

/// A leaf over `refs`, which it sorts by id. Which of two primitives hit at the same distance a ray
/// reports is the one tested first; in id order, that is the one brute force reports, however the
/// partitions above left them.
fn leaf(refs: &mut [PrimRef], extent: &Extent, base: u32) -> Node {
    refs.sort_unstable_by_key(|r| r.id);
    Node {
        bounds: extent.bounds.aabb(),
        first: base,
        count: refs.len() as u32,
    }
}

/// Maps a centroid to its bin on each axis.
struct Binner {
    origin: Vec3A,
    scale: Vec3A,
    last: Vec3A,
}

impl Binner {
    /// The bins of `c`: ⌊(c − origin)·scale⌋ clamped to the bins, on each axis. Clamping the floats
    /// first lets each conversion be one instruction (`as` saturates, which cost a fifth of the build's
    /// instructions).
    #[inline(always)]
    fn bins(&self, c: Vec3A) -> [usize; 3] {
        // `max` before `min` maps NaN (0 · ∞, where a tiny extent made the scale infinite) to bin 0 as
        // a saturating `as` would, and ∞ to the last bin.
        let x = ((c - self.origin) * self.scale).max(Vec3A::ZERO).min(self.last);
        // SAFETY: each lane of `x` is a number in [0, last], last < 64, which an i32 holds.
        x.to_array()
            .map(|v| unsafe { v.to_int_unchecked::<i32>() } as usize)
    }
}

/// Per axis and bin: how many centroids fell in it and the box of their primitives.
struct Bins<const B: usize> {
    count: [[u32; B]; 3],
    boxes: [[Box3; B]; 3],
}

impl<const B: usize> Bins<B> {
    const EMPTY: Self = Bins {
        count: [[0; B]; 3],
        boxes: [[Box3::EMPTY; B]; 3],
    };

    fn of(refs: &[PrimRef], binner: &Binner) -> Self {
        let mut bins = Self::EMPTY;
        for r in refs {
            let bounds = r.bounds();
            for (axis, b) in binner.bins(r.centroid()).into_iter().enumerate() {
                bins.count[axis][b] += 1;
                bins.boxes[axis][b] = bins.boxes[axis][b].union(bounds);
            }
        }
        bins
    }

    fn merge(mut self, other: Self) -> Self {
        for axis in 0..3 {
            for b in 0..B {
                self.count[axis][b] += other.count[axis][b];
                self.boxes[axis][b] = self.boxes[axis][b].union(other.boxes[axis][b]);
            }
        }
        self
    }
}

/// Splits at the centroids' midpoint on their longest axis; by count if that leaves a side empty.
fn midpoint(refs: &mut [PrimRef], centroids: &Box3) -> Split {
    let axis = (centroids.max - centroids.min).max_position();
    let mid = ((centroids.min + centroids.max) * 0.5)[axis];
    let split = partition(refs, |r| r.centroid()[axis] < mid);
    if split.0 == 0 || split.0 == refs.len() {
        median(refs, centroids)
    } else {
        split
    }
}

/// Splits in two equal halves along the centroids' longest axis.
fn median(refs: &mut [PrimRef], centroids: &Box3) -> Split {
    let axis = (centroids.max - centroids.min).max_position();
    let mid = refs.len() / 2;
    refs.select_nth_unstable_by(mid, |a, b| a.centroid()[axis].total_cmp(&b.centroid()[axis]));
    (mid, Extent::of(&refs[..mid]), Extent::of(&refs[mid..]))
}

/// Moves the primitives for which `left` holds to the front, and measures both sides on the way. Large
/// ranges partition their halves in parallel, then swap the first half's right part with the second
/// half's left part (only as many as the shorter of the two: the order within a side is free).
fn partition(refs: &mut [PrimRef], left: impl Fn(&PrimRef) -> bool + Sync + Copy) -> Split {
    if refs.len() < PARALLEL_NODE {
        return partition_serial(refs, left);
    }
    let half = refs.len() / 2;
    let (a, b) = refs.split_at_mut(half);
    let ((ka, la, ra), (kb, lb, rb)) = rayon::join(|| partition(a, left), || partition(b, left));
    // [left of a, right of a | left of b, right of b]
    let middle = &mut refs[ka..half + kb];
    let swapped = (half - ka).min(kb);
    let len = middle.len();
    let (front, back) = middle.split_at_mut(len - swapped);
    front[..swapped].swap_with_slice(back);
    (ka + kb, la.merge(lb), ra.merge(rb))
}

/// Hoare's partition: from both ends, swapping each pair on the wrong sides.
fn partition_serial(refs: &mut [PrimRef], left: impl Fn(&PrimRef) -> bool) -> Split {
    let (mut l, mut r) = (Extent::EMPTY, Extent::EMPTY);
    let (mut i, mut j) = (0, refs.len());
    loop {
        while i < j && left(&refs[i]) {
            l.add(&refs[i]);
            i += 1;
        }
        while i < j && !left(&refs[j - 1]) {
            r.add(&refs[j - 1]);
            j -= 1;
        }
        if i == j {
            return (i, l, r);
        }
        refs.swap(i, j - 1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Material, Scene};

    fn random_scene(n: usize, seed: u64) -> Scene {
        let mut s = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = s.add_material(Material::default());
        let mut x = seed;
        let mut r = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 40) as f32 / (1u64 << 24) as f32
        };
        for i in 0..n {
            let p = Vec3::new(r(), r(), r()) * 10.0;
            match i % 3 {
                0 => s.add_sphere(p, 0.1 + r(), m),
                1 => s.add_triangle(p, p + Vec3::new(r(), 0.0, 0.0), p + Vec3::new(0.0, r(), r()), m),
                _ => s.add_box(p, p + Vec3::new(r(), r(), r()), m),
            }
        }
        s
    }

    /// Every primitive in exactly one leaf; every child's box inside its parent's; every leaf's box holds
    /// its primitives, in id order; leaf sizes within the builder's limit.
    fn check_invariants(prims: &Prims, nodes: &[Node], ids: &[u32], max_leaf: usize) {
        let mut seen = vec![0u32; prims.bounded() as usize];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = &nodes[i];
            if n.is_leaf() {
                assert!(n.count as usize <= max_leaf, "leaf of {}", n.count);
                let leaf = &ids[n.first as usize..(n.first + n.count) as usize];
                assert!(leaf.is_sorted(), "a leaf's ids out of order: {leaf:?}");
                for &id in leaf {
                    seen[id as usize] += 1;
                    assert!(n.bounds.contains(&prims.bounds(id)));
                }
            } else {
                for c in [n.first as usize, n.first as usize + 1] {
                    assert!(n.bounds.contains(&nodes[c].bounds), "child {c} escapes node {i}");
                    stack.push(c);
                }
            }
        }
        assert!(
            seen.iter().all(|&c| c == 1),
            "a primitive is in no leaf or in two"
        );
    }

    #[test]
    fn invariants_hold_for_both_builders_serial_and_parallel() {
        // 150,000 primitives reach the parallel binning and partition of the nodes near the root.
        for n in [1, 2, 5, 100, 3000, 40_000, 150_000] {
            let scene = random_scene(n, n as u64);
            let prims = Prims::new(&scene);
            for (builder, max_leaf, block) in [
                (Builder::Midpoint, MIDPOINT_LEAF, 1),
                (Builder::Sah { bins: 12 }, MAX_LEAF, 1),
                (Builder::Sah { bins: 12 }, MAX_LEAF, 4),
            ] {
                let (nodes, ids) = build(&prims, builder, block);
                check_invariants(&prims, &nodes, &ids, max_leaf);
            }
        }
    }

    /// The parallel partition (halves partitioned apart, then the misplaced parts swapped) leaves every
    /// primitive on its side exactly once, and measures each side as a pass over it would.
    #[test]
    fn parallel_partition_matches_a_pass_over_each_side() {
        let scene = random_scene(300_000, 7);
        let prims = Prims::new(&scene);
        let mut refs: Vec<PrimRef> = (0..prims.bounded())
            .map(|id| {
                let b = prims.bounds(id);
                PrimRef {
                    min: b.min,
                    id,
                    max: b.max,
                    triangle: false,
                }
            })
            .collect();
        let left = |r: &PrimRef| r.centroid().x < 3.7;
        let want = refs.iter().filter(|r| left(r)).count();
        let (k, l, r) = partition(&mut refs, left);
        assert_eq!(k, want);
        assert!(refs[..k].iter().all(left) && !refs[k..].iter().any(left));
        let mut ids: Vec<u32> = refs.iter().map(|r| r.id).collect();
        ids.sort_unstable();
        assert!(
            ids.iter().copied().eq(0..prims.bounded()),
            "a primitive lost or doubled"
        );
        for (side, got) in [(&refs[..k], l), (&refs[k..], r)] {
            let e = Extent::of(side);
            assert_eq!(got.bounds.aabb(), e.bounds.aabb());
            assert_eq!(got.centroids.aabb(), e.centroids.aabb());
        }
    }

    /// Identical primitives cannot be separated by any plane: the builders fall back to count splits and
    /// the depth stays logarithmic.
    #[test]
    fn coincident_primitives() {
        let mut s = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = s.add_material(Material::default());
        for _ in 0..5000 {
            s.add_sphere(Vec3::ONE, 1.0, m);
        }
        let prims = Prims::new(&s);
        for builder in [Builder::Midpoint, Builder::Sah { bins: 12 }] {
            let (nodes, ids) = build(&prims, builder, 4);
            check_invariants(&prims, &nodes, &ids, MAX_LEAF);
            let bvh = super::super::Bvh2 { prims, nodes, ids };
            assert!(bvh.stats().depth <= 16, "depth {}", bvh.stats().depth);
        }
    }
}
