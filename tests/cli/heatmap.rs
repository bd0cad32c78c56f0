//! `render --heatmap`: exact per-pixel counts where they are known in closed form (brute force tests
//! every primitive for every ray; each pixel sends its samples' camera rays), the same on any number of
//! threads, with `--passes` and `--tiles`, the legend's scale equal to the raw file's largest value,
//! and usage errors for what cannot be counted.

use std::path::Path;

use serde_json::Value;

use crate::common::{fails, json, stdout};

/// The raw counts of a heatmap's `.exr` (one value per pixel, in all three channels).
fn counts(path: &Path) -> (u32, u32, Vec<f32>) {
    let img = image::open(path).unwrap().to_rgb32f();
    let values = img.pixels().map(|p| {
        assert!(p.0[0] == p.0[1] && p.0[1] == p.0[2], "{p:?}");
        p.0[0]
    });
    (img.width(), img.height(), values.collect())
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
    for kernel in ["single", "packet", "stream"] {
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
        let img = image::open(&png).unwrap();
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
        let one = heatmap(d, "one", &["--threads", "1", "--heatmap", kind]);
        let two = heatmap(d, "two", &["--threads", "2", "--heatmap", kind]);
        let (a, b) = (counts(&one[1]).2, counts(&two[1]).2);
        assert!(a == b, "{kind}");
        let max = a.iter().copied().fold(0.0, f32::max);
        assert!(max > 0.0, "{kind}");
        let rays = kind.split_once(':').map_or("all", |(_, k)| k);
        assert_eq!(
            summary(&one[2])["per_pixel"][rays]["max"].as_f64(),
            Some(f64::from(max)),
            "{kind}"
        );
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
