//! BVH2 → BVH4: each 4-wide node takes its BVH2 node's two children and, while it has fewer than four,
//! opens the interior child with the largest surface area (the one a ray is most likely to enter), so the
//! wide node replaces the most likely-visited binary levels.

use super::{COUNT_BITS, ChildRef, EMPTY, LEAF, Node4};
use crate::accel::bvh2::Node;

/// The nodes (depth-first, root first) and the root reference.
pub fn collapse(nodes2: &[Node]) -> (Vec<Node4>, ChildRef) {
    let Some(root) = nodes2.first() else {
        return (Vec::new(), EMPTY);
    };
    if root.is_leaf() {
        return (Vec::new(), leaf_ref(root));
    }
    let mut out = Vec::with_capacity(nodes2.len() / 3 + 1);
    emit(nodes2, 0, &mut out);
    (out, 0)
}

fn leaf_ref(n: &Node) -> ChildRef {
    debug_assert!(n.count < 1 << COUNT_BITS);
    LEAF | (n.first << COUNT_BITS) | n.count
}

/// Appends the 4-wide node for interior BVH2 node `i` and, after it, its subtrees in order.
fn emit(nodes2: &[Node], i: usize, out: &mut Vec<Node4>) -> u32 {
    let at = out.len();
    out.push(Node4::EMPTY);
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
            leaf_ref(child)
        } else {
            emit(nodes2, s, out)
        };
    }
    out[at] = node;
    at as u32
}
