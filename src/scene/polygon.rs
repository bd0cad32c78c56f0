//! Triangulation of planar polygons by ear clipping.
//!
//! NFF polygons are not always convex (the SPD gears have 144-vertex concave faces), so a fan would cover
//! the notches. Ear clipping (Meisters 1975) on the polygon projected to its dominant plane gives the
//! N - 2 triangles of any simple polygon, each keeping the polygon's winding.

use glam::{Vec2, Vec3};

/// Appends the triangles of the polygon `points` (indices into `points`) to `out`. Always appends exactly
/// `points.len() - 2` triangles for `points.len() >= 3`, even for degenerate input (a fan then).
pub fn triangulate(points: &[Vec3], out: &mut Vec<[u32; 3]>) {
    let n = points.len();
    if n < 3 {
        return;
    }
    if n == 3 {
        out.push([0, 1, 2]);
        return;
    }
    // Newell's normal: robust for any simple polygon, convex or not.
    let mut normal = Vec3::ZERO;
    for i in 0..n {
        let (a, b) = (points[i], points[(i + 1) % n]);
        normal += Vec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let abs = normal.abs();
    if abs.max_element().is_nan() || abs.max_element() <= 0.0 {
        fan(n, out);
        return;
    }
    // Drop the dominant axis; mirror so that the projected polygon runs counter-clockwise. Mirroring the
    // coordinates (not the order) keeps each ear in the polygon's own winding.
    let (axis_u, axis_v, sign) = if abs.x >= abs.y && abs.x >= abs.z {
        (1, 2, normal.x.signum())
    } else if abs.y >= abs.z {
        (2, 0, normal.y.signum())
    } else {
        (0, 1, normal.z.signum())
    };
    let flat: Vec<Vec2> = points
        .iter()
        .map(|p| Vec2::new(p[axis_u] * sign, p[axis_v]))
        .collect();
    ear_clip(&flat, out);
}

fn fan(n: usize, out: &mut Vec<[u32; 3]>) {
    for i in 1..n - 1 {
        out.push([0, i as u32, i as u32 + 1]);
    }
}

fn cross(o: Vec2, a: Vec2, b: Vec2) -> f32 {
    (a - o).perp_dot(b - o)
}

fn ear_clip(p: &[Vec2], out: &mut Vec<[u32; 3]>) {
    let mut ring: Vec<u32> = (0..p.len() as u32).collect();
    let mut i = 0;
    let mut misses = 0;
    while ring.len() > 3 {
        let m = ring.len();
        let (ia, ib, ic) = (ring[(i + m - 1) % m], ring[i % m], ring[(i + 1) % m]);
        let (a, b, c) = (p[ia as usize], p[ib as usize], p[ic as usize]);
        let convex = cross(a, b, c) > 0.0;
        let is_ear = convex
            && ring.iter().all(|&j| {
                let q = p[j as usize];
                j == ia || j == ib || j == ic || q == a || q == b || q == c || !inside(a, b, c, q)
            });
        // After a full lap without an ear (a self-touching or numerically flat polygon), clip anyway: the
        // count of triangles stays N - 2 and the surface stays closed.
        if is_ear || misses > m {
            out.push([ia, ib, ic]);
            ring.remove(i % m);
            misses = 0;
            i %= ring.len();
        } else {
            misses += 1;
            i = (i + 1) % m;
        }
    }
    out.push([ring[0], ring[1], ring[2]]);
}

fn inside(a: Vec2, b: Vec2, c: Vec2, q: Vec2) -> bool {
    cross(a, b, q) >= 0.0 && cross(b, c, q) >= 0.0 && cross(c, a, q) >= 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area(points: &[Vec3], tris: &[[u32; 3]]) -> Vec3 {
        tris.iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| points[i as usize]);
                (b - a).cross(c - a) * 0.5
            })
            .sum()
    }

    #[test]
    fn square_and_winding() {
        let sq = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let mut out = vec![];
        triangulate(&sq, &mut out);
        assert_eq!(out.len(), 2);
        assert_eq!(area(&sq, &out), Vec3::new(0.0, 0.0, 1.0));
        // Clockwise: the triangles keep the clockwise winding (normal -z).
        let rev: Vec<Vec3> = sq.iter().rev().copied().collect();
        out.clear();
        triangulate(&rev, &mut out);
        assert_eq!(area(&rev, &out), Vec3::new(0.0, 0.0, -1.0));
    }

    /// A concave comb in the x-z plane: a fan from vertex 0 would cover the notches and overshoot the area.
    #[test]
    fn concave_comb_area_is_exact() {
        let mut pts = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(6.0, 0.0, 0.0)];
        for k in (0..3).rev() {
            let x = 2.0 * k as f32;
            pts.push(Vec3::new(x + 2.0, 0.0, 2.0));
            pts.push(Vec3::new(x + 1.5, 0.0, 2.0));
            pts.push(Vec3::new(x + 1.0, 0.0, 0.5));
            pts.push(Vec3::new(x + 0.5, 0.0, 2.0));
            pts.push(Vec3::new(x, 0.0, 2.0));
        }
        pts.dedup();
        let mut out = vec![];
        triangulate(&pts, &mut out);
        assert_eq!(out.len(), pts.len() - 2);
        let total: f32 = out
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| pts[i as usize]);
                (b - a).cross(c - a).length() * 0.5
            })
            .sum();
        let signed = area(&pts, &out).length();
        // The comb is a 6 x 2 rectangle less three notches of base 1 and height 1.5: 12 - 3 x 0.75.
        assert!((signed - 9.75).abs() < 1e-4, "signed area {signed}");
        // No triangle overlaps another: the unsigned sum equals it too.
        assert!((total - 9.75).abs() < 1e-4, "unsigned sum {total}");
    }

    #[test]
    fn degenerate_polygon_still_gives_n_minus_2() {
        let line: Vec<Vec3> = (0..5).map(|i| Vec3::splat(i as f32)).collect();
        let mut out = vec![];
        triangulate(&line, &mut out);
        assert_eq!(out.len(), 3);
    }
}
