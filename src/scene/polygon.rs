//! Triangulation of planar polygons by ear clipping, in near n log n time.
//!
//! NFF polygons are not always convex (the SPD gears have 144-vertex concave faces), so a fan would cover
//! the notches. Every simple polygon of n > 3 vertices has at least two non-overlapping ears (Meisters
//! 1975, "Polygons have ears"): convex corners whose triangle holds no other vertex of the polygon.
//! Clipping ears one by one from the polygon projected to its dominant plane gives the n - 2 triangles of
//! any simple polygon, each keeping the polygon's winding.
//!
//! Done naively (testing every vertex of the ring against each candidate ear, removing clipped vertices
//! from a `Vec`) that is O(n^2) tests for a convex polygon and worse for tangled ones: one
//! self-intersecting 20,000-vertex polygon took 30 s to load (7 billion point-in-triangle tests). So, with
//! the ideas of Mapbox's earcut for large polygons and of Eberly's "Triangulation by Ear Clipping":
//!
//! - the ring is a doubly-linked list of indices (`prev`/`next` arrays): clipping is O(1). A second list
//!   holds the convex corners in ring order, the only candidates for ears, so that the walk steps over
//!   runs of reflex corners (the inside of a spiral) at no cost;
//! - only reflex (and flat) vertices can block an ear: a chain of the boundary of a simple polygon that
//!   enters a convex corner's triangle does so through the diagonal and turns back out, and the corner
//!   where it turns is reflex. So the ear test looks for reflex vertices only, through a 2-d tree over
//!   them (split across the longer side of each node, which adapts to reflex vertices bunched in a corner
//!   or lined up, as in a comb; a uniform grid does neither). The descent skips the nodes whose region lies
//!   outside one of the triangle's edges, so a long thin triangle costs about its area, and stops at the
//!   first vertex inside. A vertex leaves the tree when it is clipped or becomes convex (in a simple
//!   polygon clipping an ear only makes its neighbours more convex), and a subtree none of whose vertices
//!   is left is skipped whole;
//! - the walk goes on from the clipped ear's next corner, whose triangle has just changed.
//!
//! A self-intersecting or degenerate polygon can still defeat this: its ears may be blocked everywhere and
//! each test may look at most of the tree. So the whole triangulation has a budget of work (ear candidates
//! visited, tree nodes visited and point-in-triangle tests) of [`BUDGET_PER_VERTEX`] · n · ⌈log2 n⌉, 10 to
//! 200 times what simple polygons need (the tests measure combs, spirals, gears and random star-shaped
//! polygons of up to 20,000 corners). Past the budget, and after a lap of the candidates without an ear,
//! the routine clips without testing, so that the count stays n - 2 and the surface stays closed, and says
//! so in [`Outcome::exact`] for the loader to warn. A 20,000-vertex tangle then loads in about 0.1 s.

use glam::{DVec2, DVec3, Vec3};

/// The work budget per vertex and per bit of n: a triangulation of n vertices may spend
/// `BUDGET_PER_VERTEX * n * ceil(log2 n)` units of work (see the module comment) on ear tests.
pub const BUDGET_PER_VERTEX: u64 = 128;

/// How a triangulation went.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Outcome {
    /// Every triangle was clipped as a tested ear. False when the polygon has no normal (all its points on
    /// a line), when a full lap of the ring found no ear, or when the work budget ran out: the polygon
    /// intersects itself or is degenerate, and its triangles may overlap or stick out of it.
    pub exact: bool,
    /// The point-in-triangle tests made.
    pub tests: u64,
    /// The work counted against the budget: ear candidates visited, tree nodes visited and tests.
    pub work: u64,
}

/// The work budget of an n-gon's triangulation.
pub fn budget(n: usize) -> u64 {
    let n = n as u64;
    BUDGET_PER_VERTEX * n * u64::from(n.max(2).next_power_of_two().trailing_zeros())
}

/// Appends the triangles of the polygon `points` (indices into `points`) to `out`. Always appends exactly
/// `points.len() - 2` triangles for `points.len() >= 3`, even for degenerate or self-intersecting input
/// (which [`Outcome::exact`] reports).
pub fn triangulate(points: &[Vec3], out: &mut Vec<[u32; 3]>) -> Outcome {
    let n = points.len();
    let exact = Outcome {
        exact: true,
        tests: 0,
        work: 0,
    };
    if n < 3 {
        return exact;
    }
    if n == 3 {
        out.push([0, 1, 2]);
        return exact;
    }
    // Newell's normal: robust for any simple polygon, convex or not.
    let mut normal = DVec3::ZERO;
    for i in 0..n {
        let (a, b) = (points[i].as_dvec3(), points[(i + 1) % n].as_dvec3());
        normal += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let abs = normal.abs();
    if abs.max_element().is_nan() || abs.max_element() <= 0.0 {
        fan(n, out);
        return Outcome {
            exact: false,
            ..exact
        };
    }
    // Drop the dominant axis; mirror so that the projected polygon runs counter-clockwise. Mirroring the
    // coordinates (not the order) keeps each ear in the polygon's own winding.
    let (axis_u, axis_v, sign) = if abs.x >= abs.y && abs.x >= abs.z {
        (1, 2, normal.x.signum())
    } else if abs.y >= abs.z {
        (2, 0, normal.y.signum())
    } else {
        (0, 1, normal.z.signum())
    };
    let flat: Vec<DVec2> = points
        .iter()
        .map(|p| DVec2::new(f64::from(p[axis_u]) * sign, f64::from(p[axis_v])))
        .collect();
    ear_clip(&flat, out)
}

fn fan(n: usize, out: &mut Vec<[u32; 3]>) {
    for i in 1..n - 1 {
        out.push([0, i as u32, i as u32 + 1]);
    }
}

fn cross(o: DVec2, a: DVec2, b: DVec2) -> f64 {
    (a - o).perp_dot(b - o)
}

/// `q` is in the closed triangle `a b c` (counter-clockwise).
fn inside(a: DVec2, b: DVec2, c: DVec2, q: DVec2) -> bool {
    cross(a, b, q) >= 0.0 && cross(b, c, q) >= 0.0 && cross(c, a, q) >= 0.0
}

fn ear_clip(p: &[DVec2], out: &mut Vec<[u32; 3]>) -> Outcome {
    let n = p.len();
    let mut ring = Ring::cycle(n);
    let turn = |ring: &Ring, v: u32| {
        cross(
            p[ring.prev[v as usize] as usize],
            p[v as usize],
            p[ring.next[v as usize] as usize],
        )
    };
    let convex: Vec<bool> = (0..n as u32).map(|v| turn(&ring, v) > 0.0).collect();
    let reflex: Vec<u32> = (0..n as u32).filter(|&v| !convex[v as usize]).collect();
    let mut tree = ReflexTree::new(p, &reflex);
    // The candidates for ears: the convex vertices, in ring order, so that the walk skips runs of
    // reflex ones (the inside of a spiral) at no cost.
    let mut ears = Ring::of(&convex);
    let budget = budget(n);
    let mut outcome = Outcome {
        exact: true,
        tests: 0,
        work: 0,
    };
    // `b` is on `ears` whenever that is not empty.
    let mut b = convex.iter().position(|&c| c).unwrap_or(0) as u32;
    let (mut m, mut misses) = (n, 0);
    while m > 3 {
        let (a, c) = (ring.prev[b as usize], ring.next[b as usize]);
        if outcome.work < budget && ears.len > 0 {
            outcome.work += 1;
            if tree.blocks([a, b, c], &mut outcome) {
                if misses < ears.len {
                    misses += 1;
                    b = ears.next[b as usize];
                    continue;
                }
                // A full lap without an ear: a self-intersecting or numerically flat polygon.
                outcome.exact = false;
            }
        } else {
            // Out of budget, or no convex corner left (which no simple polygon lacks): clip blind.
            outcome.exact = false;
        }
        out.push([a, b, c]);
        ring.remove(b);
        m -= 1;
        misses = 0;
        tree.remove(b);
        // The neighbours' corners changed: in a simple polygon they only become more convex.
        let b_on = ears.on[b as usize];
        for (v, before) in [(a, true), (c, false)] {
            let is_convex = turn(&ring, v) > 0.0;
            if is_convex {
                tree.remove(v);
            }
            if is_convex && !ears.on[v as usize] {
                // Next to `b` on `ears`, which keeps its ring order (or alone on it, or after `a`).
                let at = if b_on {
                    b
                } else if ears.len > 0 {
                    a
                } else {
                    v
                };
                ears.insert(v, at, before && b_on);
            } else if !is_convex && ears.on[v as usize] {
                ears.remove(v);
            }
        }
        let after = ears.next[b as usize];
        if b_on {
            ears.remove(b);
        }
        b = if ears.on[c as usize] || ears.len == 0 {
            c
        } else if b_on {
            after
        } else {
            a
        };
    }
    // The last triangle was not tested: a reversed one means that the polygon turned on itself.
    if turn(&ring, b) <= 0.0 {
        outcome.exact = false;
    }
    out.push([ring.prev[b as usize], b, ring.next[b as usize]]);
    outcome
}

/// A cyclic doubly-linked list of vertices, in arrays indexed by vertex.
struct Ring {
    prev: Vec<u32>,
    next: Vec<u32>,
    /// Whether the vertex is on the list.
    on: Vec<bool>,
    len: usize,
}

impl Ring {
    /// The vertices 0..n in order.
    fn cycle(n: usize) -> Self {
        Self::of(&vec![true; n])
    }

    /// The vertices `v` with `on[v]`, in order.
    fn of(on: &[bool]) -> Self {
        let n = on.len();
        let mut ring = Ring {
            prev: vec![0; n],
            next: vec![0; n],
            on: on.to_vec(),
            len: 0,
        };
        let members: Vec<u32> = (0..n as u32).filter(|&v| on[v as usize]).collect();
        ring.len = members.len();
        for (k, &v) in members.iter().enumerate() {
            ring.next[v as usize] = members[(k + 1) % members.len()];
            ring.prev[members[(k + 1) % members.len()] as usize] = v;
        }
        ring
    }

    fn remove(&mut self, v: u32) {
        let (a, c) = (self.prev[v as usize], self.next[v as usize]);
        self.next[a as usize] = c;
        self.prev[c as usize] = a;
        self.on[v as usize] = false;
        self.len -= 1;
    }

    /// Puts `v` just before `at` (if `before`) or just after it; `at` is on the list, or is `v` itself
    /// when the list is empty.
    fn insert(&mut self, v: u32, at: u32, before: bool) {
        let (a, c) = if at == v {
            (v, v)
        } else if before {
            (self.prev[at as usize], at)
        } else {
            (at, self.next[at as usize])
        };
        self.prev[v as usize] = a;
        self.next[v as usize] = c;
        self.next[a as usize] = v;
        self.prev[c as usize] = v;
        self.on[v as usize] = true;
        self.len += 1;
    }
}

/// A 2-d tree (kdbush's implicit layout: each node a range of `items`, split at its middle item, children
/// on either side) over the reflex vertices, from which vertices leave but none enter.
struct ReflexTree<'a> {
    p: &'a [DVec2],
    /// The reflex vertices and their points, in tree order.
    items: Vec<(DVec2, u32)>,
    /// Whether the item is still reflex and in the ring.
    alive: Vec<bool>,
    /// For the node split at an item: how many of its range are alive.
    live: Vec<u32>,
    /// For the node split at an item: the axis of the split (that of its items' larger extent).
    axis: Vec<u8>,
    /// Each vertex's position in `items`, `u32::MAX` if it was not reflex.
    slot: Vec<u32>,
}

/// Nodes of at most this many items are scanned, not split.
const LEAF: usize = 8;

impl<'a> ReflexTree<'a> {
    fn new(p: &'a [DVec2], reflex: &[u32]) -> Self {
        let mut items: Vec<(DVec2, u32)> = reflex.iter().map(|&v| (p[v as usize], v)).collect();
        let (mut live, mut axis) = (vec![0; items.len()], vec![0; items.len()]);
        build(&mut items, &mut live, &mut axis, 0);
        let mut slot = vec![u32::MAX; p.len()];
        for (k, &(_, v)) in items.iter().enumerate() {
            slot[v as usize] = k as u32;
        }
        ReflexTree {
            p,
            alive: vec![true; items.len()],
            items,
            live,
            axis,
            slot,
        }
    }

    /// Takes `v` out of the tree, if it is there.
    fn remove(&mut self, v: u32) {
        let k = self.slot[v as usize] as usize;
        if k == u32::MAX as usize || !self.alive[k] {
            return;
        }
        self.alive[k] = false;
        let (mut lo, mut hi) = (0, self.items.len());
        while hi - lo > LEAF {
            let mid = (lo + hi) / 2;
            self.live[mid] -= 1;
            match k.cmp(&mid) {
                std::cmp::Ordering::Less => hi = mid,
                std::cmp::Ordering::Equal => break,
                std::cmp::Ordering::Greater => lo = mid + 1,
            }
        }
    }

    /// Whether a reflex vertex other than the corners (or a point equal to one) lies in the closed
    /// triangle `corners`, counting the work in `outcome`. The descent keeps each node's box (its region
    /// of the plane, clipped to the triangle's bounds) and skips the nodes whose box lies wholly outside
    /// one of the triangle's edges, so that a long thin triangle costs about its area, not its bounds'.
    fn blocks(&self, corners: [u32; 3], outcome: &mut Outcome) -> bool {
        let [a, b, c] = corners.map(|v| self.p[v as usize]);
        let outside = |min: DVec2, max: DVec2| {
            [(a, b), (b, c), (c, a)].iter().any(|&(u, v)| {
                // The box's corner farthest to the left of u -> v, and whether even it is to the right.
                let d = v - u;
                let x = DVec2::new(
                    if d.y > 0.0 { min.x } else { max.x },
                    if d.x > 0.0 { max.y } else { min.y },
                );
                d.perp_dot(x - u) < 0.0
            })
        };
        let test = |&(q, v): &(DVec2, u32), min: DVec2, max: DVec2, outcome: &mut Outcome| {
            if q.cmplt(min).any() || q.cmpgt(max).any() || corners.contains(&v) || q == a || q == b || q == c
            {
                return false;
            }
            outcome.tests += 1;
            outcome.work += 1;
            inside(a, b, c, q)
        };
        let (min, max) = (a.min(b).min(c), a.max(b).max(c));
        let mut stack = [(0usize, 0usize, min, max); 64];
        stack[0] = (0, self.items.len(), min, max);
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let (lo, hi, lo_box, hi_box) = stack[depth];
            outcome.work += 1;
            if outside(lo_box, hi_box) {
                continue;
            }
            if hi - lo <= LEAF {
                for k in lo..hi {
                    if self.alive[k] && test(&self.items[k], min, max, outcome) {
                        return true;
                    }
                }
                continue;
            }
            let mid = (lo + hi) / 2;
            if self.live[mid] == 0 {
                continue;
            }
            let (q, axis) = (self.items[mid].0, usize::from(self.axis[mid]));
            if self.alive[mid] && test(&self.items[mid], min, max, outcome) {
                return true;
            }
            if lo_box[axis] <= q[axis] {
                let mut split = hi_box;
                split[axis] = q[axis];
                stack[depth] = (lo, mid, lo_box, split);
                depth += 1;
            }
            if hi_box[axis] >= q[axis] {
                let mut split = lo_box;
                split[axis] = q[axis];
                stack[depth] = (mid + 1, hi, split, hi_box);
                depth += 1;
            }
        }
        false
    }
}

/// Arranges `items` (the node at `offset` in the whole) as a 2-d tree, each node split across the longer
/// side of its items' bounds (alternating axes would not split points on a line), and records each node's
/// count of items in `live` and its axis in `axis`.
fn build(items: &mut [(DVec2, u32)], live: &mut [u32], axis: &mut [u8], offset: usize) {
    if items.len() <= LEAF {
        return;
    }
    let (min, max) = items.iter().fold((items[0].0, items[0].0), |(lo, hi), &(q, _)| {
        (lo.min(q), hi.max(q))
    });
    let extent = max - min;
    let split = usize::from(extent.y > extent.x);
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |x, y| x.0[split].total_cmp(&y.0[split]));
    live[offset + mid] = items.len() as u32;
    axis[offset + mid] = split as u8;
    let (left, rest) = items.split_at_mut(mid);
    build(left, live, axis, offset);
    build(&mut rest[1..], live, axis, offset + mid + 1);
}

#[cfg(test)]
mod tests;
