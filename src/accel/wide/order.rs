//! The order in which a ray visits the children it entered, shared by the single-ray, packet and
//! stream kernels: nearest first for closest hit, the farther ones kept on the stack far to near.

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

use super::ChildRef;
use crate::accel::stack::Stack;

/// A single ray's stack entry: a child to visit and the ray's entry distance into its box. Eight bytes,
/// the child first, so that an entry is one 64-bit lane of the AVX-512 child order ([`network_avx512`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(8))]
pub(crate) struct Visit {
    pub child: ChildRef,
    pub t: f32,
}

/// The children a single ray entered (the lanes of `mask`, at least three) with their entry distances
/// `t`: all but the nearest pushed far to near ([`sort_far_to_near`], so among equal distances the later
/// lane is nearer), the nearest returned. What `Lanes::order_entered` runs on every lane type but AVX-512's.
#[inline(always)]
pub(super) fn push_ordered<const N: usize, const S: usize>(
    t: [f32; N],
    mut mask: u32,
    child: &[ChildRef; N],
    stack: &mut Stack<Visit, S>,
) -> ChildRef {
    let start = stack.len();
    while mask != 0 {
        let k = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        stack.push(Visit {
            child: child[k],
            t: t[k],
        });
    }
    sort_far_to_near(stack.above_mut(start), |e| e.t);
    stack.pop().expect("just pushed").child
}

/// Sorts the 2 to 8 entries one node pushed by decreasing entry distance `key`, so that the nearest is
/// popped first (insertion sort: at most six compares for four, and a ray enters more than four of
/// eight children rarely). Both kernels order their stacks with it.
#[inline(always)]
pub(super) fn sort_far_to_near<T>(run: &mut [T], key: impl Fn(&T) -> f32) {
    for i in 1..run.len() {
        let mut j = i;
        while j > 0 && key(&run[j - 1]) < key(&run[j]) {
            run.swap(j - 1, j);
            j -= 1;
        }
    }
}

/// The children a single ray entered (the lanes of `mask`, at least three, their entry distances in
/// `t`) ordered as [`push_ordered`] orders them, without a branch on their distances:
/// each lane's key is its distance's bits above `7 - lane` (so that among equal
/// distances the later lane sorts nearer, as [`push_ordered`]'s stable sort has it), the entered
/// lanes' keys are compressed into the low lanes (`vpcompressq` into a register: the compress-store
/// to memory is slow on some CPUs), the rest filled with the largest key, and sorted nearest first
/// by Batcher's odd-even merge network (Knuth, *TAOCP* vol. 3, 5.3.4): the optimal network for four
/// on each half, (0,1)(2,3), (0,2)(1,3), (1,2), then, only for more than four children, the merge
/// of the halves, (0,4)(1,5)(2,6)(3,7), (2,4)(3,5), (1,2)(3,4)(5,6); each layer a permute, a max
/// and a masked min. Lane 0 is the nearest; the others get their children back through their
/// keys' lane numbers and are stored far to near in one masked store.
///
/// # Safety
/// The CPU must have AVX-512 F and VL; the caller is compiled for them, so that this inlines there.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(super) unsafe fn network_avx512<const S: usize>(
    t: __m256,
    mask: u32,
    child: &[ChildRef; 8],
    stack: &mut Stack<Visit, S>,
) -> ChildRef {
    let n = mask.count_ones() as usize;
    // SAFETY: the caller runs on a CPU with AVX-512 F and VL (this function's contract); the masked store writes the `n - 1` entries `push_written` makes room for.
    unsafe {
        // Lane k holds 7 - k: a key's tie-breaker, and the index that reverses the lanes.
        let reverse = _mm512_set_epi64(0, 1, 2, 3, 4, 5, 6, 7);
        let bits = _mm512_cvtepu32_epi64(_mm256_castps_si256(t));
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
