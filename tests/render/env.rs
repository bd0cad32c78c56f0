//! The skybox (`env DIR`, `src/render/env.rs`) against closed forms written here, not taken from the
//! renderer.
//!
//! `scenes/skybox/` holds six generated faces, each [`SIZE`] x [`SIZE`] texels, given by [`texel`]: a base
//! colour per face scaled by a brightness that falls with the row (by 2 a row) and the column (by 1 a
//! column), so that a face, a flip of either axis and a swap of the axes all give other colours. The
//! first test regenerates every face from the formula and asserts the shipped PNGs equal it pixel for
//! pixel; `WHITTED_WRITE_SKYBOX=1 cargo test --release --test render env::shipped_faces` writes them
//! first (how they were made).
//!
//! The lookups follow the OpenGL 4.6 specification, section 8.13 "Cube Map Texture Selection", table
//! 8.19: the major axis of the direction r picks the face and (sc, tc, ma):
//!
//! | major axis | face                | sc  | tc  | ma  |
//! |------------|---------------------|-----|-----|-----|
//! | +rx        | right (0)           | −rz | −ry | rx  |
//! | −rx        | left (1)            | +rz | −ry | rx  |
//! | +ry        | top (2)             | +rx | +rz | ry  |
//! | −ry        | bottom (3)          | +rx | −rz | ry  |
//! | +rz        | front (4)           | +rx | −ry | rz  |
//! | −rz        | back (5)            | −rx | −ry | rz  |
//!
//! s = (sc/|ma| + 1)/2, t = (tc/|ma| + 1)/2; nearest texel (section 8.14.2): column ⌊s·w⌋, row ⌊t·h⌋,
//! rows counted from the first row of the image file (its top). Colours are the 8-bit values taken as
//! linear (value / 255, no gamma: `docs/scene-format.md`), so an 8-bit render of a miss is the texel's
//! bytes. The face size is odd, so the centre of a face is the centre of texel (31, 31), not a corner
//! shared by four texels.

use std::path::{Path, PathBuf};

use whitted::accel::{Accel, AccelKind, Prims};
use whitted::render::{Options, Renderer};

use crate::common;

/// Texels along each side of a face.
const SIZE: u32 = 63;

/// The face files, in the order of the table above (+x, −x, +y, −y, +z, −z).
const FACES: [&str; 6] = ["right", "left", "top", "bottom", "front", "back"];

/// Each face's base colour (its texel at row 0, column 0): red, green, sky blue, brown, yellow, violet.
const BASE: [[u32; 3]; 6] = [
    [255, 80, 80],
    [80, 255, 80],
    [120, 180, 255],
    [170, 120, 70],
    [255, 220, 60],
    [200, 80, 255],
];

/// The texel of `face` at `col`, `row` (from the top-left): the base colour times k/255, k = 255 − 2·row −
/// col (255 at the top-left corner, 69 at the bottom-right), rounded down.
fn texel(face: usize, col: u32, row: u32) -> [u8; 3] {
    assert!(col < SIZE && row < SIZE);
    let k = 255 - 2 * row - col;
    BASE[face].map(|c| (c * k / 255) as u8)
}

/// The face's 8-bit RGB bytes, row-major, from the formula.
fn face_bytes(face: usize) -> Vec<u8> {
    (0..SIZE)
        .flat_map(|y| (0..SIZE).flat_map(move |x| texel(face, x, y)))
        .collect()
}

/// `rgb` (8-bit RGB, row-major) as PNG bytes, best compression.
fn png_bytes(width: u32, height: u32, rgb: &[u8]) -> Vec<u8> {
    let mut png = Vec::new();
    let mut encoder = png::Encoder::new(&mut png, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::High);
    encoder.set_filter(png::Filter::Adaptive);
    let mut writer = encoder.write_header().unwrap();
    writer.write_image_data(rgb).unwrap();
    writer.finish().unwrap();
    png
}

fn skybox_dir() -> PathBuf {
    common::root().join("scenes/skybox")
}

/// Writes the six faces from the formula (`WHITTED_WRITE_SKYBOX=1`): 8-bit RGB PNG, best compression.
fn write_faces(dir: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    for (face, name) in FACES.iter().enumerate() {
        let png = png_bytes(SIZE, SIZE, &face_bytes(face));
        std::fs::write(dir.join(format!("{name}.png")), png).unwrap();
    }
}

#[test]
fn shipped_faces_are_the_formula() {
    let dir = skybox_dir();
    if std::env::var_os("WHITTED_WRITE_SKYBOX").is_some() {
        write_faces(&dir);
    }
    // Exactly the six PNGs: a .jpg beside one would be read instead (env.rs prefers .jpg).
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    let mut want: Vec<String> = FACES.iter().map(|f| format!("{f}.png")).collect();
    want.sort();
    assert_eq!(names, want, "scenes/skybox holds other files than the six faces");
    for (face, name) in FACES.iter().enumerate() {
        let path = dir.join(format!("{name}.png"));
        let bytes = std::fs::read(&path).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"), "{name}.png is not a PNG");
        // 8-bit RGB, or the decoder says what it is.
        let img = common::images::decode_rgb8(&bytes).unwrap_or_else(|e| panic!("{name}.png: {e}"));
        assert_eq!(img.dimensions(), (SIZE, SIZE), "{name}");
        for y in 0..SIZE {
            for x in 0..SIZE {
                assert_eq!(
                    img.get_pixel(x, y),
                    texel(face, x, y),
                    "{name}.png at column {x}, row {y}"
                );
            }
        }
    }
    // A texel tells its face: no colour appears on two faces.
    let mut seen = std::collections::HashMap::new();
    for (face, name) in FACES.iter().enumerate() {
        for row in 0..SIZE {
            for col in 0..SIZE {
                let other = *seen.entry(texel(face, col, row)).or_insert(face);
                assert_eq!(other, face, "a colour of {name} is also on {}", FACES[other]);
            }
        }
    }
}

/// A copy of the shipped faces in a fresh folder, as `sky/`, with the scene files written there.
fn sky_folder() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("sky")).unwrap();
    for name in FACES {
        let file = format!("{name}.png");
        std::fs::copy(skybox_dir().join(&file), dir.path().join("sky").join(&file)).unwrap();
    }
    dir
}

/// A scene with nothing in it, looking from the origin toward `at` with `up`, 3 x 3 pixels, a magenta
/// background and the skybox `sky`.
fn empty_scene(dir: &Path, at: [f64; 3], up: [f64; 3]) -> PathBuf {
    let path = dir.join("scene.p3f");
    let text = format!(
        "spp 0\nbclr 1 0 1\nenv sky\nv\nfrom 0 0 0\nat {} {} {}\nup {} {} {}\nangle 30\nhither 0.01\n\
         resolution 3 3\n",
        at[0], at[1], at[2], up[0], up[1], up[2]
    );
    std::fs::write(&path, text).unwrap();
    path
}

/// The 8-bit colour and the linear colour of the centre pixel, which looks exactly toward `at`.
fn centre_pixel(dir: &Path, at: [f64; 3], up: [f64; 3]) -> ([u8; 3], glam::Vec3) {
    let scene = whitted::scene::load(&empty_scene(dir, at, up)).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let accel = Accel::build(Prims::new(&scene), AccelKind::None);
    let renderer = Renderer::new(&scene, &accel, Options::new(&scene));
    assert!(renderer.warnings.is_empty(), "{:?}", renderer.warnings);
    assert_eq!(renderer.size(), (3, 3));
    let bytes = renderer.render().to_rgb8(false);
    let i = (3 + 1) * 3;
    ([bytes[i], bytes[i + 1], bytes[i + 2]], renderer.pixel(1, 1))
}

#[track_caller]
fn assert_sees(dir: &Path, at: [f64; 3], up: [f64; 3], face: usize, col: u32, row: u32) {
    let want = texel(face, col, row);
    let (bytes, linear) = centre_pixel(dir, at, up);
    assert_eq!(
        bytes, want,
        "looking toward {at:?}: want {} texel (column {col}, row {row})",
        FACES[face]
    );
    for c in 0..3 {
        let v = f32::from(want[c]) / 255.0;
        assert!(
            (linear[c] - v).abs() <= 1e-6,
            "toward {at:?}: linear {linear:?}, want {want:?} / 255 (no gamma)"
        );
    }
}

/// Along each axis the camera sees the centre texel (31, 31) of that axis' face (s = t = 1/2, ⌊31.5⌋ =
/// 31). `up` is +y for the horizontal views; looking up it is −z, looking down +z.
#[test]
fn the_six_axes_see_the_centres_of_their_faces() {
    let dir = sky_folder();
    let views: [([f64; 3], [f64; 3]); 6] = [
        ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
        ([0.0, 1.0, 0.0], [0.0, 0.0, -1.0]),
        ([0.0, -1.0, 0.0], [0.0, 0.0, 1.0]),
        ([0.0, 0.0, 1.0], [0.0, 1.0, 0.0]),
        ([0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
    ];
    for (face, (at, up)) in views.into_iter().enumerate() {
        assert_sees(dir.path(), at, up, face, 31, 31);
    }
}

/// One direction off the centre of each face, its texel worked out by hand from table 8.19 (above):
/// s·63 and t·63 fall a quarter of a texel or more inside their texel, so rounding cannot move them. A
/// face read mirrored, upside down or transposed gives another colour at each (k differs).
#[test]
fn off_centre_directions_see_the_texels_of_the_opengl_table() {
    let dir = sky_folder();
    let y = [0.0, 1.0, 0.0];
    // (direction, up, face, column, row)
    type Case = ([f64; 3], [f64; 3], usize, u32, u32);
    let cases: [Case; 6] = [
        // +x major: sc = −rz = 0.25, tc = −ry = −0.5; s = 0.625, t = 0.25; 39.375, 15.75.
        ([1.0, 0.5, -0.25], y, 0, 39, 15),
        // −x major: sc = +rz = −0.25, tc = −ry = −0.5; s = 0.375, t = 0.25; 23.625, 15.75.
        ([-1.0, 0.5, -0.25], y, 1, 23, 15),
        // +y major: sc = +rx = 0.5, tc = +rz = −0.25; s = 0.75, t = 0.375; 47.25, 23.625.
        ([0.5, 1.0, -0.25], [0.0, 0.0, -1.0], 2, 47, 23),
        // −y major: sc = +rx = 0.5, tc = −rz = 0.25; s = 0.75, t = 0.625; 47.25, 39.375.
        ([0.5, -1.0, -0.25], [0.0, 0.0, 1.0], 3, 47, 39),
        // +z major: sc = +rx = 0.5, tc = −ry = 0.25; s = 0.75, t = 0.625; 47.25, 39.375.
        ([0.5, -0.25, 1.0], y, 4, 47, 39),
        // −z major: sc = −rx = −0.5, tc = −ry = 0.25; s = 0.25, t = 0.625; 15.75, 39.375.
        ([0.5, -0.25, -1.0], y, 5, 15, 39),
    ];
    for (at, up, face, col, row) in cases {
        // The check can tell the texel from its mirror images and its transpose on the same face.
        let k = |c: u32, r: u32| texel(face, c, r);
        let m = SIZE - 1;
        for (c, r) in [(m - col, row), (col, m - row), (row, col)] {
            assert_ne!(k(c, r), k(col, row), "{at:?}: ({c}, {r})");
        }
        assert_sees(dir.path(), at, up, face, col, row);
    }
}

/// `env missing_dir`: the binary warns (one line, on stderr) and renders the background colour.
#[test]
fn a_missing_skybox_warns_and_renders_the_background_colour() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.p3f");
    std::fs::write(
        &scene,
        "spp 0\nbclr 0.2 0.4 0.6\nenv missing_dir\nv\nfrom 0 0 0\nat 1 0.5 0.25\nup 0 1 0\nangle 60\n\
         hither 0.01\nresolution 8 6\n",
    )
    .unwrap();
    let out = dir.path().join("out.png");
    let run = common::whitted(&[
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    let err = String::from_utf8(run.stderr).unwrap();
    assert!(run.status.success(), "{err}");
    assert_eq!(
        err,
        format!(
            "whitted: warning: {}:3:5: environment map directory \"{}\" not found; using the background \
             colour\n",
            scene.display(),
            dir.path().join("missing_dir").display()
        )
    );
    let img = common::images::rgb(&out);
    assert_eq!(img.dimensions(), (8, 6));
    // 0.2, 0.4, 0.6 times 255, rounded.
    assert!(img.pixels().all(|p| p == [51, 102, 153]), "{img:?}");
}

/// A course scene finds `scenes/skybox`: no warning about it, and where it shows its background (the pixels that
/// are exactly `bclr` when the skybox is taken away) the binary's render shows texels of the faces.
#[test]
fn a_course_scene_renders_its_sky() {
    let path = common::root().join("scenes/balls_low.p3f");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("balls_low.png");
    let run = common::whitted(&[
        "render",
        "scenes/balls_low.p3f",
        "-o",
        out.to_str().unwrap(),
        "--width",
        "64",
        "--height",
        "64",
        "--quiet",
    ]);
    let err = String::from_utf8(run.stderr).unwrap();
    assert!(run.status.success(), "{err}");
    // Its one warning is about its lens (aperture 1 at spp 0), none about the skybox.
    assert!(
        !err.contains("environment map") && !err.contains("skybox"),
        "{err}"
    );
    let sky = common::images::rgb(&out);
    assert_eq!(sky.dimensions(), (64, 64));

    // The same frame without the skybox (spp 0 in the file: one ray a pixel, so a miss is exactly bclr).
    let mut scene = whitted::scene::load(&path).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.env.as_deref(), Some(skybox_dir().as_path()));
    scene.env = None;
    let accel = Accel::build(Prims::new(&scene), AccelKind::None);
    let options = Options {
        width: 64,
        height: 64,
        ..Options::new(&scene)
    };
    assert_eq!(options.spp, 0);
    let flat = Renderer::new(&scene, &accel, options).render().to_rgb8(false);
    // bclr 0.078 0.361 0.753, times 255, rounded.
    let bclr = [20, 92, 192];
    let texels: std::collections::HashSet<[u8; 3]> = (0..6)
        .flat_map(|f| (0..SIZE).flat_map(move |r| (0..SIZE).map(move |c| texel(f, c, r))))
        .collect();
    let mut background = 0;
    for (i, p) in sky.pixels().enumerate() {
        if flat[3 * i..3 * i + 3] == bclr {
            background += 1;
            assert_ne!(p, bclr, "pixel {i} shows bclr");
            assert!(
                texels.contains(&p),
                "pixel {i}: {:?} is no texel of the skybox",
                p
            );
        }
    }
    assert!(background > 64 * 64 / 10, "only {background} background pixels");
}

/// `whitted ARGS` under `ulimit -v` of `kib` KiB, killed (and the test failed) if it runs for more than
/// a minute: what it is given here must neither hang it nor let it take the machine's memory.
fn whitted_bounded(kib: u64, args: &[&str]) -> std::process::Output {
    use std::process::{Command, Stdio};
    let child = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {kib} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_whitted"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_a_minute(child, &format!("whitted {args:?}"))
}

/// A scene of nothing but the skybox `sky` and the background colour 0.2 0.4 0.6, 32 x 24 pixels.
fn sky_scene(dir: &Path) -> PathBuf {
    let scene = dir.join("scene.p3f");
    std::fs::write(
        &scene,
        "spp 0\nbclr 0.2 0.4 0.6\nenv sky\nv\nfrom 0 0 0\nat 1 0.5 0.25\nup 0 1 0\nangle 60\n\
         hither 0.01\nresolution 32 24\n",
    )
    .unwrap();
    scene
}

/// Renders `sky_scene` under [`whitted_bounded`], which must succeed with `warning` about the face
/// `sky/FACE` as its only output and the background colour in every pixel.
#[track_caller]
fn renders_the_background_colour(dir: &Path, kib: u64, face: &str, warning: &str) {
    let scene = sky_scene(dir);
    let out = dir.join("out.png");
    let run = whitted_bounded(
        kib,
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--quiet",
        ],
    );
    let err = String::from_utf8(run.stderr).unwrap();
    assert!(run.status.success(), "{err}");
    let face = dir.join("sky").join(face);
    assert_eq!(
        err,
        format!(
            "whitted: warning: {}: {warning}; using the background colour\n",
            face.display()
        )
    );
    assert!(common::images::rgb(&out).pixels().all(|p| p == [51, 102, 153]));
}

/// A face that is a FIFO (opened for reading, it waits for a writer) or a link to `/dev/zero` (a JPEG
/// decoder reads it to its end, which never comes) is refused at once, with the scene loader's words,
/// and the background colour is rendered; a link to a regular file is a face like any other.
#[test]
fn a_face_that_is_not_a_regular_file_is_refused_at_once() {
    let not_regular = "cannot open the skybox face: it is not a regular file (a FIFO, a device or a socket)";
    let dir = sky_folder();
    let png = dir.path().join("sky/right.png");
    std::fs::remove_file(&png).unwrap();
    common::mkfifo(&png);
    renders_the_background_colour(dir.path(), 2_000_000, "right.png", not_regular);

    // A .jpg is taken before a .png of the same face.
    let jpg = dir.path().join("sky/right.jpg");
    std::os::unix::fs::symlink("/dev/zero", &jpg).unwrap();
    renders_the_background_colour(dir.path(), 2_000_000, "right.jpg", not_regular);

    std::fs::remove_file(&jpg).unwrap();
    std::fs::remove_file(&png).unwrap();
    std::os::unix::fs::symlink(skybox_dir().join("right.png"), &png).unwrap();
    assert_sees(dir.path(), [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0, 31, 31);
}

/// A 1 x 1 PNG whose header says it is `width` x `height` (its data is then far too short).
fn png_declaring(width: u32, height: u32) -> Vec<u8> {
    let mut png = png_bytes(1, 1, &[0; 3]);
    // The IHDR chunk follows the 8-byte signature: length (4), type (4), width (4), height (4), ...
    assert_eq!(&png[12..16], b"IHDR");
    png[16..20].copy_from_slice(&width.to_be_bytes());
    png[20..24].copy_from_slice(&height.to_be_bytes());
    // Its CRC covers its type and its 13 bytes of data.
    let mut crc = flate2::Crc::new();
    crc.update(&png[12..29]);
    png[29..33].copy_from_slice(&crc.sum().to_be_bytes());
    png
}

/// Six faces whose headers say `side` x `side`, in `dir/sky`.
fn faces_declaring(dir: &Path, side: u32) {
    std::fs::create_dir(dir.join("sky")).unwrap();
    for name in FACES {
        std::fs::write(dir.join(format!("sky/{name}.png")), png_declaring(side, side)).unwrap();
    }
}

/// A small file whose header declares a face of 12000 x 12000 texels (six of them are 2.4 GiB decoded,
/// for a 32 x 24 render) is refused from its header, before anything is decoded, with the bound.
#[test]
fn a_face_over_8192_texels_a_side_is_refused_from_its_header() {
    let dir = tempfile::tempdir().unwrap();
    faces_declaring(dir.path(), 12000);
    renders_the_background_colour(
        dir.path(),
        1_000_000,
        "right.png",
        "the skybox face is 12000x12000 texels: at most 8192x8192",
    );
}

/// The skybox's images are counted in the memory check a render makes before any work: six faces of
/// 8192 x 8192 texels need 1.31 GiB (each as 8-bit RGB, and one more face while it is decoded), which
/// `ulimit -v 1000000` (under 0.96 GiB) does not leave: refused, status 1, nothing written.
#[test]
fn a_skybox_larger_than_the_memory_limit_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    faces_declaring(dir.path(), 8192);
    let scene = sky_scene(dir.path());
    let out = dir.path().join("out.png");
    let run = whitted_bounded(
        1_000_000,
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--quiet",
        ],
    );
    let err = common::failed(&run, 1);
    let prefix = "whitted: the skybox's faces need 1.31 GiB to load, beside the frame's 0.00 GiB, and only ";
    let suffix = " GiB is available: use smaller faces\n";
    assert!(err.starts_with(prefix) && err.ends_with(suffix), "{err}");
    assert!(!out.exists());
}
