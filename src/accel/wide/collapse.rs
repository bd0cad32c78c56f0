//! BVH2 → W-wide BVH: each wide node takes its BVH2 node's two children and, while it has fewer than
//! `W`, opens the interior child with the largest surface area (the one a ray is most likely to enter),
//! so the wide node replaces the most likely-visited binary levels.

use rayon::prelude::*;

use super::tri4::Tri4;
use super::{COUNT_BITS, ChildRef, EMPTY, LEAF, Node, TRIANGLES};
use crate::accel::bvh2::Node as Node2;
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
        nodes: Vec::with_capacity(nodes2.len() / (W - 1) + 1),
        blocks: Vec::with_capacity(nodes2.len() / 4),
    };
    let root = match nodes2.first() {
        None => EMPTY,
        Some(root) if root.is_leaf() => c.leaf(root),
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

struct Collapser<'a, const W: usize> {
    nodes2: &'a [Node2],
    ids: &'a [u32],
    prims: &'a Prims<'a>,
    nodes: Vec<Node<W>>,
    /// Each triangle block to pack, in order: its first id's index in `ids` and how many follow (1-4).
    blocks: Vec<(u32, u32)>,
}

impl<const W: usize> Collapser<'_, W> {
    /// A leaf reference: triangles get the next SIMD blocks, other kinds keep their id range.
    fn leaf(&mut self, n: &Node2) -> ChildRef {
        debug_assert!(n.count < 1 << COUNT_BITS);
        // Leaves hold one kind (the builder splits mixed ones), so the first id tells.
        if !matches!(self.prims.kind(self.ids[n.first as usize]), PrimKind::Triangle(_)) {
            return LEAF | (n.first << COUNT_BITS) | n.count;
        }
        let start = self.blocks.len() as u32;
        self.blocks.extend(
            (0..n.count)
                .step_by(4)
                .map(|k| (n.first + k, (n.count - k).min(4))),
        );
        LEAF | TRIANGLES | (start << COUNT_BITS) | n.count
    }

    /// Appends the wide node for interior BVH2 node `i` and, after it, its subtrees in order.
    fn emit(&mut self, i: usize) -> u32 {
        let nodes2 = self.nodes2;
        let at = self.nodes.len();
        self.nodes.push(Node::EMPTY);
        // Gather up to W BVH2 nodes under `i`.
        let mut slots = [0usize; W];
        slots[..2].copy_from_slice(&[nodes2[i].first as usize, nodes2[i].first as usize + 1]);
        let mut len = 2;
        while len < W {
            let open = (0..len)
                .filter(|&k| !nodes2[slots[k]].is_leaf())
                .max_by(|&a, &b| {
                    nodes2[slots[a]]
                        .bounds
                        .area()
                        .total_cmp(&nodes2[slots[b]].bounds.area())
                });
            let Some(k) = open else { break };
            let n = &nodes2[slots[k]];
            slots[k] = n.first as usize;
            slots[len] = n.first as usize + 1;
            len += 1;
        }
        let mut node = Node::<W>::EMPTY;
        for (k, &s) in slots[..len].iter().enumerate() {
            let child = &nodes2[s];
            for axis in 0..3 {
                node.min[axis][k] = child.bounds.min[axis];
                node.max[axis][k] = child.bounds.max[axis];
            }
            node.child[k] = if child.is_leaf() {
                self.leaf(child)
            } else {
                self.emit(s)
            };
        }
        self.nodes[at] = node;
        at as u32
    }
}
