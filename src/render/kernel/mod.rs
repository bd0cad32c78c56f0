//! The two ways a tile's pixel samples are traced and shaded, one file each ([`Kernel`]): one ray at a
//! time (`single`) or eight neighbouring pixels' rays as packets (`packet`). Both give the same image,
//! bit for bit: both run the integrator's one walk of the ray tree (`super::whitted`), at one lane or
//! at eight, from the same rays.
//!
//! [`Kernel`]: super::Kernel

mod packet;
mod single;

use std::sync::atomic::AtomicBool;

use glam::Vec3;

use super::setup::Setup;
use super::stats::{Count, TileRays};
use super::tiles::{TILE, Tile};
use crate::accel::PACKET;

/// A kernel: how a tile's pixel samples are traced and shaded.
pub(super) trait Driver {
    /// Shades `tile` of `setup`'s frame for pass `pass` into `buf`, counting its rays into `rays`
    /// (and their steps where `C` counts them); leaves the tile half done once `stop` is set.
    fn tile<C: Count>(
        setup: &Setup,
        tile: Tile,
        pass: u32,
        buf: &mut TilePixels,
        rays: &mut TileRays,
        stop: &AtomicBool,
    );
}

/// One pixel sample's ray at a time (`single.rs`).
pub(super) struct Single;

/// The camera rays of 4x2 pixels as a packet of eight (`packet.rs`).
pub(super) struct Packets;

/// A tile's pixels, row-major at a stride of [`TILE`].
pub(super) type TilePixels = [Vec3; (TILE * TILE) as usize];

/// The block of pixels whose camera rays make a packet: 4 wide, `PACKET / 4` = 2 high.
const BLOCK_W: u32 = 4;
const BLOCK_H: u32 = PACKET as u32 / BLOCK_W;

/// One value per ray of a packet (its rays, their samples, the colours they see).
type PerRay<T> = [T; PACKET];
