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

use super::agreement::{Agreement, may_round_apart};
use super::contestants::Contestant;
use super::rays::Case;
use crate::accel::packet::{self, bits};
use crate::accel::{Accel, AccelKind, Hit, PACKET, Prims};
use crate::geometry::ray::Ray;

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
/// ([`check_single`]) and with packets ([`check_packets`]). Panics at the first disagreement, with
/// `label`, the ray and both answers in the message.
pub fn check(label: &str, accel: &Accel, agreement: Agreement, cases: &[Case], want: &[Hit]) -> Tally {
    let excused = check_single(label, accel, agreement, cases, want)
        + check_packets(label, accel, agreement, cases, want);
    Tally {
        excused,
        ..Tally::of(want)
    }
}

/// Single rays: `intersect` finds the closest hit as `want` has it (per `agreement`), and
/// `intersect_coherent` the same hit, bit for bit; `occluded` says
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
        let mut coherent = Hit::miss(c.t_max);
        let found_coherent = accel.intersect_coherent(&c.ray, c.t_min, &mut coherent);
        assert!(
            found_coherent == found && coherent == got,
            "intersect_coherent gave {coherent:?}: {}",
            ctx()
        );
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
