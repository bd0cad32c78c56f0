//! `render --heatmap`: exact per-pixel counts where they are known in closed form (brute force tests
//! every primitive for every ray; each pixel sends its samples' camera rays), the same on any number of
//! threads, with `--passes` and `--tiles`, the colour scale's top equal to the raw file's largest value
//! or percentile, the default scale spreading the dragon's skewed costs over the colours, and usage
//! errors for what cannot be counted and scales that do not parse.

use std::path::Path;

use serde_json::Value;
use whitted::heatmap::{Heatmap, Ramp, Scale, nearest_rank, viridis};

use crate::common::images::rgb;
use crate::common::{self, fails, json, stdout};

/// The raw counts of a heatmap's `.exr` (one value per pixel, in all three channels).
fn counts(path: &Path) -> (u32, u32, Vec<f32>) {
    let (width, height, pixels) = common::images::exr(path);
    let values = pixels.iter().map(|p| {
        assert!(p[0] == p[1] && p[1] == p[2], "{p:?}");
        p[0]
    });
    (width, height, values.collect())
}

fn summary(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

/// Renders the default scene at 16x12 with `args` into `dir/NAME.png` and returns the heatmap's paths.
fn heatmap(dir: &Path, name: &str, args: &[&str]) -> [std::path::PathBuf; 3] {
    let out = dir.join(format!("{name}.png"));
    let base = [
        "render",
        "--width",
        "16",
        "--height",
        "12",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ];
    stdout(&[&base[..], args].concat());
    ["png", "exr", "json"].map(|ext| dir.join(format!("{name}.heatmap.{ext}")))
}

#[test]
fn brute_force_tests_every_primitive_for_every_camera_ray() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let info = json(&["info", "--json", "scenes/default.p3f"]);
    let prims: u64 = ["spheres", "triangles", "boxes", "planes", "cones"]
        .iter()
        .map(|k| info[*k].as_u64().unwrap())
        .sum();
    for kernel in ["single", "packet"] {
        let [png, exr, json] = heatmap(
            d,
            kernel,
            &["--accel", "none", "--kernel", kernel, "--heatmap", "prims:camera"],
        );
        let (w, h, values) = counts(&exr);
        assert_eq!((w, h), (16, 12));
        assert!(values.iter().all(|&v| v == prims as f32), "{kernel}: {values:?}");
        let s = summary(&json);
        assert_eq!(s["measure"], "primitives tested per pixel (camera rays)");
        assert_eq!(s["per_pixel"]["camera"]["max"], prims);
        assert_eq!(s["per_pixel"]["camera"]["median"], prims);
        // The legend's last number is the raw file's largest value, under a 16-pixel-wide image
        // widened to hold it.
        let img = rgb(&png);
        assert!(
            img.width() >= 16 && img.height() > 12,
            "{}x{}",
            img.width(),
            img.height()
        );
    }
}

#[test]
fn camera_rays_per_pixel_are_the_samples_times_the_passes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let [_, exr, json] = heatmap(d, "spp", &["--spp", "4", "--heatmap", "rays:camera"]);
    assert!(counts(&exr).2.iter().all(|&v| v == 4.0));
    assert_eq!(summary(&json)["per_pixel"]["camera"]["mean"], 4.0);
    let [_, exr, _] = heatmap(d, "passes", &["--passes", "3", "--heatmap", "rays:camera"]);
    assert!(counts(&exr).2.iter().all(|&v| v == 3.0));
    // A part counts its own tiles' pixels; the others are 0. 16x12 is one tile: 40x12 is three.
    let out = d.join("part.partial");
    stdout(&[
        "render",
        "--width",
        "40",
        "--height",
        "12",
        "--tiles",
        "1/3",
        "-q",
        "-o",
        out.to_str().unwrap(),
        "--heatmap",
        "rays:camera",
    ]);
    let (w, _, values) = counts(&d.join("part.heatmap.exr"));
    let lit: Vec<usize> = (0..w as usize).filter(|&x| values[x] == 1.0).collect();
    assert!(!lit.is_empty() && lit.len() < 40, "{lit:?}");
    assert!(values.iter().all(|&v| v == 0.0 || v == 1.0));
}

#[test]
fn counts_do_not_depend_on_threads_and_the_legend_ends_at_the_max() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for kind in ["nodes", "prims:shadow", "rays"] {
        let linear = ["--heatmap-scale", "linear", "--heatmap", kind];
        let one = heatmap(d, "one", &[&["--threads", "1"], &linear[..]].concat());
        let two = heatmap(d, "two", &[&["--threads", "2"], &linear[..]].concat());
        let (a, b) = (counts(&one[1]).2, counts(&two[1]).2);
        assert!(a == b, "{kind}");
        let max = a.iter().copied().fold(0.0, f32::max);
        assert!(max > 0.0, "{kind}");
        let rays = kind.split_once(':').map_or("all", |(_, k)| k);
        let s = summary(&one[2]);
        assert_eq!(
            s["per_pixel"][rays]["max"].as_f64(),
            Some(f64::from(max)),
            "{kind}"
        );
        assert_eq!(s["scale"], "linear", "{kind}");
        assert_eq!(s["scale_top"].as_f64(), Some(f64::from(max)), "{kind}");
    }
}

#[test]
fn what_cannot_be_counted_is_a_usage_error() {
    let err = fails(&["render", "--heatmap", "steps", "-o", "/nonexistent/x.png"], 2);
    assert!(
        err.contains("unknown heatmap \"steps\": expected nodes, prims or rays"),
        "{err}"
    );
    let err = fails(
        &["render", "--heatmap", "nodes:diffuse", "-o", "/nonexistent/x.png"],
        2,
    );
    assert!(err.contains("unknown ray kind \"diffuse\""), "{err}");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let err = fails(
        &[
            "render",
            "--heatmap",
            "nodes",
            "--resume",
            "-o",
            out.to_str().unwrap(),
        ],
        2,
    );
    assert!(
        err.contains("--heatmap counts the rays of one whole run"),
        "{err}"
    );
    // A name the heatmap would take, held by a directory, is refused before the render.
    std::fs::create_dir(dir.path().join("x.heatmap.exr")).unwrap();
    let err = fails(&["render", "--heatmap", "nodes", "-o", out.to_str().unwrap()], 1);
    assert!(err.contains("x.heatmap.exr: is not a regular file"), "{err}");
    assert!(!out.exists());
}

/// The default scale (log(1 + count) to the p99) on the dragon, whose costs are skewed (the median a
/// few nodes, the costliest pixels dozens of times more): its median pixel lies above a fifth of the
/// colour bar, where the linear scale to the max leaves it in the bottom tenth. The JSON's scale top
/// is its p99, and the PNG is the library's drawing of the `.exr` counts on the scale the JSON names,
/// legend (numbers, `>=` at the clamp, "log scale to p99, max N") included.
#[test]
fn the_default_scale_spreads_the_dragons_costs_over_the_colours() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d.png");
    let args = [
        "render",
        "scenes/dragon.p3f",
        "--width",
        "160",
        "-q",
        "--heatmap",
        "nodes",
    ];
    stdout(&[&args[..], &["-o", out.to_str().unwrap()]].concat());
    let [png, exr, json] = ["png", "exr", "json"].map(|e| dir.path().join(format!("d.heatmap.{e}")));
    let (w, h, values) = counts(&exr);
    let s = summary(&json);
    let all = &s["per_pixel"]["all"];
    let (median, p99, max) = (
        all["median"].as_f64().unwrap(),
        all["p99"].as_f64().unwrap(),
        all["max"].as_f64().unwrap(),
    );
    let mut sorted = values.clone();
    sorted.sort_by(f32::total_cmp);
    assert_eq!(f64::from(sorted[nearest_rank(sorted.len(), 50)]), median);
    assert_eq!(s["scale"], "log:p99");
    assert_eq!(s["scale_top"].as_f64(), Some(p99));
    assert!(p99 < max, "the clamp is marked: {p99} < {max}");
    let position = median.ln_1p() / p99.ln_1p();
    assert!(
        position > 0.2 && median / max < 0.1,
        "median {median}, p99 {p99}, max {max}: {position}"
    );

    let map = Heatmap {
        width: w,
        height: h,
        values,
        what: s["measure"].as_str().unwrap().into(),
        scale: s["scale"].as_str().unwrap().parse().unwrap(),
    };
    let ramp = map.ramp();
    assert_eq!(ramp.top, p99 as f32);
    assert!((f64::from(ramp.position(median as f32)) - position).abs() < 1e-6);
    let ours = dir.path().join("ours.png");
    map.write_png(&ours).unwrap();
    let img = rgb(&png);
    assert!(
        img == rgb(&ours),
        "the PNG is the counts drawn on the JSON's scale"
    );
    let x0 = (img.width() - w) / 2;
    for (i, &v) in map.values.iter().enumerate() {
        let (x, y) = (i as u32 % w, i as u32 / w);
        assert_eq!(img.get_pixel(x0 + x, y), viridis(ramp.position(v)));
    }
}

/// `--heatmap-scale` takes `linear`, `log`, `pNN` and `log:pNN`, each named in the JSON with the count
/// at the top of its colour bar: the max, or that percentile of the counts (nearest rank); anything
/// else, or the option without `--heatmap`, is a usage error that lists the accepted forms.
#[test]
fn the_scale_option_parses_and_the_json_says_which() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let [_, exr, json] = heatmap(d, "default", &["--heatmap", "nodes"]);
    let (_, _, values) = counts(&exr);
    let ramp = |scale: &str| Ramp::new(scale.parse::<Scale>().unwrap(), &values);
    let s = summary(&json);
    assert_eq!(s["scale"], Scale::default().to_string());
    assert_eq!(s["scale_top"], s["per_pixel"]["all"]["p99"]);
    let keys: Vec<&String> = s.as_object().unwrap().keys().collect();
    assert_eq!(
        keys,
        ["measure", "width", "height", "per_pixel", "scale", "scale_top"],
        "the scale comes after the counts"
    );
    for (scale, top) in [
        ("linear", "max"),
        ("log", "max"),
        ("p50", "median"),
        ("p99", "p99"),
        ("log:p50", "median"),
        ("p90", ""),
    ] {
        let [_, exr, json] = heatmap(d, "s", &["--heatmap", "nodes", "--heatmap-scale", scale]);
        assert_eq!(
            counts(&exr).2,
            values,
            "{scale}: the counts do not depend on the scale"
        );
        let s = summary(&json);
        assert_eq!(s["scale"], scale);
        assert_eq!(
            s["scale_top"].as_f64(),
            Some(f64::from(ramp(scale).top)),
            "{scale}"
        );
        if !top.is_empty() {
            assert_eq!(s["scale_top"], s["per_pixel"]["all"][top], "{scale}");
        }
    }
    for bad in ["p100", "p0", "log:linear", "sqrt"] {
        let err = fails(
            &[
                "render",
                "--heatmap",
                "nodes",
                "--heatmap-scale",
                bad,
                "-o",
                "/nonexistent/x.png",
            ],
            2,
        );
        assert!(
            err.contains(&format!(
                "unknown heatmap scale \"{bad}\": expected linear, log, pNN or log:pNN, NN a percentile from 1 to 99"
            )),
            "{err}"
        );
    }
    let err = fails(
        &["render", "--heatmap-scale", "log", "-o", "/nonexistent/x.png"],
        2,
    );
    assert!(err.contains("--heatmap <KIND>"), "{err}");
}
