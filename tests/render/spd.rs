//! The SPD test procedure (`render::spd`) against the ray counts of the SPD Readme, an independent
//! reference, on the two default-size databases shipped in `scenes/spd/`: every count within the
//! Readme's 10%.

use whitted::accel::{Accel, AccelKind, Prims};
use whitted::render::spd::{self, Counts};
use whitted::render::{Kernel, Renderer};

use crate::common;

fn counts(file: &str, kernel: Kernel) -> (Counts, Vec<u8>) {
    let scene = whitted::scene::load(&common::root().join("scenes/spd").join(file)).unwrap();
    let accel = Accel::build(Prims::new(&scene), AccelKind::Bvh4);
    let options = whitted::render::Options {
        kernel,
        ..spd::options(&scene)
    };
    options.validate().unwrap();
    let renderer = Renderer::new(&scene, &accel, options);
    let never = std::sync::atomic::AtomicBool::new(false);
    let (film, rays) = renderer.render_pass(1, &|| {}, &never).unwrap();
    assert_eq!(rays.primary, 513 * 513, "{file}: one eye ray per corner");
    let image = spd::corners_to_pixels(&film);
    assert_eq!((image.width, image.height), (512, 512));
    (Counts::of(&rays), image.to_rgb8(false))
}

#[test]
fn tetra_and_teapot_match_the_readme_within_ten_percent() {
    for file in ["tetra_default.nff", "teapot_default.nff"] {
        let want = spd::readme_counts(file).unwrap();
        let (got, image) = counts(file, Kernel::Packet);
        eprintln!("{file}: {got:?}, readme {want:?}");
        assert!(
            got.within(&want, 0.10),
            "{file}: {got:?} against the Readme's {want:?}"
        );
        // The packet and single-ray kernels count (and draw) the same.
        assert_eq!(counts(file, Kernel::Single), (got, image), "{file}");
    }
}
