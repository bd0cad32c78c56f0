//! `whitted bench`'s arguments made into what it times: the scene and the frames' options.

use std::path::{Path, PathBuf};

use whitted::render::Options;
use whitted::scene::Scene;

use super::args::BenchArgs;
use crate::cli::frame::{DEFAULT_DEPTH, checked, spd_refuses};

/// The benchmark scene, relative to a source tree or to the current directory.
const DRAGON: &str = "scenes/dragon.p3f";

/// The first of `candidates` that is a file, or an error that names them all and says how to pass a
/// scene.
fn find_scene(candidates: &[PathBuf]) -> whitted::Result<PathBuf> {
    if let Some(found) = candidates.iter().find(|p| p.is_file()) {
        return Ok(found.clone());
    }
    let tried: Vec<String> = candidates.iter().map(|p| p.display().to_string()).collect();
    Err(whitted::Error::msg(format!(
        "no scene given, and the default benchmark scene is not at {}; pass one: whitted bench SCENE",
        tried.join(" nor at ")
    )))
}

/// The scene given, or the dragon scene: in the source tree this binary was built from while that tree
/// exists (a `cargo install`ed binary outlives its build directory), else under the current directory.
pub fn scene(args: &BenchArgs) -> whitted::Result<PathBuf> {
    if let Some(path) = &args.scene {
        return Ok(path.clone());
    }
    let sources = Path::new(env!("CARGO_MANIFEST_DIR")).join(DRAGON);
    find_scene(&[sources, PathBuf::from(DRAGON)])
}

/// The frames' options: the scene's with the arguments', or the SPD procedure's.
pub fn options(args: &BenchArgs, scene: &Scene) -> whitted::Result<Options> {
    spd_refuses(
        args.spd,
        &[
            ("--spp", args.spp.is_some()),
            ("--width", args.frame.width.is_some()),
            ("--height", args.frame.height.is_some()),
            ("--max-depth", args.max_depth.is_some()),
        ],
    )?;
    let depth = args.max_depth.unwrap_or(DEFAULT_DEPTH);
    let options = Options {
        spp: args.spp.unwrap_or(scene.spp),
        count_steps: args.counters,
        ..args.frame.options(scene, depth)
    };
    checked(args.spd, options, scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_scene_is_the_first_file_found_or_an_error_naming_where_it_looked() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.p3f"), dir.path().join("b.p3f"));
        let error = find_scene(&[a.clone(), b.clone()]).unwrap_err().to_string();
        let expected = format!(
            "no scene given, and the default benchmark scene is not at {} nor at {}; pass one: \
             whitted bench SCENE",
            a.display(),
            b.display()
        );
        assert_eq!(error, expected);
        std::fs::write(&b, "").unwrap();
        assert_eq!(find_scene(&[a.clone(), b.clone()]).unwrap(), b);
        std::fs::write(&a, "").unwrap();
        assert_eq!(find_scene(&[a.clone(), b]).unwrap(), a);
        // A directory of that name is not the scene.
        let c = dir.path().join("c.p3f");
        std::fs::create_dir(&c).unwrap();
        assert!(find_scene(&[c]).is_err());
    }
}
