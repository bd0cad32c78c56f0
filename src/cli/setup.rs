//! The first steps of the subcommands: the scene they load, the warnings they print, the threads they
//! render on.

use std::path::Path;

use whitted::scene::{self, Scene};

/// The scene drawn when none is given, compiled into the binary so the first command works anywhere.
const DEFAULT_SCENE: &str = include_str!("../../scenes/default.p3f");

/// Loads the named scene, or the built-in one.
pub fn load_scene(path: Option<&Path>) -> whitted::Result<Scene> {
    match path {
        Some(p) => scene::load(p),
        None => scene::p3f::parse(Path::new("(default scene)"), Box::new(DEFAULT_SCENE.as_bytes())),
    }
}

/// A rayon pool of `threads` workers (all cores when `None`; clap bounds the count).
pub fn thread_pool(threads: Option<usize>) -> whitted::Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| whitted::Error::msg(format!("cannot start the worker threads: {e}")))
}

/// Prints `warnings` on stderr, one a line.
pub fn warn(warnings: &[String]) {
    for w in warnings {
        crate::cli::console::note(format!("whitted: warning: {w}"));
    }
}
