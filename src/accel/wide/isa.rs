//! The one run-time choice of instruction set for the wide BVHs' kernels. AVX2 and AVX-512 code is
//! reached only through [`Simd::run8`], and a [`Simd`] that selects either is made only by [`Simd::new`]
//! after the CPU was asked: the [`Detected`] token those variants carry has a private field.

use wide::f32x8;

use super::lanes::OnLanes8;
#[cfg(target_arch = "x86_64")]
use super::lanes::{run_avx2, run_avx512};

/// The instruction sets a wide BVH's kernels can run on (the public name of a choice; `Simd` is the
/// checked one).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// Baseline x86-64 SSE (or whatever `wide` maps to elsewhere): runs on every CPU.
    Portable,
    /// 256-bit AVX2 (with FMA, and the BMI1 and POPCNT bit instructions that every AVX2 CPU has) for
    /// eight lanes: detected at run time.
    Avx2,
    /// The AVX2 kernels compiled for AVX-512 (F and VL): mask registers for the box tests' results;
    /// detected at run time.
    Avx512,
}

impl Isa {
    /// The best the running CPU has.
    pub fn detect() -> Isa {
        Simd::detect().isa()
    }

    /// True if the running CPU can execute it.
    pub fn available(self) -> bool {
        Simd::new(self).is_some()
    }
}

/// Proof that the running CPU has the instructions of the [`Simd`] variant that carries it: made only
/// by [`Simd::new`], after asking the CPU.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Detected {
    _private: (),
}

/// A checked instruction set: what the kernels dispatch on, once per ray or packet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Simd {
    /// `wide`'s lanes: any CPU.
    Portable,
    /// AVX2, FMA, BMI1 and POPCNT, with the proof that the CPU has them.
    #[cfg(target_arch = "x86_64")]
    Avx2(Detected),
    /// AVX-512 F and VL besides the above, with the proof.
    #[cfg(target_arch = "x86_64")]
    Avx512(Detected),
}

impl Simd {
    /// The best the running CPU has.
    pub fn detect() -> Simd {
        Simd::new(Isa::Avx512)
            .or_else(|| Simd::new(Isa::Avx2))
            .unwrap_or(Simd::Portable)
    }

    /// `simd` if the running CPU has it.
    pub fn new(isa: Isa) -> Option<Simd> {
        #[cfg(target_arch = "x86_64")]
        let avx2 = || {
            is_x86_feature_detected!("avx2")
                && is_x86_feature_detected!("fma")
                && is_x86_feature_detected!("bmi1")
                && is_x86_feature_detected!("popcnt")
        };
        match isa {
            Isa::Portable => Some(Simd::Portable),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => avx2().then_some(Simd::Avx2(Detected { _private: () })),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => {
                (avx2() && is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl"))
                    .then_some(Simd::Avx512(Detected { _private: () }))
            }
            #[cfg(not(target_arch = "x86_64"))]
            Isa::Avx2 | Isa::Avx512 => None,
        }
    }

    /// The public name of this instruction set.
    pub fn isa(self) -> Isa {
        match self {
            Simd::Portable => Isa::Portable,
            #[cfg(target_arch = "x86_64")]
            Simd::Avx2(_) => Isa::Avx2,
            #[cfg(target_arch = "x86_64")]
            Simd::Avx512(_) => Isa::Avx512,
        }
    }

    /// Runs `k` on `wide`'s portable eight lanes, whatever the CPU: for work whose speed matters
    /// less than the code its other instances would add to the build.
    #[inline(always)]
    pub fn run8_portable<K: OnLanes8>(k: K) -> K::Output {
        k.run::<f32x8>()
    }

    /// Runs `k` on eight-lane vectors of this instruction set: the one run-time dispatch of the
    /// kernels.
    #[inline(always)]
    pub fn run8<K: OnLanes8>(self, k: K) -> K::Output {
        match self {
            // SAFETY: a `Detected` token exists only if the CPU has the variant's instructions
            // (`Simd::new`).
            #[cfg(target_arch = "x86_64")]
            Simd::Avx2(_) => unsafe { run_avx2(k) },
            #[cfg(target_arch = "x86_64")]
            Simd::Avx512(_) => unsafe { run_avx512(k) },
            Simd::Portable => Simd::run8_portable(k),
        }
    }
}
