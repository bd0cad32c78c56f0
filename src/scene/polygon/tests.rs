use std::f64::consts::TAU;

use super::*;
use crate::scene::polygon_checks::assert_triangulates_simple;

fn area(points: &[Vec3], tris: &[[u32; 3]]) -> Vec3 {
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| points[i as usize]);
            (b - a).cross(c - a) * 0.5
        })
        .sum()
}

/// A seeded generator of uniform numbers in [0, 1) (SplitMix64), so that the polygons are the same on
/// every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The polygon `xy` in the plane z = 0.5, with its corners' coordinates as f32 then back in f64 (what the
/// routine sees).
fn in_plane(xy: &[[f64; 2]]) -> (Vec<Vec3>, Vec<[f64; 2]>) {
    let points: Vec<Vec3> = xy
        .iter()
        .map(|&[x, y]| Vec3::new(x as f32, y as f32, 0.5))
        .collect();
    let exact = points.iter().map(|p| [f64::from(p.x), f64::from(p.y)]).collect();
    (points, exact)
}

/// n points drawn uniformly in a square: a polygon that crosses itself about n^2 / 10 times.
fn tangle(n: usize, seed: u64) -> Vec<[f64; 2]> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|_| [rng.next() * 2.0 - 1.0, rng.next() * 2.0 - 1.0])
        .collect()
}

/// A zigzag up between x = -1 and x = 1, then one down between x = -0.5 and 1.5, out of phase with it:
/// every edge of the way down crosses two of the way up.
fn crossing_zigzag(n: usize) -> Vec<[f64; 2]> {
    let half = n / 2;
    let side = |i: usize| if i.is_multiple_of(2) { -1.0 } else { 1.0 };
    let up = (0..half).map(|i| [side(i), i as f64]);
    let down = (0..n - half).rev().map(|i| [0.5 - side(i), i as f64 + 0.5]);
    up.chain(down).collect()
}

fn convex(n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let a = TAU * i as f64 / n as f64;
            [a.cos(), a.sin()]
        })
        .collect()
}

/// A comb of n / 4 unit teeth on a bar: 4 corners a tooth, two of them reflex (the notches' floor).
fn comb(n: usize) -> Vec<[f64; 2]> {
    let k = n / 4;
    let mut p = vec![[0.0, 0.0], [(2 * k - 1) as f64, 0.0]];
    for t in (0..k).rev() {
        let x = 2.0 * t as f64;
        p.push([x + 1.0, 2.0]);
        p.push([x, 2.0]);
        if t > 0 {
            p.push([x, 1.0]);
            p.push([x - 1.0, 1.0]);
        }
    }
    p
}

/// A band wound 20 times around the origin: out along its outer edge, back along its inner one (all reflex).
fn spiral(n: usize) -> Vec<[f64; 2]> {
    let half = n / 2;
    let turns = 20.0;
    let at = |i: usize, width: f64| {
        let a = TAU * turns * i as f64 / (half - 1) as f64;
        let r = 1.0 + a / TAU + width;
        [r * a.cos(), r * a.sin()]
    };
    let outer = (0..half).map(|i| at(i, 0.5));
    let inner = (0..half).rev().map(|i| at(i, 0.0));
    outer.chain(inner).collect()
}

/// A polygon star-shaped about the origin: corners at random radii in [0.05, 1] and random angles, the
/// i-th in the i-th of n equal sectors (less than a half-turn apart).
fn star(n: usize, rng: &mut Rng) -> Vec<[f64; 2]> {
    (0..n)
        .map(|i| {
            let a = (i as f64 + 0.9 * rng.next()) / n as f64 * TAU;
            let r = 0.05 + 0.95 * rng.next();
            [r * a.cos(), r * a.sin()]
        })
        .collect()
}

/// A gear like the SPD's: 36 teeth of 4 corners, 144 in all, 72 of them reflex.
fn gear() -> Vec<[f64; 2]> {
    (0..144)
        .map(|i| {
            let a = TAU * i as f64 / 144.0;
            let r = if i % 4 < 2 { 1.0 } else { 0.85 };
            [r * a.cos(), r * a.sin()]
        })
        .collect()
}

/// n log2 n, the yardstick of the work counts.
fn n_log_n(n: usize) -> u64 {
    (n as f64 * (n as f64).log2()) as u64
}

/// Triangulates `xy` in the plane z = 0.5 (and its mirror image, which runs the other way), checking the
/// count and the winding of every triangle against the polygon's; returns the outcome of the first.
fn run(xy: &[[f64; 2]]) -> (Outcome, Vec<[u32; 3]>) {
    let (points, _) = in_plane(xy);
    let mut out = vec![];
    let outcome = triangulate(&points, &mut out);
    assert_eq!(out.len(), xy.len() - 2, "n - 2 triangles");
    assert!(out.iter().flatten().all(|&i| (i as usize) < xy.len()));
    (outcome, out)
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
    assert!(triangulate(&sq, &mut out).exact);
    assert_eq!(out.len(), 2);
    assert_eq!(area(&sq, &out), Vec3::new(0.0, 0.0, 1.0));
    // Clockwise: the triangles keep the clockwise winding (normal -z).
    let rev: Vec<Vec3> = sq.iter().rev().copied().collect();
    out.clear();
    assert!(triangulate(&rev, &mut out).exact);
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
    assert!(!triangulate(&line, &mut out).exact, "reported as degenerate");
    assert_eq!(out.len(), 3);
    // Every corner the same point, and a polygon with NaN corners.
    for p in [Vec3::ONE, Vec3::NAN] {
        out.clear();
        triangulate(&[p; 7], &mut out);
        assert_eq!(out.len(), 5);
    }
}

/// Asserts that `outcome` (of an n-gon) kept to the budget: the last ear test before it ran out may have
/// visited the whole tree (2n nodes and n tests at most).
#[track_caller]
fn assert_within_budget(outcome: Outcome, n: usize) {
    assert!(outcome.tests <= outcome.work, "{outcome:?}");
    assert!(
        outcome.work <= budget(n) + 3 * n as u64,
        "{outcome:?}, budget {}",
        budget(n)
    );
}

/// A self-intersecting 20,000-gon of random points. The old routine (an O(n) ear test over the whole ring,
/// `Vec::remove`, a lap of misses before clipping blind) made 7,164,763,973 point-in-triangle tests on it
/// (measured once by instrumenting it); this one stops testing after 128 n ⌈log2 n⌉ = 38.4 million units
/// of work (about 6 million tests) and clips the rest blind, reporting it.
#[test]
fn self_intersecting_random_polygon_stays_within_budget() {
    let n = 20_000;
    let (outcome, _) = run(&tangle(n, 1));
    assert!(!outcome.exact, "a tangle is reported: {outcome:?}");
    assert_within_budget(outcome, n);
}

/// A zigzag that crosses itself 20,000 times: laps of the ring without an ear, each ended by a blind clip.
/// The old routine made 187,452,503 point-in-triangle tests on it.
#[test]
fn crossing_zigzag_stays_within_budget() {
    let n = 20_000;
    let (outcome, _) = run(&crossing_zigzag(n));
    assert!(!outcome.exact, "the crossings are reported: {outcome:?}");
    assert_within_budget(outcome, n);
}

/// A convex 20,000-gon: no ear is blocked, so one visit per vertex, and the only tests are against the
/// few corners that rounding the points to f32 made flat or reflex (292 of them). The old routine made
/// 199,950,003 tests on it (every vertex against every ear).
#[test]
fn convex_polygon_needs_few_tests() {
    let n = 20_000;
    let xy = convex(n);
    let (outcome, tris) = run(&xy);
    assert!(outcome.exact, "{outcome:?}");
    assert!(outcome.tests <= n_log_n(n), "{outcome:?}");
    assert!(outcome.work <= budget(n) / 32, "{outcome:?}");
    assert_triangulates_simple(&in_plane(&xy).1, &tris, 1);
}

/// A comb of 5,000 teeth and a spiral band wound 20 times, 20,000 corners each, about half of them reflex:
/// simple polygons, triangulated exactly, well within the budget. The old routine made 199,960,006 and
/// 207,556,690 point-in-triangle tests on them.
#[test]
fn comb_and_spiral_are_exact_and_fast() {
    let n = 20_000;
    for (name, xy) in [("comb", comb(n)), ("spiral", spiral(n))] {
        let (outcome, tris) = run(&xy);
        assert!(outcome.exact, "{name}: {outcome:?}");
        assert!(outcome.tests <= 2 * n_log_n(n), "{name}: {outcome:?}");
        assert!(outcome.work <= budget(n) / 16, "{name}: {outcome:?}");
        assert_triangulates_simple(&in_plane(&xy).1, &tris, 97);
    }
}

/// Random star-shaped (so simple) polygons of 4 to 20,000 corners: the area is kept (against the shoelace
/// formula), no triangle overlaps another or lies outside, every one is wound as the polygon.
#[test]
fn random_simple_polygons_keep_their_area() {
    let mut rng = Rng(7);
    for n in (4..40).chain([100, 144, 500, 1000, 3000, 20_000]) {
        for _ in 0..4 {
            let xy = star(n, &mut rng);
            let (outcome, tris) = run(&xy);
            assert!(outcome.exact, "n = {n}: {outcome:?}");
            assert!(outcome.work <= budget(n) / 8, "n = {n}: {outcome:?}");
            assert_triangulates_simple(&in_plane(&xy).1, &tris, if n > 3000 { 97 } else { 1 });
        }
    }
}

/// The SPD gear's 144-vertex face, both ways round and in each axis plane: exact, well within the budget.
#[test]
fn gear_face_is_exact() {
    let xy = gear();
    for flip in [false, true] {
        let mut xy = xy.clone();
        if flip {
            xy.reverse();
        }
        let (outcome, tris) = run(&xy);
        assert!(outcome.exact, "{outcome:?}");
        assert!(outcome.work <= budget(xy.len()) / 8, "{outcome:?}");
        assert_triangulates_simple(&in_plane(&xy).1, &tris, 1);
        // The same face in the y-z and z-x planes: the triangles' normals point as the polygon's.
        for rotate in [1, 2] {
            let points: Vec<Vec3> = in_plane(&xy)
                .0
                .iter()
                .map(|p| Vec3::from_array([0, 1, 2].map(|k| p[(k + 3 - rotate) % 3])))
                .collect();
            let mut out = vec![];
            assert!(triangulate(&points, &mut out).exact);
            let normal = area(&points, &out);
            for t in &out {
                let [a, b, c] = t.map(|i| points[i as usize]);
                assert!(
                    (b - a).cross(c - a).dot(normal) > 0.0,
                    "{t:?} is wound against the face"
                );
            }
        }
    }
}

/// Self-intersecting and degenerate polygons of every small size still give n - 2 triangles of corners
/// in range.
#[test]
fn any_polygon_gives_n_minus_2() {
    let mut rng = Rng(3);
    for n in 3..60 {
        for seed in 0..5 {
            run(&tangle(n, seed));
            // Corners snapped to a coarse lattice: repeated points, collinear runs, zero-length edges.
            let coarse: Vec<[f64; 2]> = (0..n)
                .map(|_| [(rng.next() * 3.0).floor(), (rng.next() * 3.0).floor()])
                .collect();
            run(&coarse);
        }
        run(&crossing_zigzag(n.max(4)));
    }
}
