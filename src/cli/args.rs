//! What the subcommands share: the frame's arguments, the camera overrides, the SPD procedure's frame,
//! the scene they load, the threads they render on, and the parsers of their numbers.

use std::path::Path;

use clap::Args;
use glam::Vec3;
use whitted::accel::AccelKind;
use whitted::render::film::Film;
use whitted::render::{Kernel, Options, spd};
use whitted::scene::{self, Camera, Scene};

use super::render::RenderArgs;

/// The scene drawn when none is given, compiled into the binary so the first command works anywhere.
const DEFAULT_SCENE: &str = include_str!("../../scenes/default.p3f");

/// The frame's size, the threads and the structure and kernel that trace it (`render`, `bench`, `view`).
#[derive(Args)]
pub struct FrameArgs {
    /// Image width (keeps the vertical field of view; the height follows the aspect ratio if not given).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height.
    #[arg(long)]
    pub height: Option<u32>,
    /// Worker threads, 1 to 1024 (default: all cores).
    #[arg(long, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=1024))]
    pub threads: Option<usize>,
    /// Acceleration structure: none, grid, bvh2, bvh4, bvh8 (8-wide nodes, AVX2 where the CPU has it),
    /// auto (bvh8 on CPUs with AVX2, else bvh4) or embree (Embree 3; builds with `--features embree`).
    #[arg(long, default_value = "auto")]
    pub accel: AccelKind,
    /// Rays one at a time (single), in packets of 8 neighbouring pixels (packet, BVH4 and BVH8), or a
    /// few tiles' rays a generation at a time, as streams split at each node (stream); same image.
    #[arg(long, default_value = "packet")]
    pub kernel: Kernel,
}

/// The bounce limit when `--max-depth` is not given.
pub const DEFAULT_DEPTH: u32 = 6;

/// Where the camera is and looks, over the scene file's (`render`, `bench`). Points are `X,Y,Z`: one
/// word, so that a printed command line needs no quotes.
#[derive(Args, Clone, Debug, Default, PartialEq)]
pub struct CameraArgs {
    /// The eye position, `X,Y,Z` (overrides the file's `from`).
    #[arg(long, value_name = "X,Y,Z", value_parser = point, allow_hyphen_values = true)]
    pub from: Option<Vec3>,
    /// The point looked at, seen at the image centre, `X,Y,Z` (overrides `at`).
    #[arg(long, value_name = "X,Y,Z", value_parser = point, allow_hyphen_values = true)]
    pub at: Option<Vec3>,
    /// The up vector, `X,Y,Z` (overrides `up`).
    #[arg(long, value_name = "X,Y,Z", value_parser = point, allow_hyphen_values = true)]
    pub up: Option<Vec3>,
    /// The vertical field of view in degrees, edge to edge (overrides `angle`).
    #[arg(long, value_name = "DEG", value_parser = number, allow_hyphen_values = true)]
    pub fov: Option<f32>,
}

impl CameraArgs {
    /// Puts the overrides into `camera` and checks the camera they make, with its own message (the
    /// file's camera was checked when it was read: without overrides there is nothing new to check).
    pub fn apply(&self, camera: &mut Camera) -> whitted::Result<()> {
        if *self == CameraArgs::default() {
            return Ok(());
        }
        camera.from = self.from.unwrap_or(camera.from);
        camera.at = self.at.unwrap_or(camera.at);
        camera.up = self.up.unwrap_or(camera.up);
        camera.fov_y = self.fov.unwrap_or(camera.fov_y);
        camera
            .validate()
            .map_err(|e| whitted::Error::msg(format!("the camera of --from/--at/--up/--fov: {e}")))
    }
}

/// A point or vector written `X,Y,Z`, each a finite number.
pub fn point(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let [x, y, z] = parts[..] else {
        return Err(format!(
            "expected three numbers separated by commas, X,Y,Z (such as 0,1.5,-4), found \"{s}\""
        ));
    };
    Ok(Vec3::new(number(x.trim())?, number(y.trim())?, number(z.trim())?))
}

/// The options of the SPD test procedure ([`spd::options`]: 513 x 513 corner rays, spp 0, 4 bounces)
/// in place of `options` when `spd`, keeping what the procedure leaves open (kernel, seed, roughness).
pub fn spd_frame(spd: bool, options: Options, scene: &Scene) -> Options {
    if !spd {
        return options;
    }
    Options {
        kernel: options.kernel,
        seed: options.seed,
        roughness: options.roughness,
        ..spd::options(scene)
    }
}

/// The image of a frame rendered with `options`: an SPD frame's corners averaged into its pixels.
pub fn image(options: &Options, film: Film) -> Film {
    if options.spd {
        spd::corners_to_pixels(&film)
    } else {
        film
    }
}

/// Refuses, with `--spd`, the first of the options `given` (its name, and whether it was given): the
/// procedure fixes the frame they would change, and the Readme's counts hold for that frame only.
pub fn spd_refuses(spd: bool, given: &[(&str, bool)]) -> whitted::Result<()> {
    match given.iter().find(|(_, g)| *g) {
        Some((option, _)) if spd => Err(whitted::Error::msg(format!(
            "--spd renders the SPD test procedure's frame (512x512 pixels from 513x513 corner rays, spp 0, \
             {} bounces, one pass) and cannot be combined with {option}",
            spd::MAX_DEPTH
        ))),
        _ => Ok(()),
    }
}

/// `render`'s options that `--spd` refuses (see [`spd_refuses`]).
pub fn render_spd_refuses(args: &RenderArgs) -> whitted::Result<()> {
    let partial = args.partial
        || args
            .output
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("partial"));
    spd_refuses(
        args.report.spd,
        &[
            ("--spp", args.spp.is_some()),
            ("--passes", args.passes > 1),
            ("--tiles", args.tiles.is_some()),
            ("--passes-range", args.passes_range.is_some()),
            ("--width", args.frame.width.is_some()),
            ("--height", args.frame.height.is_some()),
            ("--max-depth", args.max_depth.is_some()),
            ("a .partial output", partial),
        ],
    )
}

/// The BVH2 builder, as a command-line value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum BuildKind {
    /// Binned surface area heuristic.
    Sah,
    /// Centroid midpoint of the longest axis.
    Midpoint,
}

/// The library's build options from the command line's.
pub fn build_options(build: BuildKind, bins: usize) -> whitted::accel::BuildOptions {
    let builder = match build {
        BuildKind::Sah => whitted::accel::bvh2::Builder::Sah { bins },
        BuildKind::Midpoint => whitted::accel::bvh2::Builder::Midpoint,
    };
    whitted::accel::BuildOptions { builder, bins }
}

/// Loads the named scene, or the built-in one.
pub fn load_scene(path: Option<&Path>) -> whitted::Result<Scene> {
    match path {
        Some(p) => scene::load(p),
        None => scene::p3f::parse(Path::new("(default scene)"), Box::new(DEFAULT_SCENE.as_bytes())),
    }
}

/// The resolution after `--width`/`--height`: one given alone keeps the file's aspect ratio. It is
/// checked with the rest of the [`whitted::render::Options`] it goes into.
pub fn resolution(scene: &Scene, width: Option<u32>, height: Option<u32>) -> (u32, u32) {
    let (fw, fh) = (scene.camera.width as u64, scene.camera.height as u64);
    match (width, height) {
        (Some(w), Some(h)) => (w, h),
        (Some(w), None) => (w, ((w as u64 * fh).div_ceil(fw)).min(u32::MAX as u64) as u32),
        (None, Some(h)) => (((h as u64 * fw).div_ceil(fh)).min(u32::MAX as u64) as u32, h),
        (None, None) => (fw as u32, fh as u32),
    }
}

/// A rayon pool of `threads` workers (all cores when `None`; clap bounds the count).
pub fn thread_pool(threads: Option<usize>) -> whitted::Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| whitted::Error::msg(format!("cannot start the worker threads: {e}")))
}

/// A finite number.
pub fn number(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .parse()
        .map_err(|_| format!("expected a number, found \"{s}\""))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("expected a finite number, found {s}"))
    }
}

/// A finite number of at least 0.
pub fn non_negative(s: &str) -> Result<f32, String> {
    let v = number(s)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("expected a number of at least 0, found {s}"))
    }
}

/// A finite number above 0.
pub fn positive(s: &str) -> Result<f32, String> {
    let v = number(s)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("expected a number above 0, found {s}"))
    }
}

/// Two numbers `a` and `b` written `a{sep}b`; `expected` says what the whole should look like.
fn u32_pair(s: &str, sep: &str, expected: &str) -> Result<(u32, u32), String> {
    let bad = || format!("expected {expected}; found \"{s}\"");
    let (a, b) = s.split_once(sep).ok_or_else(bad)?;
    Ok((
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    ))
}

/// `K/N` with K < N.
pub fn part_of(s: &str) -> Result<(u32, u32), String> {
    let (k, n) = u32_pair(s, "/", "K/N, part K (from 0) of N parts, such as 3/8")?;
    if n == 0 || k >= n {
        return Err(format!("part {k}/{n} does not exist: K counts from 0 to N-1"));
    }
    Ok((k, n))
}

/// `A..B` with A < B.
pub fn pass_range(s: &str) -> Result<(u32, u32), String> {
    let (a, b) = u32_pair(s, "..", "A..B, passes A to B-1 (from 0), such as 0..16")?;
    if a >= b {
        return Err(format!("the pass range {a}..{b} is empty"));
    }
    Ok((a, b))
}

/// Prints `warnings` on stderr, one a line.
pub fn warn(warnings: &[String]) {
    for w in warnings {
        eprintln!("whitted: warning: {w}");
    }
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::*;
    use crate::cli::plan::Plan;

    use crate::cli::render::Render;

    /// The plan of `whitted render` with `words` for the built-in scene (or the scene they name), and
    /// that scene after the plan's overrides.
    fn plan<'a>(words: impl IntoIterator<Item = &'a str>) -> (whitted::Result<Plan>, Scene) {
        let render =
            Render::try_parse_from(std::iter::once("render").chain(words)).expect("arguments clap accepts");
        let mut scene = load_scene(render.args.scene.as_deref()).expect("the scene");
        (Plan::new(&render.args, &mut scene), scene)
    }

    fn error(args: &str) -> String {
        match plan(args.split_whitespace()).0 {
            Ok(_) => panic!("{args}: accepted"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn points_are_three_finite_numbers_separated_by_commas() {
        assert_eq!(point("1,2,3"), Ok(Vec3::new(1.0, 2.0, 3.0)));
        assert_eq!(point(" -1.5 , 0,2e3 "), Ok(Vec3::new(-1.5, 0.0, 2000.0)));
        let three = "expected three numbers separated by commas, X,Y,Z (such as 0,1.5,-4)";
        assert_eq!(point("1,2"), Err(format!("{three}, found \"1,2\"")));
        assert_eq!(point("1 2 3"), Err(format!("{three}, found \"1 2 3\"")));
        assert_eq!(point("1,2,3,4"), Err(format!("{three}, found \"1,2,3,4\"")));
        assert_eq!(point("1,x,3"), Err("expected a number, found \"x\"".to_string()));
        assert_eq!(
            point("1,inf,3"),
            Err("expected a finite number, found inf".to_string())
        );
    }

    #[test]
    fn camera_overrides_replace_the_files_and_are_checked_by_the_camera() {
        let (p, scene) = plan("--from -1,2,3.5 --at 0,1,0 --up 0,0,1 --fov 30".split_whitespace());
        p.unwrap();
        let c = scene.camera;
        assert_eq!(
            (c.from, c.at, c.up, c.fov_y),
            (Vec3::new(-1.0, 2.0, 3.5), Vec3::Y, Vec3::Z, 30.0)
        );
        // What is not overridden stays the file's (scenes/default.p3f: from 0 1.6 5.5, angle 40).
        let (_, scene) = plan(["--at", "1,1,1"]);
        assert_eq!(
            (scene.camera.from, scene.camera.fov_y),
            (Vec3::new(0.0, 1.6, 5.5), 40.0)
        );
        let camera = "the camera of --from/--at/--up/--fov";
        assert_eq!(
            error("--from 1,2,3 --at 1,2,3"),
            format!("{camera}: \"from\" and \"at\" are the same point (1 2 3)")
        );
        assert_eq!(
            error("--up 0,0,0"),
            format!("{camera}: \"up\" is the zero vector")
        );
        assert_eq!(
            error("--fov 180"),
            format!("{camera}: expected an angle between 0 and 180 degrees, found 180")
        );
        assert!(Render::try_parse_from(["render", "--from", "1,2"]).is_err());
        assert!(Render::try_parse_from(["render", "--fov", "wide"]).is_err());
    }

    #[test]
    fn spd_renders_the_procedures_frame_and_refuses_what_would_change_it() {
        let (p, _) = plan([
            "scenes/spd/tetra_default.nff",
            "--spd",
            "--kernel",
            "single",
            "--seed",
            "3",
        ]);
        let o = p.unwrap().options;
        let frame = (o.width, o.height, o.spp, o.max_depth, o.spd, o.kernel, o.seed);
        assert_eq!(frame, (513, 513, 0, 4, true, Kernel::Single, 3));
        let spd = "--spd renders the SPD test procedure's frame (512x512 pixels from 513x513 corner rays, \
                   spp 0, 4 bounces, one pass) and cannot be combined with";
        for (args, option) in [
            ("--spd --spp 0", "--spp"),
            ("--spd --passes 4", "--passes"),
            ("--spd --tiles 0/2 --partial", "--tiles"),
            ("--spd --passes 4 --passes-range 0..2", "--passes"),
            ("--spd --width 512", "--width"),
            ("--spd --height 512", "--height"),
            ("--spd --max-depth 4", "--max-depth"),
            ("--spd --partial", "a .partial output"),
            ("--spd -o frame.partial", "a .partial output"),
        ] {
            assert_eq!(error(args), format!("{spd} {option}"), "{args}");
        }
        // Without --spd the same options are the plan's.
        assert_eq!(plan(["--max-depth", "3"]).0.unwrap().options.max_depth, 3);
        assert_eq!(plan([]).0.unwrap().options.max_depth, DEFAULT_DEPTH);
    }

    /// The command the viewer prints with a screenshot, run through `render`'s parser and plan, gives
    /// the view's camera, size, depth and passes.
    #[cfg(feature = "view")]
    #[test]
    fn the_viewers_render_command_gives_the_views_camera() {
        use whitted::accel::AccelKind;
        use whitted::view::reproduce::render_command;
        use whitted::view::state::{Input, Key, Settings, ViewState};

        let path = Path::new("scenes/balls_low.p3f");
        let scene = load_scene(Some(path)).unwrap();
        let options = Options {
            width: 96,
            height: 64,
            ..Options::new(&scene)
        };
        let mut view = ViewState::new(&scene, options, Settings::new(AccelKind::Bvh4, Kernel::Packet, 6));
        view.input(Input::Drag { dx: 31.0, dy: 9.0 });
        view.input(Input::Scroll(-2.0));
        for key in [Key::LessDepth, Key::DepthOfField] {
            view.input(Input::Key { key, pressed: true });
        }
        let job = view.job();
        for passes in [1, 5] {
            let command = render_command(Some(path), &view.file_camera(), &job, passes, false);
            let words = command.strip_prefix("whitted render ").expect("a render command");
            let (p, scene) = plan(words.split_whitespace());
            let p = p.unwrap_or_else(|e| panic!("{command}: {e}"));
            let o = p.options;
            let camera = Camera {
                width: o.width,
                height: o.height,
                ..scene.camera
            };
            assert_eq!(camera, job.camera, "{command}");
            assert_eq!((o.max_depth, p.total_passes), (5, passes), "{command}");
            assert_eq!(o.spp, 1, "one jittered sample per pass: {command}");
        }
    }
}
