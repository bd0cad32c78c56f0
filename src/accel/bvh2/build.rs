//! Top-down BVH builders: midpoint split and binned SAH (Wald 2007, "On fast Construction of SAH-based
//! Bounding Volume Hierarchies"). Both partition one array of primitive ids in place, so a node's
//! primitives are always a contiguous range and no per-node temporaries exist; large subtrees are built in
//! parallel with `rayon::join`, each into its own node array, merged once at the top levels.

use glam::Vec3;
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
/// Past this depth splits are by count (median), which bounds the depth by log2(n) more levels: a run of
/// lopsided SAH splits, or midpoint splits of clustered centroids, cannot make the tree arbitrarily deep.
const MAX_FREE_DEPTH: usize = 64;
/// The deepest a built tree can be: `MAX_FREE_DEPTH` levels, then halvings of at most 2³² primitives.
/// The traversal stacks are sized from it.
pub const MAX_DEPTH: usize = MAX_FREE_DEPTH + 32;

/// Per-primitive data the builders read: the box, its centre, and whether it is a triangle (leaves hold
/// one kind only, so a BVH4 leaf of triangles is a block the SIMD kernel tests as a whole).
#[derive(Clone, Copy)]
struct Info {
    bounds: Aabb,
    centroid: Vec3,
    triangle: bool,
}

/// Builds the nodes and the reordered ids of a BVH over the bounded primitives. `block` is how many
/// primitives a leaf tests at the cost of one (4 for the BVH4's SIMD leaves, 1 for scalar leaves): the
/// SAH then charges a leaf ⌈n / block⌉ tests, which favours leaves that fill their lanes, each at
/// [`BLOCK_COST`] where `block > 1`.
pub fn build(prims: &Prims, builder: Builder, block: usize) -> (Vec<Node>, Vec<u32>) {
    let n = prims.bounded();
    if n == 0 {
        return (Vec::new(), Vec::new());
    }
    let info: Vec<Info> = (0..n)
        .into_par_iter()
        .map(|id| {
            let bounds = prims.bounds(id);
            Info {
                bounds,
                centroid: bounds.center(),
                triangle: matches!(prims.kind(id), PrimKind::Triangle(_)),
            }
        })
        .collect();
    let mut ids: Vec<u32> = (0..n).collect();
    let ctx = Ctx {
        info: &info,
        builder: match builder {
            Builder::Sah { bins } => Builder::Sah {
                bins: bins.clamp(2, 64),
            },
            b => b,
        },
        block: block.max(1) as u32,
    };
    let nodes = ctx.subtree(&mut ids, 0, 0);
    (nodes, ids)
}

struct Ctx<'a> {
    info: &'a [Info],
    builder: Builder,
    block: u32,
}

impl Ctx<'_> {
    /// A subtree over `ids` (which start at `base` in the final id array) as its own node array, root
    /// first, child indices relative to it. Large ones build their halves in parallel and merge.
    fn subtree(&self, ids: &mut [u32], base: u32, depth: usize) -> Vec<Node> {
        if ids.len() < PARALLEL_THRESHOLD {
            let mut nodes = Vec::with_capacity(2 * ids.len().div_ceil(2));
            nodes.push(self.leaf(ids, base));
            self.fill(&mut nodes, 0, ids, base, depth);
            return nodes;
        }
        let (bounds, split) = self.split(ids, depth);
        let Some(mid) = split else {
            return vec![Node {
                bounds,
                first: base,
                count: ids.len() as u32,
            }];
        };
        let (left_ids, right_ids) = ids.split_at_mut(mid);
        let (left, right) = rayon::join(
            || self.subtree(left_ids, base, depth + 1),
            || self.subtree(right_ids, base + mid as u32, depth + 1),
        );
        // [root, left root, right root, rest of left, rest of right]: each subtree's node i > 0 moves to
        // a fixed offset, and its children (pairs, never index 0) move with it.
        let (nl, nr) = (left.len(), right.len());
        let mut nodes = Vec::with_capacity(1 + nl + nr);
        nodes.push(Node {
            bounds,
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

    /// A leaf over `ids`.
    fn leaf(&self, ids: &[u32], base: u32) -> Node {
        Node {
            bounds: self.bounds(ids),
            first: base,
            count: ids.len() as u32,
        }
    }

    fn bounds(&self, ids: &[u32]) -> Aabb {
        ids.iter()
            .fold(Aabb::EMPTY, |b, &id| b.union(self.info[id as usize].bounds))
    }

    /// Turns `nodes[at]` into the subtree over `ids`, appending children as adjacent pairs.
    fn fill(&self, nodes: &mut Vec<Node>, at: usize, ids: &mut [u32], base: u32, depth: usize) {
        let (bounds, split) = self.split(ids, depth);
        let Some(mid) = split else {
            nodes[at] = Node {
                bounds,
                first: base,
                count: ids.len() as u32,
            };
            return;
        };
        let first = nodes.len();
        nodes[at] = Node {
            bounds,
            first: first as u32,
            count: 0,
        };
        let placeholder = Node {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        };
        nodes.extend([placeholder, placeholder]);
        let (l, r) = ids.split_at_mut(mid);
        self.fill(nodes, first, l, base, depth + 1);
        self.fill(nodes, first + 1, r, base + mid as u32, depth + 1);
    }

    /// The node's bounds and, unless it should be a leaf, the split point after partitioning `ids`.
    fn split(&self, ids: &mut [u32], depth: usize) -> (Aabb, Option<usize>) {
        let mut bounds = Aabb::EMPTY;
        let mut centroids = Aabb::EMPTY;
        for &id in ids.iter() {
            let i = &self.info[id as usize];
            bounds = bounds.union(i.bounds);
            centroids.grow(i.centroid);
        }
        let n = ids.len();
        let split = match self.builder {
            Builder::Midpoint if n <= MIDPOINT_LEAF => None,
            Builder::Midpoint if depth >= MAX_FREE_DEPTH => Some(self.median(ids, &centroids)),
            Builder::Midpoint => Some(self.midpoint(ids, &centroids)),
            Builder::Sah { .. } if n == 1 => None,
            Builder::Sah { .. } if depth >= MAX_FREE_DEPTH => {
                (n > MAX_LEAF).then(|| self.median(ids, &centroids))
            }
            Builder::Sah { bins } => self.sah(ids, &bounds, &centroids, bins),
        };
        // A leaf of mixed kinds splits once more, triangles from the rest.
        let split = split.or_else(|| {
            let k = partition(ids, |id| self.info[id as usize].triangle);
            (k > 0 && k < n).then_some(k)
        });
        (bounds, split)
    }

    /// Splits at the centroids' midpoint on their longest axis; by count if that leaves a side empty.
    fn midpoint(&self, ids: &mut [u32], centroids: &Aabb) -> usize {
        let axis = centroids.extent().max_position();
        let mid = centroids.center()[axis];
        let k = partition(ids, |id| self.info[id as usize].centroid[axis] < mid);
        if k == 0 || k == ids.len() {
            self.median(ids, centroids)
        } else {
            k
        }
    }

    /// Splits in two equal halves along the centroids' longest axis.
    fn median(&self, ids: &mut [u32], centroids: &Aabb) -> usize {
        let axis = centroids.extent().max_position();
        let mid = ids.len() / 2;
        ids.select_nth_unstable_by(mid, |&a, &b| {
            let (ca, cb) = (
                self.info[a as usize].centroid[axis],
                self.info[b as usize].centroid[axis],
            );
            ca.total_cmp(&cb)
        });
        mid
    }

    /// The cheapest binned-SAH split over the three axes, cost c = c_t + (S_L/S_P)·n_L·c_i +
    /// (S_R/S_P)·n_R·c_i; `None` (a leaf) when that costs more than testing the primitives directly and
    /// the node is small enough to be a leaf.
    fn sah(&self, ids: &mut [u32], bounds: &Aabb, centroids: &Aabb, bins: usize) -> Option<usize> {
        // The bin arrays live on the stack and are cleared at every node: size them to the bin count
        // (clearing 64 bins per node was 5% of a dragon.p3f render's instructions).
        match bins {
            0..=16 => self.sah_with::<16>(ids, bounds, centroids, bins),
            17..=32 => self.sah_with::<32>(ids, bounds, centroids, bins),
            _ => self.sah_with::<64>(ids, bounds, centroids, bins),
        }
    }

    fn sah_with<const B: usize>(
        &self,
        ids: &mut [u32],
        bounds: &Aabb,
        centroids: &Aabb,
        bins: usize,
    ) -> Option<usize> {
        let n = ids.len();
        let extent = centroids.extent();
        if extent.max_element() <= 0.0 {
            // Every centroid at one point: no plane separates them.
            return (n > MAX_LEAF).then(|| self.median(ids, centroids));
        }
        let scale = Vec3::select(extent.cmpgt(Vec3::ZERO), bins as f32 / extent, Vec3::ZERO);
        let bin_of =
            |c: Vec3, axis: usize| (((c[axis] - centroids.min[axis]) * scale[axis]) as usize).min(bins - 1);

        let mut count = [[0u32; B]; 3];
        let mut boxes = [[Aabb::EMPTY; B]; 3];
        for &id in ids.iter() {
            let i = &self.info[id as usize];
            for axis in 0..3 {
                let b = bin_of(i.centroid, axis);
                count[axis][b] += 1;
                boxes[axis][b] = boxes[axis][b].union(i.bounds);
            }
        }
        let mut best = (f32::INFINITY, 0usize, 0usize);
        for axis in 0..3 {
            if extent[axis] <= 0.0 {
                continue;
            }
            // Sweep from the right for the right-hand areas, then from the left evaluating each plane.
            let mut right_area = [0f32; B];
            let mut right_count = [0u32; B];
            let (mut b, mut c) = (Aabb::EMPTY, 0);
            for k in (1..bins).rev() {
                b = b.union(boxes[axis][k]);
                c += count[axis][k];
                right_area[k] = b.area();
                right_count[k] = c;
            }
            let (mut b, mut c) = (Aabb::EMPTY, 0);
            for k in 0..bins - 1 {
                b = b.union(boxes[axis][k]);
                c += count[axis][k];
                let cost = b.area() * c.div_ceil(self.block) as f32
                    + right_area[k + 1] * right_count[k + 1].div_ceil(self.block) as f32;
                if c > 0 && right_count[k + 1] > 0 && cost < best.0 {
                    best = (cost, axis, k);
                }
            }
        }
        let area = bounds.area().max(f32::MIN_POSITIVE);
        let test_cost = if self.block > 1 {
            BLOCK_COST
        } else {
            INTERSECTION_COST
        };
        let split_cost = TRAVERSAL_COST + test_cost * best.0 / area;
        let leaf_cost = test_cost * (n as u32).div_ceil(self.block) as f32;
        if best.0.is_infinite() {
            return (n > MAX_LEAF).then(|| self.median(ids, centroids));
        }
        if split_cost >= leaf_cost && n <= MAX_LEAF {
            return None;
        }
        let (_, axis, k) = best;
        let mid = partition(ids, |id| bin_of(self.info[id as usize].centroid, axis) <= k);
        debug_assert!(mid > 0 && mid < n);
        Some(mid)
    }
}

/// Moves the ids for which `left` holds to the front; returns how many there are.
fn partition(ids: &mut [u32], left: impl Fn(u32) -> bool) -> usize {
    let mut k = 0;
    for i in 0..ids.len() {
        if left(ids[i]) {
            ids.swap(i, k);
            k += 1;
        }
    }
    k
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
    /// its primitives; leaf sizes within the builder's limit.
    fn check_invariants(prims: &Prims, nodes: &[Node], ids: &[u32], max_leaf: usize) {
        let mut seen = vec![0u32; prims.bounded() as usize];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = &nodes[i];
            if n.is_leaf() {
                assert!(n.count as usize <= max_leaf, "leaf of {}", n.count);
                for &id in &ids[n.first as usize..(n.first + n.count) as usize] {
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
        for n in [1, 2, 5, 100, 3000, 40_000] {
            let scene = random_scene(n, n as u64);
            let prims = Prims::new(&scene);
            for (builder, max_leaf) in [
                (Builder::Midpoint, MIDPOINT_LEAF),
                (Builder::Sah { bins: 12 }, MAX_LEAF),
            ] {
                let (nodes, ids) = build(&prims, builder, 1);
                check_invariants(&prims, &nodes, &ids, max_leaf.max(1));
            }
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
