//! SIMD lanes: the one vector abstraction under the wide BVHs' kernels.
//!
//! A [`Lanes<N>`] value is `N` floats side by side: `wide`'s `f32x4` (one SSE register) and `f32x8`
//! (two SSE halves, so any x86-64 CPU) in [`portable`], and `avx`'s eight lanes in one 256-bit register
//! (compiled for AVX2, or for AVX-512 where the CPU has it: the same kernels, with the box test's
//! compare written straight into a mask register). The single-ray kernel puts a node's children in the
//! lanes (one ray against `W` boxes); the packet kernel puts eight rays in them, twice ([`Twice`]:
//! sixteen lanes, eight rays against each of two boxes). A kernel is written once as an [`OnLanes8`]
//! and run on the lane type that `super::isa` chose for the CPU.

#[cfg(target_arch = "x86_64")]
mod avx;
mod portable;
#[cfg(test)]
mod tests;

#[cfg(target_arch = "x86_64")]
pub(super) use avx::{run_avx2, run_avx512};

use super::ChildRef;
use super::order::{Visit, push_ordered};
use crate::accel::stack::Stack;

/// `N` floats in SIMD lanes: what the slab test, the packet kernel's bookkeeping and the renderer's
/// shading need. Arithmetic is IEEE's, lane by lane and never fused (but [`Lanes::mul_sub`]), so a
/// computation gives the same bits on every lane type and in scalar code.
pub(crate) trait Lanes<const N: usize>: Copy {
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
    /// Lane-wise square root.
    fn sqrt(self) -> Self;
    /// Lane-wise maximum; `o`'s lane where `self`'s is NaN (`f32::max` where `o` is a number).
    fn max(self, o: Self) -> Self;
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
    /// Per lane, `if_set`'s where the lane's bit of `mask` is set, else `if_clear`'s.
    fn blend(mask: u32, if_set: Self, if_clear: Self) -> Self;
    /// `f()` compiled for this lane type's instruction set: how code over these lanes that is not
    /// inlined into the kernel that chose them (a recursive call, a phase kept apart for the
    /// profiles) stays on their instructions instead of calling each one out of line.
    fn call<R>(f: impl FnOnce() -> R) -> R;
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
pub(crate) trait Lanes8: Lanes<8> {
    /// Whether the eight lanes are one register: where they are two SSE halves, an eight-lane step
    /// costs two four-lane ones and more to fill (`profiles/README.md`).
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
    each_half!(lanes: sub, mul, add, div, max, max_bits, min_bits);
    each_half!(mask: le, lt, ge, ne, le_bits);
    each_half!(unary: neg, abs, sqrt);
    #[inline(always)]
    fn select(self, if_set: Self, if_clear: Self) -> Self {
        Twice(
            self.0.select(if_set.0, if_clear.0),
            self.1.select(if_set.1, if_clear.1),
        )
    }
    #[inline(always)]
    fn blend(mask: u32, if_set: Self, if_clear: Self) -> Self {
        Twice(
            L::blend(mask, if_set.0, if_clear.0),
            L::blend(mask >> 8, if_set.1, if_clear.1),
        )
    }
    #[inline(always)]
    fn call<R>(f: impl FnOnce() -> R) -> R {
        L::call(f)
    }
    const FUSED: bool = L::FUSED;
    #[inline(always)]
    fn mul_sub(self, m: Self, s: Self) -> Self {
        Twice(self.0.mul_sub(m.0, s.0), self.1.mul_sub(m.1, s.1))
    }
}

/// A kernel over eight-lane vectors, for `Simd::run8` to run on the lane type it chose.
pub(crate) trait OnLanes8 {
    type Output;
    fn run<L: Lanes8>(self) -> Self::Output;
}
