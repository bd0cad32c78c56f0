//! Ray intersection with the lateral surface of an NFF cone or cylinder (no caps).
//!
//! The solid runs from a base disc (centre `B`, radius `rb`) to an apex disc (centre `A`, radius `ra`), both
//! radii `>= 0`: equal radii make a cylinder, a zero radius a true cone tip. With unit axis `w = (A - B) / h`,
//! `h = |A - B|`, the surface is the set of points at height `s = (p - B) . w` in `[0, h]` whose distance
//! to the axis is `r(s) = rb + (ra - rb) s / h`.

use glam::Vec3;

use super::aabb::Aabb;
use super::ray::Ray;

/// The nearest `t` in the open interval `(t_min, t_max)` at which `ray` meets the side of the cone.
///
/// Substituting the ray into `|p - B - s w|^2 = r(s)^2` gives a quadratic in `t` (the quadric form of
/// P. Hanrahan, "Ray Tracing Algebraic Surfaces", *SIGGRAPH* 1983, written in the axis frame as in E. Haines,
/// "Essential Ray Tracing Algorithms", in A. Glassner (ed.), *An Introduction to Ray Tracing*, 1989); its
/// roots are taken in the cancellation-free form of W. Press et al., *Numerical Recipes*, §5.6, and only
/// those with `s` in `[0, h]` are kept. With `inside_only` (NFF: both radii negative) only hits where the
/// ray passes from inside to outside (`d . n > 0`) count.
#[inline]
#[allow(clippy::too_many_arguments)] // The NFF record's own fields; a struct would only rename them.
pub fn intersect(
    base: Vec3,
    base_radius: f32,
    apex: Vec3,
    apex_radius: f32,
    inside_only: bool,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
) -> Option<f32> {
    let axis = apex - base;
    let h = axis.length();
    // A zero-height cone makes w NaN and every test below fail: it is never hit.
    let w = axis / h;
    // dr/ds.
    let slope = (apex_radius - base_radius) / h;
    let co = ray.origin - base;
    // Height and radius along the ray are linear in t: s(t) = s0 + t sd, r(t) = r0 + t rd.
    let (s0, sd) = (co.dot(w), ray.dir.dot(w));
    let (r0, rd) = (base_radius + slope * s0, slope * sd);
    // Offset from the axis, also linear: p0 + t pd.
    let p0 = co - w * s0;
    let pd = ray.dir - w * sd;
    // F(t) = |p0 + t pd|^2 - (r0 + t rd)^2 = a t^2 + 2 b t + c.
    let a = pd.length_squared() - rd * rd;
    let b = p0.dot(pd) - r0 * rd;
    let c = p0.length_squared() - r0 * r0;
    // b^2 - a c, expanded and regrouped by Lagrange's identity |p0|^2 |pd|^2 - (p0 . pd)^2 = |p0 × pd|^2,
    // as |r0 pd - rd p0|^2 - |p0 × pd|^2. The textbook b^2 - a c subtracts two large, nearly equal products
    // and loses all precision for a ray aimed nearly at the axis from afar (a zero-radius "cone" then gets
    // hits); here each term is the square of a vector computed without that cancellation, so the error
    // scales with the terms themselves. The cone analogue of E. Haines et al., "Precision Improvements for
    // Ray/Sphere Intersection", *Ray Tracing Gems*, ch. 7, 2019.
    let disc = (pd * r0 - p0 * rd).length_squared() - p0.cross(pd).length_squared();
    // NaN (a zero direction or height) falls through to NaN roots, which `accept` rejects.
    if disc < 0.0 {
        return None;
    }
    // With a == 0 (a ray along a cylinder, or parallel to a cone's side line) q / a is infinite and the
    // window drops it, while c / q is still the one root of the linear equation: no special case needed.
    let q = -(b + disc.sqrt().copysign(b));
    let (t0, t1) = (q / a, c / q);
    let accept = |t: f32| {
        let s = s0 + t * sd;
        // F grows with |offset| - r, so F'(t) = 2 (a t + b) > 0 is d . grad F > 0: the ray leaving.
        // (The squared equation also holds on the mirror cone beyond the tip, where r(s) < 0; with radii
        // >= 0 that lies outside s in [0, h].)
        t > t_min && t < t_max && (0.0..=h).contains(&s) && (!inside_only || a * t + b > 0.0)
    };
    // f32::min/max drop the NaN of c / q when q == 0 (b == 0 and a double root at c == 0).
    let (near, far) = (t0.min(t1), t0.max(t1));
    if accept(near) {
        Some(near)
    } else if accept(far) {
        Some(far)
    } else {
        None
    }
}

/// The outward unit normal at a point `p` on the side of the cone: the radial direction `q` tilted by the
/// slope `k = (rb - ra) / h` towards the narrow end, `normalise(q + k w)` (the gradient of the implicit
/// surface, Hanrahan 1983). At the tip itself, where `q` is undefined, it is `±w`.
#[inline]
pub fn normal(base: Vec3, base_radius: f32, apex: Vec3, apex_radius: f32, p: Vec3) -> Vec3 {
    let axis = apex - base;
    let h = axis.length();
    let w = axis / h;
    let v = p - base;
    let radial = (v - w * v.dot(w)).normalize_or_zero();
    let k = (base_radius - apex_radius) / h;
    (radial + w * k).normalize_or_zero()
}

/// The tight bounding box of the cone: that of its two end discs, whose convex hull it lies in. A disc of
/// radius `r` and unit normal `w` spans `±r sqrt(1 - w_i^2)` along axis `i` (I. Quilez, "Disk and Cylinder
/// Bounding Box", 2016, iquilezles.org).
#[inline]
pub fn bounds(base: Vec3, base_radius: f32, apex: Vec3, apex_radius: f32) -> Aabb {
    let w = (apex - base).normalize();
    // max(0) guards against 1 - w_i^2 rounding below zero for an axis-aligned w.
    let span = (Vec3::ONE - w * w).max(Vec3::ZERO).sqrt();
    let (eb, ea) = (span * base_radius, span * apex_radius);
    Aabb::new((base - eb).min(apex - ea), (base + eb).max(apex + ea))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kit::rays::TestRng;

    const INF: f32 = f32::INFINITY;

    #[test]
    fn cylinder_perpendicular_ray() {
        // Axis along z from z = 1 to z = 5, radius 2; a ray along x at height 3 and offset y = 0.5.
        let (b, a) = (Vec3::new(1.0, 1.0, 1.0), Vec3::new(1.0, 1.0, 5.0));
        let ray = Ray::new(Vec3::new(-9.0, 1.5, 3.0), Vec3::new(2.0, 0.0, 0.0));
        let t = intersect(b, 2.0, a, 2.0, false, &ray, 0.0, INF).unwrap();
        let x = 1.0 - (4.0f32 - 0.25).sqrt();
        assert!((ray.at(t).x - x).abs() < 1e-5, "{}", ray.at(t));
        let n = normal(b, 2.0, a, 2.0, ray.at(t));
        assert!((n - Vec3::new(x - 1.0, 0.5, 0.0) / 2.0).length() < 1e-5, "{n}");
        // At distance exactly r from the axis: tangent.
        let edge = Ray::new(Vec3::new(-9.0, 3.0, 3.0), Vec3::X);
        let t = intersect(b, 2.0, a, 2.0, false, &edge, 0.0, INF).unwrap();
        assert!((t - 10.0).abs() < 1e-2, "{t}");
    }

    #[test]
    fn cone_normal_matches_analytic() {
        // Tip at the origin (apex radius 0), base radius 1 at z = -2: slope k = 1/2, the side makes
        // atan(1/2) with the axis, so at (1, 0, -2) the outward normal is (2, 0, 1)/sqrt(5).
        let (b, a) = (Vec3::new(0.0, 0.0, -2.0), Vec3::ZERO);
        let p = Vec3::new(1.0, 0.0, -2.0);
        let want = Vec3::new(2.0, 0.0, 1.0) / 5.0f32.sqrt();
        assert!((normal(b, 1.0, a, 0.0, p) - want).length() < 1e-6);
        // The same halfway up, on the y side, and for the flipped orientation.
        let p = Vec3::new(0.0, -0.5, -1.0);
        let want = Vec3::new(0.0, -2.0, 1.0) / 5.0f32.sqrt();
        assert!((normal(b, 1.0, a, 0.0, p) - want).length() < 1e-6);
        assert!((normal(a, 0.0, b, 1.0, p) - want).length() < 1e-6);
        // And a ray down the x axis at z = -1 hits at x = 0.5 with that normal.
        let ray = Ray::new(Vec3::new(5.0, 0.0, -1.0), Vec3::NEG_X);
        let t = intersect(b, 1.0, a, 0.0, false, &ray, 0.0, INF).unwrap();
        assert!((t - 4.5).abs() < 1e-5, "{t}");
        let want = Vec3::new(2.0, 0.0, 1.0) / 5.0f32.sqrt();
        assert!((normal(b, 1.0, a, 0.0, ray.at(t)) - want).length() < 1e-5);
    }

    #[test]
    fn ray_along_cylinder_axis_misses_side() {
        let (b, a) = (Vec3::ZERO, Vec3::new(0.0, 3.0, 0.0));
        for origin in [
            Vec3::new(0.0, -5.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.5, -5.0, 0.2),
        ] {
            let ray = Ray::new(origin, Vec3::new(0.0, 2.0, 0.0));
            assert_eq!(intersect(b, 1.0, a, 1.0, false, &ray, 0.0, INF), None, "{origin}");
            assert_eq!(intersect(b, 1.0, a, 1.0, true, &ray, 0.0, INF), None, "{origin}");
        }
    }

    #[test]
    fn ray_parallel_to_cone_side_hits_once() {
        // The quadratic term vanishes; the linear root must still be found.
        let (b, a) = (Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0));
        // Parallel to the side line from the tip (0, 0, 2) to (1, 0, 0); it meets the opposite side line at
        // t = 0.75, (-0.25, 0, 1.5), where r = 0.25, and the parallel one never.
        let ray = Ray::new(Vec3::new(-1.0, 0.0, 3.0), Vec3::new(1.0, 0.0, -2.0));
        let t = intersect(b, 1.0, a, 0.0, false, &ray, 0.0, INF).unwrap();
        assert!((t - 0.75).abs() < 1e-6, "{t}");
    }

    #[test]
    fn hits_outside_height_rejected() {
        let (b, a) = (Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0));
        // The infinite cylinder would be hit at z = 3 and z = -1; the finite one is not.
        for z in [3.0, -1.0, 2.001, -0.001] {
            let ray = Ray::new(Vec3::new(-5.0, 0.0, z), Vec3::X);
            assert_eq!(intersect(b, 1.0, a, 1.0, false, &ray, 0.0, INF), None, "z = {z}");
        }
        // A cone's mirror nappe beyond its tip: tip at z = 2, so at z = 3 the squared equation has
        // roots at |x| = 0.5 which must not count.
        let ray = Ray::new(Vec3::new(-5.0, 0.0, 3.0), Vec3::X);
        assert_eq!(intersect(b, 1.0, a, 0.0, false, &ray, 0.0, INF), None);
        // A ray entering through the missing cap hits the inside of the wall.
        let ray = Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::new(1.0, 0.0, -2.0));
        let t = intersect(b, 1.0, a, 1.0, false, &ray, 0.0, INF).unwrap();
        assert!((t - 1.0).abs() < 1e-6 && (ray.at(t).z - 1.0).abs() < 1e-6, "{t}");
    }

    #[test]
    fn inside_only_keeps_leaving_hits() {
        let (b, a) = (Vec3::ZERO, Vec3::new(0.0, 0.0, 4.0));
        let ray = Ray::new(Vec3::new(-5.0, 0.0, 2.0), Vec3::X);
        // Cone of radius 2 at the base, 0 at the tip: r(2) = 1, so walls at x = -1 and x = 1.
        let enter = intersect(b, 2.0, a, 0.0, false, &ray, 0.0, INF).unwrap();
        let leave = intersect(b, 2.0, a, 0.0, true, &ray, 0.0, INF).unwrap();
        assert!(
            (enter - 4.0).abs() < 1e-5 && (leave - 6.0).abs() < 1e-5,
            "{enter} {leave}"
        );
        assert!(ray.dir.dot(normal(b, 2.0, a, 0.0, ray.at(leave))) > 0.0);
        assert_eq!(intersect(b, 2.0, a, 0.0, true, &ray, 0.0, 5.0), None);
        // From inside, both kinds see the far wall.
        let inside = Ray::new(Vec3::new(0.0, 0.0, 2.0), Vec3::X);
        assert!((intersect(b, 2.0, a, 0.0, true, &inside, 0.0, INF).unwrap() - 1.0).abs() < 1e-5);
        assert!((intersect(b, 2.0, a, 0.0, false, &inside, 0.0, INF).unwrap() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn bounds_of_tilted_cylinder() {
        // Axis along (1, 1, 0)/sqrt(2): each disc spans r/sqrt(2) in x and y and r in z.
        let (b, a) = (Vec3::ZERO, Vec3::new(2.0, 2.0, 0.0));
        let bb = bounds(b, 1.0, a, 0.5);
        let s = 0.5f32.sqrt();
        assert!(
            (bb.min - Vec3::new(-s, -s, -1.0)).abs().max_element() < 1e-6,
            "{bb:?}"
        );
        assert!(
            (bb.max - Vec3::new(2.0 + 0.5 * s, 2.0 + 0.5 * s, 1.0))
                .abs()
                .max_element()
                < 1e-6,
            "{bb:?}"
        );
        let axis_aligned = bounds(Vec3::ZERO, 1.0, Vec3::Z, 1.0);
        assert_eq!(
            axis_aligned,
            Aabb::new(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 1.0))
        );
    }

    /// Signed distance to the surface's radius at height s: |offset from the axis| - r(s).
    fn excess(base: Vec3, rb: f32, apex: Vec3, ra: f32, p: Vec3) -> (f64, f64, f64) {
        let (b, p) = (base.as_dvec3(), p.as_dvec3());
        let axis = apex.as_dvec3() - b;
        let h = axis.length();
        let w = axis / h;
        let s = (p - b).dot(w);
        let r = rb as f64 + (ra as f64 - rb as f64) * s / h;
        ((p - b - w * s).length() - r, s, h)
    }

    /// Random rays: hits satisfy the implicit equation and lie in the bounds; a march along the ray finds no
    /// crossing of the surface before the returned hit (nor any, for a miss).
    #[test]
    fn random_rays_match_implicit_surface() {
        let mut rng = TestRng::new(17);
        let (mut hits, mut leaving) = (0, 0);
        for i in 0..10_000 {
            let base = rng.vec3(-5.0, 5.0);
            let apex = base + rng.direction() * rng.range(0.5, 5.0);
            let rb = if i % 7 == 0 { 0.0 } else { rng.range(0.0, 3.0) };
            let ra = match i % 5 {
                0 => 0.0,
                1 => rb,
                _ => rng.range(0.0, 3.0),
            };
            let inside_only = i % 3 == 0;
            let origin = rng.vec3(-10.0, 10.0);
            let target = base + (apex - base) * rng.range(-0.2, 1.2) + rng.direction() * rng.range(0.0, 3.0);
            let dir = (target - origin) * rng.range(0.1, 10.0);
            let ray = Ray::new(origin, dir);
            let scale = 1e-4 * (1.0 + origin.length() as f64 + base.length() as f64 + apex.length() as f64);
            let got = intersect(base, rb, apex, ra, inside_only, &ray, 0.0, INF);
            if let Some(t) = got {
                hits += 1;
                let p = ray.at(t);
                let (e, s, h) = excess(base, rb, apex, ra, p);
                assert!(e.abs() < scale, "ray {i}: off the surface by {e}");
                assert!(
                    s > -scale && s < h + scale,
                    "ray {i}: height {s} outside [0, {h}]"
                );
                let bb = bounds(base, rb, apex, ra);
                let tol = scale as f32;
                assert!(
                    p.cmpge(bb.min - tol).all() && p.cmple(bb.max + tol).all(),
                    "ray {i}: {p} not in {bb:?}"
                );
                if inside_only {
                    leaving += 1;
                    let n = normal(base, rb, apex, ra, p);
                    assert!(dir.dot(n) > -1e-3 * dir.length(), "ray {i}: not leaving");
                }
            }
            // March up to the hit (or far past the cone) looking for a sign change of the excess between two
            // samples both within the height range: a certain crossing of the surface.
            let reach = (origin - base).length().max((origin - apex).length()) + 3.0;
            let end = got.unwrap_or(2.0 * reach / dir.length());
            let steps = 400;
            let mut prev = excess(base, rb, apex, ra, origin);
            for k in 1..=steps {
                let tk = end * k as f32 / steps as f32;
                let cur = excess(base, rb, apex, ra, ray.at(tk));
                let in_height = |(_, s, h): (f64, f64, f64)| s > scale && s < h - scale;
                let crossed =
                    prev.0 < -scale && cur.0 > scale || (!inside_only && prev.0 > scale && cur.0 < -scale);
                let before = got.is_none_or(|t| tk < t * (1.0 - 1e-3));
                assert!(
                    !(crossed && in_height(prev) && in_height(cur) && before),
                    "ray {i}: crossing at {tk} missed, got {got:?}"
                );
                prev = cur;
            }
        }
        assert!(hits > 2000 && leaving > 500, "{hits} hits, {leaving} leaving");
    }
}
