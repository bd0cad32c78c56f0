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
//! arrays (lane `k` of every [`f32x8`] is ray `k`) and keeps one stack of node references, each entry
//! carrying the mask of rays that entered it and their entry distances; a ray leaves an entry once it
//! has a hit nearer than its entry, and an entry no ray is left in is skipped.
//!
//! What is SIMD over the rays: every child box test (the node's boxes one at a time, against the eight
//! lanes).
//! What goes ray by ray: the leaves, each active ray through the same code as the single-ray kernel
//! (triangles four at a time in their [`Tri4`](super::tri4::Tri4) blocks, other kinds one by one), and the
//! planes beside the hierarchy. Testing one triangle against the eight lanes instead (bit-identical
//! Möller–Trumbore in `f32x8`) was measured slower: an `f32x8` is two SSE registers without AVX, so it
//! does the per-ray blocks' arithmetic plus fetching each triangle from the scene's arrays (the blocks
//! keep their lanes private), and even with AVX2 the per-ray blocks were faster on the dragon.
//!
//! The answers are the single-ray kernel's ([`super::Bvh4::traverse`]): the per-lane box arithmetic is its
//! operation for operation (the near/far blend by each ray's own direction signs, [`SLAB_ROBUST`] on the
//! exit, [`CULL_MARGIN`] on the hit), so a ray is never kept out of a box the single-ray kernel would
//! enter for it, and each leaf runs the single-ray kernel's leaf code, so hits, and ties inside a leaf, come
//! out bit for bit the same. Only the order of leaves differs (the packet's, not each ray's), which could
//! matter only for two primitives in different leaves hit at bit-identical `t`.

use wide::f32x8;

use super::{ChildRef, EMPTY, LEAF, Node, STACK, Simd, TRIANGLES, WideBvh, leaf_parts};
use crate::accel::policy::HitPolicy;
use crate::accel::prims::Hit;
use crate::accel::stack::Stack;
use crate::geometry::ray::{CULL_MARGIN, Ray, SLAB_ROBUST, safe_inverse};

/// Rays per packet: the lanes of one [`f32x8`].
pub const PACKET: usize = 8;

/// A stack entry: a child, the mask of the rays that entered it, and their entry distances.
#[derive(Clone, Copy)]
struct Entry {
    node: ChildRef,
    mask: u8,
    entry: f32x8,
}

/// The bits of a ray mask, lowest (first ray) first.
#[inline(always)]
pub fn lanes(mut mask: u32) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let k = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            k
        })
    })
}

/// Eight rays prepared for slab tests in structure of arrays: per axis the origins and (Embree's
/// [`safe_inverse`]) inverse directions of all eight. When the live rays' directions share their signs
/// (camera and shadow rays nearly always do), `flip` says per axis whether the near plane is the max
/// one, as in the single-ray kernel; otherwise (`mixed`) each lane orders its two planes by min/max.
struct Packet {
    origin: [f32x8; 3],
    inv: [f32x8; 3],
    flip: [bool; 3],
    mixed: bool,
}

impl Packet {
    #[inline(always)]
    fn new(rays: &[Ray; PACKET], live: u32) -> Self {
        let inv = soa(rays, &|r| safe_inverse(r.dir));
        let zero = f32x8::splat(0.0);
        let negative = inv.map(|i| i.simd_lt(zero).to_bitmask() & live);
        Packet {
            origin: soa(rays, &|r| r.origin),
            inv,
            flip: negative.map(|m| m != 0),
            mixed: negative.iter().any(|&m| m != 0 && m != live),
        }
    }

    /// Child `c` of `n` against all eight rays: their entry distances and the mask of rays that enter it
    /// within `[t_min, t_max]`. Lane by lane the single-ray kernel's slab test (Kay & Kajiya 1986) with
    /// [`SLAB_ROBUST`] on the exit distance. The min/max ordering of mixed packets gives the same planes
    /// as ordering by sign for any box that is not inverted, and inverted (empty) slots are never tested.
    #[inline(always)]
    fn slab8<const W: usize>(&self, n: &Node<W>, c: usize, t_min: f32x8, t_max: f32x8) -> (f32x8, u32) {
        let mut near = t_min;
        let mut far = f32x8::splat(f32::INFINITY);
        for axis in 0..3 {
            let (a, b) = (n.min[axis][c], n.max[axis][c]);
            let (a, b) = if self.flip[axis] { (b, a) } else { (a, b) };
            let t0 = (f32x8::splat(a) - self.origin[axis]) * self.inv[axis];
            let t1 = (f32x8::splat(b) - self.origin[axis]) * self.inv[axis];
            if self.mixed {
                near = near.fast_max(t0.fast_min(t1));
                far = far.fast_min(t0.fast_max(t1));
            } else {
                near = near.fast_max(t0);
                far = far.fast_min(t1);
            }
        }
        let far = (far * f32x8::splat(SLAB_ROBUST)).fast_min(t_max);
        (near, near.simd_le(far).to_bitmask())
    }
}

/// A vector of each ray, in structure of arrays: per axis, the eight rays' components. (`f` is a `&dyn`
/// only because with a generic closure the whole kernel measured 8% slower on the dragon: a codegen
/// accident, the calls are devirtualised either way.)
#[inline(always)]
fn soa(rays: &[Ray; PACKET], f: &dyn Fn(&Ray) -> glam::Vec3) -> [f32x8; 3] {
    let v: [glam::Vec3; PACKET] = std::array::from_fn(|k| f(&rays[k]));
    [0, 1, 2].map(|axis| f32x8::new(v.map(|v| v[axis])))
}

/// The search limits of the eight rays (their `hit.t`), gathered into lanes.
#[inline(always)]
fn limits(hits: &[Hit; PACKET]) -> f32x8 {
    f32x8::new(std::array::from_fn(|k| hits[k].t))
}

/// How a packet tests one child box against its eight rays: `wide`'s `f32x8` (two SSE halves in the
/// default build), or one AVX2 register in the kernel's AVX2 compile. The same operations in the same
/// order, so both enter exactly the same children.
trait PacketSlab {
    fn slab8<const W: usize>(p: &Packet, n: &Node<W>, c: usize, t_min: f32x8, t_max: f32x8) -> (f32x8, u32);
}

/// `wide`'s lanes: any CPU.
struct WideLanes;

impl PacketSlab for WideLanes {
    #[inline(always)]
    fn slab8<const W: usize>(p: &Packet, n: &Node<W>, c: usize, t_min: f32x8, t_max: f32x8) -> (f32x8, u32) {
        p.slab8(n, c, t_min, t_max)
    }
}

/// One AVX2 register: reached only through [`Simd::Avx2`], chosen only on CPUs with AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
struct Avx2Lanes;

#[cfg(target_arch = "x86_64")]
impl PacketSlab for Avx2Lanes {
    #[inline(always)]
    fn slab8<const W: usize>(p: &Packet, n: &Node<W>, c: usize, t_min: f32x8, t_max: f32x8) -> (f32x8, u32) {
        // SAFETY: as the type's comment says.
        unsafe { slab8_avx2(p, n, c, t_min, t_max) }
    }
}

/// [`Packet::slab8`] in 256-bit registers.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[inline]
fn slab8_avx2<const W: usize>(p: &Packet, n: &Node<W>, c: usize, t_min: f32x8, t_max: f32x8) -> (f32x8, u32) {
    use std::arch::x86_64::*;
    let ld = |v: f32x8| {
        let a = v.to_array();
        // SAFETY: an unaligned load of eight floats from an eight-float array.
        unsafe { _mm256_loadu_ps(a.as_ptr()) }
    };
    let mut near = ld(t_min);
    let mut far = _mm256_set1_ps(f32::INFINITY);
    for axis in 0..3 {
        let (a, b) = (n.min[axis][c], n.max[axis][c]);
        let (a, b) = if p.flip[axis] { (b, a) } else { (a, b) };
        let (o, inv) = (ld(p.origin[axis]), ld(p.inv[axis]));
        let t0 = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(a), o), inv);
        let t1 = _mm256_mul_ps(_mm256_sub_ps(_mm256_set1_ps(b), o), inv);
        if p.mixed {
            near = _mm256_max_ps(near, _mm256_min_ps(t0, t1));
            far = _mm256_min_ps(far, _mm256_max_ps(t0, t1));
        } else {
            near = _mm256_max_ps(near, t0);
            far = _mm256_min_ps(far, t1);
        }
    }
    let far = _mm256_min_ps(_mm256_mul_ps(far, _mm256_set1_ps(SLAB_ROBUST)), ld(t_max));
    let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(near, far)) as u32;
    let mut out = [0.0f32; 8];
    // SAFETY: an unaligned store of eight floats into an eight-float array.
    unsafe { _mm256_storeu_ps(out.as_mut_ptr(), near) };
    (f32x8::new(out), mask)
}

impl<const W: usize> WideBvh<'_, W> {
    /// Tests leaf `r` for each ray in `mask` exactly as the single-ray kernel's leaf does (triangles four
    /// at a time in their blocks, in order, a hit kept only when strictly nearer; other kinds one by one;
    /// any-hit stops a ray at its first hit). Returns the mask of rays that hit.
    #[inline(always)]
    fn leaf8<P: HitPolicy>(
        &self,
        r: ChildRef,
        rays: &[Ray; PACKET],
        mask: u32,
        t_min: f32,
        hits: &mut [Hit; PACKET],
    ) -> u32 {
        let (start, count) = leaf_parts(r);
        let mut found = 0;
        if r & TRIANGLES == 0 {
            let ids = &self.ids[start..start + count];
            for k in lanes(mask) {
                if self
                    .prims
                    .intersect_each::<P>(ids.iter().copied(), &rays[k], t_min, &mut hits[k])
                {
                    found |= 1 << k;
                }
            }
            return found;
        }
        for k in lanes(mask) {
            for block in &self.tris[start..start + count.div_ceil(4)] {
                if let Some((l, t, u, v)) = block.intersect(rays[k].origin, rays[k].dir, t_min, hits[k].t) {
                    hits[k] = Hit {
                        t,
                        prim: block.id[l],
                        u,
                        v,
                    };
                    found |= 1 << k;
                    if P::ANY {
                        break;
                    }
                }
            }
        }
        found
    }

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
    pub fn traverse_packet<P: HitPolicy>(
        &self,
        rays: &[Ray; PACKET],
        active: u8,
        t_min: f32,
        hits: &mut [Hit; PACKET],
    ) -> u8 {
        match self.simd {
            // SAFETY: `simd` is `Avx2` only if the CPU has AVX2 and FMA (`Simd::detect`, `set_simd`).
            #[cfg(target_arch = "x86_64")]
            Simd::Avx2 => unsafe { self.traverse_packet_avx2::<P>(rays, active, t_min, hits) },
            _ => self.packet_with::<P, WideLanes>(rays, active, t_min, hits),
        }
    }

    /// The packet kernel compiled for AVX2, with its box tests in 256-bit registers.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    fn traverse_packet_avx2<P: HitPolicy>(
        &self,
        rays: &[Ray; PACKET],
        active: u8,
        t_min: f32,
        hits: &mut [Hit; PACKET],
    ) -> u8 {
        self.packet_with::<P, Avx2Lanes>(rays, active, t_min, hits)
    }

    /// The packet kernel's one body, over the box test `S`.
    #[inline(always)]
    fn packet_with<P: HitPolicy, S: PacketSlab>(
        &self,
        rays: &[Ray; PACKET],
        active: u8,
        t_min: f32,
        hits: &mut [Hit; PACKET],
    ) -> u8 {
        // The planes first, ray by ray, as the single-ray kernel does.
        let mut found = 0u32;
        for k in lanes(active as u32) {
            if self.prims.intersect_planes::<P>(&rays[k], t_min, &mut hits[k]) {
                found |= 1 << k;
            }
        }
        // Rays still searching: any-hit is done with a ray once it has a hit.
        let mut live = active as u32 & if P::ANY { !found } else { u32::MAX };
        if live == 0 || self.root == EMPTY {
            return found as u8;
        }
        let p = Packet::new(rays, live);
        let lo = f32x8::splat(t_min);
        let margin = f32x8::splat(CULL_MARGIN);
        // The rays' hit distances, kept in lanes beside `hits`.
        let mut t_hit = limits(hits);
        let mut stack = Stack::<Entry, STACK>::new();
        let (mut current, mut mask) = (self.root, live);
        loop {
            if current & LEAF != 0 {
                let hit = self.leaf8::<P>(current, rays, mask, t_min, hits);
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
                let node = &self.nodes[current as usize];
                let t_max = t_hit * margin;
                let start = stack.len();
                let mut keys = [0f32; 8];
                for c in 0..W {
                    if node.child[c] == EMPTY {
                        continue;
                    }
                    let (entry, entered) = S::slab8(&p, node, c, lo, t_max);
                    let entered = entered & mask;
                    if entered != 0 {
                        keys[stack.len() - start] = entry.to_array()[entered.trailing_zeros() as usize];
                        stack.push(Entry {
                            node: node.child[c],
                            mask: entered as u8,
                            entry,
                        });
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
                    n if !P::ANY => sort_far_to_near(&mut keys[..n], stack.above_mut(start)),
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
                        e.entry.simd_le(t_hit * margin).to_bitmask()
                    };
                if m != 0 {
                    (current, mask) = (e.node, m);
                    break;
                }
            }
        }
    }
}

/// Orders the entries one node pushed (2 to `W`, with their sort `keys`) far to near, so that the
/// nearest is popped first (insertion sort: at most six compares for four).
#[inline(always)]
fn sort_far_to_near(keys: &mut [f32], run: &mut [Entry]) {
    for i in 1..keys.len() {
        let mut j = i;
        while j > 0 && keys[j - 1] < keys[j] {
            keys.swap(j - 1, j);
            run.swap(j - 1, j);
            j -= 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use glam::Vec3;

    use super::*;
    use crate::accel::policy::{AnyHit, Closest};
    use crate::accel::prims::Prims;
    use crate::accel::wide::Bvh4;
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
        rays: &[Ray; PACKET],
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
        rays: &[Ray; PACKET],
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

    /// Throughput of the packet kernel against the single-ray kernel on the dragon at 800×600, one
    /// thread: camera rays (closest hit) and the shadow rays of their hits toward each light (any hit).
    /// `cargo test --release --lib accel::wide::packet -- --ignored --nocapture`
    #[test]
    #[ignore]
    fn throughput_single_vs_packet() {
        use std::time::Instant;
        let scene = load("scenes/dragon.p3f");
        let bvh = bvh(&scene);
        let packets = camera_packets(&scene, 800, 600);
        let n = (packets.len() * PACKET) as f64;
        let inf = [Hit::miss(f32::INFINITY); PACKET];
        let mut primary = vec![(inf, 0u8); packets.len()];
        let mrays = |rays: f64, secs: f64| rays / secs / 1e6;
        let best = |f: &mut dyn FnMut() -> u64| {
            (0..5)
                .map(|_| {
                    let t = Instant::now();
                    std::hint::black_box(f());
                    t.elapsed().as_secs_f64()
                })
                .fold(f64::INFINITY, f64::min)
        };
        let single = best(&mut || {
            let mut sum = 0u64;
            for rays in &packets {
                for r in rays {
                    let mut h = Hit::miss(f32::INFINITY);
                    sum += bvh.traverse::<Closest>(r, 0.0, &mut h) as u64;
                }
            }
            sum
        });
        let packet = best(&mut || {
            let mut sum = 0u64;
            for (rays, out) in packets.iter().zip(primary.iter_mut()) {
                let mut h = inf;
                let f = bvh.traverse_packet::<Closest>(rays, 0xff, 0.0, &mut h);
                *out = (h, f);
                sum += f.count_ones() as u64;
            }
            sum
        });
        println!(
            "camera (closest): {n} rays, single {:.2} Mrays/s, packet {:.2} Mrays/s",
            mrays(n, single),
            mrays(n, packet)
        );
        let mut shadows = Vec::new();
        for light in scene.point_lights.iter().map(|l| l.position) {
            for (rays, (h, f)) in packets.iter().zip(&primary) {
                let (s, t_max) = shadow_packet(&bvh, rays, h, *f, light);
                shadows.push((s, t_max, *f));
            }
        }
        let m: f64 = shadows.iter().map(|s| s.2.count_ones() as f64).sum();
        let single = best(&mut || {
            let mut sum = 0u64;
            for (rays, t_max, f) in &shadows {
                for k in lanes(*f as u32) {
                    let mut h = Hit::miss(t_max[k]);
                    sum += bvh.traverse::<AnyHit>(&rays[k], 0.0, &mut h) as u64;
                }
            }
            sum
        });
        let packet = best(&mut || {
            let mut sum = 0u64;
            for (rays, t_max, f) in &shadows {
                let mut h = t_max.map(Hit::miss);
                sum += bvh.traverse_packet::<AnyHit>(rays, *f, 0.0, &mut h).count_ones() as u64;
            }
            sum
        });
        println!(
            "shadow (any): {m} rays, single {:.2} Mrays/s, packet {:.2} Mrays/s",
            mrays(m, single),
            mrays(m, packet)
        );
    }
}
