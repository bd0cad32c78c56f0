use glam::Vec3;
use wide::f32x8;

use super::super::ChildRef;
use super::super::isa::{Isa, Simd};
use super::super::order::Visit;
use super::super::slab::{SlabRays, slab};
use super::*;
use crate::accel::stack::Stack;
use crate::geometry::ray::testing::TestRng;
use crate::geometry::ray::{Ray, safe_inverse};

/// [`slab`] over eight boxes on the lanes [`Simd::run8`] picks: entry distances and mask.
struct Slab8<'a> {
    ray: &'a Ray,
    boxes: &'a [[f32; 8]; 6],
    t_max: f32,
}

impl OnLanes8 for Slab8<'_> {
    type Output = ([f32; 8], u32);
    fn run<L: Lanes8>(self) -> Self::Output {
        let rays = SlabRays::<L>::splat(self.ray);
        let plane = |axis: usize, max: bool| L::load(&self.boxes[axis + 3 * usize::from(max)]);
        let (t, mask) = slab(&rays, plane, L::splat(0.0), L::splat(self.t_max));
        (t.to_array(), mask)
    }
}

/// Eight rays against two boxes at once ([`Twice`]) and against each alone, on the lanes
/// [`Simd::run8`] picks: whether the two agree bit for bit, entries and masks.
struct Pairs<'a> {
    rays: &'a [Ray; 8],
    live: u32,
    boxes: &'a [[f32; 2]; 6],
    t_max: f32,
}

impl OnLanes8 for Pairs<'_> {
    type Output = bool;
    fn run<L: Lanes8>(self) -> bool {
        let p = SlabRays::<L>::packet(self.rays, self.live);
        let (lo, hi) = (L::splat(0.0), L::splat(self.t_max));
        let one = |k: usize| {
            slab(
                &p,
                |axis, max| L::splat(self.boxes[axis + 3 * usize::from(max)][k]),
                lo,
                hi,
            )
        };
        let plane = |axis: usize, max: bool| {
            let b = &self.boxes[axis + 3 * usize::from(max)];
            Twice(L::splat(b[0]), L::splat(b[1]))
        };
        let (Twice(e0, e1), mask) = slab(&p.doubled(), plane, Twice(lo, lo), Twice(hi, hi));
        let bits = |v: L| v.to_array().map(f32::to_bits);
        let ((f0, m0), (f1, m1)) = (one(0), one(1));
        mask == m0 | m1 << 8 && bits(e0) == bits(f0) && bits(e1) == bits(f1)
    }
}

/// Two boxes a step, as the packet kernel tests a node's children, give each box's own test's
/// entries and masks bit for bit, with rays of one direction octant and of mixed ones.
#[test]
fn two_boxes_at_once_match_each_alone() {
    let mut rng = TestRng::new(0x2b0c);
    let simds: Vec<Simd> = [Isa::Portable, Isa::Avx2, Isa::Avx512]
        .into_iter()
        .filter_map(Simd::new)
        .collect();
    let mut entered = 0;
    for case in 0..3_000 {
        let base = rng.direction();
        let rays: [Ray; 8] = std::array::from_fn(|_| {
            let dir = if case % 2 == 0 {
                (base + rng.vec3(-0.1, 0.1)).normalize()
            } else {
                rng.direction()
            };
            Ray::new(rng.vec3(-0.2, 0.2), dir)
        });
        let corners: [(Vec3, Vec3); 2] = std::array::from_fn(|_| {
            let c = rays[0].origin + rays[0].dir * rng.range(0.5, 3.0) + rng.vec3(-0.3, 0.3);
            let h = rng.vec3(0.01, 0.5);
            (c - h, c + h)
        });
        let boxes: [[f32; 2]; 6] =
            std::array::from_fn(|row| corners.map(|(lo, hi)| if row < 3 { lo[row] } else { hi[row - 3] }));
        let live = if case % 3 == 0 {
            rng.below(256) as u32
        } else {
            0xff
        };
        for &simd in &simds {
            assert!(
                simd.run8(Pairs {
                    rays: &rays,
                    live,
                    boxes: &boxes,
                    t_max: 4.0,
                }),
                "{:?}: case {case}",
                simd.isa()
            );
        }
        let p = SlabRays::<f32x8>::packet(&rays, live);
        let (_, m) = slab(
            &p,
            |axis, max| f32x8::splat(boxes[axis + 3 * usize::from(max)][0]),
            f32x8::splat(0.0),
            f32x8::splat(4.0),
        );
        entered += m.count_ones();
    }
    // The boxes lie on the first ray's way: many rays enter them, so the masks are worth comparing.
    assert!(entered > 3_000, "{entered}");
}

/// [`Lanes::order_entered`] on the lanes [`Simd::run8`] picks: the nearest child and the stack.
struct Order<'a> {
    t: &'a [f32; 8],
    mask: u32,
    child: &'a [ChildRef; 8],
}

impl OnLanes8 for Order<'_> {
    type Output = (ChildRef, Vec<Visit>);
    fn run<L: Lanes8>(self) -> Self::Output {
        let mut stack = Stack::<Visit, 16>::new();
        // An entry already on the stack, which the order must leave in place.
        stack.push(Visit { child: 99, t: -1.0 });
        let nearest = L::load(self.t).order_entered(self.mask, self.child, &mut stack);
        (nearest, std::iter::from_fn(|| stack.pop()).collect())
    }
}

/// Every lane type orders three to eight entered children as a sort by distance would, nearest
/// first and, among equal distances, the later lane first (the scalar stable sort's order), with
/// ties common: the nearest is returned, the others popped nearest first, the entry below kept.
#[test]
fn entered_children_come_nearest_first() {
    let mut rng = TestRng::new(0x50f7);
    let simds: Vec<Simd> = [Isa::Portable, Isa::Avx2, Isa::Avx512]
        .into_iter()
        .filter_map(Simd::new)
        .collect();
    let child: [ChildRef; 8] = std::array::from_fn(|k| (1000 + 7 * k as u32) | ((k as u32 % 2) << 31));
    for case in 0..20_000 {
        let mask = loop {
            let m = rng.below(256) as u32;
            if m.count_ones() >= 3 {
                break m;
            }
        };
        // Distances from a handful of values (ties), or any (case odd); +0 and large ones too.
        let t: [f32; 8] = std::array::from_fn(|_| match case % 2 {
            0 => [0.0, 0.25, 1.0, 1.0e30][rng.below(4)],
            _ => rng.range(0.0, 100.0),
        });
        let mut lanes: Vec<usize> = (0..8).filter(|k| mask >> k & 1 != 0).collect();
        lanes.sort_by(|&a, &b| t[a].total_cmp(&t[b]).then(b.cmp(&a)));
        let mut want: Vec<Visit> = lanes[1..]
            .iter()
            .map(|&k| Visit {
                child: child[k],
                t: t[k],
            })
            .collect();
        want.push(Visit { child: 99, t: -1.0 });
        for &simd in &simds {
            let (nearest, popped) = simd.run8(Order {
                t: &t,
                mask,
                child: &child,
            });
            assert_eq!(nearest, child[lanes[0]], "{:?}: case {case}", simd.isa());
            assert_eq!(popped, want, "{:?}: case {case}", simd.isa());
        }
    }
}

/// Stores box `k` of eight: min planes in rows 0-2, max planes in rows 3-5.
fn put(boxes: &mut [[f32; 8]; 6], k: usize, lo: Vec3, hi: Vec3) {
    for a in 0..3 {
        boxes[a][k] = lo[a];
        boxes[a + 3][k] = hi[a];
    }
}

/// The exact slab test in f64 for the ray's f32 inverse direction (a difference of two floats and
/// its product with a third are exact in f64): whether box `k` meets the ray within `[0, t_max]`.
fn exact(ray: &Ray, boxes: &[[f32; 8]; 6], k: usize, t_max: f32) -> bool {
    let inv = safe_inverse(ray.dir);
    let (mut near, mut far) = (0.0f64, t_max as f64);
    for a in 0..3 {
        let t0 = (boxes[a][k] as f64 - ray.origin[a] as f64) * inv[a] as f64;
        let t1 = (boxes[a + 3][k] as f64 - ray.origin[a] as f64) * inv[a] as f64;
        near = near.max(t0.min(t1));
        far = far.min(t0.max(t1));
    }
    near <= far
}

/// Every lane type enters every box the exact test says the ray meets, on the cases where
/// rounding decides: boxes around a point of the ray, flat on some axes, some with a face through
/// the point (the ray grazes it), origins far from the box, and directions along an axis. The
/// fused form (AVX2, AVX-512) is checked wherever the CPU has it.
#[test]
fn slab_never_rejects_a_box_the_ray_meets() {
    let simds: Vec<Simd> = [Isa::Portable, Isa::Avx2, Isa::Avx512]
        .into_iter()
        .filter_map(|s| {
            let simd = Simd::new(s);
            if simd.is_none() {
                eprintln!("this CPU lacks {s:?}: its slab test is not checked here");
            }
            simd
        })
        .collect();
    let mut rng = TestRng::new(0x51ab);
    let (mut met, mut checked) = (0, 0);
    for case in 0..20_000 {
        let scale = [1.0, 1e-3, 1e3][case % 3];
        let origin = rng.vec3(-1.0, 1.0) * scale * if case % 7 == 0 { 1e3 } else { 1.0 };
        let mut dir = rng.direction();
        if case % 5 == 0 {
            dir[rng.below(3)] = 0.0;
        }
        let ray = Ray::new(origin, dir);
        let mut boxes = [[0.0f32; 8]; 6];
        for k in 0..8 {
            let t = rng.range(0.0, 4.0) * scale;
            let p = ray.origin + ray.dir * t;
            let (mut lo, mut hi) = (p, p);
            for a in 0..3 {
                match rng.below(4) {
                    0 => {}
                    1 => hi[a] += rng.range(0.0, 1e-3) * scale,
                    2 => lo[a] -= rng.range(0.0, 1e-3) * scale,
                    _ => {
                        let w = rng.range(0.0, 0.1) * scale;
                        (lo[a], hi[a]) = (p[a] - w, p[a] + w);
                    }
                }
            }
            put(&mut boxes, k, lo, hi);
        }
        let t_max = 8.0 * scale;
        for &simd in &simds {
            let (_, mask) = simd.run8(Slab8 {
                ray: &ray,
                boxes: &boxes,
                t_max,
            });
            for k in 0..8 {
                if exact(&ray, &boxes, k, t_max) {
                    met += 1;
                    assert!(
                        mask & (1 << k) != 0,
                        "{:?}: box {k} of case {case} ({boxes:?}) meets {ray:?} but was not entered",
                        simd.isa()
                    );
                }
                checked += 1;
            }
        }
    }
    // About half the boxes are met exactly (a point of the ray rounded to floats is off the ray
    // by an ulp, so flat boxes through it are met or missed by that much): the cases that decide.
    assert!(met * 3 > checked, "{met} of {checked} boxes met");
}

/// Where the ray misses a box by a clear margin, no lane type enters it (the outward rounding is
/// a few ulps, not a looser test).
#[test]
fn slab_rejects_a_box_the_ray_clearly_misses() {
    let mut rng = TestRng::new(0x0ff);
    for case in 0..5_000 {
        let ray = Ray::new(rng.vec3(-1.0, 1.0), rng.direction());
        let mut boxes = [[0.0f32; 8]; 6];
        for k in 0..8 {
            let p = ray.origin + ray.dir * rng.range(0.5, 4.0);
            // A box of half-width 0.01 moved 0.5 along an axis other than the ray's steepest `a`:
            // to move 0.5 along that axis the ray moves at least 0.5 along `a`, out of the box's
            // 0.02 there, so it never meets it.
            let a = (0..3)
                .max_by(|&i, &j| ray.dir[i].abs().total_cmp(&ray.dir[j].abs()))
                .unwrap();
            let mut c = p;
            c[(a + 1) % 3] += 0.5;
            put(&mut boxes, k, c - 0.01, c + 0.01);
            assert!(!exact(&ray, &boxes, k, 8.0));
        }
        for s in [Isa::Portable, Isa::Avx2, Isa::Avx512] {
            let Some(simd) = Simd::new(s) else { continue };
            let (_, mask) = simd.run8(Slab8 {
                ray: &ray,
                boxes: &boxes,
                t_max: 8.0,
            });
            assert_eq!(mask, 0, "{s:?}: case {case}");
        }
    }
}
