//! The one id space of the scene's primitives, and what a hit on each kind means.
//!
//! Bounded primitives are numbered kind by kind: spheres `0..S`, triangles `S..S+T`, boxes, then cones;
//! planes (unbounded, kept out of every hierarchy) follow. The kind of an id is a comparison against those
//! boundaries, never a `dyn` call.

use glam::Vec3;

use super::counters;
use super::policy::HitPolicy;
use crate::geometry::{aabb::Aabb, cone, cuboid, plane, ray::Ray, sphere, triangle};
use crate::scene::{MaterialId, NO_NORMALS, Scene};

/// The closest (or any) hit found so far: the ray parameter, the primitive, and the triangle's
/// barycentrics (zero for other kinds). Point, normals and material are derived after traversal, once.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit (the search limit while none is found).
    pub t: f32,
    /// Primitive id, or [`Hit::NONE`] if nothing was hit.
    pub prim: u32,
    /// Barycentric weight of the triangle's second vertex.
    pub u: f32,
    /// Barycentric weight of the triangle's third vertex.
    pub v: f32,
}

impl Hit {
    /// The id of "no primitive".
    pub const NONE: u32 = u32::MAX;

    /// No hit yet, searching up to `t_max`.
    pub fn miss(t_max: f32) -> Self {
        Hit {
            t: t_max,
            prim: Self::NONE,
            u: 0.0,
            v: 0.0,
        }
    }

    /// True if a primitive was hit.
    pub fn is_hit(&self) -> bool {
        self.prim != Self::NONE
    }
}

/// The kind of a primitive and its index within that kind's arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimKind {
    /// `scene.spheres[i]`.
    Sphere(usize),
    /// `scene.triangles[i]`.
    Triangle(usize),
    /// `scene.boxes[i]`.
    Cuboid(usize),
    /// `scene.cones[i]`.
    Cone(usize),
    /// `scene.planes[i]`.
    Plane(usize),
}

/// The hit record: the surface at the closest hit, computed once after traversal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// Ray parameter of the hit.
    pub t: f32,
    /// The hit point.
    pub point: Vec3,
    /// Unit geometric normal, turned toward the incoming ray (surfaces are two-sided).
    pub geometric: Vec3,
    /// Unit shading normal (interpolated for smooth triangles), turned with the geometric normal.
    pub shading: Vec3,
    /// The material.
    pub material: MaterialId,
    /// True if the ray hit the back of the surface (the outward side of a sphere, box or cone, the
    /// counter-clockwise front of a triangle): for a closed object, the ray travelled inside it.
    pub inside: bool,
}

/// A view of a scene's primitives by id.
#[derive(Clone, Copy, Debug)]
pub struct Prims<'a> {
    /// The scene.
    pub scene: &'a Scene,
    first_triangle: u32,
    first_box: u32,
    first_cone: u32,
    bounded: u32,
    total: u32,
}

impl<'a> Prims<'a> {
    /// Numbers the scene's primitives.
    pub fn new(scene: &'a Scene) -> Self {
        let first_triangle = scene.spheres.radius.len() as u32;
        let first_box = first_triangle + scene.triangles.len() as u32;
        let first_cone = first_box + scene.boxes.material.len() as u32;
        let bounded = first_cone + scene.cones.material.len() as u32;
        Prims {
            scene,
            first_triangle,
            first_box,
            first_cone,
            bounded,
            total: bounded + scene.planes.material.len() as u32,
        }
    }

    /// Number of bounded primitives: ids `0..bounded()` go into hierarchies.
    pub fn bounded(&self) -> u32 {
        self.bounded
    }

    /// Number of primitives, planes included.
    pub fn total(&self) -> u32 {
        self.total
    }

    /// The ids of the planes.
    pub fn planes(&self) -> std::ops::Range<u32> {
        self.bounded..self.total
    }

    /// The id of triangle `i`.
    pub fn triangle_id(&self, i: usize) -> u32 {
        self.first_triangle + i as u32
    }

    /// The kind of primitive `id`.
    #[inline(always)]
    pub fn kind(&self, id: u32) -> PrimKind {
        if id < self.first_triangle {
            PrimKind::Sphere(id as usize)
        } else if id < self.first_box {
            PrimKind::Triangle((id - self.first_triangle) as usize)
        } else if id < self.first_cone {
            PrimKind::Cuboid((id - self.first_box) as usize)
        } else if id < self.bounded {
            PrimKind::Cone((id - self.first_cone) as usize)
        } else {
            PrimKind::Plane((id - self.bounded) as usize)
        }
    }

    /// The bounding box of bounded primitive `id` (empty for planes).
    pub fn bounds(&self, id: u32) -> Aabb {
        let s = self.scene;
        match self.kind(id) {
            PrimKind::Sphere(i) => sphere::bounds(s.spheres.center.get(i), s.spheres.radius[i]),
            PrimKind::Triangle(i) => {
                let t = &s.triangles;
                triangle::bounds(t.v0.get(i), t.e1.get(i), t.e2.get(i))
            }
            PrimKind::Cuboid(i) => Aabb::new(s.boxes.min.get(i), s.boxes.max.get(i)),
            PrimKind::Cone(i) => {
                let c = &s.cones;
                cone::bounds(c.base.get(i), c.base_radius[i], c.apex.get(i), c.apex_radius[i])
            }
            PrimKind::Plane(_) => Aabb::EMPTY,
        }
    }

    /// Intersects primitive `id`: `Some((t, u, v))` for a hit with `t` in `(t_min, t_max)`.
    #[inline(always)]
    pub fn intersect(&self, id: u32, ray: &Ray, t_min: f32, t_max: f32) -> Option<(f32, f32, f32)> {
        let s = self.scene;
        let only_t = |t: Option<f32>| t.map(|t| (t, 0.0, 0.0));
        match self.kind(id) {
            PrimKind::Triangle(i) => {
                let t = &s.triangles;
                triangle::intersect(t.v0.get(i), t.e1.get(i), t.e2.get(i), ray, t_min, t_max)
            }
            PrimKind::Sphere(i) => {
                let sp = &s.spheres;
                only_t(sphere::intersect(
                    sp.center.get(i),
                    sp.radius[i],
                    sp.inside_only[i],
                    ray,
                    t_min,
                    t_max,
                ))
            }
            PrimKind::Cuboid(i) => only_t(cuboid::intersect(
                s.boxes.min.get(i),
                s.boxes.max.get(i),
                ray,
                t_min,
                t_max,
            )),
            PrimKind::Cone(i) => {
                let c = &s.cones;
                only_t(cone::intersect(
                    c.base.get(i),
                    c.base_radius[i],
                    c.apex.get(i),
                    c.apex_radius[i],
                    c.inside_only[i],
                    ray,
                    t_min,
                    t_max,
                ))
            }
            PrimKind::Plane(i) => {
                let p = &s.planes;
                only_t(plane::intersect(p.normal.get(i), p.offset[i], ray, t_min, t_max))
            }
        }
    }

    /// Tests the primitives `ids` in order, updating `hit` (closest-hit shrinks `hit.t`, any-hit stops at
    /// the first); true if one was hit. Brute force, BVH leaves of mixed kinds and the planes beside every
    /// hierarchy all go through this one loop.
    #[inline(always)]
    pub fn intersect_each<P: HitPolicy>(
        &self,
        ids: impl IntoIterator<Item = u32>,
        ray: &Ray,
        t_min: f32,
        hit: &mut Hit,
    ) -> bool {
        let mut found = false;
        for id in ids {
            counters::prims::<P>(1);
            if let Some((t, u, v)) = self.intersect(id, ray, t_min, hit.t) {
                *hit = Hit { t, prim: id, u, v };
                found = true;
                if P::ANY {
                    break;
                }
            }
        }
        found
    }

    /// Tests every plane (see [`Prims::intersect_each`]). Planes are unbounded, so every accelerator
    /// tests them this way, beside its hierarchy.
    #[inline]
    pub fn intersect_planes<P: HitPolicy>(&self, ray: &Ray, t_min: f32, hit: &mut Hit) -> bool {
        self.intersect_each::<P>(self.planes(), ray, t_min, hit)
    }

    /// The surface at a hit.
    // Not inlined: a phase of `profiles/frame.sh` (the single-ray path's hit points).
    #[inline(never)]
    pub fn surface(&self, ray: &Ray, hit: &Hit) -> Surface {
        let point = ray.at(hit.t);
        let (geometric, shading, material) = self.normals(point, hit);
        let inside = ray.dir.dot(geometric) > 0.0;
        let sign = if inside { -1.0 } else { 1.0 };
        Surface {
            t: hit.t,
            point,
            geometric: sign * geometric,
            shading: sign * shading,
            material,
            inside,
        }
    }

    /// The geometric and shading normals (not yet turned toward the ray) and the material of `hit`,
    /// at its `point`.
    #[inline(always)]
    pub fn normals(&self, point: Vec3, hit: &Hit) -> (Vec3, Vec3, MaterialId) {
        let s = self.scene;
        match self.kind(hit.prim) {
            PrimKind::Sphere(i) => {
                let sp = &s.spheres;
                let n = sphere::normal(sp.center.get(i), sp.radius[i], point);
                (n, n, sp.material[i])
            }
            PrimKind::Triangle(i) => {
                let t = &s.triangles;
                let ng = triangle::geometric_normal(t.e1.get(i), t.e2.get(i));
                let ns = match t.normals[i] {
                    NO_NORMALS => ng,
                    k => {
                        // Vertex normals may face against the winding (SPD patches): turn each to the
                        // geometric normal's side before interpolating.
                        let n = t.vertex_normals[k as usize].map(|n| if n.dot(ng) < 0.0 { -n } else { n });
                        let ns = triangle::interpolate_normal(&n, hit.u, hit.v);
                        if ns.is_finite() { ns } else { ng }
                    }
                };
                (ng, ns, t.material[i])
            }
            PrimKind::Cuboid(i) => {
                let b = &s.boxes;
                let n = cuboid::normal(b.min.get(i), b.max.get(i), point);
                (n, n, b.material[i])
            }
            PrimKind::Cone(i) => {
                let c = &s.cones;
                let n = cone::normal(
                    c.base.get(i),
                    c.base_radius[i],
                    c.apex.get(i),
                    c.apex_radius[i],
                    point,
                );
                (n, n, c.material[i])
            }
            PrimKind::Plane(i) => {
                let n = s.planes.normal.get(i);
                (n, n, s.planes.material[i])
            }
        }
    }
}
