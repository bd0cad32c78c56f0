//! The two ways a tile's pixel samples are traced and shaded, one file each ([`Kernel`]): one ray at a
//! time (`single`) or eight neighbouring pixels' rays as packets (`packet`). Both give the same image,
//! bit for bit: both run the integrator's one walk of the ray tree (`super::whitted`), at one lane or
//! at eight, from the same rays.
//!
//! [`Kernel`]: super::Kernel

mod packet;
mod single;

use glam::Vec3;

use super::tiles::TILE;
use crate::accel::PACKET;

/// A tile's pixels, row-major at a stride of [`TILE`].
pub(super) type TilePixels = [Vec3; (TILE * TILE) as usize];

/// The block of pixels whose camera rays make a packet: 4 wide, `PACKET / 4` = 2 high.
const BLOCK_W: u32 = 4;
const BLOCK_H: u32 = PACKET as u32 / BLOCK_W;

/// One value per ray of a packet (its rays, their samples, the colours they see).
type PerRay<T> = [T; PACKET];
