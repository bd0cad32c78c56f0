//! Embree 3 as a peer of the kernels bench, through the library's binding (`whitted::accel::embree`, the
//! accelerator of `--accel embree`): its single rays (`rtcIntersect1`, `rtcOccluded1`) and its 8-wide
//! packets (`rtcIntersect8`, `rtcOccluded8`, consecutive rays as our packet kernel takes them), on its
//! high-quality (spatial split) BVH.

use whitted::accel::embree::Embree as Scene;
use whitted::accel::{Hit, PrimKind};
use whitted::kit::workload::packets_of;

use crate::contestant::{Contestant, FirstHit, Segment, Side};

/// The triangle a segment hits first by Embree's test (`rtcIntersect1`), if any.
struct First<'a>(&'a Scene<'a>);

impl FirstHit for First<'_> {
    fn triangle(&self, (ray, t_max): &Segment) -> Option<u32> {
        let mut hit = Hit::miss(*t_max);
        self.0
            .intersect(ray, 0.0, &mut hit)
            .then(|| match self.0.prims().kind(hit.prim) {
                PrimKind::Triangle(t) => t as u32,
                _ => panic!("the bench scene holds triangles only"),
            })
    }
}

/// Embree's single rays (`embree-avx2`) or its 8-wide packets (`embree-avx2-8`) on one scene, the
/// instruction set its device was made for in the name.
pub struct Embree<'a> {
    first: First<'a>,
    eight: bool,
    id: String,
}

impl<'a> Embree<'a> {
    /// Both kernels on `scene`, whose device runs `isa` (its name in the kit's words).
    pub fn both(scene: &'a Scene<'a>, isa: &str) -> [Embree<'a>; 2] {
        [false, true].map(|eight| Embree {
            first: First(scene),
            eight,
            id: format!("embree-{isa}{}", if eight { "-8" } else { "" }),
        })
    }
}

impl Contestant for Embree<'_> {
    fn id(&self) -> &str {
        &self.id
    }

    fn side(&self) -> Side {
        Side::Peer
    }

    fn packets(&self) -> bool {
        self.eight
    }

    fn closest(&self, rays: &[Segment]) -> usize {
        let e = self.first.0;
        if self.eight {
            return packets_of(rays, |r, active, t_max| {
                let mut hits = t_max.map(Hit::miss);
                e.intersect_packet(r, active, 0.0, &mut hits)
            });
        }
        rays.iter()
            .filter(|(ray, t_max)| e.intersect(ray, 0.0, &mut Hit::miss(*t_max)))
            .count()
    }

    fn occluded(&self, rays: &[Segment]) -> usize {
        let e = self.first.0;
        if self.eight {
            return packets_of(rays, |r, active, t_max| e.occluded_packet(r, active, 0.0, t_max));
        }
        rays.iter()
            .filter(|(ray, t_max)| e.occluded(ray, 0.0, *t_max))
            .count()
    }

    /// Embree's triangle test is its own: it may part from ours at edges.
    fn first_hit(&self) -> Option<&dyn FirstHit> {
        Some(&self.first)
    }
}
