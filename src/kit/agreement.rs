//! How closely a structure's answers must match the oracle's ([`Agreement`]), and when two triangle
//! tests may honestly round apart (a hit near a triangle's edge, at the ray's origin, or with an
//! ill-conditioned `t`).

use glam::Vec3;

use super::rays::Case;
use crate::accel::{Hit, PrimKind, Prims};
use crate::geometry::ray::Ray;

/// How closely a structure's closest hits must match the reference's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Agreement {
    /// The whole hit record: `t`, primitive and barycentrics.
    Exact,
    /// The same hit or miss, and `t` within 1e-5 of the reference's (relative above 1, absolute below):
    /// where primitives meet at the hit point (a mesh's shared edges, duplicates) a hierarchy may find
    /// another of them first, whose `t` rounds differently.
    Close,
    /// As [`Agreement::Close`], except on rays where two triangle tests may round apart
    /// ([`may_round_apart`]: a hit within [`EDGE`] of a triangle's edge, or at the ray's origin, or
    /// hits whose `t`s are ill-conditioned): there a structure with its own triangle test (Embree's)
    /// may round the other way, onto the neighbour, through a crack of ours or to another `t`, and such
    /// a ray is counted ([`Tally::excused`](super::oracle::Tally::excused)) rather than failed.
    /// Anything else must agree as for `Close`.
    Edges,
}

/// How close to a triangle's edge a ray must cross for [`Agreement::Edges`] to excuse a disagreement
/// there: the distance of the crossing from the edge in the triangle's plane, relative to the largest
/// coordinate of the ray's origin and the triangle's corners (the scale of f32 rounding in the
/// triangle test), as [`edge_distance`] measures it: 1e-6, about 16 units of f32 precision.
pub const EDGE: f64 = 1e-6;

/// Barycentric distance (in f64) of the point where `ray` crosses the plane of triangle `[a, b, c]` from
/// the triangle's nearest edge: min(u, v, 1 − u − v), negative outside. Skinny triangles magnify
/// rounding in these units; [`edge_distance`] measures in the rounding's own.
pub fn edge_margin(ray: &Ray, [a, b, c]: [Vec3; 3]) -> f64 {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let (a, e1, e2) = (a.as_dvec3(), (b - a).as_dvec3(), (c - a).as_dvec3());
    let p = d.cross(e2);
    let det = e1.dot(p);
    let s = o - a;
    let u = s.dot(p) / det;
    let v = d.dot(s.cross(e1)) / det;
    u.min(v).min(1.0 - u - v)
}

/// Distance (in f64) of the point where `ray` crosses the plane of triangle `[a, b, c]` from the
/// triangle's nearest edge line, in the plane, positive inside and negative outside, times the cosine
/// of the ray's angle with the plane's normal (a grazing ray's crossing moves far along the plane for a
/// small rounding of the test), relative to the largest coordinate (in magnitude) of the ray's origin
/// and the three corners: about how many units of f32 precision, times 2^-24, the test's rounding must
/// reach to move the crossing over the edge. NaN for a degenerate triangle or a ray parallel to its
/// plane.
pub fn edge_distance(ray: &Ray, [a, b, c]: [Vec3; 3]) -> f64 {
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    let n = (b - a).cross(c - a);
    let p = o + d * (n.dot(a - o) / n.dot(d));
    // n × edge points into the triangle for edges taken in the corners' order.
    let inside = |p0: glam::DVec3, p1: glam::DVec3| (p - p0).dot(n.cross(p1 - p0).normalize());
    let distance = inside(a, b).min(inside(b, c)).min(inside(c, a));
    let cos = n.normalize().dot(d.normalize()).abs();
    let scale = [o, a, b, c]
        .iter()
        .map(|v| v.abs().max_element())
        .fold(f64::MIN_POSITIVE, f64::max);
    distance * cos / scale
}

/// The [`edge_distance`] of `hit` along `ray` when it is a triangle's (its corners as our test sees
/// them); `None` for a miss or another kind of primitive.
pub fn hit_edge_distance(prims: &Prims, ray: &Ray, hit: &Hit) -> Option<f64> {
    hit_triangle(prims, hit).map(|corners| edge_distance(ray, corners))
}

/// The corners of the triangle `hit` is on, as our test sees them (`v0, v0 + e1, v0 + e2`).
pub fn hit_triangle(prims: &Prims, hit: &Hit) -> Option<[Vec3; 3]> {
    if !hit.is_hit() {
        return None;
    }
    let PrimKind::Triangle(i) = prims.kind(hit.prim) else {
        return None;
    };
    let t = &prims.scene.triangles;
    let (v0, e1, e2) = (t.v0.get(i), t.e1.get(i), t.e2.get(i));
    Some([v0, v0 + e1, v0 + e2])
}

/// True when `hit` lies within [`EDGE`] of the ray's origin, relative to the origin's largest
/// coordinate: a ray that leaves a surface (`t_min` 0) may find that surface again at a `t` of
/// rounding, by one triangle test and not by another.
pub fn at_origin(ray: &Ray, hit: &Hit) -> bool {
    let scale = ray.origin.abs().max_element().max(f32::MIN_POSITIVE) as f64;
    hit.is_hit() && f64::from(hit.t) * f64::from(ray.dir.abs().max_element()) < EDGE * scale
}

/// A bound on the rounding error of a triangle hit's `t` (zero for another kind of primitive, or a
/// miss): `t = n · (v0 − o) / (n · d)` loses about `ε (|e1| |e2| (|v0 − o| + t |d|)) / |n · d|` (a few
/// roundings of each product, with `n = e1 × e2` rounded too), taken 16 times over. It is large where
/// the ray runs nearly in the triangle's plane, or starts nearly in it far from `v0` (a ray leaving a
/// surface toward a nearly coplanar neighbour): there two triangle tests may find `t`s far apart, or
/// one a hit just inside the interval and the other none.
pub fn t_rounding(prims: &Prims, ray: &Ray, hit: &Hit) -> f64 {
    let Some([a, b, c]) = hit_triangle(prims, hit) else {
        return 0.0;
    };
    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
    let (a, e1, e2) = (a.as_dvec3(), (b - a).as_dvec3(), (c - a).as_dvec3());
    let n = e1.cross(e2);
    let size = e1.length() * e2.length();
    let t = f64::from(hit.t);
    16.0 * f64::from(f32::EPSILON) * size * ((a - o).length() + t * d.length()) / n.dot(d).abs()
}

/// True where two triangle tests may round apart on `ray` searched over `(t_min, t_max)`, `got` one's
/// closest hit and `want` the other's: a hit of either is a triangle's within [`EDGE`] of an edge
/// ([`edge_distance`]) or lies at the ray's origin ([`at_origin`]); or both hit and their `t`s differ
/// by no more than their rounding ([`t_rounding`]); or one alone hits, within its rounding of an end
/// of the interval.
pub fn may_round_apart(prims: &Prims, ray: &Ray, (t_min, t_max): (f32, f32), got: &Hit, want: &Hit) -> bool {
    let near =
        |h: &Hit| at_origin(ray, h) || hit_edge_distance(prims, ray, h).is_some_and(|m| m.abs() < EDGE);
    if near(got) || near(want) {
        return true;
    }
    let rounding = |h: &Hit| t_rounding(prims, ray, h);
    match (got.is_hit(), want.is_hit()) {
        (true, true) => f64::from((got.t - want.t).abs()) <= rounding(got) + rounding(want),
        (true, false) | (false, true) => {
            let h = if got.is_hit() { got } else { want };
            let r = rounding(h);
            f64::from(h.t - t_min) <= r || f64::from(t_max - h.t) <= r
        }
        (false, false) => false,
    }
}

impl Agreement {
    /// True when `got` agrees with `want` within [`Agreement::Close`]'s tolerance.
    pub(super) fn close(got: &Hit, want: &Hit) -> bool {
        got.is_hit() == want.is_hit() && (!want.is_hit() || (got.t - want.t).abs() <= 1e-5 * want.t.max(1.0))
    }

    /// Asserts that `got` agrees with `want`; `ctx` describes the ray for the message.
    pub(super) fn assert(self, got: &Hit, want: &Hit, ctx: impl Fn() -> String) {
        match self {
            Agreement::Exact => assert_eq!(got, want, "closest hit differs: {}", ctx()),
            Agreement::Close | Agreement::Edges => {
                if want.is_hit() {
                    assert!(
                        (got.t - want.t).abs() <= 1e-5 * want.t.max(1.0),
                        "t differs: {}",
                        ctx()
                    );
                }
            }
        }
    }

    /// Judges a batch kernel's closest hit `got` (`found`: whether the kernel said it hit) of `ray` in
    /// `(t_min, t_max)` against `want`: true when [`Agreement::Edges`] excuses a disagreement
    /// ([`may_round_apart`]), else asserts agreement as
    /// [`check_single`](super::oracle::check_single) does.
    pub(super) fn spares_closest(
        self,
        prims: &Prims,
        (ray, t_min, t_max): (&Ray, f32, f32),
        got: &Hit,
        found: bool,
        want: &Hit,
        ctx: impl Fn() -> String,
    ) -> bool {
        if self == Agreement::Edges
            && !(found == got.is_hit() && Agreement::close(got, want))
            && may_round_apart(prims, ray, (t_min, t_max), got, want)
        {
            return true;
        }
        assert_eq!(found, want.is_hit(), "hit or miss differs: {}", ctx());
        self.assert(got, want, ctx);
        false
    }

    /// The any-hit questions asked of a ray whose closest hit is `want`, and their answers: just beyond
    /// the closest hit (yes; beyond by 1e-6 for [`Agreement::Close`], whose own hit may lie that far
    /// off) and just before it (no); for a miss, the whole interval (no).
    pub(super) fn any_hit_limits(self, case: &Case, want: &Hit) -> ([(f32, bool); 2], usize) {
        if !want.is_hit() {
            return ([(case.t_max, false); 2], 1);
        }
        let margin = match self {
            Agreement::Exact => 1e-30,
            Agreement::Close => 1e-6,
            // Another triangle test's `t` lies within the closest-hit tolerance of ours, which near the
            // origin (a ray leaving a surface) is all of it: ask only beyond that.
            Agreement::Edges => 1e-5 * want.t.max(1.0),
        };
        let above = (want.t * 1.001 + margin).min(case.t_max);
        let below = match self {
            Agreement::Edges => (want.t * 0.999).min(want.t - margin),
            _ => want.t * 0.999,
        };
        if self == Agreement::Edges && below <= case.t_min {
            return ([(above, true); 2], 1);
        }
        ([(above, true), (below, false)], 2)
    }
}
