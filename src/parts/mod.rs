//! Parts of a frame rendered apart (on the nodes of a cluster, by the jobs of an array) and merged into
//! the one image a single machine would have made.
//!
//! A part is a subset of the frame's tiles ([`crate::render::tiles::part`], `--tiles K/N`) over a range
//! of its passes (`--passes-range A..B`: passes A to B−1, counted from 0). Since a pixel's random numbers
//! depend only on (seed, pixel, pass) ([`crate::render::sampler`]), a part's pixels are exactly those
//! the whole render computes, and since parts keep `f64` sums rather than means
//! ([`crate::render::progressive::Progressive`]), merging adds them up to the whole render's sums.
//!
//! These are files the renderer writes, not part of rendering: [`partial`] is the file format a part
//! is written in, and [`merge`] adds parts up into the frame after checking that they belong to one
//! render and cover it exactly once.

pub mod merge;
pub mod partial;
