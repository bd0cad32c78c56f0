//! Eight hits shaded at once, for the kernels that hold them together (packets, and the stream
//! kernel's generations): the packet's hit points and normals computed in lanes, each light sample's
//! eight shadow rays set up in lanes, the Blinn-Phong sum in lanes, and the packet's refracted and
//! reflected rays set up in lanes. The operations are the single-ray path's in its order
//! ([`Prims::surface`], [`ShadowRay::new`], [`Whitted::shade_surface`], [`Whitted::bounces`]), lane
//! by lane, so the bits are its bits; only `powf` goes lane by lane, as the scalar function.
//!
//! [`ShadowRay::new`]: crate::render::whitted::ShadowRay::new
//! [`Whitted::shade_surface`]: crate::render::whitted::Whitted::shade_surface
//! [`Whitted::bounces`]: crate::render::whitted::Whitted::bounces

use glam::Vec3;
use wide::f32x8;

use super::PerRay;
use crate::accel::packet::{PACKET, bits};
use crate::accel::{Hit, PrimKind, Prims, Surface};
use crate::geometry::ray::Ray;
use crate::render::lanes::{Vec3x8, lane_mask, positive};
use crate::render::light::Lights;
use crate::render::optics::{clamp01, reflect8, refract8, schlick8};
use crate::render::whitted::EPSILON;
use crate::scene::{Material, MaterialId, NO_NORMALS, Scene};

/// Up to eight hits in lanes: where they lie, their normals, the rays' directions and their
/// materials.
pub(super) struct HitLanes {
    t: f32x8,
    p: Vec3x8,
    ng: Vec3x8,
    ns: Vec3x8,
    dir: Vec3x8,
    /// Each lane's material (a dead lane holds a live lane's).
    ids: PerRay<MaterialId>,
    m: Materials,
    /// The lanes whose ray hit the back of its surface ([`Surface::inside`]).
    inside: u8,
    /// The lanes that hold a hit.
    live: u8,
}

/// One light sample seen from the hits of a [`HitLanes`].
pub(super) struct ShadowLanes {
    /// The light sample's positions.
    at: Vec3x8,
    /// Unit directions toward the light, and their cosines with the shading normals.
    l: Vec3x8,
    n_dot_l: f32x8,
    /// The live lanes whose light lies in front of the shading normal: those whose shadow rays are
    /// traced (the others add nothing, as `ShadowRay::new` returns none for them).
    pub lit: u8,
}

/// One kind of secondary ray spawned by the hits of a [`HitLanes`] ([`HitLanes::bounces`]).
pub(super) struct Spawned {
    /// The lanes that spawn one.
    pub lanes: u8,
    /// Where the rays start (just off the surface), their unit directions and their weights.
    pub origin: Vec3x8,
    pub dir: Vec3x8,
    pub weight: f32x8,
}

impl Spawned {
    const NONE: Spawned = Spawned {
        lanes: 0,
        origin: Vec3x8::ZERO,
        dir: Vec3x8::ZERO,
        weight: f32x8::ZERO,
    };
}

impl HitLanes {
    /// The surfaces at the closest hits `hits` of `rays` in the lanes of `live`, computed in lanes
    /// ([`Prims::surface`]'s operations in its order): a triangle's normals from its edges and vertex
    /// normals gathered lane by lane, other kinds' normals lane by lane. `None` if no lane is live.
    // Not inlined: a phase of `profiles/frame.sh`, called once a packet.
    #[inline(never)]
    pub fn of_hits(prims: &Prims, rays: &PerRay<Ray>, hits: &PerRay<Hit>, live: u8) -> Option<Self> {
        let first = bits(live).next()?;
        let tris = &prims.scene.triangles;
        // Every array cut to one length: one bounds check a lane.
        let n = tris.material.len();
        let (edge1, edge2) = (tris.e1.first(n), tris.e2.first(n));
        let (material, normals) = (&tris.material[..n], &tris.normals[..n]);
        // Gathered straight into the lanes: each triangle's edges and vertex normals, and the other
        // kinds' normals.
        let (mut e1, mut e2) = (Vec3x8::ZERO, Vec3x8::ZERO);
        let mut corners = [Vec3x8::ZERO; 3];
        let (mut u, mut v) = (f32x8::ZERO, f32x8::ZERO);
        let (mut other_ng, mut other_ns) = (Vec3x8::ZERO, Vec3x8::ZERO);
        let mut ids = [MaterialId::MAX; PACKET];
        // Lanes on triangles with vertex normals, and lanes on other kinds of primitive.
        let (mut smooth, mut other) = (0u8, 0u8);
        for k in bits(live) {
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
                    (u.as_mut_array()[k], v.as_mut_array()[k]) = (hit.u, hit.v);
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
        let dir = Vec3x8::from_fn(|k| rays[k].dir);
        let t = f32x8::from(std::array::from_fn::<_, PACKET, _>(|k| hits[k].t));
        let p = Vec3x8::from_fn(|k| rays[k].origin) + dir * t;
        let mut ng = e1.cross(e2).normalize_or_zero();
        let mut ns = ng;
        if smooth != 0 {
            // Each vertex normal turned to the geometric normal's side, then interpolated.
            let [n0, n1, n2] = corners.map(|n| Vec3x8::select(n.dot(ng).simd_lt(f32x8::ZERO), -n, n));
            let smoothed = (n0 * (f32x8::ONE - u - v) + n1 * u + n2 * v).normalize_or_zero();
            ns = Vec3x8::select(lane_mask(smooth & smoothed.finite()), smoothed, ng);
        }
        if other != 0 {
            let other = lane_mask(other);
            ng = Vec3x8::select(other, other_ng, ng);
            ns = Vec3x8::select(other, other_ns, ns);
        }
        // Two-sided: both normals turned toward the incoming ray.
        let back = dir.dot(ng).simd_gt(f32x8::ZERO);
        let sign = back.select(f32x8::splat(-1.0), f32x8::ONE);
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
            inside: live & back.to_bitmask() as u8,
            live,
        })
    }

    /// The lanes whose ray hit the back of its surface.
    #[inline]
    pub fn inside(&self) -> u8 {
        self.inside
    }

    /// The lanes whose material transmits.
    #[inline]
    pub fn transmits(&self) -> u8 {
        self.m.transmits
    }

    /// The live lanes whose material passes `test`: one test where the lanes share a material.
    #[inline]
    pub fn materials_where(&self, test: impl Fn(MaterialId) -> bool) -> u8 {
        match self.m.shared {
            Some(id) => self.live & 0u8.wrapping_sub(u8::from(test(id))),
            None => bits(self.live).fold(0, |m, k| m | u8::from(test(self.ids[k])) << k),
        }
    }

    /// Lane `k`'s surface, as [`Prims::surface`] gives it.
    pub fn surface(&self, k: usize) -> Surface {
        Surface {
            t: self.t.as_array()[k],
            point: self.p.lane(k),
            geometric: self.ng.lane(k),
            shading: self.ns.lane(k),
            material: self.ids[k],
            inside: self.inside >> k & 1 == 1,
        }
    }

    /// The refracted (0) and reflected (1) rays of the hits in `lanes` on smooth materials, from
    /// just off each surface on the side each leaves to, with their weights: [`Whitted::bounces`]'
    /// rays in lanes (Snell's refraction and Schlick's Fresnel split for transmitters, Ks for the
    /// mirror), under the SPD's rules with `spd`.
    ///
    /// [`Whitted::bounces`]: crate::render::whitted::Whitted::bounces
    #[inline]
    pub fn bounces(&self, scene: &Scene, lanes: u8, spd: bool) -> [Spawned; 2] {
        let (m, d, eps) = (&self.m, self.dir, f32x8::splat(EPSILON));
        let (mut kr, mut total, mut transmission) = (f32x8::ONE, f32x8::ZERO, f32x8::ZERO);
        let mut refracted = Spawned::NONE;
        let glass = lanes & m.transmits;
        if glass != 0 {
            // Gathered here, not with the shading's materials: few packets hit a transmitter.
            let ior;
            (transmission, ior) = match m.shared {
                Some(id) => {
                    let one = &scene.materials[id as usize];
                    (f32x8::splat(one.transmission), f32x8::splat(one.ior))
                }
                None => {
                    let each = self.ids.map(|id| &scene.materials[id as usize]);
                    (
                        f32x8::from(each.map(|m| m.transmission)),
                        f32x8::from(each.map(|m| m.ior)),
                    )
                }
            };
            let inside = lane_mask(self.inside);
            let (eta_i, eta_t) = (inside.select(ior, f32x8::ONE), inside.select(f32x8::ONE, ior));
            let fresnel = schlick8(clamp01(-d.dot(self.ns)), eta_i, eta_t);
            let (t, all_reflected) = refract8(d, self.ns, eta_i / eta_t);
            total = lane_mask(glass) & all_reflected;
            kr = lane_mask(glass).select(total.select(f32x8::ONE, fresnel), f32x8::ONE);
            let weight = transmission * (f32x8::ONE - kr);
            let kept = if spd { !0 } else { positive(weight) };
            refracted = Spawned {
                lanes: glass & !(total.to_bitmask() as u8) & kept,
                origin: self.p - self.ng * eps,
                dir: t.normalize(),
                weight,
            };
        }
        let weight = if spd {
            total.select(m.ks + transmission, m.ks * kr)
        } else {
            m.ks * kr
        };
        let kept = positive(weight) | if spd { m.transmits } else { 0 };
        let reflected = Spawned {
            lanes: lanes & kept,
            origin: self.p + self.ng * eps,
            dir: reflect8(d, self.ns).normalize(),
            weight,
        };
        [refracted, reflected]
    }

    /// Light sample positions `at` seen from the hits: the directions toward them and which lanes
    /// they light (`ShadowRay::new` in lanes, up to its ray).
    #[inline]
    pub fn toward(&self, at: Vec3x8) -> ShadowLanes {
        let l = (at - self.p).normalize();
        let n_dot_l = self.ns.dot(l);
        ShadowLanes {
            at,
            l,
            n_dot_l,
            lit: self.live & positive(n_dot_l),
        }
    }

    /// The shadow rays of `light`, from just off each surface on the light's side, and the distances
    /// to the light (`ShadowRay::new`'s ray and distance in lanes).
    #[inline]
    pub fn shadow_rays(&self, light: &ShadowLanes) -> (PerRay<Ray>, [f32; PACKET]) {
        let eps = f32x8::splat(EPSILON);
        let origin = self.p + self.ng * self.ng.dot(light.l).simd_ge(f32x8::ZERO).select(eps, -eps);
        let distance = (light.at - origin).length().to_array();
        let (origins, dirs) = (origin.lanes(), light.l.lanes());
        (std::array::from_fn(|k| Ray::new(origins[k], dirs[k])), distance)
    }

    /// Adds the light sample `toward`, of colour `light`, to `color` in the lanes of `seen` (lit
    /// and not blocked): Kd·Cd·(n·L), plus Ks·Cs·(n·h)^shine where Ks > 0.
    #[inline]
    pub fn add_light(&self, color: &mut Vec3x8, toward: &ShadowLanes, seen: u8, light: Vec3) {
        if seen == 0 {
            return;
        }
        let m = &self.m;
        let mut c = m.diffuse * (m.kd * toward.n_dot_l);
        let glossy = seen & m.glossy;
        if glossy != 0 {
            let n_dot_h = (toward.l - self.dir).normalize().dot(self.ns).to_array();
            let mut power = [0.0; PACKET];
            for k in bits(glossy) {
                power[k] = n_dot_h[k].max(0.0).powf(m.shininess[k]);
            }
            let highlight = m.specular * (m.ks * f32x8::from(power));
            c = Vec3x8::select(lane_mask(glossy), c + highlight, c);
        }
        *color = Vec3x8::select(lane_mask(seen), *color + Vec3x8::splat(light) * c, *color);
    }
}

/// Light sample `i` of eight pixel samples' lights: its positions (one splat where the sample is a
/// fixed light, the same for every pixel sample) and its colour.
#[inline(always)]
pub(super) fn light(i: usize, lights: &PerRay<Lights>) -> (Vec3x8, Vec3) {
    let one = lights[0].get(i);
    let at = if lights[0].shared(i) {
        Vec3x8::splat(one.position)
    } else {
        // An array first: through `Vec3x8::from_fn` the light loop ran more instructions.
        Vec3x8::from_lanes(&std::array::from_fn(|k| lights[k].get(i).position))
    };
    (at, one.color)
}

/// The materials of eight hits in lanes, gathered once (one load where every live lane hit the same
/// material, the usual case).
struct Materials {
    kd: f32x8,
    ks: f32x8,
    shininess: [f32; PACKET],
    diffuse: Vec3x8,
    specular: Vec3x8,
    /// The lanes whose material has a highlight and a mirror (Ks > 0).
    glossy: u8,
    /// The lanes whose material transmits (refracts).
    transmits: u8,
    /// The material of every lane, where they share one.
    shared: Option<MaterialId>,
}

impl Materials {
    /// The materials `ids`.
    #[inline(always)]
    fn gather(scene: &Scene, ids: &PerRay<MaterialId>) -> Self {
        let one = ids[0];
        let all = |yes: bool| if yes { !0 } else { 0 };
        if ids.iter().all(|&i| i == one) {
            let m = &scene.materials[one as usize];
            return Materials {
                kd: f32x8::splat(m.kd),
                ks: f32x8::splat(m.ks),
                shininess: [m.shininess; PACKET],
                diffuse: Vec3x8::splat(m.diffuse),
                specular: Vec3x8::splat(m.specular),
                glossy: all(m.ks > 0.0),
                transmits: all(m.transmission > 0.0),
                shared: Some(one),
            };
        }
        let m = ids.map(|i| &scene.materials[i as usize]);
        let lanes = |test: fn(&Material) -> bool| {
            m.iter()
                .enumerate()
                .fold(0, |g, (k, m)| g | u8::from(test(m)) << k)
        };
        Materials {
            kd: f32x8::from(m.map(|m| m.kd)),
            ks: f32x8::from(m.map(|m| m.ks)),
            shininess: m.map(|m| m.shininess),
            diffuse: Vec3x8::from_lanes(&m.map(|m| m.diffuse)),
            specular: Vec3x8::from_lanes(&m.map(|m| m.specular)),
            glossy: lanes(|m| m.ks > 0.0),
            transmits: lanes(|m| m.transmission > 0.0),
            shared: None,
        }
    }
}
