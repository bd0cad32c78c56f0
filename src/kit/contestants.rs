//! Every accelerator and kernel, built over one scene and named: the one list the tests check and the
//! benches measure, so that a structure, build option or instruction set added here is checked against
//! brute force and measured beside the others without another line anywhere. With the `embree` feature
//! Embree joins them (named `embree`), checked with [`Agreement::Edges`]: its own triangle test may
//! part from ours where a ray crosses an edge.

use super::agreement::Agreement;
use crate::accel::bvh2::Builder;
use crate::accel::{Accel, AccelKind, BuildOptions, Isa, Prims};

/// A structure and the options it is built with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Build {
    /// Its name: `grid`, `bvh2 midpoint`, `bvh2 sah`, `bvh2 optimized`, `bvh4`, `bvh4 4 bins`, `bvh8`
    /// (the wide BVHs at the default build, [`BuildOptions::DEFAULT`]), `bvh8 sah` (without
    /// reinsertion).
    pub name: &'static str,
    /// The structure.
    pub kind: AccelKind,
    /// Its build options (the BVH2's split rule, the SAH's bins).
    pub options: BuildOptions,
    /// True where the structure is listed once per instruction set its kernels have (the wide BVHs
    /// at their default build); the other builds of a wide BVH run on the CPU's best set only.
    pub each_simd: bool,
}

/// The binned SAH alone, 12 bins per axis.
const SAH: BuildOptions = BuildOptions {
    reinsert: false,
    ..BuildOptions::DEFAULT
};

/// Every build: what the build bench times, and what [`all`] builds.
pub const BUILDS: [Build; 8] = [
    Build {
        name: "grid",
        kind: AccelKind::Grid,
        options: SAH,
        each_simd: false,
    },
    Build {
        name: "bvh2 midpoint",
        kind: AccelKind::Bvh2,
        options: BuildOptions {
            builder: Builder::Midpoint,
            ..SAH
        },
        each_simd: false,
    },
    Build {
        name: "bvh2 sah",
        kind: AccelKind::Bvh2,
        options: SAH,
        each_simd: false,
    },
    Build {
        name: "bvh2 optimized",
        kind: AccelKind::Bvh2,
        options: BuildOptions::DEFAULT,
        each_simd: false,
    },
    Build {
        name: "bvh4",
        kind: AccelKind::Bvh4,
        options: BuildOptions::DEFAULT,
        each_simd: true,
    },
    Build {
        name: "bvh4 4 bins",
        kind: AccelKind::Bvh4,
        options: BuildOptions {
            builder: Builder::Sah { bins: 4 },
            bins: 4,
            ..BuildOptions::DEFAULT
        },
        each_simd: false,
    },
    Build {
        name: "bvh8",
        kind: AccelKind::Bvh8,
        options: BuildOptions::DEFAULT,
        each_simd: true,
    },
    Build {
        name: "bvh8 sah",
        kind: AccelKind::Bvh8,
        options: SAH,
        each_simd: false,
    },
];

impl Build {
    /// Builds it over `prims` (on the current rayon pool).
    pub fn build<'a>(&self, prims: Prims<'a>) -> Accel<'a> {
        Accel::build_with(prims, self.kind, self.options)
    }
}

/// A built accelerator and its name.
#[derive(Clone, Debug)]
pub struct Contestant<'a> {
    /// The build's name, then the instruction set for those listed once per set: `grid`,
    /// `bvh2 midpoint`, `bvh2 sah`, `bvh4 avx2`, `bvh4 portable`, `bvh4 4 bins`, `bvh8 avx2`,
    /// `bvh8 portable`.
    pub name: String,
    /// The structure.
    pub accel: Accel<'a>,
}

impl Contestant<'_> {
    /// True for the structures that trace a packet's rays together (the wide BVHs, Embree). The others
    /// answer packets ray by ray: the tests still check that answer, but a bench would only time
    /// single rays again.
    pub fn has_packet_kernel(&self) -> bool {
        self.accel.has_packet_kernel()
    }

    /// True for Embree, a peer's structure with its own triangle test (feature `embree`).
    pub fn is_embree(&self) -> bool {
        #[cfg(feature = "embree")]
        if matches!(self.accel, Accel::Embree(_)) {
            return true;
        }
        false
    }

    /// True where the images rendered are brute force's, byte for byte: every structure of ours, not
    /// Embree (whose images `tests/embree/main.rs` compares within a tolerance).
    pub fn same_images(&self) -> bool {
        !self.is_embree()
    }

    /// True for the uniform grid: the reference where brute force on every ray would take minutes
    /// ([`super::oracle::against_grid`]).
    pub fn is_grid(&self) -> bool {
        matches!(self.accel, Accel::Grid(_))
    }

    /// How closely it must agree with brute force. The grid tests the same primitives with the same
    /// code as brute force and keeps the same hit in ties: bit for bit. The hierarchies may reach
    /// another of the primitives that meet at a hit point first: [`Agreement::Close`]. Embree's own
    /// triangle test may round the other way at an edge: [`Agreement::Edges`].
    pub fn agreement(&self) -> Agreement {
        if self.is_grid() {
            Agreement::Exact
        } else if self.is_embree() {
            Agreement::Edges
        } else {
            Agreement::Close
        }
    }
}

/// The instruction sets the wide BVHs' kernels have, in the order they are listed.
const SIMD: [(Isa, &str); 3] = [
    (Isa::Avx512, "avx512"),
    (Isa::Avx2, "avx2"),
    (Isa::Portable, "portable"),
];

/// Every build of [`BUILDS`] over `prims`, each built once (on the current rayon pool), the wide BVHs at
/// their default build once per instruction set this CPU has (copies of one build), then, with the
/// `embree` feature, Embree (`--accel embree`'s build). On a CPU without AVX2 or AVX-512 it says, on
/// stderr, which kernels are not there; a set the CPU has but a structure refuses is a bug, and
/// panics, as does an Embree that fails to build.
pub fn all(prims: Prims<'_>) -> Vec<Contestant<'_>> {
    if !Isa::Avx2.available() {
        eprintln!("this CPU has no AVX2: the wide BVHs run their portable kernels only");
    } else if !Isa::Avx512.available() {
        eprintln!("this CPU has no AVX-512: the wide BVHs' AVX-512 kernels are not tested here");
    }
    let mut out = Vec::new();
    for b in &BUILDS {
        let accel = b.build(prims);
        // A scene beyond the wide BVHs' primitive limit gets a BVH2, which has no instruction set.
        if !b.each_simd || accel.simd().is_none() {
            out.push(Contestant {
                name: b.name.into(),
                accel,
            });
            continue;
        }
        for (simd, set) in SIMD {
            let mut copy = accel.clone();
            if copy.set_simd(simd) {
                out.push(Contestant {
                    name: format!("{} {set}", b.name),
                    accel: copy,
                });
            } else {
                assert!(
                    !simd.available(),
                    "{}: {set} refused on a CPU that has it",
                    b.name
                );
            }
        }
    }
    #[cfg(feature = "embree")]
    out.push(Contestant {
        name: "embree".into(),
        accel: Accel::build_with(prims, AccelKind::Embree, SAH),
    });
    out
}
