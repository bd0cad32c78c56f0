//! The test kit, compiled only with the `kit` feature: what the unit tests, the integration tests, the
//! benches and the profiles share, written once so that they test and measure the same things.
//!
//! - [`agreement`]: how closely an accelerator's hits must match the oracle's, and when two triangle
//!   tests may round apart.
//! - [`rays`]: seeded random numbers and the test rays (random, camera, grazing, from surfaces).
//! - [`contestants`]: every accelerator and kernel, built and named, for a test or a bench to go through.
//! - [`oracle`]: the comparison with brute force (or with the grid, itself proven identical to brute
//!   force, where brute force on every ray would take minutes).
//! - [`workload`]: the dragon benchmark's ray sets.
//!
//! None of it is needed to render, so the library's default surface leaves it out. `Cargo.toml` turns it
//! on for tests, benches and examples through a dev-dependency of the crate on itself.

pub mod agreement;
pub mod contestants;
pub mod oracle;
pub mod rays;
pub mod workload;
