//! Ctrl-C, SIGTERM and SIGHUP during `whitted render`: what is finished is written, stderr says what
//! and how to go on, the exit status is 128 + the signal's number, and `--resume` with the same
//! arguments finishes the very image an uninterrupted render makes; the stop comes within a tile, and
//! a second signal ends the process at once.
#![cfg(target_os = "linux")]

use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::time::Duration;

use crate::common;

/// Starts `whitted ARGS` with stderr piped (so no progress bar is drawn).
fn spawn(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_whitted"))
        .args(args)
        .current_dir(common::root())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Field `n` (from 1) of `/proc/PID/stat`, after the command name (which may hold spaces).
fn stat_field(pid: u32, n: usize) -> Option<u64> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let after_name = &stat[stat.rfind(')')? + 2..];
    after_name.split(' ').nth(n - 3)?.parse().ok()
}

/// CPU time the process has used, in clock ticks (utime + stime).
fn cpu_ticks(pid: u32) -> u64 {
    stat_field(pid, 14).unwrap_or(0) + stat_field(pid, 15).unwrap_or(0)
}

/// Whether the process catches SIGINT (its Ctrl-C handler is installed, just before it renders).
fn catches_sigint(pid: u32) -> bool {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("SigCgt:"))
        .and_then(|mask| u64::from_str_radix(mask.trim(), 16).ok())
        .is_some_and(|mask| mask & (1 << (libc::SIGINT - 1)) != 0)
}

/// Waits (polling, 10,000 times at most) until `child` catches SIGINT and has then used `ticks` more
/// clock ticks of CPU time rendering, sends it SIGINT, and returns how it ended. Work done, not time
/// passed, decides when: the render has finished some tiles however loaded the machine is.
fn interrupt_after(child: Child, ticks: u64) -> Output {
    signal_after(&child, ticks, libc::SIGINT);
    child.wait_with_output().unwrap()
}

/// As [`interrupt_after`], with `signal`, without waiting for the end.
fn signal_after(child: &Child, ticks: u64, signal: libc::c_int) {
    let pid = child.id();
    let mut polls = 0;
    let mut poll = |what: &str| {
        polls += 1;
        assert!(polls < 10_000, "gave up waiting for {what}");
        std::thread::sleep(Duration::from_millis(10));
    };
    while !catches_sigint(pid) {
        poll("the Ctrl-C handler");
    }
    let start = cpu_ticks(pid);
    while cpu_ticks(pid) < start + ticks {
        poll("the render's CPU time");
    }
    assert_eq!(unsafe { libc::kill(pid as libc::pid_t, signal) }, 0);
}

/// Starts `whitted ARGS`, interrupts it after 10 clock ticks of rendering, and returns its stderr, after
/// checking that it exited with status 130.
fn interrupted(args: &[&str]) -> String {
    let result = interrupt_after(spawn(args), 10);
    let err = String::from_utf8(result.stderr).unwrap();
    assert_eq!(result.status.code(), Some(130), "{err}");
    err
}

/// Runs `whitted ARGS`, which must succeed; returns its stderr.
fn run(args: &[&str]) -> String {
    let out = common::whitted(args);
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(out.status.success(), "{args:?}: {err}");
    err
}

/// The number in `text` between `before` and `after`.
fn number_between(text: &str, before: &str, after: &str) -> u32 {
    let start = text
        .find(before)
        .unwrap_or_else(|| panic!("no \"{before}\" in {text}"))
        + before.len();
    let len = text[start..]
        .find(after)
        .unwrap_or_else(|| panic!("no \"{after}\" in {text}"));
    text[start..start + len].parse().unwrap()
}

/// A one-pass render interrupted keeps its finished tiles in `OUT.partial` (even with `-q`, stderr
/// says so); `--resume` renders the others and writes the same bytes as an uninterrupted render, then
/// removes `OUT.partial`.
#[test]
fn an_interrupted_render_keeps_its_tiles_and_resumes_into_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("one.png").to_string_lossy().into_owned();
    // The default scene at 320 x 240 (20 x 15 = 300 tiles), 36 samples a pixel, on one thread: seconds
    // of work, of which a tenth of a second is done when Ctrl-C comes.
    let args = [
        "render",
        "--width",
        "320",
        "--spp",
        "36",
        "--threads",
        "1",
        "-q",
        "-o",
        &out,
    ];
    let err = interrupted(&args);
    let finished = number_between(&err, "whitted: interrupted: wrote the ", " of 300 tiles finished");
    assert!((1..300).contains(&finished), "{err}");
    assert_eq!(
        err,
        format!(
            "whitted: interrupted: wrote the {finished} of 300 tiles finished to {out}.partial; the same \
             command with --resume renders the rest\n"
        )
    );
    assert_eq!(common::names(dir.path()), ["one.png.partial"]);

    let resumed = run(&[&args[..], &["--resume"]].concat());
    assert_eq!(resumed, "", "-q: nothing to say");
    assert_eq!(
        common::names(dir.path()),
        ["one.png"],
        "the .partial file is spent"
    );
    let whole = dir.path().join("whole.png").to_string_lossy().into_owned();
    run(&["render", "--width", "320", "--spp", "36", "-q", "-o", &whole]);
    assert!(
        std::fs::read(&out).unwrap() == std::fs::read(&whole).unwrap(),
        "the resumed image differs from the uninterrupted one"
    );
}

/// A progressive render interrupted writes the mean of its whole passes as the image (the same bytes
/// as `--passes K` for the K it reports, and its snapshot), their sums in `OUT.partial`, and exits 130;
/// `--resume` renders the passes left into the image of the uninterrupted render.
#[test]
fn an_interrupted_progressive_render_writes_its_passes_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("c.png").to_string_lossy().into_owned();
    let snaps = d.join("snaps").to_string_lossy().into_owned();
    // 64 x 48 at one sample a pass on one thread: some milliseconds a pass, 250 passes.
    let args = [
        "render",
        "--width",
        "64",
        "--spp",
        "1",
        "--passes",
        "250",
        "--threads",
        "1",
        "-o",
        &out,
        "--progressive-out",
        &snaps,
    ];
    let err = interrupted(&args);
    let k = number_between(&err, "whitted: interrupted after ", " of 250 passes");
    assert!((1..250).contains(&k), "{err}");
    assert_eq!(
        err,
        format!(
            "whitted: interrupted after {k} of 250 passes: wrote their mean to {out} and their sums to \
             {out}.partial; the same command with --resume renders the rest\n"
        )
    );
    assert_eq!(
        common::names(d),
        ["c.png", "c.png.partial", "snaps"],
        "no temporary file left"
    );
    let image = std::fs::read(&out).unwrap();
    assert!(image == std::fs::read(d.join(format!("snaps/c-{k:04}.png"))).unwrap());
    let reference = d.join("k.png").to_string_lossy().into_owned();
    let k_text = k.to_string();
    run(&[
        "render", "--width", "64", "--spp", "1", "--passes", &k_text, "-q", "-o", &reference,
    ]);
    assert!(
        image == std::fs::read(&reference).unwrap(),
        "not the mean of {k} passes"
    );

    let resumed = run(&[&args[..], &["--resume"]].concat());
    assert!(
        resumed.starts_with(&format!(
            "whitted: resuming from {out}.partial: {k} of 250 passes done\n"
        )),
        "{resumed}"
    );
    assert_eq!(common::names(d), ["c.png", "k.png", "snaps"]);
    run(&[
        "render", "--width", "64", "--spp", "1", "--passes", "250", "-q", "-o", &reference,
    ]);
    assert!(
        std::fs::read(&out).unwrap() == std::fs::read(&reference).unwrap(),
        "the resumed image differs from the uninterrupted one"
    );
}

/// `--resume` beside a stop file it cannot use (of another render, bit-flipped,
/// truncated, not a part at all) says which file it ignores and why, renders from the start, and
/// removes the file once the image is whole, as it removes one it resumed from (it went on silently
/// and left the stale file). A `.partial` output it cannot use is replaced by the whole part.
#[test]
fn resume_names_the_stop_file_it_ignores_and_why() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let at = |name: &str| d.join(name).to_string_lossy().into_owned();
    let args = |out: &str, seed: &str| {
        let args = ["render", "--width", "64", "--seed", seed, "-q", "-o", out];
        args.map(str::to_string).to_vec()
    };
    let run_args = |a: &[String]| run(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let part = at("part.partial");
    run_args(&args(&part, "3"));
    let good = std::fs::read(&part).unwrap();
    let mut flipped = good.clone();
    flipped[good.len() / 2] ^= 1;
    let reference = at("reference.png");
    run_args(&args(&reference, "0"));
    let out = at("x.png");
    for (bytes, why) in [
        (
            &good[..],
            "it is of another render (this render's vs the file's: seed 0 vs 3)".to_string(),
        ),
        (&flipped[..], "corrupt: checksum".to_string()),
        (
            &good[..100],
            "truncated: 100 bytes where its header describes".to_string(),
        ),
        (
            b"P6 not a part\n".as_slice(),
            "not a whitted partial file".to_string(),
        ),
    ] {
        std::fs::write(format!("{out}.partial"), bytes).unwrap();
        let err = run_args(&[args(&out, "0"), vec!["--resume".to_string()]].concat());
        let warning = format!("whitted: warning: --resume ignores {out}.partial: {why}");
        assert!(err.starts_with(&warning), "{err}");
        assert!(err.trim_end().ends_with("; rendering from the start"), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            std::fs::read(&out).unwrap() == std::fs::read(&reference).unwrap(),
            "{why}"
        );
        assert!(
            !Path::new(&format!("{out}.partial")).exists(),
            "{why}: the stale file is left"
        );
    }
    // A .partial output of another render is replaced by this one's part.
    let err = run_args(&[args(&part, "0"), vec!["--resume".to_string()]].concat());
    assert!(
        err.contains(&format!("--resume ignores {part}: it is of another render")),
        "{err}"
    );
    let merged = at("merged.png");
    run(&["merge", "-q", &merged, &part]);
    assert!(std::fs::read(&merged).unwrap() == std::fs::read(&reference).unwrap());
}

/// A write that fails in the middle of a progressive render (here a snapshot's name taken by a
/// directory after the render checked it) keeps the passes finished in `OUT.partial` and says so:
/// `--resume` then goes on from them into the uninterrupted render's image (the
/// render failed with the mean of 2 of 4 passes written and nothing to resume from).
#[test]
fn a_write_failing_mid_render_keeps_the_passes_finished() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("c.png").to_string_lossy().into_owned();
    let snaps = d.join("snaps");
    let args = [
        "render",
        "--width",
        "64",
        "--passes",
        "200",
        "--threads",
        "1",
        "-q",
        "-o",
        &out,
        "--progressive-out",
        snaps.to_str().unwrap(),
    ];
    let child = spawn(&args);
    let pid = child.id() as libc::pid_t;
    // Stopped (SIGSTOP) once a snapshot is written, the render cannot pass the names taken next.
    let mut polls = 0;
    while names_or_none(&snaps).is_empty() {
        polls += 1;
        assert!(polls < 10_000, "gave up waiting for the first snapshot");
        std::thread::sleep(Duration::from_millis(1));
    }
    assert_eq!(unsafe { libc::kill(pid, libc::SIGSTOP) }, 0);
    let written = names_or_none(&snaps).len() as u32;
    for k in written + 1..=200 {
        std::fs::create_dir(snaps.join(format!("c-{k:04}.png"))).unwrap();
    }
    assert_eq!(unsafe { libc::kill(pid, libc::SIGCONT) }, 0);
    let output = child.wait_with_output().unwrap();
    let err = String::from_utf8(output.stderr).unwrap();
    assert_eq!(output.status.code(), Some(1), "{err}");
    let kept = number_between(&err, "; the ", " passes finished are kept in ");
    assert!(kept > written, "{err}");
    let taken = snaps.join(format!("c-{kept:04}.png"));
    assert_eq!(
        err,
        format!(
            "whitted: {}: cannot write the image: is not a regular file (a directory, a link or a device); \
             refusing to replace it; \
             the {kept} passes finished are kept in {out}.partial: the same command with --resume goes on \
             from them\n",
            taken.display()
        )
    );
    for name in common::names(&snaps) {
        if std::fs::metadata(snaps.join(&name)).unwrap().is_dir() {
            std::fs::remove_dir(snaps.join(name)).unwrap();
        }
    }
    let resumed = run(&[&args[..], &["--resume"]].concat());
    assert!(
        resumed.starts_with(&format!(
            "whitted: resuming from {out}.partial: {kept} of 200 passes done\n"
        )) || resumed.is_empty(),
        "{resumed}"
    );
    let reference = d.join("reference.png").to_string_lossy().into_owned();
    run(&[
        "render", "--width", "64", "--passes", "200", "-q", "-o", &reference,
    ]);
    assert!(
        std::fs::read(&out).unwrap() == std::fs::read(&reference).unwrap(),
        "the resumed image differs from the uninterrupted one"
    );
    assert!(!Path::new(&format!("{out}.partial")).exists());
}

/// The names in `dir`, none if it does not exist yet.
fn names_or_none(dir: &Path) -> Vec<String> {
    if dir.is_dir() {
        common::names(dir)
    } else {
        Vec::new()
    }
}

/// SIGTERM (a scheduler's time limit, `scancel`) and SIGHUP keep the finished passes as Ctrl-C does:
/// the mean and the sums written, no temporary left, exit status 143 and 129, and `--resume` goes on
/// into the uninterrupted render's bytes.
#[test]
fn sigterm_and_sighup_keep_the_finished_passes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("t.png").to_string_lossy().into_owned();
    let args = [
        "render",
        "--width",
        "64",
        "--spp",
        "1",
        "--passes",
        "300",
        "--threads",
        "1",
        "-o",
        &out,
    ];
    for (signal, status, name) in [(libc::SIGTERM, 143, "SIGTERM"), (libc::SIGHUP, 129, "SIGHUP")] {
        let child = spawn(&args);
        signal_after(&child, 10, signal);
        let result = child.wait_with_output().unwrap();
        let err = String::from_utf8(result.stderr).unwrap();
        assert_eq!(result.status.code(), Some(status), "{err}");
        let k = number_between(
            &err,
            &format!("whitted: interrupted by {name} after "),
            " of 300 passes",
        );
        assert_eq!(
            err,
            format!(
                "whitted: interrupted by {name} after {k} of 300 passes: wrote their mean to {out} and \
                 their sums to {out}.partial; the same command with --resume renders the rest\n"
            )
        );
        assert_eq!(
            common::names(d),
            ["t.png", "t.png.partial"],
            "no temporary file left"
        );
        std::fs::remove_file(format!("{out}.partial")).unwrap();
    }
    let child = spawn(&args);
    signal_after(&child, 10, libc::SIGTERM);
    assert_eq!(child.wait_with_output().unwrap().status.code(), Some(143));
    run(&[&args[..], &["--resume"]].concat());
    assert!(
        std::fs::read(&out).unwrap() == uninterrupted(d, 300),
        "the resumed image differs from the uninterrupted one"
    );
    assert_eq!(common::names(d), ["r.png", "t.png"]);
}

/// Waits for `child`, returning its exit status and the CPU time it used in seconds (from `wait4`),
/// with its stderr read on a thread.
fn wait_with_cpu(mut child: Child) -> (i32, f64, String) {
    let mut stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut text = String::new();
        std::io::Read::read_to_string(&mut stderr, &mut text).unwrap();
        text
    });
    let mut status = 0;
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let pid = child.id() as libc::pid_t;
    assert_eq!(unsafe { libc::wait4(pid, &mut status, 0, &mut usage) }, pid);
    let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    let cpu = seconds(usage.ru_utime) + seconds(usage.ru_stime);
    (libc::WEXITSTATUS(status), cpu, reader.join().unwrap())
}

/// Ctrl-C stops within a tile: one 32 x 24 tile of 65,536 samples a pixel (tens of seconds of CPU on
/// one thread) stops at the next block of 4 x 2 pixels, so the whole process uses a small part of the
/// tile's CPU time (measured as work done, by `wait4`, not as time passed), and writes nothing.
#[test]
fn ctrl_c_stops_within_a_long_tile() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("l.png").to_string_lossy().into_owned();
    for kernel in ["packet", "single"] {
        let child = spawn(&[
            "render",
            "--width",
            "32",
            "--height",
            "24",
            "--spp",
            "65536",
            "--threads",
            "1",
            "--kernel",
            kernel,
            "-o",
            &out,
        ]);
        signal_after(&child, 10, libc::SIGINT);
        let (status, cpu, err) = wait_with_cpu(child);
        assert_eq!(status, 130, "{err}");
        assert_eq!(
            err,
            "whitted: interrupted before any tile was finished; nothing written\n"
        );
        assert!(
            cpu < 5.0,
            "{kernel}: {cpu} s of CPU: the stop waited for the tile"
        );
        assert_eq!(common::names(dir.path()), Vec::<String>::new());
    }
}

/// A second Ctrl-C ends the process at once, while the first waits for the block being rendered
/// (here a 4 x 2 image, one block, of 65,536 samples a pixel between two facing mirrors, 64 bounces
/// each: seconds of CPU); nothing half-written is left.
#[test]
fn a_second_ctrl_c_ends_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = d.join("mirrors.p3f");
    std::fs::write(
        &scene,
        "bclr 0 0 0\nv\nfrom 0 0 0\nat 0 0 -1\nup 0 1 0\nangle 5\nhither 0.01\nresolution 4 2\n\
         l 0 0.5 0 1 1 1\nf 0.1 0.1 0.1 0.05 0.9 0.9 0.9 0.9 500 0 1\n\
         pl 0 0 -1 1 0 -1 0 1 -1\npl 0 0 1 0 1 1 1 0 1\n",
    )
    .unwrap();
    let out = d.join("m.png").to_string_lossy().into_owned();
    let child = spawn(&[
        "render",
        scene.to_str().unwrap(),
        "--spp",
        "65536",
        "--max-depth",
        "64",
        "--threads",
        "1",
        "-o",
        &out,
    ]);
    signal_after(&child, 10, libc::SIGINT);
    std::thread::sleep(Duration::from_millis(100));
    let state = stat_state(child.id());
    assert!(
        state.is_some_and(|s| s != 'Z'),
        "the first Ctrl-C ended the render before a second could be sent: the block is too cheap"
    );
    assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) }, 0);
    let (status, cpu, err) = wait_with_cpu(child);
    assert_eq!(status, 130, "{err}");
    assert_eq!(
        err,
        "whitted: Ctrl-C again: stopped at once; nothing more is written\n"
    );
    assert!(
        cpu < 1.0 + 0.2,
        "{cpu} s of CPU: the second Ctrl-C waited for the block"
    );
    assert_eq!(common::names(d), ["mirrors.p3f"]);
}

/// The state letter of `/proc/PID/stat` (R, S, Z...), if the process is there.
fn stat_state(pid: u32) -> Option<char> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    stat[stat.rfind(')')? + 2..].chars().next()
}

/// Interrupted, a `--heatmap` render gives advice that works: it cannot go on with its map, so the same
/// command starts over, or `--resume` without `--heatmap` renders the rest without the map.
#[test]
fn an_interrupted_heatmap_render_advises_what_works() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let out = d.join("h.png").to_string_lossy().into_owned();
    let args = [
        "render",
        "--width",
        "64",
        "--spp",
        "1",
        "--threads",
        "1",
        "-o",
        &out,
    ];
    let heat = [&args[..], &["--passes", "300", "--heatmap", "nodes"]].concat();
    let err = interrupted(&heat);
    let k = number_between(&err, "whitted: interrupted after ", " of 300 passes");
    assert_eq!(
        err,
        format!(
            "whitted: interrupted after {k} of 300 passes: wrote their mean to {out} and their sums to \
             {out}.partial; a --heatmap render cannot go on from them: the same command renders it again \
             from the start, or, without --heatmap, with --resume renders the rest without the map\n"
        )
    );
    run(&[&args[..], &["--passes", "300", "--resume", "-q"]].concat());
    assert!(
        std::fs::read(&out).unwrap() == uninterrupted(d, 300),
        "the resumed image differs from the uninterrupted one"
    );
}

/// The bytes of the default scene at 64 x 48, one sample a pass, `passes` passes, rendered in one go
/// to `dir/r.png`.
fn uninterrupted(dir: &Path, passes: u32) -> Vec<u8> {
    let reference = dir.join("r.png").to_string_lossy().into_owned();
    let passes = passes.to_string();
    run(&[
        "render", "--width", "64", "--spp", "1", "--passes", &passes, "-q", "-o", &reference,
    ]);
    std::fs::read(reference).unwrap()
}
