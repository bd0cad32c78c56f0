//! What every row of the bench is: something that traces the bench's rays, ours or a peer's, one ray at
//! a time or in packets. The bench is one loop over these, the ray sets and the thread counts.

use whitted::accel::{Accel, Hit};
use whitted::geometry::ray::Ray;
use whitted::kit::contestants::Contestant as Built;
use whitted::kit::workload::packets_of;

/// A ray and the end of the interval searched (∞ for whole rays): every ray set is given as segments.
pub type Segment = (Ray, f32);

/// Who a contestant is, for the ratio rows of the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// One of our structures.
    Ours,
    /// A peer's.
    Peer,
}

/// A structure with one of its kernels.
pub trait Contestant: Sync {
    /// Its bench id and row in the table: `bvh4-avx2`, `bvh8-avx2-packets`, `obvhs-cwbvh`, `embree-8`.
    fn id(&self) -> &str;
    /// Ours or a peer's.
    fn side(&self) -> Side;
    /// True for a packet kernel (compared with packets in the ratio rows).
    fn packets(&self) -> bool;
    /// True for a stream kernel (ours only: its rows stand beside the others, outside the ratio rows).
    fn streams(&self) -> bool {
        false
    }
    /// Closest hits of the segments: how many hit.
    fn closest(&self, rays: &[Segment]) -> usize;
    /// Any hit on the segments: how many are blocked.
    fn occluded(&self, rays: &[Segment]) -> usize;
    /// A peer with its own triangle test, which may round differently from ours where a ray crosses
    /// within f32 precision of an edge: the triangle a segment hits first by that test, so that a hit
    /// count that differs from ours can be reconciled ray by ray. `None` where the counts must equal
    /// ours (our structures, and obvhs, which is given our triangle test).
    fn first_hit(&self) -> Option<&dyn FirstHit> {
        None
    }
}

/// The triangle a segment hits first (by a peer's own triangle test), if any.
pub trait FirstHit {
    fn triangle(&self, ray: &Segment) -> Option<u32>;
}

/// Which of a structure's kernels a row times.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verb {
    /// One ray at a time.
    Single,
    /// Packets of 8 consecutive rays.
    Packets,
    /// Streams of [`STREAM`] consecutive rays (or of the rays a thread is given, if fewer).
    Streams,
}

/// Rays a stream: a batch of the stream kernel's frames (`whitted render --kernel stream` traces at
/// most 4,096 pixel samples a generation).
pub const STREAM: usize = 4096;

/// One of the kit's structures ([`whitted::kit::contestants`]) with one of its kernels.
pub struct Ours<'a> {
    id: String,
    accel: &'a Accel<'a>,
    verb: Verb,
}

impl<'a> Ours<'a> {
    /// `accel` under bench id `id`, with kernel `verb`.
    pub fn new(id: &str, accel: &'a Accel<'a>, verb: Verb) -> Self {
        Ours {
            id: id.to_string(),
            accel,
            verb,
        }
    }

    /// Every structure of the kit with its single-ray kernel, and the wide BVHs with their packets and
    /// streams too (the others answer packets and streams ray by ray: their rows would time single
    /// rays again). Embree, which the kit lists with the `embree` feature, is a peer's: its rows are
    /// `embree.rs`'s.
    pub fn all(built: &'a [Built<'a>]) -> Vec<Ours<'a>> {
        let mut out = Vec::new();
        for b in built.iter().filter(|b| !b.is_embree()) {
            let id = b.name.replace(' ', "-");
            if b.has_packet_kernel() {
                out.push(Ours::new(&format!("{id}-packets"), &b.accel, Verb::Packets));
                out.push(Ours::new(&format!("{id}-streams"), &b.accel, Verb::Streams));
            }
            out.push(Ours::new(&id, &b.accel, Verb::Single));
        }
        out
    }
}

impl Contestant for Ours<'_> {
    fn id(&self) -> &str {
        &self.id
    }

    fn side(&self) -> Side {
        Side::Ours
    }

    fn packets(&self) -> bool {
        self.verb == Verb::Packets
    }

    fn streams(&self) -> bool {
        self.verb == Verb::Streams
    }

    fn closest(&self, rays: &[Segment]) -> usize {
        match self.verb {
            Verb::Packets => packets_of(rays, |r, active, t_max| {
                let mut hits = t_max.map(Hit::miss);
                self.accel.intersect_packet(r, active, 0.0, &mut hits)
            }),
            Verb::Streams => streams_of(rays, |r, t_max| {
                let mut hits: Vec<Hit> = t_max.iter().map(|&t| Hit::miss(t)).collect();
                self.accel.intersect_stream(r, 0.0, &mut hits);
                hits.iter().filter(|h| h.is_hit()).count()
            }),
            Verb::Single => {
                let mut hits = 0;
                for (ray, t_max) in rays {
                    let mut hit = Hit::miss(*t_max);
                    hits += self.accel.intersect(ray, 0.0, &mut hit) as usize;
                }
                hits
            }
        }
    }

    fn occluded(&self, rays: &[Segment]) -> usize {
        match self.verb {
            Verb::Packets => packets_of(rays, |r, active, t_max| {
                self.accel.occluded_packet(r, active, 0.0, t_max)
            }),
            Verb::Streams => streams_of(rays, |r, t_max| {
                let mut blocked = vec![false; r.len()];
                self.accel.occluded_stream(r, 0.0, t_max, &mut blocked);
                blocked.iter().filter(|&&b| b).count()
            }),
            Verb::Single => rays
                .iter()
                .filter(|(ray, t_max)| self.accel.occluded(ray, 0.0, *t_max))
                .count(),
        }
    }
}

/// `count` over `rays` in streams of [`STREAM`], each given as its rays and their limits (gathered per
/// stream, as a renderer holds them; the allocation is per stream, not per ray): the sum.
fn streams_of(rays: &[Segment], count: impl Fn(&[Ray], &[f32]) -> usize) -> usize {
    rays.chunks(STREAM)
        .map(|s| {
            let (r, t): (Vec<Ray>, Vec<f32>) = s.iter().copied().unzip();
            count(&r, &t)
        })
        .sum()
}
