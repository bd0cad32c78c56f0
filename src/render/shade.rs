//! The Whitted integrator (Whitted 1980): local Blinn-Phong colour from every light sample not in shadow,
//! plus mirror reflection and Snell refraction weighted by Schlick's Fresnel term, with Beer absorption
//! inside transparent objects.
//!
//! Conventions (those of NFF/p3f renderers, `shared/DESIGN.md`): surfaces are two-sided, so normals are
//! turned toward the incoming ray; no ambient term; lights have no falloff; secondary and shadow rays start
//! [`EPSILON`] along the geometric normal on the side they leave from. In Whitted's model a transparent
//! object casts a full shadow: shadow rays do not pass through glass.

use glam::Vec3;

use super::Renderer;
use super::optics::{beer, reflect, refract, schlick};
use crate::accel::Hit;
use crate::geometry::ray::Ray;
use crate::scene::Material;

/// Offset of secondary and shadow ray origins along the geometric normal, in scene units.
pub const EPSILON: f32 = 1e-4;

impl Renderer<'_> {
    /// The colour seen along `ray` (unit direction) after `depth` bounces.
    pub fn trace(&self, ray: &Ray, depth: u32) -> Vec3 {
        let mut hit = Hit::miss(f32::INFINITY);
        self.accel.intersect(ray, 0.0, &mut hit);
        self.shade(ray, &hit, depth)
    }

    /// The colour of `ray` given its closest hit (found by a single-ray or a packet kernel): the
    /// background for a miss, else local colour plus reflected and refracted light.
    pub fn shade(&self, ray: &Ray, hit: &Hit, depth: u32) -> Vec3 {
        if !hit.is_hit() {
            return self.background.sample(ray.dir);
        }
        let surface = self.prims.surface(ray, hit);
        let m = &self.scene.materials[surface.material as usize];
        let (p, ng, ns, inside) = (surface.point, surface.geometric, surface.shading, surface.inside);
        let mut color = self.local(p, ng, ns, -ray.dir, m);

        if depth < self.options.max_depth {
            // Fresnel splits light between the mirror and the refracted ray; opaque surfaces reflect Ks.
            let mut kr = 1.0;
            if m.transmission > 0.0 {
                let (eta_i, eta_t) = if inside { (m.ior, 1.0) } else { (1.0, m.ior) };
                let cos_i = (-ray.dir.dot(ns)).clamp(0.0, 1.0);
                kr = schlick(cos_i, eta_i, eta_t);
                if let Some(t) = refract(ray.dir, ns, eta_i / eta_t) {
                    let weight = m.transmission * (1.0 - kr);
                    if weight > 0.0 {
                        let refracted = Ray::new(p - EPSILON * ng, t.normalize());
                        color += weight * self.trace(&refracted, depth + 1);
                    }
                } else {
                    kr = 1.0;
                }
            }
            let weight = m.ks * kr;
            if weight > 0.0 {
                let reflected = Ray::new(p + EPSILON * ng, reflect(ray.dir, ns).normalize());
                color += weight * self.trace(&reflected, depth + 1);
            }
        }
        if inside && m.transmission > 0.0 {
            // The ray crossed the object's interior from its entry point to here.
            color *= beer(m.diffuse, surface.t);
        }
        color
    }

    /// Blinn-Phong local colour: Σ C_light (Kd·Cd·max(0, n·L) + Ks·Cs·max(0, n·h)^shine), h = |L + V|,
    /// over the light samples that an any-hit shadow ray reaches.
    fn local(&self, p: Vec3, ng: Vec3, ns: Vec3, v: Vec3, m: &Material) -> Vec3 {
        let mut color = Vec3::ZERO;
        for light in &self.lights {
            let to_light = light.position - p;
            let l = to_light.normalize();
            let n_dot_l = ns.dot(l);
            // A light behind the shading normal contributes nothing (no diffuse, no highlight).
            if n_dot_l.is_nan() || n_dot_l <= 0.0 {
                continue;
            }
            let origin = p + ng * if ng.dot(l) >= 0.0 { EPSILON } else { -EPSILON };
            let distance = (light.position - origin).length();
            if self.accel.occluded(&Ray::new(origin, l), 0.0, distance) {
                continue;
            }
            let mut c = m.kd * n_dot_l * m.diffuse;
            if m.ks > 0.0 {
                let h = (l + v).normalize();
                c += m.ks * h.dot(ns).max(0.0).powf(m.shininess) * m.specular;
            }
            color += light.color * c;
        }
        color
    }
}
