//! The counting verbs (`Accel::counting`, `accel::counters`): exact counts on hand-made scenes, a
//! test-side traversal of the BVH2's nodes as the independent count, and the same counts from every
//! kernel where the kernels visit the same nodes.

use glam::Vec3;
use whitted::accel::counters::{self, Steps};
use whitted::accel::{Accel, AccelKind, Hit, PACKET, Prims};
use whitted::geometry::ray::Ray;
use whitted::scene::{Camera, Material, Scene};

fn scene() -> Scene {
    let mut scene = Scene::new(Camera::new(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
    scene.add_material(Material::default());
    scene
}

/// Deterministic numbers in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next()) * (hi - lo) + Vec3::splat(lo)
    }
}

/// `n` small triangles scattered in [-1, 1]^3, a sieve that most rays pass through.
fn sieve(n: usize) -> Scene {
    let mut s = scene();
    let mut rng = Lcg(9);
    for _ in 0..n {
        let a = rng.vec(-1.0, 1.0);
        s.add_triangle(a, a + rng.vec(0.0, 0.02), a + rng.vec(0.0, 0.02), 0);
    }
    s
}

fn closest(accel: &Accel, ray: &Ray) -> (bool, Steps) {
    let mut hit = Hit::miss(f32::INFINITY);
    let found = accel.counting().intersect(ray, 0.0, &mut hit);
    (found, counters::lane(0))
}

/// Brute force is one node of all primitives: a closest-hit ray tests every one, and so does an
/// any-hit ray that misses.
#[test]
fn brute_force_tests_every_primitive_once() {
    let scene = sieve(50);
    let accel = Accel::build(Prims::new(&scene), AccelKind::None);
    let mut rng = Lcg(3);
    for _ in 0..100 {
        let ray = Ray::new(rng.vec(-2.0, 2.0), rng.vec(-1.0, 1.0).normalize());
        assert_eq!(closest(&accel, &ray).1, Steps { nodes: 1, prims: 50 });
        if !accel.counting().occluded(&ray, 0.0, f32::INFINITY) {
            assert_eq!(counters::lane(0), Steps { nodes: 1, prims: 50 });
        }
    }
}

/// One triangle: every hierarchy is a single leaf, so a ray tests one primitive and visits no inner
/// node; the plain verbs count nothing.
#[test]
fn a_single_triangle_is_one_test() {
    let mut scene = scene();
    scene.add_triangle(
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        0,
    );
    let ray = Ray::new(Vec3::Z * 3.0, -Vec3::Z);
    for kind in [AccelKind::Bvh2, AccelKind::Bvh4, AccelKind::Bvh8] {
        let accel = Accel::build(Prims::new(&scene), kind);
        assert_eq!(
            closest(&accel, &ray),
            (true, Steps { nodes: 0, prims: 1 }),
            "{kind:?}"
        );
        counters::reset(1);
        let mut hit = Hit::miss(f32::INFINITY);
        assert!(accel.intersect(&ray, 0.0, &mut hit));
        assert_eq!(
            counters::lane(0),
            Steps::default(),
            "{kind:?}: the plain verb counted"
        );
    }
}

/// A ray along x through the middle of a grid over two small spheres in opposite corners walks every
/// cell of its row, and tests a sphere only where one is binned in that row.
#[test]
fn a_grid_walk_counts_its_cells() {
    let mut scene = scene();
    scene.add_sphere(Vec3::splat(-1.0), 0.1, 0);
    scene.add_sphere(Vec3::splat(1.0), 0.1, 0);
    let accel = Accel::build(Prims::new(&scene), AccelKind::Grid);
    let Accel::Grid(grid) = &accel else { unreachable!() };
    let [nx, ny, nz] = grid.stats().resolution;
    let ray = Ray::new(Vec3::new(-5.0, 0.01, -0.02), Vec3::X);
    let (found, steps) = closest(&accel, &ray);
    assert!(!found);
    assert_eq!(steps.nodes, u64::from(nx), "{nx}x{ny}x{nz}");
    // A sphere is tested where its cell lies in the ray's row (the grid spans -1.1 to 1.1; each
    // sphere, 0.2 across, lies in one cell of a grid this coarse).
    assert!(nx.max(ny).max(nz) < 11, "{nx}x{ny}x{nz}");
    let cell = |v: f32, n: u32| (((v + 1.1) / 2.2 * n as f32) as u32).min(n - 1);
    let in_row = |c: f32| cell(c, ny) == cell(0.01, ny) && cell(c, nz) == cell(-0.02, nz);
    let expected = [-1.0, 1.0].into_iter().filter(|&c| in_row(c)).count() as u64;
    assert_eq!(steps.prims, expected, "{nx}x{ny}x{nz}");
}

/// The BVH2's steps for rays that hit nothing (so no hit culls a box) equal a count by a test-side
/// traversal of its nodes, with its own slab test in f64: every inner node whose box the ray enters
/// is visited, and every leaf it enters has all its primitives tested.
#[test]
fn bvh2_steps_equal_a_test_side_traversal() {
    let scene = sieve(400);
    let accel = Accel::build(Prims::new(&scene), AccelKind::Bvh2);
    let brute = Accel::build(Prims::new(&scene), AccelKind::None);
    let Accel::Bvh2(bvh) = &accel else { unreachable!() };
    let enters = |b: &whitted::geometry::aabb::Aabb, ray: &Ray| {
        let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
        for a in 0..3 {
            let (o, d) = (f64::from(ray.origin[a]), f64::from(ray.dir[a]));
            let (lo, hi) = (f64::from(b.min[a]), f64::from(b.max[a]));
            if d == 0.0 {
                if o < lo || o > hi {
                    return false;
                }
                continue;
            }
            let (ta, tb) = ((lo - o) / d, (hi - o) / d);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        t0 <= t1
    };
    let mut rng = Lcg(5);
    let mut checked = 0;
    for _ in 0..2000 {
        let ray = Ray::new(rng.vec(-1.5, 1.5), rng.vec(-1.0, 1.0).normalize());
        let mut hit = Hit::miss(f32::INFINITY);
        if brute.intersect(&ray, 0.0, &mut hit) {
            continue;
        }
        let mut want = Steps::default();
        let mut stack = vec![0usize];
        if !enters(&bvh.nodes[0].bounds, &ray) {
            stack.clear();
        }
        while let Some(i) = stack.pop() {
            let node = &bvh.nodes[i];
            if node.is_leaf() {
                want.prims += u64::from(node.count);
                continue;
            }
            want.nodes += 1;
            for c in [node.first as usize, node.first as usize + 1] {
                if enters(&bvh.nodes[c].bounds, &ray) {
                    stack.push(c);
                }
            }
        }
        assert_eq!(closest(&accel, &ray), (false, want), "{ray:?}");
        checked += 1;
    }
    assert!(checked > 1000, "{checked} rays missed");
}

/// For rays that hit nothing, a packet counts each ray the nodes and primitives the single-ray kernel
/// does (a packet visits a node for the rays that entered it), on every structure.
#[test]
fn packets_count_what_single_rays_count() {
    let scene = sieve(400);
    let brute = Accel::build(Prims::new(&scene), AccelKind::None);
    let mut rng = Lcg(11);
    let mut rays = Vec::new();
    while rays.len() < 8 * 64 {
        // Coherent bundles: eight rays from one point in nearby directions.
        let o = rng.vec(-1.5, 1.5);
        let d = rng.vec(-1.0, 1.0);
        let bundle: Vec<Ray> = (0..8)
            .map(|_| Ray::new(o, (d + rng.vec(-0.05, 0.05)).normalize()))
            .collect();
        let misses = bundle
            .iter()
            .all(|r| !brute.intersect(r, 0.0, &mut Hit::miss(f32::INFINITY)));
        if misses {
            rays.extend(bundle);
        }
    }
    for kind in [AccelKind::Grid, AccelKind::Bvh2, AccelKind::Bvh4, AccelKind::Bvh8] {
        let accel = Accel::build(Prims::new(&scene), kind);
        let single: Vec<Steps> = rays.iter().map(|r| closest(&accel, r).1).collect();
        assert!(
            single.iter().any(|s| s.nodes > 1),
            "{kind:?}: rays that visit nothing"
        );
        for (c, chunk) in rays.chunks(PACKET).enumerate() {
            let packet: [Ray; PACKET] = std::array::from_fn(|k| chunk[k]);
            let mut hits = [Hit::miss(f32::INFINITY); PACKET];
            accel.counting().intersect_packet(&packet, 0xff, 0.0, &mut hits);
            for k in 0..PACKET {
                assert_eq!(
                    counters::lane(k),
                    single[c * PACKET + k],
                    "{kind:?} packet {c} ray {k}"
                );
            }
            let t_max = [f32::INFINITY; PACKET];
            accel.counting().occluded_packet(&packet, 0xff, 0.0, &t_max);
            for k in 0..PACKET {
                assert_eq!(
                    counters::lane(k),
                    single[c * PACKET + k],
                    "{kind:?} shadow packet {c} ray {k}"
                );
            }
        }
    }
}
