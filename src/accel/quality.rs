//! A hierarchy's quality beyond SAH: its end-point overlap (EPO; T. Aila, T. Karras and S. Laine, "On
//! Quality Metrics of Bounding Volume Hierarchies", HPG 2013) and its leaves by depth. SAH counts a
//! node's area; EPO counts the surface of the triangles *outside* a node's subtree that lies inside its
//! box, which a ray crossing that surface pays for with a visit that cannot find it. Aila et al. found
//! SAH alone a poor predictor of traversal cost and SAH with EPO a good one, so a tree optimizer is
//! judged by both.

use std::sync::atomic::{AtomicU64, Ordering};

use glam::{DVec3, Vec3};
use rand_xoshiro::Xoshiro256PlusPlus;
use rand_xoshiro::rand_core::{Rng, SeedableRng};
use rayon::prelude::*;

use super::bvh2::{Bvh2, INTERSECTION_COST, TRAVERSAL_COST};
use super::prims::{PrimKind, Prims};
use super::wide::{EMPTY, LEAF, WideBvh};
use crate::geometry::aabb::Aabb;

/// The most steps an exact EPO may take (a node reached is one, a triangle clipped to a box 16, about
/// what each costs) before it is estimated from a sample of triangles instead. The largest shipped
/// tree, the 871k-triangle dragon's BVH2, takes 0.44e9 (its BVH8 0.16e9); a soup of 10,000 large
/// random triangles in a unit cube 0.83e9 as a BVH2 and 0.27e9 as a BVH8, and 100,000 of them about a
/// hundred times as many.
pub const EPO_BUDGET: u64 = 600_000_000;

/// A triangle clipped to a box, in steps of [`EPO_BUDGET`].
const CLIP_STEPS: u64 = 16;

/// A sample takes at most this share of the budget: its error falls only as the square root of its
/// size, and a quarter already holds hundreds of the 100,000-triangle soup's triangles (a few percent).
const SAMPLE_SHARE: u64 = 4;

/// The sample's seed: the same tree gives the same estimate every run.
const EPO_SEED: u64 = 0x0045_504f;

/// Triangles drawn to measure the steps one triangle's contribution takes, to choose the sample's
/// size.
const PILOT: usize = 64;

/// A hierarchy as the figures read it, whatever its width: nodes, the root first.
#[derive(Clone, Debug, Default)]
pub struct TreeView {
    /// The nodes; a leaf has no children.
    pub nodes: Vec<ViewNode>,
}

/// A node of a [`TreeView`].
#[derive(Clone, Debug, Default)]
pub struct ViewNode {
    /// Its box.
    pub bounds: Aabb,
    /// Its children (indices into [`TreeView::nodes`]); none for a leaf.
    pub children: Vec<u32>,
    /// A leaf's primitive ids.
    pub prims: Vec<u32>,
}

impl TreeView {
    /// Leaves at each depth: `[k]` the leaves `k` levels below the root (the root is depth 0).
    pub fn leaf_depths(&self) -> Vec<usize> {
        let mut out = Vec::new();
        let mut stack = vec![(0usize, 0usize)];
        while let Some((i, depth)) = stack.pop() {
            let Some(n) = self.nodes.get(i) else { continue };
            if n.children.is_empty() {
                if out.len() <= depth {
                    out.resize(depth + 1, 0);
                }
                out[depth] += 1;
            }
            stack.extend(n.children.iter().map(|&c| (c as usize, depth + 1)));
        }
        out
    }

    /// The EPO cost: Σ over nodes of its cost (a traversal step for an inner node, a test per
    /// primitive for a leaf, as in SAH) × the area of the triangles outside its subtree within its box,
    /// over the area of all triangles (Aila et al. 2013, eq. 4). Other primitives are not counted. 0
    /// without triangles. The view must be a tree: every node but the root the child of one node.
    ///
    /// Exact when that takes at most [`EPO_BUDGET`] steps; otherwise estimated from a sample of
    /// triangles, which [`Epo::sampled`] says.
    pub fn epo(&self, prims: &Prims) -> Epo {
        self.epo_within(prims, EPO_BUDGET)
    }

    /// [`TreeView::epo`] with a budget of `budget` steps (as [`EPO_BUDGET`] counts them).
    fn epo_within(&self, prims: &Prims, budget: u64) -> Epo {
        // Each triangle's leaf and index in the scene, in the order of the nodes.
        let triangles: Vec<(usize, usize)> = self
            .nodes
            .iter()
            .enumerate()
            .flat_map(|(i, n)| n.prims.iter().map(move |&id| (i, id)))
            .filter_map(|(i, id)| match prims.kind(id) {
                PrimKind::Triangle(t) => Some((i, t)),
                _ => None,
            })
            .collect();
        let vertices = |t: usize| prims.scene.triangles.vertices(t);
        let total: f64 = triangles
            .iter()
            .map(|&(_, t)| {
                let [a, b, c] = vertices(t);
                f64::from((b - a).cross(c - a).length()) / 2.0
            })
            .sum();
        let n = triangles.len();
        let exact = |cost| Epo {
            cost,
            sampled: None,
            triangles: n,
        };
        if total <= 0.0 || self.nodes.is_empty() {
            return exact(0.0);
        }
        let subtrees = Subtrees::new(self, prims);
        if self.per_node_fits(&subtrees, budget) {
            let overlap: f64 = (0..self.nodes.len())
                .into_par_iter()
                .map(|i| self.cost(i) * self.foreign_area(i, prims, &subtrees))
                .sum();
            return exact(overlap / total);
        }
        // Too much overlap to measure node by node (a soup of large triangles crossing one another's
        // boxes grows as its size squared). The same sum, regrouped by triangle, over a uniform sample
        // of k triangles without replacement, each with its exact contribution, scaled by n / k: an
        // unbiased estimate. k fits the steps a triangle takes, measured on a pilot sample drawn
        // apart, so that k does not depend on the triangles it scales.
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(EPO_SEED);
        let mut below = |m: usize| (rng.next_u64() % m as u64) as usize;
        let pilot: Vec<usize> = (0..PILOT).map(|_| below(n)).collect();
        let pilot_steps: u64 = pilot
            .par_iter()
            .map(|&s| {
                let (leaf, t) = triangles[s];
                let mut clipped = 0;
                let reached = self.triangle_walk(&vertices(t), leaf, &subtrees, |_, inside| {
                    clipped += u64::from(!inside);
                });
                reached + CLIP_STEPS * clipped
            })
            .sum();
        let per_triangle = pilot_steps.max(1) as f64 / PILOT as f64;
        let k = ((budget / SAMPLE_SHARE) as f64 / per_triangle).clamp(1.0, n as f64) as usize;
        let mut sample: Vec<u32> = (0..n as u32).collect();
        for s in 0..k {
            sample.swap(s, s + below(n - s));
        }
        sample.truncate(k);
        let parts: Vec<f64> = sample
            .par_iter()
            .map(|&s| {
                let (leaf, t) = triangles[s as usize];
                self.triangle_overlap(&vertices(t), leaf, &subtrees)
            })
            .collect();
        // Summed in the sample's order, so that the estimate does not depend on the threads.
        let overlap: f64 = parts.iter().sum();
        Epo {
            cost: overlap / total * n as f64 / k as f64,
            sampled: (k < n).then_some(k),
            triangles: n,
        }
    }

    /// Node `i`'s cost as SAH weighs it: a traversal step for an inner node, a test per primitive for
    /// a leaf.
    fn cost(&self, i: usize) -> f64 {
        let n = &self.nodes[i];
        if n.children.is_empty() {
            f64::from(INTERSECTION_COST) * n.prims.len() as f64
        } else {
            f64::from(TRAVERSAL_COST)
        }
    }

    /// Whether [`TreeView::foreign_area`] over every node takes at most `budget` steps: its walks
    /// counted without clipping, given up once the count passes the budget.
    fn per_node_fits(&self, subtrees: &Subtrees, budget: u64) -> bool {
        let spent = AtomicU64::new(0);
        (0..self.nodes.len())
            .into_par_iter()
            .try_for_each(|i| {
                let mut steps = 0u64;
                self.foreign_walk(i, subtrees, |j, whole| {
                    steps += 1 + if whole {
                        0
                    } else {
                        CLIP_STEPS * self.nodes[j].prims.len() as u64
                    };
                    steps <= budget
                });
                let before = spent.fetch_add(steps, Ordering::Relaxed);
                if before + steps > budget { Err(()) } else { Ok(()) }
            })
            .is_ok()
    }

    /// The area of the triangles outside node `i`'s subtree that lies inside its box, as
    /// [`TreeView::foreign_walk`] finds them.
    fn foreign_area(&self, i: usize, prims: &Prims, subtrees: &Subtrees) -> f64 {
        let bounds = self.nodes[i].bounds;
        let mut sum = 0.0;
        self.foreign_walk(i, subtrees, |j, whole| {
            if whole {
                sum += subtrees.area[j];
                return true;
            }
            for &id in &self.nodes[j].prims {
                if let PrimKind::Triangle(t) = prims.kind(id) {
                    sum += clipped_area(prims.scene.triangles.vertices(t), &bounds);
                }
            }
            true
        });
        sum
    }

    /// Walks the tree from the root into the boxes that overlap node `i`'s, leaving out `i` itself,
    /// calling `visit(j, whole)` for each node reached until it answers false. `whole`: the subtree
    /// is not on the way to `i` and its triangles lie wholly in the box, so it counts whole without
    /// being walked (clipping would leave each of its triangles whole): without that, n copies of one
    /// triangle (every box the same) cost n² clippings. Otherwise its own triangles are to be clipped.
    fn foreign_walk(&self, i: usize, subtrees: &Subtrees, mut visit: impl FnMut(usize, bool) -> bool) {
        let bounds = self.nodes[i].bounds;
        let order = subtrees.order[i];
        let mut stack = vec![0usize];
        while let Some(j) = stack.pop() {
            let m = &self.nodes[j];
            if j == i || !overlap(&m.bounds, &bounds) {
                continue;
            }
            let holds_i = subtrees.order[j] < order && order < subtrees.end[j];
            let whole = !holds_i && within(&subtrees.bounds[j], &bounds);
            if !visit(j, whole) {
                return;
            }
            if !whole {
                stack.extend(m.children.iter().map(|&c| c as usize));
            }
        }
    }

    /// Triangle `v`'s part of the EPO's sum: over the nodes whose box it meets and whose subtree does
    /// not hold it (in leaf `leaf`), each node's cost × the triangle's area within its box.
    fn triangle_overlap(&self, v: &[Vec3; 3], leaf: usize, subtrees: &Subtrees) -> f64 {
        let whole = polygon_area(&v.map(|p| p.as_dvec3()));
        let mut sum = 0.0;
        self.triangle_walk(v, leaf, subtrees, |j, inside| {
            let area = if inside {
                whole
            } else {
                clipped_area(*v, &self.nodes[j].bounds)
            };
            sum += self.cost(j) * area;
        });
        sum
    }

    /// Walks the tree from the root into the boxes that overlap triangle `v`'s bounds, calling
    /// `visit(j, inside)` for each node reached whose subtree does not hold the triangle's leaf
    /// `leaf`, `inside` when the triangle lies wholly in its box. Returns the nodes reached.
    fn triangle_walk(
        &self,
        v: &[Vec3; 3],
        leaf: usize,
        subtrees: &Subtrees,
        mut visit: impl FnMut(usize, bool),
    ) -> u64 {
        let mut bounds = Aabb::EMPTY;
        v.iter().for_each(|&p| bounds.grow(p));
        let order = subtrees.order[leaf];
        let mut reached = 0;
        let mut stack = vec![0usize];
        while let Some(j) = stack.pop() {
            let m = &self.nodes[j];
            if !overlap(&m.bounds, &bounds) {
                continue;
            }
            reached += 1;
            if !(subtrees.order[j] <= order && order < subtrees.end[j]) {
                visit(j, within(&bounds, &m.bounds));
            }
            stack.extend(m.children.iter().map(|&c| c as usize));
        }
        reached
    }
}

/// An EPO cost and how it was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Epo {
    /// The cost.
    pub cost: f64,
    /// `None` when exact; `Some(k)` when estimated from `k` of the triangles, drawn uniformly without
    /// replacement from a fixed seed (the same tree gives the same estimate every run): the sum of
    /// their exact contributions × [`Epo::triangles`] / `k`, an unbiased estimate.
    pub sampled: Option<usize>,
    /// The triangles in the tree, the sample's population.
    pub triangles: usize,
}

/// What [`TreeView::foreign_area`] needs of every node's subtree: where it lies in a depth-first order
/// of the tree (a node's descendants are `order[i] + 1..end[i]`), and the bounds and total area
/// (as [`clipped_area`] measures a triangle it leaves whole) of its triangles.
struct Subtrees {
    order: Vec<u32>,
    end: Vec<u32>,
    bounds: Vec<Aabb>,
    area: Vec<f64>,
}

impl Subtrees {
    fn new(view: &TreeView, prims: &Prims) -> Self {
        let n = view.nodes.len();
        let mut s = Subtrees {
            order: vec![0; n],
            end: vec![0; n],
            bounds: vec![Aabb::EMPTY; n],
            area: vec![0.0; n],
        };
        let mut next = 0u32;
        // Each node is pushed to be entered, then again (`true`) to be finished after its children.
        let mut stack = vec![(0usize, false)];
        while let Some((i, finished)) = stack.pop() {
            let node = &view.nodes[i];
            if !finished {
                s.order[i] = next;
                next += 1;
                stack.push((i, true));
                stack.extend(node.children.iter().map(|&c| (c as usize, false)));
                continue;
            }
            s.end[i] = next;
            for &id in &node.prims {
                if let PrimKind::Triangle(t) = prims.kind(id) {
                    let v = prims.scene.triangles.vertices(t);
                    v.iter().for_each(|&p| s.bounds[i].grow(p));
                    s.area[i] += polygon_area(&v.map(|p| p.as_dvec3()));
                }
            }
            for &c in &node.children {
                s.bounds[i] = s.bounds[i].union(s.bounds[c as usize]);
                s.area[i] += s.area[c as usize];
            }
        }
        s
    }
}

impl From<&Bvh2<'_>> for TreeView {
    /// The BVH2 as it is: its nodes, its leaves' ids.
    fn from(bvh: &Bvh2<'_>) -> Self {
        let nodes = bvh
            .nodes
            .iter()
            .map(|n| {
                let (first, count) = (n.first as usize, n.count as usize);
                ViewNode {
                    bounds: n.bounds,
                    children: if n.is_leaf() {
                        Vec::new()
                    } else {
                        vec![n.first, n.first + 1]
                    },
                    prims: if n.is_leaf() {
                        bvh.ids[first..first + count].to_vec()
                    } else {
                        Vec::new()
                    },
                }
            })
            .collect();
        TreeView { nodes }
    }
}

impl<const W: usize> From<&WideBvh<'_, W>> for TreeView {
    /// A wide BVH: each child slot a node, with the box its parent holds for it (the root's, the box
    /// around everything); a triangle leaf's ids from its four-triangle blocks.
    fn from(bvh: &WideBvh<'_, W>) -> Self {
        let mut view = TreeView::default();
        if bvh.root() == EMPTY {
            return view;
        }
        let mut stack = vec![(bvh.root(), bvh.bounds(), 0usize)];
        view.nodes.push(ViewNode::default());
        while let Some((r, bounds, at)) = stack.pop() {
            view.nodes[at].bounds = bounds;
            if r & LEAF != 0 {
                view.nodes[at].prims = bvh.leaf_ids(r);
                continue;
            }
            let n = &bvh.nodes()[r as usize];
            for k in (0..W).filter(|&k| n.child[k] != EMPTY) {
                let slot = view.nodes.len();
                view.nodes.push(ViewNode::default());
                view.nodes[at].children.push(slot as u32);
                stack.push((n.child[k], WideBvh::<W>::child_bounds(n, k), slot));
            }
        }
        view
    }
}

/// Whether two boxes share any point.
fn overlap(a: &Aabb, b: &Aabb) -> bool {
    a.min.cmple(b.max).all() && b.min.cmple(a.max).all()
}

/// Whether `inner` lies in `outer`, faces included (the empty box lies in every box).
fn within(inner: &Aabb, outer: &Aabb) -> bool {
    inner.min.cmpge(outer.min).all() && inner.max.cmple(outer.max).all()
}

/// The area of triangle `v` within `bounds` (Sutherland and Hodgman 1974: clipped by each of the box's
/// six planes in turn), in f64.
pub fn clipped_area(v: [Vec3; 3], bounds: &Aabb) -> f64 {
    let mut poly: Vec<DVec3> = v.iter().map(|p| p.as_dvec3()).collect();
    for axis in 0..3 {
        for (limit, keep_below) in [
            (f64::from(bounds.max[axis]), true),
            (f64::from(bounds.min[axis]), false),
        ] {
            let inside = |p: &DVec3| {
                if keep_below {
                    p[axis] <= limit
                } else {
                    p[axis] >= limit
                }
            };
            let mut out = Vec::with_capacity(poly.len() + 1);
            for k in 0..poly.len() {
                let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
                if inside(&a) {
                    out.push(a);
                }
                if inside(&a) != inside(&b) {
                    let s = (limit - a[axis]) / (b[axis] - a[axis]);
                    out.push(a + s * (b - a));
                }
            }
            poly = out;
            if poly.len() < 3 {
                return 0.0;
            }
        }
    }
    polygon_area(&poly)
}

/// The area of a planar convex polygon: half the length of the sum of its fan's cross products.
fn polygon_area(poly: &[DVec3]) -> f64 {
    let p0 = poly[0];
    let mut n = DVec3::ZERO;
    for k in 1..poly.len() - 1 {
        n += (poly[k] - p0).cross(poly[k + 1] - p0);
    }
    n.length() / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Material, Scene};

    fn b(min: [f32; 3], max: [f32; 3]) -> Aabb {
        Aabb::new(Vec3::from(min), Vec3::from(max))
    }

    #[test]
    fn clipping_keeps_the_part_inside_the_box() {
        // The right triangle (0,0) (2,0) (0,2) in z = 0.5, area 2.
        let t = [
            Vec3::new(0.0, 0.0, 0.5),
            Vec3::new(2.0, 0.0, 0.5),
            Vec3::new(0.0, 2.0, 0.5),
        ];
        assert!((clipped_area(t, &b([-1.0; 3], [3.0; 3])) - 2.0).abs() < 1e-12);
        // Within x <= 1: 2 minus the corner triangle beyond x = 1 (legs 1 and 1: 0.5).
        assert!((clipped_area(t, &b([-1.0; 3], [1.0, 3.0, 3.0])) - 1.5).abs() < 1e-12);
        // The unit square [0,1]^2 lies wholly under the hypotenuse x + y = 2: area 1.
        assert!((clipped_area(t, &b([0.0; 3], [1.0; 3])) - 1.0).abs() < 1e-12);
        // A box the triangle's plane does not reach.
        assert_eq!(clipped_area(t, &b([0.0, 0.0, 0.6], [1.0; 3])), 0.0);
    }

    /// Two leaves whose boxes overlap: each box holds part of the other leaf's triangle, in closed form.
    #[test]
    fn epo_counts_the_other_leaves_surface_in_each_box() {
        let mut scene = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = scene.add_material(Material::default());
        // a: (0,0)-(2,0)-(0,2) at z = 0.5 (area 2); b: the same shifted by 1 in x (area 2).
        scene.add_triangle(
            Vec3::new(0.0, 0.0, 0.5),
            Vec3::new(2.0, 0.0, 0.5),
            Vec3::new(0.0, 2.0, 0.5),
            m,
        );
        scene.add_triangle(
            Vec3::new(1.0, 0.0, 0.5),
            Vec3::new(3.0, 0.0, 0.5),
            Vec3::new(1.0, 2.0, 0.5),
            m,
        );
        let prims = Prims::new(&scene);
        let (a, bb) = (prims.triangle_id(0), prims.triangle_id(1));
        let view = TreeView {
            nodes: vec![
                ViewNode {
                    bounds: b([0.0, 0.0, 0.5], [3.0, 2.0, 0.5]),
                    children: vec![1, 2],
                    prims: vec![],
                },
                ViewNode {
                    bounds: b([0.0, 0.0, 0.5], [2.0, 2.0, 0.5]),
                    children: vec![],
                    prims: vec![a],
                },
                ViewNode {
                    bounds: b([1.0, 0.0, 0.5], [3.0, 2.0, 0.5]),
                    children: vec![],
                    prims: vec![bb],
                },
            ],
        };
        // Inside a's box [0,2]x[0,2]: b's part with x <= 2, i.e. b less its corner beyond x = 2 (0.5):
        // 1.5. Inside b's box [1,3]x[0,2]: a's part with x >= 1, the corner triangle of legs 1: 0.5.
        // The root holds everything. Each leaf costs one test of one primitive.
        let want = f64::from(INTERSECTION_COST) * (1.5 + 0.5) / 4.0;
        let got = view.epo(&prims);
        assert!((got.cost - want).abs() < 1e-9, "{got:?}");
        assert_eq!(view.leaf_depths(), [0, 2]);
    }

    /// EPO straight from its definition (Aila et al. 2013, eq. 4), sharing nothing with
    /// [`TreeView::epo`] but the clipping: for every node, every triangle that is not in its subtree
    /// clipped to its box.
    fn brute_force_epo(view: &TreeView, prims: &Prims) -> f64 {
        let t = &prims.scene.triangles;
        let triangle = |id: u32| match prims.kind(id) {
            PrimKind::Triangle(i) => Some(t.vertices(i)),
            _ => None,
        };
        let all: Vec<u32> = view.nodes.iter().flat_map(|n| n.prims.iter().copied()).collect();
        let total: f64 = all
            .iter()
            .filter_map(|&id| triangle(id))
            .map(|[a, b, c]| f64::from((b - a).cross(c - a).length()) / 2.0)
            .sum();
        let mut overlap = 0.0;
        for node in &view.nodes {
            let mut inside = std::collections::HashSet::new();
            let mut stack = vec![node];
            while let Some(n) = stack.pop() {
                inside.extend(n.prims.iter().copied());
                stack.extend(n.children.iter().map(|&c| &view.nodes[c as usize]));
            }
            let foreign: f64 = all
                .iter()
                .filter(|id| !inside.contains(id))
                .filter_map(|&id| triangle(id))
                .map(|v| clipped_area(v, &node.bounds))
                .sum();
            let cost = if node.children.is_empty() {
                f64::from(INTERSECTION_COST) * node.prims.len() as f64
            } else {
                f64::from(TRAVERSAL_COST)
            };
            overlap += cost * foreign;
        }
        overlap / total
    }

    /// Overlapping, nested and identical triangles and spheres, in every structure: the EPO agrees
    /// with its definition.
    #[test]
    fn epo_is_its_definition() {
        let mut scene = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = scene.add_material(Material::default());
        for k in 0..400 {
            let o = Vec3::new((k % 13) as f32 * 0.6, (k / 13) as f32 * 0.4, (k % 7) as f32 * 0.3);
            match k % 5 {
                0 => scene.add_sphere(o, 0.3, m),
                // Large triangles across many others' boxes.
                1 => scene.add_triangle(o, o + Vec3::new(4.0, 0.5, 1.0), o + Vec3::new(0.5, 3.0, -1.0), m),
                // Copies of one triangle, and small ones inside the large ones' boxes.
                2 => scene.add_triangle(Vec3::ZERO, Vec3::new(1.0, 0.2, 0.3), Vec3::new(0.1, 1.0, 0.7), m),
                _ => scene.add_triangle(o, o + Vec3::new(0.5, 0.1, 0.0), o + Vec3::new(0.0, 0.4, 0.2), m),
            }
        }
        let prims = Prims::new(&scene);
        let bvh2 = crate::accel::bvh2::Bvh2::new(prims, crate::accel::bvh2::Builder::Sah { bins: 12 });
        let bvh4 = crate::accel::wide::Bvh4::new(prims, 12).unwrap();
        let bvh8 = crate::accel::wide::Bvh8::new(prims, 12).unwrap();
        for (name, view) in [
            ("bvh2", TreeView::from(&bvh2)),
            ("bvh4", TreeView::from(&bvh4)),
            ("bvh8", TreeView::from(&bvh8)),
        ] {
            let (got, want) = (view.epo(&prims), brute_force_epo(&view, &prims));
            assert!(want > 1.0, "{name}: {want}");
            assert_eq!(got.sampled, None, "{name}");
            assert!(
                (got.cost - want).abs() <= 1e-9 * want,
                "{name}: {got:?} against {want}"
            );
        }
    }

    /// 100,000 copies of one triangle: every box is the triangle's, so each node's box holds the whole
    /// of every triangle outside its subtree, and the EPO is Σ cost × (n − the node's triangles) / n.
    #[test]
    fn identical_triangles() {
        const N: usize = 100_000;
        let mut scene = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = scene.add_material(Material::default());
        for _ in 0..N {
            scene.add_triangle(Vec3::ZERO, Vec3::new(1.0, 0.2, 0.3), Vec3::new(0.1, 1.0, 0.7), m);
        }
        let prims = Prims::new(&scene);
        let bvh = crate::accel::bvh2::Bvh2::new(prims, crate::accel::bvh2::Builder::Sah { bins: 12 });
        let view = TreeView::from(&bvh);
        // Triangles under each node, children after parents in the BVH2's array.
        let mut under: Vec<usize> = view.nodes.iter().map(|n| n.prims.len()).collect();
        for i in (0..view.nodes.len()).rev() {
            for &c in &view.nodes[i].children {
                assert!(c as usize > i);
                under[i] += under[c as usize];
            }
        }
        assert_eq!(under[0], N);
        let want: f64 = view
            .nodes
            .iter()
            .zip(&under)
            .map(|(n, &s)| {
                let cost = if n.children.is_empty() {
                    f64::from(INTERSECTION_COST) * n.prims.len() as f64
                } else {
                    f64::from(TRAVERSAL_COST)
                };
                cost * (N - s) as f64 / N as f64
            })
            .sum();
        let got = view.epo(&prims);
        assert_eq!(got.sampled, None);
        assert!((got.cost - want).abs() <= 1e-6 * want, "{got:?} against {want}");
    }

    /// Large random triangles that cross one another's boxes, over a budget too small to measure them
    /// node by node: the EPO is estimated from a sample, says so, lands near the exact value and is
    /// the same every run; with room, it is exact. The sample rests on the sum regrouped by triangle,
    /// which over every triangle is the exact sum.
    #[test]
    fn a_soup_over_its_budget_is_sampled() {
        const N: usize = 2000;
        let mut scene = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = scene.add_material(Material::default());
        let mut rng = crate::kit::rays::TestRng::new(5);
        for _ in 0..N {
            let [a, b, c] = [(); 3].map(|_| rng.vec3(0.0, 1.0));
            scene.add_triangle(a, b, c, m);
        }
        let prims = Prims::new(&scene);
        let bvh = crate::accel::wide::Bvh8::new(prims, 12).unwrap();
        let view = TreeView::from(&bvh);
        let want = brute_force_epo(&view, &prims);
        let exact = view.epo_within(&prims, u64::MAX);
        assert_eq!(exact.sampled, None);
        assert!(
            (exact.cost - want).abs() <= 1e-9 * want,
            "{exact:?} against {want}"
        );

        let subtrees = Subtrees::new(&view, &prims);
        let (mut parts, mut total) = (Vec::new(), 0.0);
        for (leaf, node) in view.nodes.iter().enumerate() {
            for &id in &node.prims {
                let PrimKind::Triangle(t) = prims.kind(id) else {
                    panic!("{id}")
                };
                let v = scene.triangles.vertices(t);
                parts.push(view.triangle_overlap(&v, leaf, &subtrees));
                total += f64::from((v[1] - v[0]).cross(v[2] - v[0]).length()) / 2.0;
            }
        }
        let by_triangle: f64 = parts.iter().sum();
        assert!(
            (by_triangle / total - want).abs() <= 1e-9 * want,
            "{by_triangle} / {total}"
        );

        // A budget the walks node by node pass; a triangle's contribution takes about 5,000 steps,
        // so a quarter of it is some 250 triangles.
        let budget = 5_000_000;
        let got = view.epo_within(&prims, budget);
        let k = got.sampled.unwrap_or_else(|| panic!("not sampled: {got:?}"));
        assert!((100..N / 2).contains(&k), "{got:?}");
        assert_eq!(got.triangles, N);
        // The standard error of n × the mean of k of n contributions drawn without replacement.
        let mean = by_triangle / N as f64;
        let var = parts.iter().map(|p| (p - mean).powi(2)).sum::<f64>() / (N - 1) as f64;
        let k = k as f64;
        let error = N as f64 * ((1.0 - k / N as f64) * var / k).sqrt() / total;
        assert!(
            (got.cost - want).abs() <= 4.0 * error,
            "{got:?} against {want} ± {error}"
        );
        assert_eq!(view.epo_within(&prims, budget), got);
    }

    /// Triangles far apart in a real tree: no box holds another's surface.
    #[test]
    fn disjoint_triangles_have_no_overlap() {
        let mut scene = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = scene.add_material(Material::default());
        for k in 0..64 {
            let o = Vec3::new((k % 8) as f32 * 3.0, (k / 8) as f32 * 3.0, 0.0);
            scene.add_triangle(o, o + Vec3::X, o + Vec3::Y, m);
        }
        let prims = Prims::new(&scene);
        let bvh = crate::accel::bvh2::Bvh2::new(prims, crate::accel::bvh2::Builder::Sah { bins: 12 });
        let view = TreeView::from(&bvh);
        assert_eq!(view.leaf_depths().iter().sum::<usize>(), bvh.stats().leaves);
        // Axis-aligned splits of a grid of cells keep every node's cells a rectangle of the grid, so no
        // box holds a triangle of another subtree.
        assert_eq!(view.epo(&prims).cost, 0.0);
    }

    /// Every structure's view holds each bounded primitive in exactly one leaf (the wide BVHs' triangle
    /// leaves through their blocks' ids), and its leaves by depth add up to the tree's leaves.
    #[test]
    fn views_hold_every_primitive_once() {
        let mut scene = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = scene.add_material(Material::default());
        for k in 0..300 {
            let o = Vec3::new((k % 17) as f32, (k / 17) as f32 * 0.7, (k % 5) as f32);
            if k % 3 == 0 {
                scene.add_sphere(o, 0.3, m);
            } else {
                scene.add_triangle(o, o + Vec3::X * 0.9, o + Vec3::Y * 0.9, m);
            }
        }
        let prims = Prims::new(&scene);
        let sorted = |view: &TreeView| {
            let mut ids: Vec<u32> = view.nodes.iter().flat_map(|n| n.prims.iter().copied()).collect();
            ids.sort_unstable();
            ids
        };
        let all: Vec<u32> = (0..prims.bounded()).collect();
        let bvh2 = crate::accel::bvh2::Bvh2::new(prims, crate::accel::bvh2::Builder::Sah { bins: 12 });
        let bvh4 = crate::accel::wide::Bvh4::new(prims, 12).unwrap();
        let bvh8 = crate::accel::wide::Bvh8::new(prims, 12).unwrap();
        for (name, view, stats) in [
            ("bvh2", TreeView::from(&bvh2), bvh2.stats()),
            ("bvh4", TreeView::from(&bvh4), bvh4.stats()),
            ("bvh8", TreeView::from(&bvh8), bvh8.stats()),
        ] {
            assert_eq!(sorted(&view), all, "{name}");
            let depths = view.leaf_depths();
            assert_eq!(depths.iter().sum::<usize>(), stats.leaves, "{name}");
            assert_eq!(
                depths.len(),
                stats.depth,
                "{name}: the deepest leaf is the tree's depth"
            );
            // The triangles overlap in places: some surface lies in other subtrees' boxes.
            assert!(view.epo(&prims).cost > 0.0, "{name}");
        }
    }
}
