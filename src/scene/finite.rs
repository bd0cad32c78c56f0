//! Geometry within the range of `f32`: every number a file gives is finite, but a transform (`include
//! ... scale 3e38 translate 3.4e38 ...`) or a size (a sphere of radius 3e38 at x = 3.4e38) can still
//! reach past the largest float, where bounds, edges and normals become infinite and every ray test
//! on them NaN. Each primitive is checked as it is added, so the error names the statement at fault.

use glam::Vec3;

use super::store::{Scene, Vec3s};

/// The error for a primitive of kind `what` (as [`Scene::overflow_since`] names it) out of range.
pub(super) fn overflow_message(what: &str) -> String {
    format!(
        "the {what} reaches past the largest finite coordinate, {:e}: expected a size, position, \
         scale or translation that keeps it within range",
        f32::MAX
    )
}

/// How many primitives of each kind a scene held, to check those added since (the default: none).
#[derive(Clone, Copy, Debug, Default)]
pub struct Counts([usize; 6]);

impl Scene {
    /// The counts of spheres, triangles, boxes, planes, cones and area lights.
    pub fn counts(&self) -> Counts {
        Counts([
            self.spheres.radius.len(),
            self.triangles.v0.len(),
            self.boxes.min.len(),
            self.planes.offset.len(),
            self.cones.base.len(),
            self.area_lights.len(),
        ])
    }

    /// The kind of the first primitive added since `before` whose extent, or a vector stored for it
    /// (a triangle's edges and normal, a plane's normal), is not finite.
    pub fn overflow_since(&self, before: Counts) -> Option<&'static str> {
        let [spheres, triangles, boxes, planes, cones, lights] = before.0;
        let finite = |v: Vec3| v.is_finite();
        let reach = |c: Vec3, r: f32| finite(c.abs() + Vec3::splat(r.abs()));
        let s = &self.spheres;
        if (spheres..s.radius.len()).any(|i| !reach(s.center.get(i), s.radius[i])) {
            return Some("sphere");
        }
        let t = &self.triangles;
        let triangle = |i: usize| {
            let (a, e1, e2) = (t.v0.get(i), t.e1.get(i), t.e2.get(i));
            [a, e1, e2, a + e1, a + e2, e1.cross(e2)].into_iter().all(finite)
        };
        if !(triangles..t.v0.len()).all(triangle) {
            return Some("triangle");
        }
        let all = |v: &Vec3s, from: usize| (from..v.len()).all(|i| finite(v.get(i)));
        if !all(&self.boxes.min, boxes) || !all(&self.boxes.max, boxes) {
            return Some("box");
        }
        let p = &self.planes;
        if !all(&p.normal, planes) || !p.offset[planes..].iter().all(|o| o.is_finite()) {
            return Some("plane");
        }
        let c = &self.cones;
        let cone =
            |i: usize| reach(c.base.get(i), c.base_radius[i]) && reach(c.apex.get(i), c.apex_radius[i]);
        if !(cones..c.base.len()).all(cone) {
            return Some("cone");
        }
        let light = |q: &super::store::QuadLight| {
            [q.corner, q.edge_u, q.edge_v, q.corner + q.edge_u + q.edge_v]
                .into_iter()
                .all(finite)
        };
        if !self.area_lights[lights..].iter().all(light) {
            return Some("area light");
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;

    #[test]
    fn what_reaches_past_the_largest_float_is_named() {
        let mut scene = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        let m = scene.add_material(Default::default());
        let before = scene.counts();
        scene.add_sphere(Vec3::new(3e38, 0.0, 0.0), 1e37, m);
        scene.add_triangle(Vec3::X * -1e38, Vec3::X * 1e38, Vec3::Y, m);
        assert_eq!(scene.overflow_since(before), None, "within range");
        let before = scene.counts();
        scene.add_sphere(Vec3::new(3.4e38, 0.0, 0.0), 3.4e38, m);
        assert_eq!(scene.overflow_since(before), Some("sphere"));
        let before = scene.counts();
        // Finite corners, an edge of 6e38.
        scene.add_triangle(Vec3::splat(-3e38), Vec3::splat(3e38), Vec3::X, m);
        assert_eq!(scene.overflow_since(before), Some("triangle"));
        let before = scene.counts();
        // Finite edges of 2e19, a normal of 4e38.
        scene.add_triangle(Vec3::ZERO, Vec3::X * 2e19, Vec3::Y * 2e19, m);
        assert_eq!(scene.overflow_since(before), Some("triangle"));
        let before = scene.counts();
        scene.add_cone(Vec3::ZERO, 1.0, Vec3::new(0.0, -3e38, 0.0), 3e38, m);
        assert_eq!(scene.overflow_since(before), Some("cone"));
        // Only what was added since is looked at.
        assert_eq!(scene.overflow_since(scene.counts()), None);
    }
}
