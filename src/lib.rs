//! `whitted`: a data-oriented CPU Whitted ray tracer.
//!
//! The flow runs one way: a scene file is tokenized ([`scene::lex`]) and parsed ([`scene::p3f`],
//! [`scene::ply`], [`scene::obj`]) into a structure-of-arrays [`scene::Scene`]; an accelerator
//! ([`accel::Accel`]) is built over its primitives; the [`render::Renderer`] traces camera rays tile by
//! tile on rayon and shades them with Whitted's model (Whitted 1980) into a linear
//! [`image::Film`], written as an 8-bit PNG (or EXR) at the end.
//!
//! The layout of the crate, folder by folder, and the path of a ray from the camera to the film are
//! described once, in `docs/architecture.md`.
//!
//! Load a scene, build an accelerator, render:
//!
//! ```
//! use std::path::Path;
//! use whitted::accel::{Accel, AccelKind, Prims};
//! use whitted::render::{Options, Renderer};
//!
//! let scene = whitted::scene::load(Path::new("scenes/balls_low.p3f"))?;
//! let accel = Accel::build(Prims::new(&scene), AccelKind::None);
//! let mut options = Options::new(&scene);
//! (options.width, options.height) = (64, 64);
//! let film = Renderer::new(&scene, &accel, options).render();
//! film.write(&std::env::temp_dir().join("whitted-doctest.png"), false)?;
//! # Ok::<(), whitted::Error>(())
//! ```
//!
//! Scenes can be built in code too:
//!
//! ```
//! use glam::Vec3;
//! use whitted::scene::{Camera, Material, Scene};
//!
//! let mut scene = Scene::new(Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 45.0, 32, 32));
//! let red = scene.add_material(Material { diffuse: Vec3::new(1.0, 0.0, 0.0), ..Material::default() });
//! scene.add_sphere(Vec3::ZERO, 1.0, red);
//! scene.add_point_light(Vec3::new(0.0, 0.0, 5.0), Vec3::ONE);
//! assert!(scene.camera.validate().is_ok());
//! ```

pub mod accel;
pub mod digest;
pub mod error;
pub mod files;
pub mod geometry;
pub mod heatmap;
pub mod image;
#[cfg(feature = "kit")]
pub mod kit;
pub mod machine;
pub mod parts;
pub mod render;
pub mod scene;
#[cfg(feature = "view")]
pub mod view;

pub use error::{Error, Result};
