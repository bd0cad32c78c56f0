//! The viewer's window: winit for the window and its events, softbuffer to put the frames on screen.
//!
//! Why these crates and these features: both are pure Rust down to the window system's wire protocol,
//! and every system library they use is opened at run time (dlopen), not linked, so the viewer builds
//! on a machine with only the Rust toolchain: no `-dev` package, no pkg-config (CI's machines have
//! neither). On Linux, winit's `x11` backend loads Xlib and xkbcommon through `x11-dl` and
//! `xkbcommon-dl` and speaks XCB through `x11rb` with `dl-libxcb`; softbuffer's `x11-dlopen` does the
//! same for its buffers. (The build scripts of x11-dl and tiny-xlib ask pkg-config only for a hint of
//! where the libraries live, and go on without one.) Only X11: a Wayland desktop runs the window
//! through XWayland, whose window manager draws the title bar (it carries the frame rate); Wayland's
//! own backend cost a sixth of a fresh clone's build (`Cargo.toml`). softbuffer's `kms` backend
//! (drawing to a console without a window system) is left out: the viewer always has a window.
//! Without a display at run time the event loop fails to start, and that is reported as an error, not
//! a panic.

use std::num::NonZeroU32;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::mpsc::{self, Sender};
use std::time::{Duration, Instant};

use rayon::ThreadPool;
use softbuffer::{Context, Surface};
use winit::application::ApplicationHandler;
use winit::dpi::{PhysicalPosition, PhysicalSize};
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

use super::state::{Input, Job, Key, Settings, ViewState};
use super::{Config, Frame, Signals, render_loop, reproduce};
use crate::accel::AccelKind;
use crate::error::{Error, Result};
use crate::render::cost::Measure;
use crate::scene::Scene;

/// How often the camera moves while keys are held: the screen's usual rate.
const TICK: Duration = Duration::from_micros(16_667);
/// Pixels of a touchpad's scroll that count as one line of a wheel.
const PIXELS_PER_LINE: f64 = 40.0;

/// Opens a window on `scene` and runs it until it is closed (or `config.frames` frames are shown),
/// rendering on `pool`. Call it on the main thread, once per process (winit's rule). Fails, without a
/// window, where there is no display.
pub fn run(scene: &Scene, pool: &ThreadPool, config: &Config) -> Result<()> {
    require_display()?;
    let event_loop = EventLoop::<Frame>::with_user_event()
        .build()
        .map_err(|e| cannot_open(&e))?;
    let proxy = event_loop.create_proxy();
    let (jobs, job_queue) = mpsc::channel();
    let signals = &Signals::default();
    let settings = Settings::new(config.accel, config.options.kernel, config.options.max_depth);
    let mut app = App {
        config,
        state: ViewState::new(scene, config.options, settings),
        window: None,
        surface: None,
        jobs: Some(jobs),
        signals,
        sent: None,
        frame: None,
        frames: 0,
        last_tick: None,
        cursor: None,
        dragging: false,
        control: false,
        error: None,
    };
    std::thread::scope(|threads| {
        threads.spawn(move || {
            // A frame that cannot be delivered means the event loop is gone: stop.
            render_loop(scene, pool, &job_queue, signals, config.srgb, |frame| {
                proxy.send_event(frame).is_ok()
            })
        });
        let ran = event_loop.run_app(&mut app);
        // Hang up before the scope waits for the render thread: it stops at its next tile.
        app.jobs = None;
        signals.raise(true);
        ran.map_err(|e| Error::msg(format!("the window's event loop failed: {}", one_line(&e))))
    })?;
    if let Some(e) = app.error {
        return Err(e);
    }
    match config.frames {
        Some(n) if app.frames < n => Err(Error::msg(format!(
            "the window was closed after {} of {n} frames{}",
            app.frames,
            if config.screenshot.is_some() {
                "; no screenshot written"
            } else {
                ""
            }
        ))),
        _ => Ok(()),
    }
}

/// An error unless a display server is named: winit would fail too, with a longer message.
fn require_display() -> Result<()> {
    #[cfg(all(unix, not(any(target_os = "macos", target_os = "ios", target_os = "android"))))]
    {
        let set = |name| std::env::var_os(name).is_some_and(|v| !v.is_empty());
        if !set("DISPLAY") {
            return Err(Error::msg(
                "cannot open a window: no display (DISPLAY is not set; on Wayland the viewer needs \
                 XWayland); `whitted render` renders to a file without one",
            ));
        }
    }
    Ok(())
}

/// The error of a window that could not be opened, without the place in winit's source that winit's
/// system errors begin with (`os error at FILE:LINE: `), and with the display asked for.
fn cannot_open(e: &dyn std::fmt::Display) -> Error {
    let message = one_line(e);
    let message = message
        .strip_prefix("os error at ")
        .and_then(|rest| rest.split_once(": "))
        .map_or(message.as_str(), |(_, m)| m);
    let display = std::env::var("DISPLAY")
        .ok()
        .filter(|v| !v.is_empty())
        .map_or(String::new(), |value| format!(" (DISPLAY={value})"));
    Error::msg(format!("cannot open a window{display}: {message}"))
}

/// A message on one line, as every error of the command line is.
fn one_line(e: &dyn std::fmt::Display) -> String {
    e.to_string().split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The event loop's side: the window, the state, and the last frame.
struct App<'a> {
    config: &'a Config,
    state: ViewState,
    window: Option<Rc<Window>>,
    surface: Option<Surface<Rc<Window>, Rc<Window>>>,
    /// To the render thread; `None` once hung up.
    jobs: Option<Sender<Job>>,
    signals: &'a Signals,
    /// The last job sent.
    sent: Option<Job>,
    /// The frame on screen.
    frame: Option<Frame>,
    /// Frames shown so far.
    frames: u32,
    /// When the camera last moved by the keys held; `None` while nothing was animating, so that the
    /// first tick after a pause moves by nothing rather than by the pause.
    last_tick: Option<Instant>,
    /// The pointer's last position in the window.
    cursor: Option<PhysicalPosition<f64>>,
    /// The left button is down.
    dragging: bool,
    /// A Control key is down.
    control: bool,
    /// The first error, which ends the loop.
    error: Option<Error>,
}

impl App<'_> {
    /// Records `error` (the first one wins) and ends the loop.
    fn fail(&mut self, event_loop: &ActiveEventLoop, error: Error) {
        self.error.get_or_insert(error);
        event_loop.exit();
    }

    /// Opens the window and its drawing surface.
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let (width, height) = (self.config.options.width, self.config.options.height);
        let attributes = Window::default_attributes()
            .with_title(format!("whitted: {}", self.config.name))
            .with_inner_size(PhysicalSize::new(width, height));
        let window = Rc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| cannot_open(&e))?,
        );
        let context = Context::new(window.clone()).map_err(|e| cannot_open(&e))?;
        let surface = Surface::new(&context, window.clone()).map_err(|e| cannot_open(&e))?;
        self.surface = Some(surface);
        // The window manager may have given another size than asked for.
        self.resized(window.inner_size())?;
        self.window = Some(window);
        Ok(())
    }

    /// The drawable area is now `size`: the surface's buffer is reallocated (once per resize) and the
    /// state renders at the new size.
    fn resized(&mut self, size: PhysicalSize<u32>) -> Result<()> {
        let (Some(surface), Some(w), Some(h)) = (
            self.surface.as_mut(),
            NonZeroU32::new(size.width),
            NonZeroU32::new(size.height),
        ) else {
            // Minimised: nothing to draw into.
            return Ok(());
        };
        surface.resize(w, h).map_err(|e| cannot_draw(&e))?;
        self.state.input(Input::Resize {
            width: size.width,
            height: size.height,
        });
        Ok(())
    }

    /// Sends the state's job to the render thread if it is a new one.
    fn send_job(&mut self, event_loop: &ActiveEventLoop) {
        let job = self.state.job();
        if self.sent == Some(job) || self.window.is_none() {
            return;
        }
        let Some(jobs) = &self.jobs else { return };
        if jobs.send(job).is_err() {
            // The render thread is gone (it panicked): leave, and the panic is reported.
            event_loop.exit();
            return;
        }
        self.signals
            .raise(self.sent.is_none_or(|sent| sent.changes_settings(&job)));
        self.sent = Some(job);
    }

    /// Draws the frame on screen (black before the first), stretched to the window.
    fn present(&mut self) -> Result<()> {
        let (Some(window), Some(surface)) = (&self.window, self.surface.as_mut()) else {
            return Ok(());
        };
        let mut buffer = surface.buffer_mut().map_err(|e| cannot_draw(&e))?;
        let (width, height) = (buffer.width().get(), buffer.height().get());
        match &self.frame {
            Some(f) => {
                let (fw, fh) = (f.job.options.width, f.job.options.height);
                blit(&f.pixels, fw, fh, &mut buffer, width, height);
            }
            None => buffer.fill(0),
        }
        window.pre_present_notify();
        buffer.present().map_err(|e| cannot_draw(&e))
    }

    /// A frame came from the render thread: show it, learn from its time, and with `--frames` stop
    /// after the last.
    fn frame_done(&mut self, event_loop: &ActiveEventLoop, frame: Frame) -> Result<()> {
        // After the last of `--frames` the loop is exiting, but the frames already queued still come
        // (winit hands over every pending user event first): they must not replace the screenshot.
        if self.config.frames.is_some_and(|n| self.frames >= n) {
            return Ok(());
        }
        self.state.frame_rendered(&frame.job, frame.seconds);
        self.frame = Some(frame);
        self.frames += 1;
        self.show_title();
        self.present()?;
        if self.config.frames.is_some_and(|n| self.frames >= n) {
            if let (Some(path), Some(frame)) = (&self.config.screenshot, &self.frame) {
                frame.film.write(path, self.config.srgb)?;
            }
            event_loop.exit();
        }
        Ok(())
    }

    /// Puts the frame's figures and the settings in the window's title.
    fn show_title(&self) {
        if let (Some(window), Some(frame)) = (&self.window, &self.frame) {
            window.set_title(&title(
                &self.config.name,
                frame,
                self.state.settings().progressive,
            ));
        }
    }

    /// Saves the frame on screen as the first free `NAME-view-K.png` of the current directory, and
    /// prints its camera as a `v` block and the `whitted render` command of the same image.
    fn save(&self) -> Result<()> {
        let Some(frame) = &self.frame else {
            return Ok(());
        };
        let stem = Path::new(&self.config.name)
            .file_stem()
            .map_or("whitted".into(), |s| s.to_string_lossy().into_owned());
        let path = (1..)
            .map(|k| PathBuf::from(format!("{stem}-view-{k}.png")))
            .find(|p| !p.exists())
            .expect("some number is free");
        frame.film.write(&path, self.config.srgb)?;
        super::note(format_args!(
            "whitted: saved {} ({}x{}, {} pass{})",
            path.display(),
            frame.film.width,
            frame.film.height,
            frame.pass,
            if frame.pass == 1 { "" } else { "es" }
        ));
        let scene = self.config.scene.as_deref();
        let file = self.state.file_camera();
        let command = reproduce::render_command(scene, &file, &frame.job, frame.pass, self.config.srgb);
        super::note(format_args!(
            "{}{command}",
            reproduce::view_block(&frame.job.camera)
        ));
        Ok(())
    }

    /// A key went down or up.
    fn key(&mut self, event_loop: &ActiveEventLoop, code: KeyCode, pressed: bool, repeat: bool) {
        // A held key's repeats would toggle the switches to and fro, or save image after image.
        if repeat {
            return;
        }
        if pressed && code == KeyCode::Escape {
            event_loop.exit();
            return;
        }
        // S alone moves back: Control-S saves, as F12 does. (Releases go on to the state, so that a
        // key held before Control was pressed is let go.)
        if pressed && (code == KeyCode::F12 || (code == KeyCode::KeyS && self.control)) {
            if let Err(e) = self.save() {
                self.fail(event_loop, e);
            }
            return;
        }
        if let Some(key) = key_of(code) {
            self.state.input(Input::Key { key, pressed });
            // A switch that changes no image (P) shows at once.
            self.show_title();
        }
    }
}

/// The viewer's key at a position of a US keyboard (by position, so W/A/S/D sit as a hand expects on
/// any layout).
fn key_of(code: KeyCode) -> Option<Key> {
    Some(match code {
        KeyCode::KeyW => Key::Forward,
        KeyCode::KeyA => Key::Left,
        KeyCode::KeyS => Key::Back,
        KeyCode::KeyD => Key::Right,
        KeyCode::KeyQ => Key::Down,
        KeyCode::KeyE => Key::Up,
        KeyCode::ArrowLeft => Key::TurnLeft,
        KeyCode::ArrowRight => Key::TurnRight,
        KeyCode::ArrowUp => Key::TurnUp,
        KeyCode::ArrowDown => Key::TurnDown,
        KeyCode::KeyR => Key::Reset,
        KeyCode::Digit1 => Key::Accel(AccelKind::None),
        KeyCode::Digit2 => Key::Accel(AccelKind::Grid),
        KeyCode::Digit3 => Key::Accel(AccelKind::Bvh2),
        KeyCode::Digit4 => Key::Accel(AccelKind::Bvh4),
        KeyCode::Digit5 => Key::Accel(AccelKind::Bvh8),
        #[cfg(feature = "embree")]
        KeyCode::Digit6 => Key::Accel(AccelKind::Embree),
        KeyCode::KeyK => Key::Kernel,
        KeyCode::KeyH => Key::SoftShadows,
        KeyCode::KeyF => Key::DepthOfField,
        KeyCode::BracketLeft => Key::LessDepth,
        KeyCode::BracketRight => Key::MoreDepth,
        KeyCode::KeyP => Key::Progressive,
        KeyCode::KeyC => Key::Heatmap,
        _ => return None,
    })
}

impl ApplicationHandler<Frame> for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none()
            && let Err(e) = self.open(event_loop)
        {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Err(e) = self.resized(size) {
                    self.fail(event_loop, e);
                }
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.present() {
                    self.fail(event_loop, e);
                }
            }
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    let pressed = event.state == ElementState::Pressed;
                    self.key(event_loop, code, pressed, event.repeat);
                }
            }
            WindowEvent::ModifiersChanged(modifiers) => self.control = modifiers.state().control_key(),
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => self.dragging = state == ElementState::Pressed,
            WindowEvent::CursorMoved { position, .. } => {
                if let (true, Some(last)) = (self.dragging, self.cursor) {
                    self.state.input(Input::Drag {
                        dx: (position.x - last.x) as f32,
                        dy: (position.y - last.y) as f32,
                    });
                }
                self.cursor = Some(position);
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseWheel { delta, .. } => {
                let lines = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / PIXELS_PER_LINE) as f32,
                };
                self.state.input(Input::Scroll(lines));
            }
            WindowEvent::Focused(false) => {
                self.state.input(Input::ReleaseAll);
                self.dragging = false;
            }
            _ => {}
        }
    }

    fn user_event(&mut self, event_loop: &ActiveEventLoop, frame: Frame) {
        if let Err(e) = self.frame_done(event_loop, frame) {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, event_loop: &ActiveEventLoop) {
        let now = Instant::now();
        if let Some(last) = self.last_tick {
            self.state.tick((now - last).as_secs_f32());
        }
        self.send_job(event_loop);
        // Wake up on the next tick while keys are held or the camera is coming to rest; otherwise sleep
        // until an event (input, or a frame from the render thread).
        if self.state.animating() {
            self.last_tick = Some(now);
            event_loop.set_control_flow(ControlFlow::WaitUntil(now + TICK));
        } else {
            self.last_tick = None;
            event_loop.set_control_flow(ControlFlow::Wait);
        }
    }
}

/// The error of a window that cannot be drawn in.
fn cannot_draw(e: &dyn std::fmt::Display) -> Error {
    Error::msg(format!("cannot draw in the window: {}", one_line(e)))
}

/// The window's title: the scene, the speed of the last pass and what it rendered, and whether more
/// passes are coming.
fn title(name: &str, frame: &Frame, progressive: bool) -> String {
    let job = &frame.job;
    let fps = 1.0 / frame.seconds.max(1e-9);
    let mrays = frame.rays.total() as f64 / frame.seconds.max(1e-9) / 1e6;
    let accel = format!("{:?}", job.accel).to_lowercase();
    let kernel = job.options.kernel.name();
    let scale = match job.scale {
        1 => "full".to_string(),
        s => format!("1/{s}"),
    };
    let mut title = format!(
        "whitted: {name} | {fps:.1} fps, {mrays:.1} Mrays/s | pass {} | {accel}, {kernel} | {}x{} ({scale}) | {} shadows, {}, depth {}",
        frame.pass,
        job.options.width,
        job.options.height,
        if job.soft_shadows { "soft" } else { "hard" },
        if job.camera.aperture > 0.0 {
            "lens"
        } else {
            "pinhole"
        },
        job.options.max_depth,
    );
    if let Some(m) = job.heatmap {
        title.push_str(match m {
            Measure::Nodes => " | heatmap: nodes visited",
            Measure::Prims => " | heatmap: primitives tested",
            Measure::Rays => " | heatmap: rays traced",
        });
    }
    if !progressive {
        title.push_str(" | progressive off");
    }
    title
}

/// `src` (`sw` × `sh`) into `dst` (`dw` × `dh`), nearest pixel: a frame of a lower resolution, or of
/// the size before a resize, fills the window.
fn blit(src: &[u32], sw: u32, sh: u32, dst: &mut [u32], dw: u32, dh: u32) {
    if (sw, sh) == (dw, dh) {
        dst.copy_from_slice(src);
        return;
    }
    let columns: Vec<usize> = (0..dw)
        .map(|x| (u64::from(x) * u64::from(sw) / u64::from(dw)) as usize)
        .collect();
    for (y, row) in dst.chunks_exact_mut(dw as usize).enumerate() {
        let sy = (y as u64 * u64::from(sh) / u64::from(dh)) as usize;
        let line = &src[sy * sw as usize..][..sw as usize];
        for (d, &sx) in row.iter_mut().zip(&columns) {
            *d = line[sx];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blit_stretches_by_the_nearest_pixel() {
        let src = [1, 2, 3, 4];
        let mut dst = [0; 16];
        blit(&src, 2, 2, &mut dst, 4, 4);
        assert_eq!(dst, [1, 1, 2, 2, 1, 1, 2, 2, 3, 3, 4, 4, 3, 3, 4, 4]);
        let mut same = [0; 4];
        blit(&src, 2, 2, &mut same, 2, 2);
        assert_eq!(same, src);
        // Shrinking (a frame from before the window got smaller) works too.
        let mut small = [0; 1];
        blit(&src, 2, 2, &mut small, 1, 1);
        assert_eq!(small, [1]);
    }

    #[test]
    fn every_key_of_the_help_is_mapped_and_others_are_not() {
        assert_eq!(key_of(KeyCode::KeyW), Some(Key::Forward));
        assert_eq!(key_of(KeyCode::Digit3), Some(Key::Accel(AccelKind::Bvh2)));
        assert_eq!(key_of(KeyCode::BracketRight), Some(Key::MoreDepth));
        assert_eq!(key_of(KeyCode::KeyZ), None);
    }

    #[test]
    fn errors_are_one_line_without_winit_source_places() {
        let e = cannot_open(&"os error at /src/winit/linux/mod.rs:788: Failed to\n  open connection");
        let message = e.to_string();
        assert!(message.starts_with("cannot open a window"), "{message}");
        assert!(message.ends_with(": Failed to open connection"), "{message}");
        assert_eq!(cannot_draw(&"a\nb").to_string(), "cannot draw in the window: a b");
    }
}
