//! The first steps of the subcommands: the scene they load, the warnings they print, the threads they
//! render on.

use std::path::Path;

use whitted::scene::{self, Format, Scene};

/// The scene drawn when none is given, compiled into the binary so the first command works anywhere.
const DEFAULT_SCENE: &str = include_str!("../../scenes/default.p3f");

/// Loads the named scene (standard input for `-`), in `format` if given, or the built-in one.
pub fn load_scene(path: Option<&Path>, format: Option<Format>) -> whitted::Result<Scene> {
    match (path, format) {
        (Some(p), _) if p == Path::new("-") => scene::read(Box::new(std::io::stdin()), format),
        (Some(p), Some(format)) => scene::load_as(p, format),
        (Some(p), None) => scene::load(p),
        (None, None) => scene::p3f::parse(Path::new("(default scene)"), Box::new(DEFAULT_SCENE.as_bytes())),
        (None, Some(_)) => Err(whitted::Error::msg(
            "--format gives the format of SCENE: name one (- for standard input)",
        )),
    }
}

/// How reports name the scene at `path`: standard input as `<stdin>`.
pub fn scene_name(path: &Path) -> String {
    if path == Path::new("-") {
        scene::STDIN.into()
    } else {
        path.display().to_string()
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
