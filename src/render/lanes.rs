//! The shading's numbers and vectors in lanes: [`Fx`], `N` floats, and [`V3`], `N` 3-vectors, over the
//! accelerator's lane types ([`Lanes`]: one float, eight in `wide`'s portable form, or eight in one AVX2
//! or AVX-512 register, chosen when the frame runs).
//!
//! Each operation is glam's `Vec3` operation lane by lane, in glam's order (a dot product is
//! `(x·x' + y·y') + z·z'`, a normalisation multiplies by the length's reciprocal): IEEE add, multiply,
//! divide and square root are exact per lane and never fused here, so every lane type gives a one-ray
//! computation's bits.

use std::ops::{Add, Div, Mul, Neg, Sub};

use glam::Vec3;

pub(crate) use crate::accel::lanes::Lanes;

/// `N` floats in lanes, with arithmetic operators.
#[derive(Clone, Copy)]
pub(crate) struct Fx<L, const N: usize>(pub L);

impl<L: Lanes<N>, const N: usize> Fx<L, N> {
    /// `v` in every lane.
    #[inline(always)]
    pub fn splat(v: f32) -> Self {
        Fx(L::splat(v))
    }

    /// Lane `k` is `a[k]`.
    #[inline(always)]
    pub fn from(a: [f32; N]) -> Self {
        Fx(L::load(&a))
    }

    /// The lanes.
    #[inline(always)]
    pub fn to_array(self) -> [f32; N] {
        self.0.to_array()
    }

    /// `f32::sqrt` in each lane.
    #[inline(always)]
    pub fn sqrt(self) -> Self {
        Fx(self.0.sqrt())
    }

    /// `f32::max` in each lane, for a number `o`.
    #[inline(always)]
    pub fn max(self, o: Self) -> Self {
        Fx(self.0.max(o.0))
    }

    /// `x.clamp(0.0, 1.0)` in each lane (a NaN stays NaN).
    #[inline(always)]
    pub fn clamp01(self) -> Self {
        let (zero, one) = (Fx::splat(0.0), Fx::splat(1.0));
        let x = Fx::blend(self.lt(zero), zero, self);
        Fx::blend(x.gt(one), one, x)
    }

    /// The lanes where `self < o`, as bits (false on NaN).
    #[inline(always)]
    pub fn lt(self, o: Self) -> u32 {
        self.0.lt(o.0)
    }

    /// The lanes where `self > o`, as bits (false on NaN).
    #[inline(always)]
    pub fn gt(self, o: Self) -> u32 {
        o.0.lt(self.0)
    }

    /// The lanes where `self >= o`, as bits (false on NaN).
    #[inline(always)]
    pub fn ge(self, o: Self) -> u32 {
        self.0.ge(o.0)
    }

    /// The lanes above zero (not NaN), as bits.
    #[inline(always)]
    pub fn positive(self) -> u32 {
        self.gt(Fx::splat(0.0))
    }

    /// The finite lanes, as bits.
    #[inline(always)]
    pub fn finite(self) -> u32 {
        // |x| < ∞ is false for an infinite x and, ordered, for a NaN.
        self.0.abs().lt(L::splat(f32::INFINITY))
    }

    /// Per lane, `a`'s where the lane's bit of `mask` is set, else `b`'s.
    #[inline(always)]
    pub fn blend(mask: u32, a: Self, b: Self) -> Self {
        Fx(L::blend(mask, a.0, b.0))
    }
}

/// The bits of all `N` lanes.
#[inline(always)]
pub(crate) const fn full<const N: usize>() -> u32 {
    if N >= 32 { !0 } else { (1 << N) - 1 }
}

/// The lanes of `mask` (of `N` lanes), by index, the first lane first. Each index is taken modulo
/// `N` (a no-op on such a mask, an `and` for the powers of two `N` is), so that indexing `[T; N]`
/// arrays with it needs no bounds check.
#[inline(always)]
pub(crate) fn each<const N: usize>(mask: u32) -> impl Iterator<Item = usize> {
    let mut mask = mask;
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let k = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            k % N
        })
    })
}

/// Lane-wise operators of [`Fx`], each the lane type's own.
macro_rules! lane_ops {
    ($($trait:ident $f:ident),*) => {$(
        impl<L: Lanes<N>, const N: usize> $trait for Fx<L, N> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Fx(self.0.$f(o.0))
            }
        }
    )*};
}

lane_ops!(Add add, Sub sub, Mul mul, Div div);

impl<L: Lanes<N>, const N: usize> Neg for Fx<L, N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Fx(self.0.neg())
    }
}

/// `N` 3-vectors, a component an [`Fx`].
#[derive(Clone, Copy)]
pub(crate) struct V3<L, const N: usize> {
    pub x: Fx<L, N>,
    pub y: Fx<L, N>,
    pub z: Fx<L, N>,
}

impl<L: Lanes<N>, const N: usize> V3<L, N> {
    /// Zero in every lane.
    #[inline(always)]
    pub fn zero() -> Self {
        V3::splat(Vec3::ZERO)
    }

    /// `v` in every lane.
    #[inline(always)]
    pub fn splat(v: Vec3) -> Self {
        V3 {
            x: Fx::splat(v.x),
            y: Fx::splat(v.y),
            z: Fx::splat(v.z),
        }
    }

    /// Lane `k` is `v[k]`.
    #[inline(always)]
    pub fn from_lanes(v: &[Vec3; N]) -> Self {
        V3 {
            x: Fx::from(v.map(|v| v.x)),
            y: Fx::from(v.map(|v| v.y)),
            z: Fx::from(v.map(|v| v.z)),
        }
    }

    /// The `N` vectors.
    #[inline(always)]
    pub fn lanes(self) -> [Vec3; N] {
        let (x, y, z) = (self.x.to_array(), self.y.to_array(), self.z.to_array());
        std::array::from_fn(|k| Vec3::new(x[k], y[k], z[k]))
    }

    /// [`Vec3::dot`] in each lane.
    #[inline(always)]
    pub fn dot(self, o: Self) -> Fx<L, N> {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// [`Vec3::length`] in each lane.
    #[inline(always)]
    pub fn length(self) -> Fx<L, N> {
        self.dot(self).sqrt()
    }

    /// [`Vec3::normalize`] in each lane.
    #[inline(always)]
    pub fn normalize(self) -> Self {
        self * (Fx::splat(1.0) / self.length())
    }

    /// [`Vec3::cross`] in each lane.
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        V3 {
            x: self.y * o.z - o.y * self.z,
            y: self.z * o.x - o.z * self.x,
            z: self.x * o.y - o.x * self.y,
        }
    }

    /// [`Vec3::normalize_or_zero`] in each lane: zero where the length's reciprocal is not a finite
    /// positive number.
    #[inline(always)]
    pub fn normalize_or_zero(self) -> Self {
        let rcp = Fx::splat(1.0) / self.length();
        let usable = rcp.positive() & rcp.lt(Fx::splat(f32::INFINITY));
        V3::blend(usable, self * rcp, V3::zero())
    }

    /// The lanes whose three components are finite, as bits.
    #[inline(always)]
    pub fn finite(self) -> u32 {
        self.x.finite() & self.y.finite() & self.z.finite()
    }

    /// Per lane, `a`'s where the lane's bit of `mask` is set, else `b`'s.
    #[inline(always)]
    pub fn blend(mask: u32, a: Self, b: Self) -> Self {
        V3 {
            x: Fx::blend(mask, a.x, b.x),
            y: Fx::blend(mask, a.y, b.y),
            z: Fx::blend(mask, a.z, b.z),
        }
    }
}

/// `N` 3-vectors filled lane by lane (a gather) before they are loaded into lanes.
pub(crate) struct Gather<const N: usize>([[f32; N]; 3]);

impl<const N: usize> Gather<N> {
    /// Zero in every lane.
    pub const ZERO: Self = Gather([[0.0; N]; 3]);

    /// Sets lane `k` to `v`.
    #[inline(always)]
    pub fn set(&mut self, k: usize, v: Vec3) {
        (self.0[0][k], self.0[1][k], self.0[2][k]) = (v.x, v.y, v.z);
    }

    /// The vectors in lanes.
    #[inline(always)]
    pub fn load<L: Lanes<N>>(&self) -> V3<L, N> {
        V3 {
            x: Fx::from(self.0[0]),
            y: Fx::from(self.0[1]),
            z: Fx::from(self.0[2]),
        }
    }
}

/// Component-wise operators of [`V3`], glam's `Vec3` ones.
macro_rules! vector_ops {
    ($($trait:ident $f:ident),*) => {$(
        impl<L: Lanes<N>, const N: usize> $trait for V3<L, N> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                V3 { x: self.x.$f(o.x), y: self.y.$f(o.y), z: self.z.$f(o.z) }
            }
        }
    )*};
}

vector_ops!(Add add, Sub sub, Mul mul);

impl<L: Lanes<N>, const N: usize> Neg for V3<L, N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        V3 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

/// Each lane's vector scaled by the lane's number (glam's `Vec3 * f32`).
impl<L: Lanes<N>, const N: usize> Mul<Fx<L, N>> for V3<L, N> {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: Fx<L, N>) -> Self {
        V3 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

/// Each lane's vector divided by the lane's number (glam's `Vec3 / f32`).
impl<L: Lanes<N>, const N: usize> Div<Fx<L, N>> for V3<L, N> {
    type Output = Self;
    #[inline(always)]
    fn div(self, s: Fx<L, N>) -> Self {
        V3 {
            x: self.x / s,
            y: self.y / s,
            z: self.z / s,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::lanes::{Lanes8, OnLanes8};
    use crate::accel::{Isa, Simd};
    use crate::render::sampler::Sampler;

    /// The vector operations of `a`, `b` and `s`, each lane's results.
    fn operations<L: Lanes<N>, const N: usize>(a: V3<L, N>, b: V3<L, N>, s: Fx<L, N>) -> [[Vec3; N]; 11] {
        let (dot, length) = (a.dot(b).to_array(), a.length().to_array());
        [
            (a + b).lanes(),
            (a - b).lanes(),
            (-a).lanes(),
            (a * b).lanes(),
            (a * s).lanes(),
            (a / s).lanes(),
            a.normalize().lanes(),
            a.cross(b).lanes(),
            a.normalize_or_zero().lanes(),
            dot.map(Vec3::splat),
            length.map(Vec3::splat),
        ]
    }

    /// Every operation on eight lanes of the lane type `Simd::run8` picks, against glam and against
    /// one lane (`f32`), lane by lane.
    struct GlamBits;

    impl OnLanes8 for GlamBits {
        type Output = ();
        fn run<L: Lanes8>(self) {
            let mut rng = Sampler::new(2, 1, 0, 1);
            let mut v = |scale: f32| -> [Vec3; 8] {
                std::array::from_fn(|_| {
                    (Vec3::new(rng.uniform(), rng.uniform(), rng.uniform()) - 0.5) * scale
                })
            };
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            for scale in [1e-3, 1.0, 7.0, 1e5] {
                let (a, b, s) = (v(scale), v(1.0), v(3.0));
                let s = s.map(|s| s.x);
                let eight = operations::<L, 8>(V3::from_lanes(&a), V3::from_lanes(&b), Fx::from(s));
                for k in 0..8 {
                    let one = operations::<f32, 1>(V3::splat(a[k]), V3::splat(b[k]), Fx(s[k]));
                    let glam = [
                        a[k] + b[k],
                        a[k] - b[k],
                        -a[k],
                        a[k] * b[k],
                        a[k] * s[k],
                        a[k] / s[k],
                        a[k].normalize(),
                        a[k].cross(b[k]),
                        a[k].normalize_or_zero(),
                        Vec3::splat(a[k].dot(b[k])),
                        Vec3::splat(a[k].length()),
                    ];
                    for (i, want) in glam.iter().enumerate() {
                        assert_eq!(bits(eight[i][k]), bits(*want), "op {i}, lane {k}, scale {scale}");
                        assert_eq!(bits(one[i][0]), bits(*want), "op {i}, one lane, scale {scale}");
                    }
                }
                let mut g = Gather::<8>::ZERO;
                for (k, a) in a.iter().enumerate() {
                    g.set(k, *a);
                }
                assert_eq!(g.load::<L>().lanes().map(bits), a.map(bits));
            }
            odd_values::<L>();
        }
    }

    /// Where the length's reciprocal is zero, infinite or NaN, glam's zero; finiteness, blends,
    /// clamps, maxima and roots at the edges of the floats, on eight lanes of `L` and on one.
    fn odd_values<L: Lanes8>() {
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
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
        let lanes = V3::<L, 8>::from_lanes(&odd);
        for (k, (got, want)) in lanes.normalize_or_zero().lanes().iter().zip(odd).enumerate() {
            assert_eq!(bits(*got), bits(want.normalize_or_zero()), "lane {k}");
        }
        assert_eq!(lanes.finite(), 0b0111_0011);
        let picked = V3::blend(0b1010_0110, V3::<L, 8>::splat(Vec3::ONE), V3::zero()).lanes();
        for (k, p) in picked.iter().enumerate() {
            let want = if 0b1010_0110 >> k & 1 == 1 {
                Vec3::ONE
            } else {
                Vec3::ZERO
            };
            assert_eq!(*p, want);
        }
        let x = [1.0, -1.0, 0.0, f32::NAN, 2.0, -0.0, 1e-30, f32::INFINITY];
        assert_eq!(Fx::<L, 8>::from(x).positive(), 0b1101_0001);
        let clamped = Fx::<L, 8>::from(x).clamp01().to_array();
        let maxed = Fx::<L, 8>::from(x).max(Fx::splat(0.5)).to_array();
        let roots = Fx::<L, 8>::from(x).sqrt().to_array();
        for k in 0..8 {
            assert_eq!(clamped[k].to_bits(), x[k].clamp(0.0, 1.0).to_bits(), "lane {k}");
            let one = Fx::<f32, 1>(x[k]).clamp01().0;
            assert_eq!(
                one.to_bits(),
                x[k].clamp(0.0, 1.0).to_bits(),
                "one lane: {}",
                x[k]
            );
            assert_eq!(maxed[k].to_bits(), x[k].max(0.5).to_bits(), "lane {k}");
            assert_eq!(roots[k].to_bits(), x[k].sqrt().to_bits(), "lane {k}");
        }
    }

    /// Each operation gives glam's bits in every lane, on vectors of every size and sign, on every lane
    /// type the CPU runs.
    #[test]
    fn lanes_are_glams_bits() {
        for simd in [Isa::Portable, Isa::Avx2, Isa::Avx512]
            .into_iter()
            .filter_map(Simd::new)
        {
            simd.run8(GlamBits);
        }
    }
}
