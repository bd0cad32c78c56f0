//! Every documented option of `render`, `info`, `bench` and `merge` checked by a value it must change
//! or keep: an image that must differ from, or equal, another; a count; an exit status and its message.
//! Expectations come from the scene files read here (counts, resolutions), from formulas written here
//! (the sRGB curve, the PNG chunk layout) or from a second render that the README says must give the
//! same bytes, never from the code under test alone. Renders are tiny (32x24 and thereabouts).

use std::path::{Path, PathBuf};

use serde_json::Value;

use crate::common::images::rgb;
use crate::common::{self, fails, int, json, ok, root, stdout};

/// The built-in scene's file: a glass ball, a mirror ball (no roughness given), a copper box and a red
/// ball on a floor, 640x480, spp 0.
const DEFAULT: &str = "scenes/default.p3f";
/// A lens (aperture 12, focal 1.5) and spp 4.
const DOF: &str = "scenes/dof.p3f";

/// A usage error: exit status 2, and clap's first line is `error: invalid value 'VALUE' for
/// 'OPTION <NAME>': MESSAGE` (MESSAGE left out when `message` is empty: clap then lists the values).
fn usage_error(args: &[&str], first_line: &str) -> String {
    let err = fails(args, 2);
    assert_eq!(err.lines().next(), Some(first_line), "{err}");
    err
}

/// [`usage_error`] of `whitted render ARGS`, whose output is in a directory that does not exist: a
/// render that took the arguments writes nothing (and fails at the output, if not before).
fn render_usage(args: &[&str], first_line: &str) -> String {
    let never = ["-o", "/nonexistent/whitted-usage-error.png"];
    usage_error(&[&["render"][..], args, &never].concat(), first_line)
}

/// Renders `args` quietly to `dir/name` and returns the file's path.
fn render(dir: &Path, name: &str, args: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let out_s = out.to_str().unwrap();
    ok(&[&["render", "-q", "-o", out_s][..], args].concat());
    out
}

/// The bytes of a file.
fn bytes(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The chunks of a PNG file, read from its bytes: (type, data), after checking the signature and each
/// chunk's length.
fn png_chunks(png: &[u8]) -> Vec<(String, Vec<u8>)> {
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "the PNG signature");
    let mut chunks = Vec::new();
    let mut at = 8;
    while at < png.len() {
        let len = u32::from_be_bytes(png[at..at + 4].try_into().unwrap()) as usize;
        let kind = String::from_utf8(png[at + 4..at + 8].to_vec()).unwrap();
        assert!(at + 12 + len <= png.len(), "chunk {kind} runs past the file");
        chunks.push((kind, png[at + 8..at + 8 + len].to_vec()));
        at += 12 + len;
    }
    assert_eq!(at, png.len());
    chunks
}

/// A PNG's width and height, from its IHDR chunk.
fn png_size(path: &Path) -> (u32, u32) {
    let chunks = png_chunks(&bytes(path));
    let (kind, ihdr) = &chunks[0];
    assert_eq!(kind, "IHDR");
    let be = |i: usize| u32::from_be_bytes(ihdr[i..i + 4].try_into().unwrap());
    (be(0), be(4))
}

/// The numbers on the first line of `scene` that starts with `keyword`.
fn scene_line(scene: &str, keyword: &str) -> Vec<f64> {
    let text = std::fs::read_to_string(root().join(scene)).unwrap();
    let line = text
        .lines()
        .find(|l| l.split_whitespace().next() == Some(keyword))
        .unwrap_or_else(|| panic!("{scene} has no `{keyword}` line"));
    line.split_whitespace()
        .skip(1)
        .map(|w| w.parse().unwrap())
        .collect()
}

/// `render --stats=json`'s object for `args` (the image goes to `dir/stats.png`).
fn stats(dir: &Path, args: &[&str]) -> Value {
    let out = dir.join("stats.png");
    json(
        &[
            &["render", "-q", "--stats=json", "-o", out.to_str().unwrap()][..],
            args,
        ]
        .concat(),
    )
}

const SMALL: [&str; 4] = ["--width", "32", "--height", "24"];

fn small<'a>(scene: &'a str, more: &[&'a str]) -> Vec<&'a str> {
    [&[scene][..], &SMALL, more].concat()
}

#[test]
fn max_depth_bounds_the_bounces_and_refuses_more_than_64() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let default = bytes(&render(d, "default.png", &small(DEFAULT, &[])));
    let six = bytes(&render(d, "six.png", &small(DEFAULT, &["--max-depth", "6"])));
    let one = bytes(&render(d, "one.png", &small(DEFAULT, &["--max-depth", "1"])));
    let zero = bytes(&render(d, "zero.png", &small(DEFAULT, &["--max-depth", "0"])));
    // The default is 6 bounces; fewer change what the mirror and the glass show.
    assert!(default == six, "the default depth is not 6");
    assert!(one != default, "--max-depth 1 draws the default image");
    assert!(zero != one, "--max-depth 0 draws --max-depth 1's image");
    // At depth 0 no ray leaves a surface but the shadow rays; at 1 the mirror and glass send some.
    let rays = |depth: &str| stats(d, &small(DEFAULT, &["--max-depth", depth]))["rays"].clone();
    let (r0, r1) = (rays("0"), rays("1"));
    assert_eq!((int(&r0["reflected"]), int(&r0["refracted"])), (0, 0), "{r0}");
    assert!(int(&r1["reflected"]) > 0 && int(&r1["refracted"]) > 0, "{r1}");
    assert_eq!(
        int(&stats(d, &small(DEFAULT, &["--max-depth", "64"]))["max_depth"]),
        64
    );

    let out = d.join("deep.png");
    let args = small(DEFAULT, &["--max-depth", "65", "-q", "-o", out.to_str().unwrap()]);
    // Out of range is a usage error (status 2), refused by the argument parser with clap's words.
    let err = fails(&[&["render"][..], &args].concat(), 2);
    assert!(
        err.contains("invalid value '65' for '--max-depth") && err.contains("65 is not in 0..=64"),
        "{err}"
    );
    assert!(!out.exists());
}

/// Every `--accel` value gives the default image byte for byte, and the report names the structure
/// built; an unknown one is a usage error naming the accepted values.
#[test]
fn accel_values_give_the_same_bytes_and_build_what_they_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let default = bytes(&render(d, "default.png", &small(DEFAULT, &[])));
    for kind in ["none", "grid", "bvh2", "bvh4", "bvh8", "auto"] {
        let image = bytes(&render(
            d,
            &format!("{kind}.png"),
            &small(DEFAULT, &["--accel", kind]),
        ));
        assert!(image == default, "--accel {kind} changes the image");
        let built = stats(d, &small(DEFAULT, &["--accel", kind]))["accel"].clone();
        let built = built.as_str().unwrap();
        if kind == "auto" {
            assert!(["bvh8", "bvh4"].contains(&built), "auto built {built}");
        } else {
            assert_eq!(built, kind);
        }
    }
    render_usage(
        &small(DEFAULT, &["--accel", "kd"]),
        "error: invalid value 'kd' for '--accel <ACCEL>': unknown accelerator \"kd\": expected none, \
         grid, bvh2, bvh4, bvh8 or auto",
    );
}

#[test]
fn kernels_give_the_same_bytes_and_an_unknown_one_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut images = Vec::new();
    for kernel in ["single", "packet"] {
        let args = small(DEFAULT, &["--kernel", kernel, "--accel", "bvh4", "--spp", "4"]);
        images.push(bytes(&render(d, &format!("{kernel}.png"), &args)));
        assert_eq!(stats(d, &args)["kernel"], kernel);
    }
    assert!(
        images.iter().all(|i| *i == images[0]),
        "the kernels' images differ"
    );
    // The default is packets.
    assert_eq!(stats(d, &small(DEFAULT, &[]))["kernel"], "packet");
    render_usage(
        &small(DEFAULT, &["--kernel", "simd"]),
        "error: invalid value 'simd' for '--kernel <KERNEL>': unknown kernel \"simd\": expected single \
         or packet",
    );
}

/// Every builder and bin count gives the same image (all accelerators are exact); `--bins` outside
/// 2..=64 and an unknown builder are usage errors.
#[test]
fn build_and_bins_give_the_same_bytes_and_are_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = "scenes/balls_low.p3f";
    let default = bytes(&render(d, "default.png", &small(scene, &[])));
    for (name, extra) in [
        ("midpoint", &["--accel", "bvh2", "--build", "midpoint"][..]),
        ("sah2", &["--accel", "bvh2", "--build", "sah", "--bins", "2"]),
        ("optimized2", &["--accel", "bvh2", "--build", "optimized"]),
        ("bvh8sah", &["--accel", "bvh8", "--build", "sah"]),
        ("sah64", &["--accel", "bvh2", "--bins", "64"]),
        ("bvh4bins2", &["--accel", "bvh4", "--bins", "2"]),
        ("bvh8bins64", &["--accel", "bvh8", "--bins", "64"]),
    ] {
        let image = bytes(&render(d, &format!("{name}.png"), &small(scene, extra)));
        assert!(image == default, "{extra:?} changes the image");
    }
    for bins in ["1", "65"] {
        render_usage(
            &small(scene, &["--bins", bins]),
            &format!("error: invalid value '{bins}' for '--bins <BINS>': {bins} is not in 2..=64"),
        );
    }
    let err = render_usage(
        &small(scene, &["--build", "median"]),
        "error: invalid value 'median' for '--build <BUILD>'",
    );
    assert!(
        err.contains("[possible values: auto, sah, optimized, midpoint]"),
        "{err}"
    );
}

/// `--focal` moves the focal plane of the lens: with the file's aperture the image changes with it
/// (and the file's own focal distance gives the file's image); through a pinhole it changes nothing.
#[test]
fn focal_moves_the_focal_plane_of_a_lens_only() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // The file's lens: aperture 12, focal 1.5, spp 4.
    assert_eq!(scene_line(DOF, "aperture"), [12.0]);
    assert_eq!(scene_line(DOF, "focal"), [1.5]);
    let file = bytes(&render(d, "file.png", &small(DOF, &[])));
    let same = bytes(&render(d, "same.png", &small(DOF, &["--focal", "1.5"])));
    let near = bytes(&render(d, "near.png", &small(DOF, &["--focal", "0.5"])));
    let far = bytes(&render(d, "far.png", &small(DOF, &["--focal", "3"])));
    assert!(same == file, "--focal 1.5, the file's, changes the image");
    assert!(
        near != file && far != file && near != far,
        "--focal changes nothing"
    );
    let pinhole = ["--aperture", "0"];
    let a = bytes(&render(
        d,
        "p1.png",
        &small(DOF, &[&pinhole[..], &["--focal", "0.5"]].concat()),
    ));
    let b = bytes(&render(
        d,
        "p2.png",
        &small(DOF, &[&pinhole[..], &["--focal", "3"]].concat()),
    ));
    assert!(a == b, "a pinhole's image depends on --focal");
    assert!(a != near, "--aperture 0 keeps the lens");
    for bad in ["0", "-1"] {
        render_usage(
            &small(DOF, &[&format!("--focal={bad}")]),
            &format!(
                "error: invalid value '{bad}' for '--focal <FOCAL>': expected a number above 0, found {bad}"
            ),
        );
    }
}

/// `--roughness` roughens the mirrors whose material gives no roughness: the default scene's mirror
/// changes with 0.3, and 0 is the default; a mirror whose `f` line gives its own roughness (0) keeps
/// its image.
#[test]
fn roughness_roughens_mirrors_without_their_own() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let default = bytes(&render(d, "default.png", &small(DEFAULT, &[])));
    let zero = bytes(&render(d, "zero.png", &small(DEFAULT, &["--roughness", "0"])));
    let rough = bytes(&render(d, "rough.png", &small(DEFAULT, &["--roughness", "0.3"])));
    let rougher = bytes(&render(
        d,
        "rougher.png",
        &small(DEFAULT, &["--roughness", "0.6"]),
    ));
    assert!(zero == default, "--roughness 0 is not the default");
    assert!(
        rough != default && rougher != rough,
        "--roughness changes nothing"
    );

    // The same scene with a 12th number, roughness 0, on every `f` line: --roughness leaves it alone.
    let text = std::fs::read_to_string(root().join(DEFAULT)).unwrap();
    let own: String = text
        .lines()
        .map(|l| {
            if l.starts_with("f ") {
                assert_eq!(l.split_whitespace().count(), 12, "{l}: 11 numbers");
                format!("{l} 0\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    let scene = d.join("own.p3f");
    std::fs::write(&scene, own).unwrap();
    let scene = scene.to_str().unwrap();
    let own0 = bytes(&render(d, "own0.png", &small(scene, &[])));
    let own3 = bytes(&render(d, "own3.png", &small(scene, &["--roughness", "0.3"])));
    assert!(own0 == default, "a 12th number 0 changes the image");
    assert!(own3 == own0, "--roughness overrides a material's own roughness");
    render_usage(
        &small(DEFAULT, &["--roughness=-0.1"]),
        "error: invalid value '-0.1' for '--roughness <ROUGHNESS>': expected a number of at least 0, found -0.1",
    );
}

/// IEC 61966-2-1's sRGB transfer function of a linear value, clamped to [0, 1].
fn srgb(v: f64) -> f64 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// `--srgb`: each byte is the sRGB curve of the linear render's value (its EXR, which keeps floats)
/// within 1/255, where the default PNG holds the linear value itself; the PNG says which: an `sRGB`
/// chunk (rendering intent 0, perceptual) with `--srgb`, a `gAMA` chunk of gamma 1.0 (100000) without.
#[test]
fn srgb_encodes_with_the_srgb_curve_and_says_so_in_the_png() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let args = small(DEFAULT, &["--spp", "4"]);
    let (width, height, linear) = common::images::exr(&render(d, "linear.exr", &args));
    let plain = render(d, "linear.png", &args);
    let encoded = render(d, "srgb.png", &[&args[..], &["--srgb"]].concat());
    let (plain_px, encoded_px) = (rgb(&plain), rgb(&encoded));
    assert_eq!((width, height), (32, 24));
    let (mut checked, mut apart) = (0, 0);
    for ((l, p), s) in linear.iter().zip(plain_px.pixels()).zip(encoded_px.pixels()) {
        for c in 0..3 {
            let v = f64::from(l[c]);
            let want_linear = 255.0 * v.clamp(0.0, 1.0);
            let want_srgb = 255.0 * srgb(v);
            assert!(
                (f64::from(p[c]) - want_linear).abs() <= 1.0,
                "linear {v}: {}",
                p[c]
            );
            assert!(
                (f64::from(s[c]) - want_srgb).abs() <= 1.0,
                "sRGB of {v}: {}",
                s[c]
            );
            checked += 1;
            apart += usize::from(p[c] != s[c]);
        }
    }
    assert_eq!(checked, 32 * 24 * 3);
    assert!(
        apart > checked / 2,
        "the curve changes most values: {apart} of {checked}"
    );

    let kinds = |png: &Path| -> Vec<(String, Vec<u8>)> { png_chunks(&bytes(png)) };
    let find = |chunks: &[(String, Vec<u8>)], kind: &str| {
        chunks
            .iter()
            .find(|(k, _)| k == kind)
            .map(|(_, data)| data.clone())
    };
    let (p, s) = (kinds(&plain), kinds(&encoded));
    assert_eq!(find(&p, "gAMA"), Some(100_000u32.to_be_bytes().to_vec()));
    assert_eq!(find(&p, "sRGB"), None);
    assert_eq!(find(&s, "sRGB"), Some(vec![0]));
    assert_eq!(find(&s, "gAMA"), None);
    // Both before the image data, as the PNG specification requires.
    for chunks in [&p, &s] {
        let idat = chunks.iter().position(|(k, _)| k == "IDAT").unwrap();
        let colour = chunks
            .iter()
            .position(|(k, _)| k == "gAMA" || k == "sRGB")
            .unwrap();
        assert!(
            colour < idat,
            "{:?}",
            chunks.iter().map(|c| &c.0).collect::<Vec<_>>()
        );
    }
}

/// `--partial` writes the frame's sums under any name, and `whitted merge` turns that one part into
/// the direct render's bytes; `merge --srgb` into `render --srgb`'s.
#[test]
fn partial_merges_into_the_direct_render_with_and_without_srgb() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let args = small("scenes/distribution.p3f", &["--spp", "4"]);
    let direct = bytes(&render(d, "direct.png", &args));
    let direct_srgb = bytes(&render(d, "direct-srgb.png", &[&args[..], &["--srgb"]].concat()));
    // A name that is no image's: --partial says what to write.
    let part = render(d, "frame.sums", &[&args[..], &["--partial"]].concat());
    let sums = bytes(&part);
    assert!(!sums.starts_with(b"\x89PNG"), "a .partial file, not a PNG");
    let part = part.to_str().unwrap();
    let merged = d.join("merged.png");
    let merged_srgb = d.join("merged-srgb.png");
    ok(&["merge", "-q", merged.to_str().unwrap(), part]);
    ok(&["merge", "-q", merged_srgb.to_str().unwrap(), part, "--srgb"]);
    assert!(bytes(&merged) == direct, "merge differs from the direct render");
    assert!(
        bytes(&merged_srgb) == direct_srgb,
        "merge --srgb differs from render --srgb"
    );
    assert!(direct != direct_srgb);
}

/// `--height` alone keeps the scene file's aspect ratio: the width follows its `resolution` line.
#[test]
fn height_alone_keeps_the_files_aspect_ratio() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let file = scene_line(DEFAULT, "resolution");
    assert_eq!(file, [640.0, 480.0]);
    for h in [24u32, 30, 7] {
        let out = render(d, &format!("h{h}.png"), &[DEFAULT, "--height", &h.to_string()]);
        let (w, got_h) = png_size(&out);
        assert_eq!(got_h, h);
        let want = f64::from(h) * file[0] / file[1];
        // A fraction of a pixel is rounded one way or the other; a whole one is exact.
        assert!(
            (f64::from(w) - want).abs() < 1.0,
            "--height {h}: {w} wide, want {want}"
        );
        if want.fract() == 0.0 {
            assert_eq!(f64::from(w), want, "--height {h}");
        }
    }
    // A wide frame, 200x70: --height 10 is 28.6 pixels wide.
    let wide = d.join("wide.p3f");
    let text = std::fs::read_to_string(root().join(DEFAULT)).unwrap();
    std::fs::write(&wide, text.replace("resolution 640 480", "resolution 200 70")).unwrap();
    let out = render(d, "wide.png", &[wide.to_str().unwrap(), "--height", "10"]);
    let (w, h) = png_size(&out);
    assert_eq!(h, 10);
    assert!((f64::from(w) - 200.0 * 10.0 / 70.0).abs() < 1.0, "{w}");
    // And --width alone, the other way.
    let out = render(d, "w.png", &[DEFAULT, "--width", "48"]);
    assert_eq!(png_size(&out), (48, 36));
}

/// Any thread count gives the same bytes and the report counts the threads asked for; 0 is a usage
/// error.
#[test]
fn threads_give_the_same_bytes_and_zero_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let args = small("scenes/distribution.p3f", &["--spp", "4"]);
    let one = bytes(&render(d, "one.png", &[&args[..], &["--threads", "1"]].concat()));
    let three = bytes(&render(
        d,
        "three.png",
        &[&args[..], &["--threads", "3"]].concat(),
    ));
    assert!(one == three, "the image depends on the thread count");
    for n in ["1", "3"] {
        assert_eq!(
            int(&stats(d, &small(DEFAULT, &["--threads", n]))["threads"]).to_string(),
            n
        );
    }
    render_usage(
        &small(DEFAULT, &["--threads", "0"]),
        "error: invalid value '0' for '--threads <THREADS>': 0 is not in 1..=1024",
    );
}

/// One rule for the exit status: a value out of its range is a usage error,
/// status 2, refused by the argument parser before the scene is read, for `--spp`, `--width`,
/// `--height` and `--fov` as for `--threads` and `--max-depth` (they were status 1, found by the
/// render's checks); so are the command line's faults found once the scene is read: options that do
/// not go together, and overrides that make an impossible frame or camera.
#[test]
fn every_option_out_of_range_is_a_usage_error() {
    let invalid = |value: &str, option: &str, message: &str| {
        format!("error: invalid value '{value}' for '{option}': {message}")
    };
    let angle = |v: &str| format!("expected an angle between 0 and 180 degrees (both excluded), found {v}");
    for (args, first_line) in [
        (
            ["--spp", "70000"],
            invalid("70000", "--spp <SPP>", "70000 is not in 0..=65536"),
        ),
        (
            ["--width", "0"],
            invalid("0", "--width <WIDTH>", "0 is not in 1..=65536"),
        ),
        (
            ["--width", "100000"],
            invalid("100000", "--width <WIDTH>", "100000 is not in 1..=65536"),
        ),
        (
            ["--height", "0"],
            invalid("0", "--height <HEIGHT>", "0 is not in 1..=65536"),
        ),
        (["--fov", "0"], invalid("0", "--fov <DEG>", &angle("0"))),
        (["--fov", "180"], invalid("180", "--fov <DEG>", &angle("180"))),
    ] {
        render_usage(&[&[DEFAULT][..], &args].concat(), &first_line);
        usage_error(
            &[&["bench", DEFAULT, "--frames", "1"][..], &args].concat(),
            &first_line,
        );
    }
    // Found once the scene is read: the height that --width gives the file's 4:3 aspect ratio, a
    // camera the overrides make impossible, options that do not go together. One line, status 2, and
    // no image.
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    for (args, last) in [
        (
            &["--width", "65536"][..],
            "whitted: resolution 65536x49152 has more than 268435456 pixels",
        ),
        (
            &["--from", "1,2,3", "--at", "1,2,3"],
            "whitted: the camera of --from/--at/--up/--fov: \"from\" and \"at\" are the same point (1 2 3)",
        ),
        (
            &["--every", "2"],
            "whitted: --every and --progressive-out need --passes 2 or more",
        ),
    ] {
        let render = ["render", DEFAULT, "-o", out.to_str().unwrap()];
        let err = fails(&[&render[..], args].concat(), 2);
        assert_eq!(err.lines().last(), Some(last), "{err}");
        assert!(!out.exists());
    }
}

/// A negative value of a numeric option is read as a value, not as an option of its own (clap's refusal
/// of which tells the user to write `-- -1`, which fails too): it is a usage error that gives the
/// option's range, for every numeric option of every subcommand (`merge` has none). `--aperture -0` is
/// 0.
#[test]
fn negative_values_are_refused_with_the_range_of_their_option() {
    let ranged = |option: &str, value: &str, message: &str| {
        format!("error: invalid value '{value}' for '{option}': {message}")
    };
    let range = |option: &str, r: &str| ranged(option, "-1", &format!("-1 is not in {r}"));
    let at_least_0 = "expected a number of at least 0, found -1";
    let frame = [
        ("--width", range("--width <WIDTH>", "1..=65536")),
        ("--height", range("--height <HEIGHT>", "1..=65536")),
        ("--threads", range("--threads <THREADS>", "1..=1024")),
        ("--max-depth", range("--max-depth <MAX_DEPTH>", "0..=64")),
        ("--spp", range("--spp <SPP>", "0..=65536")),
        (
            "--fov",
            ranged(
                "--fov <DEG>",
                "-1",
                "expected an angle between 0 and 180 degrees (both excluded), found -1",
            ),
        ),
    ];
    let render_only = [
        ("--bins", range("--bins <BINS>", "2..=64")),
        ("--seed", range("--seed <SEED>", "0..=18446744073709551615")),
        ("--passes", range("--passes <PASSES>", "1..=4294967295")),
        ("--every", range("--every <EVERY>", "1..=4294967295")),
        ("--aperture", ranged("--aperture <APERTURE>", "-1", at_least_0)),
        ("--roughness", ranged("--roughness <ROUGHNESS>", "-1", at_least_0)),
        (
            "--focal",
            ranged("--focal <FOCAL>", "-1", "expected a number above 0, found -1"),
        ),
    ];
    let no_tip = |err: &str| assert!(!err.contains("-- -"), "{err}");
    for (option, first_line) in frame.iter().chain(&render_only) {
        no_tip(&render_usage(&[DEFAULT, option, "-1"], first_line));
    }
    for (option, first_line) in frame
        .iter()
        .chain(&[("--frames", range("--frames <FRAMES>", "1..=4294967295"))])
    {
        no_tip(&usage_error(&["bench", DEFAULT, option, "-1"], first_line));
    }
    no_tip(&usage_error(
        &["info", DEFAULT, "--bins", "-1"],
        &range("--bins <BINS>", "2..=64"),
    ));
    #[cfg(feature = "view")]
    for (option, range_of) in [
        ("--width", "1..=65536"),
        ("--height", "1..=65536"),
        ("--threads", "1..=1024"),
        ("--max-depth", "0..=32"),
        ("--frames", "1..=4294967295"),
    ] {
        let name = option.trim_start_matches("--").replace('-', "_").to_uppercase();
        let first_line = range(&format!("{option} <{name}>"), range_of);
        no_tip(&usage_error(&["view", DEFAULT, option, "-1"], &first_line));
    }
    // Values that are not one number: a part and a pass range.
    for (args, first_line) in [
        (
            ["--tiles", "-1/2"],
            ranged(
                "--tiles <K/N>",
                "-1/2",
                "part -1/2 does not exist: K counts from 0 to N-1",
            ),
        ),
        (
            ["--passes-range", "-1..2"],
            ranged(
                "--passes-range <A..B>",
                "-1..2",
                "the pass range -1..2 starts before pass 0: passes count from 0",
            ),
        ),
        (
            ["--passes-range", "0..-2"],
            ranged("--passes-range <A..B>", "0..-2", "the pass range 0..-2 is empty"),
        ),
    ] {
        no_tip(&render_usage(&[&[DEFAULT][..], &args].concat(), &first_line));
    }
    // Forms of a negative number that are not digits alone.
    render_usage(
        &[DEFAULT, "--aperture", "-.5"],
        &ranged(
            "--aperture <APERTURE>",
            "-.5",
            "expected a number of at least 0, found -.5",
        ),
    );
    render_usage(
        &[DEFAULT, "--roughness", "-inf"],
        &ranged(
            "--roughness <ROUGHNESS>",
            "-inf",
            "expected a finite number, found -inf",
        ),
    );
    // -0 is 0: the pinhole's image, byte for byte.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let zero = render(d, "zero.png", &small(DOF, &["--aperture", "0"]));
    let minus_zero = render(d, "minus_zero.png", &small(DOF, &["--aperture", "-0"]));
    assert!(bytes(&zero) == bytes(&minus_zero), "--aperture -0 is not 0");
}

/// What a scene file holds, counted from its text as `info` documents it: spheres, triangles (a
/// polygon of N vertices is N - 2), boxes, planes, cones, point lights, area lights, and materials (one
/// per `f`, plus the default grey one when an object comes before the first `f`).
fn count_scene(text: &str) -> [(&'static str, u64); 8] {
    let (mut spheres, mut triangles, mut boxes, mut planes, mut cones) = (0, 0, 0, 0, 0);
    let (mut points, mut areas, mut materials, mut object_before_f) = (0, 0, 0, false);
    for line in text.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        let object = match words.first().copied() {
            Some("s") => {
                spheres += 1;
                true
            }
            Some("p" | "pp") => {
                triangles += words[1].parse::<u64>().unwrap() - 2;
                true
            }
            Some("box") => {
                boxes += 1;
                true
            }
            Some("pl") => {
                planes += 1;
                true
            }
            Some("c") => {
                cones += 1;
                true
            }
            Some("l") => {
                points += 1;
                false
            }
            Some("lq") => {
                areas += 1;
                false
            }
            Some("f") => {
                materials += 1;
                false
            }
            _ => false,
        };
        object_before_f |= object && materials == 0;
    }
    [
        ("spheres", spheres),
        ("triangles", triangles),
        ("boxes", boxes),
        ("planes", planes),
        ("cones", cones),
        ("point lights", points),
        ("area lights", areas),
        ("materials", materials + u64::from(object_before_f)),
    ]
}

/// `info`'s text as (label, value) pairs: the label is the words before the column of values.
fn info_fields(text: &str) -> Vec<(String, String)> {
    text.lines()
        .filter(|l| !l.starts_with(' '))
        .map(|l| {
            let (label, value) = l.split_at(14.min(l.len()));
            (label.trim().to_string(), value.trim().to_string())
        })
        .collect()
}

fn field<'a>(fields: &'a [(String, String)], label: &str) -> &'a str {
    fields
        .iter()
        .find(|(l, _)| l == label)
        .map(|(_, v)| v.as_str())
        .unwrap_or_else(|| panic!("no `{label}` line: {fields:?}"))
}

#[test]
fn info_text_counts_what_the_scene_file_holds() {
    for scene in [
        DEFAULT,
        "scenes/distribution.p3f",
        "scenes/balls_low.p3f",
        "scenes/spd/jacks_1.nff",
        "scenes/spd/rings_1.nff",
    ] {
        let text = std::fs::read_to_string(root().join(scene)).unwrap();
        let fields = info_fields(&stdout(&["info", scene]));
        assert_eq!(field(&fields, "scene"), scene);
        let mut nonzero = 0;
        for (label, want) in count_scene(&text) {
            let got: u64 = field(&fields, label).parse().unwrap();
            assert_eq!(got, want, "{scene}: {label}");
            nonzero += usize::from(want > 0);
        }
        assert!(nonzero >= 3, "{scene}: a scene with something in it");
        let res = scene_line(scene, "resolution");
        assert_eq!(
            field(&fields, "resolution"),
            format!("{}x{}", res[0], res[1]),
            "{scene}"
        );
        let camera = field(&fields, "camera");
        let from = scene_line(scene, "from");
        let from = format!("from [{}, {}, {}]", from[0], from[1], from[2]);
        assert!(camera.starts_with(&from), "{scene}: {camera}, want {from}");
        assert!(
            camera.contains(&format!("fov {}°", scene_line(scene, "angle")[0])),
            "{scene}: {camera}"
        );
    }
    // The files' counts, read by hand, so that the counter above is checked too.
    let text = std::fs::read_to_string(root().join(DEFAULT)).unwrap();
    let counts: Vec<u64> = count_scene(&text).iter().map(|c| c.1).collect();
    assert_eq!(counts, [3, 2, 1, 0, 0, 2, 0, 5]);
    let text = std::fs::read_to_string(root().join("scenes/distribution.p3f")).unwrap();
    assert_eq!(count_scene(&text)[6], ("area lights", 1));
}

/// `info --accel KIND`'s last lines: `accelerator   KIND: ...` and `build time    S s`.
fn info_accel(scene: &str, extra: &[&str]) -> String {
    let text = stdout(&[&["info", scene][..], extra].concat());
    let fields = info_fields(&text);
    let build = field(&fields, "build time");
    let seconds: f64 = build.strip_suffix(" s").unwrap().parse().unwrap();
    assert!(seconds >= 0.0);
    field(&fields, "accelerator").to_string()
}

/// A BVH's line, `bvh2: N nodes, L leaves, depth D, SAH cost C; leaf sizes K:COUNT ...`, as (N, L,
/// D, C), after checking that its leaves hold the `triangles` once each.
fn tree_line(line: &str, kind: &str, triangles: u64) -> (u64, u64, u64, f64) {
    // The wide BVHs name their slab test after the kind: `bvh8 (Avx2 slab tests): ...`.
    let (head, rest) = line.split_once(": ").unwrap_or_else(|| panic!("{line}"));
    assert!(head == kind || head.starts_with(&format!("{kind} (")), "{line}");
    let (shape, sizes) = rest.split_once("; leaf sizes ").unwrap();
    let (mut held, mut leaves) = (0, 0);
    for size in sizes.split_whitespace() {
        let (k, count) = size.split_once(':').unwrap();
        let (k, count): (u64, u64) = (k.parse().unwrap(), count.parse().unwrap());
        held += k * count;
        leaves += count;
    }
    assert_eq!(held, triangles, "{line}");
    let n: Vec<&str> = shape.split(", ").collect();
    let num = |s: &str, unit: &str| -> String {
        s.strip_suffix(unit)
            .or_else(|| s.strip_prefix(unit))
            .unwrap_or_else(|| panic!("{s} {unit}"))
            .trim()
            .to_string()
    };
    assert_eq!(num(n[1], " leaves").parse::<u64>().unwrap(), leaves, "{line}");
    (
        num(n[0], " nodes").parse().unwrap(),
        leaves,
        num(n[2], "depth ").parse().unwrap(),
        num(n[3], "SAH cost ").parse().unwrap(),
    )
}

#[test]
fn info_accel_build_and_bins_describe_the_structure_built() {
    let scene = "scenes/spd/teapot_1.nff";
    // 56 triangular patches and one quad (58 triangles), counted from the file.
    let text = std::fs::read_to_string(root().join(scene)).unwrap();
    let triangles = count_scene(&text)[1].1;
    assert!(triangles > 16, "{triangles}");
    let mut trees = Vec::new();
    for extra in [
        &["--accel", "bvh2", "--build", "midpoint"][..],
        &["--accel", "bvh2", "--build", "sah"],
        &["--accel", "bvh2", "--build", "sah", "--bins", "2"],
        &["--accel", "bvh2", "--build", "optimized"],
        &["--accel", "bvh2"],
    ] {
        let line = info_accel(scene, extra);
        let (nodes, leaves, depth, sah) = tree_line(&line, "bvh2", triangles);
        assert!(nodes > 0 && leaves > 0 && depth > 0 && sah > 0.0, "{line}");
        // A binary tree: one inner node fewer than leaves.
        assert_eq!(nodes, 2 * leaves - 1, "{line}");
        trees.push((nodes, depth, sah));
    }
    let [midpoint, sah, sah2, optimized, default] = trees[..] else {
        unreachable!()
    };
    assert!(midpoint != sah, "midpoint and sah build the same tree: {sah:?}");
    assert!(
        sah.2 < midpoint.2,
        "the SAH builder costs more: {sah:?} {midpoint:?}"
    );
    assert!(sah2 != sah, "--bins 2 builds the 12 bins' tree");
    assert!(
        default == optimized,
        "the default (auto) is not sah with 12 bins and reinsertion"
    );
    assert!(optimized.2 <= sah.2, "reinsertion raises the SAH cost");
    // The wide trees take --bins too.
    let four = |bins: &str| {
        let line = info_accel(scene, &["--accel", "bvh4", "--bins", bins]);
        tree_line(&line, "bvh4", triangles)
    };
    assert!(four("2") != four("12"), "--bins changes nothing in a bvh4");
    let eight = tree_line(&info_accel(scene, &["--accel", "bvh8"]), "bvh8", triangles);
    assert!(eight.0 > 0);
    // The grid: its resolution's cells.
    let grid = info_accel(scene, &["--accel", "grid"]);
    let rest = grid.strip_prefix("grid ").unwrap();
    let (res, rest) = rest.split_once(": ").unwrap();
    let cells: u64 = res.split('x').map(|n| n.parse::<u64>().unwrap()).product();
    assert!(rest.starts_with(&format!("{cells} cells (")), "{grid}");
    usage_error(
        &["info", scene, "--accel", "bvh3"],
        "error: invalid value 'bvh3' for '--accel <ACCEL>': unknown accelerator \"bvh3\": expected \
         none, grid, bvh2, bvh4, bvh8 or auto",
    );
    usage_error(
        &["info", scene, "--bins", "0"],
        "error: invalid value '0' for '--bins <BINS>': 0 is not in 2..=64",
    );
}

/// `bench --json` reports the frame it was asked for: spp, height (and the width that follows),
/// threads, accelerator; and a frame of `W x H` pixels at n² samples traces `W x H x n²` camera rays.
#[test]
fn bench_json_reflects_spp_height_threads_and_accel() {
    for (spp, height, threads, accel, samples) in [
        ("0", "24", "1", "grid", 1),
        ("4", "12", "2", "bvh2", 4),
        ("9", "6", "3", "bvh4", 9),
    ] {
        let v = json(&[
            "bench",
            DEFAULT,
            "--frames",
            "1",
            "--spp",
            spp,
            "--height",
            height,
            "--threads",
            threads,
            "--accel",
            accel,
            "--json",
        ]);
        let h: u64 = height.parse().unwrap();
        // 640x480: the width is 4/3 of the height.
        let w = h * 4 / 3;
        assert_eq!((int(&v["width"]), int(&v["height"])), (w, h), "{v}");
        assert_eq!(v["spp"].to_string(), spp);
        assert_eq!(v["threads"].to_string(), threads);
        assert_eq!(v["accel"], accel);
        assert_eq!(int(&v["frames"]), 1);
        assert_eq!(int(&v["rays_per_frame"]["primary"]), w * h * samples, "{v}");
    }
}

/// A sample count that is not a square is rounded up to one, with a warning, in `bench` as in
/// `render`: 3 samples trace 2 x 2 camera rays a pixel.
#[test]
fn bench_and_render_round_spp_up_to_a_square_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("spp3.png");
    let warning = "whitted: warning: 3 samples per pixel is not a square: taking 2 x 2 = 4\n";
    for args in [
        &["bench", DEFAULT, "--frames", "1", "--json"][..],
        &[
            "render",
            DEFAULT,
            "-q",
            "--stats=json",
            "-o",
            out.to_str().unwrap(),
        ],
    ] {
        let run = ok(&[args, &["--spp", "3", "--height", "12"]].concat());
        let err = String::from_utf8(run.stderr).unwrap();
        assert_eq!(err, warning, "{}", args[0]);
        let v: Value = serde_json::from_slice(&run.stdout).unwrap();
        let rays = if args[0] == "bench" {
            "rays_per_frame"
        } else {
            "rays"
        };
        assert_eq!(int(&v[rays]["primary"]), 16 * 12 * 4, "{}: {v}", args[0]);
        assert_eq!(int(&v["spp"]), 4, "the samples taken, {}: {v}", args[0]);
    }
}

/// `bench`'s text: the frames line, the frame line, the report's header with the frame's settings, and
/// the table of rays whose total is the sum of the kinds.
#[test]
fn bench_text_prints_the_frames_and_the_report() {
    let text = stdout(&[
        "bench",
        DEFAULT,
        "--frames",
        "2",
        "--spp",
        "4",
        "--height",
        "12",
        "--threads",
        "2",
        "--accel",
        "bvh2",
        "--kernel",
        "single",
    ]);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "frames     2 timed after one of warm-up", "{text}");
    let frame = lines[1].strip_prefix("frame      median ").unwrap();
    let (median, rest) = frame.split_once(" ms (min ").unwrap();
    let (min, rest) = rest.split_once(", max ").unwrap();
    let (max, fps) = rest.split_once("), ").unwrap();
    let [median, min, max]: [f64; 3] = [median, min, max].map(|s| s.parse().unwrap());
    assert!(min <= median && median <= max, "{}", lines[1]);
    let fps: f64 = fps.strip_suffix(" fps").unwrap().parse().unwrap();
    // The fps is the unrounded median's (to 0.01), the median printed to 0.1 ms.
    assert!(
        (1e3 / fps - median).abs() <= 0.0501 + 1e-4 * median,
        "{}",
        lines[1]
    );
    assert_eq!(
        lines[2],
        format!(
            "whitted {}: {DEFAULT}, 16x12, spp 4, depth 6, bvh2 (scalar), single kernel, 2 threads",
            env!("CARGO_PKG_VERSION")
        )
    );
    assert_eq!(lines[3], format!("cpu        {}", common::cpu_line()), "{text}");
    assert!(lines[4].starts_with("time       load "), "{}", lines[4]);
    assert!(lines[4].contains(", frame (median) "), "{}", lines[4]);
    assert_eq!(
        lines[5].split_whitespace().collect::<Vec<_>>(),
        ["rays", "a", "frame", "count", "Mrays/s"]
    );
    let count = |kind: &str| -> u64 {
        let line = lines
            .iter()
            .find(|l| l.split_whitespace().next() == Some(kind))
            .unwrap_or_else(|| panic!("no {kind} line: {text}"));
        line.split_whitespace().nth(1).unwrap().parse().unwrap()
    };
    assert_eq!(count("primary"), 16 * 12 * 4);
    assert!(count("hits") <= count("primary"));
    assert_eq!(
        count("total"),
        count("primary") + count("shadow") + count("reflected") + count("refracted")
    );
    assert!(count("reflected") > 0 && count("refracted") > 0, "{text}");
}

/// A bare `.obj` is a scene: `info` counts its triangles (each face of N corners is N - 2) and
/// `render` frames it, so the centre pixel shows the mesh, not the background that fills the corners.
#[test]
fn a_bare_obj_is_a_scene() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A unit cube of six quads; a pentagon in front of it and one triangle by negative indices.
    let obj = "\
# a cube
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 5 6 7 8
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
v 0.3 0.2 1.2
v 0.7 0.2 1.2
v 0.8 0.6 1.2
v 0.5 0.85 1.2
v 0.2 0.6 1.2
f -5 -4 -3 -2 -1
f -5 -3 -1
";
    let want: u64 = obj
        .lines()
        .filter(|l| l.starts_with("f "))
        .map(|l| l.split_whitespace().count() as u64 - 3)
        .sum();
    assert_eq!(want, 12 + 3 + 1);
    let path = d.join("cube.obj");
    std::fs::write(&path, obj).unwrap();
    let path = path.to_str().unwrap();
    let fields = info_fields(&stdout(&["info", path]));
    assert_eq!(field(&fields, "triangles").parse::<u64>().unwrap(), want);
    assert_eq!(field(&fields, "spheres"), "0");
    let image = rgb(&render(d, "cube.png", &[path, "--width", "32"]));
    // 1280x720 framing: 32 wide is 18 high.
    assert_eq!(image.dimensions(), (32, 18));
    let centre = image.get_pixel(16, 9);
    let corners = [(0, 0), (31, 0), (0, 17), (31, 17)].map(|(x, y)| image.get_pixel(x, y));
    assert!(
        corners.iter().all(|c| *c == corners[0]),
        "one background: {corners:?}"
    );
    assert_ne!(centre, corners[0], "the centre shows the background");
    // Grey material, white light: a grey pixel, lit.
    assert!(centre[0] == centre[1] && centre[1] == centre[2], "{centre:?}");
    assert!(centre[0] > corners[0][0], "{centre:?}");
}
