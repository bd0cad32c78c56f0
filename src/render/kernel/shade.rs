//! Eight hits shaded at once, for the kernels that hold them together (packets, and the stream
//! kernel's generations): each light sample's eight shadow rays set up in lanes, and the Blinn-Phong
//! sum in lanes. The operations are the single-ray path's in its order ([`ShadowRay::new`],
//! [`Whitted::shade_surface`]), lane by lane, so the bits are its bits; only `powf` goes lane by lane,
//! as the scalar function.
//!
//! [`ShadowRay::new`]: crate::render::whitted::ShadowRay::new
//! [`Whitted::shade_surface`]: crate::render::whitted::Whitted::shade_surface

use glam::Vec3;
use wide::f32x8;

use super::PerRay;
use crate::accel::Surface;
use crate::accel::packet::{PACKET, bits};
use crate::geometry::ray::Ray;
use crate::render::lanes::{Vec3x8, lane_mask, positive};
use crate::render::light::Lights;
use crate::render::whitted::EPSILON;
use crate::scene::{Material, MaterialId, Scene};

/// Up to eight hits in lanes: where they lie, their normals, the way back to the eye and their
/// materials.
pub(super) struct HitLanes {
    p: Vec3x8,
    ng: Vec3x8,
    ns: Vec3x8,
    /// Toward the eye: the rays' directions reversed.
    v: Vec3x8,
    m: Materials,
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

impl HitLanes {
    /// The hits `surface(k)` (none: a dead lane) of rays with directions `dir(k)`; `None` if no
    /// lane holds a hit. Inlined into its callers, so that the eight hits go straight from where
    /// they lie into the lanes.
    #[inline(always)]
    pub fn new<'s>(
        scene: &Scene,
        dir: impl Fn(usize) -> Vec3,
        surface: impl Fn(usize) -> Option<&'s Surface>,
    ) -> Option<Self> {
        let (mut p, mut ng, mut ns) = ([Vec3::ZERO; PACKET], [Vec3::ZERO; PACKET], [Vec3::ZERO; PACKET]);
        let mut ids = [MaterialId::MAX; PACKET];
        let mut live = 0u8;
        for k in 0..PACKET {
            if let Some(s) = surface(k) {
                (p[k], ng[k], ns[k], ids[k]) = (s.point, s.geometric, s.shading, s.material);
                live |= 1 << k;
            }
        }
        let first = bits(live).next()?;
        Some(HitLanes {
            p: Vec3x8::from_lanes(&p),
            ng: Vec3x8::from_lanes(&ng),
            ns: Vec3x8::from_lanes(&ns),
            v: -Vec3x8::from_lanes(&std::array::from_fn(dir)),
            m: Materials::gather(scene, &ids, ids[first]),
            live,
        })
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
            let n_dot_h = (toward.l + self.v).normalize().dot(self.ns).to_array();
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
    /// The lanes whose material has a highlight (Ks > 0).
    glossy: u8,
}

impl Materials {
    /// The materials `ids` (`MaterialId::MAX`: a dead lane, given `one`'s, a live lane's).
    #[inline(always)]
    fn gather(scene: &Scene, ids: &PerRay<MaterialId>, one: MaterialId) -> Self {
        let ids = ids.map(|i| if i == MaterialId::MAX { one } else { i });
        let glossy = |m: &Material| m.ks > 0.0;
        if ids.iter().all(|&i| i == one) {
            let m = &scene.materials[one as usize];
            return Materials {
                kd: f32x8::splat(m.kd),
                ks: f32x8::splat(m.ks),
                shininess: [m.shininess; PACKET],
                diffuse: Vec3x8::splat(m.diffuse),
                specular: Vec3x8::splat(m.specular),
                glossy: if glossy(m) { !0 } else { 0 },
            };
        }
        let m = ids.map(|i| &scene.materials[i as usize]);
        Materials {
            kd: f32x8::from(m.map(|m| m.kd)),
            ks: f32x8::from(m.map(|m| m.ks)),
            shininess: m.map(|m| m.shininess),
            diffuse: Vec3x8::from_lanes(&m.map(|m| m.diffuse)),
            specular: Vec3x8::from_lanes(&m.map(|m| m.specular)),
            glossy: m
                .iter()
                .enumerate()
                .fold(0, |g, (k, m)| g | u8::from(glossy(m)) << k),
        }
    }
}
