//! Ray-sphere intersection.

use glam::Vec3;

use super::aabb::Aabb;
use super::ray::Ray;

/// The nearest `t` in the open interval `(t_min, t_max)` at which `ray` meets the sphere of `center` and
/// `radius > 0`.
///
/// Solves `|o + t d - c|^2 = r^2`, i.e. `a t^2 + b t + c = 0` with `a = d.d`, `b = 2 (o - c).d`,
/// `c = |o - c|^2 - r^2` (E. Haines, "Essential Ray Tracing Algorithms", in A. Glassner (ed.), *An Introduction
/// to Ray Tracing*, 1989), with the discriminant computed as in E. Haines, J. Günther, T. Akenine-Möller,
/// "Precision Improvements for Ray/Sphere Intersection", *Ray Tracing Gems*, ch. 7, 2019, and the roots
/// taken in the cancellation-free form `q = -(b + sign(b) sqrt(disc)) / 2`, `t = q / a`, `t = c / q`
/// (W. Press et al., *Numerical Recipes*, §5.6).
///
/// With `inside_only` (an NFF sphere with a negative radius) only the far root counts, the point where the
/// ray leaves the sphere (`d . n > 0`), so the sphere is seen from inside only.
#[inline]
pub fn intersect(
    center: Vec3,
    radius: f32,
    inside_only: bool,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
) -> Option<f32> {
    let oc = ray.origin - center;
    let a = ray.dir.length_squared();
    // Half of b: the factors of 2 and 4 cancel out of both roots.
    let b = oc.dot(ray.dir);
    let c = oc.length_squared() - radius * radius;
    // b^2 - a c = a (r^2 - |l|^2), where l is the vector from the centre to its foot on the ray line: the
    // difference b^2 - a c cancels catastrophically for a small sphere far from the ray's origin, this form does
    // not (Ray Tracing Gems, ch. 7).
    let l = oc - ray.dir * (b / a);
    let disc = a * (radius * radius - l.length_squared());
    // A NaN discriminant (zero direction) needs no test of its own: it makes both roots NaN, which no
    // window accepts.
    if disc < 0.0 {
        return None;
    }
    // Adding two numbers of the same sign never cancels; the other root then comes from the product of the
    // roots, c / a, instead of from a difference.
    let q = -(b + disc.sqrt().copysign(b));
    let (r0, r1) = (q / a, c / q);
    // q == 0 only for a double root at 0, where c / q is 0/0: f32::min/max drop the NaN.
    let (near, far) = (r0.min(r1), r0.max(r1));
    if !inside_only && near > t_min && near < t_max {
        Some(near)
    } else if far > t_min && far < t_max {
        Some(far)
    } else {
        None
    }
}

/// The outward unit normal `(p - c) / r` at a point `p` on the sphere (Haines 1989).
#[inline]
pub fn normal(center: Vec3, radius: f32, p: Vec3) -> Vec3 {
    // Division rather than normalise: the hit point lies on the sphere to within rounding, so this is unit
    // length to that accuracy without a square root.
    (p - center) / radius
}

/// The bounding box `c ± r` of the sphere of `center` and `radius >= 0`.
#[inline]
pub fn bounds(center: Vec3, radius: f32) -> Aabb {
    Aabb::new(center - Vec3::splat(radius), center + Vec3::splat(radius))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kit::rays::TestRng;

    const C: Vec3 = Vec3::new(1.0, 2.0, 3.0);

    #[test]
    fn axis_ray_hits_at_known_t() {
        // From x = -4 towards +x with |d| = 2: the surface x = -1 is 3 units, t = 1.5, away.
        let ray = Ray::new(C + Vec3::new(-5.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0));
        let t = intersect(C, 2.0, false, &ray, 0.0, f32::INFINITY).unwrap();
        assert!((t - 1.5).abs() < 1e-6, "{t}");
        assert!((ray.at(t) - (C - Vec3::new(2.0, 0.0, 0.0))).length() < 1e-6);
    }

    #[test]
    fn from_inside_returns_far_root() {
        let ray = Ray::new(C, Vec3::new(0.0, -1.0, 0.0));
        let t = intersect(C, 2.0, false, &ray, 0.0, f32::INFINITY).unwrap();
        assert!((t - 2.0).abs() < 1e-6, "{t}");
    }

    #[test]
    fn inside_only_rejects_outside_hit_and_accepts_inside() {
        let outside = Ray::new(C + Vec3::new(0.0, 0.0, -10.0), Vec3::Z);
        // The entering hit at t = 8 is invisible; the leaving one at t = 12 is the inside of the far wall.
        assert_eq!(intersect(C, 2.0, false, &outside, 0.0, f32::INFINITY), Some(8.0));
        assert_eq!(intersect(C, 2.0, true, &outside, 0.0, f32::INFINITY), Some(12.0));
        assert_eq!(intersect(C, 2.0, true, &outside, 0.0, 10.0), None);
        let inside = Ray::new(C + Vec3::new(0.0, 0.0, 1.0), Vec3::Z);
        assert_eq!(intersect(C, 2.0, true, &inside, 0.0, f32::INFINITY), Some(1.0));
        let n = normal(C, 2.0, inside.at(1.0));
        assert!(inside.dir.dot(n) > 0.0);
    }

    #[test]
    fn tangent_ray_touches_once() {
        let ray = Ray::new(C + Vec3::new(-5.0, 2.0, 0.0), Vec3::X);
        let t = intersect(C, 2.0, false, &ray, 0.0, f32::INFINITY).unwrap();
        assert!((t - 5.0).abs() < 1e-3, "{t}");
        let past = Ray::new(C + Vec3::new(-5.0, 2.001, 0.0), Vec3::X);
        assert_eq!(intersect(C, 2.0, false, &past, 0.0, f32::INFINITY), None);
    }

    #[test]
    fn window_limits_roots() {
        let ray = Ray::new(C + Vec3::new(0.0, 0.0, -10.0), Vec3::Z);
        let hit = |lo, hi| intersect(C, 2.0, false, &ray, lo, hi);
        assert_eq!(hit(0.0, 20.0), Some(8.0));
        // The window is open at both ends.
        assert_eq!(hit(0.0, 8.0), None);
        assert_eq!(hit(8.0, 20.0), Some(12.0));
        assert_eq!(hit(0.0, 12.0), Some(8.0));
        assert_eq!(hit(12.0, 20.0), None);
        assert_eq!(hit(-20.0, -1.0), None);
        // Behind the origin.
        let away = Ray::new(ray.origin, -Vec3::Z);
        assert_eq!(intersect(C, 2.0, false, &away, 0.0, f32::INFINITY), None);
    }

    #[test]
    fn zero_direction_misses() {
        let ray = Ray::new(C, Vec3::ZERO);
        assert_eq!(intersect(C, 2.0, false, &ray, 0.0, f32::INFINITY), None);
    }

    #[test]
    fn normal_is_unit_and_outward() {
        let mut rng = TestRng::new(1);
        for _ in 0..1000 {
            let dir = rng.direction();
            let p = C + dir * 2.5;
            let n = normal(C, 2.5, p);
            assert!((n.length() - 1.0).abs() < 1e-5);
            assert!((n - dir).length() < 1e-5);
        }
    }

    #[test]
    fn bounds_are_tight() {
        let b = bounds(C, 2.0);
        assert_eq!(b.min, C - 2.0);
        assert_eq!(b.max, C + 2.0);
    }

    /// 10,000 random rays against the implicit equation and the roots found in f64; misses against the
    /// ray line's distance to the centre.
    #[test]
    fn random_rays_match_implicit_equation() {
        let mut rng = TestRng::new(7);
        let (mut hits, mut far_hits) = (0, 0);
        for i in 0..10_000 {
            let center = rng.vec3(-10.0, 10.0);
            let radius = rng.range(0.1, 5.0);
            let origin = if i % 10 == 0 {
                center + rng.direction() * radius * rng.unit_f32()
            } else {
                rng.vec3(-20.0, 20.0)
            };
            // Aim near the sphere so that about half the rays hit; scale d to exercise non-unit directions.
            let target = center + rng.direction() * radius * rng.range(0.0, 1.5);
            let dir = (target - origin) * rng.range(0.1, 10.0);
            let ray = Ray::new(origin, dir);
            let inside_only = i % 4 == 0;
            let t_min = 1e-3;
            let (oc, d, r) = ((origin - center).as_dvec3(), dir.as_dvec3(), radius as f64);
            // The roots in f64 (no cancellation worth the name at this precision), and the distance from the
            // centre to the ray line.
            let foot = -oc.dot(d) / d.length_squared();
            let dist = (oc + d * foot).length();
            let half = (r * r - dist * dist).max(0.0).sqrt() / d.length();
            let (near, far) = (foot - half, foot + half);
            let tol = 1e-4;
            // Tangent rays, and roots within rounding of t_min, may go either way.
            let tangent = (dist - r).abs() < tol * r;
            let near_t_min = |root: f64| (root - t_min as f64).abs() < tol * (1.0 + root.abs());
            let hit = intersect(center, radius, inside_only, &ray, t_min, f32::INFINITY);
            if tangent || near_t_min(near) || near_t_min(far) {
                continue;
            }
            let want = if dist > r {
                None
            } else if !inside_only && near > t_min as f64 {
                Some(near)
            } else if far > t_min as f64 {
                Some(far)
            } else {
                None
            };
            match (hit, want) {
                (Some(t), Some(want)) => {
                    hits += 1;
                    far_hits += usize::from(want == far);
                    let p = oc + d * t as f64;
                    let err = (p.length() - r).abs() / r;
                    assert!(err < tol, "ray {i}: |p - c| off by {err}");
                    assert!(
                        (t as f64 - want).abs() < tol * want.max(1.0),
                        "ray {i}: t = {t}, want {want}"
                    );
                }
                (None, None) => {}
                (hit, want) => panic!("ray {i}: got {hit:?}, want {want:?} (line at {dist} from the centre)"),
            }
        }
        assert!(hits > 3000 && far_hits > 1000, "{hits} hits, {far_hits} far");
    }
}
