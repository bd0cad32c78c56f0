//! Rendering: camera rays per tile, traced and shaded in parallel, into a linear film.
//!
//! Where a ray goes, from the camera to the film:
//! - `frame.rs` schedules the image's [`tiles`] on rayon; per pixel, the [`Renderer`] draws the
//!   samples ([`sampler`]: jittered positions, lens points, light points, random numbers) and makes
//!   their camera rays ([`camera`]); a kernel (`kernel/`: single rays or packets, [`Kernel`])
//!   traces and shades them;
//! - `whitted.rs`: the integrator traces rays through the accelerator, one or a packet of eight with
//!   the same code ([`crate::accel::Accel::intersect`], [`crate::accel::Accel::intersect_packet`]),
//!   shades the closest hits in lanes (`shade.rs`: Blinn-Phong over the light samples of [`light`],
//!   each behind a shadow ray, [`crate::accel::Accel::occluded`]) and recurses into the reflected and
//!   refracted rays ([`optics`]); a ray that leaves the scene sees the background
//!   ([`env`](mod@env)). The single-ray kernel runs it on one lane, [`Kernel::Packet`] on eight
//!   neighbouring pixels' rays;
//! - the colours land in a linear [`crate::image::Film`], or in a [`progressive::Progressive`] sum of passes,
//!   written as an image at the end (or as a `.partial` part of a frame, [`crate::parts`]).

pub mod camera;
pub mod env;
pub(crate) mod frame;
mod kernel;
mod lanes;
pub mod light;
pub mod memory;
pub mod optics;
mod options;
pub mod progressive;
mod renderer;
pub mod sampler;
mod setup;
mod shade;
pub mod spd;
mod stats;
pub mod tiles;
mod whitted;

pub use frame::TilePass;
pub use options::{DEFAULT_DEPTH, Kernel, MAX_DEPTH, MAX_SPP, Options};
pub use renderer::Renderer;
pub use shade::EPSILON;
pub use stats::{KindSteps, RayCounts, RayKind};
