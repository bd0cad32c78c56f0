//! Scenes through pipes and images to standard output: `-` as the scene reads standard input (its
//! format told from its first statement, or given by `--format`), and `-o -` writes the image there,
//! the same bytes as the files.

use std::io::Write;
use std::path::Path;
use std::process::{Command, Output, Stdio};

use crate::common;

/// Runs `whitted ARGS` in `dir` with `input` on standard input.
fn piped(dir: &Path, args: &[&str], input: &[u8]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_whitted"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let input = input.to_vec();
    // Written on a thread: the command may answer (an error) before it has read everything.
    let writer = std::thread::spawn(move || {
        let _ = stdin.write_all(&input);
    });
    let out = child.wait_with_output().unwrap();
    writer.join().unwrap();
    out
}

/// `bytes` gzipped.
fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut z = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    z.write_all(bytes).unwrap();
    z.finish().unwrap()
}

/// A small OBJ: a quad as two faces, with normals.
const OBJ: &str = "# a quad\nmtllib none.mtl\no quad\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
                   vn 0 0 1\nf 1//1 2//1 3//1\nf 1//1 3//1 4//1\n";

/// Every scene format, plain and gzipped, piped in renders the bytes the file renders; in the scenes'
/// folder, so that the paths a scene names (`env`, `include`) are relative to the same place.
#[test]
fn a_piped_scene_renders_the_files_bytes_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("quad.obj"), OBJ).unwrap();
    let scenes = common::root().join("scenes");
    let ply = std::fs::read(scenes.join("models/dragon_vrip_res2.ply.gz")).unwrap();
    let ply = flate2::read::GzDecoder::new(&ply[..]);
    let ply: Vec<u8> = std::io::Read::bytes(ply).map(Result::unwrap).collect();
    std::fs::write(d.join("dragon.ply"), &ply).unwrap();
    let cases = [
        (scenes.join("balls_low.p3f"), scenes.clone()),
        (scenes.join("dragon.p3f"), scenes.clone()),
        (scenes.join("spd/tetra_default.nff"), scenes.clone()),
        (d.join("dragon.ply"), d.to_path_buf()),
        (d.join("quad.obj"), d.to_path_buf()),
    ];
    for (file, cwd) in cases {
        let text = std::fs::read(&file).unwrap();
        let name = file.to_string_lossy().into_owned();
        let out = d.join("file.png").to_string_lossy().into_owned();
        let args = ["--width", "48", "--height", "36", "-q"];
        let rendered = piped(&cwd, &[&["render", &name, "-o", &out][..], &args].concat(), b"");
        common::failed(&rendered, 0);
        let from_file = std::fs::read(&out).unwrap();
        for input in [text.clone(), gzip(&text)] {
            let run = piped(&cwd, &[&["render", "-", "-o", "-"][..], &args].concat(), &input);
            let err = String::from_utf8_lossy(&run.stderr).into_owned();
            assert!(run.status.success(), "{name}: {err}");
            assert!(run.stdout == from_file, "{name}: the piped scene's image differs");
        }
        let info = piped(&cwd, &["info", "-", "--json"], &text);
        let v: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
        assert_eq!(v["scene"], "<stdin>", "{name}");
    }
}

/// `-o -` writes the bytes the file of each format holds, and `--format` reads a file whatever its
/// name.
#[test]
fn standard_output_takes_each_format_and_format_overrides_the_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (format, ext) in [("png", "png"), ("ppm", "ppm"), ("jpg", "jpg"), ("exr", "exr")] {
        let out = d.join(format!("x.{ext}")).to_string_lossy().into_owned();
        common::ok(&["render", "--width", "40", "-q", "-o", &out]);
        let run = common::ok(&[
            "render",
            "--width",
            "40",
            "-q",
            "-o",
            "-",
            "--output-format",
            format,
        ]);
        assert!(run.stdout == std::fs::read(&out).unwrap(), "{format}");
    }
    std::fs::write(d.join("quad.txt"), OBJ).unwrap();
    let path = d.join("quad.txt").to_string_lossy().into_owned();
    let v = common::json(&["info", &path, "--format", "obj", "--json"]);
    assert_eq!(common::int(&v["triangles"]), 2);
    let err = common::fails(&["info", &path], 1);
    assert!(err.contains("unknown scene format"), "{err}");
}

/// What cannot come through a pipe says so: a statement no format begins with, an error in the piped
/// scene at `<stdin>:line:col`, and `-o -` with what needs files of its own (a usage error).
#[test]
fn pipes_refuse_what_they_cannot_carry() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let unknown = piped(d, &["info", "-"], b"# generated\n\nxyz 1 2 3\n");
    assert_eq!(
        common::failed(&unknown, 1),
        "whitted: <stdin>: cannot tell the scene's format from its first statement: expected a .p3f or \
         NFF statement, \"ply\" or an OBJ statement; give it with --format p3f|nff|ply|obj\n"
    );
    let bad = piped(d, &["info", "-"], b"v\nfrom 0 0 5\nat 0 0\n");
    let err = common::failed(&bad, 1);
    assert!(
        err.starts_with("whitted: <stdin>:3:") || err.starts_with("whitted: <stdin>:4:"),
        "{err}"
    );
    let obj_as_nff = piped(d, &["info", "-", "--format", "nff"], OBJ.as_bytes());
    assert!(common::failed(&obj_as_nff, 1).starts_with("whitted: <stdin>:2:1: "));
    for extra in [
        &["--heatmap", "nodes"][..],
        &["--resume"],
        &["--passes", "4", "--every", "2"],
        &["--tiles", "0/2"],
        &["--partial"],
    ] {
        let err = common::fails(&[&["render", "--width", "16", "-o", "-"][..], extra].concat(), 2);
        assert!(
            err.starts_with("whitted: -o - writes one image to standard output: it cannot take "),
            "{err}"
        );
    }
    let err = common::fails(
        &["render", "--width", "16", "-o", "x.png", "--output-format", "exr"],
        2,
    );
    assert!(err.contains("--output-format is for -o -"), "{err}");
    assert_eq!(common::names(d), Vec::<String>::new());
}
