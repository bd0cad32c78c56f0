//! Insertion-based optimization of a built BVH2 (Bittner, Hapala and Havran 2013, "Fast Insertion-Based
//! Optimization of Bounding Volume Hierarchies"). Each round takes the interior nodes whose boxes are
//! largest against their children's, removes each with its parent, and puts its two subtrees back
//! where each adds the least surface area (a branch-and-bound search from the root), the two freed
//! nodes becoming their new parents. Leaves stay as built, so the SAH cost changes only by interior
//! nodes' areas: a move that does not lower their sum is undone, and rounds stop when one gains little.
//!
//! The moves run one after another over the whole tree: most of the gain comes from moves across the
//! top of the tree, which optimizing subtrees apart in parallel would forbid.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::{MAX_TREE_DEPTH, Node};
use crate::geometry::aabb::Aabb;

/// No node (the root's parent).
const NONE: u32 = u32::MAX;
/// Each round tries to move this share of the interior nodes, those with the worst boxes for their
/// children.
const BATCH: f64 = 0.01;
/// Rounds stop when one lowers the interior nodes' summed area by less than this share of it.
const MIN_GAIN: f64 = 0.001;
/// And after at most this many.
const MAX_ROUNDS: usize = 64;

/// A node with its parent: a box and two children, or (`count > 0`) a leaf of `count` ids from
/// `kids[0]` in the input's id array.
#[derive(Clone, Copy, Debug)]
struct Link {
    bounds: Aabb,
    parent: u32,
    kids: [u32; 2],
    count: u32,
}

impl Link {
    fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// A frontier search entry: a node and the area its ancestors would grow by (Bittner's induced cost).
#[derive(Clone, Copy)]
struct Candidate {
    induced: f32,
    node: u32,
}

impl PartialEq for Candidate {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Candidate {}
impl PartialOrd for Candidate {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Candidate {
    /// Reversed, so that the max-heap pops the least induced cost first.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .induced
            .total_cmp(&self.induced)
            .then(other.node.cmp(&self.node))
    }
}

/// The tree in linked form, and the scratch its moves use.
struct Tree {
    links: Vec<Link>,
    root: u32,
    /// The links a move changed, each as it was before the move's first change, to undo it.
    journal: Vec<(u32, Link)>,
    /// `stamp[i] == move` once link `i` is in the journal of move number `move`.
    stamp: Vec<u32>,
    moves: u32,
    heap: BinaryHeap<Candidate>,
}

/// Optimizes the BVH2 `nodes` (root first, children adjacent) over `ids`; returns the new nodes and
/// ids in the same layout, or `None` where the tree is too small to change or the result would be
/// deeper than the traversal stacks allow ([`MAX_TREE_DEPTH`]).
pub fn reinsert(nodes: &[Node], ids: &[u32]) -> Option<(Vec<Node>, Vec<u32>)> {
    if nodes.len() < 7 {
        return None;
    }
    let mut tree = Tree::from_nodes(nodes);
    tree.optimize();
    tree.emit(ids)
}

impl Tree {
    /// The tree of `nodes`, linked (in depth-first order).
    fn from_nodes(nodes: &[Node]) -> Tree {
        let mut links = Vec::with_capacity(nodes.len());
        let mut todo = vec![(0u32, NONE, 0usize)];
        while let Some((i, parent, slot)) = todo.pop() {
            let n = &nodes[i as usize];
            let at = links.len() as u32;
            if parent != NONE {
                let p: &mut Link = &mut links[parent as usize];
                p.kids[slot] = at;
            }
            let kids = if n.is_leaf() {
                [n.first, 0]
            } else {
                todo.extend([(n.first + 1, at, 1), (n.first, at, 0)]);
                [NONE, NONE]
            };
            links.push(Link {
                bounds: n.bounds,
                parent,
                kids,
                count: n.count,
            });
        }
        let stamp = vec![0; links.len()];
        Tree {
            links,
            root: 0,
            journal: Vec::new(),
            stamp,
            moves: 0,
            heap: BinaryHeap::new(),
        }
    }

    /// Rounds of reinsertion until one gains less than [`MIN_GAIN`].
    fn optimize(&mut self) {
        let mut cost = self.interior_area();
        for _ in 0..MAX_ROUNDS {
            let batch = self.worst();
            if batch.is_empty() {
                return;
            }
            let before = cost;
            for n in batch {
                cost += self.reinsert_children(n);
            }
            if before - cost < MIN_GAIN * before {
                return;
            }
        }
    }

    /// The summed area of the interior nodes: the part of the SAH cost that moves change.
    fn interior_area(&self) -> f64 {
        let interior = self.links.iter().filter(|l| !l.is_leaf());
        interior.map(|l| l.bounds.area() as f64).sum()
    }

    /// The round's batch: the interior nodes below the root's children with the largest
    /// `M_comb = A(N) · A(N)/min(A(L), A(R)) · A(N)/mean(A(L), A(R))` (Bittner et al. 2013, 3.3).
    fn worst(&self) -> Vec<u32> {
        let mut scored: Vec<(f32, u32)> = (0..self.links.len() as u32)
            .filter(|&i| {
                let l = &self.links[i as usize];
                !l.is_leaf() && l.parent != NONE && self.links[l.parent as usize].parent != NONE
            })
            .map(|i| {
                let l = &self.links[i as usize];
                let a = l.bounds.area();
                let [al, ar] = l.kids.map(|k| self.links[k as usize].bounds.area());
                let tiny = f32::MIN_POSITIVE;
                (
                    a * (a / al.min(ar).max(tiny)) * (a / (0.5 * (al + ar)).max(tiny)),
                    i,
                )
            })
            .collect();
        let k = ((scored.len() as f64 * BATCH).ceil() as usize).min(scored.len());
        if k == 0 {
            return Vec::new();
        }
        scored.select_nth_unstable_by(k - 1, |a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        scored.truncate(k);
        scored.sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        scored.into_iter().map(|(_, i)| i).collect()
    }

    /// Keeps link `i` as it is now in the journal of this move, unless it is there already.
    fn record(&mut self, i: u32) {
        if self.stamp[i as usize] != self.moves {
            self.stamp[i as usize] = self.moves;
            self.journal.push((i, self.links[i as usize]));
        }
    }

    /// Takes interior node `n` and its parent out and puts `n`'s children back where each costs least,
    /// under `n` and the parent; returns the change in the interior nodes' summed area (negative), or 0
    /// where the move would not lower it and was undone.
    fn reinsert_children(&mut self, n: u32) -> f64 {
        let p = self.links[n as usize].parent;
        if p == NONE || self.links[p as usize].parent == NONE {
            return 0.0;
        }
        self.moves += 1;
        self.journal.clear();
        let g = self.links[p as usize].parent;
        let pk = self.links[p as usize].kids;
        let sibling = if pk[0] == n { pk[1] } else { pk[0] };
        for i in [n, p, g, sibling] {
            self.record(i);
        }
        self.replace_kid(g, p, sibling);
        self.links[sibling as usize].parent = g;
        self.refit(g);
        let [a, b] = self.links[n as usize].kids;
        let (first, second) = if self.area(a) >= self.area(b) {
            (a, b)
        } else {
            (b, a)
        };
        let root = self.root;
        self.insert(first, n);
        self.insert(second, p);
        let delta: f64 = self
            .journal
            .iter()
            .filter(|(_, before)| !before.is_leaf())
            .map(|&(i, before)| self.links[i as usize].bounds.area() as f64 - before.bounds.area() as f64)
            .sum();
        if delta < 0.0 {
            return delta;
        }
        for &(i, before) in &self.journal {
            self.links[i as usize] = before;
        }
        self.root = root;
        0.0
    }

    fn area(&self, i: u32) -> f32 {
        self.links[i as usize].bounds.area()
    }

    /// Makes `new` the child of `parent` that `old` was.
    fn replace_kid(&mut self, parent: u32, old: u32, new: u32) {
        let kids = &mut self.links[parent as usize].kids;
        let slot = usize::from(kids[1] == old);
        kids[slot] = new;
    }

    /// Puts subtree `l` beside the node where it adds the least area, under the free link `free`.
    fn insert(&mut self, l: u32, free: u32) {
        let x = self.best_sibling(l);
        let q = self.links[x as usize].parent;
        for i in [free, x, l] {
            self.record(i);
        }
        self.links[free as usize] = Link {
            bounds: self.links[x as usize].bounds.union(self.links[l as usize].bounds),
            parent: q,
            kids: [x, l],
            count: 0,
        };
        self.links[x as usize].parent = free;
        self.links[l as usize].parent = free;
        if q == NONE {
            self.root = free;
        } else {
            self.record(q);
            self.replace_kid(q, x, free);
            self.refit(q);
        }
    }

    /// Boxes from `i` up to the root made the union of their children's again, stopping where one
    /// is unchanged (its ancestors are then too).
    fn refit(&mut self, mut i: u32) {
        while i != NONE {
            let [a, b] = self.links[i as usize].kids;
            let bounds = self.links[a as usize].bounds.union(self.links[b as usize].bounds);
            if bounds == self.links[i as usize].bounds {
                return;
            }
            self.record(i);
            self.links[i as usize].bounds = bounds;
            i = self.links[i as usize].parent;
        }
    }

    /// The node beside which subtree `l` adds the least area: the new parent's area plus the growth of
    /// every ancestor's, searched best first and cut where even `l`'s own area cannot beat the best
    /// found (Bittner et al. 2013, algorithm 2).
    fn best_sibling(&mut self, l: u32) -> u32 {
        let bounds = self.links[l as usize].bounds;
        let own = bounds.area();
        let (mut best, mut best_cost) = (self.root, f32::INFINITY);
        self.heap.clear();
        self.heap.push(Candidate {
            induced: 0.0,
            node: self.root,
        });
        while let Some(Candidate { induced, node }) = self.heap.pop() {
            if induced + own >= best_cost {
                break;
            }
            let x = &self.links[node as usize];
            let joined = x.bounds.union(bounds).area();
            if induced + joined < best_cost {
                best_cost = induced + joined;
                best = node;
            }
            let below = induced + joined - x.bounds.area();
            if !x.is_leaf() && below + own < best_cost {
                for kid in x.kids {
                    self.heap.push(Candidate {
                        induced: below,
                        node: kid,
                    });
                }
            }
        }
        best
    }

    /// The tree in the BVH2's layout, ids in leaf order; `None` where it is deeper than
    /// [`MAX_TREE_DEPTH`].
    fn emit(&self, ids: &[u32]) -> Option<(Vec<Node>, Vec<u32>)> {
        let placeholder = Node {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        };
        let mut nodes = Vec::with_capacity(self.links.len());
        nodes.push(placeholder);
        let mut out_ids = Vec::with_capacity(ids.len());
        // (link, its slot in `nodes`, its depth)
        let mut todo = vec![(self.root, 0usize, 1usize)];
        while let Some((i, at, depth)) = todo.pop() {
            if depth > MAX_TREE_DEPTH {
                return None;
            }
            let link = &self.links[i as usize];
            if link.is_leaf() {
                let first = link.kids[0] as usize;
                nodes[at] = Node {
                    bounds: link.bounds,
                    first: out_ids.len() as u32,
                    count: link.count,
                };
                out_ids.extend_from_slice(&ids[first..first + link.count as usize]);
            } else {
                let first = nodes.len();
                nodes[at] = Node {
                    bounds: link.bounds,
                    first: first as u32,
                    count: 0,
                };
                nodes.extend([placeholder; 2]);
                todo.push((link.kids[1], first + 1, depth + 1));
                todo.push((link.kids[0], first, depth + 1));
            }
        }
        Some((nodes, out_ids))
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::super::Bvh2;
    use crate::accel::Prims;
    use crate::accel::bvh2::Builder;
    use crate::geometry::aabb::Aabb;
    use crate::scene::{Camera, Material, Scene};

    /// 400 small triangles near the points of a 20 x 20 grid in the plane z = 0, spheres on every
    /// seventh, and one triangle in that plane over all of them whose box's centre (where the builders bin it)
    /// lies at the grid's middle.
    fn scene() -> Scene {
        let mut scene = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = scene.add_material(Material::default());
        for k in 0..400 {
            // A grid, each cell's triangle moved by a hash of its number so that no split is exact.
            let h = (k as u32).wrapping_mul(2_654_435_761);
            let jitter = Vec3::new((h >> 24) as f32, ((h >> 16) & 255) as f32, 0.0) / 512.0;
            let o = Vec3::new((k % 20) as f32, (k / 20) as f32, 0.0) + jitter;
            if k % 7 == 0 {
                scene.add_sphere(o + Vec3::splat(0.3), 0.3, m);
            } else {
                scene.add_triangle(o, o + Vec3::X * 0.8, o + Vec3::Y * 0.8, m);
            }
        }
        scene.add_triangle(
            Vec3::new(-20.0, -20.0, 0.0),
            Vec3::new(40.0, -20.0, 0.0),
            Vec3::new(-20.0, 40.0, 0.0),
            m,
        );
        scene
    }

    /// The depth of the leaf that holds `id` (the root at 1).
    fn depth_of(bvh: &Bvh2, id: u32) -> usize {
        let mut todo = vec![(0usize, 1usize)];
        while let Some((i, depth)) = todo.pop() {
            let n = &bvh.nodes[i];
            if n.is_leaf() {
                if bvh.ids[n.first as usize..(n.first + n.count) as usize].contains(&id) {
                    return depth;
                }
            } else {
                todo.extend([(n.first as usize, depth + 1), (n.first as usize + 1, depth + 1)]);
            }
        }
        panic!("{id} is in no leaf");
    }

    /// Each leaf as its box's bits and its sorted ids, all leaves sorted.
    fn leaves(bvh: &Bvh2) -> Vec<([u32; 6], Vec<u32>)> {
        let mut out: Vec<_> = (bvh.nodes.iter().filter(|n| n.is_leaf()))
            .map(|n| {
                let b = n.bounds;
                let mut ids = bvh.ids[n.first as usize..(n.first + n.count) as usize].to_vec();
                ids.sort_unstable();
                (
                    [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z].map(f32::to_bits),
                    ids,
                )
            })
            .collect();
        out.sort();
        out
    }

    fn interior_area(bvh: &Bvh2) -> f64 {
        bvh.nodes
            .iter()
            .filter(|n| !n.is_leaf())
            .map(|n| n.bounds.area() as f64)
            .sum()
    }

    /// The moves keep every leaf as built, and every interior box is its children's union again.
    #[test]
    fn reinsertion_keeps_the_leaves_and_refits_every_box() {
        let scene = scene();
        let prims = Prims::new(&scene);
        for block in [1, 4] {
            let built = Bvh2::with_block(prims, Builder::Sah { bins: 12 }, block);
            let optimized = built.clone().reinserted();
            assert_eq!(leaves(&optimized), leaves(&built), "block {block}");
            assert_eq!(optimized.nodes.len(), built.nodes.len());
            let mut ids = optimized.ids.clone();
            ids.sort_unstable();
            assert_eq!(ids, (0..prims.bounded()).collect::<Vec<_>>());
            for n in optimized.nodes.iter().filter(|n| !n.is_leaf()) {
                let (a, b) = (
                    &optimized.nodes[n.first as usize],
                    &optimized.nodes[n.first as usize + 1],
                );
                assert_eq!(n.bounds, Aabb::union(a.bounds, b.bounds));
            }
            assert!(interior_area(&optimized) < interior_area(&built), "block {block}");
        }
    }

    /// The triangle over everything, binned among the small ones by its box's centre, sits deep in the
    /// built tree; reinsertion puts it where it costs least, beside all the rest under the root.
    #[test]
    fn a_triangle_over_everything_moves_under_the_root() {
        let scene = scene();
        let prims = Prims::new(&scene);
        let large = prims.triangle_id(scene.triangles.len() - 1);
        let built = Bvh2::new(prims, Builder::Sah { bins: 12 });
        assert!(depth_of(&built, large) > 3, "the builder puts it deep");
        let optimized = built.reinserted();
        assert_eq!(depth_of(&optimized, large), 2);
    }
}
