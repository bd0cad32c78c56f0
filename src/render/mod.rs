//! Rendering: camera rays per tile, traced and shaded in parallel, into a linear film.
//!
//! Where a ray goes, from the camera to the film:
//! - [`frame`]: the [`Renderer`] splits the image into [`tiles`] on rayon and, per pixel, draws the
//!   samples ([`sampler`]: jittered positions, lens points, light points, random numbers) and makes
//!   their camera rays ([`camera`]);
//! - [`whitted`]: the integrator traces each ray through the accelerator
//!   ([`crate::accel::Accel::intersect`]), shades the closest hit (Blinn-Phong over the light samples of
//!   [`light`], each behind a shadow ray, [`crate::accel::Accel::occluded`]) and recurses into the
//!   reflected and refracted rays ([`optics`]); a ray that leaves the scene sees the background
//!   ([`env`](mod@env)). With [`Kernel::Packet`], [`packets`] does the same for eight neighbouring pixels at a
//!   time through the accelerators' packet verbs; with [`Kernel::Stream`], `streams` for the pixel
//!   samples of a few tiles at a time, generation by generation, through their stream verbs;
//! - the colours land in a linear [`film::Film`], or in a [`progressive::Progressive`] sum of passes,
//!   written as an image at the end (or as a `.partial` part of a frame, [`crate::parts`]).

pub mod camera;
pub mod env;
pub mod film;
pub mod frame;
pub mod light;
pub mod memory;
pub mod optics;
mod options;
pub mod packets;
pub mod progressive;
pub mod sampler;
pub mod spd;
mod streams;
pub mod tiles;
pub mod whitted;

pub use frame::Renderer;
pub use options::{Kernel, MAX_DEPTH, MAX_SPP, Options};
pub use whitted::RayCounts;
