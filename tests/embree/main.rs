//! Embree 3 as an accelerator (`--accel embree`, cargo feature `embree`):
//! `cargo test --release --features embree --test embree` (needs `libembree-dev`; `.ci/run` runs it).
//!
//! - every scene of `scenes/` and `scenes/spd/` at 96 pixels wide renders with Embree as with our BVH8,
//!   within 1/255 on at least 99.9% of the pixels, with every kernel (Embree's own triangle test may
//!   round the other way where a ray crosses an edge);
//! - seeded test rays of a few scenes against brute force: the same hit or miss, primitive and `t`
//!   (within 1e-5), except on rays that cross within `kit::agreement::EDGE` of a triangle's edge, which are
//!   counted and bounded; and the kit's oracle on the same rays with single rays, packets and any hit;
//! - the command line: `render`, `info` and `bench --compare` take `embree`;
//! - coordinates past Embree's largest, `FLT_LARGE`: rays from there render as with our BVH8 (Embree's
//!   traversal asserts against them, aborting the process), a scene that reaches there is refused.
//!
//! Without the feature this file checks the one-line refusal of `--accel embree` instead, and says,
//! through a test that fails under `WHITTED_REQUIRE_ALL=1`, that the Embree tests did not run.

#[path = "../common/mod.rs"]
mod common;

/// Without the feature the Embree tests are not compiled: say so, and fail where every test must run
/// (`WHITTED_REQUIRE_ALL=1`; `.ci/run` runs this file with the feature, after skipping this test in
/// its default build).
#[cfg(not(feature = "embree"))]
#[test]
fn embree_tests_need_the_feature() {
    let why = "the Embree tests are compiled with the `embree` feature only \
               (cargo test --release --features embree --test embree; needs apt-get install libembree-dev)";
    assert!(
        std::env::var_os("WHITTED_REQUIRE_ALL").is_none(),
        "{why}; WHITTED_REQUIRE_ALL is set, so they must run"
    );
    eprintln!("skipped: {why}");
}

/// `--accel embree` (and `bench --compare embree`) in a build without Embree: one line that says how to
/// build with it, the usage error status, before anything is loaded.
#[cfg(not(feature = "embree"))]
#[test]
fn accel_embree_without_the_feature_says_how_to_build_it() {
    let line = format!("whitted: {}\n", whitted::accel::NO_EMBREE);
    assert!(line.contains("cargo build --release --features embree") && line.contains("libembree-dev"));
    for args in [
        &[
            "render",
            "scenes/balls_low.p3f",
            "--accel",
            "embree",
            "-o",
            "never.png",
        ][..],
        &["render", "--accel=embree"],
        &["info", "scenes/balls_low.p3f", "--accel", "embree"],
        &["bench", "scenes/balls_low.p3f", "--compare", "embree"],
        &["bench", "scenes/no_such_scene.p3f", "--accel", "embree"],
    ] {
        let out = common::whitted(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert_eq!(String::from_utf8_lossy(&out.stderr), line, "{args:?}");
        assert!(out.stdout.is_empty(), "{args:?}");
    }
    assert!(!common::root().join("never.png").exists());
    // Other bad values keep clap's message.
    let out = common::whitted(&["render", "--accel", "bvh3"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("unknown accelerator \"bvh3\""), "{err}");
}

#[cfg(feature = "embree")]
mod with_embree {
    use std::time::Instant;

    use rayon::prelude::*;
    use whitted::accel::{Accel, AccelKind, Hit, Prims};
    use whitted::kit::agreement::{self, Agreement, EDGE};
    use whitted::kit::oracle;
    use whitted::kit::rays;
    use whitted::render::{Kernel, Options, Renderer};
    use whitted::scene::{self, Scene};

    use super::common;

    fn render(scene: &Scene, accel: &Accel, kernel: Kernel) -> Vec<u8> {
        let mut options = Options::new(scene);
        let (w, h) = (scene.camera.width as f32, scene.camera.height as f32);
        options.width = 96;
        options.height = ((96.0 * h / w).round() as u32).max(1);
        options.kernel = kernel;
        Renderer::new(scene, accel, options).render().to_rgb8(false)
    }

    /// Pixels (of `a.len() / 3`) where some channel differs by more than 1/255.
    fn differing(a: &[u8], b: &[u8]) -> usize {
        a.chunks(3)
            .zip(b.chunks(3))
            .filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > 1))
            .count()
    }

    #[test]
    fn every_scene_renders_as_with_our_bvh8() {
        let (mut pixels, mut worst) = (0, 0.0f64);
        for path in common::scene_files(&common::root().join("scenes")) {
            let start = Instant::now();
            let scene = scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            let prims = Prims::new(&scene);
            let ours = Accel::build(prims, AccelKind::Bvh8);
            let embree = Accel::try_build_with(prims, AccelKind::Embree, Default::default()).unwrap();
            assert!(matches!(embree, Accel::Embree(_)));
            let mut line = Vec::new();
            for kernel in Kernel::ALL {
                let (a, b) = (render(&scene, &ours, kernel), render(&scene, &embree, kernel));
                let n = a.len() / 3;
                let d = differing(&a, &b);
                pixels += n;
                let share = d as f64 / n as f64;
                worst = worst.max(share);
                line.push(format!("{kernel:?} {d} of {n} pixels differ"));
                assert!(
                    share <= 0.001,
                    "{}: {kernel:?} kernel, {d} of {n} pixels differ by more than 1/255",
                    path.display()
                );
            }
            eprintln!(
                "{}: {} ({:.2} s)",
                path.display(),
                line.join(", "),
                start.elapsed().as_secs_f64()
            );
        }
        eprintln!(
            "{pixels} pixels compared; the worst scene differs on {:.3}% of its pixels",
            worst * 100.0
        );
    }

    /// How Embree's closest hit on one ray compares with brute force's.
    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Verdict {
        /// The same hit or miss, on the same primitive, `t` within 1e-5 (relative above 1).
        Same,
        /// Another primitive at the very same `t`: primitives that meet at the hit point (a cone and
        /// the sphere on its end), either one right; Embree's BVH reaches the other first.
        Tie,
        /// A hit of either side is a triangle's within `EDGE` of an edge: its edge distance
        /// (`kit::agreement::edge_distance`) and barycentric margin (`edge_margin`).
        Edge(f64, f64),
        /// A hit of either side lies at the ray's origin within rounding (a ray leaving a surface
        /// finds it again by one test and not by the other).
        Origin,
        /// The `t`s differ by no more than their rounding, or one side alone hits within its rounding
        /// of an end of the interval (`kit::agreement::t_rounding`: a ray nearly in the triangle's plane).
        Rounding,
        /// Anything else: a bug.
        Different,
    }

    fn verdict(prims: &Prims, case: &rays::Case, got: &Hit, want: &Hit) -> Verdict {
        let ray = &case.ray;
        let same = got.is_hit() == want.is_hit()
            && (!want.is_hit()
                || (got.prim == want.prim && (got.t - want.t).abs() <= 1e-5 * want.t.max(1.0)));
        if same {
            return Verdict::Same;
        }
        if got.is_hit() && want.is_hit() && got.t == want.t {
            return Verdict::Tie;
        }
        let near = [got, want]
            .iter()
            .filter_map(|h| {
                let d = agreement::hit_edge_distance(prims, ray, h)?;
                let b = agreement::edge_margin(ray, agreement::hit_triangle(prims, h)?);
                Some((d.abs(), b.abs()))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((d, b)) = near.filter(|n| n.0 < EDGE) {
            return Verdict::Edge(d, b);
        }
        if agreement::at_origin(ray, got) || agreement::at_origin(ray, want) {
            return Verdict::Origin;
        }
        if agreement::may_round_apart(prims, ray, (case.t_min, case.t_max), got, want) {
            return Verdict::Rounding;
        }
        Verdict::Different
    }

    /// Embree against brute force on `n` seeded rays of `path`: asserts that every ray on which they
    /// part has a reason ([`Verdict`]), prints how many of each, runs the kit's oracle (single rays,
    /// packets, any hit) on the same rays, and returns the rays that part (ties aside) and the single
    /// rays and packet lanes the oracle excused.
    fn against_brute_force(path: &str, n: usize, seed: u64) -> (usize, usize) {
        let scene = scene::load(&common::root().join(path)).unwrap();
        let prims = Prims::new(&scene);
        let embree = Accel::build(prims, AccelKind::Embree);
        let grid = Accel::build(prims, AccelKind::Grid);
        let cases = rays::cases(&scene, &grid, n, seed);
        let want = oracle::answers(&Accel::build(prims, AccelKind::None), &cases);
        let got: Vec<Hit> = cases
            .par_iter()
            .map(|c| {
                let mut hit = Hit::miss(c.t_max);
                embree.intersect(&c.ray, c.t_min, &mut hit);
                hit
            })
            .collect();
        let verdicts: Vec<Verdict> = (0..n)
            .map(|i| verdict(&prims, &cases[i], &got[i], &want[i]))
            .collect();
        if let Some(i) = verdicts.iter().position(|v| *v == Verdict::Different) {
            panic!(
                "{path}: ray {i} {:?}: Embree {:?}, brute force {:?}",
                cases[i], got[i], want[i]
            );
        }
        let count = |f: fn(&Verdict) -> bool| verdicts.iter().filter(|v| f(v)).count();
        let ties = count(|v| *v == Verdict::Tie);
        let edges = count(|v| matches!(v, Verdict::Edge(..)));
        let origin = count(|v| *v == Verdict::Origin);
        let rounding = count(|v| *v == Verdict::Rounding);
        // At edges: another primitive at about the same t (a shared edge or vertex, where either is
        // right), hit against miss (a crack of one test), or another t.
        let (mut shared, mut crack, mut embree_only, mut other_t) = (0, 0, 0, 0);
        let (mut farthest, mut barycentric) = (0.0f64, 0.0f64);
        for (i, v) in verdicts.iter().enumerate() {
            if let Verdict::Edge(d, b) = v {
                (farthest, barycentric) = (farthest.max(*d), barycentric.max(*b));
                if got[i].is_hit() != want[i].is_hit() {
                    crack += 1;
                    embree_only += usize::from(got[i].is_hit());
                } else if (got[i].t - want[i].t).abs() <= 1e-5 * want[i].t.max(1.0) {
                    shared += 1;
                } else {
                    other_t += 1;
                }
            }
        }
        let tally = oracle::check(path, &embree, Agreement::Edges, &cases, &want);
        eprintln!(
            "{path}: {n} rays, {} hits; Embree parts from brute force on {edges} at edges ({shared} \
             another primitive at the same t, {crack} hit against miss, of which Embree \
             hits on {embree_only}, {other_t} another t; the \
             farthest {farthest:.1e} from its edge relative to the coordinates, {barycentric:.1e} \
             in barycentric distance), {origin} at the origin, {rounding} by t's rounding, and {ties} \
             on another primitive at the very same t; the oracle excused {} single rays and packet \
             lanes",
            tally.hits, tally.excused
        );
        (edges + origin + rounding, tally.excused)
    }

    /// Every ray on which Embree parts from brute force has a reason ([`Verdict`]: an edge within
    /// `EDGE`, 16 units of f32 precision; the ray's origin; t's rounding; an exact tie), and they stay
    /// rare. The kit's rays aim at vertices and edges on purpose (a quarter of them), so these counts are
    /// their worst case. The columns: rays, the most that may part (ties aside) and the most single
    /// rays and packet lanes the oracle may excuse, each at least a quarter above the count measured
    /// (parted: Embree 3.13.5, 2026-12-01, commit 103c3c8, 2-vCPU AVX-512 Intel Xeon; excused: 2026-12-02,
    /// commit b479852, 2-vCPU AMD Zen 4 with Embree's AVX-512 kernels).
    #[test]
    fn hits_match_brute_force_except_at_edges() {
        let mut total = (0, 0, 0);
        for (path, n, most_parted, most_excused) in [
            ("scenes/spd/gears_1.nff", 4000, 132, 199),
            ("scenes/spd/teapot_1.nff", 4000, 202, 340),
            ("scenes/spd/tree_1.nff", 4000, 65, 186),
            ("scenes/spd/balls_1.nff", 4000, 43, 118),
            ("scenes/spd/lattice_1.nff", 4000, 0, 0),
            ("scenes/balls_box.p3f", 4000, 7, 19),
            ("scenes/mount_low.p3f", 4000, 203, 355),
            ("scenes/dragon.p3f", 2000, 32, 46),
        ] {
            let (parted, excused) = against_brute_force(path, n, 11);
            assert!(
                parted <= most_parted && excused <= most_excused,
                "{path}: {parted} of {n} rays part from brute force at edges (at most {most_parted}), \
                 {excused} excused by the oracle (at most {most_excused})"
            );
            total = (total.0 + n, total.1 + parted, total.2 + excused);
        }
        eprintln!(
            "in all: {} rays, Embree's closest hit parted from brute force on {}, the oracle excused {} \
             rays and lanes",
            total.0, total.1, total.2
        );
    }

    /// The test kit lists Embree when the feature is on, and its oracle holds it to `Edges`.
    #[test]
    fn the_kit_lists_embree() {
        let scene = scene::load(&common::root().join("scenes/balls_low.p3f")).unwrap();
        let list = whitted::kit::contestants::all(Prims::new(&scene));
        let e = list.iter().find(|c| c.name == "embree").expect("embree listed");
        assert!(e.is_embree() && e.has_packet_kernel() && !e.same_images());
        assert_eq!(e.agreement(), Agreement::Edges);
    }

    fn run_ok(args: &[&str]) -> String {
        let out = common::whitted(args);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    }

    /// Embree asserts that a ray's origin lies within its largest coordinate, `FLT_LARGE` (1.844e18),
    /// an assertion that aborts the process (exit status 134): a camera at 1.85e18, or a camera near
    /// the scene whose shadow rays leave a plane's points beyond it. Such rays render as with our BVH8,
    /// with every kernel: a large sphere and box seen from 3e18 (unlit: their outlines against the
    /// background colour; a triangle's test overflows at such sizes, ours as Embree's), and a plane
    /// seen nearly edge-on from 1e12 whose points lit are 3.3e18 away.
    #[test]
    fn rays_from_beyond_embrees_largest_coordinate_render_as_with_our_bvh8() {
        let dir = tempfile::tempdir().unwrap();
        let far_camera = dir.path().join("far_camera.p3f");
        std::fs::write(
            &far_camera,
            "v\nfrom 0 0 1\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0.01\nresolution 64 48\n\
             bclr 0.2 0.4 0.6\nf 1 1 1 1 0 0 0 0\ns 0 0 0 5e17\n\
             box 1e17 -1.2e18 -1e18  9e17 -8e17 1e18\n",
        )
        .unwrap();
        let far_plane = dir.path().join("far_plane.p3f");
        std::fs::write(
            &far_plane,
            "v\nfrom 0 1e12 0\nat 1e12 0.9999997e12 0\nup 0 1 0\nangle 0.000001\nhither 0.01\n\
             resolution 16 16\nl 0 1e13 0\nf 1 1 1 1 0 0 0 0\npl 0 0 0  1 0 0  0 0 -1\ns 0 0 0 1\n",
        )
        .unwrap();
        let far = ["--from", "3e18,0,0", "--at", "0,0,0", "--up", "0,1,0"];
        for (scene, extra) in [(&far_camera, &far[..]), (&far_plane, &[])] {
            let scene = scene.to_str().unwrap();
            for kernel in ["single", "packet"] {
                let image = |accel: &str| {
                    let out = dir.path().join(format!("{accel}.png"));
                    let out_s = out.to_str().unwrap();
                    let args = ["render", scene, "-q", "--accel", accel, "--kernel", kernel];
                    run_ok(&[&args[..], extra, &["-o", out_s]].concat());
                    common::images::rgb(&out).data
                };
                let (ours, embree) = (image("bvh8"), image("embree"));
                let (d, n) = (differing(&ours, &embree), ours.len() / 3);
                assert!(
                    d * 1000 <= n,
                    "{scene} {kernel}: {d} of {n} pixels differ by more than 1/255"
                );
            }
        }
    }

    /// Embree's builders leave out, without a word, the primitives that reach past its largest
    /// coordinate: such a scene is refused with the reason (status 1) rather than rendered without them.
    #[test]
    fn a_scene_past_embrees_largest_coordinate_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("huge.p3f");
        std::fs::write(
            &scene,
            "v\nfrom 0 0 1e20\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0.01\nresolution 16 16\n\
             bclr 0.2 0.4 0.6\nf 1 1 1 1 0 0 0 0\ns 0 0 0 1e19\n",
        )
        .unwrap();
        let out = dir.path().join("out.png");
        let run = common::whitted(&[
            "render",
            scene.to_str().unwrap(),
            "--accel",
            "embree",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_eq!(
            common::failure(&run),
            "whitted: Embree takes coordinates below 1.844e18 (its FLT_LARGE), and the scene's \
             primitives reach 1e19: another --accel renders it"
        );
        assert!(!out.exists());
    }

    /// `render`, `info` and `bench` take `--accel embree`; `bench --compare embree` times both.
    #[test]
    fn the_command_line_takes_embree() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
        let (a, b) = (a.to_str().unwrap(), b.to_str().unwrap());
        let common_args = ["scenes/balls_low.p3f", "--width", "64", "--quiet"];
        run_ok(&[&["render", "--accel", "embree", "-o", a][..], &common_args].concat());
        run_ok(&[&["render", "--accel", "bvh8", "-o", b][..], &common_args].concat());
        let (a, b) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
        assert!(
            a == b,
            "balls_low at 64x64: Embree's image differs from the BVH8's"
        );

        let info: serde_json::Value = serde_json::from_str(&run_ok(&[
            "info",
            "scenes/balls_low.p3f",
            "--accel",
            "embree",
            "--json",
        ]))
        .unwrap();
        assert_eq!(info["accel"]["kind"], "embree");
        assert_eq!(info["accel"]["triangles"], info["triangles"]);
        let text = run_ok(&["info", "scenes/balls_low.p3f", "--accel", "embree"]);
        assert!(text.contains("accelerator   embree 3."), "{text}");

        let bench = run_ok(&[
            "bench",
            "scenes/balls_low.p3f",
            "--frames",
            "2",
            "--width",
            "48",
            "--accel",
            "bvh8",
            "--compare",
            "embree",
            "--json",
        ]);
        let bench: serde_json::Value = serde_json::from_str(&bench).unwrap();
        assert_eq!(bench["accel"], "bvh8");
        assert_eq!(bench["compare"]["accel"], "embree");
        assert_eq!(bench["compare"]["frame_ms"].as_array().unwrap().len(), 2);
        let ratio = bench["speed_ratio"].as_f64().unwrap();
        let medians = bench["compare"]["frame_ms_median"].as_f64().unwrap()
            / bench["frame_ms_median"].as_f64().unwrap();
        assert!((ratio - medians).abs() < 1e-9, "{ratio} {medians}");
        // Same rays on both sides (balls_low has no edge case at this size).
        assert_eq!(bench["rays_per_frame"], bench["compare"]["rays_per_frame"]);
        let text = run_ok(&[
            "bench",
            "scenes/balls_low.p3f",
            "--frames",
            "1",
            "--width",
            "32",
            "--compare",
            "embree",
        ]);
        assert!(text.contains("\nspeed      bvh"), "{text}");
    }
}
