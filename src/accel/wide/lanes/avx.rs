//! Eight lanes in one 256-bit register, for AVX2 and AVX-512. The lane type is private to this file
//! and reached only through [`run_avx2`] and [`run_avx512`], which `super::super::isa` calls only after
//! the CPU said it has their instructions: no other code can run them on a CPU without them.

use std::arch::x86_64::*;

use super::super::ChildRef;
use super::super::order::{Visit, network_avx512, push_ordered};
use super::{Lanes, Lanes8, OnLanes8};
use crate::accel::stack::Stack;

/// Eight lanes in one 256-bit register. Values of this type exist only inside [`run_avx2`] (`MASK`
/// false) and [`run_avx512`] (`MASK` true), which run only on CPUs with those instructions (`super::super::isa`'s
/// detection token is proof of that); those functions are compiled for them, so these intrinsics
/// inline into the kernels they run. With `MASK`, the ordered `<=` of the slab test is one AVX-512VL
/// compare into a mask register instead of a compare and a `movmskps`: the same bits.
#[derive(Clone, Copy)]
struct Avx8<const MASK: bool>(__m256);

/// `unsafe` blocks of [`Avx8`]'s methods: each is an AVX intrinsic (AVX-512VL for the masked compare),
/// reached only from [`run_avx2`] or [`run_avx512`].
macro_rules! avx {
    ($e:expr) => {
        // SAFETY: `Avx8` is used only by code that `run_avx2` or `run_avx512` runs, on CPUs with AVX2
        // (and AVX-512 F and VL for `Avx8<true>`, the only user of AVX-512 intrinsics; see the type).
        unsafe { $e }
    };
}

impl<const MASK: bool> Lanes<8> for Avx8<MASK> {
    #[inline(always)]
    fn splat(v: f32) -> Self {
        Avx8(avx!(_mm256_set1_ps(v)))
    }
    #[inline(always)]
    fn load(a: &[f32; 8]) -> Self {
        // An unaligned load of eight floats from an eight-float array.
        Avx8(avx!(_mm256_loadu_ps(a.as_ptr())))
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 8] {
        let mut out = [0.0f32; 8];
        // An unaligned store of eight floats into an eight-float array.
        avx!(_mm256_storeu_ps(out.as_mut_ptr(), self.0));
        out
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Avx8(avx!(_mm256_sub_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        Avx8(avx!(_mm256_mul_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn le(self, o: Self) -> u32 {
        self.cmp::<_CMP_LE_OQ>(o)
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Avx8(avx!(_mm256_add_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        Avx8(avx!(_mm256_div_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Avx8(avx!(_mm256_sqrt_ps(self.0)))
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        // `maxps` gives its second operand where either is NaN: `o`'s where `self`'s is NaN.
        Avx8(avx!(_mm256_max_ps(self.0, o.0)))
    }
    #[inline(always)]
    fn neg(self) -> Self {
        Avx8(avx!(_mm256_xor_ps(self.0, _mm256_set1_ps(-0.0))))
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Avx8(avx!(_mm256_andnot_ps(_mm256_set1_ps(-0.0), self.0)))
    }
    #[inline(always)]
    fn lt(self, o: Self) -> u32 {
        self.cmp::<_CMP_LT_OQ>(o)
    }
    #[inline(always)]
    fn ge(self, o: Self) -> u32 {
        self.cmp::<_CMP_GE_OQ>(o)
    }
    #[inline(always)]
    fn ne(self, o: Self) -> u32 {
        self.cmp::<_CMP_NEQ_UQ>(o)
    }
    #[inline(always)]
    fn max_bits(self, o: Self) -> Self {
        Avx8(avx!(_mm256_castsi256_ps(_mm256_max_epi32(
            _mm256_castps_si256(self.0),
            _mm256_castps_si256(o.0)
        ))))
    }
    #[inline(always)]
    fn min_bits(self, o: Self) -> Self {
        Avx8(avx!(_mm256_castsi256_ps(_mm256_min_epi32(
            _mm256_castps_si256(self.0),
            _mm256_castps_si256(o.0)
        ))))
    }
    #[inline(always)]
    fn le_bits(self, o: Self) -> u32 {
        let (a, b) = avx!((_mm256_castps_si256(self.0), _mm256_castps_si256(o.0)));
        if MASK {
            u32::from(avx!(_mm256_cmple_epi32_mask(a, b)))
        } else {
            let gt = avx!(_mm256_castsi256_ps(_mm256_cmpgt_epi32(a, b)));
            !(avx!(_mm256_movemask_ps(gt)) as u32) & 0xff
        }
    }
    #[inline(always)]
    fn select(self, if_set: Self, if_clear: Self) -> Self {
        Avx8(avx!(_mm256_blendv_ps(if_clear.0, if_set.0, self.0)))
    }
    #[inline(always)]
    fn blend(mask: u32, if_set: Self, if_clear: Self) -> Self {
        if MASK {
            return Avx8(avx!(_mm256_mask_blend_ps(mask as u8, if_clear.0, if_set.0)));
        }
        // Each lane's bit of the mask, tested in the lane.
        let bits = avx!(_mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128));
        let lanes = avx!(_mm256_cmpeq_epi32(
            _mm256_and_si256(_mm256_set1_epi32(mask as i32), bits),
            bits
        ));
        Avx8(avx!(_mm256_blendv_ps(
            if_clear.0,
            if_set.0,
            _mm256_castsi256_ps(lanes)
        )))
    }
    #[inline(always)]
    fn call<R>(f: impl FnOnce() -> R) -> R {
        // SAFETY: values of `Avx8<MASK>` exist only on a CPU with `MASK`'s instructions (see the type).
        unsafe { if MASK { with_avx512(f) } else { with_avx2(f) } }
    }
    const FUSED: bool = true;
    #[inline(always)]
    fn mul_sub(self, m: Self, s: Self) -> Self {
        Avx8(avx!(_mm256_fmsub_ps(self.0, m.0, s.0)))
    }
    /// Without `MASK`, [`push_ordered`]; with it (AVX-512 F), [`network_avx512`]: the same order
    /// without a branch on the children's distances.
    #[inline(always)]
    fn order_entered<const S: usize>(
        self,
        mask: u32,
        child: &[ChildRef; 8],
        stack: &mut Stack<Visit, S>,
    ) -> ChildRef {
        if !MASK {
            return push_ordered(self.to_array(), mask, child, stack);
        }
        // SAFETY: `MASK` lanes exist only inside `run_avx512`, on a CPU with AVX-512 F and VL.
        unsafe { network_avx512(self.0, mask, child, stack) }
    }
}

impl<const MASK: bool> Lanes8 for Avx8<MASK> {
    const ONE_REGISTER: bool = true;

    #[inline(always)]
    fn halves(lo: &[f32; 4], hi: &[f32; 4]) -> Self {
        // Two unaligned loads of four floats from four-float arrays, into one register.
        Avx8(avx!(_mm256_loadu2_m128(hi.as_ptr(), lo.as_ptr())))
    }
}

impl<const MASK: bool> Avx8<MASK> {
    /// The bit mask of the lanes where `self OP o`: with `MASK`, one compare into a mask register.
    #[inline(always)]
    fn cmp<const OP: i32>(self, o: Self) -> u32 {
        if MASK {
            u32::from(avx!(_mm256_cmp_ps_mask::<OP>(self.0, o.0)))
        } else {
            avx!(_mm256_movemask_ps(_mm256_cmp_ps::<OP>(self.0, o.0))) as u32
        }
    }
}

/// `f()` compiled for AVX2, for [`Lanes::call`] (`f` inlined into it, and its intrinsics with it). A
/// function of its own, never inlined, so that the profiles see each body by its closure's name.
#[inline(never)]
#[target_feature(enable = "avx2,fma,bmi1,popcnt")]
unsafe fn with_avx2<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// `f()` compiled for AVX-512 F and VL, for [`Lanes::call`], never inlined.
#[inline(never)]
#[target_feature(enable = "avx2,fma,bmi1,popcnt,avx512f,avx512vl")]
unsafe fn with_avx512<R>(f: impl FnOnce() -> R) -> R {
    f()
}

/// `k` compiled for AVX2 (the whole kernel, so that its intrinsics and `wide`'s operations inline into
/// one AVX2 function), on one 256-bit register per eight lanes.
#[target_feature(enable = "avx2,fma,bmi1,popcnt")]
pub(in crate::accel::wide) unsafe fn run_avx2<K: OnLanes8>(k: K) -> K::Output {
    k.run::<Avx8<false>>()
}

/// `k` compiled for AVX-512 F and VL (as a `target-cpu=native` build would compile it on such a CPU:
/// EVEX encodings, 32 vector registers, mask registers), on the same 256-bit lanes.
#[target_feature(enable = "avx2,fma,bmi1,popcnt,avx512f,avx512vl")]
pub(in crate::accel::wide) unsafe fn run_avx512<K: OnLanes8>(k: K) -> K::Output {
    k.run::<Avx8<true>>()
}
