//! BVH2 → W-wide BVH, choosing by the surface area heuristic which binary nodes become wide nodes,
//! which are skipped, and which subtrees of at most [`MAX_LEAF`] primitives become one leaf: the
//! dynamic programme of Ylitie, Karras and Laine 2017 ("Efficient Incoherent Ray Traversal on GPUs
//! Through Compressed Wide BVHs", 4.1), with the builder's costs (a wide node's test
//! [`TRAVERSAL_COST`], a block of four triangles [`BLOCK_COST`]).
//!
//! `cost(n, j)`: the least SAH cost of the subtree under binary node `n` as a forest of at most `j`
//! roots. One root is a leaf or a wide node whose children are the best forest of `W` roots under
//! `n`'s two children; `j` roots are `j - 1`, or `k` roots under the left child and `j - k` under the
//! right.

use rayon::prelude::*;

use super::tri4::Tri4;
use super::{COUNT_BITS, ChildRef, EMPTY, LEAF, Node, TRIANGLES};
use crate::accel::bvh2::{BLOCK_COST, INTERSECTION_COST, MAX_LEAF, Node as Node2, TRAVERSAL_COST};
use crate::accel::pages::with_capacity_on_huge_pages;
use crate::accel::prims::{PrimKind, Prims};

/// The collapsed tree: nodes depth-first (root first), the root reference, and the triangle blocks
/// that triangle leaves point into, in the order a depth-first walk meets them.
pub struct Collapsed<const W: usize> {
    pub nodes: Vec<Node<W>>,
    pub root: ChildRef,
    pub tris: Vec<Tri4>,
}

/// Collapses a BVH2 whose leaves hold one kind of primitive each. The walk lays out the nodes and
/// gives each triangle leaf its blocks' place; the blocks, most of the work (each gathers four
/// triangles from the scene's arrays), are then packed in parallel, into memory advised for huge pages.
pub fn collapse<const W: usize>(nodes2: &[Node2], ids: &[u32], prims: &Prims) -> Collapsed<W> {
    let mut c = Collapser {
        nodes2,
        ids,
        prims,
        plans: plan::<W>(nodes2, ids, prims),
        nodes: Vec::with_capacity(nodes2.len() / (W - 1) + 1),
        blocks: Vec::with_capacity(nodes2.len() / 4),
    };
    let root = match nodes2.first() {
        None => EMPTY,
        Some(root) if root.is_leaf() => c.leaf(root.first, root.count),
        Some(_) => c.emit(0),
    };
    let mut tris = with_capacity_on_huge_pages(c.blocks.len());
    c.blocks
        .par_iter()
        .with_min_len(1024)
        .map(|&(first, len)| {
            let mut lanes = [(0u32, 0usize); 4];
            let mut used = 0;
            for &id in &ids[first as usize..(first + len) as usize] {
                if let PrimKind::Triangle(i) = prims.kind(id) {
                    lanes[used] = (id, i);
                    used += 1;
                }
            }
            Tri4::pack(&prims.scene.triangles, &lanes[..used])
        })
        .collect_into_vec(&mut tris);
    Collapsed {
        nodes: c.nodes,
        root,
        tris,
    }
}

/// The programme's answer for one binary node.
#[derive(Clone, Copy)]
struct Plan<const W: usize> {
    /// `cost[j - 1]`: the least cost of the subtree as at most `j` roots.
    cost: [f32; W],
    /// `split[j - 1]` for `j >= 2`: how many of the `j` roots go under the left child, or 0 where
    /// `j - 1` roots cost as little. `split[0]`: the split of the `W` children of the wide node `n`
    /// becomes as one root.
    split: [u8; W],
    /// As one root, a leaf (else a wide node).
    leaf: bool,
    /// Its primitives' first index in `ids` (a subtree's are contiguous), and how many.
    first: u32,
    count: u32,
    /// Its primitives are all triangles (or none are): it may be one leaf.
    kind: Kind,
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Triangles,
    Others,
    Mixed,
}

/// The programme over every binary node, children first (they follow their parents in `nodes2`).
fn plan<const W: usize>(nodes2: &[Node2], ids: &[u32], prims: &Prims) -> Vec<Plan<W>> {
    let mut plans = vec![
        Plan {
            cost: [0.0; W],
            split: [0; W],
            leaf: true,
            first: 0,
            count: 0,
            kind: Kind::Mixed,
        };
        nodes2.len()
    ];
    let leaf_cost = |count: u32, kind: Kind| match kind {
        Kind::Triangles => count.div_ceil(4) as f32 * BLOCK_COST,
        Kind::Others => count as f32 * INTERSECTION_COST,
        Kind::Mixed => f32::INFINITY,
    };
    for i in (0..nodes2.len()).rev() {
        let n = &nodes2[i];
        let area = n.bounds.area();
        if n.is_leaf() {
            // Leaves hold one kind (the builder splits mixed ones), so the first id tells.
            let kind = match prims.kind(ids[n.first as usize]) {
                PrimKind::Triangle(_) => Kind::Triangles,
                _ => Kind::Others,
            };
            plans[i] = Plan {
                cost: [area * leaf_cost(n.count, kind); W],
                split: [0; W],
                leaf: true,
                first: n.first,
                count: n.count,
                kind,
            };
            continue;
        }
        debug_assert!(n.first as usize > i, "children follow their parent");
        let (l, r) = (&plans[n.first as usize], &plans[n.first as usize + 1]);
        let kind = if l.kind == r.kind { l.kind } else { Kind::Mixed };
        debug_assert_eq!(l.first + l.count, r.first, "a subtree's ids are contiguous");
        let mut plan = Plan {
            cost: [f32::INFINITY; W],
            split: [0; W],
            leaf: false,
            first: l.first,
            count: l.count + r.count,
            kind,
        };
        // dist[j - 1]: the best forest of j >= 2 roots, k under the left child.
        let mut dist = [(f32::INFINITY, 0u8); W];
        for j in 2..=W {
            for k in 1..j {
                let c = l.cost[k - 1] + r.cost[j - k - 1];
                if c < dist[j - 1].0 {
                    dist[j - 1] = (c, k as u8);
                }
            }
        }
        let wide = area * TRAVERSAL_COST + dist[W - 1].0;
        let leaf = if plan.count as usize <= MAX_LEAF {
            area * leaf_cost(plan.count, kind)
        } else {
            f32::INFINITY
        };
        plan.leaf = leaf <= wide;
        plan.cost[0] = leaf.min(wide);
        plan.split[0] = dist[W - 1].1;
        for j in 2..=W {
            if dist[j - 1].0 < plan.cost[j - 2] {
                plan.cost[j - 1] = dist[j - 1].0;
                plan.split[j - 1] = dist[j - 1].1;
            } else {
                plan.cost[j - 1] = plan.cost[j - 2];
            }
        }
        plans[i] = plan;
    }
    plans
}

struct Collapser<'a, const W: usize> {
    nodes2: &'a [Node2],
    ids: &'a [u32],
    prims: &'a Prims<'a>,
    plans: Vec<Plan<W>>,
    nodes: Vec<Node<W>>,
    /// Each triangle block to pack, in order: its first id's index in `ids` and how many follow (1-4).
    blocks: Vec<(u32, u32)>,
}

impl<const W: usize> Collapser<'_, W> {
    /// A leaf reference over `ids[first..first + count]` (one kind): triangles get the next SIMD
    /// blocks, other kinds keep their id range.
    fn leaf(&mut self, first: u32, count: u32) -> ChildRef {
        debug_assert!(count < 1 << COUNT_BITS);
        if !matches!(self.prims.kind(self.ids[first as usize]), PrimKind::Triangle(_)) {
            return LEAF | (first << COUNT_BITS) | count;
        }
        let start = self.blocks.len() as u32;
        self.blocks
            .extend((0..count).step_by(4).map(|k| (first + k, (count - k).min(4))));
        LEAF | TRIANGLES | (start << COUNT_BITS) | count
    }

    /// The roots of binary node `i`'s best forest of at most `j` roots, appended to `roots`.
    fn roots(&self, i: usize, j: usize, roots: &mut Vec<usize>) {
        let plan = &self.plans[i];
        if j == 1 || self.nodes2[i].is_leaf() {
            roots.push(i);
            return;
        }
        match plan.split[j - 1] as usize {
            0 => self.roots(i, j - 1, roots),
            k => {
                let first = self.nodes2[i].first as usize;
                self.roots(first, k, roots);
                self.roots(first + 1, j - k, roots);
            }
        }
    }

    /// Appends the wide node for interior binary node `i` and, after it, its subtrees in order.
    fn emit(&mut self, i: usize) -> u32 {
        let at = self.nodes.len();
        self.nodes.push(Node::EMPTY);
        let first = self.nodes2[i].first as usize;
        let k = self.plans[i].split[0] as usize;
        let mut roots = Vec::with_capacity(W);
        self.roots(first, k, &mut roots);
        self.roots(first + 1, W - k, &mut roots);
        let mut node = Node::<W>::EMPTY;
        for (slot, &s) in roots.iter().enumerate() {
            let bounds = self.nodes2[s].bounds;
            for axis in 0..3 {
                node.min[axis][slot] = bounds.min[axis];
                node.max[axis][slot] = bounds.max[axis];
            }
            let plan = self.plans[s];
            node.child[slot] = if plan.leaf {
                self.leaf(plan.first, plan.count)
            } else {
                self.emit(s)
            };
        }
        self.nodes[at] = node;
        at as u32
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use glam::Vec3;
    use rand_xoshiro::Xoshiro256PlusPlus;
    use rand_xoshiro::rand_core::{Rng, SeedableRng};

    use super::super::WideBvh;
    use crate::accel::Prims;
    use crate::accel::bvh2::{BLOCK_COST, Builder, Bvh2, INTERSECTION_COST, MAX_LEAF, TRAVERSAL_COST};
    use crate::accel::quality::TreeView;
    use crate::scene::{Camera, Material, Scene};

    /// Triangles of many sizes, with spheres among them on odd seeds (leaves of two kinds).
    fn scene(seed: u64, n: usize) -> Scene {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut point =
            move || Vec3::from_array([0; 3].map(|_| (rng.next_u32() >> 8) as f32 / (1 << 24) as f32));
        let mut scene = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = scene.add_material(Material::default());
        for k in 0..n {
            let o = point() * 10.0;
            let size = if k % 7 == 0 { 4.0 } else { 0.5 };
            if seed % 2 == 1 && k % 5 == 0 {
                scene.add_sphere(o, size * 0.3, m);
            } else {
                let (a, b) = (point() * size, point() * size);
                scene.add_triangle(o, o + a, o + b, m);
            }
        }
        scene
    }

    /// The least cost of binary node `i`'s subtree as one root, by trying every wide tree: a leaf where
    /// it may be one, else a wide node over every frontier of at most `w` nodes under it.
    fn exhaustive(bvh: &Bvh2, i: usize, w: usize, memo: &mut HashMap<usize, f64>) -> f64 {
        if let Some(&c) = memo.get(&i) {
            return c;
        }
        let n = &bvh.nodes[i];
        let area = n.bounds.area() as f64;
        let prims = bvh.prims();
        let count = if n.is_leaf() {
            n.count as usize
        } else {
            subtree_count(bvh, i)
        };
        let first_id = if n.is_leaf() {
            n.first as usize
        } else {
            first_of(bvh, i)
        };
        let kinds: Vec<bool> = bvh.ids[first_id..first_id + count]
            .iter()
            .map(|&id| matches!(prims.kind(id), crate::accel::PrimKind::Triangle(_)))
            .collect();
        let leaf = if (n.is_leaf() || count <= MAX_LEAF) && kinds.iter().all(|&t| t == kinds[0]) {
            let tests = if kinds[0] {
                count.div_ceil(4) as f64 * BLOCK_COST as f64
            } else {
                count as f64 * INTERSECTION_COST as f64
            };
            area * tests
        } else {
            f64::INFINITY
        };
        let mut best = f64::INFINITY;
        if !n.is_leaf() {
            for frontier in frontiers(bvh, n.first as usize, n.first as usize + 1, w) {
                let c: f64 = frontier.iter().map(|&f| exhaustive(bvh, f, w, memo)).sum();
                best = best.min(c);
            }
        }
        let c = leaf.min(area * TRAVERSAL_COST as f64 + best);
        memo.insert(i, c);
        c
    }

    /// Every set of at most `w` nodes that covers the subtrees of `a` and `b` (each node or, opened,
    /// a frontier of its children).
    fn frontiers(bvh: &Bvh2, a: usize, b: usize, w: usize) -> Vec<Vec<usize>> {
        let mut out = Vec::new();
        for fa in covers(bvh, a, w - 1) {
            for fb in covers(bvh, b, w - fa.len()) {
                out.push([fa.clone(), fb].concat());
            }
        }
        out
    }

    fn covers(bvh: &Bvh2, i: usize, w: usize) -> Vec<Vec<usize>> {
        let mut out = vec![vec![i]];
        let n = &bvh.nodes[i];
        if !n.is_leaf() && w >= 2 {
            out.extend(frontiers(bvh, n.first as usize, n.first as usize + 1, w));
        }
        out
    }

    fn subtree_count(bvh: &Bvh2, i: usize) -> usize {
        let n = &bvh.nodes[i];
        if n.is_leaf() {
            n.count as usize
        } else {
            subtree_count(bvh, n.first as usize) + subtree_count(bvh, n.first as usize + 1)
        }
    }

    fn first_of(bvh: &Bvh2, i: usize) -> usize {
        let n = &bvh.nodes[i];
        if n.is_leaf() {
            n.first as usize
        } else {
            first_of(bvh, n.first as usize)
        }
    }

    /// The cost of a collapsed tree, read off its nodes: a wide node's area at the traversal cost, a
    /// leaf's at the cost of its tests.
    fn cost(view: &TreeView, prims: &Prims) -> f64 {
        view.nodes
            .iter()
            .map(|n| {
                let area = n.bounds.area() as f64;
                if !n.children.is_empty() {
                    return area * TRAVERSAL_COST as f64;
                }
                let triangles = matches!(prims.kind(n.prims[0]), crate::accel::PrimKind::Triangle(_));
                let tests = if triangles {
                    n.prims.len().div_ceil(4) as f64 * BLOCK_COST as f64
                } else {
                    n.prims.len() as f64 * INTERSECTION_COST as f64
                };
                area * tests
            })
            .sum()
    }

    /// The collapse of every small tree costs what the cheapest of all its possible wide trees costs:
    /// over the wide BVHs' own binary trees (leaves of up to eight) and over trees of scalar leaves,
    /// whose small leaves the collapse merges.
    #[test]
    fn the_collapse_is_the_cheapest_wide_tree() {
        let mut merged = 0;
        for seed in 0..8 {
            let scene = scene(seed, 24 + 4 * seed as usize);
            let prims = Prims::new(&scene);
            for block in [4, 1] {
                let bvh2 = Bvh2::with_block(prims, Builder::Sah { bins: 12 }, block);
                let want4 = exhaustive(&bvh2, 0, 4, &mut HashMap::new());
                let want8 = exhaustive(&bvh2, 0, 8, &mut HashMap::new());
                let bvh8 = WideBvh::<8>::from_bvh2(bvh2.clone());
                let got4 = cost(&TreeView::from(&WideBvh::<4>::from_bvh2(bvh2.clone())), &prims);
                let got8 = cost(&TreeView::from(&bvh8), &prims);
                assert!(
                    (got4 - want4).abs() <= 1e-4 * want4,
                    "seed {seed}, block {block}: BVH4 {got4} vs {want4}"
                );
                assert!(
                    (got8 - want8).abs() <= 1e-4 * want8,
                    "seed {seed}, block {block}: BVH8 {got8} vs {want8}"
                );
                merged += usize::from(bvh8.stats().leaves < bvh2.stats().leaves);
            }
        }
        assert!(merged > 0, "some collapse merges leaves");
    }
}
