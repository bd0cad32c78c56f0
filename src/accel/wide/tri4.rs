//! Four triangles in structure-of-arrays form, tested against one ray in the four lanes of `f32x4`, or
//! two such blocks side by side in eight lanes (one AVX step for a leaf of five to eight triangles,
//! where the blocks took two SSE steps; such leaves hold 63% of `dragon.p3f`'s triangles in its BVH8).
//!
//! The arithmetic is the scalar [`crate::geometry::triangle::intersect`] (Möller–Trumbore 1997, grouped
//! as in Embree) operation for operation, with the normal `e1 × e2` precomputed: every lane returns the
//! bit-identical `(t, u, v)` the scalar routine would, so accelerators with SIMD leaves render the same
//! image as brute force.

use glam::Vec3;
use wide::f32x4;

use super::lanes::{Lanes, Lanes8};
use crate::scene::Triangles;

/// Four triangles (unused lanes are degenerate: zero edges, never hit).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct Tri4 {
    v0: [[f32; 4]; 3],
    e1: [[f32; 4]; 3],
    e2: [[f32; 4]; 3],
    n: [[f32; 4]; 3],
    /// Primitive ids of the lanes (`u32::MAX` in unused lanes).
    pub id: [u32; 4],
}

impl Tri4 {
    /// Packs up to four triangles: `(primitive id, index in the scene's triangle arrays)`.
    pub fn pack(triangles: &Triangles, lanes: &[(u32, usize)]) -> Self {
        debug_assert!(lanes.len() <= 4);
        let mut b = Tri4 {
            v0: [[0.0; 4]; 3],
            e1: [[0.0; 4]; 3],
            e2: [[0.0; 4]; 3],
            n: [[0.0; 4]; 3],
            id: [u32::MAX; 4],
        };
        for (k, &(id, i)) in lanes.iter().enumerate() {
            let (v0, e1, e2) = (triangles.v0.get(i), triangles.e1.get(i), triangles.e2.get(i));
            let n = e1.cross(e2);
            for axis in 0..3 {
                b.v0[axis][k] = v0[axis];
                b.e1[axis][k] = e1[axis];
                b.e2[axis][k] = e2[axis];
                b.n[axis][k] = n[axis];
            }
            b.id[k] = id;
        }
        b
    }

    /// The nearest lane hit with `t` in `(t_min, t_max)`: `(lane, t, u, v)`; on equal `t` the lowest lane.
    #[inline(always)]
    pub fn intersect(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(usize, f32, f32, f32)> {
        nearest(self.intersect4(origin, dir, t_min, t_max))
    }

    /// The nearest hit of the eight triangles of `lo` and `hi` side by side in the eight lanes `L` (one
    /// AVX step where four-lane blocks take two), with `t` in `(t_min, t_max)`: `(lane, t, u, v)`, lanes
    /// 0-3 being `lo`'s and 4-7 `hi`'s; on equal `t` the lowest lane, so `lo`'s hit wins a tie as it
    /// would tested first. Each lane's arithmetic is [`Tri4::intersect4`]'s: the one [`moller_trumbore`].
    #[inline(always)]
    pub(super) fn intersect_pair<L: Lanes8>(
        lo: &Tri4,
        hi: &Tri4,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(usize, f32, f32, f32)> {
        let ld = |a: &[[f32; 4]; 3], b: &[[f32; 4]; 3]| {
            [
                L::halves(&a[0], &b[0]),
                L::halves(&a[1], &b[1]),
                L::halves(&a[2], &b[2]),
            ]
        };
        let block = [
            ld(&lo.v0, &hi.v0),
            ld(&lo.e1, &hi.e1),
            ld(&lo.e2, &hi.e2),
            ld(&lo.n, &hi.n),
        ];
        nearest(moller_trumbore(block, origin, dir, t_min, t_max))
    }

    /// All four lanes: `t`, `u`, `v` and the bit mask of lanes that hit within `(t_min, t_max)`.
    #[inline(always)]
    pub fn intersect4(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> (f32x4, f32x4, f32x4, u32) {
        let ld = |a: &[[f32; 4]; 3]| [f32x4::new(a[0]), f32x4::new(a[1]), f32x4::new(a[2])];
        let block = [ld(&self.v0), ld(&self.e1), ld(&self.e2), ld(&self.n)];
        moller_trumbore(block, origin, dir, t_min, t_max)
    }
}

/// The scalar routine's Möller–Trumbore test on `N` triangles in lanes (`[v0, e1, e2, n]`, component
/// arrays), operation for operation: each lane's `t`, `u`, `v` and the bit mask of the lanes hit within
/// `(t_min, t_max)`. Both block widths run this one body.
#[inline(always)]
fn moller_trumbore<const N: usize, L: Lanes<N>>(
    [v0, e1, e2, n]: [[L; 3]; 4],
    origin: Vec3,
    dir: Vec3,
    t_min: f32,
    t_max: f32,
) -> (L, L, L, u32) {
    let d = [L::splat(dir.x), L::splat(dir.y), L::splat(dir.z)];
    let s = [
        L::splat(origin.x).sub(v0[0]),
        L::splat(origin.y).sub(v0[1]),
        L::splat(origin.z).sub(v0[2]),
    ];
    // r = s × d, as glam's cross.
    let r = [
        s[1].mul(d[2]).sub(d[1].mul(s[2])),
        s[2].mul(d[0]).sub(d[2].mul(s[0])),
        s[0].mul(d[1]).sub(d[0].mul(s[1])),
    ];
    let dot = |a: &[L; 3], b: &[L; 3]| a[0].mul(b[0]).add(a[1].mul(b[1])).add(a[2].mul(b[2]));
    let det = dot(&n, &d).neg();
    let zero = L::splat(0.0);
    let finite = det.abs().lt(L::splat(f32::INFINITY));
    let inv_det = L::splat(1.0).div(det);
    let u = dot(&e2, &r).mul(inv_det);
    let v = dot(&e1, &r).neg().mul(inv_det);
    let t = dot(&n, &s).mul(inv_det);
    let ok = det.ne(zero)
        & finite
        & u.ge(zero)
        & v.ge(zero)
        & u.add(v).le(L::splat(1.0))
        & L::splat(t_min).lt(t)
        & t.lt(L::splat(t_max));
    (t, u, v, ok)
}

/// The hit lane of a block test's `(t, u, v, mask)` with the least `t` (the lowest such lane on a tie):
/// `(lane, t, u, v)`; `None` for an empty mask.
#[inline(always)]
fn nearest<const N: usize, L: Lanes<N>>((t, u, v, mask): (L, L, L, u32)) -> Option<(usize, f32, f32, f32)> {
    if mask == 0 {
        return None;
    }
    let t = t.to_array();
    let mut best = mask.trailing_zeros() as usize;
    let mut rest = mask & (mask - 1);
    while rest != 0 {
        let k = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        if t[k] < t[best] {
            best = k;
        }
    }
    Some((best, t[best], u.to_array()[best], v.to_array()[best]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::wide::isa::{Isa, Simd};
    use crate::accel::wide::lanes::OnLanes8;
    use crate::geometry::ray::testing::TestRng;
    use crate::geometry::{ray::Ray, triangle};
    use crate::scene::{Camera, Material, Scene};

    /// A pair of blocks over eight lanes, on every instruction set the CPU has, against the blocks
    /// tested one after the other as four-lane blocks (the second only for strictly nearer hits).
    struct Pairs<'a> {
        blocks: &'a [(Tri4, Tri4)],
        /// Rays: the pair they are tested against, the ray, `t_min` and `t_max`.
        rays: &'a [(usize, Ray, f32, f32)],
    }

    impl OnLanes8 for Pairs<'_> {
        type Output = Vec<Option<(usize, f32, f32, f32)>>;
        fn run<L: Lanes8>(self) -> Self::Output {
            let mut out = Vec::new();
            for &(pair, ray, t_min, t_max) in self.rays {
                let (lo, hi) = &self.blocks[pair];
                out.push(Tri4::intersect_pair::<L>(
                    lo, hi, ray.origin, ray.dir, t_min, t_max,
                ));
            }
            out
        }
    }

    #[test]
    fn pairs_match_two_blocks_in_turn() {
        let mut s = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = s.add_material(Material::default());
        let mut rng = TestRng::new(7);
        let mut r = || rng.range(-1.0, 1.0);
        for i in 0..2000 {
            let p = Vec3::new(r(), r(), r());
            s.add_triangle(p, p + Vec3::new(r(), r(), r()), p + Vec3::new(r(), r(), r()), m);
            if i % 50 == 0 {
                // Copies of a triangle in both blocks: ties at equal `t`.
                s.add_triangle(p, p + Vec3::X, p + Vec3::Y, m);
                s.add_triangle(p, p + Vec3::X, p + Vec3::Y, m);
            }
        }
        let t = &s.triangles;
        let count = t.v0.len();
        let blocks: Vec<(Tri4, Tri4)> = (0..600)
            .map(|c| {
                let lanes = |n: usize, from: usize| -> Vec<(u32, usize)> {
                    (0..n).map(|k| ((from + k) as u32, (from + k) % count)).collect()
                };
                // Full and partly empty blocks, and the duplicated triangles split across the two.
                let from = (c * 7) % count;
                (
                    Tri4::pack(t, &lanes(4, from)),
                    Tri4::pack(t, &lanes(1 + c % 4, from + 3)),
                )
            })
            .collect();
        // Per pair, rays from anywhere: half toward one of its triangles' centroids (hits, ties
        // included), half in any direction; some with a positive `t_min` or a finite `t_max`.
        let mut rays = Vec::new();
        for (pair, (lo, hi)) in blocks.iter().enumerate() {
            for i in 0..20 {
                let origin = Vec3::new(r(), r(), r()) * 3.0;
                let dir = if i % 2 == 0 {
                    let k = (i / 4) % 4;
                    let (b, k) = if i % 4 == 0 {
                        (lo, k)
                    } else {
                        (hi, if hi.id[k] == u32::MAX { 0 } else { k })
                    };
                    let at = |a: &[[f32; 4]; 3]| Vec3::new(a[0][k], a[1][k], a[2][k]);
                    at(&b.v0) + (at(&b.e1) + at(&b.e2)) / 3.0 - origin
                } else {
                    Vec3::new(r(), r(), r())
                };
                let t_max = if i % 3 == 0 {
                    r().abs() * 2.0
                } else {
                    f32::INFINITY
                };
                rays.push((
                    pair,
                    Ray::new(origin, dir),
                    if i % 5 == 0 { 0.3 } else { 0.0 },
                    t_max,
                ));
            }
        }
        let mut want = Vec::new();
        for &(pair, ray, t_min, t_max) in &rays {
            let (lo, hi) = &blocks[pair];
            let first = lo.intersect(ray.origin, ray.dir, t_min, t_max);
            let limit = first.map_or(t_max, |h| h.1);
            let second = hi.intersect(ray.origin, ray.dir, t_min, limit);
            want.push(second.map(|(k, t, u, v)| (k + 4, t, u, v)).or(first));
        }
        let bits = |h: &Option<(usize, f32, f32, f32)>| {
            h.map(|(k, t, u, v)| (k, t.to_bits(), u.to_bits(), v.to_bits()))
        };
        let hits = want.iter().filter(|h| h.is_some()).count();
        let from_hi = want.iter().filter(|h| h.is_some_and(|h| h.0 >= 4)).count();
        assert!(
            hits > 3000 && from_hi > 500,
            "{hits} hits, {from_hi} in the second block"
        );
        for simd in [Isa::Portable, Isa::Avx2, Isa::Avx512] {
            let Some(simd) = Simd::new(simd) else {
                continue;
            };
            let got = simd.run8(Pairs {
                blocks: &blocks,
                rays: &rays,
            });
            assert_eq!(got.len(), want.len());
            for (i, (g, w)) in got.iter().zip(&want).enumerate() {
                assert_eq!(bits(g), bits(w), "{simd:?}, case {i}");
            }
        }
    }

    /// Every lane returns exactly the scalar routine's `(t, u, v)`, and misses where it misses.
    #[test]
    fn lanes_match_the_scalar_test_bit_for_bit() {
        let mut s = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = s.add_material(Material::default());
        let mut x = 1u64;
        let mut r = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (x >> 40) as f32 / (1u64 << 24) as f32 * 2.0 - 1.0
        };
        for _ in 0..4000 {
            let p = Vec3::new(r(), r(), r());
            s.add_triangle(p, p + Vec3::new(r(), r(), r()), p + Vec3::new(r(), r(), r()), m);
        }
        let t = &s.triangles;
        for chunk in 0..1000 {
            let lanes: Vec<(u32, usize)> = (0..(chunk % 4) + 1).map(|k| (k as u32, chunk * 4 + k)).collect();
            let block = Tri4::pack(t, &lanes);
            for _ in 0..20 {
                let ray = Ray::new(Vec3::new(r(), r(), r()) * 3.0, Vec3::new(r(), r(), r()));
                let (tt, uu, vv, mask) = block.intersect4(ray.origin, ray.dir, 0.0, f32::INFINITY);
                for k in 0..4 {
                    let want = lanes.get(k).and_then(|&(_, i)| {
                        triangle::intersect(t.v0.get(i), t.e1.get(i), t.e2.get(i), &ray, 0.0, f32::INFINITY)
                    });
                    let got =
                        (mask >> k & 1 == 1).then(|| (tt.to_array()[k], uu.to_array()[k], vv.to_array()[k]));
                    assert_eq!(
                        got.map(|g| (g.0.to_bits(), g.1.to_bits(), g.2.to_bits())),
                        want.map(|w| (w.0.to_bits(), w.1.to_bits(), w.2.to_bits()))
                    );
                }
            }
        }
    }
}
