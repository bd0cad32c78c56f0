//! The scene in memory: one structure of arrays per primitive kind, a material table, lights and the view.
//!
//! Kernels read a primitive's components from parallel arrays (`x[i]`, `y[i]`, `z[i]`), so four or eight
//! lanes can load four or eight primitives with plain vector loads; there is no `Box<dyn Object>`: a
//! primitive is a kind and an index, and everything dispatches on that.

use std::path::PathBuf;

use glam::Vec3;

use super::MeshData;
use crate::error::{Error, Result};
use crate::geometry::aabb::Aabb;
use crate::geometry::length_and_direction;

/// Index into [`Scene::materials`].
pub type MaterialId = u32;

/// Three component arrays: the SoA form of a `Vec<Vec3>`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Vec3s {
    /// x components.
    pub x: Vec<f32>,
    /// y components.
    pub y: Vec<f32>,
    /// z components.
    pub z: Vec<f32>,
}

/// A run of [`Vec3s`], its three components cut to one length ([`Vec3s::first`]).
#[derive(Clone, Copy, Debug)]
pub struct Vec3View<'a> {
    x: &'a [f32],
    y: &'a [f32],
    z: &'a [f32],
}

impl Vec3View<'_> {
    /// The `i`-th vector.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }
}

impl Vec3s {
    /// Appends one vector.
    pub fn push(&mut self, v: Vec3) {
        self.x.push(v.x);
        self.y.push(v.y);
        self.z.push(v.z);
    }

    /// The `i`-th vector.
    #[inline(always)]
    pub fn get(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }

    /// The first `n` vectors, as three slices of one length: indexing the view checks the index
    /// once for all three components (and for any other slice cut to `n`).
    #[inline(always)]
    pub fn first(&self, n: usize) -> Vec3View<'_> {
        Vec3View {
            x: &self.x[..n],
            y: &self.y[..n],
            z: &self.z[..n],
        }
    }

    /// Number of vectors.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// True if there are none.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    fn reserve(&mut self, n: usize) {
        self.x.reserve(n);
        self.y.reserve(n);
        self.z.reserve(n);
    }
}

/// Spheres. A sphere from an NFF line with a negative radius is visible from the inside only.
#[derive(Clone, Debug, Default)]
pub struct Spheres {
    /// Centres.
    pub center: Vec3s,
    /// Radii (always positive).
    pub radius: Vec<f32>,
    /// True where only the inside is visible.
    pub inside_only: Vec<bool>,
    /// Materials.
    pub material: Vec<MaterialId>,
}

/// Marks a triangle without per-vertex normals in [`Triangles::normals`].
pub const NO_NORMALS: u32 = u32::MAX;

/// Triangles, stored as one vertex and two edges: the form Möller–Trumbore (1997) consumes.
#[derive(Clone, Debug, Default)]
pub struct Triangles {
    /// First vertex.
    pub v0: Vec3s,
    /// Edge `v1 - v0`.
    pub e1: Vec3s,
    /// Edge `v2 - v0`.
    pub e2: Vec3s,
    /// Materials.
    pub material: Vec<MaterialId>,
    /// Index into `vertex_normals`, or [`NO_NORMALS`].
    pub normals: Vec<u32>,
    /// Per-vertex normals of the triangles that have them (`pp` patches, meshes with normals).
    pub vertex_normals: Vec<[Vec3; 3]>,
}

impl Triangles {
    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.material.len()
    }

    /// True if there are none.
    pub fn is_empty(&self) -> bool {
        self.material.is_empty()
    }

    /// The three vertices of triangle `i`.
    pub fn vertices(&self, i: usize) -> [Vec3; 3] {
        let v0 = self.v0.get(i);
        [v0, v0 + self.e1.get(i), v0 + self.e2.get(i)]
    }

    /// Makes room for `n` more triangles.
    pub fn reserve(&mut self, n: usize) {
        for v in [&mut self.v0, &mut self.e1, &mut self.e2] {
            v.reserve(n);
        }
        self.material.reserve(n);
        self.normals.reserve(n);
    }

    /// True if triangle `i` has no area (it can never be hit; it is kept so that counts match the file).
    pub fn is_degenerate(&self, i: usize) -> bool {
        self.e1.get(i).cross(self.e2.get(i)).length_squared() == 0.0
    }
}

/// The points `tri` indexes, if every index is in range.
fn corners(points: &[Vec3], tri: &[u32; 3]) -> Option<[Vec3; 3]> {
    let [a, b, c] = tri.map(|i| points.get(i as usize).copied());
    Some([a?, b?, c?])
}

/// Axis-aligned boxes.
#[derive(Clone, Debug, Default)]
pub struct Boxes {
    /// Smallest corners.
    pub min: Vec3s,
    /// Largest corners.
    pub max: Vec3s,
    /// Materials.
    pub material: Vec<MaterialId>,
}

/// Infinite planes `normal · p = offset`; unbounded, so they stay outside the accelerators.
#[derive(Clone, Debug, Default)]
pub struct Planes {
    /// Unit normals (the side the three defining points wind counter-clockwise around).
    pub normal: Vec3s,
    /// `normal · p` for any point `p` of the plane.
    pub offset: Vec<f32>,
    /// Materials.
    pub material: Vec<MaterialId>,
}

/// NFF cones and cylinders without end caps (equal radii make a cylinder).
#[derive(Clone, Debug, Default)]
pub struct Cones {
    /// Centre of the base disc.
    pub base: Vec3s,
    /// Radius at the base (non-negative).
    pub base_radius: Vec<f32>,
    /// Centre of the apex disc.
    pub apex: Vec3s,
    /// Radius at the apex (non-negative).
    pub apex_radius: Vec<f32>,
    /// True where only the inside is visible (both radii negative in the file).
    pub inside_only: Vec<bool>,
    /// Materials.
    pub material: Vec<MaterialId>,
}

/// A surface's response, the course's Whitted model (Whitted 1980 with Blinn-Phong highlights).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Diffuse colour Cd.
    pub diffuse: Vec3,
    /// Diffuse weight Kd.
    pub kd: f32,
    /// Specular colour Cs (the diffuse colour for 8-number NFF materials).
    pub specular: Vec3,
    /// Specular and mirror weight Ks.
    pub ks: f32,
    /// Blinn-Phong exponent.
    pub shininess: f32,
    /// Transmission weight T.
    pub transmission: f32,
    /// Index of refraction (meaningful when `transmission > 0`).
    pub ior: f32,
    /// Spread of reflections (the radius of the ball the mirror direction is perturbed within): 0 is a
    /// perfect mirror; `None` when the file does not say, and the renderer's default applies.
    pub roughness: Option<f32>,
}

impl Default for Material {
    /// Grey and diffuse: what an object gets before the file's first `f`.
    fn default() -> Self {
        Material {
            diffuse: Vec3::splat(0.8),
            kd: 1.0,
            specular: Vec3::ONE,
            ks: 0.0,
            shininess: 1.0,
            transmission: 0.0,
            ior: 1.0,
            roughness: None,
        }
    }
}

/// A point light (no distance falloff, as NFF renderers do).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    /// Position.
    pub position: Vec3,
    /// Colour (white when NFF gives none).
    pub color: Vec3,
}

/// A quad area light `corner + s·edge_u + t·edge_v`, s, t in [0, 1], sampled on a `grid` × `grid` lattice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuadLight {
    /// One corner.
    pub corner: Vec3,
    /// First edge.
    pub edge_u: Vec3,
    /// Second edge.
    pub edge_v: Vec3,
    /// Total colour (each of the grid² samples carries colour / grid²).
    pub color: Vec3,
    /// Samples per side.
    pub grid: u32,
}

/// The most light samples a scene may have in all: a point light is one, a quad light grid². Without
/// sampling every one is a point light in memory (a [`LightSample`](crate::render::light::LightSample),
/// 24 bytes) and a shadow ray from every shaded point, so this bounds both, whatever the file's length:
/// 2^20 is the one quad light of the largest grid (1024²) the format allows, 24 MiB. The shipped scenes
/// use at most 17 (`scenes/distribution.p3f`: a quad of 4² and a point light).
pub const MAX_LIGHT_SAMPLES: u64 = 1 << 20;

impl QuadLight {
    /// The point of the light at `(s, t)` in the unit square.
    pub fn point(&self, s: f32, t: f32) -> Vec3 {
        self.corner + s * self.edge_u + t * self.edge_v
    }
}

/// The view: the NFF/p3f `v` block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub from: Vec3,
    /// Look-at point, seen at the image centre.
    pub at: Vec3,
    /// Up hint (need not be perpendicular to the view direction).
    pub up: Vec3,
    /// Vertical field of view in degrees, edge to edge.
    pub fov_y: f32,
    /// Near distance (NFF `hither`); informational for a ray tracer.
    pub hither: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Lens aperture as a multiple of the pixel size on the view plane (0 = pinhole).
    pub aperture: f32,
    /// Focal distance as a ratio of the view-plane distance `|at - from|`.
    pub focal: f32,
}

/// The largest image side accepted (a 64k-pixel side is already an absurd frame for a CPU tracer).
pub const MAX_RESOLUTION: u32 = 65_536;
/// The largest pixel count accepted.
pub const MAX_PIXELS: u64 = 1 << 28;

impl Camera {
    /// A pinhole camera; check it with [`Camera::validate`].
    pub fn new(from: Vec3, at: Vec3, up: Vec3, fov_y: f32, width: u32, height: u32) -> Self {
        Camera {
            from,
            at,
            up,
            fov_y,
            hither: 0.0,
            width,
            height,
            aperture: 0.0,
            focal: 1.0,
        }
    }

    /// Checks what would make the view undefined; the error names the offending `v`-block keyword.
    pub fn validate(&self) -> std::result::Result<(), CameraError> {
        let fail = |field, message: String| Err(CameraError { field, message });
        let dir = self.at - self.from;
        if !dir.is_finite() {
            return fail(
                "at",
                format!(
                    "\"from\" {} and \"at\" {} are too far apart: their distance overflows single precision",
                    fmt_vec(self.from),
                    fmt_vec(self.at)
                ),
            );
        }
        if dir == Vec3::ZERO {
            return fail(
                "at",
                format!("\"from\" and \"at\" are the same point {}", fmt_vec(self.from)),
            );
        }
        if self.up == Vec3::ZERO {
            return fail("up", "\"up\" is the zero vector".into());
        }
        // Directions scaled before they are squared: a camera 2e19 units from its target is fine.
        let (forward, up) = (length_and_direction(dir).1, length_and_direction(self.up).1);
        if forward.cross(up).length() < 1e-6 {
            return fail(
                "up",
                format!(
                    "\"up\" {} is parallel to the view direction {}",
                    fmt_vec(self.up),
                    fmt_vec(dir)
                ),
            );
        }
        if !(self.fov_y > 0.0 && self.fov_y < 180.0) {
            return fail(
                "angle",
                format!(
                    "expected an angle between 0 and 180 degrees, found {}",
                    self.fov_y
                ),
            );
        }
        if let Err(message) = check_resolution(self.width, self.height) {
            return fail("resolution", message);
        }
        if self.aperture < 0.0 {
            return fail(
                "aperture",
                format!("expected a non-negative aperture, found {}", self.aperture),
            );
        }
        if self.focal <= 0.0 {
            return fail(
                "focal",
                format!("expected a positive focal ratio, found {}", self.focal),
            );
        }
        Ok(())
    }
}

/// Why a camera is unusable: the `v`-block keyword at fault and a message.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CameraError {
    /// `from`, `at`, `up`, `angle`, `resolution`, `aperture` or `focal`.
    pub field: &'static str,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for CameraError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

/// Checks an image size.
pub fn check_resolution(width: u32, height: u32) -> std::result::Result<(), String> {
    if width == 0 || height == 0 || width > MAX_RESOLUTION || height > MAX_RESOLUTION {
        return Err(format!(
            "resolution must be between 1 and {MAX_RESOLUTION} on each side, found {width}x{height}"
        ));
    }
    if width as u64 * height as u64 > MAX_PIXELS {
        return Err(format!(
            "resolution {width}x{height} has more than {MAX_PIXELS} pixels"
        ));
    }
    Ok(())
}

fn fmt_vec(v: Vec3) -> String {
    format!("({} {} {})", v.x, v.y, v.z)
}

/// The accelerator a scene file asks for (`accel N`); the CLI may override it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AccelHint {
    /// `accel 0`: brute force.
    None,
    /// `accel 1`: uniform grid.
    Grid,
    /// `accel 2`: binary BVH.
    Bvh2,
    /// `accel 3` (ours): the 4-wide BVH.
    Bvh4,
}

/// A whole scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The view.
    pub camera: Camera,
    /// Colour of rays that hit nothing.
    pub background: Vec3,
    /// Cube-map directory named by `env`, if any (resolved against the scene file's folder).
    pub env: Option<PathBuf>,
    /// Samples per pixel from `spp` (0 = one ray through each pixel centre).
    pub spp: u32,
    /// Accelerator named by `accel`, if any.
    pub accel: Option<AccelHint>,
    /// Material table.
    pub materials: Vec<Material>,
    /// Point lights.
    pub point_lights: Vec<PointLight>,
    /// Quad area lights.
    pub area_lights: Vec<QuadLight>,
    /// Spheres.
    pub spheres: Spheres,
    /// Triangles (polygons and meshes after triangulation).
    pub triangles: Triangles,
    /// Axis-aligned boxes.
    pub boxes: Boxes,
    /// Infinite planes.
    pub planes: Planes,
    /// Cones and cylinders.
    pub cones: Cones,
    /// Things the loader accepted but a user should know about (printed by the CLI).
    pub warnings: Vec<String>,
}

impl Scene {
    /// An empty scene seen through `camera`, black background, no materials.
    pub fn new(camera: Camera) -> Self {
        Scene {
            camera,
            background: Vec3::ZERO,
            env: None,
            spp: 0,
            accel: None,
            materials: Vec::new(),
            point_lights: Vec::new(),
            area_lights: Vec::new(),
            spheres: Spheres::default(),
            triangles: Triangles::default(),
            boxes: Boxes::default(),
            planes: Planes::default(),
            cones: Cones::default(),
            warnings: Vec::new(),
        }
    }

    /// Adds a material and returns its id.
    pub fn add_material(&mut self, material: Material) -> MaterialId {
        self.materials.push(material);
        (self.materials.len() - 1) as MaterialId
    }

    /// Adds a point light.
    pub fn add_point_light(&mut self, position: Vec3, color: Vec3) {
        self.point_lights.push(PointLight { position, color });
    }

    /// Adds a sphere; a negative radius makes it visible from the inside only (NFF).
    pub fn add_sphere(&mut self, center: Vec3, radius: f32, material: MaterialId) {
        self.spheres.center.push(center);
        self.spheres.radius.push(radius.abs());
        self.spheres.inside_only.push(radius < 0.0);
        self.spheres.material.push(material);
    }

    /// Adds a triangle (counter-clockwise seen from its front).
    pub fn add_triangle(&mut self, a: Vec3, b: Vec3, c: Vec3, material: MaterialId) {
        self.triangles.v0.push(a);
        self.triangles.e1.push(b - a);
        self.triangles.e2.push(c - a);
        self.triangles.material.push(material);
        self.triangles.normals.push(NO_NORMALS);
    }

    /// Adds a triangle with per-vertex normals for smooth shading.
    pub fn add_smooth_triangle(&mut self, v: [Vec3; 3], n: [Vec3; 3], material: MaterialId) {
        self.add_triangle(v[0], v[1], v[2], material);
        *self.triangles.normals.last_mut().unwrap() = self.triangles.vertex_normals.len() as u32;
        self.triangles.vertex_normals.push(n);
    }

    /// Adds the triangles of an indexed mesh, checking every index. Triangles with normals become smooth
    /// ones ([`Scene::add_smooth_triangle`]); the loaders store those normals at unit length.
    pub fn add_mesh(&mut self, mesh: &MeshData, material: MaterialId) -> Result<()> {
        let count = mesh.triangles.len();
        if !(mesh.normal_triangles.is_empty() || mesh.normal_triangles.len() == count) {
            return Err(Error::msg(format!(
                "mesh has normals for {} triangles, expected none or all {count}",
                mesh.normal_triangles.len()
            )));
        }
        self.triangles.reserve(count);
        for (k, tri) in mesh.triangles.iter().enumerate() {
            let Some([a, b, c]) = corners(&mesh.positions, tri) else {
                return Err(Error::msg(format!(
                    "mesh triangle {k} has a vertex index out of range 0..{}: {tri:?}",
                    mesh.positions.len()
                )));
            };
            match mesh.normal_triangles.get(k).copied().flatten() {
                None => self.add_triangle(a, b, c, material),
                Some(normals) => {
                    let Some(n) = corners(&mesh.normals, &normals) else {
                        return Err(Error::msg(format!(
                            "mesh triangle {k} has a normal index out of range 0..{}: {normals:?}",
                            mesh.normals.len()
                        )));
                    };
                    self.add_smooth_triangle([a, b, c], n, material);
                }
            }
        }
        Ok(())
    }

    /// Adds an axis-aligned box.
    pub fn add_box(&mut self, min: Vec3, max: Vec3, material: MaterialId) {
        self.boxes.min.push(min);
        self.boxes.max.push(max);
        self.boxes.material.push(material);
    }

    /// Adds the infinite plane through three points (its normal follows their counter-clockwise order).
    /// Returns false, adding nothing, if the points are collinear.
    pub fn add_plane(&mut self, p0: Vec3, p1: Vec3, p2: Vec3, material: MaterialId) -> bool {
        let n = (p1 - p0).cross(p2 - p0);
        if n.length_squared().is_nan() || n.length_squared() <= 0.0 {
            return false;
        }
        let n = n.normalize();
        self.planes.normal.push(n);
        self.planes.offset.push(n.dot(p0));
        self.planes.material.push(material);
        true
    }

    /// Adds a cone or cylinder without caps; negative radii (both) make it inside-only.
    pub fn add_cone(
        &mut self,
        base: Vec3,
        base_radius: f32,
        apex: Vec3,
        apex_radius: f32,
        material: MaterialId,
    ) {
        self.cones.base.push(base);
        self.cones.base_radius.push(base_radius.abs());
        self.cones.apex.push(apex);
        self.cones.apex_radius.push(apex_radius.abs());
        self.cones
            .inside_only
            .push(base_radius < 0.0 && apex_radius < 0.0);
        self.cones.material.push(material);
    }

    /// Number of bounded primitives (everything but planes).
    pub fn bounded_count(&self) -> usize {
        self.spheres.material.len()
            + self.triangles.len()
            + self.boxes.material.len()
            + self.cones.material.len()
    }

    /// Number of triangles with zero area.
    pub fn degenerate_triangles(&self) -> usize {
        (0..self.triangles.len())
            .filter(|&i| self.triangles.is_degenerate(i))
            .count()
    }

    /// The box around every bounded primitive (planes excluded); empty if there are none.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        let s = &self.spheres;
        for i in 0..s.radius.len() {
            let r = Vec3::splat(s.radius[i]);
            b = b.union(Aabb::new(s.center.get(i) - r, s.center.get(i) + r));
        }
        for i in 0..self.triangles.len() {
            for v in self.triangles.vertices(i) {
                b.grow(v);
            }
        }
        for i in 0..self.boxes.material.len() {
            b = b.union(Aabb::new(self.boxes.min.get(i), self.boxes.max.get(i)));
        }
        let c = &self.cones;
        for i in 0..c.material.len() {
            let r = Vec3::splat(c.base_radius[i].max(c.apex_radius[i]));
            for p in [c.base.get(i), c.apex.get(i)] {
                b = b.union(Aabb::new(p - r, p + r));
            }
        }
        b
    }
}
