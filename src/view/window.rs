//! The viewer's window: X11's core protocol spoken directly through x11rb.
//!
//! Why x11rb alone: it is pure Rust down to the wire protocol, and its own connection
//! (`RustConnection`) talks to the X server over the socket, so the viewer needs no system library at
//! build or at run time: nothing to install, no `-dev` package, no pkg-config, no libX11 or libxcb.
//! The core protocol has everything a window of pixels needs (keys, pointer, resize, `PutImage`), so no
//! extension of its own is compiled in, and x11rb builds in a fraction of the time of winit's X11
//! backend with softbuffer (`docs/testing.md`). Only X11: a Wayland desktop runs the window through
//! XWayland.
//! Without a display the viewer fails with one line, not a panic.
//!
//! The event loop drains the X events, then waits for the render thread's next frame for at most a
//! `TICK`, the step of the held keys' motion, so that both are served without spinning.

use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, Sender};
use std::time::{Duration, Instant};

use rayon::ThreadPool;
use x11rb::connection::{Connection, RequestConnection};
use x11rb::errors::{ConnectError, ConnectionError, ReplyError};
use x11rb::protocol::Event;
use x11rb::protocol::xproto::{
    AtomEnum, ConnectionExt as _, CreateGCAux, CreateWindowAux, EventMask, ImageFormat, ImageOrder,
    KeyButMask, KeyPressEvent, Keycode, Mapping, NotifyDetail, PropMode, VisualClass, WindowClass,
};
use x11rb::rust_connection::RustConnection;
use x11rb::wrapper::ConnectionExt as _;

use super::state::{Input, Job, Key, Settings, ViewState};
use super::{Config, Frame, Signals, render_loop, reproduce};
use crate::accel::AccelKind;
use crate::error::{Error, Result};
use crate::heatmap::cost::Measure;
use crate::scene::Scene;

/// How often the camera moves while keys are held: the screen's usual rate. Also the longest the event
/// loop waits for a frame before it looks at the X events again.
const TICK: Duration = Duration::from_micros(16_667);

/// Keysyms (X11's keysymdef.h) of the keys the viewer reacts to besides the printable ones, whose
/// keysyms are their ASCII codes.
mod keysym {
    pub const ESCAPE: u32 = 0xff1b;
    pub const F12: u32 = 0xffc9;
    pub const LEFT: u32 = 0xff51;
    pub const UP: u32 = 0xff52;
    pub const RIGHT: u32 = 0xff53;
    pub const DOWN: u32 = 0xff54;
}

/// Opens a window on `scene` and runs it until it is closed (or `config.frames` frames are shown),
/// rendering on `pool`. Fails, without a window, where there is no display.
pub fn run(scene: &Scene, pool: &ThreadPool, config: &Config) -> Result<()> {
    require_display()?;
    let title = format!("whitted: {}", config.name);
    let window = XWindow::open(config.options.width, config.options.height, &title)?;
    let (jobs, job_queue) = mpsc::channel();
    let (frame_sender, frames) = mpsc::channel();
    let signals = &Signals::default();
    let settings = Settings::new(config.accel, config.options.kernel, config.options.max_depth);
    let mut app = App {
        config,
        state: ViewState::new(scene, config.options, settings),
        size: (config.options.width, config.options.height),
        window,
        canvas: Vec::new(),
        jobs,
        frames,
        signals,
        sent: None,
        frame: None,
        shown: 0,
        last_tick: None,
        cursor: None,
        dragging: false,
        pending: None,
        quit: false,
    };
    let shown = std::thread::scope(|threads| {
        threads.spawn(move || {
            // A frame that cannot be delivered means the window is gone: stop.
            render_loop(scene, pool, &job_queue, signals, config.srgb, |frame| {
                frame_sender.send(frame).is_ok()
            })
        });
        let ran = app.run();
        let shown = app.shown;
        // Close the window and hang up before the scope waits for the render thread: it stops at its
        // next tile.
        drop(app);
        signals.raise(true);
        ran.map(|()| shown)
    })?;
    match config.frames {
        Some(n) if shown < n => Err(Error::msg(format!(
            "the window was closed after {shown} of {n} frames{}",
            if config.screenshot.is_some() {
                "; no screenshot written"
            } else {
                ""
            }
        ))),
        _ => Ok(()),
    }
}

/// An error unless a display server is named, before any connection is tried.
fn require_display() -> Result<()> {
    let set = |name| std::env::var_os(name).is_some_and(|v| !v.is_empty());
    if !set("DISPLAY") {
        return Err(Error::msg(
            "cannot open a window: no display (DISPLAY is not set; on Wayland the viewer needs \
             XWayland); `whitted render` renders to a file without one",
        ));
    }
    Ok(())
}

/// The error of a window that could not be opened, with the display asked for.
fn cannot_open(e: &dyn std::fmt::Display) -> Error {
    let display = std::env::var("DISPLAY")
        .ok()
        .filter(|v| !v.is_empty())
        .map_or(String::new(), |value| format!(" (DISPLAY={value})"));
    Error::msg(format!("cannot open a window{display}: {}", one_line(e)))
}

/// A connection that failed: the socket's error says that no server answered.
fn cannot_connect(e: &ConnectError) -> Error {
    match e {
        ConnectError::IoError(io) => cannot_open(&format_args!("cannot connect to the X server: {io}")),
        other => cannot_open(other),
    }
}

/// The error of a window that cannot be drawn in or listened to any more.
fn cannot_draw(e: &dyn std::fmt::Display) -> Error {
    Error::msg(format!("cannot draw in the window: {}", one_line(e)))
}

/// A message on one line, as every error of the command line is.
fn one_line(e: &dyn std::fmt::Display) -> String {
    e.to_string().split_whitespace().collect::<Vec<_>>().join(" ")
}

/// How the screen's visual lays out a pixel: 32 bits, the colour channels at their masks' places, in
/// the server's byte order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct PixelFormat {
    /// The visual's depth: 24 or 32.
    depth: u8,
    /// The pixel's bytes most significant first.
    msb_first: bool,
    /// Bits per row are padded to a multiple of this.
    scanline_pad: u8,
    /// The red, green and blue masks.
    masks: [u32; 3],
}

impl PixelFormat {
    /// The format of a TrueColor visual of depth 24 or 32 stored in 32 bits a pixel, or why not.
    fn new(
        depth: u8,
        class: VisualClass,
        masks: [u32; 3],
        bits_per_pixel: u8,
        scanline_pad: u8,
        order: ImageOrder,
    ) -> std::result::Result<PixelFormat, String> {
        // A mask of up to 8 contiguous bits takes the top bits of an 8-bit channel.
        let contiguous = |m: u32| {
            let bits = m.checked_shr(m.trailing_zeros()).unwrap_or(0);
            bits != 0 && bits <= 0xff && bits & (bits + 1) == 0
        };
        if class != VisualClass::TRUE_COLOR
            || !matches!(depth, 24 | 32)
            || bits_per_pixel != 32
            || !masks.iter().all(|&m| contiguous(m))
            || !matches!(scanline_pad, 8 | 16 | 32 | 64)
        {
            return Err(format!(
                "the screen's visual is not 24- or 32-bit TrueColor in 32-bit pixels (depth {depth}, \
                 class {}, {bits_per_pixel} bits per pixel, masks {:#x} {:#x} {:#x})",
                u8::from(class),
                masks[0],
                masks[1],
                masks[2]
            ));
        }
        Ok(PixelFormat {
            depth,
            msb_first: order == ImageOrder::MSB_FIRST,
            scanline_pad,
            masks,
        })
    }

    /// The bytes of a row of `width` pixels, padded.
    fn stride(&self, width: u32) -> usize {
        let pad = usize::from(self.scanline_pad);
        (width as usize * 32).div_ceil(pad) * pad / 8
    }

    /// The pixel of a `0x00RRGGBB` word: each channel's top bits at its mask, and the bits of the depth
    /// outside the masks (a 32-bit visual's alpha) set, so that the window is opaque.
    fn pixel(&self, word: u32) -> u32 {
        let [r, g, b] = self.masks;
        let channel =
            |value: u32, mask: u32| ((value & 0xff) >> (8 - mask.count_ones())) << mask.trailing_zeros();
        let depth_bits = if self.depth == 32 {
            u32::MAX
        } else {
            (1 << self.depth) - 1
        };
        channel(word >> 16, r) | channel(word >> 8, g) | channel(word, b) | (depth_bits & !(r | g | b))
    }

    /// `words` (`width` × `height`) as an image of this format, row after row, into `bytes`.
    fn encode(&self, words: &[u32], width: u32, bytes: &mut Vec<u8>) {
        let stride = self.stride(width);
        let rows = words.len() / width.max(1) as usize;
        bytes.clear();
        bytes.resize(stride * rows, 0);
        for (row, out) in words
            .chunks_exact(width as usize)
            .zip(bytes.chunks_exact_mut(stride))
        {
            for (&word, px) in row.iter().zip(out.chunks_exact_mut(4)) {
                let p = self.pixel(word);
                px.copy_from_slice(&if self.msb_first {
                    p.to_be_bytes()
                } else {
                    p.to_le_bytes()
                });
            }
        }
    }
}

/// Rows of `stride` bytes that one `PutImage` request of at most `max_bytes` takes (its header, and
/// BIG-REQUESTS' longer length, aside), at least 1 and at most 65535 (the request's height is 16-bit).
fn rows_per_request(max_bytes: usize, stride: usize) -> usize {
    const HEADER: usize = 28;
    (max_bytes.saturating_sub(HEADER) / stride.max(1)).clamp(1, usize::from(u16::MAX))
}

/// The window and what drawing in it needs.
struct XWindow {
    conn: RustConnection,
    window: u32,
    gc: u32,
    format: PixelFormat,
    /// The keysym of each keycode from the setup's smallest, in the keymap's first column (unshifted).
    keymap: Vec<u32>,
    /// The atoms of the title and of the close button.
    net_wm_name: u32,
    utf8_string: u32,
    wm_protocols: u32,
    wm_delete_window: u32,
    /// The image as the server takes it, kept between frames.
    bytes: Vec<u8>,
}

impl XWindow {
    /// Connects to `DISPLAY` and opens a `width` × `height` window titled `title` on its screen.
    fn open(width: u32, height: u32, title: &str) -> Result<XWindow> {
        let (conn, screen) = RustConnection::connect(None).map_err(|e| cannot_connect(&e))?;
        let opened = XWindow::create(conn, screen, width, height, title);
        opened.map_err(|e| cannot_open(&e))
    }

    /// The window on `screen` of `conn`, mapped; an error message if the screen cannot show it.
    fn create(
        conn: RustConnection,
        screen: usize,
        width: u32,
        height: u32,
        title: &str,
    ) -> std::result::Result<XWindow, String> {
        let text = |e: &dyn std::fmt::Display| e.to_string();
        let setup = conn.setup();
        let root = setup.roots.get(screen).ok_or("the display has no such screen")?;
        let visual = root
            .allowed_depths
            .iter()
            .filter(|d| d.depth == root.root_depth)
            .flat_map(|d| &d.visuals)
            .find(|v| v.visual_id == root.root_visual)
            .ok_or("the screen's visual is not in its list of visuals")?;
        let bits = setup.pixmap_formats.iter().find(|f| f.depth == root.root_depth);
        let format = PixelFormat::new(
            root.root_depth,
            visual.class,
            [visual.red_mask, visual.green_mask, visual.blue_mask],
            bits.map_or(0, |f| f.bits_per_pixel),
            bits.map_or(0, |f| f.scanline_pad),
            setup.image_byte_order,
        )?;
        let root = root.root;
        let (window, gc) = (
            conn.generate_id().map_err(|e| text(&e))?,
            conn.generate_id().map_err(|e| text(&e))?,
        );
        // The four names asked at once: one round trip to the server, not four.
        let names: [&[u8]; 4] = [
            b"_NET_WM_NAME",
            b"UTF8_STRING",
            b"WM_PROTOCOLS",
            b"WM_DELETE_WINDOW",
        ];
        let asked = names.map(|name| conn.intern_atom(false, name));
        let mut atoms = [0; 4];
        for (atom, cookie) in atoms.iter_mut().zip(asked) {
            *atom = cookie.map_err(|e| text(&e))?.reply().map_err(|e| text(&e))?.atom;
        }
        let [net_wm_name, utf8_string, wm_protocols, wm_delete_window] = atoms;
        let events = EventMask::KEY_PRESS
            | EventMask::KEY_RELEASE
            | EventMask::BUTTON_PRESS
            | EventMask::BUTTON_RELEASE
            | EventMask::BUTTON_MOTION
            | EventMask::LEAVE_WINDOW
            | EventMask::EXPOSURE
            | EventMask::STRUCTURE_NOTIFY
            | EventMask::FOCUS_CHANGE;
        // No background: every Expose is answered with the whole frame, and a resize does not flash.
        let attributes = CreateWindowAux::new()
            .background_pixmap(x11rb::NONE)
            .event_mask(events);
        let side = |v: u32| u16::try_from(v).unwrap_or(u16::MAX).max(1);
        let sent = (|| -> std::result::Result<(), ConnectionError> {
            conn.create_window(
                x11rb::COPY_DEPTH_FROM_PARENT,
                window,
                root,
                0,
                0,
                side(width),
                side(height),
                0,
                WindowClass::INPUT_OUTPUT,
                x11rb::COPY_FROM_PARENT,
                &attributes,
            )?;
            conn.change_property32(
                PropMode::REPLACE,
                window,
                wm_protocols,
                AtomEnum::ATOM,
                &[wm_delete_window],
            )?;
            conn.change_property8(
                PropMode::REPLACE,
                window,
                AtomEnum::WM_CLASS,
                AtomEnum::STRING,
                b"whitted\0whitted\0",
            )?;
            conn.create_gc(gc, window, &CreateGCAux::new())?;
            Ok(())
        })();
        sent.map_err(|e| text(&e))?;
        let mut window = XWindow {
            keymap: Vec::new(),
            conn,
            window,
            gc,
            format,
            net_wm_name,
            utf8_string,
            wm_protocols,
            wm_delete_window,
            bytes: Vec::new(),
        };
        window.load_keymap().map_err(|e| text(&e))?;
        window.set_title(title).map_err(|e| text(&e))?;
        window.conn.map_window(window.window).map_err(|e| text(&e))?;
        // Ask for the largest request now (BIG-REQUESTS where the server has it), without waiting.
        window.conn.prefetch_maximum_request_bytes();
        window.conn.flush().map_err(|e| text(&e))?;
        Ok(window)
    }

    /// Reads the keyboard's mapping: the unshifted keysym of every keycode.
    fn load_keymap(&mut self) -> std::result::Result<(), ReplyError> {
        let (min, max) = (self.conn.setup().min_keycode, self.conn.setup().max_keycode);
        let map = self.conn.get_keyboard_mapping(min, max - min + 1)?.reply()?;
        self.keymap = unshifted(&map.keysyms, map.keysyms_per_keycode);
        Ok(())
    }

    /// The unshifted keysym of `code` (0, NoSymbol, for none).
    fn keysym(&self, code: Keycode) -> u32 {
        code.checked_sub(self.conn.setup().min_keycode)
            .and_then(|i| self.keymap.get(usize::from(i)))
            .copied()
            .unwrap_or(x11rb::NO_SYMBOL)
    }

    /// Sets the title: `_NET_WM_NAME` in UTF-8 for today's window managers, and `WM_NAME` for the
    /// others (Latin-1 where the title is, else UTF-8 too).
    fn set_title(&self, title: &str) -> std::result::Result<(), ConnectionError> {
        let (w, conn) = (self.window, &self.conn);
        conn.change_property8(
            PropMode::REPLACE,
            w,
            self.net_wm_name,
            self.utf8_string,
            title.as_bytes(),
        )?;
        let latin1: Option<Vec<u8>> = title.chars().map(|c| u8::try_from(u32::from(c)).ok()).collect();
        match latin1 {
            Some(bytes) => {
                conn.change_property8(PropMode::REPLACE, w, AtomEnum::WM_NAME, AtomEnum::STRING, &bytes)?
            }
            None => conn.change_property8(
                PropMode::REPLACE,
                w,
                AtomEnum::WM_NAME,
                self.utf8_string,
                title.as_bytes(),
            )?,
        };
        Ok(())
    }

    /// Puts `words` (`width` × `height`, `0x00RRGGBB`) in the window, in strips of rows that each fit
    /// one request. (A request places an image at most 32767 rows down: rows below are not drawn.)
    fn put(&mut self, words: &[u32], width: u32, height: u32) -> std::result::Result<(), ConnectionError> {
        let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
            return Ok(());
        };
        self.format.encode(words, width, &mut self.bytes);
        let stride = self.format.stride(width);
        let rows = rows_per_request(self.conn.maximum_request_bytes(), stride);
        let mut y = 0;
        while y < usize::from(h) {
            let Ok(dst_y) = i16::try_from(y) else { break };
            let n = rows.min(usize::from(h) - y);
            let data = &self.bytes[y * stride..(y + n) * stride];
            self.conn.put_image(
                ImageFormat::Z_PIXMAP,
                self.window,
                self.gc,
                w,
                n as u16,
                0,
                dst_y,
                0,
                self.format.depth,
                data,
            )?;
            y += n;
        }
        self.conn.flush()
    }
}

/// The event loop's side: the window, the state, and the last frame.
struct App<'a> {
    config: &'a Config,
    state: ViewState,
    /// The window's size.
    size: (u32, u32),
    window: XWindow,
    /// The frame stretched to the window, kept between frames.
    canvas: Vec<u32>,
    /// To the render thread; dropping it hangs up.
    jobs: Sender<Job>,
    /// From the render thread.
    frames: Receiver<Frame>,
    signals: &'a Signals,
    /// The last job sent.
    sent: Option<Job>,
    /// The frame on screen.
    frame: Option<Frame>,
    /// Frames shown so far.
    shown: u32,
    /// When the camera last moved by the keys held; `None` while nothing was animating, so that the
    /// first tick after a pause moves by nothing rather than by the pause.
    last_tick: Option<Instant>,
    /// The pointer's last position in the window.
    cursor: Option<(i16, i16)>,
    /// The left button is down.
    dragging: bool,
    /// An event read ahead, to tell a key's auto-repeat from its release.
    pending: Option<Event>,
    /// The window is done: closed, Escape, or the last of `--frames`.
    quit: bool,
}

impl App<'_> {
    /// The event loop, until the window is done or the render thread ends (a panic, reported when the
    /// thread is joined).
    fn run(&mut self) -> Result<()> {
        loop {
            while let Some(event) = self.next_event()? {
                self.event(event)?;
                if self.quit {
                    return Ok(());
                }
            }
            let now = Instant::now();
            if let Some(last) = self.last_tick {
                self.state.tick((now - last).as_secs_f32());
            }
            if !self.send_job() {
                return Ok(());
            }
            // Keys held or the camera coming to rest: the next tick moves it by the time elapsed.
            self.last_tick = self.state.animating().then_some(now);
            self.window.conn.flush().map_err(|e| cannot_draw(&e))?;
            match self.frames.recv_timeout(TICK) {
                Ok(frame) => {
                    self.frame_done(frame)?;
                    if self.quit {
                        return Ok(());
                    }
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => return Ok(()),
            }
        }
    }

    /// The next X event, if one has come, without the release and press pairs of a held key's
    /// auto-repeat: a held key would otherwise toggle the switches to and fro, or save image after
    /// image.
    fn next_event(&mut self) -> Result<Option<Event>> {
        loop {
            let event = match self.pending.take() {
                Some(event) => event,
                None => match self.poll()? {
                    Some(event) => event,
                    None => return Ok(None),
                },
            };
            if let Event::KeyRelease(release) = &event {
                let next = self.poll()?;
                if next.as_ref().is_some_and(|next| repeats(release, next)) {
                    continue;
                }
                self.pending = next;
            }
            return Ok(Some(event));
        }
    }

    /// An event already read from the server or waiting on the socket.
    fn poll(&self) -> Result<Option<Event>> {
        self.window.conn.poll_for_event().map_err(|e| cannot_draw(&e))
    }

    /// Acts on one X event.
    fn event(&mut self, event: Event) -> Result<()> {
        match event {
            Event::KeyPress(e) => self.key(
                self.window.keysym(e.detail),
                true,
                e.state.contains(KeyButMask::CONTROL),
            )?,
            Event::KeyRelease(e) => self.key(self.window.keysym(e.detail), false, false)?,
            Event::ButtonPress(e) => match e.detail {
                1 => {
                    self.dragging = true;
                    self.cursor = Some((e.event_x, e.event_y));
                }
                // The wheel's clicks, away from the user and toward (6 and 7, sideways, zoom nothing).
                4 => self.state.input(Input::Scroll(1.0)),
                5 => self.state.input(Input::Scroll(-1.0)),
                _ => {}
            },
            Event::ButtonRelease(e) if e.detail == 1 => self.dragging = false,
            Event::MotionNotify(e) => {
                let position = (e.event_x, e.event_y);
                if let (true, Some(last)) = (self.dragging, self.cursor) {
                    self.state.input(Input::Drag {
                        dx: f32::from(position.0) - f32::from(last.0),
                        dy: f32::from(position.1) - f32::from(last.1),
                    });
                }
                self.cursor = Some(position);
            }
            Event::LeaveNotify(_) => self.cursor = None,
            Event::FocusOut(e) if e.detail != NotifyDetail::INFERIOR => {
                // The keys held are let go elsewhere: their releases will not come here.
                self.state.input(Input::ReleaseAll);
                self.dragging = false;
            }
            Event::ConfigureNotify(e) if e.window == self.window.window => {
                let size = (u32::from(e.width), u32::from(e.height));
                if size != self.size && size.0 > 0 && size.1 > 0 {
                    self.size = size;
                    self.state.input(Input::Resize {
                        width: size.0,
                        height: size.1,
                    });
                }
            }
            // The last of a series of exposed rectangles: the whole frame again.
            Event::Expose(e) if e.count == 0 => self.present()?,
            Event::ClientMessage(e)
                if e.type_ == self.window.wm_protocols
                    && e.format == 32
                    && e.data.as_data32()[0] == self.window.wm_delete_window =>
            {
                self.quit = true;
            }
            Event::MappingNotify(e) if e.request == Mapping::KEYBOARD => {
                self.window.load_keymap().map_err(|e| cannot_draw(&e))?;
            }
            Event::Error(e) => {
                return Err(cannot_draw(&format_args!(
                    "the X server refused a request: {:?} error in {} (major opcode {})",
                    e.error_kind,
                    e.request_name.unwrap_or("a request"),
                    e.major_opcode
                )));
            }
            _ => {}
        }
        Ok(())
    }

    /// Sends the state's job to the render thread if it is a new one; false if the thread is gone.
    fn send_job(&mut self) -> bool {
        let job = self.state.job();
        if self.sent == Some(job) {
            return true;
        }
        if self.jobs.send(job).is_err() {
            return false;
        }
        self.signals
            .raise(self.sent.is_none_or(|sent| sent.changes_settings(&job)));
        self.sent = Some(job);
        true
    }

    /// Draws the frame on screen (black before the first), stretched to the window.
    fn present(&mut self) -> Result<()> {
        let (width, height) = self.size;
        self.canvas.resize(width as usize * height as usize, 0);
        match &self.frame {
            Some(f) => {
                let (fw, fh) = (f.job.options.width, f.job.options.height);
                blit(&f.pixels, fw, fh, &mut self.canvas, width, height);
            }
            None => self.canvas.fill(0),
        }
        self.window
            .put(&self.canvas, width, height)
            .map_err(|e| cannot_draw(&e))
    }

    /// A frame came from the render thread: learn from its time and show it, or the newest of the
    /// frames queued behind it (each counts; drawing each would fall behind a fast render), and with
    /// `--frames` stop after the last.
    fn frame_done(&mut self, mut frame: Frame) -> Result<()> {
        loop {
            self.state.frame_rendered(&frame.job, frame.seconds);
            self.frame = Some(frame);
            self.shown += 1;
            if self.config.frames.is_some_and(|n| self.shown >= n) {
                break;
            }
            match self.frames.try_recv() {
                Ok(next) => frame = next,
                Err(_) => break,
            }
        }
        self.show_title()?;
        self.present()?;
        if self.config.frames.is_some_and(|n| self.shown >= n) {
            if let (Some(path), Some(frame)) = (&self.config.screenshot, &self.frame) {
                frame.film.write(path, self.config.srgb)?;
            }
            self.quit = true;
        }
        Ok(())
    }

    /// Puts the frame's figures and the settings in the window's title.
    fn show_title(&self) -> Result<()> {
        let Some(frame) = &self.frame else { return Ok(()) };
        let text = title(&self.config.name, frame, self.state.settings().progressive);
        self.window.set_title(&text).map_err(|e| cannot_draw(&e))
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

    /// The key of `keysym` went down or up; `control`: a Control key was down.
    fn key(&mut self, keysym: u32, pressed: bool, control: bool) -> Result<()> {
        if pressed && keysym == keysym::ESCAPE {
            self.quit = true;
            return Ok(());
        }
        // S alone moves back: Control-S saves, as F12 does. (Releases go on to the state, so that a
        // key held before Control was pressed is let go.)
        if pressed && (keysym == keysym::F12 || (key_of(keysym) == Some(Key::Back) && control)) {
            return self.save();
        }
        if let Some(key) = key_of(keysym) {
            self.state.input(Input::Key { key, pressed });
            // A switch that changes no image (P) shows at once.
            self.show_title()?;
        }
        Ok(())
    }
}

/// The first keysym of each keycode in a keyboard mapping of `per` keysyms a keycode: the key's
/// symbol without Shift or another group.
fn unshifted(keysyms: &[u32], per: u8) -> Vec<u32> {
    match usize::from(per) {
        0 => Vec::new(),
        per => keysyms.chunks(per).map(|syms| syms[0]).collect(),
    }
}

/// Whether `next` is the press that follows `release` in a held key's auto-repeat: the server sends
/// both at once, for the same key, with the same time.
fn repeats(release: &KeyPressEvent, next: &Event) -> bool {
    matches!(next, Event::KeyPress(press) if press.detail == release.detail && press.time == release.time)
}

/// The viewer's key of an unshifted keysym.
fn key_of(keysym: u32) -> Option<Key> {
    Some(match keysym {
        keysym::LEFT => Key::TurnLeft,
        keysym::RIGHT => Key::TurnRight,
        keysym::UP => Key::TurnUp,
        keysym::DOWN => Key::TurnDown,
        // Printable ASCII; a capital (some keymaps list it alone) counts as its letter.
        0x20..=0x7e => match (keysym as u8).to_ascii_lowercase() {
            b'w' => Key::Forward,
            b'a' => Key::Left,
            b's' => Key::Back,
            b'd' => Key::Right,
            b'q' => Key::Down,
            b'e' => Key::Up,
            b'r' => Key::Reset,
            b'1' => Key::Accel(AccelKind::None),
            b'2' => Key::Accel(AccelKind::Grid),
            b'3' => Key::Accel(AccelKind::Bvh2),
            b'4' => Key::Accel(AccelKind::Bvh4),
            b'5' => Key::Accel(AccelKind::Bvh8),
            #[cfg(feature = "embree")]
            b'6' => Key::Accel(AccelKind::Embree),
            b'k' => Key::Kernel,
            b'h' => Key::SoftShadows,
            b'f' => Key::DepthOfField,
            b'[' => Key::LessDepth,
            b']' => Key::MoreDepth,
            b'p' => Key::Progressive,
            b'c' => Key::Heatmap,
            _ => return None,
        },
        _ => return None,
    })
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
        let keys = [
            (b'w', Key::Forward),
            (b'a', Key::Left),
            (b's', Key::Back),
            (b'd', Key::Right),
            (b'q', Key::Down),
            (b'e', Key::Up),
            (b'r', Key::Reset),
            (b'1', Key::Accel(AccelKind::None)),
            (b'2', Key::Accel(AccelKind::Grid)),
            (b'3', Key::Accel(AccelKind::Bvh2)),
            (b'4', Key::Accel(AccelKind::Bvh4)),
            (b'5', Key::Accel(AccelKind::Bvh8)),
            (b'k', Key::Kernel),
            (b'h', Key::SoftShadows),
            (b'f', Key::DepthOfField),
            (b'[', Key::LessDepth),
            (b']', Key::MoreDepth),
            (b'p', Key::Progressive),
            (b'c', Key::Heatmap),
        ];
        for (c, key) in keys {
            assert_eq!(key_of(u32::from(c)), Some(key), "{}", char::from(c));
        }
        // A capital is its letter's key.
        assert_eq!(key_of(0x57), Some(Key::Forward));
        // XK_Left, XK_Up, XK_Right, XK_Down.
        assert_eq!(key_of(0xff51), Some(Key::TurnLeft));
        assert_eq!(key_of(0xff52), Some(Key::TurnUp));
        assert_eq!(key_of(0xff53), Some(Key::TurnRight));
        assert_eq!(key_of(0xff54), Some(Key::TurnDown));
        #[cfg(feature = "embree")]
        assert_eq!(key_of(u32::from(b'6')), Some(Key::Accel(AccelKind::Embree)));
        #[cfg(not(feature = "embree"))]
        assert_eq!(key_of(u32::from(b'6')), None);
        // z, Escape and F12 (handled before the state), NoSymbol, keypad 8 (XK_KP_8), `{`, and a keysym
        // whose low byte is w's (XK_wcircumflex).
        for other in [u32::from(b'z'), 0xff1b, 0xffc9, 0, 0xffb8, 0x7b, 0x1000177] {
            assert_eq!(key_of(other), None, "{other:#x}");
        }
    }

    #[test]
    fn the_keymaps_first_column_is_the_unshifted_symbol() {
        // Keycodes of `a A`, `1 !` and F12 alone, as a server lists them (NoSymbol fills rows).
        let map = [0x61, 0x41, 0, 0x31, 0x21, 0, 0xffc9, 0, 0];
        assert_eq!(unshifted(&map, 3), [0x61, 0x31, 0xffc9]);
        assert!(unshifted(&map, 0).is_empty());
    }

    fn key_event(detail: Keycode, time: u32, response_type: u8) -> KeyPressEvent {
        KeyPressEvent {
            response_type,
            detail,
            sequence: 0,
            time,
            root: 1,
            event: 2,
            child: 0,
            root_x: 0,
            root_y: 0,
            event_x: 0,
            event_y: 0,
            state: KeyButMask::default(),
            same_screen: true,
        }
    }

    #[test]
    fn an_auto_repeat_is_a_release_and_a_press_of_one_key_at_one_time() {
        use x11rb::protocol::xproto::{KEY_PRESS_EVENT, KEY_RELEASE_EVENT};
        let release = key_event(38, 1000, KEY_RELEASE_EVENT);
        assert!(repeats(
            &release,
            &Event::KeyPress(key_event(38, 1000, KEY_PRESS_EVENT))
        ));
        // Let go and pressed again later, another key, another release.
        assert!(!repeats(
            &release,
            &Event::KeyPress(key_event(38, 1001, KEY_PRESS_EVENT))
        ));
        assert!(!repeats(
            &release,
            &Event::KeyPress(key_event(39, 1000, KEY_PRESS_EVENT))
        ));
        assert!(!repeats(
            &release,
            &Event::KeyRelease(key_event(38, 1000, KEY_RELEASE_EVENT))
        ));
    }

    #[test]
    fn pixels_follow_the_visuals_masks_and_the_servers_byte_order() {
        let rgb = [0xff_0000, 0xff00, 0xff];
        let lsb = PixelFormat::new(24, VisualClass::TRUE_COLOR, rgb, 32, 32, ImageOrder::LSB_FIRST).unwrap();
        let mut bytes = Vec::new();
        lsb.encode(&[0x0012_3456, 0x00ab_cdef], 2, &mut bytes);
        assert_eq!(bytes, [0x56, 0x34, 0x12, 0, 0xef, 0xcd, 0xab, 0]);
        let msb = PixelFormat::new(24, VisualClass::TRUE_COLOR, rgb, 32, 32, ImageOrder::MSB_FIRST).unwrap();
        msb.encode(&[0x0012_3456], 1, &mut bytes);
        assert_eq!(bytes, [0, 0x12, 0x34, 0x56]);
        // Blue high, red low; a 32-bit visual's alpha opaque.
        let bgr = PixelFormat::new(
            32,
            VisualClass::TRUE_COLOR,
            [0xff, 0xff00, 0xff_0000],
            32,
            32,
            ImageOrder::LSB_FIRST,
        );
        assert_eq!(bgr.unwrap().pixel(0x0012_3456), 0xff56_3412);
        // 5-6-5 masks keep each channel's top bits.
        let rgb565 = PixelFormat::new(
            24,
            VisualClass::TRUE_COLOR,
            [0xf800, 0x7e0, 0x1f],
            32,
            32,
            ImageOrder::LSB_FIRST,
        );
        assert_eq!(rgb565.unwrap().pixel(0x00ff_80ff) & 0xffff, 0xfc1f);
        // Rows padded to 64 bits.
        let padded =
            PixelFormat::new(24, VisualClass::TRUE_COLOR, rgb, 32, 64, ImageOrder::LSB_FIRST).unwrap();
        assert_eq!((padded.stride(3), padded.stride(4)), (16, 16));
        padded.encode(&[1, 2, 3, 4, 5, 6], 3, &mut bytes);
        assert_eq!(bytes.len(), 32);
        assert_eq!(&bytes[16..20], &[4, 0, 0, 0]);
        // Masks of holes or of more than 8 bits.
        for masks in [[0xff_0000, 0xff00, 0xf0f], [0x3ff0_0000, 0xf_fc00, 0x3ff]] {
            let e = PixelFormat::new(24, VisualClass::TRUE_COLOR, masks, 32, 32, ImageOrder::LSB_FIRST);
            assert!(e.is_err(), "{masks:x?}");
        }
        // What the viewer cannot draw in.
        for (depth, class, bits) in [
            (16, VisualClass::TRUE_COLOR, 16),
            (24, VisualClass::PSEUDO_COLOR, 32),
            (24, VisualClass::TRUE_COLOR, 24),
        ] {
            let e = PixelFormat::new(depth, class, rgb, bits, 32, ImageOrder::LSB_FIRST).unwrap_err();
            assert!(
                e.starts_with("the screen's visual is not 24- or 32-bit TrueColor"),
                "{e}"
            );
        }
    }

    #[test]
    fn an_image_is_sent_in_strips_that_fit_a_request() {
        // The core protocol's 262140 bytes, 800 pixels a row: 81 rows of 3200 bytes and the header.
        assert_eq!(rows_per_request(262_140, 3200), 81);
        // BIG-REQUESTS: no more rows than a request's 16-bit height; a row too long still goes alone.
        assert_eq!(rows_per_request(16 << 20, 4), 65535);
        assert_eq!(rows_per_request(1000, 4000), 1);
    }

    #[test]
    fn errors_are_one_line_and_name_the_display() {
        let message = cannot_open(&"Failed to\n  open connection").to_string();
        assert!(message.starts_with("cannot open a window"), "{message}");
        assert!(message.ends_with(": Failed to open connection"), "{message}");
        let refused = std::io::Error::from(std::io::ErrorKind::ConnectionRefused);
        let message = cannot_connect(&ConnectError::IoError(refused)).to_string();
        assert!(
            message.ends_with(": cannot connect to the X server: connection refused"),
            "{message}"
        );
        assert_eq!(cannot_draw(&"a\nb").to_string(), "cannot draw in the window: a b");
    }
}
