//! Every scene of `scenes/` and `scenes/spd/` renders, deterministically, to the bytes recorded in
//! `tests/golden/images.txt` with every accelerator and kernel of the test kit (`kit::contestants`: every
//! build, on every instruction set this CPU has) and with brute force, each rendered once; frames that
//! end in partial packets agree with single rays, and the big scenes agree with brute force on a small
//! frame; the scenes of millions of triangles that the table marks `exhaustive`, in the exhaustive
//! tier, on the grid and the default structure. The recorded images are a regression check beside the
//! closed-form ones (`shading.rs`): they say that an image changed, not that it is right;
//! `tests/golden/images.txt` says where they come from.

use std::time::Instant;

use whitted::accel::{Accel, AccelKind, Isa, Prims};
use whitted::kit::contestants::{self, Contestant};
use whitted::render::{Kernel, Options, Renderer};
use whitted::scene::{self, Scene};

use crate::common;

/// The recorded frame: 64x48 pixels at the file's samples per pixel.
const RECORDED: (u32, u32) = (64, 48);

fn render(scene: &Scene, accel: &Accel, (width, height): (u32, u32), kernel: Kernel) -> Vec<u8> {
    let mut options = Options::new(scene);
    (options.width, options.height) = (width, height);
    options.kernel = kernel;
    Renderer::new(scene, accel, options).render().to_rgb8(false)
}

/// FNV-1a, 64 bits, over the 8-bit RGB pixels (written here, not taken from the crate under test).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// A recorded digest.
struct Recorded {
    path: String,
    digest: u64,
    /// Marked `exhaustive`: a scene of millions of triangles, too big to build every structure of
    /// in the normal tier, checked by [`big_scenes_render_the_recorded_bytes`].
    exhaustive: bool,
}

/// The recorded digests: `path digest [exhaustive]` per line, `#` comments.
fn recorded() -> Vec<Recorded> {
    let text = std::fs::read_to_string(common::root().join("tests/golden/images.txt")).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let mut words = l.split_whitespace();
            let path = words.next().unwrap().to_string();
            let digest = u64::from_str_radix(words.next().unwrap(), 16).unwrap();
            let exhaustive = match words.next() {
                None => false,
                Some("exhaustive") => true,
                Some(other) => {
                    panic!("{path}: expected `exhaustive` or nothing after the digest, found {other}")
                }
            };
            Recorded {
                path,
                digest,
                exhaustive,
            }
        })
        .collect()
}

/// Brute force renders the recorded frame with every kernel on scenes of fewer than 20,000 bounded
/// primitives. On the others it renders a small frame with single rays, compared with the first wide
/// BVH's: 24x24, or 8x8 beyond 500,000 primitives (the full dragon, where 24x24 takes 24 s of CPU: the
/// exhaustive tier renders that, `full_dragon_matches_brute_force_at_24x24`).
fn brute_size(scene: &Scene) -> Option<u32> {
    match scene.bounded_count() {
        0..20_000 => None,
        20_000..=500_000 => Some(24),
        _ => Some(8),
    }
}

/// Checks the scene file `path` (relative to the crate root) against its recorded digest `want`.
fn check(path: &str, want: u64) {
    let start = Instant::now();
    let scene = scene::load(&common::root().join(path)).unwrap_or_else(|e| panic!("{e}"));
    let prims = Prims::new(&scene);
    // Embree (with the `embree` feature) renders within a tolerance of these: tests/embree/main.rs.
    let list: Vec<Contestant> = contestants::all(prims)
        .into_iter()
        .filter(|c| c.same_images())
        .collect();
    let brute_size = brute_size(&scene);
    let brute = Accel::build(prims, AccelKind::None);
    let built = start.elapsed();
    // Every accelerator and kernel, rendered once: the recorded bytes, so every one gives the same image
    // (and the same image every time).
    let mut accels: Vec<(&str, &Accel)> = list.iter().map(|c| (c.name.as_str(), &c.accel)).collect();
    if brute_size.is_none() {
        accels.push(("brute force", &brute));
    }
    for (name, accel) in accels {
        for kernel in Kernel::ALL {
            let got = fnv1a(&render(&scene, accel, RECORDED, kernel));
            assert_eq!(
                format!("{got:016x}"),
                format!("{want:016x}"),
                "{path}: {name}, {kernel:?} kernel renders other bytes than recorded"
            );
        }
    }
    // The reference for the frames below: the first wide BVH's single rays (the fastest to render).
    let first = list
        .iter()
        .find(|c| c.has_packet_kernel())
        .expect("a wide BVH is listed");
    // 125x125 leaves partial packets at the tiles' edges (the recorded frame is a multiple of the 4x2
    // packets).
    let a125 = render(&scene, &first.accel, (125, 125), Kernel::Single);
    for c in list.iter().filter(|c| c.has_packet_kernel()) {
        assert!(
            render(&scene, &c.accel, (125, 125), Kernel::Packet) == a125,
            "{path}: {}'s packet kernel differs from {}'s single rays at 125x125",
            c.name,
            first.name
        );
    }
    if let Some(size) = brute_size {
        assert!(
            render(&scene, &brute, (size, size), Kernel::Single)
                == render(&scene, &first.accel, (size, size), Kernel::Single),
            "{path}: {} differs from brute force at {size}x{size}",
            first.name
        );
    }
    eprintln!(
        "{path}: {} contestants built in {:.2} s, checked in {:.2} s",
        list.len(),
        built.as_secs_f64(),
        (start.elapsed() - built).as_secs_f64()
    );
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
    let listed: Vec<String> = table.iter().map(|r| r.path.clone()).collect();
    assert_eq!(
        listed, files,
        "tests/golden/images.txt lists other scenes than scenes/ holds"
    );
    for r in table.iter().filter(|r| !r.exhaustive) {
        check(&r.path, r.digest);
    }
}

/// The scenes marked `exhaustive` (millions of triangles) render their recorded bytes with the
/// default structure on every instruction set this CPU has, both kernels, and with the grid; and
/// the default structure's single rays agree with brute force at 8x8.
#[test]
#[ignore = "exhaustive tier: ten full dragons, 8.7M triangles, loaded and built three times"]
fn big_scenes_render_the_recorded_bytes() {
    let big: Vec<Recorded> = recorded().into_iter().filter(|r| r.exhaustive).collect();
    assert!(
        !big.is_empty(),
        "tests/golden/images.txt marks no scene exhaustive"
    );
    for r in &big {
        let scene = scene::load(&common::root().join(&r.path)).unwrap_or_else(|e| panic!("{e}"));
        let prims = Prims::new(&scene);
        let best = Accel::build(prims, AccelKind::best());
        let mut accels = vec![("grid".to_string(), Accel::build(prims, AccelKind::Grid))];
        for isa in [Isa::Portable, Isa::Avx2, Isa::Avx512] {
            let mut copy = best.clone();
            if copy.set_simd(isa) {
                accels.push((format!("{:?} {isa:?}", AccelKind::best()), copy));
            }
        }
        for (name, accel) in &accels {
            for kernel in Kernel::ALL {
                let got = fnv1a(&render(&scene, accel, RECORDED, kernel));
                assert_eq!(
                    format!("{got:016x}"),
                    format!("{:016x}", r.digest),
                    "{}: {name}, {kernel:?} kernel renders other bytes than recorded",
                    r.path
                );
            }
        }
        let brute = Accel::build(prims, AccelKind::None);
        assert!(
            render(&scene, &brute, (8, 8), Kernel::Single) == render(&scene, &best, (8, 8), Kernel::Single),
            "{}: brute force differs at 8x8",
            r.path
        );
    }
}

#[test]
#[ignore = "exhaustive tier: brute force over 871k triangles at 24x24, 24 s of CPU"]
fn full_dragon_matches_brute_force_at_24x24() {
    let scene = scene::load(&common::root().join("scenes/dragon_full.p3f")).unwrap();
    let prims = Prims::new(&scene);
    let brute = Accel::build(prims, AccelKind::None);
    let best = Accel::build(prims, AccelKind::best());
    assert!(
        render(&scene, &brute, (24, 24), Kernel::Single) == render(&scene, &best, (24, 24), Kernel::Single)
    );
}

/// The same render with 1 and 2 worker threads: tiles are independent, so the bytes are identical.
#[test]
fn thread_count_does_not_change_the_image() {
    let scene = scene::load(&common::root().join("scenes/balls_medium.p3f")).unwrap();
    let accel = Accel::build(Prims::new(&scene), AccelKind::Bvh4);
    let images: Vec<Vec<u8>> = [1, 2]
        .iter()
        .map(|&n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
                .install(|| render(&scene, &accel, (96, 96), Kernel::Single))
        })
        .collect();
    assert!(images[0] == images[1]);
}

/// `whitted render` with no scene writes the default scene's image; an output in a missing directory is
/// refused (before rendering) and leaves nothing.
#[test]
fn cli_renders_the_default_scene() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("default.png");
    let run = common::whitted(&["render", "-o", out.to_str().unwrap(), "--width", "80", "--quiet"]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let img = common::images::rgb(&out);
    assert_eq!((img.width(), img.height()), (80, 60));
    let bad = dir.path().join("nowhere").join("x.png");
    let run = common::whitted(&["render", "-o", bad.to_str().unwrap(), "--width", "8", "--quiet"]);
    assert_eq!(run.status.code(), Some(1));
    assert_eq!(
        String::from_utf8_lossy(&run.stderr),
        format!(
            "whitted: {}: the directory {} does not exist\n",
            bad.display(),
            dir.path().join("nowhere").display()
        )
    );
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no temporary file left behind"
    );
}

/// More light samples than the packet path traces as packets (81 from a 9x9 quad light, one point
/// light), glass and mirrors several bounces deep: packets and single rays still give the same image,
/// on every structure and, for the wide BVHs, on every instruction set the CPU has (a packet frame's
/// shading runs on its accelerator's lanes: portable, AVX2, AVX-512).
#[test]
fn packets_match_single_rays_with_many_light_samples_and_deep_bounces() {
    use glam::Vec3;
    use whitted::scene::{Camera, Material, QuadLight};

    let mut s = Scene::new(Camera::new(
        Vec3::new(0.0, 2.0, 8.0),
        Vec3::ZERO,
        Vec3::Y,
        45.0,
        64,
        64,
    ));
    s.add_point_light(Vec3::new(-4.0, 6.0, 4.0), Vec3::splat(0.5));
    s.area_lights.push(QuadLight {
        corner: Vec3::new(-1.0, 5.0, -1.0),
        edge_u: Vec3::X * 2.0,
        edge_v: Vec3::Z * 2.0,
        color: Vec3::ONE,
        grid: 9,
    });
    let glass = s.add_material(Material {
        ks: 0.2,
        transmission: 0.9,
        ior: 1.5,
        ..Material::default()
    });
    let mirror = s.add_material(Material {
        ks: 0.9,
        ..Material::default()
    });
    let matte = s.add_material(Material::default());
    s.add_sphere(Vec3::new(-1.0, 1.0, 0.0), 1.0, glass);
    s.add_sphere(Vec3::new(1.5, 0.7, -0.5), 0.7, mirror);
    s.add_box(Vec3::new(-3.0, 0.0, -3.0), Vec3::new(3.0, 2.5, -2.5), mirror);
    s.add_triangle(
        Vec3::new(-5.0, 0.0, 5.0),
        Vec3::new(5.0, 0.0, 5.0),
        Vec3::new(0.0, 0.0, -5.0),
        matte,
    );
    for c in contestants::all(Prims::new(&s))
        .into_iter()
        .filter(|c| c.same_images())
    {
        for size in [64, 61] {
            let single = render(&s, &c.accel, (size, size), Kernel::Single);
            assert!(
                render(&s, &c.accel, (size, size), Kernel::Packet) == single,
                "{}: packet and single-ray kernels differ at {size}x{size}",
                c.name
            );
        }
    }
}

/// `whitted bench --json` counts the same rays with either kernel (`tests/cli/cli_report.rs` checks its keys).
#[test]
fn cli_bench_json() {
    let run = |kernel: &str| {
        let out = common::whitted(&[
            "bench",
            "scenes/balls_low.p3f",
            "--frames",
            "2",
            "--width",
            "40",
            "--kernel",
            kernel,
            "--json",
        ]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        v["rays_per_frame"].clone()
    };
    let packet = run("packet");
    assert_eq!(packet["primary"], 1600, "{packet}");
    assert_eq!(packet, run("single"));
}
