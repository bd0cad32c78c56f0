//! What any correct triangulation of a polygon satisfies, for the loaders' tests (`obj.rs`, `ply.rs`):
//! expectations written without `polygon::triangulate`, the routine under test, so that they do not
//! accept whatever it returns.

use glam::Vec3;

/// The two ways to split the quad of corners 0, 1, 2, 3 along a diagonal, each triangle wound as the
/// quad.
const QUAD_SPLITS: [[[u32; 3]; 2]; 2] = [[[0, 1, 2], [0, 2, 3]], [[0, 1, 3], [1, 2, 3]]];

/// `tris` with each triangle rotated to start at its smallest index (a rotation keeps the winding), in
/// order.
fn canonical(tris: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let mut out: Vec<[u32; 3]> = tris
        .iter()
        .map(|t| {
            let k = (0..3).min_by_key(|&i| t[i]).unwrap();
            [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
        })
        .collect();
    out.sort_unstable();
    out
}

/// Asserts that `tris` are one of the two diagonal splits of the quad whose corners, in order, are the
/// mesh vertices `corners`.
#[track_caller]
pub fn assert_quad_split(tris: &[[u32; 3]], corners: [u32; 4]) {
    let got = canonical(tris);
    assert!(
        QUAD_SPLITS
            .iter()
            .any(|split| canonical(&split.map(|t| t.map(|k| corners[k as usize]))) == got),
        "{tris:?} is neither diagonal split of the quad {corners:?}"
    );
}

/// The signed area of the polygon `p` (counter-clockwise positive), by the shoelace formula.
pub fn shoelace(p: &[[f64; 2]]) -> f64 {
    let n = p.len();
    let twice: f64 = (0..n)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum();
    twice / 2.0
}

/// Asserts that `tris` triangulate the polygon of the mesh vertices `corners` (in order), which lies in a
/// plane z = constant: its shoelace area (in x-y) is `area`, and there are n − 2 triangles, each with
/// indices among the corners, each wound as the polygon (a signed area of the polygon's sign, not zero),
/// their areas summing to the polygon's exactly.
#[track_caller]
pub fn assert_triangulates(positions: &[Vec3], corners: &[u32], tris: &[[u32; 3]], area: f64) {
    let at = |i: u32| positions[i as usize];
    let z = at(corners[0]).z;
    assert!(
        corners.iter().all(|&i| at(i).z == z),
        "the polygon lies in a plane z = {z}"
    );
    let xy = |i: u32| [f64::from(at(i).x), f64::from(at(i).y)];
    let polygon: Vec<[f64; 2]> = corners.iter().map(|&i| xy(i)).collect();
    let whole = shoelace(&polygon);
    assert_eq!(whole, area, "the polygon's area, by the shoelace formula");
    assert_eq!(tris.len(), corners.len() - 2, "{tris:?}: n - 2 triangles");
    let mut sum = 0.0;
    for t in tris {
        assert!(
            t.iter().all(|i| corners.contains(i)),
            "{t:?}: an index outside the polygon {corners:?}"
        );
        let a = shoelace(&t.map(xy));
        assert!(
            a * whole > 0.0,
            "{t:?} is not wound as the polygon: signed area {a}, the polygon's {whole}"
        );
        sum += a;
    }
    assert_eq!(
        sum, whole,
        "{tris:?}: the triangles' areas sum to {sum}, the polygon's is {whole}"
    );
}

/// Whether the point `q` is inside the polygon `p` (even-odd rule, by counting the edges that a ray
/// towards +x crosses).
pub fn contains(p: &[[f64; 2]], q: [f64; 2]) -> bool {
    let n = p.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        if (a[1] > q[1]) != (b[1] > q[1]) {
            let x = a[0] + (q[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if q[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Asserts that `tris` triangulate the simple polygon `p` (corners 0..n in order): n − 2 triangles of
/// corners in range, each wound as the polygon (a signed area of its sign, not zero), their areas summing
/// to the shoelace area of the polygon within a relative `1e-9` (so none overlaps another), and the
/// centroid of every `stride`-th triangle inside the polygon (so none lies outside it).
#[track_caller]
pub fn assert_triangulates_simple(p: &[[f64; 2]], tris: &[[u32; 3]], stride: usize) {
    let whole = shoelace(p);
    assert_ne!(whole, 0.0, "the test polygon has an area");
    assert_eq!(tris.len(), p.len() - 2, "n - 2 triangles");
    let mut sum = 0.0;
    for (k, t) in tris.iter().enumerate() {
        assert!(
            t.iter().all(|&i| (i as usize) < p.len()),
            "{t:?}: an index outside the polygon of {} corners",
            p.len()
        );
        let corners = t.map(|i| p[i as usize]);
        let a = shoelace(&corners);
        assert!(
            a * whole > 0.0,
            "{t:?} is not wound as the polygon: signed area {a}, the polygon's {whole}"
        );
        sum += a.abs();
        if k % stride == 0 {
            let centroid = [0, 1].map(|axis| corners.iter().map(|c| c[axis]).sum::<f64>() / 3.0);
            assert!(contains(p, centroid), "{t:?} lies outside the polygon");
        }
    }
    assert!(
        (sum - whole.abs()).abs() <= 1e-9 * whole.abs(),
        "the triangles' unsigned areas sum to {sum}, the polygon's area is {whole}"
    );
}
