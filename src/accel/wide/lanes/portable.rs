//! [`Lanes`] on `wide`'s portable types: four lanes in one SSE register, eight in two halves.

use wide::bytemuck::cast;
use wide::{f32x4, f32x8, i32x4, i32x8};

use super::{Lanes, Lanes8};

impl Lanes8 for f32x8 {
    const ONE_REGISTER: bool = cfg!(target_feature = "avx");

    #[inline(always)]
    fn halves(lo: &[f32; 4], hi: &[f32; 4]) -> Self {
        f32x8::new([lo[0], lo[1], lo[2], lo[3], hi[0], hi[1], hi[2], hi[3]])
    }
}

/// [`Lanes`] over `wide`'s types, written once for both widths.
macro_rules! wide_lanes {
    ($v:ty, $i:ty, $n:literal) => {
        impl Lanes<$n> for $v {
            #[inline(always)]
            fn splat(v: f32) -> Self {
                <$v>::splat(v)
            }
            #[inline(always)]
            fn load(a: &[f32; $n]) -> Self {
                <$v>::new(*a)
            }
            #[inline(always)]
            fn to_array(self) -> [f32; $n] {
                <$v>::to_array(self)
            }
            #[inline(always)]
            fn sub(self, o: Self) -> Self {
                self - o
            }
            #[inline(always)]
            fn mul(self, o: Self) -> Self {
                self * o
            }
            #[inline(always)]
            fn le(self, o: Self) -> u32 {
                self.simd_le(o).to_bitmask()
            }
            #[inline(always)]
            fn add(self, o: Self) -> Self {
                self + o
            }
            #[inline(always)]
            fn div(self, o: Self) -> Self {
                self / o
            }
            #[inline(always)]
            fn sqrt(self) -> Self {
                <$v>::sqrt(self)
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                <$v>::max(self, o)
            }
            #[inline(always)]
            fn neg(self) -> Self {
                -self
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$v>::abs(self)
            }
            #[inline(always)]
            fn lt(self, o: Self) -> u32 {
                self.simd_lt(o).to_bitmask()
            }
            #[inline(always)]
            fn ge(self, o: Self) -> u32 {
                self.simd_ge(o).to_bitmask()
            }
            #[inline(always)]
            fn ne(self, o: Self) -> u32 {
                self.simd_ne(o).to_bitmask()
            }
            #[inline(always)]
            fn max_bits(self, o: Self) -> Self {
                cast::<$i, $v>(cast::<$v, $i>(self).max(cast(o)))
            }
            #[inline(always)]
            fn min_bits(self, o: Self) -> Self {
                cast::<$i, $v>(cast::<$v, $i>(self).min(cast(o)))
            }
            #[inline(always)]
            fn le_bits(self, o: Self) -> u32 {
                let gt = cast::<$v, $i>(self).simd_gt(cast::<$v, $i>(o));
                !cast::<$i, $v>(gt).to_bitmask() & ((1 << $n) - 1)
            }
            #[inline(always)]
            fn select(self, if_set: Self, if_clear: Self) -> Self {
                <$v>::select(self, if_set, if_clear)
            }
            #[inline(always)]
            fn blend(mask: u32, if_set: Self, if_clear: Self) -> Self {
                let lanes: [u32; $n] = std::array::from_fn(|k| 0u32.wrapping_sub(mask >> k & 1));
                <$v>::select(cast::<[u32; $n], $v>(lanes), if_set, if_clear)
            }
            #[inline(always)]
            fn call<R>(f: impl FnOnce() -> R) -> R {
                f()
            }
            // `wide` fuses where the whole build targets FMA (`-C target-cpu=native`).
            const FUSED: bool = cfg!(target_feature = "fma");
            #[inline(always)]
            fn mul_sub(self, m: Self, s: Self) -> Self {
                <$v>::mul_sub(self, m, s)
            }
        }
    };
}

wide_lanes!(f32x4, i32x4, 4);
wide_lanes!(f32x8, i32x8, 8);

/// One lane: a plain `f32`, for code written over lanes and run on one ray (the renderer's shading).
impl Lanes<1> for f32 {
    #[inline(always)]
    fn splat(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn load(a: &[f32; 1]) -> Self {
        a[0]
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 1] {
        [self]
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self - o
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self * o
    }
    #[inline(always)]
    fn le(self, o: Self) -> u32 {
        u32::from(self <= o)
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self + o
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        self / o
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        f32::sqrt(self)
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        f32::max(self, o)
    }
    #[inline(always)]
    fn neg(self) -> Self {
        -self
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f32::abs(self)
    }
    #[inline(always)]
    fn lt(self, o: Self) -> u32 {
        u32::from(self < o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> u32 {
        u32::from(self >= o)
    }
    #[inline(always)]
    fn ne(self, o: Self) -> u32 {
        u32::from(self != o)
    }
    #[inline(always)]
    fn max_bits(self, o: Self) -> Self {
        f32::from_bits((self.to_bits() as i32).max(o.to_bits() as i32) as u32)
    }
    #[inline(always)]
    fn min_bits(self, o: Self) -> Self {
        f32::from_bits((self.to_bits() as i32).min(o.to_bits() as i32) as u32)
    }
    #[inline(always)]
    fn le_bits(self, o: Self) -> u32 {
        u32::from(self.to_bits() as i32 <= o.to_bits() as i32)
    }
    #[inline(always)]
    fn select(self, if_set: Self, if_clear: Self) -> Self {
        if self.to_bits() == !0 { if_set } else { if_clear }
    }
    #[inline(always)]
    fn blend(mask: u32, if_set: Self, if_clear: Self) -> Self {
        if mask & 1 == 1 { if_set } else { if_clear }
    }
    #[inline(always)]
    fn call<R>(f: impl FnOnce() -> R) -> R {
        f()
    }
    const FUSED: bool = false;
    #[inline(always)]
    fn mul_sub(self, m: Self, s: Self) -> Self {
        self * m - s
    }
}
