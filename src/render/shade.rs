//! Whitted's shading of `N` hits at once, written once over lanes (one lane for a single ray, eight
//! for a packet): the hits' points and normals, each light sample's shadow rays set up, the
//! Blinn-Phong sum over the samples not in shadow, and the refracted and reflected rays (Snell,
//! Schlick's Fresnel split, the mirror) with their weights. Every operation is the same IEEE
//! arithmetic on every lane type, so a hit's colour has the same bits whatever its lane count; only
//! `powf` goes lane by lane.
//!
//! Conventions (those of NFF/p3f renderers; the README lists them): surfaces are two-sided, so normals
//! are turned toward the incoming ray; no ambient term; lights have no falloff; secondary and shadow rays
//! start [`EPSILON`] along the geometric normal on the side they leave from.

use glam::Vec3;

use super::lanes::{Fx, Gather, Lanes, V3, each, full};
use super::light::Lights;
use super::optics::{reflect_lanes, refract_lanes, schlick_lanes};
use super::spd::Spawning;
use crate::accel::{Hit, PrimKind, Prims};
use crate::geometry::ray::Ray;
use crate::scene::{Material, MaterialId, NO_NORMALS, Scene};

/// Offset of secondary and shadow ray origins along the geometric normal, in scene units.
pub const EPSILON: f32 = 1e-4;

/// Up to `N` hits in lanes: where they lie, their normals, the rays' directions and their
/// materials.
pub(super) struct HitLanes<L, const N: usize> {
    t: Fx<L, N>,
    p: V3<L, N>,
    ng: V3<L, N>,
    ns: V3<L, N>,
    dir: V3<L, N>,
    /// Each lane's material (a dead lane holds a live lane's).
    ids: [MaterialId; N],
    m: Materials<L, N>,
    /// The lanes whose ray hit the back of its surface ([`crate::accel::Surface::inside`]).
    inside: u32,
    /// The lanes that hold a hit.
    live: u32,
}

/// One light sample seen from the hits of a [`HitLanes`].
pub(super) struct ShadowLanes<L, const N: usize> {
    /// The light sample's positions.
    at: V3<L, N>,
    /// Unit directions toward the light, and their cosines with the shading normals.
    l: V3<L, N>,
    n_dot_l: Fx<L, N>,
    /// The live lanes whose light lies in front of the shading normal: those whose shadow rays are
    /// traced (the others add nothing, neither diffuse nor highlight).
    pub lit: u32,
}

/// One kind of secondary ray spawned by the hits of a [`HitLanes`] ([`HitLanes::bounces`]).
pub(super) struct Spawned<L, const N: usize> {
    /// The lanes that spawn one.
    pub lanes: u32,
    /// Where the rays start (just off the surface), their unit directions and their weights.
    pub origin: V3<L, N>,
    pub dir: V3<L, N>,
    pub weight: Fx<L, N>,
}

impl<L: Lanes<N>, const N: usize> Spawned<L, N> {
    #[inline(always)]
    fn none() -> Self {
        Spawned {
            lanes: 0,
            origin: V3::zero(),
            dir: V3::zero(),
            weight: Fx::splat(0.0),
        }
    }
}

impl<L: Lanes<N>, const N: usize> HitLanes<L, N> {
    /// The surfaces at the closest hits `hits` of `rays` in the lanes of `live`, computed in lanes
    /// ([`Prims::surface`]'s normals): a triangle's normals from its edges and vertex normals
    /// gathered lane by lane, other kinds' normals lane by lane. `None` if no lane is live.
    // Its body on the lanes' instructions (`Lanes::call`: for eight lanes a function of its own, a
    // phase of `profiles/frame.sh`).
    #[inline(always)]
    pub fn of_hits(prims: &Prims, rays: &[Ray; N], hits: &[Hit; N], live: u32) -> Option<Self> {
        L::call(
            #[inline(always)]
            || {
                let first = each::<N>(live).next()?;
                let tris = &prims.scene.triangles;
                // Every array cut to one length: one bounds check a lane.
                let n = tris.material.len();
                let (edge1, edge2) = (tris.e1.first(n), tris.e2.first(n));
                let (material, normals) = (&tris.material[..n], &tris.normals[..n]);
                // Gathered lane by lane, then loaded: each triangle's edges and vertex normals, and the
                // other kinds' normals.
                let (mut e1, mut e2) = (Gather::ZERO, Gather::ZERO);
                let mut corners = [Gather::ZERO, Gather::ZERO, Gather::ZERO];
                let (mut u, mut v) = ([0.0; N], [0.0; N]);
                let (mut other_ng, mut other_ns) = (Gather::ZERO, Gather::ZERO);
                let mut ids = [MaterialId::MAX; N];
                // Lanes on triangles with vertex normals, and lanes on other kinds of primitive.
                let (mut smooth, mut other) = (0u32, 0u32);
                for k in each::<N>(live) {
                    let hit = &hits[k];
                    if let PrimKind::Triangle(i) = prims.kind(hit.prim) {
                        e1.set(k, edge1.get(i));
                        e2.set(k, edge2.get(i));
                        ids[k] = material[i];
                        if normals[i] != NO_NORMALS {
                            let n = &tris.vertex_normals[normals[i] as usize];
                            for (corner, n) in corners.iter_mut().zip(n) {
                                corner.set(k, *n);
                            }
                            (u[k], v[k]) = (hit.u, hit.v);
                            smooth |= 1 << k;
                        }
                    } else {
                        let (ng, ns, id) = prims.normals(rays[k].at(hit.t), hit);
                        other_ng.set(k, ng);
                        other_ns.set(k, ns);
                        ids[k] = id;
                        other |= 1 << k;
                    }
                }
                let dir = V3::from_lanes(&rays.each_ref().map(|r| r.dir));
                let t = Fx::from(hits.each_ref().map(|h| h.t));
                let p = V3::from_lanes(&rays.each_ref().map(|r| r.origin)) + dir * t;
                let mut ng = e1.load::<L>().cross(e2.load()).normalize_or_zero();
                let mut ns = ng;
                if smooth != 0 {
                    // Each vertex normal turned to the geometric normal's side, then interpolated.
                    let [n0, n1, n2] = corners.each_ref().map(|n| {
                        let n = n.load::<L>();
                        V3::blend(n.dot(ng).lt(Fx::splat(0.0)), -n, n)
                    });
                    let (u, v) = (Fx::from(u), Fx::from(v));
                    let smoothed = (n0 * (Fx::splat(1.0) - u - v) + n1 * u + n2 * v).normalize_or_zero();
                    ns = V3::blend(smooth & smoothed.finite(), smoothed, ng);
                }
                if other != 0 {
                    ng = V3::blend(other, other_ng.load(), ng);
                    ns = V3::blend(other, other_ns.load(), ns);
                }
                // Two-sided: both normals turned toward the incoming ray.
                let back = dir.dot(ng).positive();
                let sign = Fx::blend(back, Fx::splat(-1.0), Fx::splat(1.0));
                // Dead lanes take a live lane's material: most packets then share one.
                let ids = ids.map(|id| if id == MaterialId::MAX { ids[first] } else { id });
                Some(HitLanes {
                    t,
                    p,
                    ng: ng * sign,
                    ns: ns * sign,
                    dir,
                    m: Materials::gather(prims.scene, &ids),
                    ids,
                    inside: live & back,
                    live,
                })
            },
        )
    }

    /// The lanes that hold a hit.
    #[inline(always)]
    pub fn live(&self) -> u32 {
        self.live
    }

    /// The lanes whose ray hit the back of a transmitter: the light they carry crossed its inside.
    #[inline(always)]
    pub fn inside_transmitters(&self) -> u32 {
        self.inside & self.m.transmits
    }

    /// The live lanes whose material passes `test`: one test where the lanes share a material.
    #[inline(always)]
    pub fn materials_where(&self, test: impl Fn(MaterialId) -> bool) -> u32 {
        match self.m.shared {
            Some(id) => self.live & 0u32.wrapping_sub(u32::from(test(id))),
            None => each::<N>(self.live).fold(0, |m, k| m | u32::from(test(self.ids[k])) << k),
        }
    }

    /// Lane `k`'s material.
    #[inline(always)]
    pub fn material(&self, k: usize) -> MaterialId {
        self.ids[k]
    }

    /// The distances along the rays to their hits.
    #[inline(always)]
    pub fn distances(&self) -> [f32; N] {
        self.t.to_array()
    }

    /// The refracted (0) and reflected (1) rays of the hits in `lanes`, from just off each surface
    /// on the side each leaves to, with their weights: Snell's refraction and Schlick's Fresnel split
    /// for transmitters, Ks for the mirror, those kept as `spawning` rules. The mirror direction of
    /// the lanes of `rough` is `perturb(k, mirror, geometric normal)`'s.
    #[inline(always)]
    pub fn bounces(
        &self,
        scene: &Scene,
        lanes: u32,
        spawning: Spawning,
        rough: u32,
        mut perturb: impl FnMut(usize, Vec3, Vec3) -> Vec3,
    ) -> [Spawned<L, N>; 2] {
        let (m, d, eps) = (&self.m, self.dir, Fx::splat(EPSILON));
        let one = Fx::splat(1.0);
        let (mut kr, mut total, mut transmission) = (one, 0, Fx::splat(0.0));
        let mut refracted = Spawned::none();
        let glass = lanes & m.transmits;
        if glass != 0 {
            // Gathered here, not with the shading's materials: few packets hit a transmitter.
            let ior;
            (transmission, ior) = match m.shared {
                Some(id) => {
                    let one = &scene.materials[id as usize];
                    (Fx::splat(one.transmission), Fx::splat(one.ior))
                }
                None => {
                    let each = self.ids.map(|id| &scene.materials[id as usize]);
                    (
                        Fx::from(each.map(|m| m.transmission)),
                        Fx::from(each.map(|m| m.ior)),
                    )
                }
            };
            let (eta_i, eta_t) = (Fx::blend(self.inside, ior, one), Fx::blend(self.inside, one, ior));
            let fresnel = schlick_lanes((-d.dot(self.ns)).clamp01(), eta_i, eta_t);
            let (t, all_reflected) = refract_lanes(d, self.ns, eta_i / eta_t);
            total = glass & all_reflected;
            kr = Fx::blend(glass & !total, fresnel, one);
            let weight = transmission * (one - kr);
            let kept = spawning.refracted(weight);
            refracted = Spawned {
                lanes: glass & !total & kept,
                origin: self.p - self.ng * eps,
                dir: t.normalize(),
                weight,
            };
        }
        let (weight, kept) = spawning.reflected(m.ks, kr, transmission, total, m.transmits);
        let mut dir = reflect_lanes(d, self.ns).normalize();
        let rough = rough & lanes & kept;
        if rough != 0 {
            let (mut mirror, ng) = (dir.lanes(), self.ng.lanes());
            for k in each::<N>(rough) {
                mirror[k] = perturb(k, mirror[k], ng[k]);
            }
            dir = V3::from_lanes(&mirror);
        }
        let reflected = Spawned {
            lanes: lanes & kept,
            origin: self.p + self.ng * eps,
            dir,
            weight,
        };
        [refracted, reflected]
    }

    /// Light sample positions `at` seen from the hits: the directions toward them and which lanes
    /// they light.
    #[inline(always)]
    pub fn toward(&self, at: V3<L, N>) -> ShadowLanes<L, N> {
        let l = (at - self.p).normalize();
        let n_dot_l = self.ns.dot(l);
        ShadowLanes {
            at,
            l,
            n_dot_l,
            lit: self.live & n_dot_l.positive(),
        }
    }

    /// The shadow rays of `light`, from just off each surface on the light's side, and the distances
    /// to the light: anything hit before it casts the shadow.
    #[inline(always)]
    pub fn shadow_rays(&self, light: &ShadowLanes<L, N>) -> ([Ray; N], [f32; N]) {
        let eps = Fx::splat(EPSILON);
        let side = Fx::blend(self.ng.dot(light.l).ge(Fx::splat(0.0)), eps, -eps);
        let origin = self.p + self.ng * side;
        let distance = (light.at - origin).length().to_array();
        let (origins, dirs) = (origin.lanes(), light.l.lanes());
        (std::array::from_fn(|k| Ray::new(origins[k], dirs[k])), distance)
    }

    /// Adds the light sample `toward`, of colour `light`, to `color` in the lanes of `seen` (lit
    /// and not blocked): Blinn-Phong, Kd·Cd·(n·L), plus Ks·Cs·max(0, n·h)^shine where Ks > 0,
    /// h = |L + V|.
    #[inline(always)]
    pub fn add_light(&self, color: &mut V3<L, N>, toward: &ShadowLanes<L, N>, seen: u32, light: Vec3) {
        if seen == 0 {
            return;
        }
        let m = &self.m;
        let mut c = m.diffuse * (m.kd * toward.n_dot_l);
        let glossy = seen & m.glossy;
        if glossy != 0 {
            let n_dot_h = (toward.l - self.dir).normalize().dot(self.ns).to_array();
            let mut power = [0.0; N];
            for k in each::<N>(glossy) {
                power[k] = n_dot_h[k].max(0.0).powf(m.shininess[k]);
            }
            let highlight = m.specular * (m.ks * Fx::from(power));
            c = V3::blend(glossy, c + highlight, c);
        }
        *color = V3::blend(seen, *color + V3::splat(light) * c, *color);
    }
}

/// Light sample `i` of `N` pixel samples' lights: its positions (one splat where the sample is a
/// fixed light, the same for every pixel sample) and its colour.
#[inline(always)]
pub(super) fn light<L: Lanes<N>, const N: usize>(i: usize, lights: &[Lights; N]) -> (V3<L, N>, Vec3) {
    let one = lights[0].get(i);
    let at = if lights[0].shared(i) {
        V3::splat(one.position)
    } else {
        V3::from_lanes(&std::array::from_fn(|k| lights[k].get(i).position))
    };
    (at, one.color)
}

/// The materials of `N` hits in lanes, gathered once (one load where every live lane hit the same
/// material, the usual case).
struct Materials<L, const N: usize> {
    kd: Fx<L, N>,
    ks: Fx<L, N>,
    shininess: [f32; N],
    diffuse: V3<L, N>,
    specular: V3<L, N>,
    /// The lanes whose material has a highlight and a mirror (Ks > 0).
    glossy: u32,
    /// The lanes whose material transmits (refracts).
    transmits: u32,
    /// The material of every lane, where they share one.
    shared: Option<MaterialId>,
}

impl<L: Lanes<N>, const N: usize> Materials<L, N> {
    /// The materials `ids`.
    #[inline(always)]
    fn gather(scene: &Scene, ids: &[MaterialId; N]) -> Self {
        let one = ids[0];
        let all = |yes: bool| if yes { full::<N>() } else { 0 };
        if ids.iter().all(|&i| i == one) {
            let m = &scene.materials[one as usize];
            return Materials {
                kd: Fx::splat(m.kd),
                ks: Fx::splat(m.ks),
                shininess: [m.shininess; N],
                diffuse: V3::splat(m.diffuse),
                specular: V3::splat(m.specular),
                glossy: all(m.ks > 0.0),
                transmits: all(m.transmission > 0.0),
                shared: Some(one),
            };
        }
        let m = ids.map(|i| &scene.materials[i as usize]);
        let lanes = |test: fn(&Material) -> bool| {
            m.iter()
                .enumerate()
                .fold(0, |g, (k, m)| g | u32::from(test(m)) << k)
        };
        Materials {
            kd: Fx::from(m.map(|m| m.kd)),
            ks: Fx::from(m.map(|m| m.ks)),
            shininess: m.map(|m| m.shininess),
            diffuse: V3::from_lanes(&m.map(|m| m.diffuse)),
            specular: V3::from_lanes(&m.map(|m| m.specular)),
            glossy: lanes(|m| m.ks > 0.0),
            transmits: lanes(|m| m.transmission > 0.0),
            shared: None,
        }
    }
}
