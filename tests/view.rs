//! `whitted view`: a clear error without a display; under Xvfb (when `xvfb-run` is installed) a real
//! window whose scripted frames give `render --passes`'s image.
#![cfg(feature = "view")]

mod common;

use std::path::Path;
use std::process::{Command, Output};

const BIN: &str = env!("CARGO_BIN_EXE_whitted");

/// `whitted ARGS` with no display server named in the environment.
fn headless(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("the binary runs")
}

/// The error line of a failed run: exit status 1, one `whitted:` line last, and no panic.
fn failure(out: &Output) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let last = stderr.lines().last().unwrap_or_default().to_string();
    assert!(last.starts_with("whitted: "), "{stderr}");
    last
}

#[test]
fn without_a_display_view_fails_with_one_clear_line() {
    let last = failure(&headless(&["view", "scenes/balls_low.p3f"]));
    assert!(last.contains("cannot open a window: no display"), "{last}");
    // The built-in scene too.
    let last = failure(&headless(&["view"]));
    assert!(last.contains("no display"), "{last}");
}

#[test]
fn a_missing_scene_is_reported_before_the_display() {
    let last = failure(&headless(&["view", "no/such/scene.p3f"]));
    assert!(last.contains("no/such/scene.p3f"), "{last}");
}

#[test]
fn a_display_that_does_not_answer_is_an_error_not_a_panic() {
    let out = Command::new(BIN)
        .args(["view", "scenes/balls_low.p3f"])
        .env("DISPLAY", ":8731")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .output()
        .expect("the binary runs");
    let last = failure(&out);
    assert!(last.contains("cannot open a window (DISPLAY=:8731)"), "{last}");
}

#[test]
fn screenshot_needs_frames() {
    let out = headless(&["view", "--screenshot", "x.png"]);
    assert_eq!(out.status.code(), Some(2), "a usage error");
}

#[test]
fn under_xvfb_the_scripted_frames_are_render_passes() {
    if !common::have("xvfb-run", &["--help"], "apt-get install xvfb") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot.png");
    let reference = dir.path().join("reference.png");
    let scene = "scenes/balls_low.p3f";
    // Without Wayland's variables, so that winit takes Xvfb's display even inside a Wayland session.
    let out = Command::new("xvfb-run")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .args([
            "-a",
            BIN,
            "view",
            scene,
            "--width",
            "96",
            "--threads",
            "2",
            "--frames",
            "3",
        ])
        .arg("--screenshot")
        .arg(&shot)
        .output()
        .expect("xvfb-run runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = Command::new(BIN)
        .args(["render", scene, "--width", "96", "--passes", "3", "-q", "-o"])
        .arg(&reference)
        .output()
        .expect("the binary runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (shot, reference) = (read(&shot), read(&reference));
    assert_eq!(shot.dimensions(), (96, 96));
    // A still camera's frames are the passes of a progressive render: the same image, bit for bit.
    assert!(
        shot == reference,
        "the viewer's third frame differs from render --passes 3"
    );
}

fn read(path: &Path) -> image::RgbImage {
    image::open(path).unwrap().to_rgb8()
}
