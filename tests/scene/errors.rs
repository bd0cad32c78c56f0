//! Bad input: every class of malformed scene gets one clear error with file, line and column, never a
//! panic. Each test asserts the message and the line.

use std::io::Write;
use std::path::Path;

use whitted::Error;
use whitted::scene::{self, p3f};

use crate::common;

const CAMERA: &str = "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 64 48\n";

fn parse(text: &str) -> Result<whitted::scene::Scene, Error> {
    p3f::parse(
        Path::new("t.p3f"),
        Box::new(std::io::Cursor::new(text.as_bytes().to_vec())),
    )
}

/// Parses `text`, expects an error on `line` whose message contains `needle`.
fn fails(text: &str, line: u64, needle: &str) -> Error {
    let e = parse(text).expect_err("should not parse");
    assert!(
        e.message.contains(needle),
        "message {:?} lacks {needle:?}",
        e.message
    );
    assert_eq!(e.line(), Some(line), "wrong line for {e}");
    assert!(e.to_string().starts_with(&format!("t.p3f:{line}:")), "{e}");
    e
}

/// Camera lines are 1-7, so the first statement after them is on line 8.
fn after_camera(rest: &str) -> String {
    format!("{CAMERA}{rest}")
}

#[test]
fn a_good_scene_parses() {
    let s = parse(&after_camera("l 1 1 1\nf 1 0 0 1 0 0 0 0\ns 0 0 0 1\n")).unwrap();
    assert_eq!(s.spheres.radius.len(), 1);
}

#[test]
fn truncated_file() {
    let e = fails(
        &after_camera("s 0 0 0"),
        8,
        "expected a number for the sphere radius, found the end of the file",
    );
    assert_eq!(
        e.to_string(),
        "t.p3f:8:8: expected a number for the sphere radius, found the end of the file"
    );
}

#[test]
fn not_a_number() {
    let e = fails(
        &after_camera("s 0 0 0 abc\n"),
        8,
        "expected a number for the sphere radius, found \"abc\"",
    );
    assert_eq!(
        e.to_string(),
        "t.p3f:8:9: expected a number for the sphere radius, found \"abc\""
    );
}

#[test]
fn nan_and_infinity() {
    fails(&after_camera("s 0 0 0 1\ns nan 0 0 1\n"), 9, "finite number");
    fails(&after_camera("l 1 1 inf\n"), 8, "finite number");
    fails(&after_camera("s 0 0 0 1e39\n"), 8, "finite number");
}

#[test]
fn negative_sizes() {
    // NFF: a negative sphere radius is an inside-only sphere, not an error.
    let s = parse(&after_camera("s 0 0 0 -2\n")).unwrap();
    assert_eq!((s.spheres.radius[0], s.spheres.inside_only[0]), (2.0, true));
    let s = parse(&after_camera("c 0 0 0 -1 0 1 0 -1\n")).unwrap();
    assert!(s.cones.inside_only[0]);
    fails(&after_camera("c 0 0 0 -1 0 1 0 1\n"), 8, "must both be negative");
    fails(&after_camera("\nbox 1 0 0 0 1 1\n"), 9, "negative size");
    fails(&after_camera("s 0 0 0 0\n"), 8, "non-zero sphere radius");
    fails(&after_camera("f 1 1 1 -1 0 0 0 0\n"), 8, "must not be negative");
    fails(&after_camera("b -1 0 0\n"), 8, "must not be negative");
}

#[test]
fn unknown_keyword() {
    fails(
        &after_camera("s 0 0 0 1\nsphere 0 0 0 1\n"),
        9,
        "unknown keyword \"sphere\"",
    );
}

#[test]
fn polygon_with_fewer_vertices_than_announced() {
    fails(
        &after_camera("p 4\n0 0 0\n1 0 0\n1 1 0\ns 0 0 0 1\n"),
        12,
        "expected a number for vertex 4 of 4 of the polygon, found \"s\"",
    );
    fails(
        &after_camera("p 2\n0 0 0\n1 0 0\n"),
        8,
        "polygon's vertex count between 3",
    );
}

#[test]
fn polygon_with_more_vertices_than_announced() {
    fails(
        &after_camera("p 3\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"),
        12,
        "expected a keyword, found the number",
    );
}

#[test]
fn mesh_index_out_of_range() {
    let mesh = "mesh 3 2\n0 0 0\n1 0 0\n0 1 0\n1 2 3\n1 2 4\n";
    fails(
        &after_camera(mesh),
        13,
        "expected a vertex index between 1 and 3 (or -3..-1), found 4",
    );
    fails(
        &after_camera("mesh 3 1\n0 0 0\n1 0 0\n0 1 0\n0 1 2\n"),
        12,
        "found 0",
    );
    fails(
        &after_camera("mesh 3 1\n0 0 0\n1 0 0\n0 1 0\n-4 1 2\n"),
        12,
        "found -4",
    );
    // Negative indices count back from the end.
    let s = parse(&after_camera("mesh 3 1\n0 0 0\n1 0 0\n0 1 0\n-3 -2 -1\n")).unwrap();
    assert_eq!(s.triangles.vertices(0)[2], glam::Vec3::Y);
}

#[test]
fn counts_larger_than_the_data() {
    // A billion vertices announced, three given: an error at the end, not a 12 GB allocation.
    fails(
        &after_camera("mesh 1000000000 1\n0 0 0\n1 0 0\n0 1 0\n"),
        12,
        "expected a number for vertex 4 of 1000000000 of the mesh, found the end of the file",
    );
    fails(&after_camera("p 99999999999\n"), 8, "vertex count between 3 and");
}

#[test]
fn odd_file_names_are_read_and_named_exactly() {
    use std::ffi::OsStr;
    use std::os::unix::ffi::OsStrExt;
    let dir = tempfile::tempdir().unwrap();
    // Not UTF-8, but a .p3f: read as one (it was "unknown scene format").
    let odd = dir.path().join(OsStr::from_bytes(b"ok\xfe.p3f"));
    std::fs::copy(common::root().join("scenes/balls_low.p3f"), &odd).unwrap();
    scene::load(&odd).unwrap();
    // Messages name such paths escaped and quoted, on one line.
    let missing = Path::new(OsStr::from_bytes(b"no\xfe.p3f"));
    let e = scene::load(missing).unwrap_err().to_string();
    assert!(e.starts_with("\"no\\xFE.p3f\": cannot open: "), "{e}");
    let e = scene::load(Path::new("a\nb.p3f")).unwrap_err().to_string();
    assert!(
        e.starts_with("\"a\\nb.p3f\": cannot open: ") && !e.contains('\n'),
        "{e}"
    );
    // A plain name is written as it is.
    let e = scene::load(Path::new("plain-missing.p3f"))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("plain-missing.p3f: cannot open: "), "{e}");
}

#[test]
fn a_not_finite_optional_number_is_refused_as_a_number() {
    // The 12th material number (the roughness) and a light's optional colour: `nan` and `inf` were
    // taken for the next keyword ("unknown keyword \"nan\"").
    for word in ["nan", "NaN", "inf", "-inf", "Infinity"] {
        fails(
            &after_camera(&format!("f 1 1 1 1 1 1 1 1 10 0 1 {word}\ns 0 0 0 1\n")),
            8,
            &format!("expected a finite number for the material, found \"{word}\""),
        );
        fails(
            &after_camera(&format!("l 0 5 0 {word} 1 1\n")),
            8,
            "expected a finite number",
        );
    }
}

#[test]
fn an_area_lights_grid_is_told_its_one_range() {
    // 0 and 1,000,000 get the same range, 1 to 1024 (0 was once "between 0 and 1024" in one message
    // and "at least 1" in another).
    let lq = |grid: &str| after_camera(&format!("lq -1.5 5 1 3 0 0 0 0 -3 0.9 0.9 0.9 {grid}\n"));
    for grid in ["0", "1000000", "-1"] {
        let e = fails(
            &lq(grid),
            8,
            "expected the area light's grid resolution between 1 and 1024",
        );
        assert!(e.message.ends_with(&format!("found {grid}")), "{e}");
    }
    parse(&lq("1")).unwrap();
    parse(&lq("1024")).unwrap();
}

/// Each quad light of N is N² light samples, and a scene's light samples (a point light is one) are
/// bounded in total: a few kilobytes of `lq ... 1024` lines were gigabytes of samples. The error names
/// the light that passes the bound, the bound and the total it would make.
#[test]
fn light_samples_are_bounded_in_total() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lights.p3f");
    let lq = "lq -1.5 5 1 3 0 0 0 0 -3 0.9 0.9 0.9 1024\n";
    std::fs::write(&path, after_camera(&lq.repeat(200))).unwrap();
    let (name, image) = (path.to_str().unwrap(), dir.path().join("x.png"));
    for args in [
        &["info", name][..],
        &["render", name, "-o", image.to_str().unwrap()],
    ] {
        let err = common::failure(&common::whitted(args));
        assert_eq!(
            err,
            format!(
                "whitted: {name}:9:1: this area light's 1024 x 1024 samples bring the scene's light samples \
                 to 2097152, more than the 1048576 allowed: expected fewer lights or smaller grids"
            )
        );
    }
    // One light of the largest grid is within the bound; a point light more is not.
    parse(&after_camera(lq)).unwrap();
    fails(
        &after_camera(&format!("{lq}l 0 5 0\n")),
        9,
        "this point light brings the scene's light samples to 1048577, more than the 1048576 allowed",
    );
    fails(
        &after_camera(&format!("l 0 5 0\n{lq}")),
        9,
        "this area light's 1024 x 1024 samples bring the scene's light samples to 1048577",
    );
}

#[test]
fn resolutions() {
    let res = |w: &str, h: &str| CAMERA.replace("resolution 64 48", &format!("resolution {w} {h}"));
    fails(&res("0", "48"), 7, "resolution must be between 1 and");
    fails(&res("100000", "48"), 7, "resolution must be between 1 and");
    fails(&res("60000", "60000"), 7, "more than");
    fails(&res("-5", "48"), 7, "image width between 0 and");
    fails(&res("64.5", "48"), 7, "whole number");
}

#[test]
fn degenerate_cameras() {
    fails(
        &CAMERA.replace("at 0 0 0", "at 0 0 5"),
        3,
        "\"from\" and \"at\" are the same point",
    );
    fails(
        &CAMERA.replace("up 0 1 0", "up 0 0 0"),
        4,
        "\"up\" is the zero vector",
    );
    fails(
        &CAMERA.replace("up 0 1 0", "up 0 0 3"),
        4,
        "parallel to the view direction",
    );
    // A camera whose distance to its target squares past f32::MAX is still a valid view (it was
    // once refused as "parallel"), and renders: its centre ray points at the target.
    let far = parse(&CAMERA.replace("from 0 0 5", "from 0 0 2e19")).unwrap();
    let ray = whitted::render::camera::RayCamera::new(&far.camera, 64, 48).ray(32.0, 24.0);
    assert_eq!(ray.dir, glam::Vec3::NEG_Z, "{ray:?}");
    fails(
        &CAMERA
            .replace("from 0 0 5", "from 0 0 -3e38")
            .replace("at 0 0 0", "at 0 0 3e38"),
        3,
        "are too far apart: their distance overflows single precision",
    );
    fails(&CAMERA.replace("angle 45", "angle 180"), 5, "between 0 and 180");
    fails(
        &CAMERA.replace("hither 1\n", ""),
        6,
        "expected \"hither\" in the \"v\" camera block, found \"resolution\"",
    );
    fails(&format!("{CAMERA}{CAMERA}"), 8, "a second \"v\" camera block");
    fails(
        "s 0 0 0 1\n",
        2,
        "expected a \"v\" camera block, found the end of the file",
    );
}

#[test]
fn materials() {
    fails(
        &after_camera("f 1 1 1 1 0 0 0\ns 0 0 0 1"),
        8,
        "expected 8 numbers (NFF",
    );
    fails(
        &after_camera("f 1 1 1 1 0 0 0.5 0\n"),
        8,
        "positive index of refraction",
    );
    // Opaque materials with `ior 0` (course and SPD files) are fine.
    assert!(parse(&after_camera("f 1 1 1 1 0 0 0 0\n")).is_ok());
}

#[test]
fn empty_file() {
    let e = parse("").unwrap_err();
    assert_eq!(
        e.to_string(),
        "t.p3f: empty scene file: expected a \"v\" camera block and objects"
    );
    let e = parse("# only a comment\n\n").unwrap_err();
    assert!(e.message.contains("empty scene file"), "{e}");
}

#[test]
fn binary_garbage() {
    // Deterministic pseudo-random bytes: whatever they are, an error with a position, never a panic.
    let mut x: u32 = 12345;
    for len in [1, 7, 100, 5000] {
        let bytes: Vec<u8> = (0..len)
            .map(|_| {
                x = x.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (x >> 24) as u8
            })
            .collect();
        let r = p3f::parse(Path::new("t.p3f"), Box::new(std::io::Cursor::new(bytes)));
        assert!(r.is_err());
    }
    let e = parse("\u{0}\u{1}\u{2}ELF\u{7f}").unwrap_err();
    assert!(e.message.contains("unknown keyword"), "{e}");
}

/// A number of 100,000 digits is a number too long, not binary data; a word of
/// 2,000 letters is a word too long; only bytes that are not printable say "binary data".
#[test]
fn overlong_words_say_what_they_are() {
    let digits = "1".repeat(100_000);
    let e = fails(
        &after_camera(&format!("s 0 0 0 {digits}\n")),
        8,
        "expected a number of at most 1024 characters, found a longer one: \"1111",
    );
    assert!(!e.message.contains("binary"), "{e}");
    fails(
        &after_camera(&format!("s 0 0 0 -0.{digits}e5\n")),
        8,
        "expected a number of at most 1024 characters",
    );
    let word = "x".repeat(2_000);
    fails(
        &after_camera(&format!("{word}\n")),
        8,
        "found a word of more than 1024 characters: \"xxx",
    );
    let junk: String = std::iter::repeat_n("\u{1}a", 1_000).collect();
    fails(
        &after_camera(&format!("{junk}\n")),
        8,
        "(binary data in a text file?)",
    );
}

#[test]
fn missing_files() {
    let e = scene::load(Path::new("no/such/scene.p3f")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "no/such/scene.p3f: cannot open: No such file or directory"
    );
    let e = scene::load(Path::new("scene.txt")).unwrap_err();
    assert!(e.message.contains("unknown scene format"), "{e}");
}

#[test]
fn missing_include() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.p3f");
    std::fs::write(
        &path,
        after_camera("f 1 1 1 1 0 0 0 0\ninclude nothere.ply scale 2\n"),
    )
    .unwrap();
    let e = scene::load(&path).unwrap_err();
    assert_eq!(e.line(), Some(9));
    assert!(
        e.message.contains("cannot open include file") && e.message.contains("nothere.ply"),
        "{e}"
    );
    std::fs::write(&path, after_camera("include s.p3f\n")).unwrap();
    let e = scene::load(&path).unwrap_err();
    assert!(e.message.contains("not a mesh file"), "{e}");
    assert_eq!(e.line(), Some(8));
}

/// Geometry that a transform or a size takes past the largest float is an error at
/// its statement (the include's scale and translation loaded with vertices at infinity, exit 0), as
/// infinite numbers in the file are; so is a bare mesh whose edges overflow.
#[test]
fn geometry_reaching_past_the_largest_float_is_refused() {
    let past = "reaches past the largest finite coordinate, 3.4028235e38";
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let path = dir.path().join("s.p3f");
    std::fs::write(
        &path,
        after_camera("include m.obj scale 3e38 translate 3.4e38 0 0\n"),
    )
    .unwrap();
    let e = scene::load(&path).unwrap_err();
    assert_eq!(e.line(), Some(8), "{e}");
    assert!(e.message.starts_with(&format!("the triangle {past}")), "{e}");
    std::fs::write(
        &path,
        after_camera("include m.obj scale 1e30 translate 3e38 0 0\n"),
    )
    .unwrap();
    scene::load(&path).unwrap();
    fails(
        &after_camera("s 3.4e38 0 0 3.4e38\n"),
        8,
        &format!("the sphere {past}"),
    );
    fails(
        &after_camera("s 0 0 0 1\nc\n0 0 0 1\n3.4e38 0 0 3e38\n"),
        9,
        &format!("the cone {past}"),
    );
    fails(
        &after_camera("p 3\n-3e38 0 0\n3e38 0 0\n0 1 0\n"),
        8,
        &format!("the triangle {past}"),
    );
    parse(&after_camera(
        "s 3e38 0 0 4e37\np 3\n-1e38 0 0\n1e38 0 0\n0 1 0\n",
    ))
    .unwrap();
    let ply = dir.path().join("wide.obj");
    std::fs::write(&ply, "v -3e38 0 0\nv 3e38 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let e = scene::load(&ply).unwrap_err();
    assert_eq!(e.to_string(), format!("{}: a triangle {past}", ply.display()));
}

#[test]
fn include_transforms_and_errors_inside_the_mesh() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(dir.path().join("bad.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n").unwrap();
    let path = dir.path().join("s.p3f");
    std::fs::write(&path, after_camera("include m.obj scale 2 translate 0 0 1\n")).unwrap();
    let s = scene::load(&path).unwrap();
    assert_eq!(
        s.triangles.vertices(0),
        [
            glam::Vec3::Z,
            glam::Vec3::new(2.0, 0.0, 1.0),
            glam::Vec3::new(0.0, 2.0, 1.0)
        ]
    );
    std::fs::write(&path, after_camera("include bad.obj\n")).unwrap();
    let e = scene::load(&path).unwrap_err();
    // The error names the mesh file and its line.
    assert!(e.to_string().contains("bad.obj:4:"), "{e}");
}

#[test]
fn corrupt_gzip() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.p3f.gz");
    let mut text = after_camera("");
    for i in 0..2000 {
        text += &format!("s {i} 0 0 0.5\n");
    }
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(text.as_bytes()).unwrap();
    let mut bytes = gz.finish().unwrap();
    std::fs::write(&path, &bytes).unwrap();
    assert_eq!(scene::load(&path).unwrap().spheres.radius.len(), 2000);
    let mid = bytes.len() / 2;
    for b in &mut bytes[mid..mid + 16] {
        *b ^= 0x5a;
    }
    std::fs::write(&path, &bytes).unwrap();
    let e = scene::load(&path).unwrap_err();
    assert!(
        e.message.contains("cannot read") || e.message.contains("expected"),
        "{e}"
    );
    assert!(e.line().is_some(), "{e}");
    // Truncated: cut in the middle.
    std::fs::write(&path, &bytes[..mid]).unwrap();
    assert!(scene::load(&path).is_err());
}

/// The binary turns every error into one line on stderr and a non-zero exit, never a panic.
#[test]
fn cli_reports_errors_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.p3f");
    std::fs::write(&path, after_camera("s 0 0 0 x\n")).unwrap();
    let image = dir.path().join("x.png");
    for cmd in ["info", "render"] {
        let out = common::whitted(
            &[cmd, path.to_str().unwrap(), "-o", image.to_str().unwrap()]
                [..if cmd == "info" { 2 } else { 4 }],
        );
        assert_eq!(out.status.code(), Some(1));
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.contains("bad.p3f:8:9: expected a number for the sphere radius, found \"x\""),
            "{err}"
        );
    }
}
