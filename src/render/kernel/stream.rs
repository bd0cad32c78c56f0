//! The stream kernel ([`Kernel::Stream`](crate::render::Kernel::Stream)): the pixel
//! samples of a few tiles are traced together, generation by generation. A generation's rays (and then
//! its hits' shadow rays, light by light) go eight at a time as a packet where eight consecutive rays
//! share a direction octant, and all the others as one stream through the accelerators' stream verbs
//! ([`crate::accel::Accel::intersect_stream`], [`crate::accel::Accel::occluded_stream`]). On the wide
//! BVHs a stream goes down the tree split at each node (Barringer and Akenine-Möller 2014), so a node
//! is loaded once for all the rays that reach it, where the single-ray kernel loads it once a ray.
//!
//! The image is the single-ray path's, bit for bit. Each pixel sample walks its ray tree depth first, as
//! [`Whitted::trace`] recurses (a hit's bounce, then its refracted ray's tree, then its reflected ray's),
//! and puts one ray into each generation's stream: its next ray in that order. So its random numbers
//! (fuzzy reflections) are drawn and its split budget spent in the single-ray order. A generation's
//! hits are shaded eight at a time in lanes (`shade.rs`: the shadow rays' set-up and Blinn-Phong, the
//! single-ray path's operations in its order), and a hit's colour is finished by
//! [`Whitted::add_bounces`] once its children's colours are back; a pixel's samples are summed in
//! sample order.
//!
//! [`Whitted::trace`]: crate::render::whitted::Whitted::trace
//! [`Whitted::add_bounces`]: crate::render::whitted::Whitted::add_bounces

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::Vec3;

use super::shade::{HitLanes, light};
use super::{BLOCK_H, BLOCK_W, PerRay, TilePixels, coherent};
use crate::accel::counters::{self, Steps};
use crate::accel::packet::{bits, first};
use crate::accel::policy::HitPolicy;
use crate::accel::{Counting, Hit, PACKET, Plain, Surface, Tally};
use crate::geometry::ray::Ray;
use crate::render::lanes::Vec3x8;
use crate::render::light::Lights;
use crate::render::renderer::Renderer;
use crate::render::sampler::PixelPattern;
use crate::render::tiles::{TILE, Tile};
use crate::render::whitted::{Bounces, PixelSample, RayCounts, RayKind, charge, take_steps};

/// The most pixel samples in flight at once: past this (many samples per pixel), a set of tiles is
/// traced in batches of whole pixels' samples, so that a worker's state stays bounded (about 130 bytes
/// a sample and 200 a pending ray: a few MiB at most).
const BATCH: usize = 4096;

/// No node: a sample's root ray has no parent.
const NONE: u32 = u32::MAX;

/// A ray of some sample's tree whose colour is not known yet: what its hit spawned, and what has come
/// back of it.
#[derive(Clone, Copy, Debug)]
struct RayNode {
    ray: Ray,
    /// Bounces before this ray.
    depth: u32,
    /// The sample it belongs to.
    sample: u32,
    /// The ray that spawned it, and which of that ray's children it is (0 refracted, 1 reflected).
    parent: u32,
    slot: u8,
    /// Where its closest hit lies (`None`: it left the scene).
    surface: Option<Surface>,
    bounces: Bounces,
    /// The colour its hit gets from the light samples (Blinn-Phong over those not in shadow).
    local: Vec3,
    /// What its refracted and reflected rays see.
    seen: [Vec3; 2],
}

/// A pixel sample of the batch: what it carries down its tree, where its colour goes, and the colour.
struct Walk<'a> {
    sample: PixelSample<'a>,
    /// Its pixel's slot: tile (within the set) and pixel (within the tile's buffer).
    tile: u32,
    pixel: u32,
    color: Vec3,
}

/// A worker's buffers, kept from batch to batch (nothing is allocated per ray).
#[derive(Default)]
struct StreamBuffers {
    nodes: Vec<RayNode>,
    free: Vec<u32>,
    /// The nodes whose rays the next generation traces, in sample order.
    queue: Vec<u32>,
    next: Vec<u32>,
    rays: Vec<Ray>,
    hits: Vec<Hit>,
    shadow_rays: Vec<Ray>,
    shadow_t: Vec<f32>,
    /// Each shadow ray's light sample, and the sample it is for.
    shadow_light: Vec<u32>,
    shadow_owner: Vec<u32>,
    /// The steps of each ray traced by the last [`Renderer::trace_split`], when counting.
    steps: Vec<Steps>,
    /// The rays to trace in order (the generation's in sample order, its shadow rays light by
    /// light), where each run of them ends, and the count of each light's shadow rays.
    order: Vec<u32>,
    runs: Vec<u32>,
    per_light: Vec<u32>,
    /// The rays of the order that go as one stream, and their rays, limits and answers.
    stream: Vec<u32>,
    stream_rays: Vec<Ray>,
    stream_t: Vec<f32>,
    stream_hits: Vec<Hit>,
    stream_blocked: Vec<bool>,
    /// The generation's shadow rays' answers, in the order they were queued.
    blocked: Vec<bool>,
    /// The generation's nodes whose rays hit something, in queue order, and their hits in lanes,
    /// eight a [`HitLanes`].
    hit_nodes: Vec<u32>,
    lanes: Vec<HitLanes>,
}

impl StreamBuffers {
    /// A node for `ray`, reusing a finished one's slot.
    fn add(&mut self, node: RayNode) -> u32 {
        match self.free.pop() {
            Some(i) => {
                self.nodes[i as usize] = node;
                i
            }
            None => {
                self.nodes.push(node);
                (self.nodes.len() - 1) as u32
            }
        }
    }
}

impl Renderer<'_> {
    /// Renders `tiles` for pass `pass` as streams into `bufs` (one per tile) and counts each tile's
    /// rays into `counts` and, unless `pixel_rays` is empty, each pixel's into its own (tile by tile,
    /// [`TILE`] x [`TILE`] each), with the calling worker's buffers, kept from job to job; leaves
    /// them half done once `stop` is set.
    pub(in crate::render) fn tiles_streamed(
        &self,
        tiles: &[Tile],
        pass: u32,
        bufs: &mut [TilePixels],
        counts: &mut [RayCounts],
        pixel_rays: &mut [RayCounts],
        stop: &AtomicBool,
    ) {
        thread_local! {
            static BUFFERS: RefCell<StreamBuffers> = RefCell::default();
        }
        BUFFERS.with_borrow_mut(|b| self.trace_tiles(tiles, pass, (bufs, counts, pixel_rays), b, stop));
    }

    /// [`Renderer::tiles_streamed`] with the buffers `b`.
    fn trace_tiles(
        &self,
        tiles: &[Tile],
        pass: u32,
        (bufs, counts, pixel_rays): (&mut [TilePixels], &mut [RayCounts], &mut [RayCounts]),
        b: &mut StreamBuffers,
        stop: &AtomicBool,
    ) {
        let samples = self.samples() as usize;
        // Pixels tile by tile, in blocks of 4x2 within a tile (eight neighbours, so that eight
        // consecutive camera rays make a coherent packet), cut into batches of whole pixels.
        let mut pixels = Vec::with_capacity(tiles.len() * (TILE * TILE) as usize);
        for (t, tile) in tiles.iter().enumerate() {
            for y0 in (tile.y0..tile.y1).step_by(BLOCK_H as usize) {
                for x0 in (tile.x0..tile.x1).step_by(BLOCK_W as usize) {
                    for k in 0..PACKET as u32 {
                        let (x, y) = (x0 + k % BLOCK_W, y0 + k / BLOCK_W);
                        if x < tile.x1 && y < tile.y1 {
                            pixels.push((t as u32, x, y));
                        }
                    }
                }
            }
        }
        let per_batch = (BATCH / samples).max(1);
        let mut pattern = PixelPattern::default();
        let mut walks = Vec::with_capacity(per_batch * samples);
        for batch in pixels.chunks(per_batch) {
            if stop.load(Ordering::Relaxed) {
                return;
            }
            walks.clear();
            b.nodes.clear();
            b.free.clear();
            b.queue.clear();
            b.blocked.clear();
            for &(t, x, y) in batch {
                let tile = tiles[t as usize];
                let pixel = (y - tile.y0) * TILE + (x - tile.x0);
                self.fill_pattern(x, y, pass, &mut pattern);
                for s in 0..samples as u32 {
                    let (at, lens, sample) = self.sample_start(x, y, pass, s, &pattern);
                    let ray = self.camera().sample_ray(at, lens);
                    let id = walks.len() as u32;
                    walks.push(Walk {
                        sample: PixelSample { slot: id, ..sample },
                        tile: t,
                        pixel,
                        color: Vec3::ZERO,
                    });
                    let node = b.add(root(ray, id));
                    b.queue.push(node);
                }
            }
            self.walk(&mut walks, b);
            // Each pixel's samples summed in sample order, as the other kernels sum them.
            for pixel in walks.chunks_mut(samples) {
                let mut sum = Vec3::ZERO;
                for w in pixel.iter_mut() {
                    sum += w.color;
                    w.sample.rays.primary += 1;
                    counts[w.tile as usize] += w.sample.rays;
                    if let Some(p) = pixel_rays.get_mut((w.tile * TILE * TILE + w.pixel) as usize) {
                        let steps = take_steps(w.sample.slot);
                        counts[w.tile as usize].steps += steps;
                        *p += w.sample.rays;
                        p.steps += steps;
                    }
                }
                bufs[pixel[0].tile as usize][pixel[0].pixel as usize] = sum / samples as f32;
            }
        }
    }

    /// Traces the batch's trees generation by generation until every sample has its colour. In each
    /// generation, eight consecutive rays that share a direction octant go as a packet (eight
    /// neighbouring pixels' camera rays, or one pixel's samples; a light's shadow rays from them; their
    /// rays off a flat mirror), and the others, in any directions, as one stream.
    fn walk(&self, walks: &mut [Walk], b: &mut StreamBuffers) {
        let whitted = &self.whitted;
        while !b.queue.is_empty() {
            b.rays.clear();
            b.rays.extend(b.queue.iter().map(|&n| b.nodes[n as usize].ray));
            b.hits.clear();
            b.hits.resize(b.rays.len(), Hit::miss(f32::INFINITY));
            b.order.clear();
            b.order.extend(0..b.rays.len() as u32);
            b.runs.clear();
            b.runs.push(b.rays.len() as u32);
            self.trace_split::<false>(b);
            if whitted.counts() {
                for (j, &n) in b.queue.iter().enumerate() {
                    let node = &b.nodes[n as usize];
                    let kind = match node.depth {
                        0 => RayKind::Camera,
                        _ => RayKind::secondary(node.slot as usize),
                    };
                    charge(walks[node.sample as usize].sample.slot, kind, b.steps[j]);
                }
            }
            // Each hit's surface and bounces (in each sample's single-ray order: one ray a sample).
            b.hit_nodes.clear();
            for (j, &n) in b.queue.iter().enumerate() {
                let node = &mut b.nodes[n as usize];
                let hit = b.hits[j];
                if !hit.is_hit() {
                    continue;
                }
                let walk = &mut walks[node.sample as usize];
                walk.sample.rays.primary_hits += u64::from(node.depth == 0);
                let s = whitted.prims.surface(&node.ray, &hit);
                node.bounces = whitted.bounces(&node.ray, &s, node.depth, &mut walk.sample);
                walk.sample.rays.add_bounces(&node.bounces);
                node.surface = Some(s);
                b.hit_nodes.push(n);
            }
            // Their shadow rays, eight hits at a time and light sample by light sample, set up in
            // lanes.
            b.shadow_rays.clear();
            b.shadow_t.clear();
            b.shadow_light.clear();
            b.shadow_owner.clear();
            b.lanes.clear();
            for eight in b.hit_nodes.chunks(PACKET) {
                let hits = self.hit_lanes(eight, &b.nodes);
                let lights = lights_of(eight, &b.nodes, walks);
                for i in 0..lights[0].len() {
                    let toward = hits.toward(light(i, &lights).0);
                    if toward.lit == 0 {
                        continue;
                    }
                    let (rays, distance) = hits.shadow_rays(&toward);
                    for k in bits(toward.lit) {
                        let sample = b.nodes[eight[k] as usize].sample;
                        b.shadow_rays.push(rays[k]);
                        b.shadow_t.push(distance[k]);
                        b.shadow_light.push(i as u32);
                        b.shadow_owner.push(sample);
                        walks[sample as usize].sample.rays.shadow += 1;
                    }
                }
                b.lanes.push(hits);
            }
            b.blocked.clear();
            b.blocked.resize(b.shadow_rays.len(), false);
            by_light(b);
            self.trace_split::<true>(b);
            if whitted.counts() {
                for (j, &owner) in b.shadow_owner.iter().enumerate() {
                    charge(walks[owner as usize].sample.slot, RayKind::Shadow, b.steps[j]);
                }
            }
            // The hits' local colours: the same shadow rays set up again, their answers read in the
            // order they were queued in.
            let mut answer = b.blocked.iter();
            for (eight, hits) in b.hit_nodes.chunks(PACKET).zip(&b.lanes) {
                let lights = lights_of(eight, &b.nodes, walks);
                let mut color = Vec3x8::ZERO;
                for i in 0..lights[0].len() {
                    let (at, light) = light(i, &lights);
                    let toward = hits.toward(at);
                    let blocked = bits(toward.lit).fold(0u8, |m, k| {
                        m | u8::from(*answer.next().expect("an answer a shadow ray")) << k
                    });
                    hits.add_light(&mut color, &toward, toward.lit & !blocked, light);
                }
                for (&n, local) in eight.iter().zip(color.lanes()) {
                    b.nodes[n as usize].local = local;
                }
            }
            // Each sample's next ray, or its finished rays' colours, up its tree.
            let queue = std::mem::take(&mut b.queue);
            b.next.clear();
            for &n in &queue {
                self.advance(n, 0, walks, b);
            }
            b.queue = queue;
            std::mem::swap(&mut b.queue, &mut b.next);
        }
    }

    /// Traces the rays of `b.order`, run by run (`b.runs`: where each ends): the generation's rays
    /// (closest hits into `b.hits`) or, with `ANY`, its shadow rays (answers into `b.blocked`). Each run is cut into chunks of eight; a chunk that is [`coherent`] is traced as a
    /// packet (the packet driver's rule), the others' rays together as one stream.
    fn trace_split<const ANY: bool>(&self, b: &mut StreamBuffers) {
        if self.whitted.counts() {
            self.trace_runs::<ANY, Counting>(b);
        } else {
            self.trace_runs::<ANY, Plain>(b);
        }
    }

    /// [`Renderer::trace_split`] through the verbs of `T`: counting ones leave each ray's steps in
    /// `b.steps`.
    fn trace_runs<const ANY: bool, T: Tally>(&self, b: &mut StreamBuffers) {
        let accel = self.whitted.accel.verbs::<T>();
        let count = T::Closest::COUNT;
        let rays = if ANY { &b.shadow_rays } else { &b.rays };
        if count {
            b.steps.clear();
            b.steps.resize(rays.len(), Steps::default());
        }
        b.stream.clear();
        let mut from = 0;
        for &end in &b.runs {
            for ids in b.order[from as usize..end as usize].chunks(PACKET) {
                if !coherent(ids.iter().map(|&j| &rays[j as usize])) {
                    b.stream.extend_from_slice(ids);
                    continue;
                }
                let mut packet = [Ray::new(Vec3::ZERO, Vec3::Z); PACKET];
                for (k, &j) in ids.iter().enumerate() {
                    packet[k] = rays[j as usize];
                }
                if ANY {
                    let t_max: [f32; PACKET] =
                        std::array::from_fn(|k| ids.get(k).map_or(0.0, |&j| b.shadow_t[j as usize]));
                    let blocked = accel.occluded_packet(&packet, first(ids.len()), 0.0, &t_max);
                    for (k, &j) in ids.iter().enumerate() {
                        b.blocked[j as usize] = blocked >> k & 1 == 1;
                    }
                } else {
                    let mut hits = [Hit::miss(f32::INFINITY); PACKET];
                    accel.intersect_packet(&packet, first(ids.len()), 0.0, &mut hits);
                    for (k, &j) in ids.iter().enumerate() {
                        b.hits[j as usize] = hits[k];
                    }
                }
                if count {
                    for (k, &j) in ids.iter().enumerate() {
                        b.steps[j as usize] = counters::lane(k);
                    }
                }
            }
            from = end;
        }
        // The rest as one stream, gathered and scattered back.
        b.stream_rays.clear();
        b.stream_rays.extend(b.stream.iter().map(|&j| rays[j as usize]));
        if ANY {
            b.stream_t.clear();
            b.stream_t
                .extend(b.stream.iter().map(|&j| b.shadow_t[j as usize]));
            b.stream_blocked.clear();
            b.stream_blocked.resize(b.stream.len(), false);
            accel.occluded_stream(&b.stream_rays, 0.0, &b.stream_t, &mut b.stream_blocked);
            for (&j, &blocked) in b.stream.iter().zip(&b.stream_blocked) {
                b.blocked[j as usize] = blocked;
            }
        } else {
            b.stream_hits.clear();
            b.stream_hits.resize(b.stream.len(), Hit::miss(f32::INFINITY));
            accel.intersect_stream(&b.stream_rays, 0.0, &mut b.stream_hits);
            for (&j, &hit) in b.stream.iter().zip(&b.stream_hits) {
                b.hits[j as usize] = hit;
            }
        }
        if count {
            for (i, &j) in b.stream.iter().enumerate() {
                b.steps[j as usize] = counters::lane(i);
            }
        }
    }

    /// The hits of nodes `eight` (up to eight, each with a surface) in lanes.
    fn hit_lanes(&self, eight: &[u32], nodes: &[RayNode]) -> HitLanes {
        let node = |k: usize| eight.get(k).map(|&n| &nodes[n as usize]);
        HitLanes::of_surfaces(
            self.whitted.prims.scene,
            |k| node(k).map_or(Vec3::Z, |n| n.ray.dir),
            |k| node(k).and_then(|n| n.surface.as_ref()),
        )
        .expect("hits")
    }

    /// After node `n`'s hit and shadow rays are back, or its child in `slot - 1` has its colour:
    /// queues its next child (refracted, then reflected), or else shades it, frees it and goes on up
    /// its tree with the colour.
    fn advance(&self, mut n: u32, mut from: u8, walks: &mut [Walk], b: &mut StreamBuffers) {
        loop {
            let node = &b.nodes[n as usize];
            let (sample, depth, parent, slot) = (node.sample, node.depth, node.parent, node.slot);
            let children = [&node.bounces.refracted, &node.bounces.reflected];
            if let Some(next) = (from..2).find(|&i| children[i as usize].is_some()) {
                let (ray, _) = children[next as usize].expect("found");
                let child = b.add(RayNode {
                    parent: n,
                    slot: next,
                    depth: depth + 1,
                    ..root(ray, sample)
                });
                b.next.push(child);
                return;
            }
            // Read in place, not copied: a node is some 200 bytes.
            let walk = &mut walks[sample as usize];
            let color = match &node.surface {
                // A miss: what the ray sees leaving the scene.
                None => self
                    .whitted
                    .shade(&node.ray, &Hit::miss(f32::INFINITY), depth, &mut walk.sample),
                Some(s) => self
                    .whitted
                    .add_bounces(node.local, s, &node.bounces, &mut |i, _| node.seen[i]),
            };
            b.free.push(n);
            if parent == NONE {
                walk.color = color;
                return;
            }
            (n, from) = (parent, slot + 1);
            b.nodes[n as usize].seen[slot as usize] = color;
        }
    }
}

/// The lights of the samples of nodes `eight` (up to eight; a dead lane gets the first's).
fn lights_of<'s>(eight: &[u32], nodes: &[RayNode], walks: &[Walk<'s>]) -> PerRay<Lights<'s>> {
    let lights = |n: u32| walks[nodes[n as usize].sample as usize].sample.lights;
    let first = lights(eight[0]);
    std::array::from_fn(|k| eight.get(k).map_or(first, |&n| lights(n)))
}

/// Puts the generation's shadow rays in order of light, one run per light (a counting sort: stable, so
/// each light's rays stay in the order of their hits, neighbours beside neighbours).
fn by_light(b: &mut StreamBuffers) {
    let lights = b.shadow_light.iter().max().map_or(0, |&l| l as usize + 1);
    b.per_light.clear();
    b.per_light.resize(lights, 0);
    for &l in &b.shadow_light {
        b.per_light[l as usize] += 1;
    }
    // Each light's first slot, then (as rays are placed) its next.
    b.runs.clear();
    let mut at = 0;
    for count in b.per_light.iter_mut() {
        (*count, at) = (at, at + *count);
        b.runs.push(at);
    }
    b.order.clear();
    b.order.resize(b.shadow_light.len(), 0);
    for (j, &l) in b.shadow_light.iter().enumerate() {
        let next = &mut b.per_light[l as usize];
        b.order[*next as usize] = j as u32;
        *next += 1;
    }
}

/// The root node of sample `sample`'s tree: its camera ray (or a child's ray, the rest filled in).
fn root(ray: Ray, sample: u32) -> RayNode {
    RayNode {
        ray,
        depth: 0,
        sample,
        parent: NONE,
        slot: 0,
        surface: None,
        bounces: Bounces::default(),
        local: Vec3::ZERO,
        seen: [Vec3::ZERO; 2],
    }
}
