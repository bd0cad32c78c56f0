//! Every accelerator and kernel, built over one scene and named: the one list the tests check and the
//! benches measure, so that a structure, build option or instruction set added here is checked against
//! brute force and measured beside the others without another line anywhere.

use super::oracle::Agreement;
use crate::accel::bvh2::Builder;
use crate::accel::{Accel, AccelKind, BuildOptions, Prims, Simd};

/// A built accelerator and its name.
#[derive(Clone, Debug)]
pub struct Contestant<'a> {
    /// The structure, its build where it has a choice, and its instruction set where it has one:
    /// `grid`, `bvh2 midpoint`, `bvh2 sah`, `bvh4 avx2`, `bvh4 portable`, `bvh4 4 bins`, `bvh8 avx2`,
    /// `bvh8 portable`.
    pub name: String,
    /// The structure.
    pub accel: Accel<'a>,
}

impl Contestant<'_> {
    /// True for the structures that trace a packet's rays together (the wide BVHs). The others answer
    /// packets ray by ray: the tests still check that answer, but a bench would only time single rays
    /// again.
    pub fn has_packet_kernel(&self) -> bool {
        self.accel.simd().is_some()
    }

    /// True for the uniform grid: the reference where brute force on every ray would take minutes
    /// ([`super::oracle::against_grid`]).
    pub fn is_grid(&self) -> bool {
        matches!(self.accel, Accel::Grid(_))
    }

    /// How closely it must agree with brute force. The grid tests the same primitives with the same
    /// code as brute force and keeps the same hit in ties: bit for bit. The hierarchies may reach
    /// another of the primitives that meet at a hit point first: [`Agreement::Close`].
    pub fn agreement(&self) -> Agreement {
        if self.is_grid() {
            Agreement::Exact
        } else {
            Agreement::Close
        }
    }
}

/// The instruction sets the wide BVHs' kernels have, in the order they are listed.
const SIMD: [(Simd, &str); 2] = [(Simd::Avx2, "avx2"), (Simd::Portable, "portable")];

/// Every accelerator and kernel over `prims`, each built once (on the current rayon pool): the grid,
/// the BVH2 by midpoint split and by binned SAH, the BVH4 and the BVH8 on each instruction set this CPU
/// has (one build each, copied for the other set), and the BVH4 from 4 SAH bins instead of 12. On a CPU
/// without AVX2 it says, on stderr, that only the portable kernels are there.
pub fn all(prims: Prims<'_>) -> Vec<Contestant<'_>> {
    let with = |kind, options| Accel::build_with(prims, kind, options);
    let mut out = vec![
        Contestant {
            name: "grid".into(),
            accel: Accel::build(prims, AccelKind::Grid),
        },
        Contestant {
            name: "bvh2 midpoint".into(),
            accel: with(
                AccelKind::Bvh2,
                BuildOptions {
                    builder: Builder::Midpoint,
                    ..BuildOptions::default()
                },
            ),
        },
        Contestant {
            name: "bvh2 sah".into(),
            accel: Accel::build(prims, AccelKind::Bvh2),
        },
    ];
    if !Simd::Avx2.available() {
        eprintln!("this CPU has no AVX2: the wide BVHs run their portable kernels only");
    }
    for (kind, width) in [(AccelKind::Bvh4, "bvh4"), (AccelKind::Bvh8, "bvh8")] {
        let built = Accel::build(prims, kind);
        let variants: Vec<Contestant> = SIMD
            .iter()
            .filter_map(|&(simd, set)| {
                let mut accel = built.clone();
                accel.set_simd(simd).then(|| Contestant {
                    name: format!("{width} {set}"),
                    accel,
                })
            })
            .collect();
        if variants.is_empty() {
            // Beyond the wide BVHs' primitive limit: the BVH2 the build falls back to.
            out.push(Contestant {
                name: format!("{width} (bvh2 fallback)"),
                accel: built,
            });
        }
        out.extend(variants);
        if kind == AccelKind::Bvh4 {
            out.push(Contestant {
                name: "bvh4 4 bins".into(),
                accel: with(
                    kind,
                    BuildOptions {
                        bins: 4,
                        ..BuildOptions::default()
                    },
                ),
            });
        }
    }
    out
}
