//! The stream kernel of the wide BVHs: many rays (hundreds to thousands, in any directions) taken down
//! the tree together, the stream partitioned at each node by the children each ray enters (Barringer
//! and Akenine-Möller 2014, "Dynamic Ray Stream Traversal"; Tsakok 2009). Each ray pays what the
//! single-ray kernel pays for a node (its own `W`-lane slab test of the children, [`slab`]) and a node
//! is loaded once for all the rays that reach it, where the single-ray kernel loads it once per ray:
//! a stream can only win on memory traffic, on a tree too large for the caches. Where a node's stream
//! has thinned to fewer than [`STREAM_MIN`] rays, each goes on alone through the single-ray kernel
//! ([`WideBvh::descend`]), whose stack costs less than a stream's lists.
//!
//! Closest hit visits a node's children nearest first by the least entry distance of their rays, and
//! drops a ray from a child whose box it enters beyond its closest hit so far (the single-ray kernel's
//! test when it pops); any hit drops a ray at its first hit. Each ray's answer is the single-ray
//! kernel's: the same slab and leaf tests, a hit kept only when strictly nearer.

use std::cell::RefCell;
use std::marker::PhantomData;

use wide::{f32x4, f32x8};

use super::lanes::{Lanes, Lanes8, OnLanes8};
use super::order::sort_far_to_near;
use super::slab::{SlabRay, SlabRays, slab};
use super::{Bvh4, Bvh8, ChildRef, EMPTY, LEAF, WideBvh};
use crate::accel::counters;
use crate::accel::policy::HitPolicy;
use crate::accel::prims::Hit;
use crate::geometry::ray::{CULL_MARGIN, Ray, ahead};

/// Below this many rays a node's stream goes on ray by ray: each ray pays a single ray's node test plus
/// its place in the lists, and what a stream saves is loads from memory (`profiles/README.md`).
pub const STREAM_MIN: usize = 64;

/// A ray of a node's stream: its index in the caller's slice and its entry distance into the node's box.
#[derive(Clone, Copy, Debug)]
struct Entry {
    ray: u32,
    t: f32,
}

/// A node (or leaf) still to visit, and where its rays start on the list stack (they run to its top).
#[derive(Clone, Copy, Debug)]
struct Frame {
    child: ChildRef,
    start: usize,
}

/// A worker's lists, kept from stream to stream (nothing is allocated per ray, and after the first
/// streams nothing at all): the rays prepared for slab tests, the stack of lists (each frame's rays on
/// top of its parent's siblings'), the stack of frames, and a list per child slot for partitioning.
#[derive(Default)]
struct Scratch {
    prepared: Vec<SlabRay>,
    entries: Vec<Entry>,
    frames: Vec<Frame>,
    parts: [Vec<Entry>; 8],
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::default();
}

impl Bvh4<'_> {
    /// [`Bvh4::traverse`] for each ray of `rays`, as a stream: `hits[i]` and `found[i]` are ray `i`'s.
    pub fn traverse_stream<P: HitPolicy>(
        &self,
        rays: &[Ray],
        t_min: f32,
        hits: &mut [Hit],
        found: &mut [bool],
    ) {
        self.stream::<P, f32x4, f32x8>(rays, t_min, hits, found);
    }
}

impl Bvh8<'_> {
    /// [`Bvh8::traverse`] for each ray of `rays`, as a stream, on the instruction set chosen at build
    /// time: `hits[i]` and `found[i]` are ray `i`'s.
    pub fn traverse_stream<P: HitPolicy>(
        &self,
        rays: &[Ray],
        t_min: f32,
        hits: &mut [Hit],
        found: &mut [bool],
    ) {
        self.simd.run8(Stream::<P> {
            bvh: self,
            rays,
            t_min,
            hits,
            found,
            policy: PhantomData,
        });
    }
}

/// The BVH8's stream kernel as a computation over eight lanes, for [`super::isa::Simd::run8`].
struct Stream<'r, 'b, P> {
    bvh: &'r Bvh8<'b>,
    rays: &'r [Ray],
    t_min: f32,
    hits: &'r mut [Hit],
    found: &'r mut [bool],
    policy: PhantomData<P>,
}

impl<P: HitPolicy> OnLanes8 for Stream<'_, '_, P> {
    type Output = ();

    #[inline(always)]
    fn run<L: Lanes8>(self) {
        self.bvh
            .stream::<P, L, L>(self.rays, self.t_min, self.hits, self.found);
    }
}

impl<const W: usize> WideBvh<'_, W> {
    /// The one stream traversal, for both policies, every width and every lane type.
    #[inline(always)]
    fn stream<P: HitPolicy, L: Lanes<W>, T: Lanes8>(
        &self,
        rays: &[Ray],
        t_min: f32,
        hits: &mut [Hit],
        found: &mut [bool],
    ) {
        assert!(
            hits.len() == rays.len() && found.len() == rays.len() && rays.len() <= u32::MAX as usize,
            "a hit and a flag per ray"
        );
        let t_min = ahead(t_min);
        // Taken out of the thread-local and put back, not borrowed in a closure: a closure is compiled
        // without the caller's target features, leaving its intrinsics as calls (`profiles/README.md`).
        let mut scratch = SCRATCH.take();
        let Scratch {
            prepared,
            entries,
            frames,
            parts,
        } = &mut scratch;
        prepared.clear();
        entries.clear();
        frames.clear();
        for (i, ray) in rays.iter().enumerate() {
            counters::at::<P>(i);
            found[i] = self.prims.intersect_planes::<P>(ray, t_min, &mut hits[i]);
            prepared.push(SlabRay::new::<W, L>(ray));
            if !(P::ANY && found[i]) {
                entries.push(Entry {
                    ray: i as u32,
                    t: t_min,
                });
            }
        }
        if self.root != EMPTY {
            frames.push(Frame {
                child: self.root,
                start: 0,
            });
        }
        while let Some(Frame { child, start }) = frames.pop() {
            // The rays that may still find a (nearer) hit under `child`: closest hit drops those
            // whose entry lies beyond their hit so far, any hit those that found one.
            let mut live = start;
            for j in start..entries.len() {
                let e = entries[j];
                let i = e.ray as usize;
                if if P::ANY {
                    !found[i]
                } else {
                    e.t <= hits[i].t * CULL_MARGIN
                } {
                    entries[live] = e;
                    live += 1;
                }
            }
            entries.truncate(live);
            if live - start < STREAM_MIN || child & LEAF != 0 {
                if child & LEAF != 0 {
                    for i in entries.drain(start..).map(|e| e.ray as usize) {
                        counters::at::<P>(i);
                        self.leaf::<P, T>(child, &rays[i], t_min, &mut hits[i], &mut found[i]);
                    }
                } else {
                    for i in entries.drain(start..).map(|e| e.ray as usize) {
                        counters::at::<P>(i);
                        let r = SlabRays::<L>::one(&prepared[i]);
                        self.descend::<P, L, T>(child, &rays[i], &r, t_min, &mut hits[i], &mut found[i]);
                    }
                }
                continue;
            }
            // Each ray's own slab test of the node's children, the stream split by child.
            let node = &self.nodes[child as usize];
            let plane = |axis: usize, max: bool| L::load(if max { &node.max[axis] } else { &node.min[axis] });
            let mut nearest = [f32::INFINITY; W];
            for e in entries.drain(start..) {
                let i = e.ray as usize;
                counters::at::<P>(i);
                counters::node::<P>();
                let r = SlabRays::<L>::one(&prepared[i]);
                let (lanes, mut mask) = slab(&r, plane, L::splat(t_min), L::splat(hits[i].t * CULL_MARGIN));
                let t = lanes.to_array();
                while mask != 0 {
                    let k = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    parts[k].push(Entry { ray: e.ray, t: t[k] });
                    nearest[k] = nearest[k].min(t[k]);
                }
            }
            // The children far to near (popped near to far), each with its rays on the list stack.
            let mut order = [0usize; W];
            let mut n = 0;
            for (k, part) in parts.iter().enumerate().take(W) {
                if !part.is_empty() {
                    order[n] = k;
                    n += 1;
                }
            }
            if !P::ANY {
                sort_far_to_near(&mut order[..n], |&k| nearest[k]);
            }
            for &k in &order[..n] {
                self.prefetch(node.child[k]);
                frames.push(Frame {
                    child: node.child[k],
                    start: entries.len(),
                });
                entries.append(&mut parts[k]);
            }
        }
        SCRATCH.set(scratch);
    }
}
