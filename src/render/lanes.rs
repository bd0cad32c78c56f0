//! Vectors of a packet's eight lanes, one `f32x8` a component: the packet kernel's shading arithmetic.
//!
//! Each operation is glam's `Vec3` operation lane by lane, in glam's order (a dot product is
//! `(x·x' + y·y') + z·z'`, a normalisation multiplies by the length's reciprocal): IEEE add, multiply,
//! divide and square root are exact per lane and Rust never fuses them, so lanes give the scalar
//! path's bits.

use std::ops::{Add, Div, Mul, Neg, Sub};

use glam::Vec3;
use wide::f32x8;

/// Eight 3-vectors, a component a register.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Vec3x8 {
    pub x: f32x8,
    pub y: f32x8,
    pub z: f32x8,
}

impl Vec3x8 {
    /// Zero in every lane.
    pub const ZERO: Vec3x8 = Vec3x8 {
        x: f32x8::ZERO,
        y: f32x8::ZERO,
        z: f32x8::ZERO,
    };

    /// `v` in every lane.
    #[inline]
    pub fn splat(v: Vec3) -> Self {
        Vec3x8 {
            x: f32x8::splat(v.x),
            y: f32x8::splat(v.y),
            z: f32x8::splat(v.z),
        }
    }

    /// Lane `k` is `v[k]`.
    #[inline]
    pub fn from_lanes(v: &[Vec3; 8]) -> Self {
        Vec3x8 {
            x: f32x8::from(v.map(|v| v.x)),
            y: f32x8::from(v.map(|v| v.y)),
            z: f32x8::from(v.map(|v| v.z)),
        }
    }

    /// The eight vectors.
    #[inline]
    pub fn lanes(self) -> [Vec3; 8] {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        std::array::from_fn(|k| Vec3::new(x[k], y[k], z[k]))
    }

    /// [`Vec3::dot`] in each lane.
    #[inline]
    pub fn dot(self, o: Self) -> f32x8 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// [`Vec3::length`] in each lane.
    #[inline]
    pub fn length(self) -> f32x8 {
        self.dot(self).sqrt()
    }

    /// [`Vec3::normalize`] in each lane.
    #[inline]
    pub fn normalize(self) -> Self {
        self * (f32x8::ONE / self.length())
    }

    /// [`Vec3::cross`] in each lane.
    #[inline]
    pub fn cross(self, o: Self) -> Self {
        Vec3x8 {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }

    /// [`Vec3::normalize_or_zero`] in each lane: zero where the length's reciprocal is not a finite
    /// positive number.
    #[inline]
    pub fn normalize_or_zero(self) -> Self {
        let rcp = f32x8::ONE / self.length();
        let usable = rcp.simd_gt(f32x8::ZERO) & rcp.simd_lt(f32x8::splat(f32::INFINITY));
        Vec3x8::select(usable, self * rcp, Vec3x8::ZERO)
    }

    /// The lanes whose three components are finite, as bits.
    #[inline]
    pub fn finite(self) -> u8 {
        (self.x.is_finite() & self.y.is_finite() & self.z.is_finite()).to_bitmask() as u8
    }

    /// Lane `k` is `f(k)`.
    #[inline(always)]
    pub fn from_fn(f: impl Fn(usize) -> Vec3) -> Self {
        let mut v = Vec3x8::ZERO;
        for k in 0..8 {
            v.set(k, f(k));
        }
        v
    }

    /// Lane `k`'s vector.
    #[inline]
    pub fn lane(&self, k: usize) -> Vec3 {
        Vec3::new(self.x.as_array()[k], self.y.as_array()[k], self.z.as_array()[k])
    }

    /// Sets lane `k` to `v`, in place: a gather writes each lane's components where the lanes lie.
    #[inline(always)]
    pub fn set(&mut self, k: usize, v: Vec3) {
        self.x.as_mut_array()[k] = v.x;
        self.y.as_mut_array()[k] = v.y;
        self.z.as_mut_array()[k] = v.z;
    }

    /// Lane by lane, `self` where `mask` is set (all bits of the lane), else `other`.
    #[inline]
    pub fn select(mask: f32x8, a: Self, b: Self) -> Self {
        Vec3x8 {
            x: mask.select(a.x, b.x),
            y: mask.select(a.y, b.y),
            z: mask.select(a.z, b.z),
        }
    }
}

impl Add for Vec3x8 {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Vec3x8 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl Sub for Vec3x8 {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Vec3x8 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl Neg for Vec3x8 {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Vec3x8 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

/// Component by component (glam's `Vec3 * Vec3`).
impl Mul for Vec3x8 {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        Vec3x8 {
            x: self.x * o.x,
            y: self.y * o.y,
            z: self.z * o.z,
        }
    }
}

/// Each lane's vector scaled by the lane's number (glam's `Vec3 * f32`).
impl Mul<f32x8> for Vec3x8 {
    type Output = Self;
    #[inline]
    fn mul(self, s: f32x8) -> Self {
        Vec3x8 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

/// Each lane's vector divided by the lane's number (glam's `Vec3 / f32`).
impl Div<f32x8> for Vec3x8 {
    type Output = Self;
    #[inline]
    fn div(self, s: f32x8) -> Self {
        Vec3x8 {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
}

/// The lanes of `mask` (bit `k`, lane `k`) as a lane mask for [`Vec3x8::select`].
#[inline]
pub(crate) fn lane_mask(mask: u8) -> f32x8 {
    let bits: [f32; 8] = std::array::from_fn(|k| {
        if mask >> k & 1 == 1 {
            f32::from_bits(!0)
        } else {
            0.0
        }
    });
    f32x8::from(bits)
}

/// The lanes of `mask` whose value is above zero (not NaN), as bits.
#[inline]
pub(crate) fn positive(v: f32x8) -> u8 {
    v.simd_gt(f32x8::ZERO).to_bitmask() as u8
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::Sampler;

    /// Each operation gives glam's bits in every lane, on vectors of every size and sign.
    #[test]
    fn lanes_are_glams_bits() {
        let mut rng = Sampler::new(2, 1, 0, 1);
        let mut v = |scale: f32| -> [Vec3; 8] {
            std::array::from_fn(|_| (Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) - 0.5) * scale)
        };
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        for scale in [1e-3, 1.0, 7.0, 1e5] {
            let (a, b, s) = (v(scale), v(1.0), v(3.0));
            let (la, lb) = (Vec3x8::from_lanes(&a), Vec3x8::from_lanes(&b));
            let ls = f32x8::from(s.map(|s| s.x)).to_array();
            let lanes = [
                (la + lb).lanes(),
                (la - lb).lanes(),
                (-la).lanes(),
                (la * lb).lanes(),
                (la * f32x8::from(ls)).lanes(),
                (la / f32x8::from(ls)).lanes(),
                la.normalize().lanes(),
                la.cross(lb).lanes(),
                la.normalize_or_zero().lanes(),
            ];
            let dot = la.dot(lb).to_array();
            let length = la.length().to_array();
            for k in 0..8 {
                let want = [
                    a[k] + b[k],
                    a[k] - b[k],
                    -a[k],
                    a[k] * b[k],
                    a[k] * ls[k],
                    a[k] / ls[k],
                    a[k].normalize(),
                    a[k].cross(b[k]),
                    a[k].normalize_or_zero(),
                ];
                for (got, want) in lanes.iter().zip(want) {
                    assert_eq!(bits(got[k]), bits(want), "lane {k}, scale {scale}");
                }
                assert_eq!(dot[k].to_bits(), a[k].dot(b[k]).to_bits());
                assert_eq!(length[k].to_bits(), a[k].length().to_bits());
                assert_eq!(bits(la.lane(k)), bits(a[k]));
                let mut one = Vec3x8::from_fn(|j| b[j]);
                one.set(k, a[k]);
                assert_eq!(bits(one.lane(k)), bits(a[k]));
                assert_eq!(bits(one.lane((k + 1) % 8)), bits(b[(k + 1) % 8]));
            }
        }
        // Where the length's reciprocal is zero, infinite or NaN, glam's zero; non-finite lanes.
        let odd = [
            Vec3::ZERO,
            Vec3::splat(1e-30),
            Vec3::splat(f32::INFINITY),
            Vec3::new(f32::NAN, 0.0, 1.0),
            Vec3::new(3e38, 3e38, 0.0),
            Vec3::X,
            Vec3::new(0.0, -1e-20, 0.0),
            Vec3::new(1.0, f32::NEG_INFINITY, 0.0),
        ];
        let lanes = Vec3x8::from_lanes(&odd);
        for (k, (got, want)) in lanes.normalize_or_zero().lanes().iter().zip(odd).enumerate() {
            assert_eq!(bits(*got), bits(want.normalize_or_zero()), "lane {k}");
        }
        assert_eq!(lanes.finite(), 0b0111_0011);
        let m = lane_mask(0b1010_0110);
        let picked = Vec3x8::select(m, Vec3x8::splat(Vec3::ONE), Vec3x8::ZERO).lanes();
        for (k, p) in picked.iter().enumerate() {
            assert_eq!(
                *p,
                if 0b1010_0110 >> k & 1 == 1 {
                    Vec3::ONE
                } else {
                    Vec3::ZERO
                }
            );
        }
        assert_eq!(
            positive(f32x8::from([
                1.0,
                -1.0,
                0.0,
                f32::NAN,
                2.0,
                -0.0,
                1e-30,
                f32::INFINITY
            ])),
            0b1101_0001
        );
    }
}
