//! The brute-force comparison: every accelerator must answer every test ray as brute force does, with
//! single rays and with packets, for the closest hit and for any hit. Brute force is the oracle because
//! it is too simple to be wrong in an interesting way: every primitive's own test, the closest kept.
//!
//! On meshes of 10^5 triangles and more brute force costs milliseconds a ray, so there it answers an
//! evenly spaced sample, the grid must agree with it bit for bit on that sample, and the grid (proven
//! identical to brute force on every ray of the smaller scenes) answers all of the rays for the others
//! ([`against_grid`]).

use glam::Vec3;
use rayon::prelude::*;

use super::contestants::Contestant;
use super::rays::Case;
use crate::accel::{Accel, AccelKind, Hit, PACKET, Prims, packet::bits};
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
}

impl Agreement {
    /// Asserts that `got` agrees with `want`; `ctx` describes the ray for the message.
    fn assert(self, got: &Hit, want: &Hit, ctx: impl Fn() -> String) {
        match self {
            Agreement::Exact => assert_eq!(got, want, "closest hit differs: {}", ctx()),
            Agreement::Close => {
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
        };
        let above = (want.t * 1.001 + margin).min(case.t_max);
        ([(above, true), (want.t * 0.999, false)], 2)
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
}

impl Tally {
    fn of(answers: &[Hit]) -> Tally {
        Tally {
            rays: answers.len(),
            hits: answers.iter().filter(|h| h.is_hit()).count(),
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
/// ([`check_single`]) and with packets ([`check_packets`]). Panics at the first disagreement, with
/// `label`, the ray and both answers in the message.
pub fn check(label: &str, accel: &Accel, agreement: Agreement, cases: &[Case], want: &[Hit]) -> Tally {
    check_single(label, accel, agreement, cases, want);
    check_packets(label, accel, agreement, cases, want);
    Tally::of(want)
}

/// Single rays: `intersect` finds the closest hit as `want` has it (per `agreement`); `occluded` says
/// yes just beyond it and no just before it, and no on the whole interval of a miss.
pub fn check_single(label: &str, accel: &Accel, agreement: Agreement, cases: &[Case], want: &[Hit]) {
    assert_eq!(cases.len(), want.len(), "{label}: one answer per case");
    cases.par_iter().zip(want).enumerate().for_each(|(i, (c, want))| {
        let mut got = Hit::miss(c.t_max);
        let found = accel.intersect(&c.ray, c.t_min, &mut got);
        let ctx = || {
            format!(
                "{label}, ray {i} {:?} in ({}, {}): got {got:?}, reference {want:?}",
                c.ray, c.t_min, c.t_max
            )
        };
        assert_eq!(found, want.is_hit(), "hit or miss differs: {}", ctx());
        agreement.assert(&got, want, ctx);
        let (limits, n) = agreement.any_hit_limits(c, want);
        for &(limit, yes) in &limits[..n] {
            assert_eq!(
                accel.occluded(&c.ray, c.t_min, limit),
                yes,
                "any hit before {limit}: {}",
                ctx()
            );
        }
    });
}

/// Packets: the same cases eight at a time, through `intersect_packet` and `occluded_packet`, with the
/// same expectations as [`check_single`], and every lane left out of the mask untouched. The cases are
/// grouped by `t_min` (a packet has one) and sorted by direction octant, so that most packets share
/// their direction signs (the kernels' coherent path) and the rest mix them; the second lane of every
/// packet of more than two rays is left out.
pub fn check_packets(label: &str, accel: &Accel, agreement: Agreement, cases: &[Case], want: &[Hit]) {
    assert_eq!(cases.len(), want.len(), "{label}: one answer per case");
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
        let all = (1u16 << ids.len()).wrapping_sub(1) as u8;
        let active = all & if ids.len() > 2 { !2 } else { 0xff };
        let mut hits: [Hit; PACKET] = std::array::from_fn(|k| match active >> k & 1 {
            1 => Hit::miss(t_max[k]),
            _ => sentinel,
        });
        let found = accel.intersect_packet(&rays, active, t_min, &mut hits);
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
            assert_eq!(
                found >> k & 1 == 1,
                want.is_hit(),
                "hit or miss differs: {}",
                ctx()
            );
            agreement.assert(got, want, ctx);
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
            assert_eq!(
                blocked,
                expected,
                "{label}, packet any hit, pass {pass}: rays {:?}, limits {limits:?}, blocked {blocked:08b}, \
                 expected {expected:08b}",
                ids.iter().map(|&i| cases[i].ray).collect::<Vec<_>>()
            );
        }
    });
}

/// Every contestant against brute force on every case: for scenes where brute force is cheap (up to a
/// few thousand primitives, or a few thousand rays).
pub fn against_brute_force(label: &str, prims: Prims, contestants: &[Contestant], cases: &[Case]) -> Tally {
    let want = answers(&Accel::build(prims, AccelKind::None), cases);
    for c in contestants {
        check(
            &format!("{label}, {}", c.name),
            &c.accel,
            c.agreement(),
            cases,
            &want,
        );
    }
    Tally::of(&want)
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
    against_brute_force(
        &format!("{label}, brute-force sample of {}", sampled.len()),
        prims,
        contestants,
        &sampled,
    );
    let want = answers(&grid.accel, cases);
    for c in contestants.iter().filter(|c| !c.is_grid()) {
        check(
            &format!("{label}, {} against the grid", c.name),
            &c.accel,
            c.agreement(),
            cases,
            &want,
        );
    }
    Tally::of(&want)
}
