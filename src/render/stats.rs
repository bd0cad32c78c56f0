//! What a render counts: the rays it traced by kind and, where it counts them, their steps (nodes
//! visited, primitives tested). Counting is a type parameter of the frame ([`Count`]: [`Plain`] or
//! [`Counting`]), as the accelerators' tally is, so a plain frame compiles no counting.

use super::tiles::TILE;
use crate::accel::counters::{self, Steps};
use crate::accel::lanes::OnLanes8;
use crate::accel::{Counting, Plain, Simd, Tally};

/// What a render counts beyond its rays by kind: nothing ([`Plain`]) or each ray's steps
/// ([`Counting`]), through the accelerator's verbs of the same tally.
pub(crate) trait Count: Tally {
    /// A pixel sample's steps by kind: nothing, or [`KindSteps`].
    type Steps: Copy + Default;
    /// Adds the steps the last verb counted for lane `k` to `steps`, as a ray of `kind`'s.
    fn charge(steps: &mut Self::Steps, kind: RayKind, k: usize);
    /// `steps` by kind (none in a plain render).
    fn kinds(steps: &Self::Steps) -> KindSteps;
    /// Runs the packet kernel's tile work `k` on the lanes of `simd`: a plain frame's choice; a
    /// counting frame (a diagnostic, slow by its counting) shades on the portable lanes, which give
    /// the same bits, so that the build holds one counting instance of the shading, not three.
    fn run_tile<K: OnLanes8>(simd: Simd, k: K) -> K::Output;
}

impl Count for Plain {
    type Steps = ();
    #[inline(always)]
    fn charge(_: &mut (), _: RayKind, _: usize) {}
    #[inline(always)]
    fn kinds(_: &()) -> KindSteps {
        KindSteps::default()
    }
    #[inline(always)]
    fn run_tile<K: OnLanes8>(simd: Simd, k: K) -> K::Output {
        simd.run8(k)
    }
}

impl Count for Counting {
    type Steps = KindSteps;
    #[inline]
    fn charge(steps: &mut KindSteps, kind: RayKind, k: usize) {
        *steps.of(kind) += counters::lane(k);
    }
    #[inline]
    fn kinds(steps: &KindSteps) -> KindSteps {
        *steps
    }
    #[inline(always)]
    fn run_tile<K: OnLanes8>(_: Simd, k: K) -> K::Output {
        Simd::run8_portable(k)
    }
}

/// Rays traced, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Camera rays.
    pub primary: u64,
    /// Camera rays that hit something (not counted in [`RayCounts::total`]: they are camera rays).
    pub primary_hits: u64,
    /// Shadow rays (any hit).
    pub shadow: u64,
    /// Mirror rays.
    pub reflected: u64,
    /// Refracted rays.
    pub refracted: u64,
    /// The steps of the rays of each kind, when the render counts them ([`Options::count_steps`]).
    ///
    /// [`Options::count_steps`]: super::Options::count_steps
    pub steps: KindSteps,
}

/// Which kind a traced ray is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// From the camera.
    Camera,
    /// Toward a light sample (any hit).
    Shadow,
    /// Off a mirror.
    Reflected,
    /// Through a transmitter.
    Refracted,
}

impl RayKind {
    /// The kind of a hit's secondary ray `i`: 0 refracted, 1 reflected (the order in which a hit's
    /// rays are traced).
    pub fn secondary(i: usize) -> RayKind {
        if i == 0 {
            RayKind::Refracted
        } else {
            RayKind::Reflected
        }
    }
}

/// Steps ([`Steps`]: nodes visited, primitives tested) summed over the rays of each kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KindSteps {
    /// Camera rays'.
    pub camera: Steps,
    /// Shadow rays'.
    pub shadow: Steps,
    /// Mirror rays'.
    pub reflected: Steps,
    /// Refracted rays'.
    pub refracted: Steps,
}

impl KindSteps {
    /// The steps of `kind`.
    pub fn get(&self, kind: RayKind) -> Steps {
        match kind {
            RayKind::Camera => self.camera,
            RayKind::Shadow => self.shadow,
            RayKind::Reflected => self.reflected,
            RayKind::Refracted => self.refracted,
        }
    }

    /// The steps of `kind`, to add to.
    pub fn of(&mut self, kind: RayKind) -> &mut Steps {
        match kind {
            RayKind::Camera => &mut self.camera,
            RayKind::Shadow => &mut self.shadow,
            RayKind::Reflected => &mut self.reflected,
            RayKind::Refracted => &mut self.refracted,
        }
    }

    /// All kinds' steps.
    pub fn total(&self) -> Steps {
        let mut all = self.camera;
        for s in [self.shadow, self.reflected, self.refracted] {
            all += s;
        }
        all
    }
}

impl std::ops::AddAssign for KindSteps {
    fn add_assign(&mut self, o: KindSteps) {
        self.camera += o.camera;
        self.shadow += o.shadow;
        self.reflected += o.reflected;
        self.refracted += o.refracted;
    }
}

impl RayCounts {
    /// All rays.
    pub fn total(&self) -> u64 {
        self.primary + self.shadow + self.reflected + self.refracted
    }
}

/// The rays one pixel sample traced, by kind: [`RayCounts`] without the steps, which a sample carries
/// apart ([`Count::Steps`]: nothing in a plain render).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SampleRays {
    /// Camera rays.
    pub primary: u64,
    /// Camera rays that hit something.
    pub primary_hits: u64,
    /// Shadow rays.
    pub shadow: u64,
    /// Mirror rays.
    pub reflected: u64,
    /// Refracted rays.
    pub refracted: u64,
}

impl std::ops::AddAssign<SampleRays> for RayCounts {
    fn add_assign(&mut self, o: SampleRays) {
        self.primary += o.primary;
        self.primary_hits += o.primary_hits;
        self.shadow += o.shadow;
        self.reflected += o.reflected;
        self.refracted += o.refracted;
    }
}

impl std::ops::AddAssign for RayCounts {
    fn add_assign(&mut self, o: RayCounts) {
        self.primary += o.primary;
        self.primary_hits += o.primary_hits;
        self.shadow += o.shadow;
        self.reflected += o.reflected;
        self.refracted += o.refracted;
        self.steps += o.steps;
    }
}

/// A tile's rays: their sum and, where the render counts steps, each pixel's (row by row, [`TILE`] a
/// row; for heatmaps).
#[derive(Debug)]
pub(crate) struct TileRays {
    /// The tile's rays.
    pub total: RayCounts,
    /// Each pixel's rays, where the render counts steps.
    pub pixels: Option<Vec<RayCounts>>,
}

impl TileRays {
    /// No rays yet; each pixel's kept apart with `per_pixel`.
    pub(crate) fn new(per_pixel: bool) -> Self {
        TileRays {
            total: RayCounts::default(),
            pixels: per_pixel.then(|| vec![RayCounts::default(); (TILE * TILE) as usize]),
        }
    }

    /// Adds a finished pixel sample of pixel `i` (row-major in the tile): its camera ray, the `rays`
    /// of its tree and their `steps`.
    #[inline]
    pub(crate) fn add<C: Count>(&mut self, i: usize, rays: &SampleRays, steps: &C::Steps) {
        let mut r = RayCounts {
            steps: C::kinds(steps),
            ..RayCounts::default()
        };
        r += *rays;
        r.primary += 1;
        self.total += r;
        if let Some(p) = self.pixels.as_mut() {
            p[i] += r;
        }
    }
}
