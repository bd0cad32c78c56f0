//! The command line's reports, parsed as a script would read them: `info --json`, `bench --json`,
//! `render --stats` (text and JSON), the SPD procedure's counts against the SPD Readme's table; and the
//! camera overrides. Expected values come from the scene files (read by hand), the Readme, or counts
//! that follow from the frame's size.

use std::collections::BTreeSet;
use std::process::Command;

use glam::Vec3;
use serde_json::Value;
use whitted::accel::bvh2::{INTERSECTION_COST, TRAVERSAL_COST};
use whitted::accel::quality::{TreeView, clipped_area};
use whitted::accel::{Accel, AccelKind, BuildOptions, PrimKind, Prims};
use whitted::kit::rays::TestRng;

use crate::common::{self, int, json, root, stdout, usage_failure, whitted};

/// The SPD Readme's counts (eye hits, reflected, refracted, shadow) at the default sizes.
const TETRA: [u64; 4] = [49_788, 0, 0, 46_112];
const TEAPOT: [u64; 4] = [161_120, 225_248, 0, 407_656];

fn keys(v: &Value) -> BTreeSet<&str> {
    v.as_object().unwrap().keys().map(String::as_str).collect()
}

fn set<'a>(keys: &[&'a str]) -> BTreeSet<&'a str> {
    keys.iter().copied().collect()
}

fn float(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// A JSON array of three numbers as `f32`s (the scene's precision).
fn vec3(v: &Value) -> [f32; 3] {
    let a = v.as_array().unwrap_or_else(|| panic!("not an array: {v}"));
    assert_eq!(a.len(), 3, "{v}");
    [0, 1, 2].map(|i| float(&a[i]) as f32)
}

fn close(got: f64, want: f64, tolerance: f64) -> bool {
    (got - want).abs() <= tolerance * want.abs()
}

#[test]
fn info_json_has_every_field_of_the_text_with_the_files_values() {
    let v = json(&["info", "--json", "scenes/spd/tetra_default.nff"]);
    let documented = [
        "scene",
        "spheres",
        "triangles",
        "boxes",
        "planes",
        "cones",
        "point_lights",
        "area_lights",
        "materials",
        "degenerate_triangles",
        "width",
        "height",
        "from",
        "at",
        "up",
        "fov_y",
        "aperture",
        "focal",
        "spp",
        "bounds_min",
        "bounds_max",
        "load_s",
    ];
    assert_eq!(keys(&v), set(&documented));
    assert_eq!(v["scene"], "scenes/spd/tetra_default.nff");
    // The file: 1,024 tetrahedra of 4 triangles, one light, one `f`, a 512x512 `v` block.
    let counts = [
        ("spheres", 0),
        ("triangles", 4096),
        ("boxes", 0),
        ("planes", 0),
        ("cones", 0),
        ("point_lights", 1),
        ("area_lights", 0),
        ("materials", 1),
        ("degenerate_triangles", 0),
        ("width", 512),
        ("height", 512),
        ("spp", 0),
    ];
    for (key, want) in counts {
        assert_eq!(int(&v[key]), want, "{key}");
    }
    assert_eq!(vec3(&v["from"]), [1.02285, -3.17715, -2.17451]);
    assert_eq!(vec3(&v["at"]), [-0.004103, -0.004103, 0.216539]);
    assert_eq!(vec3(&v["up"]), [-0.816497, -0.816497, 0.816497]);
    assert_eq!(
        [&v["fov_y"], &v["aperture"], &v["focal"]].map(float),
        [45.0, 0.0, 1.0]
    );
    // The outermost tetrahedra's corners are (±1, ±1, ±1).
    assert_eq!(vec3(&v["bounds_min"]), [-1.0; 3]);
    assert_eq!(vec3(&v["bounds_max"]), [1.0; 3]);
    assert!(float(&v["load_s"]) >= 0.0);
}

/// Bounds near the largest float are written as they are; a scene of planes alone has none: null.
/// (Geometry past the largest float, which once gave infinite bounds, is refused when read.)
#[test]
fn info_json_writes_bounds_near_the_float_limit_and_none_as_null() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("huge.nff");
    let scene = "v\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 8 8\ns 1e38 0 0 2e38\n";
    std::fs::write(&path, scene).unwrap();
    let v = json(&["info", "--json", path.to_str().unwrap()]);
    assert_eq!(float(&v["bounds_max"][0]) as f32, 1e38 + 2e38);
    assert_eq!(float(&v["bounds_max"][1]) as f32, 2e38);
    assert_eq!(float(&v["bounds_min"][0]) as f32, 1e38 - 2e38);
    // A scene of planes alone has no bounds: null, not a missing key.
    let planes = dir.path().join("planes.p3f");
    let scene =
        "v\nfrom 0 1 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 8 8\npl 0 1 0 0 0 0 1 0 0\n";
    std::fs::write(&planes, scene).unwrap();
    let v = json(&["info", "--json", planes.to_str().unwrap()]);
    assert_eq!((v["planes"].as_u64(), &v["bounds_min"]), (Some(1), &Value::Null));
}

/// `--build`: the course's dragon stands on a box far larger than its triangles, which the binned SAH
/// files among them by its centre; reinsertion (`optimized`, and `auto`, which is it today) moves it
/// up, so the same leaves sit under inner boxes of less area: a lower SAH cost, the leaves unchanged.
#[test]
fn info_build_optimized_lowers_the_sah_cost_of_the_same_leaves() {
    let tree = |kind: &str, build: &str| {
        let v = json(&[
            "info",
            "--json",
            "--accel",
            kind,
            "--build",
            build,
            "scenes/dragon.p3f",
        ]);
        v["accel"].clone()
    };
    for kind in ["bvh2", "bvh8"] {
        let (sah, optimized, auto) = (tree(kind, "sah"), tree(kind, "optimized"), tree(kind, "auto"));
        assert_eq!(auto, optimized, "{kind}");
        assert_eq!(sah["leaf_sizes"], optimized["leaf_sizes"], "{kind}");
        let (before, after) = (float(&sah["sah_cost"]), float(&optimized["sah_cost"]));
        assert!(after < before, "{kind}: {after} vs {before}");
    }
}

#[test]
fn info_json_with_a_bvh_gives_the_trees_shape() {
    for kind in ["bvh2", "bvh4", "bvh8"] {
        let v = json(&["info", "--json", "--accel", kind, "scenes/spd/tetra_default.nff"]);
        assert!(float(&v["build_s"]) >= 0.0);
        let a = &v["accel"];
        let documented = [
            "kind",
            "simd",
            "nodes",
            "leaves",
            "depth",
            "leaf_sizes",
            "sah_cost",
            "leaf_depths",
        ];
        assert_eq!(keys(a), set(&documented), "{kind}");
        assert_eq!(a["kind"], kind);
        let simd = a["simd"].as_str().unwrap();
        let want = if kind == "bvh2" {
            "scalar"
        } else {
            common::best_simd()
        };
        assert_eq!(simd, want, "{kind}");
        let sizes: Vec<u64> = a["leaf_sizes"].as_array().unwrap().iter().map(int).collect();
        assert_eq!(sizes.len(), 17, "sizes 0 to 15, then 16 or more");
        let (leaves, nodes, depth) = (int(&a["leaves"]), int(&a["nodes"]), int(&a["depth"]));
        // Every leaf is counted once, and every triangle lies in exactly one leaf (none of 16+).
        assert_eq!(sizes.iter().sum::<u64>(), leaves, "{kind}");
        assert_eq!(sizes[16], 0, "{kind}");
        let triangles: u64 = sizes.iter().enumerate().map(|(k, n)| k as u64 * n).sum();
        assert_eq!(triangles, 4096, "{kind}");
        // An n-wide tree over `leaves` leaves has at least (leaves - 1) / (n - 1) inner nodes and
        // 1 + ⌈log_n(leaves)⌉ levels.
        let width: u64 = kind[3..].parse().unwrap();
        assert!(
            nodes >= leaves + (leaves - 1).div_ceil(width - 1),
            "{kind}: {nodes}"
        );
        let levels = 1 + (leaves as f64).log(width as f64).ceil() as u64;
        assert!(depth >= levels, "{kind}: depth {depth} < {levels}");
        // Each node's term is its cost (1 a step, 1 a triangle) times its area over the root's, which
        // is at most 1: from the root's step alone up to all inner steps and triangles.
        let sah = float(&a["sah_cost"]);
        assert!(
            sah > 1.0 && sah <= (nodes - leaves) as f64 + 4096.0,
            "{kind}: {sah}"
        );
        // Leaves by depth below the root: all of them, the deepest at the tree's depth.
        let depths: Vec<u64> = a["leaf_depths"].as_array().unwrap().iter().map(int).collect();
        assert_eq!(depths.iter().sum::<u64>(), leaves, "{kind}");
        assert_eq!(depths.len() as u64, depth, "{kind}");
        // --epo adds the end-point overlap; it asks for a BVH (usage errors otherwise).
        let v = json(&[
            "info",
            "--json",
            "--accel",
            kind,
            "--epo",
            "scenes/spd/tetra_default.nff",
        ]);
        let epo = float(&v["accel"]["epo_cost"]);
        assert!(epo.is_finite() && epo >= 0.0, "{kind}: {epo}");
        // Measured exactly: no sample, and null rather than a missing key.
        assert_eq!(v["accel"]["epo_sampled"], Value::Null, "{kind}");
        assert_eq!(
            keys(&v["accel"]),
            set(&[&documented[..], &["epo_cost", "epo_sampled"]].concat())
        );
        let text = stdout(&["info", "--accel", kind, "--epo", "scenes/spd/tetra_default.nff"]);
        assert!(
            text.contains("\nleaf depths   ") && text.contains(&format!("\nEPO cost      {epo:.2}\n")),
            "{text}"
        );
    }
    let err = common::fails(
        &["info", "--accel", "grid", "--epo", "scenes/spd/tetra_default.nff"],
        2,
    );
    assert_eq!(
        err,
        "whitted: --epo measures a BVH: it needs --accel bvh2, bvh4 or bvh8\n"
    );
    common::fails(&["info", "--epo", "scenes/spd/tetra_default.nff"], 2);
}

/// 100,000 large random triangles in a unit cube cross one another's boxes everywhere: measured node
/// by node, their EPO would take most of an hour, so `info --epo` estimates it from a sample of
/// triangles and says so, in JSON and in text, with the same figures each run. The estimate agrees
/// with one worked out from the definition over another sample of triangles of the same tree.
#[test]
fn info_epo_estimates_a_soup_of_large_triangles() {
    const N: usize = 100_000;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("soup.obj");
    let mut rng = TestRng::new(11);
    let mut obj = String::new();
    for _ in 0..3 * N {
        let p = rng.vec3(0.0, 1.0);
        obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for i in 0..N {
        obj += &format!("f {} {} {}\n", 3 * i + 1, 3 * i + 2, 3 * i + 3);
    }
    std::fs::write(&path, obj).unwrap();
    let file = path.to_str().unwrap();
    let v = json(&["info", "--json", "--accel", "bvh8", "--epo", file]);
    let (epo, k) = (float(&v["accel"]["epo_cost"]), int(&v["accel"]["epo_sampled"]));
    assert!((100..N as u64).contains(&k), "{k}");
    let text = stdout(&["info", "--accel", "bvh8", "--epo", file]);
    let line = format!("\nEPO cost      {epo:.2} (estimated from {k} of {N} triangles)\n");
    assert!(text.contains(&line), "{text}");

    // The same tree, and for each triangle drawn, every node that does not hold it: its cost × the
    // triangle's area in its box.
    let scene = whitted::scene::load(&path).unwrap();
    let prims = Prims::new(&scene);
    let Ok(Accel::Bvh8(bvh)) = Accel::try_build_with(prims, AccelKind::Bvh8, BuildOptions::DEFAULT) else {
        panic!("no BVH8")
    };
    let view = TreeView::from(&bvh);
    let (mut parent, mut leaf) = (vec![None; view.nodes.len()], vec![0; N]);
    for (i, node) in view.nodes.iter().enumerate() {
        node.children.iter().for_each(|&c| parent[c as usize] = Some(i));
        for &id in &node.prims {
            let PrimKind::Triangle(t) = prims.kind(id) else {
                panic!("{id}")
            };
            leaf[t] = i;
        }
    }
    let area = |[a, b, c]: [Vec3; 3]| f64::from((b - a).cross(c - a).length()) / 2.0;
    let total: f64 = (0..N).map(|t| area(scene.triangles.vertices(t))).sum();
    const DRAWN: usize = 128;
    let mut sum = 0.0;
    for _ in 0..DRAWN {
        let t = rng.below(N);
        let mut holds = vec![false; view.nodes.len()];
        let mut at = Some(leaf[t]);
        while let Some(i) = at {
            holds[i] = true;
            at = parent[i];
        }
        for (node, _) in view.nodes.iter().zip(holds).filter(|(_, h)| !h) {
            let cost = if node.children.is_empty() {
                f64::from(INTERSECTION_COST) * node.prims.len() as f64
            } else {
                f64::from(TRAVERSAL_COST)
            };
            sum += cost * clipped_area(scene.triangles.vertices(t), &node.bounds);
        }
    }
    let want = sum / DRAWN as f64 * N as f64 / total;
    // Both are estimates: a fifth is over three standard errors of their difference.
    assert!(close(epo, want, 0.2), "{epo} against {want}");
}

#[test]
fn info_json_with_a_grid_or_brute_force() {
    let v = json(&[
        "info",
        "--json",
        "--accel",
        "grid",
        "scenes/spd/tetra_default.nff",
    ]);
    let g = &v["accel"];
    let documented = [
        "kind",
        "simd",
        "resolution",
        "cells",
        "empty_cells",
        "references",
        "loose",
    ];
    assert_eq!(keys(g), set(&documented));
    assert_eq!(
        (g["kind"].as_str(), g["simd"].as_str()),
        (Some("grid"), Some("scalar"))
    );
    let res: Vec<u64> = g["resolution"].as_array().unwrap().iter().map(int).collect();
    assert_eq!(int(&g["cells"]), res.iter().product::<u64>());
    assert!(int(&g["empty_cells"]) < int(&g["cells"]));
    // Every triangle overlaps at least one cell.
    assert!(int(&g["references"]) >= 4096);
    assert_eq!(int(&g["loose"]), 0);
    let v = json(&[
        "info",
        "--json",
        "--accel",
        "none",
        "scenes/spd/tetra_default.nff",
    ]);
    assert_eq!(v["accel"], serde_json::json!({"kind": "none", "simd": "scalar"}));
}

#[test]
fn info_spd_prints_the_procedures_frame_and_the_readmes_row() {
    let v = json(&["info", "--json", "--spd", "scenes/spd/teapot_default.nff"]);
    let spd = &v["spd"];
    let want = serde_json::json!({
        "width": 512, "height": 512, "corner_rays": 513 * 513, "spp": 0, "max_depth": 4,
        "readme": {"eye_hits": TEAPOT[0], "reflected": TEAPOT[1], "refracted": TEAPOT[2], "shadow": TEAPOT[3]},
    });
    assert_eq!(spd, &want);
    let v = json(&["info", "--json", "--spd", "scenes/spd/jacks_1.nff"]);
    assert_eq!(v["spd"]["readme"], Value::Null);
    let text = stdout(&["info", "--spd", "scenes/spd/tetra_default.nff"]);
    assert!(
        text.contains("spd           512x512 pixels from 513x513 corner rays, spp 0, 4 bounces\n"),
        "{text}"
    );
    assert!(
        text.contains("spd readme    eye hits 49788, reflected 0, refracted 0, shadow 46112"),
        "{text}"
    );
}

/// The keys of the report that `bench --json` and `render --stats=json` share; the rays are
/// `rays_per_frame` in the first and `rays` in the second.
const REPORT_KEYS: [&str; 17] = [
    "version",
    "cpu",
    "scene",
    "width",
    "height",
    "spp",
    "max_depth",
    "accel",
    "simd",
    "kernel",
    "threads",
    "passes",
    "load_s",
    "build_s",
    "render_s",
    "mrays_per_s",
    "mrays_per_s_by_kind",
];

/// The keys of `bench --json`: the frames' times, then the report's.
fn bench_keys() -> BTreeSet<&'static str> {
    let frames = [
        "frames",
        "frame_ms",
        "frame_ms_median",
        "frame_ms_min",
        "frame_ms_max",
        "fps_median",
        "rays_per_frame",
    ];
    set(&[&frames[..], &REPORT_KEYS].concat())
}

/// Checks the rays and rates of a report `r` (whose rays are under `rays_key`): the total is the sum
/// of the kinds, and each rate is its count over the render time.
fn check_rays(r: &Value, rays_key: &str) -> [u64; 6] {
    let rays = &r[rays_key];
    let kinds = [
        "primary",
        "primary_hits",
        "shadow",
        "reflected",
        "refracted",
        "total",
    ];
    assert_eq!(keys(rays), set(&kinds));
    let n = kinds.map(|k| int(&rays[k]));
    assert_eq!(n[5], n[0] + n[2] + n[3] + n[4], "{rays}");
    assert!(n[1] <= n[0], "{rays}");
    let seconds = float(&r["render_s"]);
    let rates = &r["mrays_per_s_by_kind"];
    assert_eq!(
        keys(rates),
        set(&["primary", "shadow", "reflected", "refracted", "total"])
    );
    for (k, count) in [
        ("primary", n[0]),
        ("shadow", n[2]),
        ("reflected", n[3]),
        ("refracted", n[4]),
        ("total", n[5]),
    ] {
        let want = count as f64 / seconds / 1e6;
        assert!(close(float(&rates[k]), want, 1e-9), "{k}: {rates} at {seconds} s");
    }
    assert_eq!(r["mrays_per_s"], rates["total"]);
    n
}

#[test]
fn bench_json_has_every_documented_key_with_the_runs_values() {
    let args = [
        "bench",
        "scenes/spd/tetra_default.nff",
        "--frames",
        "3",
        "--width",
        "32",
        "--threads",
        "1",
        "--accel",
        "bvh4",
        "--kernel",
        "single",
        "--max-depth",
        "2",
        "--json",
    ];
    let v = json(&args);
    assert_eq!(keys(&v), bench_keys());
    let ms: Vec<f64> = v["frame_ms"].as_array().unwrap().iter().map(float).collect();
    assert_eq!((int(&v["frames"]), ms.len()), (3, 3));
    let mut sorted = ms.clone();
    sorted.sort_by(f64::total_cmp);
    let median = float(&v["frame_ms_median"]);
    assert_eq!(
        (float(&v["frame_ms_min"]), median, float(&v["frame_ms_max"])),
        (sorted[0], sorted[1], sorted[2])
    );
    assert!(close(float(&v["fps_median"]), 1e3 / median, 1e-12));
    assert!(close(float(&v["render_s"]), median / 1e3, 1e-9));
    assert_eq!(v["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(v["cpu"].as_str(), Some(common::cpu_line().as_str()));
    assert_eq!(v["scene"], "scenes/spd/tetra_default.nff");
    let frame = [
        ("width", 32),
        ("height", 32),
        ("spp", 0),
        ("max_depth", 2),
        ("threads", 1),
        ("passes", 1),
    ];
    for (key, want) in frame {
        assert_eq!(int(&v[key]), want, "{key}");
    }
    assert_eq!(
        (v["accel"].as_str(), v["kernel"].as_str()),
        (Some("bvh4"), Some("single"))
    );
    assert_eq!(v["simd"].as_str(), Some(common::best_simd()));
    assert!(float(&v["load_s"]) >= 0.0 && float(&v["build_s"]) >= 0.0);
    let n = check_rays(&v, "rays_per_frame");
    // 32x32 camera rays; tetra's one material neither reflects nor refracts; one light.
    assert_eq!((n[0], n[3], n[4]), (1024, 0, 0));
    assert!(n[1] > 0 && n[2] <= n[1], "{n:?}");
}

#[test]
fn bench_json_takes_any_file_name() {
    let dir = tempfile::tempdir().unwrap();
    let name = "tab\there \"quoted\" back\\slash é.nff";
    let path = dir.path().join(name);
    std::fs::copy(root().join("scenes/spd/tetra_default.nff"), &path).unwrap();
    let path = path.to_str().unwrap();
    let v = json(&["bench", path, "--frames", "1", "--width", "8", "--json"]);
    assert_eq!(v["scene"], path);
    let v = json(&["info", "--json", path]);
    assert_eq!(v["scene"], path);
}

#[test]
fn bench_finds_the_dragon_beside_its_sources_from_any_directory() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_whitted"))
        .args(["bench", "--frames", "1", "--width", "8", "--json"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let dragon = root().join("scenes/dragon.p3f");
    assert_eq!(v["scene"], dragon.to_str().unwrap());
    assert_eq!((int(&v["width"]), int(&v["height"])), (8, 6));
}

#[test]
fn bench_text_is_the_report() {
    let args = [
        "bench",
        "scenes/spd/tetra_default.nff",
        "--frames",
        "1",
        "--width",
        "16",
    ];
    let text = stdout(&args);
    let version = env!("CARGO_PKG_VERSION");
    assert!(
        text.contains(&format!(
            "whitted {version}: scenes/spd/tetra_default.nff, 16x16, spp 0, depth 6,"
        )),
        "{text}"
    );
    assert!(text.contains("frame (median)"), "{text}");
    assert!(text.contains("\n  primary             256 "), "{text}");
}

/// `render --spd --stats=json` of `file`: the report, after checking the image is 512x512.
fn spd_render(file: &str) -> Value {
    let dir = tempfile::tempdir().unwrap();
    let image = dir.path().join("spd.png");
    let scene = format!("scenes/spd/{file}");
    let v = json(&[
        "render",
        &scene,
        "--spd",
        "--stats=json",
        "-q",
        "-o",
        image.to_str().unwrap(),
    ]);
    assert_eq!(common::images::rgb(&image).dimensions(), (512, 512));
    v
}

/// Checks the `spd` object of a report against the Readme's `want`.
fn check_spd(v: &Value, want: [u64; 4]) -> [u64; 4] {
    let spd = &v["spd"];
    assert_eq!(
        keys(spd),
        set(&["counts", "readme", "ratio", "within_10_percent"])
    );
    let names = ["eye_hits", "reflected", "refracted", "shadow"];
    let got = names.map(|k| int(&spd["counts"][k]));
    assert_eq!(names.map(|k| int(&spd["readme"][k])), want);
    for ((k, g), w) in names.into_iter().zip(got).zip(want) {
        assert!(
            close(g as f64, w as f64, 0.10),
            "{k}: {g} against the Readme's {w}"
        );
        let ratio = &spd["ratio"][k];
        if w == 0 {
            assert_eq!(ratio, &Value::Null, "{k}");
        } else {
            assert!(close(float(ratio), g as f64 / w as f64, 1e-12), "{k}: {ratio}");
        }
    }
    assert_eq!(spd["within_10_percent"], true);
    assert_eq!(
        int(&v["rays"]["primary"]),
        513 * 513,
        "one eye ray per pixel corner"
    );
    assert_eq!(int(&v["rays"]["primary_hits"]), got[0]);
    got
}

#[test]
fn render_spd_stats_counts_tetra_within_ten_percent_of_the_readme() {
    let v = spd_render("tetra_default.nff");
    assert_eq!(keys(&v), set(&[&REPORT_KEYS[..], &["rays", "spd"]].concat()));
    let frame = [
        ("width", 512),
        ("height", 512),
        ("spp", 0),
        ("max_depth", 4),
        ("passes", 1),
    ];
    for (key, want) in frame {
        assert_eq!(int(&v[key]), want, "{key}");
    }
    check_rays(&v, "rays");
    let got = check_spd(&v, TETRA);
    eprintln!("tetra: {got:?}, the Readme {TETRA:?}");

    // The text, on stderr even with --quiet, shows the same counts beside the Readme's.
    let dir = tempfile::tempdir().unwrap();
    let image = dir.path().join("tetra.png");
    let out = whitted(&[
        "render",
        "scenes/spd/tetra_default.nff",
        "--spd",
        "--stats",
        "-q",
        "-o",
        image.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stderr).unwrap();
    let table = &text[text.find("SPD counts").expect("the SPD table")..];
    let row = |name: &str| -> Vec<String> {
        let line = table
            .lines()
            .find(|l| l.trim_start().starts_with(name))
            .unwrap_or_else(|| panic!("{name}: {text}"));
        line[name.len() + 2..]
            .split_whitespace()
            .map(str::to_string)
            .collect()
    };
    assert_eq!(
        row("eye hits"),
        [
            got[0].to_string(),
            TETRA[0].to_string(),
            format!("{:.3}", got[0] as f64 / TETRA[0] as f64)
        ]
    );
    assert_eq!(row("reflected")[1..], ["0", "-"]);
    assert_eq!(row("shadow")[..2], [got[3].to_string(), TETRA[3].to_string()]);
    assert!(text.contains("within the Readme's 10%: yes"), "{text}");
}

#[test]
fn render_spd_stats_counts_teapot_within_ten_percent_of_the_readme() {
    let v = spd_render("teapot_default.nff");
    let got = check_spd(&v, TEAPOT);
    eprintln!("teapot: {got:?}, the Readme {TEAPOT:?}");
}

#[test]
fn bench_spd_times_the_procedures_frames() {
    let v = json(&[
        "bench",
        "scenes/spd/tetra_default.nff",
        "--spd",
        "--frames",
        "1",
        "--json",
    ]);
    let mut want = bench_keys();
    want.insert("spd");
    assert_eq!(keys(&v), want);
    assert_eq!(int(&v["rays_per_frame"]["primary"]), 513 * 513);
    assert_eq!((int(&v["width"]), int(&v["max_depth"])), (512, 4));
    assert_eq!(v["spd"]["within_10_percent"], true);
    let last = usage_failure(&whitted(&[
        "bench",
        "scenes/spd/tetra_default.nff",
        "--spd",
        "--width",
        "64",
    ]));
    assert!(last.ends_with("cannot be combined with --width"), "{last}");
}

#[test]
fn render_stats_counts_every_pass() {
    let dir = tempfile::tempdir().unwrap();
    let image = dir.path().join("passes.png");
    let args = [
        "render",
        "--width",
        "40",
        "--passes",
        "3",
        "--stats=json",
        "-o",
        image.to_str().unwrap(),
    ];
    let v = json(&args);
    assert_eq!(int(&v["passes"]), 3);
    let n = check_rays(&v, "rays");
    assert_eq!(n[0], 3 * 40 * 30);
    assert_eq!(v["scene"], "(default scene)");
}

/// The camera overrides give exactly the file's image when they repeat the file's camera, and
/// another one when they move it; a camera that cannot be (from = at) is the camera's own error.
#[test]
fn camera_overrides_render_the_camera_they_describe() {
    let dir = tempfile::tempdir().unwrap();
    let render = |name: &str, extra: &[&str]| {
        let out = dir.path().join(name);
        let mut args = vec![
            "render",
            "scenes/spd/tetra_default.nff",
            "--width",
            "48",
            "-q",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend(extra);
        stdout(&args);
        std::fs::read(out).unwrap()
    };
    let plain = render("plain.png", &[]);
    let file = [
        "--from=1.02285,-3.17715,-2.17451",
        "--at=-0.004103,-0.004103,0.216539",
        "--up",
        "-0.816497,-0.816497,0.816497",
        "--fov",
        "45",
    ];
    assert_eq!(render("same.png", &file), plain);
    assert_ne!(render("narrow.png", &["--fov", "30"]), plain);
    let last = usage_failure(&whitted(&[
        "render", "--from", "1,2,3", "--at", "1,2,3", "-o", "x.png",
    ]));
    assert_eq!(
        last,
        "whitted: the camera of --from/--at/--up/--fov: \"from\" and \"at\" are the same point (1 2 3)"
    );
    let last = usage_failure(&whitted(&[
        "bench",
        "scenes/spd/tetra_default.nff",
        "--up",
        "0,0,0",
    ]));
    assert_eq!(
        last,
        "whitted: the camera of --from/--at/--up/--fov: \"up\" is the zero vector"
    );
}

#[test]
fn spd_refuses_the_options_that_change_its_frame() {
    for option in [["--spp", "4"], ["--passes", "2"], ["--height", "100"]] {
        let last = usage_failure(&whitted(&[
            "render", "--spd", option[0], option[1], "-o", "x.png",
        ]));
        assert!(
            last.ends_with(&format!("cannot be combined with {}", option[0])),
            "{last}"
        );
    }
}

/// `--counters`: `render --stats --counters` and `bench --counters` add each ray kind's mean nodes
/// visited and primitives tested per ray; brute force's are one node and every primitive per camera
/// ray (the default scene's primitives, counted by `info`). Without --stats,
/// render refuses it (usage error).
#[test]
fn counters_report_the_steps_per_ray_by_kind() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("c.png");
    let v = json(&[
        "render",
        "--width",
        "32",
        "--accel",
        "none",
        "--stats=json",
        "--counters",
        "-o",
        out.to_str().unwrap(),
    ]);
    let info = json(&["info", "--json", "scenes/default.p3f"]);
    let prims = ["spheres", "triangles", "boxes", "planes", "cones"]
        .iter()
        .map(|k| info[*k].as_u64().unwrap_or(0))
        .sum::<u64>();
    let primary = &v["steps_per_ray"]["primary"];
    assert_eq!(primary["nodes"].as_f64(), Some(1.0), "{v}");
    assert_eq!(primary["prims"].as_f64(), Some(prims as f64), "{v}");
    let kinds: Vec<&String> = v["steps_per_ray"].as_object().unwrap().keys().collect();
    assert_eq!(kinds, ["primary", "shadow", "reflected", "refracted", "total"]);
    let plain = json(&[
        "render",
        "--width",
        "32",
        "--stats=json",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(plain.get("steps_per_ray").is_none(), "{plain}");
    let b = json(&[
        "bench",
        "scenes/spd/tetra_default.nff",
        "--frames",
        "1",
        "--counters",
        "--json",
    ]);
    assert!(
        b["steps_per_ray"]["primary"]["nodes"].as_f64().unwrap() > 1.0,
        "{b}"
    );
    let text = String::from_utf8(
        whitted(&[
            "render",
            "--width",
            "32",
            "--stats",
            "--counters",
            "-o",
            out.to_str().unwrap(),
        ])
        .stderr,
    )
    .unwrap();
    assert!(text.contains("count    Mrays/s  nodes/ray  prims/ray"), "{text}");
    let err =
        String::from_utf8(whitted(&["render", "--counters", "-o", out.to_str().unwrap()]).stderr).unwrap();
    assert!(err.contains("--stats"), "{err}");
}

/// `--stats=json --resume` on a part already whole renders nothing and says so in its report: the
/// part's passes, no rays, no render time.
#[test]
fn render_stats_of_a_part_already_done_report_no_rays() {
    let dir = tempfile::tempdir().unwrap();
    let part = dir.path().join("p.partial");
    let args = [
        "render",
        "--width",
        "40",
        "--passes",
        "2",
        "--tiles",
        "0/2",
        "-q",
        "--resume",
        "--stats=json",
        "-o",
        part.to_str().unwrap(),
    ];
    let first = json(&args);
    assert_eq!(int(&first["passes"]), 2);
    assert!(check_rays(&first, "rays")[0] > 0);
    let again = json(&args);
    assert_eq!(int(&again["passes"]), 2);
    assert_eq!(int(&again["rays"]["total"]), 0, "{again}");
    assert_eq!(again["render_s"].as_f64(), Some(0.0), "{again}");
}
