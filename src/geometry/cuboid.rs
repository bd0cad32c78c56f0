//! Ray intersection with an axis-aligned box primitive (`box` is a Rust keyword).

use glam::Vec3;

use super::ray::Ray;

/// The parameter interval `(t_enter, t_exit)` over which the ray `origin + t / inv_dir` lies in the box
/// `[min, max]`, clipped to `[t_min, t_max]`; `None` if that is empty.
///
/// The slab method of T. Kay, J. Kajiya, "Ray Tracing Complex Scenes", *SIGGRAPH* 1986, in the branchless
/// form of T. Barnes, "Fast, Branchless Ray/Bounding Box Intersections, Part 3: Boundaries", 2022. A zero
/// direction component gives `inv_dir = ±inf`, so that slab spans all or nothing of the line; an origin lying
/// exactly on that slab's plane gives `0 * inf = NaN`, which `f32::min`/`max` drop (they return the other
/// operand), leaving the interval unchanged: a ray grazing a face counts as touching the closed box.
#[inline]
pub fn slab(min: Vec3, max: Vec3, origin: Vec3, inv_dir: Vec3, t_min: f32, t_max: f32) -> Option<(f32, f32)> {
    let t1 = (min - origin) * inv_dir;
    let t2 = (max - origin) * inv_dir;
    let (mut enter, mut exit) = (t_min, t_max);
    for i in 0..3 {
        // Each bound is compared with the running interval before the two slab ends are ordered, so a NaN
        // end is replaced by that bound rather than carried into it. Glam's `Vec3::min` would keep a NaN
        // in its second operand, hence the scalar f32 calls.
        enter = f32::min(f32::max(t1[i], enter), f32::max(t2[i], enter));
        exit = f32::max(f32::min(t1[i], exit), f32::min(t2[i], exit));
    }
    (enter <= exit).then_some((enter, exit))
}

/// The nearest `t` in the open interval `(t_min, t_max)` at which `ray` meets the surface of the box
/// `[min, max]`: the entering `t`, or the exiting one when the ray starts inside (entering `t <= t_min`).
///
/// Slab test of Kay & Kajiya 1986 (see [`slab`]).
#[inline]
pub fn intersect(min: Vec3, max: Vec3, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
    let (enter, exit) = slab(min, max, ray.origin, ray.dir.recip(), t_min, t_max)?;
    // `slab` clamps to the window, so an interval starting above `t_min` starts at the true entry, and
    // one ending below `t_max` ends at the true exit.
    if enter > t_min {
        (enter < t_max).then_some(enter)
    } else {
        (exit > t_min && exit < t_max).then_some(exit)
    }
}

/// The outward unit normal of the face of the box `[min, max]` that `p` lies on: the face whose plane is
/// nearest `p` (Haines, "Essential Ray Tracing Algorithms", in Glassner (ed.), *An Introduction to Ray
/// Tracing*, 1989, takes the normal of the slab that gave the hit; this recovers it from the point alone).
///
/// The distances are absolute, not relative to the box's extent: the error in a computed hit point is
/// proportional to the magnitude of its coordinates, not to the box's size, so scaling the distance to a
/// thin side's plane by the large extent across it would pick that side for points on the broad faces.
#[inline]
pub fn normal(min: Vec3, max: Vec3, p: Vec3) -> Vec3 {
    let lo = (p - min).abs();
    let hi = (max - p).abs();
    let mut best = lo.x;
    let mut n = Vec3::NEG_X;
    for (d, face) in [
        (hi.x, Vec3::X),
        (lo.y, Vec3::NEG_Y),
        (hi.y, Vec3::Y),
        (lo.z, Vec3::NEG_Z),
        (hi.z, Vec3::Z),
    ] {
        if d < best {
            best = d;
            n = face;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kit::rays::TestRng;
    use glam::DVec3;

    const MIN: Vec3 = Vec3::new(-1.0, -2.0, -3.0);
    const MAX: Vec3 = Vec3::new(1.0, 2.0, 3.0);

    fn hit(origin: Vec3, dir: Vec3) -> Option<f32> {
        intersect(MIN, MAX, &Ray::new(origin, dir), 0.0, f32::INFINITY)
    }

    #[test]
    fn entering_face_normals() {
        for (axis, n) in [Vec3::X, Vec3::Y, Vec3::Z, Vec3::NEG_X, Vec3::NEG_Y, Vec3::NEG_Z]
            .into_iter()
            .enumerate()
        {
            // Start 10 units out along n, off-centre, and head back in with |d| = 2.
            let origin = n * 10.0 + Vec3::new(0.1, 0.2, 0.3) * (Vec3::ONE - n.abs());
            let ray = Ray::new(origin, -n * 2.0);
            let t = hit(ray.origin, ray.dir).unwrap_or_else(|| panic!("{n} missed"));
            let face = if axis < 3 { MAX } else { -MIN }.dot(n.abs());
            assert_eq!(t, (10.0 - face) / 2.0, "{n}");
            assert_eq!(normal(MIN, MAX, ray.at(t)), n);
        }
    }

    #[test]
    fn from_inside_returns_exit() {
        let ray = Ray::new(Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.0, -4.0, 0.0));
        let t = hit(ray.origin, ray.dir).unwrap();
        assert_eq!(t, 0.5);
        assert_eq!(normal(MIN, MAX, ray.at(t)), Vec3::NEG_Y);
        // With a window starting past the entry point, from outside: the exit is found too.
        let outside = Ray::new(Vec3::new(0.5, 0.0, -13.0), Vec3::Z);
        assert_eq!(intersect(MIN, MAX, &outside, 0.0, f32::INFINITY), Some(10.0));
        assert_eq!(intersect(MIN, MAX, &outside, 11.0, f32::INFINITY), Some(16.0));
        assert_eq!(intersect(MIN, MAX, &outside, 0.0, 10.0), None);
        assert_eq!(intersect(MIN, MAX, &outside, 16.0, f32::INFINITY), None);
        assert_eq!(
            slab(MIN, MAX, outside.origin, outside.dir.recip(), 11.0, 14.0),
            Some((11.0, 14.0))
        );
    }

    /// A ray parallel to a face whose origin lies exactly on that face's plane: `0 * inf` is NaN there.
    #[test]
    fn origin_on_slab_plane_parallel_to_it() {
        // In the plane x = max.x, running along y towards the box; both signs of zero.
        for dx in [0.0, -0.0] {
            let ray = Ray::new(Vec3::new(1.0, -10.0, 0.0), Vec3::new(dx, 1.0, 0.0));
            assert!(ray.dir.recip().x.is_infinite());
            assert_eq!(hit(ray.origin, ray.dir), Some(8.0), "dx = {dx}");
            // Same on the min side, and on a slab in z.
            assert_eq!(hit(Vec3::new(-1.0, -10.0, 0.0), ray.dir), Some(8.0));
            assert_eq!(
                hit(Vec3::new(0.0, -10.0, 3.0), Vec3::new(0.0, 1.0, dx)),
                Some(8.0)
            );
            // Both zero components on slab planes: the ray runs along an edge.
            assert_eq!(
                hit(Vec3::new(1.0, -10.0, -3.0), Vec3::new(dx, 1.0, dx)),
                Some(8.0)
            );
            // Just outside the plane the same ray misses, and just inside it hits.
            assert_eq!(hit(Vec3::new(1.0001, -10.0, 0.0), ray.dir), None);
            assert_eq!(hit(Vec3::new(-1.0001, -10.0, 0.0), ray.dir), None);
            assert_eq!(hit(Vec3::new(0.9999, -10.0, 0.0), ray.dir), Some(8.0));
            // The NaN must not turn a miss into a hit: on the x plane but beside the box in z.
            assert_eq!(hit(Vec3::new(1.0, -10.0, 3.5), ray.dir), None);
            // Nor the other way round when pointing away from the box.
            assert_eq!(hit(Vec3::new(1.0, -10.0, 0.0), -ray.dir), None);
        }
    }

    #[test]
    fn normal_picks_nearest_face_of_thin_box() {
        let (min, max) = (Vec3::new(-100.0, -100.0, 0.0), Vec3::new(100.0, 100.0, 1e-3));
        assert_eq!(normal(min, max, Vec3::new(99.0, 0.0, 1e-3)), Vec3::Z);
        assert_eq!(normal(min, max, Vec3::new(-50.0, 99.9, 0.0)), Vec3::NEG_Z);
        assert_eq!(normal(min, max, Vec3::new(100.0, 3.0, 5e-4)), Vec3::X);
        assert_eq!(normal(min, max, Vec3::new(0.0, -100.0, 4e-4)), Vec3::NEG_Y);
    }

    /// The face the ray enters through, known from which slab set the entry `t`, must be the one `normal`
    /// reports, on a thin box whose hit points carry rounding error comparable to its thickness.
    #[test]
    fn normal_matches_entry_slab_on_thin_box() {
        let mut rng = TestRng::new(5);
        let (min, max) = (Vec3::new(-50.0, -50.0, 1.0), Vec3::new(50.0, 50.0, 1.01));
        let mut checked = 0;
        for _ in 0..10_000 {
            let origin = rng.vec3(-200.0, 200.0);
            let dir = rng.vec3(min.x, max.x).with_z(rng.range(min.z, max.z)) - origin;
            let ray = Ray::new(origin, dir);
            let Some(t) = intersect(min, max, &ray, 0.0, f32::INFINITY) else {
                continue;
            };
            if inside(min, max, origin.as_dvec3(), 0.0) {
                continue;
            }
            let t1 = (min - origin) / dir;
            let t2 = (max - origin) / dir;
            let near = t1.min(t2);
            let axis = near.max_position();
            // Skip hits within rounding of an edge, where either face is right.
            let mut rest = near.to_array();
            rest[axis] = f32::NEG_INFINITY;
            if near[axis] - rest.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b)) < 1e-4 * t {
                continue;
            }
            let mut want = Vec3::ZERO;
            want[axis] = -dir[axis].signum();
            assert_eq!(normal(min, max, ray.at(t)), want, "{ray:?} t = {t}");
            checked += 1;
        }
        assert!(checked > 5000, "{checked}");
    }

    /// Point in box, in f64 so that steps much shorter than an f32 ulp of the coordinates still count.
    fn inside(min: Vec3, max: Vec3, p: DVec3, tol: f64) -> bool {
        p.cmpge(min.as_dvec3() - tol).all() && p.cmple(max.as_dvec3() + tol).all()
    }

    /// Random rays against point-in-box tests just before and after the returned `t`, and misses against
    /// a dense march along the ray.
    #[test]
    fn random_rays_match_brute_force() {
        let mut rng = TestRng::new(9);
        let (mut hits, mut exits) = (0, 0);
        for i in 0..10_000 {
            let a = rng.vec3(-5.0, 5.0);
            let b = a + rng.vec3(0.01, 4.0);
            let origin = if i % 5 == 0 {
                a + (b - a) * rng.vec3(0.0, 1.0)
            } else {
                rng.vec3(-10.0, 10.0)
            };
            let target = a + (b - a) * rng.vec3(-0.2, 1.2);
            let dir = (target - origin) * rng.range(0.1, 10.0);
            let ray = Ray::new(origin, dir);
            // Step 1e-4 along the ray either side of the hit; the point beyond it may lie up to that step
            // outside the box when the ray clips an edge or corner.
            let eps = 1e-4 / dir.length();
            match intersect(a, b, &ray, 0.0, f32::INFINITY) {
                Some(t) => {
                    hits += 1;
                    let at = |t: f32| origin.as_dvec3() + dir.as_dvec3() * t as f64;
                    let (before, after) = (at((t - eps).max(0.0)), at(t + eps));
                    let on_surface = inside(a, b, at(t), 1e-4) && !inside(a, b, at(t), -1e-4);
                    assert!(on_surface, "ray {i}: {} off the surface", at(t));
                    if inside(a, b, origin.as_dvec3(), 0.0) {
                        exits += 1;
                        assert!(
                            inside(a, b, before, 0.0) && !inside(a, b, after, 0.0),
                            "ray {i}: exit"
                        );
                    } else {
                        assert!(
                            !inside(a, b, before, 0.0) && inside(a, b, after, 1.01e-4),
                            "ray {i}: entry"
                        );
                    }
                }
                None => {
                    // Any face crossed well inside its rectangle, ahead of the origin, in f64.
                    let (o, d) = (origin.as_dvec3(), dir.as_dvec3());
                    let (lo, hi) = (a.as_dvec3(), b.as_dvec3());
                    for axis in 0..3 {
                        for plane in [lo[axis], hi[axis]] {
                            let t = (plane - o[axis]) / d[axis];
                            let p = o + d * t;
                            let within =
                                (0..3).all(|k| k == axis || (p[k] > lo[k] + 1e-4 && p[k] < hi[k] - 1e-4));
                            assert!(!(t > 1e-4 && within), "ray {i}: missed face {axis} at t = {t}");
                        }
                    }
                }
            }
        }
        assert!(hits > 3000 && exits > 1000, "{hits} hits, {exits} exits");
    }
}
