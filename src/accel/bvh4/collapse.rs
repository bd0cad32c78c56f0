//! BVH2 → BVH4: each 4-wide node takes its BVH2 node's two children and, while it has fewer than four,
//! opens the interior child with the largest surface area (the one a ray is most likely to enter), so the
//! wide node replaces the most likely-visited binary levels.

use super::tri4::Tri4;
use super::{COUNT_BITS, ChildRef, EMPTY, LEAF, Node4, TRIANGLES};
use crate::accel::bvh2::Node;
use crate::accel::prims::{PrimKind, Prims};

/// The collapsed tree: nodes depth-first (root first), the root reference, and the triangle blocks
/// that triangle leaves point into, in the order a depth-first walk meets them.
pub struct Collapsed {
    pub nodes: Vec<Node4>,
    pub root: ChildRef,
    pub tris: Vec<Tri4>,
}

/// Collapses a BVH2 whose leaves hold one kind of primitive each.
pub fn collapse(nodes2: &[Node], ids: &[u32], prims: &Prims) -> Collapsed {
    let mut c = Collapser {
        nodes2,
        ids,
        prims,
        out: Collapsed {
            nodes: Vec::with_capacity(nodes2.len() / 3 + 1),
            root: EMPTY,
            tris: Vec::with_capacity(nodes2.len() / 4),
        },
    };
    if let Some(root) = nodes2.first() {
        c.out.root = if root.is_leaf() { c.leaf(root) } else { c.emit(0) };
    }
    c.out
}

struct Collapser<'a> {
    nodes2: &'a [Node],
    ids: &'a [u32],
    prims: &'a Prims<'a>,
    out: Collapsed,
}

impl Collapser<'_> {
    /// A leaf reference: triangles are packed into SIMD blocks, other kinds keep their id range.
    fn leaf(&mut self, n: &Node) -> ChildRef {
        debug_assert!(n.count < 1 << COUNT_BITS);
        let ids = &self.ids[n.first as usize..(n.first + n.count) as usize];
        // Leaves hold one kind (the builder splits mixed ones), so the first id tells.
        if !matches!(self.prims.kind(ids[0]), PrimKind::Triangle(_)) {
            return LEAF | (n.first << COUNT_BITS) | n.count;
        }
        let start = self.out.tris.len() as u32;
        let mut lanes = [(0u32, 0usize); 4];
        for chunk in ids.chunks(4) {
            let mut len = 0;
            for &id in chunk {
                if let PrimKind::Triangle(i) = self.prims.kind(id) {
                    lanes[len] = (id, i);
                    len += 1;
                }
            }
            self.out
                .tris
                .push(Tri4::pack(&self.prims.scene.triangles, &lanes[..len]));
        }
        LEAF | TRIANGLES | (start << COUNT_BITS) | n.count
    }

    /// Appends the 4-wide node for interior BVH2 node `i` and, after it, its subtrees in order.
    fn emit(&mut self, i: usize) -> u32 {
        let nodes2 = self.nodes2;
        let at = self.out.nodes.len();
        self.out.nodes.push(Node4::EMPTY);
        // Gather up to four BVH2 nodes under `i`.
        let mut slots = [nodes2[i].first as usize, nodes2[i].first as usize + 1, 0, 0];
        let mut len = 2;
        while len < 4 {
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
        let mut node = Node4::EMPTY;
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
        self.out.nodes[at] = node;
        at as u32
    }
}
