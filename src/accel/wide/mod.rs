//! Wide BVHs: the SAH BVH2 collapsed to `W` children per node (Dammertz et al. 2008, "Shallow Bounding
//! Volume Hierarchies for Fast SIMD Ray Tracing of Incoherent Rays"; Wald et al. 2008) and flattened
//! depth-first into one array. Each node keeps its children's boxes as structure of arrays, so one
//! `W`-lane slab test answers all of them at once.
//!
//! One structure and one collapse (`collapse.rs`) serve both widths: [`Bvh4`] (4 lanes of SSE, the
//! default where the CPU lacks AVX2) and [`Bvh8`] (8 lanes: one AVX2 register where the CPU has AVX2,
//! detected at run time, else two SSE halves). Their kernels are a pair, each written once for both
//! widths, both hit policies and every instruction set: one ray (`single.rs`) and a packet of eight
//! (`packet.rs`). Both test boxes with the one slab test
//! (`slab.rs`) on the SIMD lanes (`lanes/`) of the instruction set chosen at run time (`isa.rs`),
//! order the children they enter by `order.rs`, and test leaves four or eight triangles at a time
//! (`tri4.rs`). Wider nodes mean fewer node visits and fewer stack operations per ray (`profiles/`).

mod collapse;
pub(crate) mod isa;
mod lanes;
mod order;
mod packet;
mod single;
mod slab;
pub mod tri4;

pub use isa::Isa;
pub(crate) use isa::Simd;
pub(crate) use lanes::{Lanes, Lanes8, OnLanes8};

use glam::Vec3;

use super::BuildOptions;
use super::bvh2::{self, Bvh2, Stats};
use super::packet::{HitPacket, RayPacket};
use super::pages::on_huge_pages;
use super::policy::HitPolicy;
use super::prims::{Hit, Prims};
use super::structure::Structure;
use crate::geometry::aabb::Aabb;
use crate::geometry::ray::Ray;

/// A child reference: an interior node's index, a leaf, or [`EMPTY`]. A leaf is
/// `LEAF | start << COUNT_BITS | count`, with [`TRIANGLES`] set when it holds triangles: then `start` is
/// its first block of [`tri4::Tri4`] (`⌈count / 4⌉` blocks), else the first of its ids.
pub type ChildRef = u32;
/// Marks a leaf reference.
pub const LEAF: u32 = 1 << 31;
/// Marks a leaf of triangles (tested four at a time).
pub const TRIANGLES: u32 = 1 << 30;
/// Bits of a leaf reference that hold its primitive count.
pub const COUNT_BITS: u32 = 4;
/// An unused child slot (its box is inverted, so no ray ever enters it).
pub const EMPTY: ChildRef = u32::MAX;
/// Traversal stack depth (single rays and packets), for any width up to 8: a node pushes at most
/// eight children and pops one, so seven entries per level of a tree no deeper than the BVH2 it was
/// collapsed from. The stack is not cleared (`Stack`), so its size costs only address space.
const STACK: usize = 7 * bvh2::MAX_TREE_DEPTH + 1;
/// The most primitives a wide BVH can index: what fits a leaf reference's start beside its count.
pub const MAX_PRIMS: u32 = 1 << (30 - COUNT_BITS);

/// A node: its `W` children's boxes as component arrays, then their references. Aligned to a 64-byte
/// cache line: a 4-wide node (112 bytes) spans exactly two lines, an 8-wide one (224 bytes) four.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct Node<const W: usize> {
    /// Children's smallest x, y, z.
    pub min: [[f32; W]; 3],
    /// Children's largest x, y, z.
    pub max: [[f32; W]; 3],
    /// Children.
    pub child: [ChildRef; W],
}

/// A 4-wide node.
pub type Node4 = Node<4>;
/// An 8-wide node.
pub type Node8 = Node<8>;

impl<const W: usize> Node<W> {
    /// A node with every slot empty (inverted boxes).
    pub const EMPTY: Self = Node {
        min: [[f32::INFINITY; W]; 3],
        max: [[f32::NEG_INFINITY; W]; 3],
        child: [EMPTY; W],
    };
}

/// A leaf reference's start (first block or first id) and primitive count.
#[inline(always)]
pub fn leaf_parts(r: ChildRef) -> (usize, usize) {
    (
        ((r & !(LEAF | TRIANGLES)) >> COUNT_BITS) as usize,
        (r & ((1 << COUNT_BITS) - 1)) as usize,
    )
}

/// A `W`-wide BVH over a scene's bounded primitives (planes are tested beside it).
#[derive(Clone, Debug)]
pub struct WideBvh<'a, const W: usize> {
    prims: Prims<'a>,
    /// Nodes in depth-first order, the root first.
    nodes: Vec<Node<W>>,
    /// Primitive ids in leaf order (each leaf's primitives are contiguous).
    ids: Vec<u32>,
    /// Triangle leaves' blocks, four triangles each in SoA form.
    tris: Vec<tri4::Tri4>,
    /// The root reference (a node, a lone leaf, or [`EMPTY`] for a scene without bounded primitives).
    root: ChildRef,
    /// The box around everything.
    bounds: Aabb,
    /// The kernels' instruction set, chosen at build time from the CPU.
    simd: Simd,
}

/// The 4-wide BVH (the default accelerator on CPUs without AVX2).
pub type Bvh4<'a> = WideBvh<'a, 4>;
/// The 8-wide BVH.
pub type Bvh8<'a> = WideBvh<'a, 8>;

impl<'a, const W: usize> WideBvh<'a, W> {
    /// Builds the default tree ([`BuildOptions::DEFAULT`]: binned SAH, then reinsertion) with `bins`
    /// bins and collapses it. Scenes beyond [`MAX_PRIMS`] primitives have no wide BVH.
    pub fn new(prims: Prims<'a>, bins: usize) -> Option<Self> {
        Self::build(
            prims,
            &BuildOptions {
                bins,
                ..BuildOptions::default()
            },
        )
    }

    /// Builds the BVH2 `options` describe with the binned SAH ([`BuildOptions::sah`]) and collapses
    /// it. Scenes beyond [`MAX_PRIMS`] primitives have no wide BVH.
    pub fn build(prims: Prims<'a>, options: &BuildOptions) -> Option<Self> {
        if prims.bounded() > MAX_PRIMS {
            return None;
        }
        Some(Self::from_bvh2(Bvh2::build_with_block(prims, &options.sah(), 4)))
    }

    /// Collapses a BVH2 (whose leaves hold one kind, at most 15 primitives each).
    pub fn from_bvh2(bvh2: Bvh2<'a>) -> Self {
        let c = collapse::collapse::<W>(&bvh2.nodes, &bvh2.ids, bvh2.prims());
        WideBvh {
            prims: *bvh2.prims(),
            nodes: on_huge_pages(c.nodes),
            ids: bvh2.ids,
            tris: c.tris,
            root: c.root,
            bounds: bvh2.nodes.first().map_or(Aabb::EMPTY, |n| n.bounds),
            simd: Simd::detect(),
        }
    }

    /// The scene's primitives.
    pub fn prims(&self) -> Prims<'a> {
        self.prims
    }

    /// The instruction set the kernels use (the BVH4's single-ray kernel is SSE on any CPU).
    pub fn simd(&self) -> Isa {
        self.simd.isa()
    }

    /// Uses `simd` for the kernels (tests and benchmarks compare the paths); one the CPU lacks is
    /// refused and the current one kept.
    pub fn set_simd(&mut self, simd: Isa) -> bool {
        match Simd::new(simd) {
            Some(simd) => {
                self.simd = simd;
                true
            }
            None => false,
        }
    }

    /// Asks the CPU to start loading child `r` (an interior node's cache lines, or a triangle leaf's first
    /// block) while the kernel goes on with another, as Embree's traversal does for every child a ray
    /// enters. A hint only: no fault, no change to any answer; nothing on other architectures.
    #[inline(always)]
    pub(super) fn prefetch(&self, r: ChildRef) {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let (p, bytes) = if r & LEAF == 0 {
                (
                    self.nodes.as_ptr().wrapping_add(r as usize) as *const i8,
                    size_of::<Node<W>>(),
                )
            } else if r & TRIANGLES != 0 {
                let start = leaf_parts(r).0;
                (
                    self.tris.as_ptr().wrapping_add(start) as *const i8,
                    size_of::<tri4::Tri4>(),
                )
            } else {
                return;
            };
            for line in (0..bytes).step_by(64) {
                // SAFETY: a prefetch reads nothing architecturally and cannot fault, whatever the
                // address (`wrapping_add` keeps the pointer arithmetic itself defined).
                unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(line)) };
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = r;
    }

    /// The root reference (a node, a lone leaf, or [`EMPTY`] for a scene without bounded primitives).
    pub fn root(&self) -> ChildRef {
        self.root
    }

    /// The box around everything.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// The nodes in depth-first order, the root first.
    pub fn nodes(&self) -> &[Node<W>] {
        &self.nodes
    }

    /// The primitive ids of the leaf `r` (a [`LEAF`] reference), in leaf order.
    pub fn leaf_ids(&self, r: ChildRef) -> Vec<u32> {
        let (start, count) = leaf_parts(r);
        if r & TRIANGLES != 0 {
            let blocks = &self.tris[start..start + count.div_ceil(4)];
            blocks.iter().flat_map(|b| b.id).take(count).collect()
        } else {
            self.ids[start..start + count].to_vec()
        }
    }

    /// The box of child slot `k` of node `n`.
    pub fn child_bounds(n: &Node<W>, k: usize) -> Aabb {
        Aabb::new(
            Vec3::new(n.min[0][k], n.min[1][k], n.min[2][k]),
            Vec3::new(n.max[0][k], n.max[1][k], n.max[2][k]),
        )
    }

    /// Node count (leaves included), depth, leaf sizes and SAH cost, weighted as for the BVH2 (each node
    /// visited costs one traversal step, each leaf one test per primitive, in proportion to their area,
    /// so the figures compare across structures).
    pub fn stats(&self) -> Stats {
        let mut s = Stats::default();
        let root_area = self.bounds.area().max(f32::MIN_POSITIVE) as f64;
        let mut stack = vec![(self.root, 1.0f64, 1usize)];
        while let Some((r, rel, depth)) = stack.pop() {
            if r == EMPTY {
                continue;
            }
            s.nodes += 1;
            s.depth = s.depth.max(depth);
            if r & LEAF != 0 {
                let count = leaf_parts(r).1;
                s.leaves += 1;
                s.add_leaf(count);
                s.sah += bvh2::INTERSECTION_COST as f64 * count as f64 * rel;
                continue;
            }
            s.sah += bvh2::TRAVERSAL_COST as f64 * rel;
            let n = &self.nodes[r as usize];
            for k in 0..W {
                let area = Self::child_bounds(n, k).area() as f64;
                stack.push((n.child[k], area / root_area, depth + 1));
            }
        }
        s
    }
}

/// The structure's verbs for one width, each through its kernel.
macro_rules! wide_structure {
    ($bvh:ident, |$b:ident| $describe:expr) => {
        impl<'a> Structure<'a> for $bvh<'a> {
            fn prims(&self) -> Prims<'a> {
                self.prims
            }

            fn describe(&self) -> String {
                let $b = self;
                $describe
            }

            fn has_packet_kernel(&self) -> bool {
                true
            }

            fn simd(&self) -> Option<Isa> {
                Some($bvh::simd(self))
            }

            fn set_simd(&mut self, simd: Isa) -> bool {
                $bvh::set_simd(self, simd)
            }

            #[inline(always)]
            fn traverse<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
                $bvh::traverse::<P>(self, ray, t_min, hit)
            }

            #[inline(always)]
            fn traverse_packet<P: HitPolicy>(
                &self,
                rays: &RayPacket,
                active: u8,
                t_min: f32,
                hits: &mut HitPacket,
            ) -> u8 {
                $bvh::traverse_packet::<P>(self, rays, active, t_min, hits)
            }
        }
    };
}

wide_structure!(Bvh4, |b| format!("bvh4: {}", b.stats()));
wide_structure!(Bvh8, |b| format!(
    "bvh8 ({:?} slab tests): {}",
    b.simd(),
    b.stats()
));
