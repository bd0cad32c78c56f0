//! Four triangles in structure-of-arrays form, tested against one ray in the four lanes of `f32x4`.
//!
//! The arithmetic is the scalar [`crate::geometry::triangle::intersect`] (Möller–Trumbore 1997, grouped
//! as in Embree) operation for operation, with the normal `e1 × e2` precomputed: every lane returns the
//! bit-identical `(t, u, v)` the scalar routine would, so accelerators with SIMD leaves render the same
//! image as brute force.

use glam::Vec3;
use wide::f32x4;

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
        let (t, u, v, mask) = self.intersect4(origin, dir, t_min, t_max);
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

    /// All four lanes: `t`, `u`, `v` and the bit mask of lanes that hit within `(t_min, t_max)`.
    #[inline(always)]
    pub fn intersect4(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> (f32x4, f32x4, f32x4, u32) {
        let ld = |a: &[[f32; 4]; 3]| [f32x4::new(a[0]), f32x4::new(a[1]), f32x4::new(a[2])];
        let (v0, e1, e2, n) = (ld(&self.v0), ld(&self.e1), ld(&self.e2), ld(&self.n));
        let d = [f32x4::splat(dir.x), f32x4::splat(dir.y), f32x4::splat(dir.z)];
        let s = [
            f32x4::splat(origin.x) - v0[0],
            f32x4::splat(origin.y) - v0[1],
            f32x4::splat(origin.z) - v0[2],
        ];
        // r = s × d, as glam's cross.
        let r = [
            s[1] * d[2] - d[1] * s[2],
            s[2] * d[0] - d[2] * s[0],
            s[0] * d[1] - d[0] * s[1],
        ];
        let dot = |a: &[f32x4; 3], b: &[f32x4; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let det = -dot(&n, &d);
        let zero = f32x4::splat(0.0);
        let finite = det.abs().simd_lt(f32x4::splat(f32::INFINITY));
        let inv_det = f32x4::splat(1.0) / det;
        let u = dot(&e2, &r) * inv_det;
        let v = -dot(&e1, &r) * inv_det;
        let t = dot(&n, &s) * inv_det;
        let ok = det.simd_ne(zero)
            & finite
            & u.simd_ge(zero)
            & v.simd_ge(zero)
            & (u + v).simd_le(f32x4::splat(1.0))
            & t.simd_gt(f32x4::splat(t_min))
            & t.simd_lt(f32x4::splat(t_max));
        (t, u, v, ok.to_bitmask())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{ray::Ray, triangle};
    use crate::scene::{Camera, Material, Scene};

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
