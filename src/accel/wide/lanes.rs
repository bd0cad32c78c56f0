//! SIMD lanes: the one vector abstraction under the wide BVHs' kernels, the slab test written once over
//! it, and the one run-time choice of instruction set.
//!
//! A [`Lanes<N>`] value is `N` floats side by side: `wide`'s `f32x4` (one SSE register), `wide`'s
//! `f32x8` (two SSE halves, so any x86-64 CPU) and [`Avx8`] (one 256-bit register, compiled for AVX2,
//! or for AVX-512 where the CPU has it: the same kernels, with the box test's compare written straight
//! into a mask register). The single-ray kernel
//! puts a node's children in the lanes (one ray against `W` boxes); the packet kernel puts eight rays in
//! them, twice ([`Twice`]: sixteen lanes, eight rays against each of two boxes). Both call [`slab`], the same test on every lane type (its
//! distances' maximum, minimum and compare on the integers of their bits, exact on any instruction
//! set; the distances themselves one fused multiply-subtract where the lanes have FMA, a subtract and
//! a multiply where not, both rounded so that no box holding a hit is missed), so every path enters
//! every box that holds a hit and the images do not depend on the CPU (the tests compare them byte for
//! byte across the paths).
//!
//! Where the single-ray kernel enters three or more children, [`Lanes::order_entered`] orders them: a
//! stable insertion sort on every lane type but AVX-512's, which sorts them in lanes with no branch on
//! their distances (`Avx8`'s `order_entered`), in the same order.
//!
//! AVX2 and AVX-512 code is reached only through [`Isa::run8`], and an [`Isa`] that selects either is
//! made only by [`Isa::new`] after the CPU was asked: the [`Avx8`] lane type is private to this file,
//! and the [`Detected`] token that those variants carry has a private field. No other code can run
//! these instructions on a CPU without them.

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

use glam::Vec3;
use wide::bytemuck::cast;
use wide::{f32x4, f32x8, i32x4, i32x8};

use super::ChildRef;
use super::traverse::{Visit, push_ordered};
use crate::accel::stack::Stack;
use crate::geometry::ray::{Ray, SLAB_ROBUST, safe_inverse};

/// Relative outward move of a per-ray `origin · inv` for the fused slab test: 2⁻²², four times the
/// largest relative error of a product rounded to nearest (2⁻²⁴), so that after the nudge's own rounding
/// it still lies beyond the exact product.
const NUDGE: f32 = 1.0 / (1 << 22) as f32;

/// `N` floats in SIMD lanes: what the slab test and the packet kernel's bookkeeping need.
pub(super) trait Lanes<const N: usize>: Copy {
    /// `v` in every lane.
    fn splat(v: f32) -> Self;
    /// The lanes from an array.
    fn load(a: &[f32; N]) -> Self;
    /// The lanes as an array.
    fn to_array(self) -> [f32; N];
    /// Lane-wise difference.
    fn sub(self, o: Self) -> Self;
    /// Lane-wise product.
    fn mul(self, o: Self) -> Self;
    /// The bit mask of the lanes where `self <= o` (ordered: false on NaN).
    fn le(self, o: Self) -> u32;
    /// Lane-wise sum.
    fn add(self, o: Self) -> Self;
    /// Lane-wise quotient.
    fn div(self, o: Self) -> Self;
    /// Each lane with its sign bit flipped (as `wide`'s `-`).
    fn neg(self) -> Self;
    /// Each lane with its sign bit cleared (as `wide`'s `abs`).
    fn abs(self) -> Self;
    /// The bit mask of the lanes where `self < o` (ordered).
    fn lt(self, o: Self) -> u32;
    /// The bit mask of the lanes where `self >= o` (ordered).
    fn ge(self, o: Self) -> u32;
    /// The bit mask of the lanes where `self != o` (unordered: true on NaN, as SSE's `cmpneqps`).
    fn ne(self, o: Self) -> u32;
    /// Lane-wise maximum of the lanes' bits read as `i32` (Embree's `maxi`): the float order where both
    /// lanes are at least +0, and a lane that is negative (or −0) below every such lane. The slab test
    /// uses it on distances, where it costs an integer instruction's latency instead of a float one's.
    fn max_bits(self, o: Self) -> Self;
    /// Lane-wise minimum of the lanes' bits read as `i32` (see [`Lanes::max_bits`]).
    fn min_bits(self, o: Self) -> Self;
    /// The bit mask of the lanes where `self <= o`, their bits read as `i32` (see [`Lanes::max_bits`]).
    fn le_bits(self, o: Self) -> u32;
    /// Per lane, `if_set`'s where `self`'s lane is all ones, `if_clear`'s where it is all zeros.
    fn select(self, if_set: Self, if_clear: Self) -> Self;
    /// Whether [`Lanes::mul_sub`] rounds once: a fused multiply-subtract in hardware (FMA).
    const FUSED: bool;
    /// `self * m - s`, rounded once where [`Lanes::FUSED`], else twice.
    fn mul_sub(self, m: Self, s: Self) -> Self;
    /// The children a single ray entered (the lanes of `mask`, at least three, their entry distances
    /// in `self`) pushed on `stack` far to near but for the nearest, which is returned: what
    /// [`push_ordered`] does, which every lane type but AVX-512's runs.
    #[inline(always)]
    fn order_entered<const S: usize>(
        self,
        mask: u32,
        child: &[ChildRef; N],
        stack: &mut Stack<Visit, S>,
    ) -> ChildRef {
        push_ordered(self.to_array(), mask, child, stack)
    }
}

/// Eight lanes that can be filled from two halves of four: two four-triangle leaf blocks side by side
/// ([`super::tri4::Tri4::intersect_pair`]).
pub(super) trait Lanes8: Lanes<8> {
    /// Whether the eight lanes are one register: where they are two SSE halves, an eight-lane step
    /// costs two four-lane ones and more to fill (measured +1-2% instructions a ray).
    const ONE_REGISTER: bool;
    /// Lanes 0-3 from `lo`, 4-7 from `hi`.
    fn halves(lo: &[f32; 4], hi: &[f32; 4]) -> Self;
}

/// Sixteen lanes as two eight-lane values side by side, each operation done on both: the packet
/// kernel tests two children against its eight rays at once this way, so that both tests are under
/// way, interleaved, before either's result is branched on (and the slab test's choices per ray
/// packet are made once for the two). One 512-bit AVX-512 register in their place measured slower on
/// an AVX-512 CPU of the Zen 4 family, which splits such operations in two (`profiles/tried.md`).
#[derive(Clone, Copy)]
pub(super) struct Twice<L>(pub L, pub L);

/// [`Twice`]'s operations: each half's own, the lane masks side by side (the second half's bits above
/// the first's eight).
macro_rules! each_half {
    (lanes: $($f:ident),*) => {$(
        #[inline(always)]
        fn $f(self, o: Self) -> Self {
            Twice(self.0.$f(o.0), self.1.$f(o.1))
        }
    )*};
    (mask: $($f:ident),*) => {$(
        #[inline(always)]
        fn $f(self, o: Self) -> u32 {
            self.0.$f(o.0) | self.1.$f(o.1) << 8
        }
    )*};
    (unary: $($f:ident),*) => {$(
        #[inline(always)]
        fn $f(self) -> Self {
            Twice(self.0.$f(), self.1.$f())
        }
    )*};
}

impl<L: Lanes8> Lanes<16> for Twice<L> {
    #[inline(always)]
    fn splat(v: f32) -> Self {
        Twice(L::splat(v), L::splat(v))
    }
    #[inline(always)]
    fn load(a: &[f32; 16]) -> Self {
        let (lo, hi) = a.split_at(8);
        Twice(
            L::load(lo.try_into().expect("eight")),
            L::load(hi.try_into().expect("eight")),
        )
    }
    #[inline(always)]
    fn to_array(self) -> [f32; 16] {
        let mut out = [0.0; 16];
        out[..8].copy_from_slice(&self.0.to_array());
        out[8..].copy_from_slice(&self.1.to_array());
        out
    }
    each_half!(lanes: sub, mul, add, div, max_bits, min_bits);
    each_half!(mask: le, lt, ge, ne, le_bits);
    each_half!(unary: neg, abs);
    #[inline(always)]
    fn select(self, if_set: Self, if_clear: Self) -> Self {
        Twice(
            self.0.select(if_set.0, if_clear.0),
            self.1.select(if_set.1, if_clear.1),
        )
    }
    const FUSED: bool = L::FUSED;
    #[inline(always)]
    fn mul_sub(self, m: Self, s: Self) -> Self {
        Twice(self.0.mul_sub(m.0, s.0), self.1.mul_sub(m.1, s.1))
    }
}

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

/// Eight lanes in one 256-bit register. Values of this type exist only inside [`run_avx2`] (`MASK`
/// false) and [`run_avx512`] (`MASK` true), which run only on CPUs with those instructions (a
/// [`Detected`] token is proof of that); those functions are compiled for them, so these intrinsics
/// inline into the kernels they run. With `MASK`, the ordered `<=` of the slab test is one AVX-512VL
/// compare into a mask register instead of a compare and a `movmskps`: the same bits.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
struct Avx8<const MASK: bool>(__m256);

/// `unsafe` blocks of [`Avx8`]'s methods: each is an AVX intrinsic (AVX-512VL for the masked compare),
/// reached only from [`run_avx2`] or [`run_avx512`].
#[cfg(target_arch = "x86_64")]
macro_rules! avx {
    ($e:expr) => {
        // SAFETY: `Avx8` is used only by code that `run_avx2` or `run_avx512` runs, on CPUs with AVX2
        // (and AVX-512 F and VL for `Avx8<true>`, the only user of AVX-512 intrinsics; see the type).
        unsafe { $e }
    };
}

#[cfg(target_arch = "x86_64")]
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
    const FUSED: bool = true;
    #[inline(always)]
    fn mul_sub(self, m: Self, s: Self) -> Self {
        Avx8(avx!(_mm256_fmsub_ps(self.0, m.0, s.0)))
    }
    /// Without `MASK`, [`push_ordered`]. With it (AVX-512 F), without a branch on the children's
    /// distances: each lane's key is its distance's bits above `7 - lane` (so that among equal
    /// distances the later lane sorts nearer, as [`push_ordered`]'s stable sort has it), the entered
    /// lanes' keys are compressed into the low lanes (`vpcompressq` into a register: the compress-store
    /// to memory is slow on some CPUs), the rest filled with the largest key, and sorted nearest first
    /// by Batcher's odd-even merge network (Knuth, *TAOCP* vol. 3, 5.3.4): the optimal network for four
    /// on each half, (0,1)(2,3), (0,2)(1,3), (1,2), then, only for more than four children, the merge
    /// of the halves, (0,4)(1,5)(2,6)(3,7), (2,4)(3,5), (1,2)(3,4)(5,6); each layer a permute, a max
    /// and a masked min. Lane 0 is the nearest; the others get their children back through their
    /// keys' lane numbers and are stored far to near in one masked store.
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
        let n = mask.count_ones() as usize;
        // SAFETY: reached only where `MASK`, i.e. from `run_avx512` on a CPU with AVX-512 F and VL
        // (see the type); the masked store writes the `n - 1` entries `push_written` makes room for.
        unsafe {
            // Lane k holds 7 - k: a key's tie-breaker, and the index that reverses the lanes.
            let reverse = _mm512_set_epi64(0, 1, 2, 3, 4, 5, 6, 7);
            let bits = _mm512_cvtepu32_epi64(_mm256_castps_si256(self.0));
            let keys = _mm512_or_si512(_mm512_slli_epi64::<32>(bits), reverse);
            let mut s = _mm512_mask_compress_epi64(_mm512_set1_epi64(i64::MAX), mask as u8, keys);
            // One layer: lane k's partner is `p`'s lane k; the lower of each pair (`low`) takes the min.
            // (A macro, not a closure: a closure is not compiled for AVX-512 and would call the
            // intrinsics out of line.)
            macro_rules! layer {
                ($s:expr, $p:expr, $low:expr) => {{
                    let p = $p;
                    _mm512_mask_min_epi64(_mm512_max_epi64($s, p), $low, $s, p)
                }};
            }
            s = layer!(s, _mm512_shuffle_epi32::<0x4e>(s), 0b0101_0101);
            s = layer!(s, _mm512_permutex_epi64::<0x4e>(s), 0b0011_0011);
            s = layer!(s, _mm512_permutex_epi64::<0xd8>(s), 0b0010_0010);
            if n > 4 {
                s = layer!(s, _mm512_shuffle_i64x2::<0x4e>(s, s), 0b0000_1111);
                let p = _mm512_permutexvar_epi64(_mm512_set_epi64(7, 6, 3, 2, 5, 4, 1, 0), s);
                s = layer!(s, p, 0b0000_1100);
                let p = _mm512_permutexvar_epi64(_mm512_set_epi64(7, 5, 6, 3, 4, 1, 2, 0), s);
                s = layer!(s, p, 0b0010_1010);
            }
            let nearest = child[(_mm_cvtsi128_si64(_mm512_castsi512_si128(s)) as usize & 7) ^ 7];
            // Each sorted key's child (lane 7 - key's low bits), its distance kept above: `Visit`s.
            let children = _mm512_cvtepu32_epi64(_mm256_loadu_si256(child.as_ptr().cast()));
            let by_key = _mm512_permutexvar_epi64(s, _mm512_permutexvar_epi64(reverse, children));
            let visits = _mm512_ternarylogic_epi64::<0xea>(s, _mm512_set1_epi64(-1 << 32), by_key);
            // Sorted lanes n - 1 down to 1 into stack slots 0 up to n - 2: the farthest deepest.
            let down = _mm512_sub_epi64(
                _mm512_set1_epi64(n as i64 - 1),
                _mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0),
            );
            let far_first = _mm512_permutexvar_epi64(down, visits);
            stack.push_written(n - 1, |at| {
                _mm512_mask_storeu_epi64(at.cast(), (1u8 << (n - 1)) - 1, far_first)
            });
            nearest
        }
    }
}

#[cfg(target_arch = "x86_64")]
impl<const MASK: bool> Lanes8 for Avx8<MASK> {
    const ONE_REGISTER: bool = true;

    #[inline(always)]
    fn halves(lo: &[f32; 4], hi: &[f32; 4]) -> Self {
        // Two unaligned loads of four floats from four-float arrays, into one register.
        Avx8(avx!(_mm256_loadu2_m128(hi.as_ptr(), lo.as_ptr())))
    }
}

#[cfg(target_arch = "x86_64")]
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

/// The instruction sets a wide BVH's kernels can run on (the public name of a choice; `Isa` is the
/// checked one).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simd {
    /// Baseline x86-64 SSE (or whatever `wide` maps to elsewhere): runs on every CPU.
    Portable,
    /// 256-bit AVX2 (with FMA, and the BMI1 and POPCNT bit instructions that every AVX2 CPU has) for
    /// eight lanes: detected at run time.
    Avx2,
    /// The AVX2 kernels compiled for AVX-512 (F and VL): mask registers for the box tests' results;
    /// detected at run time.
    Avx512,
}

impl Simd {
    /// The best the running CPU has.
    pub fn detect() -> Simd {
        Isa::detect().simd()
    }

    /// True if the running CPU can execute it.
    pub fn available(self) -> bool {
        Isa::new(self).is_some()
    }
}

/// Proof that the running CPU has the instructions of the [`Isa`] variant that carries it: made only
/// by [`Isa::new`], after asking the CPU.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Detected {
    _private: (),
}

/// A checked instruction set: what the kernels dispatch on, once per ray or packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Isa {
    /// `wide`'s lanes: any CPU.
    Portable,
    /// AVX2, FMA, BMI1 and POPCNT, with the proof that the CPU has them.
    #[cfg(target_arch = "x86_64")]
    Avx2(Detected),
    /// AVX-512 F and VL besides the above, with the proof.
    #[cfg(target_arch = "x86_64")]
    Avx512(Detected),
}

impl Isa {
    /// The best the running CPU has.
    pub fn detect() -> Isa {
        Isa::new(Simd::Avx512)
            .or_else(|| Isa::new(Simd::Avx2))
            .unwrap_or(Isa::Portable)
    }

    /// `simd` if the running CPU has it.
    pub fn new(simd: Simd) -> Option<Isa> {
        #[cfg(target_arch = "x86_64")]
        let avx2 = || {
            is_x86_feature_detected!("avx2")
                && is_x86_feature_detected!("fma")
                && is_x86_feature_detected!("bmi1")
                && is_x86_feature_detected!("popcnt")
        };
        match simd {
            Simd::Portable => Some(Isa::Portable),
            #[cfg(target_arch = "x86_64")]
            Simd::Avx2 => avx2().then_some(Isa::Avx2(Detected { _private: () })),
            #[cfg(target_arch = "x86_64")]
            Simd::Avx512 => {
                (avx2() && is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl"))
                    .then_some(Isa::Avx512(Detected { _private: () }))
            }
            #[cfg(not(target_arch = "x86_64"))]
            Simd::Avx2 | Simd::Avx512 => None,
        }
    }

    /// The public name of this instruction set.
    pub fn simd(self) -> Simd {
        match self {
            Isa::Portable => Simd::Portable,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2(_) => Simd::Avx2,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512(_) => Simd::Avx512,
        }
    }

    /// Runs `k` on eight-lane vectors of this instruction set: the one run-time dispatch of the
    /// kernels.
    #[inline(always)]
    pub fn run8<K: OnLanes8>(self, k: K) -> K::Output {
        match self {
            // SAFETY: a `Detected` token exists only if the CPU has the variant's instructions
            // (`Isa::new`).
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2(_) => unsafe { run_avx2(k) },
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512(_) => unsafe { run_avx512(k) },
            Isa::Portable => k.run::<f32x8>(),
        }
    }
}

/// A kernel over eight-lane vectors, for [`Isa::run8`] to run on the lane type it chose.
pub(super) trait OnLanes8 {
    type Output;
    fn run<L: Lanes8>(self) -> Self::Output;
}

/// `k` compiled for AVX2 (the whole kernel, so that its intrinsics and `wide`'s operations inline into
/// one AVX2 function), on one 256-bit register per eight lanes.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,popcnt")]
fn run_avx2<K: OnLanes8>(k: K) -> K::Output {
    k.run::<Avx8<false>>()
}

/// `k` compiled for AVX-512 F and VL (as a `target-cpu=native` build would compile it on such a CPU:
/// EVEX encodings, 32 vector registers, mask registers), on the same 256-bit lanes.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,popcnt,avx512f,avx512vl")]
fn run_avx512<K: OnLanes8>(k: K) -> K::Output {
    k.run::<Avx8<true>>()
}

/// Rays prepared for slab tests (Kay and Kajiya 1986): per axis their origins and (Embree's
/// [`safe_inverse`]) inverse directions in lanes, splatted for one ray or side by side for a packet, the
/// inverse directions again scaled by [`SLAB_ROBUST`] for the exit planes, what each distance
/// subtracts ([`shifts`]: the origin, or for [`slab`]'s fused form the origin times each inverse), and
/// per axis whether the max
/// plane is the near one (Embree's near/far plane selection, once per ray or packet rather than a min/max
/// per box). When a packet's rays disagree in a sign (`mixed`), each lane picks its own planes by its
/// own sign (`negative`: all ones in the lanes whose inverse direction is negative), so that every lane
/// computes what the single-ray test computes for its ray.
pub(super) struct SlabRays<V> {
    inv: [V; 3],
    inv_far: [V; 3],
    shift: [V; 3],
    shift_far: [V; 3],
    negative: [V; 3],
    flip: [bool; 3],
    mixed: bool,
}

impl<V> SlabRays<V> {
    /// One ray in every lane.
    #[inline(always)]
    pub fn splat<const N: usize>(ray: &Ray) -> Self
    where
        V: Lanes<N>,
    {
        Self::one(&SlabRay::new::<N, V>(ray))
    }

    /// One ray prepared beforehand ([`SlabRay`]) in every lane.
    #[inline(always)]
    pub fn one<const N: usize>(r: &SlabRay) -> Self
    where
        V: Lanes<N>,
    {
        let lanes = |v: Vec3| [V::splat(v.x), V::splat(v.y), V::splat(v.z)];
        SlabRays {
            inv: lanes(r.inv),
            inv_far: lanes(r.inv_far),
            shift: lanes(r.shift),
            shift_far: lanes(r.shift_far),
            negative: [V::splat(0.0); 3],
            flip: [r.inv.x < 0.0, r.inv.y < 0.0, r.inv.z < 0.0],
            mixed: false,
        }
    }

    /// Eight rays, one per lane; the signs of the rays in `live` choose the planes.
    #[inline(always)]
    pub fn packet(rays: &[Ray; 8], live: u32) -> Self
    where
        V: Lanes<8>,
    {
        // Plain loops and explicit arrays: `map` and `from_fn` closures over arrays were left out of
        // line here, outside the AVX2 compile (callgrind).
        let (mut shift, mut shift_far) = ([[0.0f32; 8]; 3], [[0.0f32; 8]; 3]);
        let (mut inv, mut inv_far, mut sign_mask, mut negative) =
            ([[0.0f32; 8]; 3], [[0.0f32; 8]; 3], [[0.0f32; 8]; 3], [0u32; 3]);
        for (k, r) in rays.iter().enumerate() {
            let i = safe_inverse(r.dir);
            for a in 0..3 {
                inv[a][k] = i[a];
                inv_far[a][k] = i[a] * SLAB_ROBUST;
                (shift[a][k], shift_far[a][k]) = shifts::<8, V>(r.origin[a], i[a], inv_far[a][k]);
                sign_mask[a][k] = f32::from_bits(if i[a] < 0.0 { u32::MAX } else { 0 });
                negative[a] |= u32::from(i[a] < 0.0) << k;
            }
        }
        let negative = [negative[0] & live, negative[1] & live, negative[2] & live];
        SlabRays {
            inv: [V::load(&inv[0]), V::load(&inv[1]), V::load(&inv[2])],
            inv_far: [V::load(&inv_far[0]), V::load(&inv_far[1]), V::load(&inv_far[2])],
            shift: [V::load(&shift[0]), V::load(&shift[1]), V::load(&shift[2])],
            shift_far: [
                V::load(&shift_far[0]),
                V::load(&shift_far[1]),
                V::load(&shift_far[2]),
            ],
            negative: [
                V::load(&sign_mask[0]),
                V::load(&sign_mask[1]),
                V::load(&sign_mask[2]),
            ],
            flip: [negative[0] != 0, negative[1] != 0, negative[2] != 0],
            mixed: negative.iter().any(|&m| m != 0 && m != live),
        }
    }
}

/// One ray's slab-test values as plain numbers ([`SlabRays`] before they are splatted): 48 bytes a ray,
/// where the splatted lanes take 480, for the stream kernel to keep one per ray of its stream and splat
/// at each node test (the division of the inverse is then once per ray, not once per node).
#[derive(Clone, Copy, Debug)]
pub(super) struct SlabRay {
    inv: Vec3,
    inv_far: Vec3,
    shift: Vec3,
    shift_far: Vec3,
}

impl SlabRay {
    /// `ray` prepared for the slab tests of lanes `V`.
    #[inline(always)]
    pub fn new<const N: usize, V: Lanes<N>>(ray: &Ray) -> Self {
        let inv = safe_inverse(ray.dir);
        let inv_far = inv * SLAB_ROBUST;
        let (mut shift, mut shift_far) = (Vec3::ZERO, Vec3::ZERO);
        for a in 0..3 {
            (shift[a], shift_far[a]) = shifts::<N, V>(ray.origin[a], inv[a], inv_far[a]);
        }
        SlabRay {
            inv,
            inv_far,
            shift,
            shift_far,
        }
    }
}

impl<L: Lanes8> SlabRays<L> {
    /// The same rays twice, in lanes 0-7 and 8-15: for testing two boxes against them at once.
    #[inline(always)]
    pub fn doubled(&self) -> SlabRays<Twice<L>> {
        SlabRays {
            inv: two(&self.inv),
            inv_far: two(&self.inv_far),
            shift: two(&self.shift),
            shift_far: two(&self.shift_far),
            negative: two(&self.negative),
            flip: self.flip,
            mixed: self.mixed,
        }
    }
}

/// Each of three lanes twice.
#[inline(always)]
fn two<L: Lanes8>(v: &[L; 3]) -> [Twice<L>; 3] {
    [Twice(v[0], v[0]), Twice(v[1], v[1]), Twice(v[2], v[2])]
}

/// What one ray's entry and exit distances subtract on one axis, given its origin, inverse direction
/// and exit inverse on that axis: the origin itself where `V` subtracts before multiplying; where it
/// fuses, `origin · inv` rounded up and `origin · inv_far` rounded down by [`NUDGE`] ([`slab`]).
#[inline(always)]
fn shifts<const N: usize, V: Lanes<N>>(origin: f32, inv: f32, inv_far: f32) -> (f32, f32) {
    if V::FUSED {
        let (near, far) = (origin * inv, origin * inv_far);
        (near + near.abs() * NUDGE, far - far.abs() * NUDGE)
    } else {
        (origin, origin)
    }
}

/// The slab test: each lane's entry distance into its box and the mask of lanes whose ray enters it
/// within `[t_min, t_max]`, for `t_min >= +0`. `plane(axis, max)` gives the boxes' min or max planes on
/// `axis` in lanes (a node's children side by side, or one child splatted).
///
/// The exit planes' distances are taken with the inverse direction scaled by [`SLAB_ROBUST`] (Ize 2013,
/// "Robust BVH Ray Traversal", rounds the reciprocal up in the same way), so that rounding never rejects
/// a primitive touching the box; the scale is then off the path from a node's load to its mask. The
/// distances are compared as the integers of their bits (Embree's `maxi`/`mini`): with the `t_min` lane
/// at least +0, the entry is the float maximum and a negative exit (the box behind the ray) stays below
/// it, while each step is a one-cycle integer instruction where `maxps` and `cmpps` take four (a single
/// ray's traversal is a chain of such steps, node to child). The one difference from float compares is
/// −0, which counts as negative: a box left exactly at the origin is not entered; it holds no point at
/// `t > t_min`. An empty slot's inverted box gives an entry of +∞ above any exit.
///
/// Where the lanes have FMA ([`Lanes::FUSED`]) a distance is one fused `plane · inv − origin · inv`
/// (Embree's `msub` with its `org_rdir`) instead of a subtract and a multiply: one step fewer on the
/// chain from a node's load to its mask. `origin · inv` is rounded once per ray, so it is moved outward
/// by [`NUDGE`] of itself (more than its rounding error), up for the entries and down for the exits
/// (the box grows by about 2⁻²¹ of the origin's coordinates): what is left is each distance's own final
/// rounding, relative to the distance, which the exits' [`SLAB_ROBUST`] covers as it covers the
/// unfused form's. Lanes without FMA would round `plane · inv` too, an error relative to the plane,
/// not to the distance, so they subtract first. The two forms can differ in the last bits of an entry
/// distance, and so in the order of two children entered at the same distance; not in whether a box
/// that holds a hit is entered.
#[inline(always)]
pub(super) fn slab<const N: usize, V: Lanes<N>>(
    rays: &SlabRays<V>,
    plane: impl Fn(usize, bool) -> V,
    t_min: V,
    t_max: V,
) -> (V, u32) {
    let (mut near, mut far) = ([t_min; 3], [t_max; 3]);
    for axis in 0..3 {
        let flip = rays.flip[axis];
        let (entry, exit) = if rays.mixed {
            let (lo, hi, neg) = (plane(axis, false), plane(axis, true), rays.negative[axis]);
            (neg.select(hi, lo), neg.select(lo, hi))
        } else {
            (plane(axis, flip), plane(axis, !flip))
        };
        if V::FUSED {
            near[axis] = entry.mul_sub(rays.inv[axis], rays.shift[axis]);
            far[axis] = exit.mul_sub(rays.inv_far[axis], rays.shift_far[axis]);
        } else {
            near[axis] = entry.sub(rays.shift[axis]).mul(rays.inv[axis]);
            far[axis] = exit.sub(rays.shift[axis]).mul(rays.inv_far[axis]);
        }
    }
    // Two levels of pairs rather than a chain of four: the chain's latency is the traversal's.
    let near = near[0].max_bits(near[1]).max_bits(near[2].max_bits(t_min));
    let far = far[0].min_bits(far[1]).min_bits(far[2].min_bits(t_max));
    (near, near.le_bits(far))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::ray::testing::TestRng;

    /// [`slab`] over eight boxes on the lanes [`Isa::run8`] picks: entry distances and mask.
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
    /// [`Isa::run8`] picks: whether the two agree bit for bit, entries and masks.
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
        let isas: Vec<Isa> = [Simd::Portable, Simd::Avx2, Simd::Avx512]
            .into_iter()
            .filter_map(Isa::new)
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
            let boxes: [[f32; 2]; 6] = std::array::from_fn(|row| {
                corners.map(|(lo, hi)| if row < 3 { lo[row] } else { hi[row - 3] })
            });
            let live = if case % 3 == 0 {
                rng.below(256) as u32
            } else {
                0xff
            };
            for &isa in &isas {
                assert!(
                    isa.run8(Pairs {
                        rays: &rays,
                        live,
                        boxes: &boxes,
                        t_max: 4.0,
                    }),
                    "{:?}: case {case}",
                    isa.simd()
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

    /// [`Lanes::order_entered`] on the lanes [`Isa::run8`] picks: the nearest child and the stack.
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
        let isas: Vec<Isa> = [Simd::Portable, Simd::Avx2, Simd::Avx512]
            .into_iter()
            .filter_map(Isa::new)
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
            for &isa in &isas {
                let (nearest, popped) = isa.run8(Order {
                    t: &t,
                    mask,
                    child: &child,
                });
                assert_eq!(nearest, child[lanes[0]], "{:?}: case {case}", isa.simd());
                assert_eq!(popped, want, "{:?}: case {case}", isa.simd());
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
        let isas: Vec<Isa> = [Simd::Portable, Simd::Avx2, Simd::Avx512]
            .into_iter()
            .filter_map(|s| {
                let isa = Isa::new(s);
                if isa.is_none() {
                    eprintln!("this CPU lacks {s:?}: its slab test is not checked here");
                }
                isa
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
            for &isa in &isas {
                let (_, mask) = isa.run8(Slab8 {
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
                            isa.simd()
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
            for s in [Simd::Portable, Simd::Avx2, Simd::Avx512] {
                let Some(isa) = Isa::new(s) else { continue };
                let (_, mask) = isa.run8(Slab8 {
                    ray: &ray,
                    boxes: &boxes,
                    t_max: 8.0,
                });
                assert_eq!(mask, 0, "{s:?}: case {case}");
            }
        }
    }
}
