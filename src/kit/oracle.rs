//! The brute-force comparison: every accelerator must answer every test ray as brute force does, with
//! single rays and with packets, for the closest hit and for any hit. Brute force is the oracle because
//! it is too simple to be wrong in an interesting way: every primitive's own test, the closest kept.
//!
//! On meshes of 10^5 triangles and more brute force costs milliseconds a ray, so there it answers an
//! evenly spaced sample, the grid must agree with it bit for bit on that sample, and the grid (proven
//! identical to brute force on every ray of the smaller scenes) answers all of the rays for the others
//! ([`against_grid`]).

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::contestants::Contestant;
use super::rays::Case;
use crate::accel::packet::{self, bits};
use crate::accel::wide::STREAM_MIN;
use crate::accel::{Accel, AccelKind, Hit, PACKET, PrimKind, Prims};
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
    /// a ray is counted ([`Tally::excused`]) rather than failed. Anything else must agree as for
    /// `Close`.
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
    fn close(got: &Hit, want: &Hit) -> bool {
        got.is_hit() == want.is_hit() && (!want.is_hit() || (got.t - want.t).abs() <= 1e-5 * want.t.max(1.0))
    }

    /// Asserts that `got` agrees with `want`; `ctx` describes the ray for the message.
    fn assert(self, got: &Hit, want: &Hit, ctx: impl Fn() -> String) {
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
    /// ([`may_round_apart`]), else asserts agreement as [`check_single`] does.
    fn spares_closest(
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
    fn any_hit_limits(self, case: &Case, want: &Hit) -> ([(f32, bool); 2], usize) {
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

/// A hit record's bits, for "left exactly as it was" (`==` on floats would let -0 pass for 0).
fn record(h: &Hit) -> (u32, u32, u32, u32) {
    (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits())
}

/// What a comparison covered, for tests to assert that their rays were worth checking.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Rays compared.
    pub rays: usize,
    /// Of those, the rays that hit something.
    pub hits: usize,
    /// Disagreements [`Agreement::Edges`] excused (rays where two triangle tests may round apart,
    /// [`may_round_apart`]), counted once per ray and kernel: single rays, then packet lanes.
    pub excused: usize,
}

impl Tally {
    fn of(answers: &[Hit]) -> Tally {
        Tally {
            rays: answers.len(),
            hits: answers.iter().filter(|h| h.is_hit()).count(),
            excused: 0,
        }
    }
}

/// `reference`'s closest hit for each case (a miss is `Hit::miss(t_max)`), traced on the rayon pool.
pub fn answers(reference: &Accel, cases: &[Case]) -> Vec<Hit> {
    cases
        .par_iter()
        .map(|c| {
            let mut hit = Hit::miss(c.t_max);
            reference.intersect(&c.ray, c.t_min, &mut hit);
            hit
        })
        .collect()
}

/// Checks `accel` against the reference answers `want` on `cases`, with single rays
/// ([`check_single`]), with packets ([`check_packets`]) and with streams ([`check_streams`]). Panics at the first disagreement, with
/// `label`, the ray and both answers in the message.
pub fn check(label: &str, accel: &Accel, agreement: Agreement, cases: &[Case], want: &[Hit]) -> Tally {
    let excused = check_single(label, accel, agreement, cases, want)
        + check_packets(label, accel, agreement, cases, want)
        + check_streams(label, accel, agreement, cases, want);
    Tally {
        excused,
        ..Tally::of(want)
    }
}

/// Single rays: `intersect` finds the closest hit as `want` has it (per `agreement`); `occluded` says
/// yes just beyond it and no just before it, and no on the whole interval of a miss. Returns the rays
/// [`Agreement::Edges`] excused.
pub fn check_single(label: &str, accel: &Accel, agreement: Agreement, cases: &[Case], want: &[Hit]) -> usize {
    assert_eq!(cases.len(), want.len(), "{label}: one answer per case");
    let prims = accel.prims();
    let excused = AtomicUsize::new(0);
    cases.par_iter().zip(want).enumerate().for_each(|(i, (c, want))| {
        let mut got = Hit::miss(c.t_max);
        let found = accel.intersect(&c.ray, c.t_min, &mut got);
        let ctx = || {
            format!(
                "{label}, ray {i} {:?} in ({}, {}): got {got:?}, reference {want:?}",
                c.ray, c.t_min, c.t_max
            )
        };
        let (limits, n) = agreement.any_hit_limits(c, want);
        if agreement == Agreement::Edges {
            let agrees = found == got.is_hit()
                && Agreement::close(&got, want)
                && limits[..n]
                    .iter()
                    .all(|&(limit, yes)| accel.occluded(&c.ray, c.t_min, limit) == yes);
            if !agrees && may_round_apart(&prims, &c.ray, (c.t_min, c.t_max), &got, want) {
                excused.fetch_add(1, Ordering::Relaxed);
                return;
            }
        }
        assert_eq!(found, want.is_hit(), "hit or miss differs: {}", ctx());
        agreement.assert(&got, want, ctx);
        for &(limit, yes) in &limits[..n] {
            assert_eq!(
                accel.occluded(&c.ray, c.t_min, limit),
                yes,
                "any hit before {limit}: {}",
                ctx()
            );
        }
    });
    excused.into_inner()
}

/// Packets: the same cases eight at a time, through `intersect_packet` and `occluded_packet`, with the
/// same expectations as [`check_single`], and every lane left out of the mask untouched. The cases are
/// grouped by `t_min` (a packet has one) and sorted by direction octant, so that most packets share
/// their direction signs (the kernels' coherent path) and the rest mix them; the second lane of every
/// packet of more than two rays is left out. Returns the lanes [`Agreement::Edges`] excused.
pub fn check_packets(
    label: &str,
    accel: &Accel,
    agreement: Agreement,
    cases: &[Case],
    want: &[Hit],
) -> usize {
    assert_eq!(cases.len(), want.len(), "{label}: one answer per case");
    let prims = accel.prims();
    let excused = AtomicUsize::new(0);
    let octant = |c: &Case| c.ray.dir.cmplt(Vec3::ZERO).bitmask();
    let mut order: Vec<usize> = (0..cases.len()).collect();
    order.sort_by_key(|&i| (cases[i].t_min.to_bits(), octant(&cases[i]), i));
    let groups: Vec<&[usize]> = order
        .chunk_by(|&a, &b| cases[a].t_min == cases[b].t_min)
        .flat_map(|g| g.chunks(PACKET))
        .collect();
    // What an inactive lane holds before and must hold after.
    let sentinel = Hit {
        t: -7.0,
        prim: 12345,
        u: 0.5,
        v: 0.25,
    };
    groups.par_iter().for_each(|ids| {
        let t_min = cases[ids[0]].t_min;
        let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); PACKET];
        let mut t_max = [0.0; PACKET];
        for (k, &i) in ids.iter().enumerate() {
            (rays[k], t_max[k]) = (cases[i].ray, cases[i].t_max);
        }
        let all = packet::first(ids.len());
        let active = all & if ids.len() > 2 { !2 } else { 0xff };
        let mut hits: [Hit; PACKET] = std::array::from_fn(|k| match active >> k & 1 {
            1 => Hit::miss(t_max[k]),
            _ => sentinel,
        });
        let found = accel.intersect_packet(&rays, active, t_min, &mut hits);
        // Lanes whose closest hit (or any hit below) disagrees where Edges excuses it: left out of the
        // checks.
        let mut spared = 0u8;
        for (k, &i) in ids.iter().enumerate() {
            let (got, want) = (&hits[k], &want[i]);
            let ctx = || {
                format!(
                    "{label}, packet lane {k}, ray {i} {:?} in ({t_min}, {}): got {got:?}, \
                     reference {want:?}",
                    rays[k], t_max[k]
                )
            };
            if active >> k & 1 == 0 {
                assert!(
                    record(got) == record(&sentinel) && found >> k & 1 == 0,
                    "inactive lane touched: {}",
                    ctx()
                );
                continue;
            }
            if agreement.spares_closest(
                &prims,
                (&rays[k], t_min, t_max[k]),
                got,
                found >> k & 1 == 1,
                want,
                ctx,
            ) {
                spared |= 1 << k;
            }
        }
        // Any hit: each lane's questions in turn, a lane with fewer left out of the later passes.
        let questions: Vec<([(f32, bool); 2], usize)> = ids
            .iter()
            .map(|&i| agreement.any_hit_limits(&cases[i], &want[i]))
            .collect();
        for pass in 0..2 {
            let mut limits = [0.0; PACKET];
            let mut asked = 0u8;
            for k in bits(active) {
                let (q, n) = questions[k];
                if pass < n {
                    limits[k] = q[pass].0;
                    asked |= 1 << k;
                }
            }
            let blocked = accel.occluded_packet(&rays, asked, t_min, &limits);
            let expected = bits(asked).fold(0u8, |m, k| m | (questions[k].0[pass].1 as u8) << k);
            let (blocked, expected) = match agreement {
                Agreement::Edges => {
                    let odd = bits((blocked ^ expected) & !spared)
                        .filter(|&k| may_round_below(accel, (&rays[k], t_min, limits[k]), &want[ids[k]]));
                    let odd = odd.fold(0u8, |m, k| m | 1 << k);
                    spared |= odd;
                    (blocked & !spared, expected & !spared)
                }
                _ => (blocked, expected),
            };
            assert_eq!(
                blocked,
                expected,
                "{label}, packet any hit, pass {pass}: rays {:?}, limits {limits:?}, blocked {blocked:08b}, \
                 expected {expected:08b}",
                ids.iter().map(|&i| cases[i].ray).collect::<Vec<_>>()
            );
        }
        excused.fetch_add(spared.count_ones() as usize, Ordering::Relaxed);
    });
    excused.into_inner()
}

/// Streams: the same cases through `intersect_stream` and `occluded_stream`, with the same expectations
/// as [`check_single`]. The cases are grouped by `t_min` (a stream has one) and, in their own order
/// (the kit's kinds of ray in turn, so directions of every octant side by side), cut into streams of
/// 1, 3, [`STREAM_MIN`] − 1, [`STREAM_MIN`] and 1,000 rays in turn: ray by ray from the root, split at
/// the root only, and split at many nodes. Returns the rays [`Agreement::Edges`] excused.
pub fn check_streams(
    label: &str,
    accel: &Accel,
    agreement: Agreement,
    cases: &[Case],
    want: &[Hit],
) -> usize {
    assert_eq!(cases.len(), want.len(), "{label}: one answer per case");
    let prims = accel.prims();
    let mut order: Vec<usize> = (0..cases.len()).collect();
    order.sort_by_key(|&i| (cases[i].t_min.to_bits(), i));
    let mut streams: Vec<&[usize]> = Vec::new();
    for group in order.chunk_by(|&a, &b| cases[a].t_min == cases[b].t_min) {
        let mut rest = group;
        for &len in [1, 3, STREAM_MIN - 1, STREAM_MIN, 1000].iter().cycle() {
            if rest.is_empty() {
                break;
            }
            let (stream, tail) = rest.split_at(len.min(rest.len()));
            streams.push(stream);
            rest = tail;
        }
    }
    let excused = AtomicUsize::new(0);
    streams.par_iter().for_each(|ids| {
        let t_min = cases[ids[0]].t_min;
        let rays: Vec<Ray> = ids.iter().map(|&i| cases[i].ray).collect();
        let mut hits: Vec<Hit> = ids.iter().map(|&i| Hit::miss(cases[i].t_max)).collect();
        accel.intersect_stream(&rays, t_min, &mut hits);
        let mut spared = vec![false; ids.len()];
        for (j, &i) in ids.iter().enumerate() {
            let (got, want, t_max) = (&hits[j], &want[i], cases[i].t_max);
            let ctx = || {
                format!(
                    "{label}, stream of {}, ray {i} {:?} in ({t_min}, {t_max}): got {got:?}, reference {want:?}",
                    ids.len(),
                    rays[j]
                )
            };
            spared[j] = agreement.spares_closest(&prims, (&rays[j], t_min, t_max), got, got.is_hit(), want, ctx);
        }
        // Any hit: each ray's questions in turn, a ray with fewer left out of the later pass.
        let questions: Vec<([(f32, bool); 2], usize)> = ids
            .iter()
            .map(|&i| agreement.any_hit_limits(&cases[i], &want[i]))
            .collect();
        for pass in 0..2 {
            let asked: Vec<usize> = (0..ids.len()).filter(|&j| pass < questions[j].1).collect();
            let limits: Vec<f32> = asked.iter().map(|&j| questions[j].0[pass].0).collect();
            let asked_rays: Vec<Ray> = asked.iter().map(|&j| rays[j]).collect();
            let mut blocked = vec![false; asked.len()];
            accel.occluded_stream(&asked_rays, t_min, &limits, &mut blocked);
            for (a, &j) in asked.iter().enumerate() {
                let expected = questions[j].0[pass].1;
                if blocked[a] == expected || spared[j] {
                    continue;
                }
                if agreement == Agreement::Edges && may_round_below(accel, (&rays[j], t_min, limits[a]), &want[ids[j]]) {
                    spared[j] = true;
                    continue;
                }
                panic!(
                    "{label}, stream of {} any hit, pass {pass}: ray {} {:?} in ({t_min}, {}): blocked {}, \
                     expected {expected}",
                    ids.len(),
                    ids[j],
                    rays[j],
                    limits[a],
                    blocked[a]
                );
            }
        }
        excused.fetch_add(spared.iter().filter(|&&s| s).count(), Ordering::Relaxed);
    });
    excused.into_inner()
}

/// Whether [`Agreement::Edges`] excuses a wrong any-hit answer of `ray` in `(t_min, limit)`: the
/// structure's own closest hit there and the reference's `want` may round apart ([`may_round_apart`]).
fn may_round_below(accel: &Accel, (ray, t_min, limit): (&Ray, f32, f32), want: &Hit) -> bool {
    let mut got = Hit::miss(limit);
    accel.intersect(ray, t_min, &mut got);
    may_round_apart(&accel.prims(), ray, (t_min, limit), &got, want)
}

/// Every contestant against brute force on every case: for scenes where brute force is cheap (up to a
/// few thousand primitives, or a few thousand rays).
pub fn against_brute_force(label: &str, prims: Prims, contestants: &[Contestant], cases: &[Case]) -> Tally {
    let want = answers(&Accel::build(prims, AccelKind::None), cases);
    let mut excused = 0;
    for c in contestants {
        excused += check(
            &format!("{label}, {}", c.name),
            &c.accel,
            c.agreement(),
            cases,
            &want,
        )
        .excused;
    }
    Tally {
        excused,
        ..Tally::of(&want)
    }
}

/// For meshes where brute force on every case would take minutes: brute force answers about `sample`
/// of the cases, evenly spaced, where every contestant is checked against it (the grid bit for bit); then
/// the grid's answers on all of the cases are the reference for every other contestant. Panics if
/// `contestants` has no grid.
pub fn against_grid(
    label: &str,
    prims: Prims,
    contestants: &[Contestant],
    cases: &[Case],
    sample: usize,
) -> Tally {
    let grid = contestants
        .iter()
        .find(|c| c.is_grid())
        .expect("the grid is the reference");
    // An odd stride: the kit's rays come in four kinds in turn, and an even one would skip two.
    let step = (cases.len() / sample.max(1)).max(1) | 1;
    let sampled: Vec<Case> = cases.iter().step_by(step).copied().collect();
    let on_sample = against_brute_force(
        &format!("{label}, brute-force sample of {}", sampled.len()),
        prims,
        contestants,
        &sampled,
    );
    let want = answers(&grid.accel, cases);
    let mut excused = on_sample.excused;
    for c in contestants.iter().filter(|c| !c.is_grid()) {
        excused += check(
            &format!("{label}, {} against the grid", c.name),
            &c.accel,
            c.agreement(),
            cases,
            &want,
        )
        .excused;
    }
    Tally {
        excused,
        ..Tally::of(&want)
    }
}
