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

/// One of the kit's structures ([`whitted::kit::contestants`]) with its single-ray or its packet
/// kernel.
pub struct Ours<'a> {
    id: String,
    accel: &'a Accel<'a>,
    packets: bool,
}

impl<'a> Ours<'a> {
    /// `accel` under bench id `id`, with its packet kernel or its single rays.
    pub fn new(id: &str, accel: &'a Accel<'a>, packets: bool) -> Self {
        Ours {
            id: id.to_string(),
            accel,
            packets,
        }
    }

    /// Every structure of the kit with its single-ray kernel, and the wide BVHs with their packets too
    /// (the others answer packets ray by ray: their packet rows would time single rays again). Embree,
    /// which the kit lists with the `embree` feature, is a peer's: its rows are `embree.rs`'s.
    pub fn all(built: &'a [Built<'a>]) -> Vec<Ours<'a>> {
        let mut out = Vec::new();
        for b in built.iter().filter(|b| !b.is_embree()) {
            let id = b.name.replace(' ', "-");
            if b.has_packet_kernel() {
                out.push(Ours::new(&format!("{id}-packets"), &b.accel, true));
            }
            out.push(Ours::new(&id, &b.accel, false));
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
        self.packets
    }

    fn closest(&self, rays: &[Segment]) -> usize {
        if self.packets {
            return packets_of(rays, |r, active, t_max| {
                let mut hits = t_max.map(Hit::miss);
                self.accel.intersect_packet(r, active, 0.0, &mut hits)
            });
        }
        let mut hits = 0;
        for (ray, t_max) in rays {
            let mut hit = Hit::miss(*t_max);
            hits += self.accel.intersect(ray, 0.0, &mut hit) as usize;
        }
        hits
    }

    fn occluded(&self, rays: &[Segment]) -> usize {
        if self.packets {
            return packets_of(rays, |r, active, t_max| {
                self.accel.occluded_packet(r, active, 0.0, t_max)
            });
        }
        rays.iter()
            .filter(|(ray, t_max)| self.accel.occluded(ray, 0.0, *t_max))
            .count()
    }
}
