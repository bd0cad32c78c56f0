//! The binary BVH: built top-down by midpoint split or binned SAH, stored as one array of nodes whose
//! children are adjacent (left at `first`, right at `first + 1`), leaves pointing into a reordered array
//! of primitive ids. It is the BVH4's source, and an accelerator of its own.

mod build;
mod reinsert;

use std::fmt;

use super::BuildOptions;
use super::counters;
use super::policy::HitPolicy;
use super::prims::{Hit, Prims};
use super::stack::Stack;
use super::structure::Structure;
use crate::geometry::aabb::Aabb;
use crate::geometry::ray::{CULL_MARGIN, Ray, safe_inverse};

pub use build::{Builder, MAX_LEAF, MAX_TREE_DEPTH, build};

/// A node: a box and either two children (`count == 0`, children at `first` and `first + 1`) or a leaf
/// of `count` primitives (`ids[first..first + count]`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// The box around everything below.
    pub bounds: Aabb,
    /// First child, or first primitive of a leaf.
    pub first: u32,
    /// Number of primitives; 0 for an interior node.
    pub count: u32,
}

impl Node {
    /// True for a leaf.
    #[inline(always)]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// Cost of one traversal step relative to one primitive test, for the surface area heuristic. Our leaf
/// tests are a few times dearer than a box test; 1:1 is the usual choice and the SAH is flat around it.
pub const TRAVERSAL_COST: f32 = 1.0;
/// Cost of one primitive test.
pub const INTERSECTION_COST: f32 = 1.0;
/// Cost of one SIMD block test (a leaf of the wide BVHs, whose builds use `block` 4), in the builder's
/// choice between a split and a leaf: half a traversal step. A leaf of five to eight triangles is one
/// eight-lane step of the wide kernels where the CPU has AVX, and a split in its place costs a wide
/// node's box test, its stack traffic and its place on the chain from node to child (figures:
/// `profiles/README.md`, tuned constants).
pub const BLOCK_COST: f32 = 0.5;

/// A binary BVH over a scene's bounded primitives.
#[derive(Clone, Debug)]
pub struct Bvh2<'a> {
    prims: Prims<'a>,
    /// Nodes, root first (absent when the scene has no bounded primitive).
    pub nodes: Vec<Node>,
    /// Primitive ids in leaf order.
    pub ids: Vec<u32>,
}

/// Traversal stack depth: one entry per level (the farther child) of a tree at most [`MAX_TREE_DEPTH`] deep.
const STACK: usize = MAX_TREE_DEPTH;

impl<'a> Bvh2<'a> {
    /// Builds the tree for scalar leaf tests.
    pub fn new(prims: Prims<'a>, builder: Builder) -> Self {
        Self::with_block(prims, builder, 1)
    }

    /// Builds the tree for leaves that test `block` primitives at the cost of one (see [`Bvh2::build`]).
    pub fn with_block(prims: Prims<'a>, builder: Builder, block: usize) -> Self {
        let (nodes, ids) = build(&prims, builder, block);
        Bvh2 { prims, nodes, ids }
    }

    /// Builds the tree `options` describe, for scalar leaf tests.
    pub fn build(prims: Prims<'a>, options: &BuildOptions) -> Self {
        Self::build_with_block(prims, options, 1)
    }

    /// Builds the tree `options` describe for leaves that test `block` primitives at the cost of one.
    pub(crate) fn build_with_block(prims: Prims<'a>, options: &BuildOptions, block: usize) -> Self {
        let bvh = Self::with_block(prims, options.builder, block);
        if options.reinsert { bvh.reinserted() } else { bvh }
    }

    /// The tree after insertion-based optimization (`reinsert.rs`): the same leaves under interior
    /// nodes of less summed area. Unchanged where no move pays, or where the moves would deepen the
    /// tree past [`MAX_TREE_DEPTH`].
    pub fn reinserted(self) -> Self {
        match reinsert::reinsert(&self.nodes, &self.ids) {
            Some((nodes, ids)) => Bvh2 {
                prims: self.prims,
                nodes,
                ids,
            },
            None => self,
        }
    }

    /// The primitives this tree indexes.
    pub fn prims(&self) -> &Prims<'a> {
        &self.prims
    }

    /// One traversal for closest and any hit: nearer child first, subtrees behind the closest hit skipped.
    #[inline]
    pub fn traverse<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        let mut found = self.prims.intersect_planes::<P>(ray, t_min, hit);
        if (P::ANY && found) || self.nodes.is_empty() {
            return found;
        }
        let inv = safe_inverse(ray.dir);
        let mut stack = Stack::<(u32, f32), STACK>::new();
        let mut node = &self.nodes[0];
        if node.bounds.ray_entry(ray.origin, inv, t_min, hit.t).is_none() {
            return found;
        }
        loop {
            if node.is_leaf() {
                let ids = &self.ids[node.first as usize..(node.first + node.count) as usize];
                if self
                    .prims
                    .intersect_each::<P>(ids.iter().copied(), ray, t_min, hit)
                {
                    found = true;
                    if P::ANY {
                        return true;
                    }
                }
            } else {
                counters::node::<P>();
                let (a, b) = (
                    &self.nodes[node.first as usize],
                    &self.nodes[node.first as usize + 1],
                );
                let ta = a.bounds.ray_entry(ray.origin, inv, t_min, hit.t * CULL_MARGIN);
                let tb = b.bounds.ray_entry(ray.origin, inv, t_min, hit.t * CULL_MARGIN);
                match (ta, tb) {
                    (Some(ta), Some(tb)) => {
                        let (near, far, t_far) = if ta <= tb {
                            (node.first, node.first + 1, tb)
                        } else {
                            (node.first + 1, node.first, ta)
                        };
                        stack.push((far, t_far));
                        node = &self.nodes[near as usize];
                        continue;
                    }
                    (Some(_), None) => {
                        node = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the next subtree that may still hold a closer hit.
            loop {
                let Some((i, t_enter)) = stack.pop() else {
                    return found;
                };
                if t_enter <= hit.t * CULL_MARGIN {
                    node = &self.nodes[i as usize];
                    break;
                }
            }
        }
    }

    /// Node count, depth, leaf sizes and SAH cost.
    pub fn stats(&self) -> Stats {
        let mut s = Stats::default();
        if self.nodes.is_empty() {
            return s;
        }
        let root_area = self.nodes[0].bounds.area().max(f32::MIN_POSITIVE);
        let mut stack = vec![(0usize, 1usize)];
        while let Some((i, depth)) = stack.pop() {
            let n = &self.nodes[i];
            s.nodes += 1;
            s.depth = s.depth.max(depth);
            let rel = n.bounds.area() / root_area;
            if n.is_leaf() {
                s.leaves += 1;
                s.add_leaf(n.count as usize);
                s.sah += (INTERSECTION_COST * n.count as f32 * rel) as f64;
            } else {
                s.sah += (TRAVERSAL_COST * rel) as f64;
                stack.push((n.first as usize, depth + 1));
                stack.push((n.first as usize + 1, depth + 1));
            }
        }
        s
    }
}

/// Shape and quality figures of a hierarchy, for `whitted info`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    /// Nodes, leaves included.
    pub nodes: usize,
    /// Leaves.
    pub leaves: usize,
    /// Levels from the root (1 for a lone leaf).
    pub depth: usize,
    /// `histogram[k]`: leaves with k primitives (the last bucket holds all larger ones).
    pub histogram: [usize; 17],
    /// Surface area heuristic cost: Σ over nodes of (cost × area / root area).
    pub sah: f64,
}

impl Stats {
    /// Counts a leaf of `n` primitives.
    pub fn add_leaf(&mut self, n: usize) {
        self.histogram[n.min(16)] += 1;
    }
}

impl fmt::Display for Stats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} nodes, {} leaves, depth {}, SAH cost {:.2}; leaf sizes",
            self.nodes, self.leaves, self.depth, self.sah
        )?;
        for (k, &n) in self.histogram.iter().enumerate().filter(|(_, n)| **n > 0) {
            let plus = if k == 16 { "+" } else { "" };
            write!(f, " {k}{plus}:{n}")?;
        }
        Ok(())
    }
}

impl<'a> Structure<'a> for Bvh2<'a> {
    fn prims(&self) -> Prims<'a> {
        self.prims
    }

    fn describe(&self) -> String {
        format!("bvh2: {}", self.stats())
    }

    #[inline(always)]
    fn traverse<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        Bvh2::traverse::<P>(self, ray, t_min, hit)
    }
}
