//! The interactive viewer (`whitted view`): a window on the scene, drawn by the same renderer as
//! `whitted render`, that moves with the keyboard and mouse.
//!
//! Three parts, one way: [`state`] turns input events and elapsed time into a [`state::Job`], the full
//! description of the image to draw (no window involved, so it is unit tested); the render thread here
//! (`render_loop`) renders jobs on the rayon pool, pass after pass, and hands back finished frames;
//! [`window`] owns the window and the event loop, feeds the input to the state, sends the jobs and
//! shows the frames. The event loop never waits on a render.
//!
//! While the camera moves each frame is one pass of one jittered sample per pixel (spp 1, the
//! renderer's progressive pass), at a resolution lowered while frames are slower than 20 fps. Once it
//! stands still, passes 1, 2, 3, ... of the full-resolution image accumulate into their running mean,
//! exactly as `whitted render --passes N` averages them: the image after N passes is that render's.

pub mod reproduce;
pub mod state;
pub mod window;

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::time::Instant;

use glam::Vec3;
use rayon::ThreadPool;

use crate::accel::{Accel, AccelKind, Prims};
use crate::heatmap::Scale;
use crate::heatmap::cost::CostKind;
use crate::image::film::{Film, to_u8};
use crate::render::RayCounts;
use crate::render::env::Background;
use crate::render::progressive::Progressive;
use crate::render::{Options, Renderer};
use crate::scene::Scene;
use state::{Accumulator, Job};

pub use window::run;

/// The largest side of the window: X11's sizes are 16-bit.
pub const MAX_WINDOW: u32 = u16::MAX as u32;

/// How the viewer starts.
#[derive(Clone, Debug)]
pub struct Config {
    /// The scene's name in the window title and in the names of saved images.
    pub name: String,
    /// The scene file as given (`None`: the built-in scene), for the `render` command printed when an
    /// image is saved.
    pub scene: Option<PathBuf>,
    /// The window's size (at most [`MAX_WINDOW`] a side), the bounce limit, the kernel, the seed and
    /// the roughness.
    pub options: Options,
    /// The first acceleration structure.
    pub accel: AccelKind,
    /// Show and save the image sRGB-encoded (else linear values, as `render` writes them).
    pub srgb: bool,
    /// Close the window after this many frames (for scripted checks).
    pub frames: Option<u32>,
    /// With `frames`: write the last frame here (.png, .ppm or .exr).
    pub screenshot: Option<PathBuf>,
}

/// A finished frame, from the render thread to the window.
#[derive(Debug)]
pub(crate) struct Frame {
    /// What it shows.
    job: Job,
    /// Passes averaged in it.
    pass: u32,
    /// The running mean, linear.
    film: Film,
    /// The same as `0x00RRGGBB` words, as the window takes them.
    pixels: Vec<u32>,
    /// Seconds the last pass took.
    seconds: f64,
    /// Rays the last pass traced.
    rays: RayCounts,
}

/// What the window tells the render thread besides the jobs: which renders in progress are not wanted
/// any more. A pass stops at the next tile once its flag is raised (see [`Renderer::render_pass`]).
#[derive(Debug, Default)]
pub(crate) struct Signals {
    /// Raised with every new job, and to quit: stops the passes of a still camera, whose image has
    /// changed.
    changed: AtomicBool,
    /// Raised with a job of other settings (accelerator, size, ...), and to quit: stops a moving
    /// camera's frame too. A camera move alone lets a moving frame finish, so that motion keeps showing
    /// frames however slow they are.
    settings: AtomicBool,
}

impl Signals {
    /// A new job was sent; `settings` if its settings differ from the last one's.
    fn raise(&self, settings: bool) {
        self.changed.store(true, Ordering::SeqCst);
        if settings {
            self.settings.store(true, Ordering::SeqCst);
        }
    }

    /// Lowered before the render thread looks for the newest job, so that anything sent after that
    /// look stops the pass that follows it.
    fn lower(&self) {
        self.changed.store(false, Ordering::SeqCst);
        self.settings.store(false, Ordering::SeqCst);
    }
}

/// The render thread: renders the newest of `jobs` on `pool`, pass after pass as
/// [`Accumulator::next`] says, and hands each finished frame to `deliver`, until the sender hangs up
/// or `deliver` returns false (the window is gone). Waits for a job while there is nothing to render.
pub(crate) fn render_loop(
    scene: &Scene,
    pool: &ThreadPool,
    jobs: &Receiver<Job>,
    signals: &Signals,
    srgb: bool,
    mut deliver: impl FnMut(Frame) -> bool,
) {
    // The skybox is read once; the frames' renderers share its images.
    let (background, warning) = Background::load(scene);
    if let Some(w) = warning {
        note(format_args!("whitted: warning: {w}"));
    }
    // Each structure is built the first time it is asked for and kept, so switching back is instant.
    let mut built: Vec<(AccelKind, Accel)> = Vec::new();
    let mut acc = Accumulator::default();
    let mut sums = Progressive::new(1, 1);
    let Ok(mut job) = jobs.recv() else { return };
    loop {
        signals.lower();
        loop {
            match jobs.try_recv() {
                Ok(newer) => job = newer,
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => return,
            }
        }
        let Some(pass) = acc.next(&job) else {
            match jobs.recv() {
                Ok(newer) => {
                    job = newer;
                    continue;
                }
                Err(_) => return,
            }
        };
        let slot = match built.iter().position(|(kind, _)| *kind == job.accel) {
            Some(slot) => slot,
            None => {
                let build = |kind| Accel::try_build_with(Prims::new(scene), kind, Default::default());
                // Only Embree can fail to build (out of memory, say): then the best of ours stands in.
                let accel = pool.install(|| build(job.accel)).unwrap_or_else(|e| {
                    note(format_args!(
                        "whitted: {e}; {:?} renders instead",
                        AccelKind::best()
                    ));
                    pool.install(|| Accel::build(Prims::new(scene), AccelKind::best()))
                });
                built.push((job.accel, accel));
                built.len() - 1
            }
        };
        let mut renderer = Renderer::with_view(
            scene,
            &built[slot].1,
            job.options,
            &job.camera,
            background.clone(),
        );
        if !job.soft_shadows {
            renderer = renderer.with_regular_lights();
        }
        if pass == 1 {
            sums = Progressive::new(job.options.width, job.options.height);
        }
        let stop = if job.moving {
            &signals.settings
        } else {
            &signals.changed
        };
        let start = Instant::now();
        let Ok(rays) = pool.install(|| sums.render_pass(&renderer, pass, &|| {}, stop)) else {
            continue;
        };
        let seconds = start.elapsed().as_secs_f64();
        acc.done(pass);
        let film = sums.film();
        let heatmap = job.heatmap.zip(sums.pixel_rays()).map(|(measure, rays)| {
            let kind = CostKind { measure, rays: None };
            let map = kind.heatmap(job.options.width, job.options.height, rays, Scale::default());
            map.overlaid().into_iter().map(packed).collect()
        });
        let pixels = heatmap.unwrap_or_else(|| film.pixels.iter().map(|&c| word(c, srgb)).collect());
        let frame = Frame {
            job,
            pass,
            film,
            pixels,
            seconds,
            rays,
        };
        if !deliver(frame) {
            return;
        }
    }
}

/// A linear colour as the window's `0x00RRGGBB` word, rounded as the saved image is.
fn word(c: Vec3, srgb: bool) -> u32 {
    packed([c.x, c.y, c.z].map(|v| to_u8(v, srgb)))
}

/// sRGB bytes as the window's `0x00RRGGBB` word.
fn packed([r, g, b]: [u8; 3]) -> u32 {
    (u32::from(r) << 16) | (u32::from(g) << 8) | u32::from(b)
}

/// Writes `text` and a newline to standard error, or drops it where standard error cannot take it:
/// a lost note must not stop the viewer.
fn note(text: impl std::fmt::Display) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr().lock(), "{text}");
}

#[cfg(test)]
mod tests {
    use std::sync::mpsc;

    use super::*;
    use crate::heatmap::cost::Measure;
    use crate::render::{DEFAULT_DEPTH, Kernel};
    use state::{Input, Job, Key, Settings, ViewState};

    #[test]
    fn words_are_the_saved_bytes() {
        assert_eq!(word(Vec3::new(1.0, 0.5, 0.0), false), 0x00ff_8000);
        assert_eq!(word(Vec3::new(2.0, -1.0, f32::NAN), false), 0x00ff_0000);
        assert_eq!(word(Vec3::splat(0.5), true), 0x00bc_bcbc);
    }

    /// The render thread without a window: a still camera's frames are `render --passes`'s passes,
    /// bit for bit; a new job starts over; hanging up ends the thread.
    #[test]
    fn renders_the_passes_of_render_and_starts_over_on_a_change() {
        let mut scene = crate::scene::load(std::path::Path::new("scenes/balls_low.p3f")).unwrap();
        // No skybox: the test is about passes, and the renderer falls back on the colour anyway.
        scene.env = None;
        let options = Options {
            width: 40,
            height: 30,
            ..Options::new(&scene)
        };
        let view = ViewState::new(
            &scene,
            options,
            Settings::new(AccelKind::Bvh4, Kernel::Packet, DEFAULT_DEPTH),
        );
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let (send, jobs) = mpsc::channel();
        let signals = Signals::default();
        // After three passes the camera turns: pass 1 of a new image, the only pass while it moves;
        // then the window hangs up, which ends the thread.
        let turned = {
            let mut v = view.clone();
            v.input(Input::Key {
                key: Key::TurnLeft,
                pressed: true,
            });
            v.tick(0.05);
            v.job()
        };
        send.send(view.job()).unwrap();
        let mut send = Some(send);
        let mut frames = Vec::new();
        render_loop(&scene, &pool, &jobs, &signals, false, |frame| {
            frames.push(frame);
            match frames.len() {
                3 => send.as_ref().unwrap().send(turned).unwrap(),
                4 => send = None,
                _ => {}
            }
            true
        });
        let passes: Vec<_> = frames.iter().map(|f| (f.pass, f.job.moving)).collect();
        assert_eq!(passes, [(1, false), (2, false), (3, false), (1, true)]);
        assert_ne!(frames[3].film, frames[0].film);

        let accel = Accel::build(Prims::new(&scene), AccelKind::Bvh4);
        let renderer = Renderer::new(&scene, &accel, Options { spp: 1, ..options });
        let mut sums = Progressive::new(40, 30);
        let never = AtomicBool::new(false);
        for pass in 1..=3 {
            sums.render_pass(&renderer, pass, &|| {}, &never).unwrap();
        }
        assert_eq!(frames[2].film, sums.film());
        assert_eq!(frames[2].rays.primary, 1200);
        let word0 = word(frames[2].film.pixels[0], false);
        assert_eq!(frames[2].pixels[0], word0);
    }

    /// C shows the heatmap of nodes visited, then of primitives tested, then the image again: the
    /// window gets the heatmap's colours (legend over its bottom rows) of a counted render whose film
    /// is the image's.
    #[test]
    fn the_heatmap_key_shows_the_counted_costs() {
        let mut scene = crate::scene::load(std::path::Path::new("scenes/balls_low.p3f")).unwrap();
        scene.env = None;
        let options = Options {
            width: 48,
            height: 64,
            ..Options::new(&scene)
        };
        let mut view = ViewState::new(
            &scene,
            options,
            Settings::new(AccelKind::Bvh4, Kernel::Packet, DEFAULT_DEPTH),
        );
        let plain = view.job();
        let press = |v: &mut ViewState| {
            v.input(Input::Key {
                key: Key::Heatmap,
                pressed: true,
            });
            v.input(Input::Key {
                key: Key::Heatmap,
                pressed: false,
            });
            v.job()
        };
        let nodes = press(&mut view);
        let prims = press(&mut view);
        assert_eq!(press(&mut view), plain);
        assert_eq!(
            (nodes.heatmap, nodes.options.count_steps),
            (Some(Measure::Nodes), true)
        );
        assert_eq!(
            (prims.heatmap, plain.heatmap, plain.options.count_steps),
            (Some(Measure::Prims), None, false)
        );

        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        let (send, jobs) = mpsc::channel();
        send.send(Job {
            progressive: false,
            ..nodes
        })
        .unwrap();
        let mut send = Some(send);
        let mut frames = Vec::new();
        render_loop(&scene, &pool, &jobs, &Signals::default(), false, |frame| {
            frames.push(frame);
            // One frame: hanging up ends the thread.
            send = None;
            true
        });
        let frame = &frames[0];
        assert!(frame.rays.steps.total().nodes > 0);
        let accel = Accel::build(Prims::new(&scene), AccelKind::Bvh4);
        let renderer = Renderer::new(
            &scene,
            &accel,
            Options {
                spp: 1,
                count_steps: true,
                ..options
            },
        );
        let mut sums = Progressive::new(48, 64);
        sums.render_pass(&renderer, 1, &|| {}, &AtomicBool::new(false))
            .unwrap();
        assert_eq!(
            frame.film,
            sums.film(),
            "the image under the heatmap is the render's"
        );
        let map = CostKind {
            measure: Measure::Nodes,
            rays: None,
        }
        .heatmap(48, 64, sums.pixel_rays().unwrap(), Scale::default());
        assert_eq!(frame.pixels[0], packed(map.overlaid()[0]));
        assert_ne!(frame.pixels[0], word(frame.film.pixels[0], false));
    }
}
