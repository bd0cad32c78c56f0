//! Property tests of the hierarchy invariants and of the slab test, on random inputs.

use glam::Vec3;
use proptest::prelude::*;
use whitted::accel::bvh2::{Builder, Bvh2};
use whitted::accel::wide::{EMPTY, LEAF, WideBvh, leaf_parts};
use whitted::accel::{PrimKind, Prims};
use whitted::geometry::{aabb::Aabb, cuboid, ray::safe_inverse};
use whitted::scene::{Camera, Material, Scene};

fn vec3(range: std::ops::Range<f32>) -> impl Strategy<Value = Vec3> {
    (range.clone(), range.clone(), range).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

/// A scene of `n` primitives of every bounded kind from a list of random numbers.
fn scene(items: &[(u8, Vec3, Vec3, f32)]) -> Scene {
    let mut s = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
    let m = s.add_material(Material::default());
    for &(kind, p, q, r) in items {
        let r = r.abs() + 1e-3;
        match kind % 4 {
            0 => s.add_sphere(p, r, m),
            1 => s.add_triangle(p, q, p + Vec3::new(r, 0.0, r), m),
            2 => s.add_box(p.min(q), p.max(q), m),
            _ => s.add_cone(p, r, p + Vec3::Y * r, r * 0.5, m),
        }
    }
    s
}

fn items() -> impl Strategy<Value = Vec<(u8, Vec3, Vec3, f32)>> {
    prop::collection::vec(
        (any::<u8>(), vec3(-50.0..50.0), vec3(-50.0..50.0), -5.0f32..5.0),
        1..400,
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// BVH2: every primitive in exactly one leaf, every child's box inside its parent's, every leaf's
    /// box around its primitives, and leaves of one kind.
    #[test]
    fn bvh2_invariants(items in items(), midpoint in any::<bool>()) {
        let s = scene(&items);
        let prims = Prims::new(&s);
        let builder = if midpoint { Builder::Midpoint } else { Builder::Sah { bins: 12 } };
        let bvh = Bvh2::new(prims, builder);
        let mut seen = vec![0; prims.bounded() as usize];
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = &bvh.nodes[i];
            if n.is_leaf() {
                let ids = &bvh.ids[n.first as usize..(n.first + n.count) as usize];
                let tri = |id: u32| matches!(prims.kind(id), PrimKind::Triangle(_));
                prop_assert!(ids.iter().all(|&id| tri(id) == tri(ids[0])), "mixed leaf");
                for &id in ids {
                    seen[id as usize] += 1;
                    prop_assert!(n.bounds.contains(&prims.bounds(id)));
                }
            } else {
                for c in [n.first as usize, n.first as usize + 1] {
                    prop_assert!(n.bounds.contains(&bvh.nodes[c].bounds));
                    stack.push(c);
                }
            }
        }
        prop_assert!(seen.iter().all(|&c| c == 1));
    }

    /// BVH4 and BVH8: every primitive reachable exactly once (through triangle blocks or id ranges),
    /// each child slot's box around everything below it, empty slots inverted.
    #[test]
    fn bvh4_invariants(items in items()) {
        wide_invariants::<4>(&items)?;
    }

    #[test]
    fn bvh8_invariants(items in items()) {
        wide_invariants::<8>(&items)?;
    }

    /// The slab test is conservative: a ray through a point of the box (its corners and faces
    /// included) always enters it, whatever its direction, zero components included.
    #[test]
    fn slab_never_misses_a_point_of_the_box(
        lo in vec3(-100.0..100.0),
        size in vec3(0.0..50.0),
        f in vec3(0.0..1.0),
        corner in any::<u8>(),
        origin in vec3(-300.0..300.0),
        zero_axes in any::<u8>(),
    ) {
        let b = Aabb::new(lo, lo + size);
        // A point inside, or snapped to a face, edge or corner.
        let mut p = lo + size * f;
        for axis in 0..3 {
            match (corner >> (2 * axis)) & 3 {
                0 => p[axis] = b.min[axis],
                1 => p[axis] = b.max[axis],
                _ => {}
            }
        }
        let mut dir = p - origin;
        for axis in 0..3 {
            if zero_axes >> axis & 1 == 1 {
                // Put the origin in the point's plane: a direction with a zero component.
                dir[axis] = 0.0;
            }
        }
        prop_assume!(dir.length_squared() > 0.0);
        let o = p - dir;
        // The hierarchies' robust slab. The one case it gives up (see `safe_inverse`): a zero direction
        // component with the origin exactly on one of the box's planes on that axis.
        let on_plane = (0..3).any(|a| dir[a] == 0.0 && (o[a] == b.min[a] || o[a] == b.max[a]));
        if !on_plane {
            prop_assert!(b.ray_entry(o, safe_inverse(dir), 0.0, f32::INFINITY).is_some());
        }
        // The box primitive's exact slab (true reciprocals, NaN-safe), for points strictly inside:
        // on edges it may round either way, like any exact test.
        let inside = lo + size * f.clamp(Vec3::splat(0.01), Vec3::splat(0.99));
        let dir = inside - origin;
        if size.min_element() > 0.0 && dir.length_squared() > 0.0 {
            prop_assert!(cuboid::slab(b.min, b.max, origin, dir.recip(), 0.0, f32::INFINITY).is_some());
        }
    }
}

/// The SAH builder beats or matches the midpoint builder's SAH cost on the dragon (the point of it).
#[test]
fn sah_cost_beats_midpoint() {
    let s =
        whitted::scene::load(&std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes/dragon.p3f"))
            .unwrap();
    let prims = Prims::new(&s);
    let sah = Bvh2::new(prims, Builder::Sah { bins: 12 }).stats().sah;
    let mid = Bvh2::new(prims, Builder::Midpoint).stats().sah;
    assert!(sah < mid, "SAH {sah} vs midpoint {mid}");
}

/// The wide BVH invariants for width `W` (see `bvh4_invariants`).
fn wide_invariants<const W: usize>(items: &[(u8, Vec3, Vec3, f32)]) -> Result<(), TestCaseError> {
    let s = scene(items);
    let prims = Prims::new(&s);
    let bvh = WideBvh::<W>::new(prims, 12).unwrap();
    let mut seen = vec![0; prims.bounded() as usize];
    let mut stack = vec![(bvh.root(), bvh.bounds())];
    while let Some((r, bounds)) = stack.pop() {
        if r == EMPTY {
            continue;
        }
        if r & LEAF != 0 {
            let count = leaf_parts(r).1;
            let ids = bvh.leaf_ids(r);
            prop_assert_eq!(ids.len(), count);
            prop_assert!(ids.iter().all(|&id| id != u32::MAX), "{:?}", ids);
            for id in ids {
                seen[id as usize] += 1;
                prop_assert!(bounds.contains(&prims.bounds(id)));
            }
            continue;
        }
        let node = &bvh.nodes()[r as usize];
        for k in 0..W {
            let child = WideBvh::<W>::child_bounds(node, k);
            if node.child[k] == EMPTY {
                prop_assert!(child.is_empty());
            } else {
                prop_assert!(bounds.contains(&child));
            }
            stack.push((node.child[k], child));
        }
    }
    prop_assert!(seen.iter().all(|&c| c == 1));
    Ok(())
}
