//! A render's step counts (`Options::count_steps`): the same on any number of threads for each
//! kernel, brute force's equal to the primitive count times the closest-hit rays, and the image the
//! same as without counting.

use std::sync::atomic::AtomicBool;

use whitted::accel::{Accel, AccelKind, Prims};
use whitted::render::{Kernel, Options, RayCounts, Renderer};
use whitted::scene::Scene;

use crate::common;

fn render(scene: &Scene, accel: &Accel, kernel: Kernel, threads: usize, count: bool) -> (Vec<u8>, RayCounts) {
    let options = Options {
        width: 48,
        height: 36,
        kernel,
        count_steps: count,
        ..Options::new(scene)
    };
    let renderer = Renderer::new(scene, accel, options);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let never = AtomicBool::new(false);
    let (film, rays) = pool.install(|| renderer.render_pass(1, &|| {}, &never)).unwrap();
    (film.to_rgb8(false), rays)
}

#[test]
fn counts_are_the_same_on_any_threads_and_the_image_unchanged() {
    // Glass, a mirror and a floor: every kind of ray.
    let scene = whitted::scene::load(&common::root().join("scenes/default.p3f")).unwrap();
    for kind in [AccelKind::Grid, AccelKind::Bvh2, AccelKind::Bvh4, AccelKind::Bvh8] {
        let accel = Accel::build(Prims::new(&scene), kind);
        for kernel in Kernel::ALL {
            let (plain, plain_rays) = render(&scene, &accel, kernel, 1, false);
            assert_eq!(
                plain_rays.steps,
                Default::default(),
                "{kind:?} {kernel:?}: counted"
            );
            let (one, rays1) = render(&scene, &accel, kernel, 1, true);
            let (two, rays2) = render(&scene, &accel, kernel, 2, true);
            assert!(
                one == plain && two == plain,
                "{kind:?} {kernel:?}: counting changed the image"
            );
            assert_eq!(rays1, rays2, "{kind:?} {kernel:?}");
            let s = rays1.steps;
            for (what, steps, n) in [
                ("camera", s.camera, rays1.primary),
                ("shadow", s.shadow, rays1.shadow),
                ("reflected", s.reflected, rays1.reflected),
                ("refracted", s.refracted, rays1.refracted),
            ] {
                assert!(
                    n > 0 && steps.prims > 0,
                    "{kind:?} {kernel:?} {what}: {n} rays, {steps:?}"
                );
            }
        }
    }
}

/// Brute force tests every primitive for every closest-hit ray: the counts are the rays times the
/// primitives, on every kernel.
#[test]
fn brute_force_counts_every_primitive_for_every_ray() {
    let scene = whitted::scene::load(&common::root().join("scenes/default.p3f")).unwrap();
    let accel = Accel::build(Prims::new(&scene), AccelKind::None);
    let n = u64::from(Prims::new(&scene).total());
    for kernel in Kernel::ALL {
        let (_, rays) = render(&scene, &accel, kernel, 2, true);
        let s = rays.steps;
        assert_eq!(
            (s.camera.nodes, s.camera.prims),
            (rays.primary, rays.primary * n),
            "{kernel:?}"
        );
        assert_eq!(s.reflected.prims, rays.reflected * n, "{kernel:?}");
        assert_eq!(s.refracted.prims, rays.refracted * n, "{kernel:?}");
        // Shadow rays stop at their first hit.
        assert_eq!(s.shadow.nodes, rays.shadow, "{kernel:?}");
        assert!(
            s.shadow.prims <= rays.shadow * n && s.shadow.prims > 0,
            "{kernel:?}"
        );
    }
}
