//! What every row of the bench is: something that traces the bench's rays, ours or a peer's, one ray at
//! a time or in packets. The bench is one loop over these, the ray sets and the thread counts.

use whitted::accel::counters::{self, Steps};
use whitted::accel::policy::HitPolicy;
use whitted::accel::{Accel, Counting, Hit, Isa, PACKET, Plain, Tally, coherent_rays};
use whitted::geometry::ray::Ray;
use whitted::kit::contestants::{BUILDS, Contestant as Built};
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
    /// Its bench id and row in the table: `bvh4-avx2`, `bvh8-avx2-packets`, `obvhs-cwbvh`, `embree-avx2-8`.
    fn id(&self) -> &str;
    /// Ours or a peer's.
    fn side(&self) -> Side;
    /// True for a packet kernel (compared with packets in the ratio rows).
    fn packets(&self) -> bool;
    /// True for a row of the comparison table ([`TABLE`]): every peer's, and ours that "our best" is
    /// taken over ([`table_structures`]).
    fn in_table(&self) -> bool {
        self.side() == Side::Peer
    }
    /// Closest hits of the segments: how many hit.
    fn closest(&self, rays: &[Segment]) -> usize;
    /// Closest hits of coherent segments (camera rays, pixel after pixel), as a renderer asks for
    /// them: ours through `intersect_coherent`, the peers' as [`Contestant::closest`].
    fn coherent(&self, rays: &[Segment]) -> usize {
        self.closest(rays)
    }
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
    /// Packets of 8 consecutive rays where they point alike, else ray by ray (`coherent_rays`: the
    /// renderer's rule for its secondary rays), as Embree's hybrid packet kernels go to single rays
    /// where a packet's rays part.
    Hybrid,
}

/// The filter that runs the comparison table's rows alone: `cargo bench --bench kernels -- table`.
pub const TABLE: &str = "table";

/// The instruction set the race runs on: `WHITTED_BENCH_ISA` (`avx2` or `avx512`), so that an AVX-512
/// CPU can race on AVX2 too, else the CPU's best (as `--simd auto` picks). The table's rows of ours
/// run on it, and so does Embree. An instruction set the CPU lacks is refused.
pub fn race_isa() -> Isa {
    let isa = match std::env::var("WHITTED_BENCH_ISA").as_deref() {
        Err(_) => return Isa::detect(),
        Ok("avx2") => Isa::Avx2,
        Ok("avx512") => Isa::Avx512,
        Ok(other) => panic!("WHITTED_BENCH_ISA={other}: expected avx2 or avx512"),
    };
    assert!(isa.available(), "WHITTED_BENCH_ISA: this CPU has no {isa:?}");
    isa
}

/// The kit's name of an instruction set, as in its rows (`bvh8 avx2`).
pub fn isa_name(isa: Isa) -> &'static str {
    match isa {
        Isa::Avx512 => "avx512",
        Isa::Avx2 => "avx2",
        Isa::Portable => "portable",
    }
}

/// The name of [`race_isa`].
pub fn auto_set() -> &'static str {
    isa_name(race_isa())
}

/// The kit's names of the structures that "our best" is taken over, with their single rays and their
/// packets: the BVH4 and the BVH8 at their default build on [`auto_set`], as `whitted render` runs them.
/// The other instruction sets run the same trees, and a best over them too would pick whichever read
/// high in the machine's noise.
pub fn table_structures() -> Vec<String> {
    BUILDS
        .iter()
        .filter(|b| b.each_simd)
        .map(|b| format!("{} {}", b.name, auto_set()))
        .collect()
}

/// One of the kit's structures ([`whitted::kit::contestants`]) with one of its kernels.
pub struct Ours<'a> {
    id: String,
    accel: &'a Accel<'a>,
    verb: Verb,
    table: bool,
}

impl<'a> Ours<'a> {
    /// `accel` under bench id `id`, with kernel `verb`.
    pub fn new(id: &str, accel: &'a Accel<'a>, verb: Verb) -> Self {
        Ours {
            id: id.to_string(),
            accel,
            verb,
            table: false,
        }
    }

    /// Every structure of `built` with its single-ray kernel, and the wide BVHs with their packets too
    /// (the others answer packets ray by ray: their rows would time single rays again). The BVH4 runs
    /// on [`auto_set`] alone: its kernels are the BVH8's code at width 4, and what another instruction
    /// set changes shows in the BVH8's rows. Embree, which the kit lists with the `embree` feature, is
    /// a peer's: its rows are `embree.rs`'s.
    pub fn all(built: &'a [Built<'a>]) -> Vec<Ours<'a>> {
        let table = table_structures();
        let mut out = Vec::new();
        for b in built.iter().filter(|b| !b.is_embree()) {
            let auto = b.accel.simd().is_none_or(|s| s == race_isa());
            if !auto && !matches!(b.accel, Accel::Bvh8(_)) {
                continue;
            }
            let id = b.name.replace(' ', "-");
            let in_table = table.contains(&b.name);
            let mut push = |id: String, verb: Verb| {
                let mut o = Ours::new(&id, &b.accel, verb);
                o.table = in_table;
                out.push(o);
            };
            if b.has_packet_kernel() {
                push(format!("{id}-packets"), Verb::Packets);
                if in_table {
                    push(format!("{id}-hybrid"), Verb::Hybrid);
                }
            }
            push(id, Verb::Single);
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
        self.verb != Verb::Single
    }

    fn in_table(&self) -> bool {
        self.table
    }

    fn closest(&self, rays: &[Segment]) -> usize {
        self.trace::<Plain>(rays, Query::Closest).0
    }

    fn coherent(&self, rays: &[Segment]) -> usize {
        self.trace::<Plain>(rays, Query::Coherent).0
    }

    fn occluded(&self, rays: &[Segment]) -> usize {
        self.trace::<Plain>(rays, Query::Any).0
    }
}

/// What a ray set asks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// The closest hit.
    Closest,
    /// The closest hit of coherent rays (single rays through `intersect_coherent`).
    Coherent,
    /// Any hit.
    Any,
}

impl Ours<'_> {
    /// The mean nodes visited and primitives tested per ray of `rays` (any hit or closest), counted
    /// by the counting verbs of the row's kernel: the table beside Mrays/s, so that a faster row can be
    /// told apart as fewer steps or cheaper steps.
    pub fn steps_per_ray(&self, rays: &[Segment], query: Query) -> (f64, f64) {
        let steps = self.trace::<Counting>(rays, query).1;
        let n = rays.len().max(1) as f64;
        (steps.nodes as f64 / n, steps.prims as f64 / n)
    }

    /// The rays that hit (or are blocked) through the verbs of `T`, and the steps counted (none
    /// for [`Plain`]).
    fn trace<T: Tally>(&self, rays: &[Segment], query: Query) -> (usize, Steps) {
        let verbs = self.accel.verbs::<T>();
        // The kernels' closures are `Fn`: the sum goes through a cell.
        let steps = std::cell::Cell::new(Steps::default());
        let tally = |n: usize| {
            if T::Closest::COUNT {
                let mut sum = steps.get();
                (0..n).for_each(|k| sum += counters::lane(k));
                steps.set(sum);
            }
        };
        let any = query == Query::Any;
        // A hybrid row's packet whose rays point apart goes ray by ray through the single-ray verbs.
        let live = |active: u8| (0..PACKET).filter(move |k| active >> k & 1 != 0);
        let apart = |r: &[Ray; PACKET], active: u8| {
            self.verb == Verb::Hybrid && !coherent_rays(live(active).map(|k| &r[k]))
        };
        let hits = match (self.verb, any) {
            (Verb::Packets | Verb::Hybrid, false) => packets_of(rays, |r, active, t_max| {
                if apart(r, active) {
                    return live(active).fold(0, |m, k| {
                        let hit = verbs.intersect(&r[k], 0.0, &mut Hit::miss(t_max[k]));
                        tally(1);
                        m | u8::from(hit) << k
                    });
                }
                let hit = verbs.intersect_packet(r, active, 0.0, &mut t_max.map(Hit::miss));
                tally(PACKET);
                hit
            }),
            (Verb::Packets | Verb::Hybrid, true) => packets_of(rays, |r, active, t_max| {
                if apart(r, active) {
                    return live(active).fold(0, |m, k| {
                        let blocked = verbs.occluded(&r[k], 0.0, t_max[k]);
                        tally(1);
                        m | u8::from(blocked) << k
                    });
                }
                let blocked = verbs.occluded_packet(r, active, 0.0, t_max);
                tally(PACKET);
                blocked
            }),
            (Verb::Single, false) => rays
                .iter()
                .filter(|(ray, t_max)| {
                    let found = match query {
                        Query::Coherent => verbs.intersect_coherent(ray, 0.0, &mut Hit::miss(*t_max)),
                        _ => verbs.intersect(ray, 0.0, &mut Hit::miss(*t_max)),
                    };
                    tally(1);
                    found
                })
                .count(),
            (Verb::Single, true) => rays
                .iter()
                .filter(|(ray, t_max)| {
                    let blocked = verbs.occluded(ray, 0.0, *t_max);
                    tally(1);
                    blocked
                })
                .count(),
        };
        (hits, steps.get())
    }
}
