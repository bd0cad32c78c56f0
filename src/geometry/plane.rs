//! Ray-plane intersection.

use glam::Vec3;

use super::ray::Ray;

/// The `t` in the open interval `(t_min, t_max)` at which `ray` meets the plane `normal . p = offset`;
/// a ray parallel to the plane misses, even one lying in it.
///
/// Substituting the ray into the plane equation: `t = (offset - n . o) / (n . d)` (E. Haines, "Essential Ray
/// Tracing Algorithms", in A. Glassner (ed.), *An Introduction to Ray Tracing*, 1989).
#[inline]
pub fn intersect(normal: Vec3, offset: f32, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
    let denom = normal.dot(ray.dir);
    // No test of the denominator is needed: a parallel ray gives t = ±inf, or NaN when it lies in the plane,
    // and the open window rejects both (t_max = inf included).
    let t = (offset - normal.dot(ray.origin)) / denom;
    (t > t_min && t < t_max).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kit::rays::TestRng;

    #[test]
    fn closed_form() {
        // z = 2, approached from below and above with |d| = 4.
        let below = Ray::new(Vec3::new(1.0, 1.0, -6.0), Vec3::new(0.0, 0.0, 4.0));
        assert_eq!(intersect(Vec3::Z, 2.0, &below, 0.0, f32::INFINITY), Some(2.0));
        let above = Ray::new(Vec3::new(1.0, 1.0, 10.0), Vec3::new(0.0, 0.0, -4.0));
        assert_eq!(intersect(Vec3::Z, 2.0, &above, 0.0, f32::INFINITY), Some(2.0));
        // Receding, and outside the (open) window.
        assert_eq!(
            intersect(
                Vec3::Z,
                2.0,
                &Ray::new(above.origin, -above.dir),
                0.0,
                f32::INFINITY
            ),
            None
        );
        assert_eq!(intersect(Vec3::Z, 2.0, &below, 0.0, 2.0), None);
        assert_eq!(intersect(Vec3::Z, 2.0, &below, 2.0, 3.0), None);
        // A tilted, unnormalised normal: x + y = 2 scaled by 3.
        let ray = Ray::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 5.0));
        let t = intersect(Vec3::new(3.0, 3.0, 0.0), 6.0, &ray, 0.0, f32::INFINITY).unwrap();
        assert_eq!(t, 2.0);
    }

    #[test]
    fn parallel_ray_misses() {
        let n = Vec3::new(0.0, 1.0, 1.0).normalize();
        for origin in [Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO] {
            for dir in [Vec3::X, Vec3::new(0.0, 1.0, -1.0), Vec3::new(2.0, -1.0, 1.0)] {
                let ray = Ray::new(origin, dir);
                assert_eq!(intersect(n, 0.0, &ray, 0.0, f32::INFINITY), None, "{ray:?}");
                assert_eq!(
                    intersect(n, 0.0, &ray, f32::NEG_INFINITY, f32::INFINITY),
                    None,
                    "{ray:?}"
                );
            }
        }
    }

    #[test]
    fn random_hits_lie_on_plane() {
        let mut rng = TestRng::new(13);
        for _ in 0..10_000 {
            let n = rng.direction();
            let offset = rng.range(-5.0, 5.0);
            let ray = Ray::new(rng.vec3(-10.0, 10.0), rng.direction() * rng.range(0.1, 10.0));
            let side = n.dot(ray.origin) - offset;
            match intersect(n, offset, &ray, 0.0, f32::INFINITY) {
                Some(t) => assert!((n.dot(ray.at(t)) - offset).abs() < 1e-4 * (1.0 + ray.at(t).length())),
                // A miss means the ray heads away from the plane (or runs along it).
                None => assert!(side * n.dot(ray.dir) >= 0.0),
            }
        }
    }
}
