//! Every scene of `scenes/` and `scenes/spd/` renders to the bytes recorded in `golden/images.txt`, with
//! every accelerator of the test kit (`whitted::kit::contestants`: every build, on every instruction set
//! this CPU has; brute force too, on scenes small enough for it), and with both kernels. The digests were recorded by the renderer as it was before the lane
//! abstraction and the split of the renderer (commit 671ea29), so this test is what proves that those
//! moves changed no pixel (the six course scenes' digests were re-recorded when `scenes/skybox` gave
//! them a sky: `golden/images.txt` says when, and lists their old digests); it stays as a guard against any change that moves one. It is a regression
//! check beside the closed-form ones (`shading.rs`): it says that an image changed, not that it is right.

mod common;

use whitted::accel::{Accel, AccelKind, Prims};
use whitted::kit::contestants;
use whitted::render::{Kernel, Options, Renderer};

/// FNV-1a, 64 bits, over the 8-bit RGB pixels (written here, not taken from the crate under test).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The recorded digests: `path digest` per line, `#` comments.
fn recorded() -> Vec<(String, u64)> {
    let text = std::fs::read_to_string(common::root().join("tests/golden/images.txt")).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let mut words = l.split_whitespace();
            let path = words.next().unwrap().to_string();
            let digest = u64::from_str_radix(words.next().unwrap(), 16).unwrap();
            (path, digest)
        })
        .collect()
}

#[test]
fn every_scene_renders_the_recorded_bytes_with_every_accelerator_and_kernel() {
    let table = recorded();
    // The table covers every scene file there is: a new scene needs its digest recorded.
    let mut files: Vec<String> = common::scene_files(&common::root().join("scenes"))
        .iter()
        .map(|p| p.strip_prefix(common::root()).unwrap().display().to_string())
        .collect();
    files.sort();
    let listed: Vec<String> = table.iter().map(|(p, _)| p.clone()).collect();
    assert_eq!(
        listed, files,
        "tests/golden/images.txt lists other scenes than scenes/ holds"
    );
    for (path, want) in &table {
        let scene = whitted::scene::load(&common::root().join(path)).unwrap();
        let prims = Prims::new(&scene);
        // Every accelerator and kernel of the test kit, and brute force where it is cheap.
        // Embree (feature `embree`) renders within a tolerance of these: tests/embree.rs.
        let mut accels: Vec<(String, Accel)> = contestants::all(prims)
            .into_iter()
            .filter(|c| c.same_images())
            .map(|c| (c.name, c.accel))
            .collect();
        if scene.bounded_count() < 20_000 {
            accels.push(("brute force".into(), Accel::build(prims, AccelKind::None)));
        }
        for (name, accel) in &accels {
            for kernel in Kernel::ALL {
                let mut options = Options::new(&scene);
                (options.width, options.height) = (64, 48);
                options.kernel = kernel;
                let got = fnv1a(&Renderer::new(&scene, accel, options).render().to_rgb8(false));
                assert_eq!(
                    format!("{got:016x}"),
                    format!("{want:016x}"),
                    "{path}: {name}, {kernel:?} kernel renders other bytes than recorded"
                );
            }
        }
    }
}
