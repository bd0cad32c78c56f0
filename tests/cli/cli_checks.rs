//! `whitted render` refuses what it could not finish before it starts: an output it could not write
//! (checked before the scene is even loaded), a frame larger than the memory it may use (under a real
//! `ulimit -v`), a thread count out of range (a usage error, never a panic).

use std::path::Path;
use std::process::Command;

use crate::common::{self, fails};

/// A bad output is named before the scene is loaded: the scene here does not exist, and the error is
/// about the output all the same.
#[test]
fn a_bad_output_is_refused_before_the_scene_is_loaded() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let at = |name: &str| d.join(name).to_string_lossy().into_owned();
    let render = |args: &[&str]| fails(&[&["render", "no-such-scene.p3f"][..], args].concat(), 1);

    let gif = at("out.gif");
    assert_eq!(
        render(&["-o", &gif]),
        format!(
            "whitted: {gif}: unknown image format: expected a .png, .ppm, .jpg, .jpeg or .exr file name\n"
        )
    );
    let missing = at("missing_dir/out.png");
    assert_eq!(
        render(&["-o", &missing]),
        format!(
            "whitted: {missing}: the directory {} does not exist\n",
            at("missing_dir")
        )
    );
    // A name that ends in a separator names a directory, not an image (it failed after the render).
    let slash = format!("{}/", at("q.png"));
    assert_eq!(
        render(&["-o", &slash]),
        format!("whitted: {slash}: names a directory (it ends in a path separator): expected a file name\n")
    );
    // A directory where the image would go is not replaced.
    std::fs::create_dir(d.join("taken.png")).unwrap();
    let taken = at("taken.png");
    assert_eq!(
        render(&["-o", &taken]),
        format!(
            "whitted: {taken}: is not a regular file (a directory, a link or a device); refusing to replace it\n"
        )
    );
    // --progressive-out: a file in its way is named.
    std::fs::write(d.join("file"), "").unwrap();
    let err = render(&[
        "-o",
        &at("ok.png"),
        "--passes",
        "2",
        "--progressive-out",
        &at("file"),
    ]);
    assert_eq!(
        err,
        format!(
            "whitted: {}: is not a directory: --progressive-out cannot keep its snapshots under it\n",
            at("file")
        )
    );
    // A .partial output may have any name; the scene is the next thing that fails.
    let err = render(&["-o", &at("out.gif"), "--partial"]);
    assert!(err.contains("no-such-scene.p3f"), "{err}");
    let entries: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        entries.len(),
        2,
        "only the directory and the file made here: {entries:?}"
    );
}

/// Under `ulimit -v 4000000` (about 3.8 GiB of address space) a 16384 x 16384 frame, which needs 10.5
/// GiB at 42 bytes a pixel, is refused with both sizes before anything is allocated: exit status 1, not
/// an abort, and no output; so is a counting render's larger need, even for a part.
#[cfg(target_os = "linux")]
#[test]
fn a_frame_larger_than_the_memory_limit_is_refused_with_both_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("huge.p3f");
    std::fs::write(
        &scene,
        "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0.01\nresolution 16384 16384\n\
         l 0 5 5\nf 1 1 1 1 0 0 0 0\ns 0 0 0 1\n",
    )
    .unwrap();
    let out = dir.path().join("huge.png");
    let run = Command::new("sh")
        .args(["-c", "ulimit -v 4000000 && exec \"$0\" \"$@\""])
        .arg(env!("CARGO_BIN_EXE_whitted"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let err = common::failed(&run, 1);
    // What is available is what the limit leaves of it after the process's own address space: below
    // 4,096,000,000 bytes (3.81 GiB).
    let prefix = "whitted: a 16384x16384 frame needs 10.50 GiB (42 bytes a pixel) and only ";
    let suffix = " GiB is available: lower the resolution, or render it in parts (--tiles K/N)\n";
    assert!(err.starts_with(prefix) && err.ends_with(suffix), "{err}");
    let available: f64 = err[prefix.len()..err.len() - suffix.len()].parse().unwrap();
    assert!(available > 0.0 && available < 3.82, "{err}");
    assert!(!out.exists());
    assert!(!Path::new(&format!("{}.partial", out.display())).exists());

    // Counting steps (a heatmap) spans the whole frame even for a part: 4096 x 4096 at 281 bytes a
    // pixel (4.39 GiB) is refused under the same limit, part or not, before anything is written.
    let part = dir.path().join("part.partial");
    let run = Command::new("sh")
        .args(["-c", "ulimit -v 4000000 && exec \"$0\" \"$@\""])
        .arg(env!("CARGO_BIN_EXE_whitted"))
        .args([
            "render",
            "--width",
            "4096",
            "--height",
            "4096",
            "--tiles",
            "0/64",
            "--heatmap",
            "nodes",
        ])
        .arg("-o")
        .arg(&part)
        .output()
        .unwrap();
    let err = common::failed(&run, 1);
    let prefix = "whitted: a 4096x4096 frame needs 4.39 GiB (281 bytes a pixel, counting steps) and only ";
    let suffix = " GiB is available: lower the resolution, or leave out --counters and --heatmap\n";
    assert!(err.starts_with(prefix) && err.ends_with(suffix), "{err}");
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "only the scene file"
    );
}

/// Every file a render may write is checked before the scene is loaded,
/// and nothing is made when one is refused: `--progressive-out` naming the output (it made a
/// directory of that name, rendered, then refused the image: a usage error now), a snapshot name
/// held by a directory (the render failed after writing half of its passes' mean), and the stop file
/// `OUT.partial` held by a directory (Ctrl-C then lost every finished tile, exit 1).
#[test]
fn every_file_a_render_may_write_is_checked_first() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let at = |name: &str| d.join(name).to_string_lossy().into_owned();
    let render = |args: &[&str], status| {
        fails(
            &[&["render", "no-such-scene.p3f", "--passes", "4"][..], args].concat(),
            status,
        )
    };
    let out = at("x.png");
    assert_eq!(
        render(&["-o", &out, "--progressive-out", &out], 2),
        format!(
            "whitted: {out}: --progressive-out names the output image, or a directory under it: expected a directory of its own for the snapshots\n"
        )
    );
    std::fs::create_dir_all(d.join("pg/x-0002.png")).unwrap();
    assert_eq!(
        render(&["-o", &out, "--progressive-out", &at("pg")], 1),
        format!(
            "whitted: {}: is not a regular file (a directory, a link or a device); refusing to replace it\n",
            at("pg/x-0002.png")
        )
    );
    std::fs::create_dir(d.join("x.png.partial")).unwrap();
    assert_eq!(
        render(&["-o", &out], 1),
        format!(
            "whitted: {out}.partial: is not a regular file (a directory, a link or a device); refusing to \
             replace it (Ctrl-C keeps the finished tiles in this file)\n"
        )
    );
    let mut entries: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    entries.sort();
    assert_eq!(
        entries,
        ["pg", "x.png.partial"],
        "nothing made but what the test made"
    );
}

/// `--threads` out of 1..=1024 is a usage error (exit status 2) in one line, for every subcommand that
/// takes it, before anything is loaded; 100000 used to print a panic of the standard library first.
#[test]
fn threads_out_of_range_are_a_usage_error() {
    for command in ["render", "bench"] {
        for n in ["0", "100000"] {
            let err = fails(&[command, "no-such-scene.p3f", "--threads", n], 2);
            assert!(
                err.starts_with(&format!(
                    "error: invalid value '{n}' for '--threads <THREADS>': {n} is not in 1..=1024\n"
                )),
                "{command} --threads {n}: {err}"
            );
        }
    }
}

/// `--partial` into an image's name writes a part all the same (scripts name parts freely), but says
/// so: a `.png` that holds no PNG would surprise whoever opens it.
#[test]
fn a_partial_written_under_an_image_name_is_warned_of() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("a.png");
    let png = png.to_str().unwrap();
    let args = [
        "render",
        "scenes/balls_low.p3f",
        "--width",
        "8",
        "--quiet",
        "--partial",
        "-o",
        png,
    ];
    let out = common::whitted(&args);
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    let warning = format!(
        "whitted: warning: {png} gets a .partial part of the frame, not an image, though its name says one; \
         `whitted merge` makes the image"
    );
    assert!(err.lines().any(|l| l == warning), "{err}");
    // A .partial name needs no such word.
    let part = dir.path().join("a.partial");
    let out = common::whitted(&[
        "render",
        "scenes/balls_low.p3f",
        "--width",
        "8",
        "--quiet",
        "-o",
        part.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    assert!(!String::from_utf8_lossy(&out.stderr).contains("gets a .partial part"));
}
