//! `whitted view`: a clear error without a display; under Xvfb (when `xvfb-run` is installed) a real
//! window whose scripted frames give `render --passes`'s image, whose options (`--height`, `--accel`,
//! `--kernel`, `--max-depth`, `--srgb`) reach the frame, its title and its screenshot, whose pixels
//! are the frame's, which resizes and closes, and whose keys (F12, Ctrl-S, P, Escape, pressed through
//! the X server's XTEST extension) save, pause and quit.
#![cfg(feature = "view")]

#[path = "../common/mod.rs"]
mod common;

use std::path::Path;
use std::process::{Command, Output};

use common::{failure, ok};

const BIN: &str = env!("CARGO_BIN_EXE_whitted");

/// One Xvfb at a time: `xvfb-run -a` picks the first free display number, and two started at once can
/// pick the same one.
static XVFB: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Holds [`XVFB`] for a test (a test that failed holding it leaves it usable).
fn one_xvfb() -> std::sync::MutexGuard<'static, ()> {
    XVFB.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

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

#[test]
fn without_a_display_view_fails_with_one_clear_line() {
    let last = failure(&headless(&["view", "scenes/balls_low.p3f"]));
    assert!(last.contains("cannot open a window: no display"), "{last}");
    // The built-in scene too.
    let last = failure(&headless(&["view"]));
    assert!(last.contains("no display"), "{last}");
}

#[test]
fn a_wayland_session_without_xwayland_is_no_display() {
    // The viewer speaks X11 only: a Wayland socket alone is not a display it can use.
    let out = Command::new(BIN)
        .args(["view", "scenes/balls_low.p3f"])
        .env_remove("DISPLAY")
        .env("WAYLAND_DISPLAY", "wayland-0")
        .output()
        .expect("the binary runs");
    let last = failure(&out);
    assert!(
        last.contains("no display (DISPLAY is not set; on Wayland the viewer needs XWayland)"),
        "{last}"
    );
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

/// A window side over 65535 (X11's sizes are 16-bit) is a usage error naming the option and its range,
/// given or made from the scene's frame, before any window (the protocol cannot carry it): here,
/// without a display, before the display is even looked for.
#[test]
fn a_window_side_over_65535_is_a_usage_error() {
    let expected = |option: &str, found: &str| {
        format!(
            "whitted: {option}: expected 1 to 65535 for the viewer's window (X11's largest), found {found}"
        )
    };
    let scene = "scenes/balls_low.p3f";
    for (args, last) in [
        (
            &[scene, "--width", "65536", "--height", "8"][..],
            expected("--width", "65536"),
        ),
        (
            &[scene, "--width", "8", "--height", "65536"],
            expected("--height", "65536"),
        ),
    ] {
        let out = headless(&[&["view"][..], args].concat());
        assert_eq!(common::usage_failure(&out), last, "{args:?}");
    }
    let dir = tempfile::tempdir().unwrap();
    let wide = dir.path().join("wide.p3f");
    std::fs::write(
        &wide,
        "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0.01\nresolution 65536 4\n\
         l 0 5 5\nf 1 1 1 1 0 0 0 0\ns 0 0 0 1\n",
    )
    .unwrap();
    let wide = wide.to_str().unwrap();
    for (args, last) in [
        (&[wide][..], expected("--width", "65536 (the scene's resolution)")),
        (
            &[wide, "--height", "8"],
            expected("--width", "131072 (the scene's aspect ratio at --height 8)"),
        ),
    ] {
        let out = headless(&[&["view"][..], args].concat());
        assert_eq!(common::usage_failure(&out), last, "{args:?}");
    }
}

/// `--screenshot` is checked as `render -o` is, before the scene is loaded (here one that does not
/// exist) and before any window: an unknown format, a missing directory, a link at the path.
#[test]
fn a_screenshot_that_could_not_be_written_is_refused_first() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let link = d.join("link.png");
    std::os::unix::fs::symlink(d.join("elsewhere.png"), &link).unwrap();
    for (path, message) in [
        (
            d.join("shot.gif"),
            "unknown image format: expected a .png, .ppm, .jpg, .jpeg or .exr file name".to_string(),
        ),
        (
            d.join("missing/shot.png"),
            format!("the directory {} does not exist", d.join("missing").display()),
        ),
        (
            link,
            "is not a regular file (a directory, a link or a device); refusing to replace it".to_string(),
        ),
    ] {
        let shot = path.to_str().unwrap();
        let args = ["view", "no/such/scene.p3f", "--frames", "1", "--screenshot", shot];
        let last = common::failure(&headless(&args));
        assert_eq!(last, format!("whitted: {shot}: {message}"));
    }
}

#[test]
fn under_xvfb_the_scripted_frames_are_render_passes() {
    if !common::have("xvfb-run", &["--help"], "apt-get install xvfb") {
        return;
    }
    let _xvfb = one_xvfb();
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot.png");
    let reference = dir.path().join("reference.png");
    let scene = "scenes/balls_low.p3f";
    // Without Wayland's variables: the same run inside a Wayland session as outside.
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

fn read(path: &Path) -> common::images::Rgb8 {
    common::images::rgb(path)
}

/// Out-of-range or unknown values are usage errors (exit status 2) named by clap, before any window.
#[test]
fn bad_option_values_are_usage_errors() {
    for (args, first_line) in [
        (
            &["--max-depth", "33"][..],
            "error: invalid value '33' for '--max-depth <MAX_DEPTH>': 33 is not in 0..=32",
        ),
        (
            &["--accel", "kd"],
            "error: invalid value 'kd' for '--accel <ACCEL>': unknown accelerator \"kd\": expected none, \
             grid, bvh2, bvh4, bvh8 or auto",
        ),
        (
            &["--kernel", "simd"],
            "error: invalid value 'simd' for '--kernel <KERNEL>': unknown kernel \"simd\": expected \
             single or packet",
        ),
        (
            &["--threads", "0"],
            "error: invalid value '0' for '--threads <THREADS>': 0 is not in 1..=1024",
        ),
        (
            &["--frames", "0"],
            "error: invalid value '0' for '--frames <FRAMES>': 0 is not in 1..=4294967295",
        ),
    ] {
        let out = headless(&[&["view", "scenes/balls_low.p3f"][..], args].concat());
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().next(), Some(first_line), "{args:?}");
    }
}

/// `whitted ARGS` under `xvfb-run`, which must succeed.
fn under_xvfb(args: &[&str]) {
    let out = Command::new("xvfb-run")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .arg("-a")
        .arg(BIN)
        .args(args)
        .current_dir(common::root())
        .output()
        .expect("xvfb-run runs");
    assert!(
        out.status.success(),
        "view {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The viewer's options reach its frames: each screenshot after 2 frames is `render --passes 2`'s image
/// with the same options (--height alone keeps the file's aspect ratio; --max-depth 1 and --srgb change
/// the image; --accel and --kernel keep it).
#[test]
fn under_xvfb_the_options_reach_the_screenshot() {
    if !common::have("xvfb-run", &["--help"], "apt-get install xvfb") {
        return;
    }
    let _xvfb = one_xvfb();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let at = |name: &str| d.join(name).to_str().unwrap().to_string();
    let balls = ["scenes/balls_low.p3f", "--width", "48", "--height", "32"];
    let mut shots = Vec::new();
    for (name, options) in [
        ("plain", &balls[..]),
        // The built-in scene, scenes/default.p3f: 640x480.
        ("height", &["--height", "30"]),
        ("depth", &[&balls[..], &["--max-depth", "1"]].concat()),
        ("srgb", &[&balls[..], &["--srgb"]].concat()),
        (
            "structures",
            &[&balls[..], &["--accel", "grid", "--kernel", "single"]].concat(),
        ),
    ] {
        let shot = at(&format!("{name}-view.png"));
        let reference = at(&format!("{name}-render.png"));
        let common = [&["--threads", "2"][..], options].concat();
        under_xvfb(&[&["view"][..], &common, &["--frames", "2", "--screenshot", &shot]].concat());
        // render takes --accel and --kernel too: the same words, the same image.
        ok(&[
            &["render", "-q"][..],
            &common,
            &["--passes", "2", "-o", &reference],
        ]
        .concat());
        let (shot, reference) = (read(Path::new(&shot)), read(Path::new(&reference)));
        assert!(
            shot == reference,
            "{name}: the screenshot is not render --passes 2's image"
        );
        shots.push((name, shot));
    }
    let image = |name: &str| &shots.iter().find(|(n, _)| *n == name).unwrap().1;
    // The default scene is 640x480: --height 30 alone is 40 wide.
    assert_eq!(image("height").dimensions(), (40, 30));
    assert_eq!(image("plain").dimensions(), (48, 32));
    assert!(image("depth") != image("plain"), "--max-depth 1 changes nothing");
    assert!(image("srgb") != image("plain"), "--srgb changes nothing");
    assert!(
        image("structures") == image("plain"),
        "--accel or --kernel change the image"
    );
}

/// The viewer on `scenes/balls_low.p3f` at 48x32 on two threads, with `more` arguments, under the
/// test's Xvfb.
#[cfg(target_os = "linux")]
fn small_viewer(dir: &Path, more: &[&str]) -> keys::Viewer {
    let scene = common::root().join("scenes/balls_low.p3f");
    let args = [
        scene.to_str().unwrap(),
        "--width",
        "48",
        "--height",
        "32",
        "--threads",
        "2",
    ];
    keys::Viewer::start(dir, &[&args[..], more].concat())
}

/// Under Xvfb, the viewer's keys through XTEST: the title shows the options given (accelerator,
/// kernel, size, depth); F12 and then Ctrl-S save the frame on screen as `balls_low-view-1.png` and
/// `-2.png` in the current directory, each with the `whitted render` command that renders the same
/// image (run here: the same pixels), Ctrl-S without moving the camera back as S alone would; Escape
/// quits with status 0.
#[cfg(target_os = "linux")]
#[test]
fn under_xvfb_f12_and_ctrl_s_save_what_render_renders_and_escape_quits() {
    if !common::have("xvfb-run", &["--help"], "apt-get install xvfb") {
        return;
    }
    let _xvfb = one_xvfb();
    let dir = tempfile::tempdir().unwrap();
    let mut viewer = small_viewer(
        dir.path(),
        &[
            "--accel",
            "grid",
            "--kernel",
            "single",
            "--max-depth",
            "2",
            "--srgb",
        ],
    );
    let title = viewer.title_once(|t| t.contains(" | pass "));
    for part in ["| grid, single |", "| 48x32 (full) |", ", depth 2"] {
        assert!(title.contains(part), "{part}: {title}");
    }
    assert!(title.starts_with("whitted: balls_low.p3f | "), "{title}");

    viewer.press(&[keys::F12]);
    let first = viewer.saved("balls_low-view-1.png");
    viewer.press(&[keys::CONTROL_L, keys::S]);
    let second = viewer.saved("balls_low-view-2.png");
    viewer.press(&[keys::ESCAPE]);
    let status = viewer.wait();
    assert_eq!(status.code(), Some(0), "Escape quits: {}", viewer.stderr());

    // Ctrl-S saved the same view: S's move back did not happen.
    let from = |command: &str| {
        let words: Vec<&str> = command.split_whitespace().collect();
        let i = words.iter().position(|w| *w == "--from").unwrap();
        words[i + 1].to_string()
    };
    assert_eq!(from(&first.command), from(&second.command));
    for (k, saved) in [first, second].into_iter().enumerate() {
        let file = dir.path().join(&saved.file);
        let shot = read(&file);
        assert_eq!(shot.dimensions(), (48, 32));
        let command = saved.command.strip_prefix("whitted render ").unwrap();
        for word in ["--max-depth 2", "--srgb", "--width 48 --height 32"] {
            assert!(command.contains(word), "{word}: {command}");
        }
        let reference = dir.path().join(format!("reference-{k}.png"));
        let mut words: Vec<&str> = command.split_whitespace().collect();
        words.extend(["-q", "-o", reference.to_str().unwrap()]);
        let out = Command::new(BIN)
            .arg("render")
            .args(&words)
            .output()
            .expect("the binary runs");
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        assert!(
            read(&reference) == shot,
            "{}: not the image of its command: whitted render {command}",
            saved.file
        );
    }
}

/// Under Xvfb, what the window shows: after P (no more passes) and F12, the window's pixels, read
/// back from the X server, are the saved frame's, pixel for pixel; a resize (no window manager here, so
/// the test's own) renders at the new size; the close button's message (WM_DELETE_WINDOW) quits with
/// status 0.
#[cfg(target_os = "linux")]
#[test]
fn under_xvfb_the_window_shows_the_frame_resizes_and_closes() {
    if !common::have("xvfb-run", &["--help"], "apt-get install xvfb") {
        return;
    }
    let _xvfb = one_xvfb();
    let dir = tempfile::tempdir().unwrap();
    let mut viewer = small_viewer(dir.path(), &[]);
    viewer.title_once(|t| t.contains(" | pass "));
    viewer.press(&[keys::P]);
    viewer.title_once(|t| t.ends_with(" | progressive off"));
    // A pass that was ending when P came may still be shown: let it.
    std::thread::sleep(std::time::Duration::from_millis(500));
    viewer.press(&[keys::F12]);
    viewer.saved("balls_low-view-1.png");
    let shot = read(&dir.path().join("balls_low-view-1.png"));
    let (width, height, pixels) = viewer.pixels();
    assert_eq!((width, height), (48, 32));
    assert!(
        pixels == shot.data[..],
        "the window does not show the saved frame"
    );

    viewer.resize(96, 64);
    viewer.title_once(|t| t.contains(" | 96x64 (full) | "));
    viewer.close();
    let status = viewer.wait();
    assert_eq!(
        status.code(),
        Some(0),
        "the close button quits: {}",
        viewer.stderr()
    );
}

/// Under Xvfb, a key held down acts once: `]` held for a second (the server repeats it many times)
/// adds one bounce, not one per repeat.
#[cfg(target_os = "linux")]
#[test]
fn under_xvfb_a_held_key_acts_once() {
    if !common::have("xvfb-run", &["--help"], "apt-get install xvfb") {
        return;
    }
    let _xvfb = one_xvfb();
    let dir = tempfile::tempdir().unwrap();
    let mut viewer = small_viewer(dir.path(), &[]);
    viewer.title_once(|t| t.ends_with(", depth 6"));
    viewer.hold(keys::BRACKET_RIGHT, std::time::Duration::from_secs(1));
    // Frames come after the release (the title follows them); a repeat would be in them by now.
    std::thread::sleep(std::time::Duration::from_millis(300));
    let title = viewer.title_once(|t| t.contains(" | pass "));
    assert!(title.ends_with(", depth 7"), "{title}");
    viewer.press(&[keys::ESCAPE]);
    assert_eq!(viewer.wait().code(), Some(0), "{}", viewer.stderr());
}

/// Driving the viewer's window under Xvfb: its display read from the shell xvfb-run starts, its window
/// found by title, its keys pressed through XTEST, its stderr read line by line.
#[cfg(target_os = "linux")]
mod keys {
    use std::io::{BufRead, BufReader};
    use std::path::Path;
    use std::process::{Child, Command, ExitStatus, Stdio};
    use std::sync::mpsc::{Receiver, channel};
    use std::time::Duration;

    use x11rb::connection::{Connection, RequestConnection};
    use x11rb::protocol::xproto::{
        AtomEnum, ClientMessageEvent, ConfigureWindowAux, ConnectionExt as _, EventMask, ImageFormat,
        ImageOrder, InputFocus, KEY_PRESS_EVENT, KEY_RELEASE_EVENT, MapState, Window,
    };
    use x11rb::protocol::xtest::ConnectionExt as _;
    use x11rb::rust_connection::RustConnection;

    /// Keysyms (X11's keysymdef.h).
    pub const F12: u32 = 0xffc9;
    pub const CONTROL_L: u32 = 0xffe3;
    pub const S: u32 = 0x0073;
    pub const ESCAPE: u32 = 0xff1b;
    pub const P: u32 = 0x0070;
    pub const BRACKET_RIGHT: u32 = 0x005d;

    /// How long anything may take: a window opening, a frame, a save.
    const PATIENCE: Duration = Duration::from_secs(60);

    /// A saved image: its file name and the `whitted render` command printed with it.
    pub struct Saved {
        pub file: String,
        pub command: String,
    }

    pub struct Viewer {
        /// xvfb-run.
        child: Child,
        /// The viewer's process.
        pid: i32,
        lines: Receiver<String>,
        seen: Vec<String>,
        conn: RustConnection,
        root: Window,
        window: Window,
    }

    /// Polls of [`until`] before it gives up on a viewer that never gets there (a hang guard, not a
    /// measure of speed: a slow machine only polls more).
    const POLLS: u32 = 3000;

    fn until<T>(what: &str, mut f: impl FnMut() -> Option<T>) -> T {
        for _ in 0..POLLS {
            if let Some(v) = f() {
                return v;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        panic!("gave up waiting for {what} after {POLLS} polls");
    }

    impl Viewer {
        /// `whitted view ARGS` in `dir` under a new Xvfb that takes any client (`-ac`), and its window.
        pub fn start(dir: &Path, args: &[&str]) -> Viewer {
            let display_file = dir.join("display");
            let mut child = Command::new("xvfb-run")
                .env_remove("WAYLAND_DISPLAY")
                .env_remove("WAYLAND_SOCKET")
                .args(["-a", "-s", "-ac -screen 0 640x480x24", "sh", "-c"])
                .arg(
                    "echo $$ > pid && echo \"$DISPLAY\" > display.tmp && mv display.tmp display && \
                     exec \"$0\" view \"$@\"",
                )
                .arg(super::BIN)
                .args(args)
                .current_dir(dir)
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .expect("xvfb-run runs");
            let stderr = child.stderr.take().unwrap();
            let (send, lines) = channel();
            std::thread::spawn(move || {
                for line in BufReader::new(stderr).lines() {
                    let Ok(line) = line else { break };
                    if send.send(line).is_err() {
                        break;
                    }
                }
            });
            let display = until("xvfb-run's display", || {
                let d = std::fs::read_to_string(&display_file).ok()?;
                Some(d.trim().to_string())
            });
            // The shell's process becomes the viewer's (exec).
            let pid = std::fs::read_to_string(dir.join("pid")).unwrap();
            let pid = pid.trim().parse().unwrap();
            let (conn, screen) = until("a connection to the X server", || {
                x11rb::connect(Some(&display)).ok()
            });
            let root = conn.setup().roots[screen].root;
            let xtest = conn
                .extension_information(x11rb::protocol::xtest::X11_EXTENSION_NAME)
                .unwrap();
            assert!(xtest.is_some(), "Xvfb without XTEST");
            let mut viewer = Viewer {
                child,
                pid,
                lines,
                seen: Vec::new(),
                conn,
                root,
                window: 0,
            };
            viewer.window = until("the viewer's window", || viewer.find_window());
            viewer
                .conn
                .set_input_focus(InputFocus::POINTER_ROOT, viewer.window, x11rb::CURRENT_TIME)
                .unwrap();
            viewer.conn.get_input_focus().unwrap().reply().unwrap();
            viewer
        }

        /// The mapped top-level window titled `whitted: ...`.
        fn find_window(&self) -> Option<Window> {
            let children = self.conn.query_tree(self.root).ok()?.reply().ok()?.children;
            children.into_iter().find(|&w| {
                let mapped = self
                    .conn
                    .get_window_attributes(w)
                    .ok()
                    .and_then(|c| c.reply().ok())
                    .is_some_and(|a| a.map_state == MapState::VIEWABLE);
                mapped && self.title(w).is_some_and(|t| t.starts_with("whitted: "))
            })
        }

        /// A window's title: `_NET_WM_NAME` (UTF-8), else `WM_NAME`.
        fn title(&self, window: Window) -> Option<String> {
            let net = self
                .conn
                .intern_atom(false, b"_NET_WM_NAME")
                .ok()?
                .reply()
                .ok()?
                .atom;
            for atom in [net, AtomEnum::WM_NAME.into()] {
                let value = self
                    .conn
                    .get_property(false, window, atom, AtomEnum::ANY, 0, 1024)
                    .ok()?
                    .reply()
                    .ok()?
                    .value;
                if !value.is_empty() {
                    return String::from_utf8(value).ok();
                }
            }
            None
        }

        /// The first title of the window that `want` accepts.
        pub fn title_once(&self, want: impl Fn(&str) -> bool) -> String {
            until("the title", || self.title(self.window).filter(|t| want(t)))
        }

        /// The keycode of `keysym` in the server's keymap.
        fn keycode(&self, keysym: u32) -> u8 {
            let setup = self.conn.setup();
            let (min, max) = (setup.min_keycode, setup.max_keycode);
            let map = self
                .conn
                .get_keyboard_mapping(min, max - min + 1)
                .unwrap()
                .reply()
                .unwrap();
            let per = map.keysyms_per_keycode as usize;
            let index = map
                .keysyms
                .chunks(per)
                .position(|syms| syms.first() == Some(&keysym))
                .unwrap_or_else(|| panic!("no key for keysym {keysym:#x}"));
            min + index as u8
        }

        /// Presses `keysyms` in order, then releases them in the reverse order.
        pub fn press(&mut self, keysyms: &[u32]) {
            let codes: Vec<u8> = keysyms.iter().map(|&k| self.keycode(k)).collect();
            let fake = |kind: u8, code: u8| {
                self.conn
                    .xtest_fake_input(kind, code, x11rb::CURRENT_TIME, self.root, 0, 0, 0)
                    .unwrap();
            };
            for &code in &codes {
                fake(KEY_PRESS_EVENT, code);
            }
            for &code in codes.iter().rev() {
                fake(KEY_RELEASE_EVENT, code);
            }
            self.conn.get_input_focus().unwrap().reply().unwrap();
        }

        /// Holds `keysym` down for `time` (long enough, the server repeats it), then lets it go.
        pub fn hold(&mut self, keysym: u32, time: Duration) {
            let code = self.keycode(keysym);
            for kind in [KEY_PRESS_EVENT, KEY_RELEASE_EVENT] {
                self.conn
                    .xtest_fake_input(kind, code, x11rb::CURRENT_TIME, self.root, 0, 0, 0)
                    .unwrap();
                self.conn.get_input_focus().unwrap().reply().unwrap();
                if kind == KEY_PRESS_EVENT {
                    std::thread::sleep(time);
                }
            }
        }

        /// The window's size and its pixels as RGB bytes, row after row, read back from the server
        /// (Xvfb's 24-bit TrueColor screen: 32-bit pixels, red, green and blue bytes from the top).
        pub fn pixels(&self) -> (u16, u16, Vec<u8>) {
            let geometry = self.conn.get_geometry(self.window).unwrap().reply().unwrap();
            let (width, height) = (geometry.width, geometry.height);
            let image = self
                .conn
                .get_image(ImageFormat::Z_PIXMAP, self.window, 0, 0, width, height, !0)
                .unwrap()
                .reply()
                .unwrap();
            let setup = self.conn.setup();
            let format = setup
                .pixmap_formats
                .iter()
                .find(|f| f.depth == image.depth)
                .unwrap();
            assert_eq!((image.depth, format.bits_per_pixel), (24, 32), "Xvfb's screen");
            let rgb = image
                .data
                .chunks_exact(4)
                .flat_map(|p| {
                    let p = [p[0], p[1], p[2], p[3]];
                    let word = match setup.image_byte_order {
                        ImageOrder::MSB_FIRST => u32::from_be_bytes(p),
                        _ => u32::from_le_bytes(p),
                    };
                    [(word >> 16) as u8, (word >> 8) as u8, word as u8]
                })
                .collect();
            (width, height, rgb)
        }

        /// Resizes the window, as a window manager would.
        pub fn resize(&self, width: u32, height: u32) {
            let size = ConfigureWindowAux::new().width(width).height(height);
            self.conn.configure_window(self.window, &size).unwrap();
            self.conn.get_input_focus().unwrap().reply().unwrap();
        }

        /// Clicks the window's close button: the window manager's WM_DELETE_WINDOW message.
        pub fn close(&self) {
            let atom = |name: &[u8]| self.conn.intern_atom(false, name).unwrap().reply().unwrap().atom;
            let (protocols, delete) = (atom(b"WM_PROTOCOLS"), atom(b"WM_DELETE_WINDOW"));
            let message = ClientMessageEvent::new(32, self.window, protocols, [delete, 0, 0, 0, 0]);
            self.conn
                .send_event(false, self.window, EventMask::NO_EVENT, message)
                .unwrap();
            self.conn.get_input_focus().unwrap().reply().unwrap();
        }

        /// The next stderr line.
        fn line(&mut self, what: &str) -> String {
            let line = self.lines.recv_timeout(PATIENCE).unwrap_or_else(|_| {
                panic!(
                    "timed out waiting for {what}; stderr so far:\n{}",
                    self.seen.join("\n")
                )
            });
            self.seen.push(line.clone());
            line
        }

        /// Waits for `whitted: saved FILE (...)` and the `whitted render` command printed after it.
        pub fn saved(&mut self, file: &str) -> Saved {
            let prefix = format!("whitted: saved {file} (48x32, ");
            while !self.line(&prefix).starts_with(&prefix) {}
            loop {
                let line = self.line("the render command");
                if line.starts_with("whitted render ") {
                    return Saved {
                        file: file.to_string(),
                        command: line,
                    };
                }
            }
        }

        /// The exit status, once the viewer (and xvfb-run) ended.
        pub fn wait(&mut self) -> ExitStatus {
            until("the viewer to quit", || self.child.try_wait().unwrap())
        }

        /// What stderr said so far, and what is left.
        pub fn stderr(&mut self) -> String {
            while let Ok(line) = self.lines.recv_timeout(Duration::from_millis(100)) {
                self.seen.push(line);
            }
            self.seen.join("\n")
        }
    }

    impl Drop for Viewer {
        /// A test that failed leaves nothing running: the viewer is killed, and xvfb-run, whose command
        /// it was, then takes its server down and exits.
        fn drop(&mut self) {
            if let Ok(None) = self.child.try_wait() {
                // SAFETY: kill(2) on the viewer's process id, which this test started.
                unsafe { libc::kill(self.pid, libc::SIGKILL) };
                let _ = self.child.wait();
            }
        }
    }
}
