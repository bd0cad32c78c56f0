//! The viewer's state, without a window: the camera as the input moves it, the settings the keys
//! switch, and the rules that decide what the render thread draws next (the resolution while the camera
//! moves, the passes accumulated while it stands still). Everything here is plain data driven by
//! [`Input`] values and elapsed seconds, so that it is tested without a display.

use glam::{Quat, Vec3};

use crate::accel::AccelKind;
use crate::heatmap::cost::Measure;
use crate::render::{Kernel, Options};
use crate::scene::{Camera, Scene};

/// A frame rendered while the camera moves that takes longer than this (under 20 fps) makes the next
/// ones coarser.
pub const SLOW_FRAME: f64 = 1.0 / 20.0;
/// A moving frame faster than this fraction of [`SLOW_FRAME`] at the next finer resolution (four times
/// the pixels) makes the next ones finer; the margin keeps the resolution from flipping to and fro.
const HEADROOM: f64 = 0.8;
/// The coarsest resolution: a quarter of the window's in each direction.
pub const MAX_SCALE: u32 = 4;
/// The camera stands still this many seconds after its last change: long enough to bridge the gaps
/// between the events of a slow drag (so the resolution does not flip at every pause), short enough
/// that the refinement starts as soon as the user lets go.
pub const STILL_AFTER: f32 = 0.25;
/// The field of view's range, in degrees: the wheel zooms within it.
pub const FOV_RANGE: (f32, f32) = (5.0, 150.0);
/// The deepest bounce limit `]` reaches.
pub const MAX_VIEW_DEPTH: u32 = 32;
/// The movement keys travel this fraction of the scene's diagonal per second: scenes come in any
/// unit, and a tenth crosses the usual ground plane in seconds without overshooting the object on it.
const MOVE_RATE: f32 = 0.1;
/// The arrow keys turn the camera this many degrees per second.
const TURN_RATE: f32 = 90.0;
/// A drag orbits the camera this many degrees per pixel.
const DRAG_RATE: f32 = 0.3;
/// Each line of the wheel divides the field of view by this (turned away from the user: zoom in).
const ZOOM_STEP: f32 = 1.1;
/// The view direction stays this many degrees from the horizon at most, off the up vector, where the
/// camera's frame is undefined.
const MAX_ELEVATION: f32 = 89.0;
/// A tick advances the camera by this many seconds at most, so that a stalled event loop does not
/// throw it across the scene.
const MAX_TICK: f32 = 0.1;

/// A key the viewer reacts to, whatever the window system calls it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// W: move along the view direction.
    Forward,
    /// A: move left.
    Left,
    /// S: move back.
    Back,
    /// D: move right.
    Right,
    /// Q: move down (along the scene's up vector).
    Down,
    /// E: move up.
    Up,
    /// Left arrow: turn left in place.
    TurnLeft,
    /// Right arrow: turn right in place.
    TurnRight,
    /// Up arrow: look up.
    TurnUp,
    /// Down arrow: look down.
    TurnDown,
    /// R: back to the scene file's camera.
    Reset,
    /// 1 to 5 (6: Embree, with the `embree` feature): the accelerator.
    Accel(AccelKind),
    /// K: single rays or packets, in turn.
    Kernel,
    /// H: soft shadows (sampled quad lights) or the quad lights' regular grids.
    SoftShadows,
    /// F: the file's lens aperture, or a pinhole.
    DepthOfField,
    /// `[`: one bounce less.
    LessDepth,
    /// `]`: one bounce more.
    MoreDepth,
    /// P: refine a still camera's image with more passes, or keep its first.
    Progressive,
    /// C: the cost heatmap: nodes visited, primitives tested, or off, in turn.
    Heatmap,
}

/// The keys held down to move or turn, in the order of [`ViewState::held`].
const MOTION: [Key; 10] = [
    Key::Forward,
    Key::Back,
    Key::Right,
    Key::Left,
    Key::Up,
    Key::Down,
    Key::TurnLeft,
    Key::TurnRight,
    Key::TurnUp,
    Key::TurnDown,
];

/// What the user did, in the viewer's terms.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Input {
    /// A key went down (`pressed`) or up.
    Key {
        /// Which.
        key: Key,
        /// Down or up.
        pressed: bool,
    },
    /// The pointer moved by `(dx, dy)` pixels (right, down) with the button held: orbit the point looked
    /// at.
    Drag {
        /// Pixels to the right.
        dx: f32,
        /// Pixels down.
        dy: f32,
    },
    /// The wheel turned this many lines away from the user (negative: toward): zoom in (out).
    Scroll(f32),
    /// The window's drawable area is now `width` × `height` pixels (0 while minimised).
    Resize {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
    },
    /// The window lost the keyboard: the keys held count as released, since their releases go elsewhere.
    ReleaseAll,
}

/// What the keys switch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Settings {
    /// The acceleration structure.
    pub accel: AccelKind,
    /// Single rays or packets.
    pub kernel: Kernel,
    /// Quad lights sampled per pixel sample (soft shadows), or as their regular grids of point lights.
    pub soft_shadows: bool,
    /// The file's lens aperture, or a pinhole.
    pub depth_of_field: bool,
    /// Most bounces after the primary hit.
    pub max_depth: u32,
    /// More passes while the camera stands still.
    pub progressive: bool,
    /// The cost heatmap shown instead of the image, if any.
    pub heatmap: Option<Measure>,
}

impl Settings {
    /// Soft shadows, depth of field and progressive refinement on.
    pub fn new(accel: AccelKind, kernel: Kernel, max_depth: u32) -> Self {
        Settings {
            accel,
            kernel,
            soft_shadows: true,
            depth_of_field: true,
            max_depth: max_depth.min(MAX_VIEW_DEPTH),
            progressive: true,
            heatmap: None,
        }
    }
}

/// What the render thread is to draw: the whole description of an image, compared as a value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Job {
    /// The viewpoint, the rendered size (the window's divided by `scale`) and the lens (aperture 0 with
    /// depth of field off).
    pub camera: Camera,
    /// The size again (the camera's), one sample per pass, the depth, the kernel, the seed.
    pub options: Options,
    /// The acceleration structure.
    pub accel: AccelKind,
    /// Sampled quad lights, or their regular grids.
    pub soft_shadows: bool,
    /// The window's size over the rendered size: 1, 2 or 4.
    pub scale: u32,
    /// The camera moves: one pass only, which nothing but a setting change interrupts.
    pub moving: bool,
    /// More passes once the camera stands still.
    pub progressive: bool,
    /// The cost heatmap shown instead of the image (the render counts steps), if any.
    pub heatmap: Option<Measure>,
}

impl Job {
    /// The image this job draws, apart from how many passes it gets: what accumulation is keyed on.
    fn image(&self) -> Job {
        Job {
            moving: false,
            progressive: false,
            ..*self
        }
    }

    /// True when `self` asks for more passes than the first.
    pub fn refines(&self) -> bool {
        self.progressive && !self.moving
    }

    /// True when `other` differs from `self` by more than where the camera is and looks: another
    /// accelerator, kernel, light model, depth, lens or size.
    pub fn changes_settings(&self, other: &Job) -> bool {
        let settings = |j: &Job| Job {
            camera: Camera {
                from: Vec3::ZERO,
                at: Vec3::ZERO,
                fov_y: 0.0,
                ..j.camera
            },
            ..j.image()
        };
        settings(self) != settings(other)
    }
}

/// The pass count of the image being drawn: which pass the render thread renders next.
#[derive(Clone, Debug, Default)]
pub struct Accumulator {
    /// The image the passes belong to.
    image: Option<Job>,
    /// Passes of it done.
    passes: u32,
}

impl Accumulator {
    /// The pass to render next for `job` (from 1; pass 1 starts a new running mean): 1 after any change
    /// of the image (camera, setting, size), then 2, 3, ... while the job refines; `None` once the
    /// image has all the passes it gets.
    pub fn next(&mut self, job: &Job) -> Option<u32> {
        let image = job.image();
        if self.image != Some(image) {
            self.image = Some(image);
            self.passes = 0;
        }
        (self.passes == 0 || job.refines()).then_some(self.passes + 1)
    }

    /// Pass `pass` of the current image is done.
    pub fn done(&mut self, pass: u32) {
        self.passes = pass;
    }

    /// Passes of the current image done.
    pub fn passes(&self) -> u32 {
        self.passes
    }
}

/// The camera, settings and resolution of the viewer, driven by [`Input`] and time.
#[derive(Clone, Debug)]
pub struct ViewState {
    /// The scene file's camera at the starting size: what [`Key::Reset`] returns to.
    file: Camera,
    /// Eye, point looked at (at the file's distance, which is the lens's view plane) and field of view.
    from: Vec3,
    at: Vec3,
    fov_y: f32,
    /// Unit up vector of the scene: the axis of turns and of Q/E.
    up: Vec3,
    /// What the options carry beyond the settings (seed, roughness).
    options: Options,
    settings: Settings,
    /// The window's drawable size.
    size: (u32, u32),
    /// Scene units per second of the movement keys.
    speed: f32,
    /// Which of [`MOTION`] are held down.
    held: [bool; MOTION.len()],
    /// The resolution divisor while moving, learnt from the frame times.
    scale: u32,
    /// Seconds since the camera last changed.
    since_change: f32,
}

impl ViewState {
    /// The scene's camera at `options`' size, which is the window's to begin with; `options` also give
    /// the seed and roughness, `settings` the rest.
    pub fn new(scene: &Scene, options: Options, settings: Settings) -> Self {
        let file = Camera {
            width: options.width,
            height: options.height,
            ..scene.camera
        };
        let up = file.up.normalize_or(Vec3::Y);
        ViewState {
            file,
            from: file.from,
            at: file.at,
            fov_y: file.fov_y,
            up,
            options,
            settings,
            size: (options.width, options.height),
            speed: MOVE_RATE * scene_size(scene),
            held: [false; MOTION.len()],
            scale: 1,
            since_change: STILL_AFTER,
        }
    }

    /// Applies an input event. Held keys take effect in [`ViewState::tick`].
    pub fn input(&mut self, input: Input) {
        match input {
            Input::Key { key, pressed } => {
                if let Some(i) = MOTION.iter().position(|&k| k == key) {
                    self.held[i] = pressed;
                } else if pressed {
                    self.press(key);
                }
            }
            Input::Drag { dx, dy } => {
                let distance = (self.at - self.from).length();
                let dir = turn(self.direction(), self.up, -dx * DRAG_RATE, -dy * DRAG_RATE);
                self.set_pose(self.at - dir * distance, self.at, self.fov_y);
            }
            Input::Scroll(lines) => {
                let fov = (self.fov_y / ZOOM_STEP.powf(lines)).clamp(FOV_RANGE.0, FOV_RANGE.1);
                self.set_pose(self.from, self.at, fov);
            }
            Input::Resize { width, height } => {
                if width > 0 && height > 0 {
                    self.size = (width, height);
                }
            }
            Input::ReleaseAll => self.held = [false; MOTION.len()],
        }
    }

    /// A key that acts once, when pressed.
    fn press(&mut self, key: Key) {
        let s = &mut self.settings;
        match key {
            // A jump, not a motion: the resolution stays as it is.
            Key::Reset => (self.from, self.at, self.fov_y) = (self.file.from, self.file.at, self.file.fov_y),
            Key::Accel(kind) => s.accel = kind,
            Key::Kernel => s.kernel = s.kernel.next(),
            Key::SoftShadows => s.soft_shadows = !s.soft_shadows,
            Key::DepthOfField => s.depth_of_field = !s.depth_of_field,
            Key::LessDepth => s.max_depth = s.max_depth.saturating_sub(1),
            Key::MoreDepth => s.max_depth = (s.max_depth + 1).min(MAX_VIEW_DEPTH),
            Key::Progressive => s.progressive = !s.progressive,
            Key::Heatmap => {
                s.heatmap = match s.heatmap {
                    None => Some(Measure::Nodes),
                    Some(Measure::Nodes) => Some(Measure::Prims),
                    Some(_) => None,
                }
            }
            // Held, not pressed: see `tick`.
            Key::Forward
            | Key::Left
            | Key::Back
            | Key::Right
            | Key::Down
            | Key::Up
            | Key::TurnLeft
            | Key::TurnRight
            | Key::TurnUp
            | Key::TurnDown => {}
        }
    }

    /// Moves and turns the camera by the keys held for `dt` seconds, and lets the time pass by which
    /// the camera comes to stand still.
    pub fn tick(&mut self, dt: f32) {
        let dt = dt.clamp(0.0, MAX_TICK);
        let axis = |i: usize| self.held[i] as i32 as f32 - self.held[i + 1] as i32 as f32;
        let (forward, right, rise) = (axis(0), axis(2), axis(4));
        let (yaw, pitch) = (axis(6), axis(8));
        let dir = self.direction();
        let right_dir = dir.cross(self.up).normalize_or_zero();
        let step = (forward * dir + right * right_dir + rise * self.up) * self.speed * dt;
        let (from, at) = (self.from + step, self.at + step);
        let at = if (yaw, pitch) == (0.0, 0.0) {
            at
        } else {
            let dir = turn(dir, self.up, yaw * TURN_RATE * dt, pitch * TURN_RATE * dt);
            from + dir * (at - from).length()
        };
        if (from, at) == (self.from, self.at) {
            self.since_change += dt;
        } else {
            self.set_pose(from, at, self.fov_y);
        }
    }

    /// Sets the viewpoint; a change counts as motion.
    fn set_pose(&mut self, from: Vec3, at: Vec3, fov_y: f32) {
        if (from, at, fov_y) != (self.from, self.at, self.fov_y) {
            (self.from, self.at, self.fov_y) = (from, at, fov_y);
            self.since_change = 0.0;
        }
    }

    /// The unit view direction.
    fn direction(&self) -> Vec3 {
        (self.at - self.from).normalize()
    }

    /// True while the camera moves: it changed less than [`STILL_AFTER`] seconds ago.
    pub fn moving(&self) -> bool {
        self.since_change < STILL_AFTER
    }

    /// True while [`ViewState::tick`] has something to do: keys are held, or the camera is about to
    /// come to rest.
    pub fn animating(&self) -> bool {
        self.held.contains(&true) || self.moving()
    }

    /// The scene file's camera at the starting size.
    pub fn file_camera(&self) -> Camera {
        self.file
    }

    /// The settings.
    pub fn settings(&self) -> Settings {
        self.settings
    }

    /// The camera at the window's full size.
    pub fn camera(&self) -> Camera {
        Camera {
            from: self.from,
            at: self.at,
            fov_y: self.fov_y,
            width: self.size.0,
            height: self.size.1,
            ..self.file
        }
    }

    /// The resolution divisor of moving frames.
    pub fn scale(&self) -> u32 {
        self.scale
    }

    /// What to render now: one sample per pixel per pass; while moving at the learnt resolution, else at
    /// the window's.
    pub fn job(&self) -> Job {
        let moving = self.moving();
        let scale = if moving { self.scale } else { 1 };
        let (width, height) = (self.size.0.div_ceil(scale), self.size.1.div_ceil(scale));
        let s = self.settings;
        let camera = Camera {
            width,
            height,
            aperture: if s.depth_of_field { self.file.aperture } else { 0.0 },
            ..self.camera()
        };
        Job {
            camera,
            options: Options {
                width,
                height,
                max_depth: s.max_depth,
                kernel: s.kernel,
                spp: 1,
                count_steps: s.heatmap.is_some(),
                ..self.options
            },
            accel: s.accel,
            soft_shadows: s.soft_shadows,
            scale,
            moving,
            progressive: s.progressive,
            heatmap: s.heatmap,
        }
    }

    /// Learns from a finished frame of `job` that took `seconds`: a moving frame under 20 fps halves
    /// the resolution of the next (down to a quarter); one fast enough to afford four times the
    /// pixels doubles it. Frames at another resolution than the current one are old news.
    pub fn frame_rendered(&mut self, job: &Job, seconds: f64) {
        if !job.moving || job.scale != self.scale {
            return;
        }
        if seconds > SLOW_FRAME {
            self.scale = (self.scale * 2).min(MAX_SCALE);
        } else if self.scale > 1 && 4.0 * seconds < HEADROOM * SLOW_FRAME {
            self.scale /= 2;
        }
    }
}

/// `dir` (unit) turned `yaw` degrees left about `up` (unit) and raised `pitch` degrees, its elevation
/// kept within [`MAX_ELEVATION`] (or where it is, for a file's camera that looks steeper).
fn turn(dir: Vec3, up: Vec3, yaw: f32, pitch: f32) -> Vec3 {
    let elevation = dir.dot(up).clamp(-1.0, 1.0).asin().to_degrees();
    let heading = (dir - dir.dot(up) * up).normalize_or(up.any_orthonormal_vector());
    let heading = Quat::from_axis_angle(up, yaw.to_radians()) * heading;
    let limit = MAX_ELEVATION.max(elevation.abs());
    let elevation = (elevation + pitch).clamp(-limit, limit).to_radians();
    (heading * elevation.cos() + up * elevation.sin()).normalize()
}

/// The scene's size for the movement speed: the diagonal of its bounded primitives, or for a scene of
/// planes alone the camera's distance to the point it looks at.
fn scene_size(scene: &Scene) -> f32 {
    let b = scene.bounds();
    let diagonal = (b.max - b.min).length();
    let distance = (scene.camera.at - scene.camera.from).length();
    [diagonal, distance, 1.0]
        .into_iter()
        .find(|d| d.is_finite() && *d > 0.0)
        .unwrap_or(1.0)
}

#[cfg(test)]
mod tests;
