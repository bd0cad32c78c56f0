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
fn shoelace(p: &[[f64; 2]]) -> f64 {
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
