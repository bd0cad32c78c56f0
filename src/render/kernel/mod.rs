//! The two ways a tile's pixel samples are traced and shaded, one file each ([`Kernel`]): one ray at a
//! time (`single`) or eight neighbouring pixels' rays as packets (`packet`). Both give the same image,
//! bit for bit: each shades with the single-ray integrator's own code (`super::whitted`) from the same
//! rays.
//!
//! [`Kernel`]: super::Kernel

mod packet;
mod shade;
mod single;

use glam::Vec3;

use super::tiles::TILE;
use crate::accel::PACKET;
use crate::geometry::ray::Ray;

/// A tile's pixels, row-major at a stride of [`TILE`].
pub(super) type TilePixels = [Vec3; (TILE * TILE) as usize];

/// The block of pixels whose camera rays make a packet: 4 wide, `PACKET / 4` = 2 high.
const BLOCK_W: u32 = 4;
const BLOCK_H: u32 = PACKET as u32 / BLOCK_W;

/// One value per ray of a packet (its rays, their samples, the colours they see).
type PerRay<T> = [T; PACKET];

/// Packets with fewer live rays than this go ray by ray: a packet's node tests cost about as much for
/// one ray as for eight.
const MIN_LANES: u32 = 2;

/// Whether `rays` (up to a packet's worth) are worth tracing as a packet: at least [`MIN_LANES`] of
/// them, their directions all in one octant.
fn coherent<'r>(mut rays: impl Iterator<Item = &'r Ray>) -> bool {
    let octant = |r: &Ray| r.dir.cmplt(Vec3::ZERO).bitmask();
    let Some(first) = rays.next().map(octant) else {
        return false;
    };
    let mut n = 1;
    for r in rays {
        if octant(r) != first {
            return false;
        }
        n += 1;
    }
    n >= MIN_LANES
}
