//! What the commands do to the files around them, tried as a hostile user or a crowded cluster would: a
//! link planted where a temporary might go is not followed, a name another writer holds is not taken,
//! an output that is one of `merge`'s parts or read-only is refused, a stale stop file is said and
//! cleared, a FIFO is refused rather than waited on, and memory is checked before it is taken.
#![cfg(target_os = "linux")]

use std::path::Path;
use std::process::{Command, Output, Stdio};

use crate::common;

/// Runs `sh -c SCRIPT` in `dir` with `$W` the whitted binary.
fn sh(dir: &Path, script: &str) -> Output {
    Command::new("sh")
        .args(["-c", script])
        .env("W", env!("CARGO_BIN_EXE_whitted"))
        .current_dir(dir)
        .output()
        .unwrap()
}

/// A small scene file in `dir`, rendered in a moment.
fn scene(dir: &Path) -> String {
    let path = dir.join("s.p3f");
    std::fs::write(
        &path,
        "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0.01\nresolution 32 24\nl 0 5 5\n\
         f 1 0.5 0 1 0 0 0 0\ns 0 0 0 1\n",
    )
    .unwrap();
    path.to_string_lossy().into_owned()
}

/// Links planted at every name the temporaries once took (`.NAME.PID.tmp.EXT`, the process id known
/// to a script that `exec`s whitted) point at a file of the victim's: neither a render that fails
/// (a missing scene) nor one that writes an image, a heatmap and a stop file, nor a merge, truncates
/// or writes it, and every output is a regular file of its own.
#[test]
fn links_planted_at_predictable_temporary_names_are_not_followed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = scene(d);
    std::fs::write(d.join("victim"), "precious").unwrap();
    let plant = "for n in out.png out.heatmap.png out.heatmap.exr out.heatmap.json out.png.partial \
                 m.png; do ln -s victim \".$n.$$.tmp.${n##*.}\"; done";
    let failed = sh(d, &format!("{plant}; exec \"$W\" render missing.p3f -o out.png"));
    common::failed(&failed, 1);
    assert_eq!(std::fs::read_to_string(d.join("victim")).unwrap(), "precious");
    for name in common::names(d).iter().filter(|n| n.starts_with('.')) {
        std::fs::remove_file(d.join(name)).unwrap();
    }

    let rendered = sh(
        d,
        &format!("{plant}; exec \"$W\" render {s} -q --heatmap nodes -o out.png"),
    );
    common::failed(&rendered, 0);
    let part = sh(
        d,
        &format!("{plant}; exec \"$W\" render {s} -q --tiles 0/1 -o all.partial"),
    );
    common::failed(&part, 0);
    let merged = sh(d, &format!("{plant}; exec \"$W\" merge -q m.png all.partial"));
    common::failed(&merged, 0);
    assert_eq!(std::fs::read_to_string(d.join("victim")).unwrap(), "precious");
    for name in [
        "out.png",
        "out.heatmap.png",
        "out.heatmap.exr",
        "out.heatmap.json",
        "m.png",
    ] {
        let kind = std::fs::symlink_metadata(d.join(name)).unwrap().file_type();
        assert!(kind.is_file(), "{name} is not a regular file");
    }
}

/// A name another writer holds beside the output (here a directory at the name this process's
/// temporary once took, as a render of the same output in another container with the same process id
/// would hold it) does not make the render fail, and is left as it was.
#[test]
fn a_name_another_writer_holds_beside_the_output_is_not_taken() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = scene(d);
    let run = sh(
        d,
        &format!("mkdir \".out.png.$$.tmp.png\"; exec \"$W\" render {s} -q -o out.png"),
    );
    common::failed(&run, 0);
    let held: Vec<String> = common::names(d)
        .into_iter()
        .filter(|n| n.starts_with(".out.png."))
        .collect();
    assert_eq!(held.len(), 1, "{held:?}");
    assert!(d.join(&held[0]).is_dir());
    assert!(d.join("out.png").is_file());
}

/// `merge OUT PART...` where OUT is one of the parts, by the same name or another (a hard link), is a
/// usage error, and the part is left as it was.
#[test]
fn merge_refuses_an_output_that_is_one_of_its_parts() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = scene(d);
    for k in 0..2 {
        let out = d.join(format!("p{k}.png")).to_string_lossy().into_owned();
        common::ok(&[
            "render",
            &s,
            "-q",
            "--partial",
            "--tiles",
            &format!("{k}/2"),
            "-o",
            &out,
        ]);
    }
    let part = std::fs::read(d.join("p0.png")).unwrap();
    std::fs::hard_link(d.join("p0.png"), d.join("same.png")).unwrap();
    for output in ["p0.png", "same.png"] {
        let out = d.join(output).to_string_lossy().into_owned();
        let p0 = d.join("p0.png").to_string_lossy().into_owned();
        let p1 = d.join("p1.png").to_string_lossy().into_owned();
        let err = common::fails(&["merge", &out, &p0, &p1], 2);
        assert_eq!(
            err,
            format!(
                "whitted: {out}: is one of the parts ({p0}): the merged image would replace it; name \
                 another output\n"
            )
        );
        assert!(std::fs::read(d.join("p0.png")).unwrap() == part);
    }
}

/// A read-only output is not replaced, whoever runs the render (root too: its mode says it is kept):
/// refused before any work with its mode, the file unchanged.
#[test]
fn a_read_only_output_is_refused_before_any_work() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("kept.png");
    std::fs::write(&out, "mine").unwrap();
    std::fs::set_permissions(&out, std::fs::Permissions::from_mode(0o444)).unwrap();
    let out = out.to_string_lossy().into_owned();
    let err = common::fails(&["render", "missing.p3f", "-o", &out], 1);
    assert!(
        err.starts_with(&format!(
            "whitted: {out}: is read-only (mode 0444, owned by user "
        )) && err.ends_with("refusing to replace it: make it writable or remove it first\n"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "mine");
}

/// A stop file beside the output that a render without `--resume` does not use is named in a warning
/// before the render, and removed once the image is whole: no stale `.partial` beside a finished
/// image.
#[test]
fn a_stale_stop_file_is_named_and_cleared_by_a_render_that_finishes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = scene(d);
    let out = d.join("x.png").to_string_lossy().into_owned();
    let stop = format!("{out}.partial");
    common::ok(&["render", &s, "-q", "--tiles", "0/2", "-o", &stop]);
    let run = common::ok(&["render", &s, "-q", "-o", &out]);
    let err = String::from_utf8(run.stderr).unwrap();
    assert_eq!(
        err,
        format!(
            "whitted: warning: {stop} holds an interrupted render of {out}: this render starts over \
             without it (--resume goes on from it), and replaces it, or removes it once the image is \
             whole\n"
        )
    );
    assert_eq!(common::names(d), ["s.p3f", "x.png"]);
}

/// A FIFO among `merge`'s parts is refused at once, not waited on (nothing writes to it).
#[test]
fn merge_refuses_a_fifo_part_without_waiting() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fifo = d.join("p.partial");
    common::mkfifo(&fifo);
    let child = Command::new(env!("CARGO_BIN_EXE_whitted"))
        .arg("merge")
        .arg(d.join("m.png"))
        .arg(&fifo)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let err = common::failed(&common::wait_a_minute(child, "merge of a FIFO"), 1);
    assert_eq!(
        err,
        format!(
            "whitted: {}: cannot read the partial file: it is not a regular file (a FIFO, a device or a socket)\n",
            fifo.display()
        )
    );
}

/// `bench` and `merge` check memory before they take it, as `render` does: under `ulimit -v`, a
/// bench of a 16384 x 16384 frame and the merge of a 4096 x 2048 frame's parts are refused with the
/// sizes, exit status 1, not an abort.
#[test]
fn bench_and_merge_check_memory_first() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = scene(d);
    let bench = sh(
        d,
        &format!("ulimit -v 2000000 && exec \"$W\" bench {s} --frames 1 --width 16384 --height 16384"),
    );
    let err = common::failed(&bench, 1);
    let prefix = "whitted: a 16384x16384 frame needs 10.50 GiB (42 bytes a pixel) and only ";
    assert!(
        err.starts_with(prefix) && err.ends_with(" GiB is available: lower the resolution\n"),
        "{err}"
    );

    for k in 0..2 {
        let part = format!("p{k}.partial");
        let tiles = format!("{k}/2");
        let args = [
            "render", &s, "-q", "--width", "4096", "--height", "2048", "--tiles", &tiles, "-o",
        ];
        let run = Command::new(env!("CARGO_BIN_EXE_whitted"))
            .args(args)
            .arg(d.join(part))
            .output()
            .unwrap();
        common::failed(&run, 0);
    }
    // 4096 x 2048 x 74 bytes: 0.58 GiB, where the limit leaves less.
    let merge = sh(
        d,
        "ulimit -v 500000 && exec \"$W\" merge m.png p0.partial p1.partial",
    );
    let err = common::failed(&merge, 1);
    let prefix = "whitted: merging a 4096x2048 frame needs 0.58 GiB (74 bytes a pixel) and only ";
    let suffix = " GiB is available: merge on a machine with more memory free\n";
    assert!(err.starts_with(prefix) && err.ends_with(suffix), "{err}");
    assert!(!d.join("m.png").exists());
    // Without the limit the parts merge, one at a time.
    let merged = sh(d, "exec \"$W\" merge -q m.png p0.partial p1.partial");
    common::failed(&merged, 0);
}

/// An output named only by its extension (`.png`) is a hidden PNG, not an unknown format; a name of
/// 245 characters and `.png` (249 bytes) is written, its temporary's name being short.
#[test]
fn outputs_named_by_an_extension_alone_or_at_the_length_limit_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = scene(d);
    common::failed(&sh(d, &format!("exec \"$W\" render {s} -q -o .png")), 0);
    let png = std::fs::read(d.join(".png")).unwrap();
    assert!(png.starts_with(b"\x89PNG"));
    assert_eq!(common::images::decode_rgb8(&png).unwrap().width(), 32);
    let long = format!("{}.png", "n".repeat(245));
    common::failed(&sh(d, &format!("exec \"$W\" render {s} -q -o {long}")), 0);
    assert!(common::images::rgb(&d.join(&long)).width() == 32);
    assert_eq!(common::names(d), [".png".to_string(), long, "s.p3f".into()]);
}

/// A write the file system refuses midway (here a file-size limit, as a full disk would) is reported
/// in the system's words for every format, not the encoder's, and leaves nothing behind.
#[test]
fn a_failed_write_gives_the_systems_reason() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = scene(d);
    for out in ["x.exr", "x.png", "x.jpg", "x.ppm"] {
        // SIGXFSZ ignored, so that the write fails with EFBIG rather than the process being killed.
        let script = format!(
            "trap '' XFSZ; ulimit -f 2; exec \"$W\" render {s} -q --width 640 --height 480 --spp 0 -o {out}"
        );
        let err = common::failed(&sh(d, &script), 1);
        assert_eq!(
            err,
            format!("whitted: {out}: cannot write the image: File too large (os error 27)\n"),
            "{out}"
        );
        assert_eq!(common::names(d), ["s.p3f"], "{out}");
    }
}

/// `--progressive-out` under a directory that cannot take it names that directory, not a file in
/// its parent that would never be written; and a snapshot directory named as one of the heatmap's
/// files is a usage error before any work.
#[test]
fn snapshot_directories_are_checked_by_their_own_names() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let s = scene(d);
    let out = d.join("o.png").to_string_lossy().into_owned();
    let heat = d.join("o.heatmap.png").to_string_lossy().into_owned();
    let err = common::fails(
        &[
            "render",
            &s,
            "--passes",
            "2",
            "--heatmap",
            "nodes",
            "-o",
            &out,
            "--progressive-out",
            &heat,
        ],
        2,
    );
    assert_eq!(
        err,
        format!(
            "whitted: {heat}: --progressive-out names a file of the heatmap, or a directory under it: \
             expected a directory of its own for the snapshots\n"
        )
    );
    assert_eq!(common::names(d), ["s.p3f"]);

    // A directory to be made where nothing can be made, root or not (/proc takes no new entries):
    // the refusal names it, not a snapshot in its parent.
    let snaps = "/proc/whitted-snapshots";
    let err = common::fails(
        &[
            "render",
            &s,
            "--passes",
            "2",
            "-o",
            &out,
            "--progressive-out",
            snaps,
        ],
        1,
    );
    assert!(
        err.starts_with(&format!(
            "whitted: {snaps}: cannot make the directory: cannot write in /proc: "
        )),
        "{err}"
    );
}
