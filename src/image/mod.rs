//! Images: the film a frame renders into (linear RGB), the file formats it is written in (PNG, PPM,
//! JPEG, OpenEXR; `film.rs` chooses by the file's name and writes through a temporary name, never half
//! an image under the real one) and the codecs that read and write them (`codecs.rs`).

pub(crate) mod codecs;
pub mod film;

pub use film::{Film, ImageFormat};
