use std::path::Path;

use super::*;
use crate::accel::policy::AnyHit;
use crate::accel::{Accel, AccelKind};
use crate::kit::agreement::Agreement;
use crate::kit::oracle::{self, Tally};
use crate::kit::rays::{self, Case, TestRng};
use crate::scene::{Camera, Material, Scene};

/// Compares the grid with brute force, bit for bit, on `2 * count` of the kit's test rays
/// (random, camera, grazing, from surfaces) and `count / 4` rays along the grid's cell boundary
/// planes, with single rays and packets ([`oracle::check`]); and checks that any hit's record lies
/// within the interval asked.
fn compare(scene: &Scene, count: usize, seed: u64) -> Tally {
    let prims = Prims::new(scene);
    let brute = Accel::build(prims, AccelKind::None);
    let accel = Accel::build(prims, AccelKind::Grid);
    let Accel::Grid(grid) = &accel else {
        panic!("a grid was asked for")
    };
    let mut cases = rays::cases(scene, &brute, 2 * count, seed);
    cases.extend(boundary_rays(grid, &prims, count / 4, seed));
    let want = oracle::answers(&brute, &cases);
    let tally = oracle::check("grid", &accel, Agreement::Exact, &cases, &want);
    for (c, want) in cases.iter().zip(&want).filter(|(_, w)| w.is_hit()) {
        let limit = (want.t * 1.001).min(c.t_max);
        let mut any = Hit::miss(limit);
        assert!(grid.traverse::<AnyHit>(&c.ray, c.t_min, &mut any), "{c:?}");
        assert!(any.t > c.t_min && any.t < limit, "{c:?}: {any:?}");
    }
    tally
}

/// Rays along cell boundary planes: an origin coordinate on a plane of the lattice and no motion
/// across it (every other one on two planes at once), where the walk's steps divide by zero.
fn boundary_rays(grid: &Grid, prims: &Prims, n: usize, seed: u64) -> Vec<Case> {
    if grid.refs.is_empty() {
        return Vec::new();
    }
    let mut rng = TestRng::new(seed ^ 0x9e37_79b9);
    let (lo, hi) = rays::origin_box(prims);
    let l = grid.lattice;
    (0..n)
        .map(|i| {
            let mut o = lo + (hi - lo) * rng.vec3(0.0, 1.0);
            let a = i % 3;
            o[a] = l.plane(a, (rng.unit_f32() * (l.res[a] + 1) as f32) as i32);
            let mut dir = rng.direction();
            dir[a] = 0.0;
            if i % 2 == 0 {
                let b = (a + 1) % 3;
                o[b] = l.plane(b, (rng.unit_f32() * (l.res[b] + 1) as f32) as i32);
                dir[b] = 0.0;
            }
            Case::ray(Ray::new(o, dir), 0.0)
        })
        .collect()
}

/// A camera looking at the origin from `(3, -30, 20)`.
fn camera() -> Camera {
    Camera::new(Vec3::new(3.0, -30.0, 20.0), Vec3::ZERO, Vec3::Z, 50.0, 64, 64)
}

/// Mixed primitives of widely different sizes: small and huge spheres (some inside-only), triangles,
/// boxes (some flat, one infinite), cones and cylinders, duplicates (exact ties), a zero-height cone, two
/// planes.
fn mixed_scene(seed: u64) -> Scene {
    let mut rng = TestRng::new(seed);
    let mut s = Scene::new(camera());
    let m = s.add_material(Material::default());
    let size = |rng: &mut TestRng, i: usize| {
        if i.is_multiple_of(23) {
            rng.range(5.0, 20.0)
        } else {
            rng.range(0.05, 1.5)
        }
    };
    for i in 0..80 {
        let r = size(&mut rng, i);
        s.add_sphere(rng.vec3(-10.0, 10.0), if i % 9 == 0 { -r } else { r }, m);
    }
    for i in 0..150 {
        let a = rng.vec3(-10.0, 10.0);
        let r = size(&mut rng, i);
        let (b, c) = (a + r * rng.direction(), a + r * rng.direction());
        s.add_triangle(a, b, c, m);
        if i % 10 == 0 {
            s.add_triangle(a, b, c, m);
        }
    }
    for i in 0..40 {
        let a = rng.vec3(-10.0, 10.0);
        let mut e = Vec3::new(size(&mut rng, i), size(&mut rng, i + 1), size(&mut rng, i + 2));
        if i % 7 == 0 {
            e.z = 0.0;
        }
        s.add_box(a, a + e, m);
        if i % 8 == 0 {
            s.add_box(a, a + e, m);
        }
    }
    for i in 0..30 {
        let base = rng.vec3(-10.0, 10.0);
        let apex = base + size(&mut rng, i) * rng.direction();
        let r = rng.range(0.1, 1.0);
        let top = if i % 3 == 0 { r } else { rng.range(0.0, 1.0) };
        let sign = if i % 11 == 0 { -1.0 } else { 1.0 };
        s.add_cone(base, sign * r, apex, sign * top, m);
    }
    s.add_cone(Vec3::ONE, 1.0, Vec3::ONE, 0.5, m);
    // Unbounded on four sides: outside the grid, tested by every ray.
    let corner = Vec3::new(12.0, -12.0, 0.0);
    s.add_box(
        corner.with_y(f32::NEG_INFINITY).with_z(f32::NEG_INFINITY),
        corner.with_x(f32::INFINITY).with_z(f32::INFINITY),
        m,
    );
    s.add_plane(
        Vec3::new(0.0, 0.0, -12.0),
        Vec3::new(1.0, 0.0, -12.0),
        Vec3::new(0.0, 1.0, -12.0),
        m,
    );
    s.add_plane(
        Vec3::new(0.0, 30.0, 0.0),
        Vec3::new(0.0, 30.0, 1.0),
        Vec3::new(1.0, 30.0, 0.0),
        m,
    );
    s
}

/// Everything in the plane z = 0: triangles and zero-thickness boxes, some huge, some duplicated.
fn flat_scene(seed: u64) -> Scene {
    let mut rng = TestRng::new(seed);
    let mut s = Scene::new(camera());
    let m = s.add_material(Material::default());
    let flat = |rng: &mut TestRng| rng.vec3(-10.0, 10.0).with_z(0.0);
    for i in 0..250 {
        let a = flat(&mut rng);
        let r = if i % 31 == 0 { 15.0 } else { rng.range(0.05, 1.5) };
        let (b, c) = (a + r * flat(&mut rng) / 10.0, a + r * flat(&mut rng) / 10.0);
        s.add_triangle(a, b, c, m);
    }
    for i in 0..60 {
        let a = flat(&mut rng);
        let e = rng.vec3(0.05, if i % 17 == 0 { 12.0 } else { 1.0 }).with_z(0.0);
        s.add_box(a, a + e, m);
        if i % 6 == 0 {
            s.add_box(a, a + e, m);
        }
    }
    s
}

#[test]
fn mixed_scenes_match_brute_force() {
    for seed in 0..3 {
        let scene = mixed_scene(seed);
        let t = compare(&scene, 6000, 100 + seed);
        assert!(t.hits > t.rays / 4, "{t:?}");
    }
}

#[test]
fn flat_scene_matches_brute_force() {
    let scene = flat_scene(1);
    let grid = Grid::build(Prims::new(&scene));
    let [x, y, z] = grid.stats().resolution;
    assert!(x > 4 && y > 4 && z == 1, "{}", grid.stats());
    let t = compare(&scene, 12_000, 7);
    assert!(t.hits > t.rays / 10, "{t:?}");
}

#[test]
fn degenerate_scenes_match_brute_force() {
    // Planes only.
    let mut s = Scene::new(camera());
    let m = s.add_material(Material::default());
    s.add_plane(Vec3::ZERO, Vec3::X, Vec3::Y, m);
    let grid = Grid::build(Prims::new(&s));
    assert_eq!(grid.stats().cells, 0);
    compare(&s, 500, 1);
    // A single sphere; point-like triangles (a grid of a few cells, not 512^3), one at the origin where
    // the padding is all that gives the grid a size; a line of spheres (two flat axes).
    let mut s = Scene::new(camera());
    s.add_sphere(Vec3::new(1.0, 2.0, 3.0), 0.5, m);
    compare(&s, 500, 2);
    for p in [Vec3::ONE, Vec3::ZERO] {
        let mut s = Scene::new(camera());
        s.add_triangle(p, p, p, m);
        assert!(Grid::build(Prims::new(&s)).stats().cells <= 8);
        compare(&s, 100, 3);
    }
    let mut s = Scene::new(camera());
    for i in 0..100 {
        s.add_triangle(
            Vec3::new(i as f32, 0.0, 0.0),
            Vec3::new(i as f32 + 0.7, 0.0, 0.0),
            Vec3::new(i as f32, 0.0, 0.0),
            m,
        );
        s.add_sphere(Vec3::new(i as f32 + 0.5, 0.0, 0.0), 0.001, m);
    }
    let stats = Grid::build(Prims::new(&s)).stats();
    assert!(
        stats.resolution[0] > 50 && stats.resolution[1] == 1 && stats.resolution[2] == 1,
        "{stats}"
    );
    let t = compare(&s, 2000, 4);
    assert!(t.hits > 100, "{t:?}");
}

/// Boxes whose faces lie exactly on the grid's cell boundary planes: their hits fall on cell
/// boundaries, where the walk's crossing `t` and the box's `t` come from different roundings.
#[test]
fn boxes_on_cell_boundaries_match_brute_force() {
    let scene = |planes: Option<&Lattice>, rng: &mut TestRng| {
        let mut s = Scene::new(camera());
        let m = s.add_material(Material::default());
        // Two corner spheres fix the grid's box; the boxes stay inside it, so the lattice is the same
        // whatever their placement.
        s.add_sphere(Vec3::splat(-9.5), 0.5, m);
        s.add_sphere(Vec3::splat(9.5), 0.5, m);
        for i in 0..300 {
            let (min, max) = match planes {
                None => (Vec3::ZERO, Vec3::ONE),
                Some(l) => {
                    // One or two cells wide on each axis, between boundary planes 1 and res - 1.
                    let mut min = Vec3::ZERO;
                    let mut max = Vec3::ZERO;
                    for a in 0..3 {
                        let lo = 1 + (rng.unit_f32() * (l.res[a] - 3) as f32) as i32;
                        let width = 1 + (rng.unit_f32() * 2.0) as i32;
                        (min[a], max[a]) = (l.plane(a, lo), l.plane(a, lo + width));
                    }
                    // Some flat, lying in a boundary plane.
                    if i % 5 == 0 {
                        max[i % 3] = min[i % 3];
                    }
                    (min, max)
                }
            };
            s.add_box(min, max, m);
        }
        s
    };
    let mut rng = TestRng::new(11);
    let probe = scene(None, &mut rng);
    let lattice = Grid::build(Prims::new(&probe)).lattice;
    let s = scene(Some(&lattice), &mut rng);
    let grid = Grid::build(Prims::new(&s));
    assert_eq!(grid.lattice.res, lattice.res);
    assert_eq!(grid.lattice.bounds, lattice.bounds);
    let t = compare(&s, 6000, 12);
    assert!(t.hits > t.rays / 4, "{t:?}");
}

#[test]
fn huge_primitives_keep_memory_bounded() {
    let mut s = Scene::new(camera());
    let m = s.add_material(Material::default());
    let mut rng = TestRng::new(3);
    for _ in 0..20_000 {
        s.add_sphere(rng.vec3(-1.0, 1.0), 0.001, m);
    }
    // Every cell overlaps these.
    for _ in 0..2000 {
        s.add_box(Vec3::splat(-1.0), Vec3::splat(1.0), m);
    }
    let stats = Grid::build(Prims::new(&s)).stats();
    assert!(stats.references <= MAX_ENTRIES && stats.cells > 1000, "{stats}");
}

#[test]
fn stats_are_consistent() {
    let scene = mixed_scene(9);
    let grid = Grid::build(Prims::new(&scene));
    let s = grid.stats();
    assert_eq!(s.cells, s.resolution.iter().map(|&n| n as u64).product::<u64>());
    assert_eq!(s.cells as usize + 1, grid.cell_start.len());
    assert_eq!(s.loose, 1, "the infinite box");
    assert!(s.references >= scene.bounded_count() as u64 - 1 && s.empty_cells < s.cells);
    // Every run is ascending, and every primitive sits in the cell holding its box's centre.
    for w in grid.cell_start.windows(2) {
        assert!(
            grid.refs[w[0] as usize..w[1] as usize]
                .windows(2)
                .all(|p| p[0] < p[1])
        );
    }
    for id in (0..grid.prims.bounded()).filter(|id| !grid.loose.contains(id)) {
        let c = grid
            .lattice
            .index(grid.lattice.cell_of(grid.prims.bounds(id).center()));
        let run = grid.cell_start[c] as usize..grid.cell_start[c + 1] as usize;
        assert!(grid.refs[run].contains(&id));
    }
    assert!(s.to_string().starts_with("grid "), "{s}");
}

fn load(name: &str) -> Scene {
    crate::scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(name)).unwrap()
}

#[test]
fn spd_scenes_match_brute_force() {
    for (i, name) in ["balls_1", "gears_1", "rings_1", "tree_1"]
        .into_iter()
        .enumerate()
    {
        let scene = load(&format!("scenes/spd/{name}.nff"));
        let t = compare(&scene, 4000, 20 + i as u64);
        assert!(t.hits > t.rays / 10, "{name}: {t:?}");
    }
}

#[test]
fn dragon_matches_brute_force() {
    let scene = load("scenes/dragon.p3f");
    let t = compare(&scene, 400, 30);
    assert!(t.hits > t.rays / 4, "{t:?}");
}
