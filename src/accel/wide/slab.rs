//! The slab test of one node's children against one ray (Kay and Kajiya 1986), in as many lanes as the
//! node is wide: 4 lanes of SSE for the BVH4; for the BVH8 one AVX2 register where the CPU has AVX2
//! (chosen at run time, so the default build needs no `target-cpu`), else two SSE halves (`wide`'s
//! portable `f32x8`). Every variant is the same arithmetic in the same order (`max(near, x)` and
//! `min(far, x)` as `maxps`/`minps` with the running value first, an ordered `<=` for the mask), so all
//! of them enter exactly the same children and the images do not depend on the CPU.

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::*;

use wide::{f32x4, f32x8};

use super::Node;
use crate::geometry::ray::{Ray, SLAB_ROBUST, safe_inverse};

/// The instruction set a wide BVH's slab tests run on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Simd {
    /// Baseline x86-64 SSE (or whatever `wide` maps to elsewhere): runs on every CPU.
    Portable,
    /// 256-bit AVX2 (with FMA) for 8-wide nodes: detected at run time.
    Avx2,
}

impl Simd {
    /// The best the running CPU has.
    pub fn detect() -> Simd {
        if Simd::Avx2.available() {
            Simd::Avx2
        } else {
            Simd::Portable
        }
    }

    /// True if the running CPU can execute it.
    pub fn available(self) -> bool {
        match self {
            Simd::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Simd::Avx2 => is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
            #[cfg(not(target_arch = "x86_64"))]
            Simd::Avx2 => false,
        }
    }
}

/// A way to test the `W` children of a node: the ray prepared once (origin and inverse direction
/// splatted, and per axis whether the max plane is the near one, Embree's near/far plane selection),
/// then per node the children's entry distances and the mask of those entered within `[t_min, t_max]`.
/// An empty slot's inverted box gives near = +∞ > far = −∞ whichever plane is near.
pub(super) trait Lanes<const W: usize> {
    type Prepared;
    fn prepare(ray: &Ray) -> Self::Prepared;
    fn slab(n: &Node<W>, r: &Self::Prepared, t_min: f32, t_max: f32) -> ([f32; W], u32);
}

/// A ray for `wide`'s lane types.
pub(super) struct Splat<V> {
    origin: [V; 3],
    inv: [V; 3],
    flip: [bool; 3],
}

/// 4 lanes of SSE (`wide::f32x4`).
pub(super) struct Sse4;
/// 8 lanes as two SSE halves (`wide::f32x8` without AVX): any CPU.
pub(super) struct Portable8;

/// The slab test over `wide`'s lane types, written once for 4 and 8 lanes.
macro_rules! wide_lanes {
    ($name:ident, $w:literal, $v:ty) => {
        impl Lanes<$w> for $name {
            type Prepared = Splat<$v>;

            #[inline(always)]
            fn prepare(ray: &Ray) -> Splat<$v> {
                let inv = safe_inverse(ray.dir);
                Splat {
                    origin: ray.origin.to_array().map(<$v>::splat),
                    inv: inv.to_array().map(<$v>::splat),
                    flip: [inv.x < 0.0, inv.y < 0.0, inv.z < 0.0],
                }
            }

            #[inline(always)]
            fn slab(n: &Node<$w>, r: &Splat<$v>, t_min: f32, t_max: f32) -> ([f32; $w], u32) {
                let mut near = <$v>::splat(t_min);
                let mut far = <$v>::splat(f32::INFINITY);
                for axis in 0..3 {
                    let (a, b) = (&n.min[axis], &n.max[axis]);
                    let (a, b) = if r.flip[axis] { (b, a) } else { (a, b) };
                    near = near.fast_max((<$v>::new(*a) - r.origin[axis]) * r.inv[axis]);
                    far = far.fast_min((<$v>::new(*b) - r.origin[axis]) * r.inv[axis]);
                }
                let far = (far * <$v>::splat(SLAB_ROBUST)).fast_min(<$v>::splat(t_max));
                (near.to_array(), near.simd_le(far).to_bitmask())
            }
        }
    };
}

wide_lanes!(Sse4, 4, f32x4);
wide_lanes!(Portable8, 8, f32x8);

/// 8 lanes in one AVX2 register. Only ever reached through [`Simd::Avx2`], which is chosen only when
/// the CPU has AVX2 and FMA; the kernels that use it are compiled for AVX2 (`#[target_feature]`), so
/// these intrinsics inline into them.
#[cfg(target_arch = "x86_64")]
pub(super) struct Avx8;

/// A ray splatted into AVX registers.
#[cfg(target_arch = "x86_64")]
pub(super) struct Splat256 {
    origin: [__m256; 3],
    inv: [__m256; 3],
    flip: [bool; 3],
}

#[cfg(target_arch = "x86_64")]
impl Lanes<8> for Avx8 {
    type Prepared = Splat256;

    #[inline(always)]
    fn prepare(ray: &Ray) -> Splat256 {
        // SAFETY: `Avx8` is used only when the CPU has AVX2 (see the type's comment).
        unsafe { prepare_avx(ray) }
    }

    #[inline(always)]
    fn slab(n: &Node<8>, r: &Splat256, t_min: f32, t_max: f32) -> ([f32; 8], u32) {
        // SAFETY: as above.
        unsafe { slab_avx(n, r, t_min, t_max) }
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
fn prepare_avx(ray: &Ray) -> Splat256 {
    let inv = safe_inverse(ray.dir);
    Splat256 {
        origin: ray.origin.to_array().map(|v| _mm256_set1_ps(v)),
        inv: inv.to_array().map(|v| _mm256_set1_ps(v)),
        flip: [inv.x < 0.0, inv.y < 0.0, inv.z < 0.0],
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
fn slab_avx(n: &Node<8>, r: &Splat256, t_min: f32, t_max: f32) -> ([f32; 8], u32) {
    let load = |a: &[f32; 8]| {
        // SAFETY: an unaligned load of eight floats from an eight-float array.
        unsafe { _mm256_loadu_ps(a.as_ptr()) }
    };
    let mut near = _mm256_set1_ps(t_min);
    let mut far = _mm256_set1_ps(f32::INFINITY);
    for axis in 0..3 {
        let (a, b) = (&n.min[axis], &n.max[axis]);
        let (a, b) = if r.flip[axis] { (b, a) } else { (a, b) };
        near = _mm256_max_ps(
            near,
            _mm256_mul_ps(_mm256_sub_ps(load(a), r.origin[axis]), r.inv[axis]),
        );
        far = _mm256_min_ps(
            far,
            _mm256_mul_ps(_mm256_sub_ps(load(b), r.origin[axis]), r.inv[axis]),
        );
    }
    let far = _mm256_min_ps(
        _mm256_mul_ps(far, _mm256_set1_ps(SLAB_ROBUST)),
        _mm256_set1_ps(t_max),
    );
    let mut out = [0.0f32; 8];
    // SAFETY: an unaligned store of eight floats into an eight-float array.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), near) };
    let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(near, far)) as u32;
    (out, mask)
}
