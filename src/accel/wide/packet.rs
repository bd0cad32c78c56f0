//! The packet kernel: eight coherent rays (a tile's primary rays, or the shadow rays of their hits)
//! traced through a wide BVH (either width) together, for closest or any hit.
//!
//! I. Wald, P. Slusallek, C. Benthin, M. Wagner, "Interactive Rendering with Coherent Ray Tracing",
//! *Computer Graphics Forum* 20(3), 2001: rays that start together and point alike visit nearly the same
//! nodes, so one traversal with a mask of active rays serves them all, each node fetched and decided once
//! per packet, its boxes tested against every ray in SIMD lanes. As in Embree's hybrid packet kernels
//! (`kernels/bvh/bvh_intersector_hybrid.cpp`; I. Wald et al., "Embree: A Kernel Framework for Efficient
//! CPU Ray Tracing", *ACM TOG* 33(4), 2014) and R. Overbeck, R. Ramamoorthi, W. R. Mark, "Large Ray
//! Packets for Real-time Whitted Ray Tracing", *IEEE RT* 2008, the packet holds its rays in structure of
//! arrays (lane `k` of every vector is ray `k`) and keeps one stack of node references, each entry
//! carrying the mask of rays that entered it and their entry distances; a ray leaves an entry once it
//! has a hit nearer than its entry, and an entry no ray is left in is skipped.
//!
//! What is SIMD over the rays: every child box test (the node's boxes two at a time, each against the
//! eight lanes, through the same [`slab`] as the single-ray kernel) and the culling of stack entries; the
//! whole kernel runs on the lane type of the instruction set the BVH chose ([`super::isa::Simd`]).
//! What goes ray by ray: the leaves, each active ray through the single-ray kernel's own leaf test
//! ([`WideBvh::leaf`]), and the planes beside the hierarchy. Testing one triangle against the eight lanes
//! instead (bit-identical Möller–Trumbore in `f32x8`) was measured slower: it fetches each triangle from
//! the scene's arrays (the leaf blocks keep their lanes private), and even with AVX2 the per-ray blocks
//! were faster on the dragon.
//!
//! The answers are the single-ray kernel's ([`super::Bvh4::traverse`]): the per-lane box arithmetic is its
//! operation for operation on the same lanes (the near/far planes by each ray's own direction signs,
//! [`SLAB_ROBUST`] on the exit, [`CULL_MARGIN`] on the hit; where the packets' lanes have FMA and the
//! BVH4's SSE single rays do not, the fused and unfused forms of the slab test (`slab.rs`), both of which
//! enter every box holding a hit), so a ray is never kept out of a box that holds its hit, and each
//! leaf runs the single-ray kernel's leaf code, so hits, and ties inside a leaf, come out bit for bit
//! the same. Only the order of leaves differs (the packet's, not each ray's), which
//! could matter only for two primitives in different leaves hit at bit-identical `t`.
//!
//! [`SLAB_ROBUST`]: crate::geometry::ray::SLAB_ROBUST

use std::marker::PhantomData;

use super::lanes::{Lanes8, OnLanes8, Twice};
use super::order::sort_far_to_near;
use super::slab::{SlabRays, slab};
use super::{ChildRef, EMPTY, LEAF, STACK, WideBvh};
use crate::accel::counters;
use crate::accel::packet::{HitPacket, PACKET, RayPacket, bits};
use crate::accel::policy::HitPolicy;
use crate::accel::stack::Stack;
use crate::geometry::ray::{CULL_MARGIN, ahead};

/// A stack entry: a child, the mask of the rays that entered it, their entry distances, and the entry
/// of the first of them (the key that orders a node's children).
#[derive(Clone, Copy)]
struct Entry<L> {
    node: ChildRef,
    mask: u8,
    key: f32,
    entry: L,
}

impl<const W: usize> WideBvh<'_, W> {
    /// Traces the rays of `rays` whose bit is set in `active`, each from `t_min` to its `hits[k].t`, and
    /// returns the mask of those that hit. For every active ray `k` the outcome is that of
    /// `self.traverse::<P>(&rays[k], t_min, &mut hits[k])`: for closest hit the same `Hit` bit for bit,
    /// for any hit the same hit-or-miss (perhaps through a different primitive). Inactive rays' hits are
    /// left as they are. Meant for coherent rays; incoherent ones get the right answers, slowly.
    ///
    /// Per node, the `W` child boxes are tested against the rays of the entry's mask; the children any
    /// of them enters are pushed with the mask of those rays and their entry distances, for closest hit
    /// in far-to-near order of the first such ray's entry (Wald et al. 2001), so that for a coherent
    /// packet every ray meets its nearest hit early and culls the rest. A popped entry keeps the rays
    /// whose entry is within their hit so far (with [`CULL_MARGIN`], as the single-ray kernel) or, for any
    /// hit, those still without one.
    #[inline]
    pub fn traverse_packet<P: HitPolicy>(
        &self,
        rays: &RayPacket,
        active: u8,
        t_min: f32,
        hits: &mut HitPacket,
    ) -> u8 {
        self.simd.run8(Packet::<P, W> {
            bvh: self,
            rays,
            active,
            t_min,
            hits,
            policy: PhantomData,
        })
    }
}

/// The packet kernel as a computation over eight lanes, for [`super::isa::Simd::run8`].
struct Packet<'r, 'b, P, const W: usize> {
    bvh: &'r WideBvh<'b, W>,
    rays: &'r RayPacket,
    active: u8,
    t_min: f32,
    hits: &'r mut HitPacket,
    policy: PhantomData<P>,
}

impl<P: HitPolicy, const W: usize> OnLanes8 for Packet<'_, '_, P, W> {
    type Output = u8;

    /// The packet kernel's one body, over the lane type `L`.
    #[inline(always)]
    fn run<L: Lanes8>(self) -> u8 {
        let Packet {
            bvh,
            rays,
            active,
            t_min,
            hits,
            ..
        } = self;
        let t_min = ahead(t_min);
        // The planes first, ray by ray, as the single-ray kernel does.
        let mut found = 0u32;
        for k in bits(active) {
            counters::at::<P>(k);
            if bvh.prims.intersect_planes::<P>(&rays[k], t_min, &mut hits[k]) {
                found |= 1 << k;
            }
        }
        // Rays still searching: any-hit is done with a ray once it has a hit.
        let mut live = active as u32 & if P::ANY { !found } else { u32::MAX };
        if live == 0 || bvh.root == EMPTY {
            return found as u8;
        }
        // The rays twice over, for two boxes a step (both widths are even).
        const { assert!(W.is_multiple_of(2)) };
        let p2 = SlabRays::<L>::packet(rays, live).doubled();
        let lo = L::splat(t_min);
        let lo2 = Twice(lo, lo);
        let margin = L::splat(CULL_MARGIN);
        // The rays' hit distances, kept in lanes beside `hits`.
        let limits = |hits: &HitPacket| {
            let mut t = [0.0; PACKET];
            for (t, h) in t.iter_mut().zip(hits) {
                *t = h.t;
            }
            L::load(&t)
        };
        let mut t_hit = limits(hits);
        let mut stack = Stack::<Entry<L>, STACK>::new();
        let (mut current, mut mask) = (bvh.root, live);
        loop {
            if current & LEAF != 0 {
                let mut hit = 0;
                for k in bits(mask as u8) {
                    let mut one = false;
                    counters::at::<P>(k);
                    bvh.leaf::<P, L>(current, &rays[k], t_min, &mut hits[k], &mut one);
                    hit |= u32::from(one) << k;
                }
                if hit != 0 {
                    found |= hit;
                    if P::ANY {
                        live &= !hit;
                        if live == 0 {
                            return found as u8;
                        }
                    }
                    t_hit = limits(hits);
                }
            } else {
                // The node's boxes are tested against every ray of the mask.
                counters::nodes::<P>(mask);
                let node = &bvh.nodes[current as usize];
                let t_max = t_hit.mul(margin);
                let start = stack.len();
                let t_max2 = Twice(t_max, t_max);
                // Two children a step (see `Twice`; faster than one: `profiles/README.md`), the pairs
                // written out (`W` is 4 or 8), which compiles to fewer instructions a node than a loop.
                // The collapse fills a node's slots first to last: the first empty one ends them (an
                // empty second slot of a pair has an inverted box, which no ray enters).
                macro_rules! pair {
                    ($pairs:lifetime, $c:expr) => {{
                        let c = $c;
                        if node.child[c] == EMPTY {
                            break $pairs;
                        }
                        let plane = |axis: usize, max: bool| {
                            let a = if max {
                                &node.max[axis]
                            } else {
                                &node.min[axis]
                            };
                            Twice(L::splat(a[c]), L::splat(a[c + 1]))
                        };
                        let (Twice(entry0, entry1), entered) = slab(&p2, plane, lo2, t_max2);
                        for (k, entry, entered) in
                            [(c, entry0, entered & 0xff), (c + 1, entry1, entered >> 8)]
                        {
                            let entered = entered & mask;
                            if entered != 0 {
                                bvh.prefetch(node.child[k]);
                                stack.push(Entry {
                                    node: node.child[k],
                                    mask: entered as u8,
                                    key: entry.to_array()[entered.trailing_zeros() as usize],
                                    entry,
                                });
                            }
                        }
                    }};
                }
                'pairs: {
                    pair!('pairs, 0);
                    pair!('pairs, 2);
                    if W > 4 {
                        pair!('pairs, 4);
                        pair!('pairs, 6);
                    }
                }
                match stack.len() - start {
                    0 => {}
                    // One child entered: straight down, its rays have just passed the test.
                    1 => {
                        let e = stack.pop().expect("just pushed");
                        (current, mask) = (e.node, e.mask as u32);
                        continue;
                    }
                    _ if !P::ANY => sort_far_to_near(stack.above_mut(start), |e| e.key),
                    _ => {}
                }
            }
            // Pop the next entry that some ray may still find a (closer) hit in.
            loop {
                let Some(e) = stack.pop() else {
                    return found as u8;
                };
                let m = e.mask as u32
                    & if P::ANY {
                        live
                    } else {
                        e.entry.le(t_hit.mul(margin))
                    };
                if m != 0 {
                    (current, mask) = (e.node, m);
                    break;
                }
            }
        }
    }
}
#[cfg(test)]
mod tests {
    use std::path::Path;

    use glam::Vec3;

    use super::*;
    use crate::accel::policy::{AnyHit, Closest};
    use crate::accel::prims::Hit;
    use crate::accel::prims::Prims;
    use crate::accel::wide::Bvh4;
    use crate::geometry::ray::Ray;
    use crate::geometry::ray::testing::TestRng;
    use crate::render::camera::RayCamera;
    use crate::scene::Scene;

    fn load(name: &str) -> Scene {
        crate::scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(name)).unwrap()
    }

    const SCENES: [&str; 2] = ["scenes/dragon.p3f", "scenes/spd/gears_1.nff"];

    fn bits(h: &Hit) -> (u32, u32, u32, u32) {
        (h.t.to_bits(), h.prim, h.u.to_bits(), h.v.to_bits())
    }

    /// Traces a packet both ways for policy `P` and asserts they agree: closest hit bit for bit, any hit
    /// in its hit-or-miss answer; inactive lanes untouched. Returns the packet's hits and found mask.
    fn check<P: HitPolicy>(
        bvh: &Bvh4,
        rays: &RayPacket,
        active: u8,
        t_min: f32,
        t_max: [f32; PACKET],
        what: &str,
    ) -> ([Hit; PACKET], u8) {
        let sentinel = Hit {
            t: -7.0,
            prim: 12345,
            u: 0.5,
            v: 0.25,
        };
        let mut hits: [Hit; PACKET] = std::array::from_fn(|k| {
            if active >> k & 1 == 1 {
                Hit::miss(t_max[k])
            } else {
                sentinel
            }
        });
        let found = bvh.traverse_packet::<P>(rays, active, t_min, &mut hits);
        for k in 0..PACKET {
            if active >> k & 1 == 0 {
                assert_eq!(
                    bits(&hits[k]),
                    bits(&sentinel),
                    "{what}: inactive lane {k} touched"
                );
                assert_eq!(found >> k & 1, 0, "{what}: inactive lane {k} reported");
                continue;
            }
            let mut want = Hit::miss(t_max[k]);
            let hit = bvh.traverse::<P>(&rays[k], t_min, &mut want);
            assert_eq!(found >> k & 1 == 1, hit, "{what}: lane {k} {:?}", rays[k]);
            if P::ANY {
                assert_eq!(hits[k].is_hit(), hit, "{what}: lane {k}");
            } else {
                assert_eq!(bits(&hits[k]), bits(&want), "{what}: lane {k} {:?}", rays[k]);
            }
        }
        (hits, found)
    }

    /// The camera's rays through the pixel centres in 2×4 blocks, row by row (the last row and column
    /// repeated where the image is not a multiple of the block).
    fn camera_packets(scene: &Scene, w: u32, h: u32) -> Vec<[Ray; PACKET]> {
        let cam = RayCamera::new(&scene.camera, w, h);
        let mut out = Vec::new();
        for y in (0..h).step_by(2) {
            for x in (0..w).step_by(4) {
                out.push(std::array::from_fn(|k| {
                    let (px, py) = (x + k as u32 % 4, (y + k as u32 / 4).min(h - 1));
                    cam.ray(px.min(w - 1) as f32 + 0.5, py as f32 + 0.5)
                }));
            }
        }
        out
    }

    /// Shadow rays from a packet's closest hits toward `light`, leaving the surface on the side the camera
    /// ray came from, each limited to the light's distance; misses are inactive.
    fn shadow_packet(
        bvh: &Bvh4,
        rays: &RayPacket,
        hits: &[Hit; PACKET],
        found: u8,
        light: Vec3,
    ) -> ([Ray; PACKET], [f32; PACKET]) {
        let mut t_max = [0.0; PACKET];
        let shadow = std::array::from_fn(|k| {
            if found >> k & 1 == 0 {
                return rays[k];
            }
            let s = bvh.prims.surface(&rays[k], &hits[k]);
            let origin = s.point + s.geometric * 1e-4;
            let l = light - origin;
            t_max[k] = l.length();
            Ray::new(origin, l / t_max[k])
        });
        (shadow, t_max)
    }

    fn bvh(scene: &Scene) -> Bvh4<'_> {
        Bvh4::new(Prims::new(scene), 12).unwrap()
    }

    /// Camera packets over the whole image, all lanes and random subsets, closest and any hit; then the
    /// shadow rays of their hits toward the lights in turn, any hit (and closest, for good measure).
    #[test]
    fn camera_and_shadow_packets_match_single_rays() {
        let mut rng = TestRng::new(5);
        for name in SCENES {
            let scene = load(name);
            let bvh = bvh(&scene);
            let lights: Vec<Vec3> = scene.point_lights.iter().map(|l| l.position).collect();
            assert!(!lights.is_empty(), "{name}");
            let (mut hit_rays, mut shadowed) = (0, 0);
            for (i, rays) in camera_packets(&scene, 200, 150).iter().enumerate() {
                let inf = [f32::INFINITY; PACKET];
                let (hits, found) = check::<Closest>(&bvh, rays, 0xff, 0.0, inf, name);
                hit_rays += found.count_ones();
                let subset = (rng.unit_f32() * 256.0) as u8;
                check::<Closest>(&bvh, rays, subset, 0.0, inf, name);
                check::<AnyHit>(&bvh, rays, subset, 0.0, inf, name);
                let light = lights[i % lights.len()];
                let (shadow, t_max) = shadow_packet(&bvh, rays, &hits, found, light);
                let (_, blocked) = check::<AnyHit>(&bvh, &shadow, found, 0.0, t_max, name);
                shadowed += blocked.count_ones();
                check::<Closest>(&bvh, &shadow, found, 0.0, t_max, name);
                check::<AnyHit>(&bvh, &shadow, found & subset, 0.0, t_max, name);
            }
            // The scenes are worth testing on: most camera rays hit, and some shadow rays are blocked.
            assert!(hit_rays > 200 * 150 / 3, "{name}: {hit_rays}");
            assert!(shadowed > 200, "{name}: {shadowed}");
        }
    }

    /// Eight unrelated rays per packet: origins all over the scene's box, directions of every sign, some
    /// components exactly zero, some with finite limits and a positive `t_min`.
    #[test]
    fn incoherent_packets_match_single_rays() {
        let mut rng = TestRng::new(17);
        for name in SCENES {
            let scene = load(name);
            let bvh = bvh(&scene);
            let (lo, hi) = (bvh.bounds.min, bvh.bounds.max);
            let mut hit_rays = 0;
            for i in 0..3000 {
                let rays: [Ray; PACKET] = std::array::from_fn(|_| {
                    let f = Vec3::new(rng.unit_f32(), rng.unit_f32(), rng.unit_f32());
                    let origin = lo + (hi - lo) * (f * 1.4 - 0.2);
                    let mut dir = rng.direction();
                    for axis in 0..3 {
                        if rng.unit_f32() < 0.15 {
                            dir[axis] = 0.0;
                        }
                    }
                    if dir == Vec3::ZERO {
                        dir = Vec3::NEG_Y;
                    }
                    Ray::new(origin, dir * rng.range(0.5, 2.0))
                });
                let t_max = std::array::from_fn(|_| {
                    if rng.unit_f32() < 0.3 {
                        rng.range(0.0, (hi - lo).length())
                    } else {
                        f32::INFINITY
                    }
                });
                let t_min = if i % 4 == 0 { rng.range(0.0, 0.5) } else { 0.0 };
                let active = if i % 3 == 0 {
                    (rng.unit_f32() * 256.0) as u8
                } else {
                    0xff
                };
                let (_, found) = check::<Closest>(&bvh, &rays, active, t_min, t_max, name);
                hit_rays += found.count_ones();
                check::<AnyHit>(&bvh, &rays, active, t_min, t_max, name);
            }
            assert!(hit_rays > 1000, "{name}: {hit_rays}");
        }
    }

    /// No active ray: nothing is touched and nothing found; a scene without bounded primitives (planes
    /// only) still answers through the planes.
    #[test]
    fn empty_mask_and_empty_hierarchy() {
        let scene = load("scenes/spd/gears_1.nff");
        let bvh = bvh(&scene);
        let rays = camera_packets(&scene, 40, 30)[37];
        let mut hits = [Hit::miss(3.0); PACKET];
        assert_eq!(bvh.traverse_packet::<Closest>(&rays, 0, 0.0, &mut hits), 0);
        assert_eq!(hits, [Hit::miss(3.0); PACKET]);

        let mut planes = Scene::new(scene.camera);
        let m = planes.add_material(crate::scene::Material::default());
        assert!(planes.add_plane(Vec3::ZERO, Vec3::X, Vec3::Y, m));
        let bvh = Bvh4::new(Prims::new(&planes), 12).unwrap();
        assert_eq!(bvh.root, EMPTY);
        let rays = camera_packets(&planes, 40, 30)[100];
        check::<Closest>(&bvh, &rays, 0xff, 0.0, [f32::INFINITY; PACKET], "planes");
        check::<AnyHit>(&bvh, &rays, 0b1010_0110, 0.0, [f32::INFINITY; PACKET], "planes");
    }
}
