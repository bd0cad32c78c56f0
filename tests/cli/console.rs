//! Whatever becomes of the standard streams, no panic and no lost work:
//! a full standard output is an error (status 1, one line), a closed one ends the command quietly
//! (status 0, as `ls | head` ends `ls`), a standard error that cannot be written never costs the
//! image, and a scene that is a FIFO is refused without being opened (opening it waits for a writer).

use std::fs::File;
use std::os::fd::{FromRawFd, OwnedFd};
use std::os::unix::fs::OpenOptionsExt;
use std::path::Path;
use std::process::{Command, Output, Stdio};

use crate::common;

const BIN: &str = env!("CARGO_BIN_EXE_whitted");

/// `whitted ARGS` from the repository root with the given stdout and stderr.
fn run(args: &[&str], stdout: Stdio, stderr: Stdio) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(common::root())
        .stdout(stdout)
        .stderr(stderr)
        .output()
        .expect("the binary runs")
}

fn full() -> Stdio {
    Stdio::from(
        File::options()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full opens"),
    )
}

/// The write end of a pipe whose read end is already closed: every write fails with EPIPE.
fn closed_pipe() -> Stdio {
    let mut fds = [0; 2];
    // SAFETY: `pipe` fills `fds` with two new descriptors, each owned once below.
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0, "pipe");
    // SAFETY: the descriptors were just made and are owned by nothing else.
    let (read, write) = unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) };
    drop(read);
    Stdio::from(write)
}

fn stderr_of(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn a_full_stdout_is_one_error_line_and_status_1() {
    let dir = tempfile::tempdir().unwrap();
    let image = dir.path().join("stats.png");
    let image = image.to_str().unwrap();
    let cases: [&[&str]; 4] = [
        &["info", "scenes/balls_low.p3f"],
        &["info", "scenes/balls_low.p3f", "--json"],
        &[
            "render",
            "scenes/balls_low.p3f",
            "--width",
            "16",
            "--quiet",
            "--stats=json",
            "-o",
            image,
        ],
        &[
            "bench",
            "scenes/balls_low.p3f",
            "--width",
            "16",
            "--frames",
            "1",
            "--json",
        ],
    ];
    for args in cases {
        let out = run(args, full(), Stdio::piped());
        let err = stderr_of(&out);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        // The scene's warning (its aperture at spp 0) may come first; the error is the last line.
        assert_eq!(
            err.lines().last(),
            Some("whitted: cannot write to standard output: No space left on device (os error 28)"),
            "{args:?}: {err}"
        );
        assert!(
            err.lines()
                .rev()
                .skip(1)
                .all(|l| l.starts_with("whitted: warning: ")),
            "{err}"
        );
    }
    // The image was written before its report failed.
    assert!(Path::new(image).is_file());
}

#[test]
fn a_closed_stdout_ends_the_command_quietly() {
    for args in [
        &["info", "scenes/balls_low.p3f", "--accel", "bvh8"][..],
        &["info", "scenes/balls_low.p3f", "--json"],
        &["bench", "scenes/balls_low.p3f", "--width", "16", "--frames", "1"],
    ] {
        let out = run(args, closed_pipe(), Stdio::piped());
        let err = stderr_of(&out);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
        // Nothing but the scene's warnings: no error, no panic.
        assert!(
            err.lines().all(|l| l.starts_with("whitted: warning: ")),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn a_failing_stderr_never_costs_the_image() {
    let dir = tempfile::tempdir().unwrap();
    let at = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    // --spp 2 is not a square: a warning goes to stderr before the render.
    let warned = at("warned.png");
    let out = run(
        &[
            "render",
            "scenes/balls_low.p3f",
            "--width",
            "8",
            "--spp",
            "2",
            "--quiet",
            "-o",
            &warned,
        ],
        Stdio::null(),
        full(),
    );
    assert_eq!(out.status.code(), Some(0));
    assert!(Path::new(&warned).is_file(), "the image is written");
    // The summary and the text report go to stderr after the image.
    let stats = at("stats.png");
    let out = run(
        &[
            "render",
            "scenes/balls_low.p3f",
            "--width",
            "8",
            "--stats",
            "-o",
            &stats,
        ],
        Stdio::null(),
        full(),
    );
    assert_eq!(out.status.code(), Some(0));
    assert!(Path::new(&stats).is_file());
    // merge's note after the image.
    let part = at("p.partial");
    common::ok(&[
        "render",
        "scenes/balls_low.p3f",
        "--width",
        "8",
        "--quiet",
        "--partial",
        "-o",
        &part,
    ]);
    let merged = at("merged.png");
    let out = run(&["merge", &merged, &part], Stdio::null(), full());
    assert_eq!(out.status.code(), Some(0));
    assert!(Path::new(&merged).is_file());
}

#[test]
fn a_fifo_as_the_scene_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("f.p3f");
    common::mkfifo(&fifo);
    // A writer that opens the FIFO and closes it at once: a reader that opened it (the old
    // behaviour) reads an empty file and finishes, so neither answer can hang the test. The opening
    // blocks until a reader comes; the test is that reader at the end if the command never was.
    let writer = {
        let fifo = fifo.clone();
        std::thread::spawn(move || drop(File::options().write(true).open(fifo)))
    };
    let out = run(&["info", fifo.to_str().unwrap()], Stdio::null(), Stdio::piped());
    let reader = File::options()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(&fifo)
        .unwrap();
    writer.join().unwrap();
    drop(reader);
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(
        stderr_of(&out),
        format!(
            "whitted: {}: cannot open: it is not a regular file (a FIFO, a device or a socket)\n",
            fifo.display()
        )
    );
}
