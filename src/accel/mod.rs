//! Accelerators. Each answers the same two questions (as tinybvh does on every layout): the closest hit
//! along a ray and whether anything lies on a segment, for one ray (`intersect`, `occluded`) or a
//! packet of eight (`intersect_packet`, `occluded_packet`), and the closest hit of a coherent single
//! ray (`intersect_coherent`, a camera ray: the same answer by steps that pay for such rays): five
//! verbs, dispatched in one place over the [`Structure`] trait, whose packet verbs default to ray by
//! ray. That shared interface is what lets every structure be checked against brute force with one
//! loop, and lets the renderer send packets without knowing which structure answers them.

pub(crate) mod brute;
pub mod bvh2;
pub mod counters;
#[cfg(feature = "embree")]
pub mod embree;
pub(crate) mod grid;
pub(crate) mod packet;
pub(crate) mod pages;
pub mod policy;
pub(crate) mod prims;
pub mod quality;
pub mod stack;
pub(crate) mod structure;
pub mod wide;

use std::marker::PhantomData;
use std::str::FromStr;

pub use packet::{HitPacket, PACKET, RayPacket, coherent_rays};
pub use prims::{Hit, PrimKind, Prims, Surface};
pub use structure::Structure;
pub use wide::Isa;
pub(crate) use wide::Simd;

/// The SIMD lanes the wide BVHs' kernels run on, shared with the renderer's shading.
pub(crate) mod lanes {
    pub(crate) use super::wide::{Lanes, Lanes8, OnLanes8};
}

use crate::geometry::ray::{Ray, ahead};
use brute::Brute;
use bvh2::{Builder, Bvh2};
use grid::Grid;
use policy::{AnyHit, Closest, Coherent, Counted, HitPolicy};
use wide::{Bvh4, Bvh8};

/// Which structure to build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelKind {
    /// Test every primitive.
    None,
    /// Uniform grid walked by 3D-DDA.
    Grid,
    /// Binary BVH.
    Bvh2,
    /// 4-wide BVH with SIMD node tests (the default where the CPU lacks AVX2).
    Bvh4,
    /// 8-wide BVH: one AVX2 slab test per node where the CPU has AVX2 (two SSE halves elsewhere).
    Bvh8,
    /// Embree 3 (the system's `libembree3`), to race against: only with the cargo feature `embree`.
    #[cfg(feature = "embree")]
    Embree,
}

/// Why `embree` is not an accelerator of this build, and how to get one that has it.
pub const NO_EMBREE: &str = "this whitted was built without Embree: `--accel embree` needs \
     `cargo build --release --features embree` (and Embree 3: `apt-get install libembree-dev` on Debian/Ubuntu)";

/// How the BVHs are built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildOptions {
    /// The BVH2's split rule (the wide BVHs always collapse a binned-SAH BVH2).
    pub builder: Builder,
    /// SAH bins per axis.
    pub bins: usize,
    /// Optimize the BVH2 by reinsertion (Bittner et al. 2013) before it is used or collapsed.
    pub reinsert: bool,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions::DEFAULT
    }
}

impl BuildOptions {
    /// Binned SAH with 12 bins, then reinsertion: what `--build auto` builds, since reinsertion keeps
    /// the build well within twice Embree's medium build (docs/performance.md).
    pub const DEFAULT: BuildOptions = BuildOptions {
        builder: Builder::Sah { bins: 12 },
        bins: 12,
        reinsert: true,
    };

    /// The same options with the binned SAH builder: the wide BVHs collapse a binned-SAH BVH2.
    pub fn sah(&self) -> BuildOptions {
        BuildOptions {
            builder: Builder::Sah { bins: self.bins },
            ..*self
        }
    }
}

impl AccelKind {
    /// The fastest structure on this CPU (measured on the dragon scenes): the BVH8 where the CPU has
    /// AVX2 for its slab test, else the BVH4 (whose 4-wide test is native SSE everywhere).
    pub fn best() -> AccelKind {
        if Isa::Avx2.available() {
            AccelKind::Bvh8
        } else {
            AccelKind::Bvh4
        }
    }
}

impl FromStr for AccelKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "none" | "brute" => Ok(AccelKind::None),
            "grid" => Ok(AccelKind::Grid),
            "bvh2" => Ok(AccelKind::Bvh2),
            "bvh4" => Ok(AccelKind::Bvh4),
            "bvh8" => Ok(AccelKind::Bvh8),
            "auto" => Ok(AccelKind::best()),
            #[cfg(feature = "embree")]
            "embree" => Ok(AccelKind::Embree),
            #[cfg(not(feature = "embree"))]
            "embree" => Err(NO_EMBREE.to_string()),
            _ => Err(format!(
                "unknown accelerator \"{s}\": expected none, grid, bvh2, bvh4, bvh8{} or auto",
                if cfg!(feature = "embree") { ", embree" } else { "" }
            )),
        }
    }
}

/// A built accelerator over a scene's primitives. One match per ray, not per primitive.
#[derive(Clone, Debug)]
pub enum Accel<'a> {
    /// Brute force.
    Brute(Brute<'a>),
    /// Uniform grid.
    Grid(Grid<'a>),
    /// Binary BVH.
    Bvh2(Bvh2<'a>),
    /// 4-wide BVH.
    Bvh4(Bvh4<'a>),
    /// 8-wide BVH.
    Bvh8(Bvh8<'a>),
    /// Embree 3's BVH over the bounded primitives, the planes beside it.
    #[cfg(feature = "embree")]
    Embree(embree::Embree<'a>),
}

/// `$body` with `$s` bound to the structure inside `$accel`, whichever it is: the one place that
/// lists the structures, so that each verb is one line and a new structure one more arm here.
macro_rules! each {
    ($accel:expr, $s:ident => $body:expr) => {
        match $accel {
            Accel::Brute($s) => $body,
            Accel::Grid($s) => $body,
            Accel::Bvh2($s) => $body,
            Accel::Bvh4($s) => $body,
            Accel::Bvh8($s) => $body,
            #[cfg(feature = "embree")]
            Accel::Embree($s) => $body,
        }
    };
}

impl<'a> Accel<'a> {
    /// Builds the chosen structure.
    pub fn build(prims: Prims<'a>, kind: AccelKind) -> Self {
        Self::build_with(prims, kind, BuildOptions::default())
    }

    /// Builds the chosen structure with explicit build options, or says why Embree could not build its
    /// scene (`--accel embree`; our own structures always build). Embree builds on as many threads as
    /// the current rayon pool has.
    pub fn try_build_with(prims: Prims<'a>, kind: AccelKind, options: BuildOptions) -> crate::Result<Self> {
        match kind {
            #[cfg(feature = "embree")]
            AccelKind::Embree => {
                let threads = rayon::current_num_threads();
                embree::Embree::new(prims, embree::DEFAULT_QUALITY, threads, None).map(Accel::Embree)
            }
            _ => Ok(Self::build_with(prims, kind, options)),
        }
    }

    /// Builds the chosen structure with explicit build options. A scene too large for the wide BVHs'
    /// leaf references gets a BVH2.
    ///
    /// # Panics
    ///
    /// When Embree fails to build its scene (out of memory, say): [`Accel::try_build_with`] returns
    /// that error instead.
    pub fn build_with(prims: Prims<'a>, kind: AccelKind, options: BuildOptions) -> Self {
        match kind {
            #[cfg(feature = "embree")]
            AccelKind::Embree => Self::try_build_with(prims, kind, options).unwrap_or_else(|e| panic!("{e}")),
            AccelKind::None => Accel::Brute(Brute::new(prims)),
            AccelKind::Grid => Accel::Grid(Grid::build(prims)),
            AccelKind::Bvh2 => Accel::Bvh2(Bvh2::build(prims, &options)),
            AccelKind::Bvh4 => match Bvh4::build(prims, &options) {
                Some(b) => Accel::Bvh4(b),
                None => Accel::Bvh2(Bvh2::build(prims, &options.sah())),
            },
            AccelKind::Bvh8 => match Bvh8::build(prims, &options) {
                Some(b) => Accel::Bvh8(b),
                None => Accel::Bvh2(Bvh2::build(prims, &options.sah())),
            },
        }
    }

    /// A one-line description of the built structure: node count, depth, leaf sizes and SAH cost for the
    /// BVHs, resolution and references for the grid.
    pub fn describe(&self) -> String {
        each!(self, s => Structure::describe(s))
    }

    /// The scene's primitives the structure was built over.
    pub fn prims(&self) -> Prims<'a> {
        each!(self, s => Structure::prims(s))
    }

    /// True for the structures that trace a packet's rays together: the wide BVHs and Embree (the
    /// others answer a packet ray by ray).
    pub fn has_packet_kernel(&self) -> bool {
        each!(self, s => Structure::has_packet_kernel(s))
    }

    /// The wide BVHs' instruction set; `None` for the other structures.
    pub fn simd(&self) -> Option<Isa> {
        each!(self, s => Structure::simd(s))
    }

    /// Makes a wide BVH use `simd` (tests and benchmarks compare the paths: the `kit` feature); false,
    /// with nothing changed, when the CPU lacks it or the structure has no such choice.
    #[cfg(feature = "kit")]
    pub fn set_simd(&mut self, simd: Isa) -> bool {
        each!(self, s => Structure::set_simd(s, simd))
    }

    /// The verbs of `T`: [`Accel::counting`]'s, or the plain ones.
    pub fn verbs<T: Tally>(&self) -> Verbs<'_, 'a, T> {
        Verbs::new(self)
    }

    /// The verbs that count their steps into [`counters`] (per ray of each call; the renderer's
    /// `--stats` and heatmaps), where the structure can count them ([`Accel::counts_steps`]).
    pub fn counting(&self) -> Verbs<'_, 'a, Counting> {
        Verbs::new(self)
    }

    /// Whether the counting verbs count: Embree's kernels are not ours to count.
    pub fn counts_steps(&self) -> bool {
        each!(self, s => Structure::counts_steps(s))
    }

    /// Finds the closest hit with `t` in `(t_min, hit.t)`; updates `hit` and returns true if there is one
    /// ([`Verbs::intersect`]).
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        Verbs::<Plain>::new(self).intersect(ray, t_min, hit)
    }

    /// The closest hit of a ray much like the one traced before it ([`Verbs::intersect_coherent`]).
    #[inline]
    pub fn intersect_coherent(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        Verbs::<Plain>::new(self).intersect_coherent(ray, t_min, hit)
    }

    /// True if anything is hit with `t` in `(t_min, t_max)` ([`Verbs::occluded`]).
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        Verbs::<Plain>::new(self).occluded(ray, t_min, t_max)
    }

    /// The closest hits of a packet's active rays ([`Verbs::intersect_packet`]).
    #[inline]
    pub fn intersect_packet(&self, rays: &RayPacket, active: u8, t_min: f32, hits: &mut HitPacket) -> u8 {
        Verbs::<Plain>::new(self).intersect_packet(rays, active, t_min, hits)
    }

    /// Which of a packet's active rays are blocked ([`Verbs::occluded_packet`]).
    #[inline]
    pub fn occluded_packet(&self, rays: &RayPacket, active: u8, t_min: f32, t_max: &[f32; PACKET]) -> u8 {
        Verbs::<Plain>::new(self).occluded_packet(rays, active, t_min, t_max)
    }
}

/// Whether an accelerator's verbs count their steps: the hit policies they trace with.
pub trait Tally {
    /// Whether the verbs count their steps.
    const COUNTS: bool;
    /// The closest-hit policy.
    type Closest: HitPolicy;
    /// The closest-hit policy for coherent rays.
    type Coherent: HitPolicy;
    /// The any-hit policy.
    type Any: HitPolicy;
}

/// The verbs as they are: nothing counted, nothing spent on counting.
pub enum Plain {}

impl Tally for Plain {
    const COUNTS: bool = false;
    type Closest = Closest;
    type Coherent = Coherent;
    type Any = AnyHit;
}

/// The verbs counting their steps into [`counters`], one lane per ray of the call.
pub enum Counting {}

impl Tally for Counting {
    const COUNTS: bool = true;
    type Closest = Counted<Closest>;
    type Coherent = Counted<Coherent>;
    type Any = Counted<AnyHit>;
}

/// An accelerator's five verbs, written once for both [`Tally`]s.
pub struct Verbs<'r, 'a, T> {
    accel: &'r Accel<'a>,
    tally: PhantomData<T>,
}

impl<'r, 'a, T: Tally> Verbs<'r, 'a, T> {
    fn new(accel: &'r Accel<'a>) -> Self {
        Verbs {
            accel,
            tally: PhantomData,
        }
    }

    /// Zeroes the lanes of the `n` rays of a counted call.
    #[inline(always)]
    fn lanes(n: usize) {
        if T::Closest::COUNT {
            counters::reset(n);
        }
    }

    /// Finds the closest hit with `t` in `(t_min, hit.t)`; updates `hit` and returns true if there is one.
    /// Every query of every accelerator searches ahead of the ray's origin: a negative `t_min` is 0.
    // Not inlined, nor is `intersect_coherent`: `profiles/frame.sh` tells traversal by its callers.
    #[inline(never)]
    pub fn intersect(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        self.closest::<T::Closest>(ray, t_min, hit)
    }

    /// [`Verbs::intersect`] for a ray that takes much the way the ray traced before it took (a camera
    /// ray after its neighbour's): the same answer, by the steps that pay for such rays.
    #[inline(never)]
    pub fn intersect_coherent(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        self.closest::<T::Coherent>(ray, t_min, hit)
    }

    /// One ray's closest hit under the closest-hit policy `P` (plain or coherent).
    #[inline(always)]
    fn closest<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        Self::lanes(1);
        let t_min = ahead(t_min);
        each!(self.accel, s => Structure::traverse::<P>(s, ray, t_min, hit))
    }

    /// True if anything is hit with `t` in `(t_min, t_max)`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_min: f32, t_max: f32) -> bool {
        Self::lanes(1);
        let (t_min, mut hit) = (ahead(t_min), Hit::miss(t_max));
        each!(self.accel, s => Structure::traverse::<T::Any>(s, ray, t_min, &mut hit))
    }

    /// The closest hits of the rays of `rays` whose bit is set in `active`, each with `t` in
    /// `(t_min, hits[k].t)`: updates those `hits` and returns the mask of the rays that hit. Each ray's
    /// answer is [`Accel::intersect`]'s; inactive rays' hits are left as they are. The wide BVHs trace
    /// the packet together (for coherent rays: camera rays of neighbouring pixels, say); the other
    /// structures answer ray by ray.
    #[inline]
    pub fn intersect_packet(&self, rays: &RayPacket, active: u8, t_min: f32, hits: &mut HitPacket) -> u8 {
        Self::lanes(PACKET);
        let t_min = ahead(t_min);
        each!(self.accel, s => Structure::traverse_packet::<T::Closest>(s, rays, active, t_min, hits))
    }

    /// The mask of the rays of `rays` in `active` that hit anything with `t` in `(t_min, t_max[k])`:
    /// [`Accel::occluded`] for each, as a packet where the structure has a packet kernel.
    #[inline]
    pub fn occluded_packet(&self, rays: &RayPacket, active: u8, t_min: f32, t_max: &[f32; PACKET]) -> u8 {
        Self::lanes(PACKET);
        let (t_min, mut hits) = (ahead(t_min), t_max.map(Hit::miss));
        each!(self.accel, s => Structure::traverse_packet::<T::Any>(s, rays, active, t_min, &mut hits))
    }
}
