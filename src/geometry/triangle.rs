//! Ray-triangle intersection on the stored form `(v0, e1 = v1 - v0, e2 = v2 - v0)`.

use glam::Vec3;

use super::aabb::Aabb;
use super::ray::Ray;

/// The hit `(t, u, v)` of `ray` with the triangle `(v0, v0 + e1, v0 + e2)` for `t` in the open interval
/// `(t_min, t_max)`, where `u` and `v` are the barycentric weights of `v1` and `v2`.
///
/// T. Möller, B. Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection", *Journal of Graphics Tools*
/// 2(1), 1997: Cramer's rule on `o + t d = v0 + u e1 + v e2`. The triple products are grouped around
/// `r = (o - v0) × d` and `n = e1 × e2`, as in Embree's Möller-Trumbore kernel
/// (`kernels/geometry/triangle_intersector_moeller.h`; I. Wald et al., "Embree: A Kernel Framework for
/// Efficient CPU Ray Tracing", *ACM TOG* 33(4), 2014). Both sides are hit (no culling). A degenerate triangle
/// (zero or non-finite determinant) never hits.
#[inline]
pub fn intersect(v0: Vec3, e1: Vec3, e2: Vec3, ray: &Ray, t_min: f32, t_max: f32) -> Option<(f32, f32, f32)> {
    let s = ray.origin - v0;
    let r = s.cross(ray.dir);
    let n = e1.cross(e2);
    // Möller-Trumbore's e1 . (d × e2).
    let det = -n.dot(ray.dir);
    // Only exact zero is rejected, not |det| < epsilon: an epsilon on an unnormalised determinant would be
    // scale dependent and would drop small or grazing triangles that do have a well-defined hit.
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    // u = s . (d × e2) / det and v = d . (s × e1) / det, rewritten around r. Each barycentric now depends
    // on its edge only through one dot product with r, so two consistently wound triangles fanned from the
    // same v0 (a quad's diagonal is e2 of one and e1 of the next) evaluate the very same `diag . r` for
    // their shared edge, and a ray crossing both planes from the same side (equal signs of det) sees it
    // with exactly opposite signs: with the inclusive comparisons below it hits at least one of them and
    // never leaks between the two. The far edge u + v = 1 has no such guarantee against its neighbour;
    // that takes a watertight test (S. Woop, C. Benthin, I. Wald, "Watertight Ray/Triangle Intersection",
    // *JCGT* 2(1), 2013).
    let u = e2.dot(r) * inv_det;
    let v = -e1.dot(r) * inv_det;
    if !(u >= 0.0 && v >= 0.0 && u + v <= 1.0) {
        return None;
    }
    // t = e2 . (s × e1) / det.
    let t = n.dot(s) * inv_det;
    (t > t_min && t < t_max).then_some((t, u, v))
}

/// The unit geometric normal `e1 × e2`, the front by the right-hand rule: seen from the side it points to,
/// `v0, v1, v2` run counter-clockwise (OpenGL's default `GL_CCW` front face). Zero for a degenerate
/// triangle.
#[inline]
pub fn geometric_normal(e1: Vec3, e2: Vec3) -> Vec3 {
    e1.cross(e2).normalize_or_zero()
}

/// The unit shading normal `(1 - u - v) n0 + u n1 + v n2` interpolated from vertex normals (B.-T. Phong,
/// "Illumination for Computer Generated Pictures", *CACM* 18(6), 1975). Zero if the weighted normals cancel.
#[inline]
pub fn interpolate_normal(n: &[Vec3; 3], u: f32, v: f32) -> Vec3 {
    (n[0] * (1.0 - u - v) + n[1] * u + n[2] * v).normalize_or_zero()
}

/// The bounding box of the triangle's three corners, as `intersect` sees them (`v0 + e1` rather than the
/// original `v1`, which may differ by rounding).
#[inline]
pub fn bounds(v0: Vec3, e1: Vec3, e2: Vec3) -> Aabb {
    let (v1, v2) = (v0 + e1, v0 + e2);
    Aabb::new(v0.min(v1).min(v2), v0.max(v1).max(v2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kit::rays::TestRng;
    use glam::DVec3;

    const V0: Vec3 = Vec3::new(1.0, 1.0, 0.0);
    const E1: Vec3 = Vec3::new(4.0, 0.0, 0.0);
    const E2: Vec3 = Vec3::new(0.0, 2.0, 0.0);

    fn hit(origin: Vec3, dir: Vec3) -> Option<(f32, f32, f32)> {
        intersect(V0, E1, E2, &Ray::new(origin, dir), 0.0, f32::INFINITY)
    }

    #[test]
    fn known_barycentric_point() {
        let (u, v) = (0.25, 0.5);
        let p = V0 + E1 * u + E2 * v;
        let (t, hu, hv) = hit(p + Vec3::new(0.0, 0.0, 6.0), Vec3::new(0.0, 0.0, -2.0)).unwrap();
        assert_eq!((t, hu, hv), (3.0, u, v));
        // Two-sided: the same point from below.
        let (t, hu, hv) = hit(p - Vec3::new(0.0, 0.0, 6.0), Vec3::new(0.0, 0.0, 3.0)).unwrap();
        assert_eq!((t, hu, hv), (2.0, u, v));
    }

    #[test]
    fn edges_and_vertices_hit_inclusively() {
        let down = Vec3::NEG_Z;
        for (u, v) in [
            (0.0, 0.0),
            (1.0, 0.0),
            (0.0, 1.0),
            (0.5, 0.0),
            (0.0, 0.5),
            (0.5, 0.5),
            (0.25, 0.75),
        ] {
            let p = V0 + E1 * u + E2 * v;
            let (t, hu, hv) = hit(p + Vec3::Z, down).unwrap_or_else(|| panic!("({u}, {v}) missed"));
            assert_eq!((t, hu, hv), (1.0, u, v));
        }
        // Just outside each edge.
        for (u, v) in [(-1e-3, 0.5), (0.5, -1e-3), (0.5, 0.501)] {
            assert_eq!(hit(V0 + E1 * u + E2 * v + Vec3::Z, down), None, "({u}, {v})");
        }
    }

    #[test]
    fn parallel_ray_misses() {
        assert_eq!(hit(Vec3::new(0.0, 1.5, 0.0), Vec3::X), None);
        assert_eq!(hit(Vec3::new(0.0, 1.5, 1.0), Vec3::new(1.0, 0.3, 0.0)), None);
    }

    #[test]
    fn degenerate_triangle_misses() {
        let ray = Ray::new(Vec3::new(2.0, 1.0, 1.0), Vec3::NEG_Z);
        // Collinear corners, a repeated corner, and a non-finite one.
        assert_eq!(intersect(V0, E1, E1 * 0.5, &ray, 0.0, f32::INFINITY), None);
        assert_eq!(intersect(V0, E1, Vec3::ZERO, &ray, 0.0, f32::INFINITY), None);
        assert_eq!(
            intersect(
                V0,
                E1,
                Vec3::new(0.0, f32::INFINITY, 0.0),
                &ray,
                0.0,
                f32::INFINITY
            ),
            None
        );
        assert_eq!(geometric_normal(E1, E1 * 0.5), Vec3::ZERO);
    }

    #[test]
    fn window_is_open() {
        let ray = Ray::new(Vec3::new(2.0, 1.5, 2.0), Vec3::NEG_Z);
        assert_eq!(intersect(V0, E1, E2, &ray, 0.0, 2.0), None);
        assert_eq!(intersect(V0, E1, E2, &ray, 2.0, 5.0), None);
        assert!(intersect(V0, E1, E2, &ray, 1.9, 2.1).is_some());
    }

    #[test]
    fn normals() {
        assert_eq!(geometric_normal(E1, E2), Vec3::Z);
        assert_eq!(geometric_normal(E2, E1), Vec3::NEG_Z);
        let n = [Vec3::X, Vec3::Y, Vec3::Z];
        assert_eq!(interpolate_normal(&n, 0.0, 0.0), Vec3::X);
        assert_eq!(interpolate_normal(&n, 1.0, 0.0), Vec3::Y);
        assert_eq!(interpolate_normal(&n, 0.0, 1.0), Vec3::Z);
        let mid = interpolate_normal(&n, 1.0 / 3.0, 1.0 / 3.0);
        assert!((mid - Vec3::ONE.normalize()).length() < 1e-6);
    }

    #[test]
    fn bounds_of_corners() {
        let b = bounds(V0, E1, Vec3::new(-1.0, 2.0, 3.0));
        assert_eq!(b.min, Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(b.max, Vec3::new(5.0, 3.0, 3.0));
    }

    /// Rays through the shared diagonal of a planar quad split into two triangles must hit one of them.
    #[test]
    fn shared_edge_never_leaks() {
        let mut rng = TestRng::new(3);
        let mut both = 0;
        for i in 0..10_000 {
            // A fresh random planar convex quad every 100 rays: (±1, ±1) corners jittered, in a random frame.
            // (A folded quad would let a ray merely graze its crease, a genuine miss of both.)
            let mut r = TestRng::new(1000 + i / 100);
            let (x, y) = (r.direction(), r.direction());
            let (x, y) = (x, x.cross(y).cross(x).normalize());
            let centre = r.vec3(-5.0, 5.0);
            let scale = r.range(0.1, 5.0);
            let corner = |r: &mut TestRng, cx: f32, cy: f32| {
                centre + (x * (cx + r.range(-0.3, 0.3)) + y * (cy + r.range(-0.3, 0.3))) * scale
            };
            let [a, b, c, d] = [
                corner(&mut r, -1.0, -1.0),
                corner(&mut r, 1.0, -1.0),
                corner(&mut r, 1.0, 1.0),
                corner(&mut r, -1.0, 1.0),
            ];
            let diag = c - a;
            let target = a + diag * rng.range(1e-3, 1.0 - 1e-3);
            // Not within about half a degree of the plane: the f32 corners make the quad very slightly folded,
            // and a ray that grazes so flat a crease can rightly miss both.
            let toward = loop {
                let v = rng.direction();
                if v.dot(x.cross(y)).abs() > 0.01 {
                    break v;
                }
            };
            let origin = target + toward * rng.range(0.5, 20.0);
            let ray = Ray::new(origin, (target - origin) * rng.range(0.1, 10.0));
            let first = intersect(a, b - a, diag, &ray, 0.0, f32::INFINITY);
            let second = intersect(a, diag, d - a, &ray, 0.0, f32::INFINITY);
            assert!(first.is_some() || second.is_some(), "ray {i} leaked: {ray:?}");
            if let (Some(f), Some(s)) = (first, second) {
                // Both hit only on the shared edge itself: the same point, so the same t.
                assert!(
                    (f.0 - s.0).abs() <= 1e-4 * f.0,
                    "ray {i}: t {} and {} on the edge",
                    f.0,
                    s.0
                );
                both += 1;
            }
        }
        // Aimed at the edge, some rays land exactly on it (both hit) and most do not.
        assert!((1..5_000).contains(&both), "{both} rays hit both triangles");
    }

    /// Plane intersection followed by barycentric coordinates from sub-triangle areas, in f64.
    fn brute_force(v0: DVec3, v1: DVec3, v2: DVec3, o: DVec3, d: DVec3) -> (f64, [f64; 3]) {
        let n = (v1 - v0).cross(v2 - v0);
        let t = n.dot(v0 - o) / n.dot(d);
        let p = o + d * t;
        let n2 = n.length_squared();
        let w0 = (v1 - p).cross(v2 - p).dot(n) / n2;
        let w1 = (v2 - p).cross(v0 - p).dot(n) / n2;
        (t, [w0, w1, 1.0 - w0 - w1])
    }

    #[test]
    fn random_rays_match_brute_force() {
        let mut rng = TestRng::new(11);
        let mut hits = 0;
        for i in 0..10_000 {
            let [v0, v1, v2] = [rng.vec3(-5.0, 5.0), rng.vec3(-5.0, 5.0), rng.vec3(-5.0, 5.0)];
            let origin = rng.vec3(-10.0, 10.0);
            let (tu, tv) = (rng.range(-0.2, 1.0), rng.range(-0.2, 1.0));
            let target = v0 + (v1 - v0) * tu + (v2 - v0) * tv;
            // The target lies at t = 1 / k; the window ends before it for about a fifth of the rays.
            let k = rng.range(0.1, 10.0);
            let dir = (target - origin) * k;
            let ray = Ray::new(origin, dir);
            let (t_min, t_max) = (0.0, rng.range(0.8, 2.0) / k);
            let got = intersect(v0, v1 - v0, v2 - v0, &ray, t_min, t_max);
            let [a, b, c, o, d] = [v0, v1, v2, origin, dir].map(Vec3::as_dvec3);
            let (wt, w) = brute_force(a, b, c, o, d);
            // Forward error bounds of the f32 computation (each a sum of products of magnitudes over the
            // determinant, times a few units of roundoff): sliver triangles and grazing rays get wide ones.
            let (e, s, dl) = (
                (b - a).length().max((c - a).length()),
                (o - a).length(),
                d.length(),
            );
            let det = (b - a).cross(c - a).dot(d).abs();
            let roundoff = 16.0 * f32::EPSILON as f64;
            let tol_uv = roundoff * e * dl * (s + 2.0 * e) / det;
            let tol_t = roundoff * e * e * (s + wt.abs() * dl) / det;
            match got {
                Some((t, u, v)) => {
                    hits += 1;
                    assert!((t as f64 - wt).abs() <= tol_t, "ray {i}: t {t} vs {wt} ± {tol_t}");
                    let (du, dv) = ((u as f64 - w[1]).abs(), (v as f64 - w[2]).abs());
                    assert!(
                        du <= tol_uv && dv <= tol_uv,
                        "ray {i}: ({u}, {v}) vs {w:?} ± {tol_uv}"
                    );
                    assert!(w.iter().all(|&x| x >= -tol_uv), "ray {i}: outside {w:?}");
                    assert!(
                        wt > t_min as f64 - tol_t && wt < t_max as f64 + tol_t,
                        "ray {i}: {wt} outside window"
                    );
                }
                None => {
                    let inside = w.iter().all(|&x| x > tol_uv);
                    let in_window = wt > t_min as f64 + tol_t && wt < t_max as f64 - tol_t;
                    assert!(!(inside && in_window), "ray {i}: missed {wt} {w:?}");
                }
            }
        }
        assert!(hits > 2000, "{hits}");
    }
}
