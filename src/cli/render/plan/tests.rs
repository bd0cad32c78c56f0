use clap::Parser;
use glam::Vec3;
use whitted::render::Kernel;

use super::super::args::Render;
use super::*;
use crate::cli::setup::load_scene;

/// The plan of `whitted render ARGS` for the scene they name (the built-in one if none: 640x480,
/// spp 0), and that scene after the plan's overrides.
fn plan_and_scene(args: &str) -> (whitted::Result<Plan>, Scene) {
    let words = std::iter::once("render").chain(args.split_whitespace());
    let render = Render::try_parse_from(words).expect("arguments clap accepts");
    let mut scene = load_scene(render.args.scene.as_deref(), None).expect("the scene");
    (Plan::new(&render.args, &mut scene), scene)
}

fn plan(args: &str) -> Plan {
    match plan_and_scene(args).0 {
        Ok(plan) => plan,
        Err(e) => panic!("{args}: {e}"),
    }
}

fn error(args: &str) -> String {
    match plan_and_scene(args).0 {
        Ok(_) => panic!("{args}: accepted"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn options_take_the_arguments_and_one_side_keeps_the_aspect_ratio() {
    let p = plan("--width 100 --max-depth 3 --kernel single --spp 4 --seed 9 --roughness 0.3");
    let expected = Options {
        width: 100,
        height: 75,
        max_depth: 3,
        kernel: Kernel::Single,
        spp: 4,
        seed: 9,
        roughness: 0.3,
        spd: false,
        count_steps: false,
    };
    assert_eq!(p.options, expected);
    assert_eq!((plan("--height 30").options.width), 40);
    assert_eq!(plan("").options, Options::new(&load_scene(None, None).unwrap()));
}

/// `--width`, `--height`, `--spp` and `--fov` are bounded where they are parsed (usage errors); what
/// the plan still refuses is what they make with the scene, such as the other side of its aspect ratio.
#[test]
fn refuses_options_out_of_their_ranges() {
    for (option, value, expected) in [
        ("--width", "70000", "70000 is not in 1..=65536"),
        ("--height", "0", "0 is not in 1..=65536"),
        ("--spp", "4294967295", "4294967295 is not in 0..=65536"),
        ("--fov", "0", "found 0"),
        ("--fov", "180", "found 180"),
    ] {
        let parsed = Render::try_parse_from(["render", option, value]);
        let e = parsed.err().expect("refused").to_string();
        assert!(e.contains(expected), "{option} {value}: {e}");
    }
    assert_eq!(plan("--width 65536 --height 1").options.width, 65536);
    assert_eq!(plan("--spp 65536").options.spp, 65536);
    // 640x480: a height of 65536 asks for a width of 87382.
    assert_eq!(
        error("--height 65536"),
        "resolution must be between 1 and 65536 on each side, found 87382x65536"
    );
}

/// `--threads` is bounded where it is parsed: a count rayon could not start (100000 threads panic
/// in the standard library before the pool reports its error) is a usage error.
#[test]
fn threads_are_parsed_within_1_to_1024() {
    for (value, expected) in [
        ("0", "0 is not in 1..=1024"),
        ("100000", "100000 is not in 1..=1024"),
    ] {
        let parsed = Render::try_parse_from(["render", "--threads", value]);
        let e = parsed.err().expect("refused").to_string();
        assert!(e.contains(expected), "{e}");
    }
    let threads =
        |value| Render::try_parse_from(["render", "--threads", value]).map(|r| r.args.frame.threads);
    assert_eq!(threads("3").expect("accepted"), Some(3));
    assert_eq!(threads("1024").expect("accepted"), Some(1024));
}

/// `--max-depth` too: past 64 bounces is a usage error (the library refuses it as well,
/// `Options::validate`).
#[test]
fn max_depth_is_parsed_within_0_to_64() {
    for value in ["65", "3000"] {
        let parsed = Render::try_parse_from(["render", "--max-depth", value]);
        let e = parsed.err().expect("refused").to_string();
        assert!(e.contains(&format!("{value} is not in 0..=64")), "{e}");
    }
    assert_eq!(plan("--max-depth 64").options.max_depth, 64);
    assert_eq!(plan("--max-depth 0").options.max_depth, 0);
}

#[test]
fn every_and_progressive_out_need_passes() {
    for args in ["--every 2", "--progressive-out snaps", "--every 2 --tiles 0/2"] {
        assert_eq!(
            error(args),
            "--every and --progressive-out need --passes 2 or more",
            "{args}"
        );
    }
}

#[test]
fn tiles_and_passes_range_need_a_partial_output() {
    for args in ["--tiles 0/2", "--passes 4 --passes-range 0..2 -o part.png"] {
        assert_eq!(
            error(args),
            "--tiles and --passes-range render part of a frame: write it to a .partial file (-o part.partial) and combine the parts with `whitted merge`",
            "{args}"
        );
    }
    for args in ["--tiles 0/2 --partial", "--tiles 0/2 -o part.PARTIAL"] {
        assert!(matches!(plan(args).target, Target::Partial { .. }), "{args}");
    }
}

#[test]
fn resume_applies_to_images_and_partial_files() {
    assert!(plan("--resume").resume);
    assert!(plan("--resume --passes 3 -o out.exr").resume);
    assert!(plan("--resume --tiles 0/2 --partial").resume);
    assert!(!plan("").resume);
}

#[test]
fn the_tiles_of_a_part_or_of_the_whole_frame() {
    // 640x480: 40 x 30 tiles of 16 pixels.
    assert_eq!(plan("").tile_indices(), (0..1200).collect::<Vec<u32>>());
    assert_eq!(
        plan("--tiles 1/4 --partial").tile_indices(),
        tiles::part(640, 480, 1, 4)
    );
    assert_eq!(plan("--tiles 1/4 --partial").tile_indices().len(), 300);
}

#[test]
fn progressive_out_refuses_a_partial_output() {
    assert_eq!(
        error("--passes 2 --progressive-out snaps -o part.partial"),
        "--progressive-out writes images; a .partial render cannot keep snapshots"
    );
}

#[test]
fn passes_range_lies_within_passes() {
    assert_eq!(
        error("--passes 4 --passes-range 2..5 --partial"),
        "--passes-range 2..5 goes beyond the render's 4 passes (set --passes to the whole render's count)"
    );
    let p = plan("--passes 4 --passes-range 2..4 --partial");
    assert_eq!((p.pass_range.clone(), p.passes()), (Some(2..4), 2..4));
    let p = plan("--passes 4");
    assert_eq!((p.pass_range.clone(), p.passes()), (None, 0..4));
}

#[test]
fn passes_take_one_sample_each_and_warn_of_more() {
    let p = plan("--passes 3 --spp 16");
    assert_eq!(p.options.spp, 1);
    assert_eq!(
        p.warnings,
        ["progressive passes take one jittered sample per pixel each; spp 16 ignored"]
    );
    for (args, spp) in [("--passes 3 --spp 1", 1), ("--passes 3", 1), ("--spp 16", 16)] {
        let p = plan(args);
        assert_eq!((p.options.spp, p.warnings.len()), (spp, 0), "{args}");
    }
}

#[test]
fn writes_every_k_passes_or_every_snapshot_or_at_the_end() {
    assert_eq!(plan("--passes 4 --every 2").every, 2);
    assert_eq!(plan("--passes 4 --every 2 --progressive-out snaps").every, 2);
    assert_eq!(plan("--passes 4 --progressive-out snaps").every, 1);
    assert_eq!(plan("--passes 4").every, u32::MAX);
}

#[test]
fn an_image_output_keeps_srgb_and_the_snapshot_directory() {
    let p = plan("-o out.exr --srgb --passes 2 --progressive-out snaps");
    assert_eq!(p.output, PathBuf::from("out.exr"));
    let snapshots = Some(PathBuf::from("snaps"));
    assert_eq!(
        p.target,
        Target::Image {
            srgb: true,
            snapshots
        }
    );
}

#[test]
fn a_partial_output_records_the_settings_after_the_lens_overrides() {
    let args = "--partial --aperture 2 --focal 0.5 --passes 4 --passes-range 1..3 --tiles 1/4 --resume";
    let (p, scene) = plan_and_scene(args);
    let p = p.unwrap();
    assert_eq!((scene.camera.aperture, scene.camera.focal), (2.0, 0.5));
    let settings = PartSettings::new(&scene, &p.options, 4);
    assert_eq!(
        (settings.aperture, settings.focal, settings.passes),
        (2.0, 0.5, 4)
    );
    assert_eq!(p.target, Target::Partial { settings });
    assert!(p.resume);
    let (w, h) = (640, 480);
    assert_eq!(p.tiles, Some((1, 4)));
    assert_eq!(p.accumulator().tile_indices(), tiles::part(w, h, 1, 4));
}
#[test]
fn camera_overrides_replace_the_files_and_are_checked_by_the_camera() {
    let (p, scene) = plan_and_scene("--from -1,2,3.5 --at 0,1,0 --up 0,0,1 --fov 30");
    p.unwrap();
    let c = scene.camera;
    assert_eq!(
        (c.from, c.at, c.up, c.fov_y),
        (Vec3::new(-1.0, 2.0, 3.5), Vec3::Y, Vec3::Z, 30.0)
    );
    // What is not overridden stays the file's (scenes/default.p3f: from 0 1.6 5.5, angle 40).
    let (_, scene) = plan_and_scene("--at 1,1,1");
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
    assert!(Render::try_parse_from(["render", "--from", "1,2"]).is_err());
    assert!(Render::try_parse_from(["render", "--fov", "wide"]).is_err());
}

#[test]
fn spd_renders_the_procedures_frame_and_refuses_what_would_change_it() {
    let p = plan("scenes/spd/tetra_default.nff --spd --kernel single --seed 3");
    let o = p.options;
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
    assert_eq!(plan("--max-depth 3").options.max_depth, 3);
    assert_eq!(plan("").options.max_depth, DEFAULT_DEPTH);
}

/// The command the viewer prints with a screenshot, run through `render`'s parser and plan, gives
/// the view's camera, size, depth and passes.
#[cfg(feature = "view")]
#[test]
fn the_viewers_render_command_gives_the_views_camera() {
    use std::path::Path;

    use whitted::accel::AccelKind;
    use whitted::scene::Camera;
    use whitted::view::reproduce::render_command;
    use whitted::view::state::{Input, Key, Settings, ViewState};

    let path = Path::new("scenes/balls_low.p3f");
    let scene = load_scene(Some(path), None).unwrap();
    let options = Options {
        width: 96,
        height: 64,
        ..Options::new(&scene)
    };
    let mut view = ViewState::new(
        &scene,
        options,
        Settings::new(AccelKind::Bvh4, Kernel::Packet, whitted::render::DEFAULT_DEPTH),
    );
    view.input(Input::Drag { dx: 31.0, dy: 9.0 });
    view.input(Input::Scroll(-2.0));
    for key in [Key::LessDepth, Key::DepthOfField] {
        view.input(Input::Key { key, pressed: true });
    }
    let job = view.job();
    for passes in [1, 5] {
        let command = render_command(Some(path), &view.file_camera(), &job, passes, false);
        let words = command.strip_prefix("whitted render ").expect("a render command");
        let (p, scene) = plan_and_scene(words);
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
