use super::*;
use crate::scene::Material;

/// A sphere of radius `r` at the origin, seen from 5 r away along +z, 200 x 100, through a lens.
fn scene(r: f32) -> Scene {
    let mut camera = Camera::new(Vec3::new(0.0, 0.0, 5.0 * r), Vec3::ZERO, Vec3::Y, 45.0, 200, 100);
    camera.aperture = 2.0;
    let mut scene = Scene::new(camera);
    let m = scene.add_material(Material::default());
    scene.add_sphere(Vec3::ZERO, r, m);
    scene
}

fn state(r: f32) -> ViewState {
    let scene = scene(r);
    let settings = Settings::new(AccelKind::Bvh4, Kernel::Packet, 6);
    ViewState::new(&scene, Options::new(&scene), settings)
}

fn key(key: Key, pressed: bool) -> Input {
    Input::Key { key, pressed }
}

/// Holds `k` for `seconds`, ticking at 100 Hz, and lets go.
fn hold(s: &mut ViewState, k: Key, seconds: f32) {
    s.input(key(k, true));
    for _ in 0..(seconds * 100.0).round() as u32 {
        s.tick(0.01);
    }
    s.input(key(k, false));
}

/// Ticks until the camera stands still.
fn settle(s: &mut ViewState) {
    for _ in 0..(STILL_AFTER / 0.05).ceil() as u32 {
        s.tick(0.05);
    }
    assert!(!s.moving());
}

#[test]
fn starts_still_with_the_file_camera_and_renders_one_jittered_sample_per_pass() {
    let scene = scene(1.0);
    let s = state(1.0);
    assert!(!s.moving() && !s.animating());
    let job = s.job();
    assert_eq!(job.camera, scene.camera, "bit for bit: the image is render's");
    assert_eq!(
        (job.options.width, job.options.height, job.options.spp),
        (200, 100, 1)
    );
    assert_eq!((job.scale, job.moving, job.refines()), (1, false, true));
}

#[test]
fn standing_still_accumulates_and_moving_resets() {
    let mut s = state(1.0);
    let mut acc = Accumulator::default();
    for pass in 1..=3 {
        assert_eq!(acc.next(&s.job()), Some(pass));
        acc.done(pass);
    }
    assert_eq!(acc.passes(), 3);
    // A step forward: a new image, one pass, no refinement while the camera moves.
    hold(&mut s, Key::Forward, 0.05);
    assert!(s.moving());
    let job = s.job();
    assert!(job.moving && !job.refines());
    assert_eq!(acc.next(&job), Some(1));
    acc.done(1);
    assert_eq!(acc.next(&job), None, "one pass per moving frame");
    // At rest, passes accumulate again from where the moving frame left them (same image).
    settle(&mut s);
    assert!(!s.animating());
    assert_eq!(acc.next(&s.job()), Some(2));
    acc.done(2);
    assert_eq!(acc.next(&s.job()), Some(3));
}

#[test]
fn setting_changes_reset_but_progressive_pauses() {
    let mut s = state(1.0);
    let mut acc = Accumulator::default();
    acc.next(&s.job());
    acc.done(1);
    acc.next(&s.job());
    acc.done(2);
    s.input(key(Key::Progressive, true));
    assert_eq!(acc.next(&s.job()), None, "paused, the image kept");
    s.input(key(Key::Progressive, true));
    assert_eq!(acc.next(&s.job()), Some(3), "resumed where it was");
    let toggles = [
        Key::Accel(AccelKind::Grid),
        Key::Kernel,
        Key::SoftShadows,
        Key::DepthOfField,
        Key::LessDepth,
    ];
    for k in toggles {
        let old = s.job();
        s.input(key(k, true));
        s.input(key(k, false));
        assert!(old.changes_settings(&s.job()), "{k:?}");
        assert_eq!(acc.next(&s.job()), Some(1), "{k:?} resets");
    }
    assert_eq!(s.settings().max_depth, 5);
    assert!(!s.settings().soft_shadows && !s.settings().depth_of_field);
    assert_eq!(s.job().camera.aperture, 0.0);
    // A camera move alone is not a change of settings; a resize is.
    let still = s.job();
    hold(&mut s, Key::TurnLeft, 0.1);
    let moved = s.job();
    assert!(moved.moving && moved.camera.at != still.camera.at);
    assert!(!still.changes_settings(&moved));
    s.input(Input::Resize {
        width: 300,
        height: 100,
    });
    assert!(moved.changes_settings(&s.job()));
}

#[test]
fn slow_moving_frames_lower_the_resolution_and_rest_restores_it() {
    let mut s = state(1.0);
    s.input(key(Key::Forward, true));
    s.tick(0.01);
    let job = s.job();
    assert_eq!((job.scale, job.options.width), (1, 200));
    s.frame_rendered(&job, 0.08);
    let job = s.job();
    assert_eq!((job.scale, job.camera.width, job.camera.height), (2, 100, 50));
    // A late frame of the old resolution does not lower it twice.
    s.frame_rendered(&Job { scale: 1, ..job }, 0.08);
    assert_eq!(s.scale(), 2);
    s.frame_rendered(&job, 0.06);
    assert_eq!(s.job().scale, 4);
    s.frame_rendered(&s.job(), 1.0);
    assert_eq!(s.job().scale, MAX_SCALE, "a quarter at most");
    // Fast enough at a quarter for a half: back to a half.
    s.frame_rendered(&s.job(), 0.005);
    assert_eq!(s.job().scale, 2);
    // Frames of a still camera teach nothing.
    s.input(key(Key::Forward, false));
    settle(&mut s);
    let job = s.job();
    assert_eq!((job.scale, job.options.width, job.options.height), (1, 200, 100));
    s.frame_rendered(&job, 10.0);
    assert_eq!(s.scale(), 2);
    // Moving again resumes at the resolution learnt.
    hold(&mut s, Key::Up, 0.02);
    assert_eq!(s.job().scale, 2);
}

#[test]
fn reset_returns_to_the_file_camera() {
    let scene = scene(1.0);
    let mut s = state(1.0);
    hold(&mut s, Key::Forward, 0.3);
    hold(&mut s, Key::TurnUp, 0.3);
    s.input(Input::Drag { dx: 40.0, dy: -10.0 });
    s.input(Input::Scroll(3.0));
    assert_ne!(s.camera(), scene.camera);
    s.input(key(Key::Reset, true));
    assert_eq!(s.camera(), scene.camera);
    assert_eq!(s.job().camera.fov_y, 45.0);
}

#[test]
fn movement_is_per_second_and_scales_with_the_scene() {
    let travelled = |r: f32, hz: u32| {
        let mut s = state(r);
        s.input(key(Key::Forward, true));
        for _ in 0..hz {
            s.tick(1.0 / hz as f32);
        }
        5.0 * r - s.camera().from.z
    };
    let small = travelled(1.0, 50);
    let large = travelled(10.0, 50);
    assert!((large / small - 10.0).abs() < 1e-3, "{small} vs {large}");
    // Twice the tick rate, the same distance a second.
    let fast = travelled(1.0, 100);
    assert!((fast - small).abs() < 1e-4, "{fast} vs {small}");
    assert!((small - MOVE_RATE * scene_size(&scene(1.0))).abs() < 1e-4);
    // The look-at point travels along: the direction and lens distance stay.
    let mut s = state(2.0);
    hold(&mut s, Key::Right, 0.5);
    let c = s.camera();
    assert!((c.at - c.from - Vec3::new(0.0, 0.0, -10.0)).length() < 1e-4);
    assert!(c.from.x > 0.0 && c.from.y.abs() < 1e-6);
}

#[test]
fn field_of_view_is_clamped() {
    let mut s = state(1.0);
    s.input(Input::Scroll(1.0));
    assert!((s.camera().fov_y - 45.0 / ZOOM_STEP).abs() < 1e-4);
    assert!(s.moving());
    s.input(Input::Scroll(1000.0));
    assert_eq!(s.camera().fov_y, FOV_RANGE.0);
    s.input(Input::Scroll(-1000.0));
    assert_eq!(s.camera().fov_y, FOV_RANGE.1);
}

#[test]
fn turning_keeps_off_the_up_vector_and_orbits_keep_the_distance() {
    let mut s = state(1.0);
    hold(&mut s, Key::TurnUp, 5.0);
    let c = s.camera();
    let dir = (c.at - c.from).normalize();
    assert!(dir.dot(Vec3::Y).asin().to_degrees() <= MAX_ELEVATION + 1e-3);
    assert!(c.validate().is_ok());
    // Left arrow turns left: from looking down -z toward -x.
    let mut s = state(1.0);
    hold(&mut s, Key::TurnLeft, 0.5);
    assert!(s.camera().at.x < 0.0);
    // Dragging right swings the camera left around the point looked at, at the same distance.
    let mut s = state(1.0);
    s.input(Input::Drag { dx: 100.0, dy: 0.0 });
    let c = s.camera();
    assert_eq!(c.at, Vec3::ZERO);
    assert!(c.from.x < 0.0 && ((c.from - c.at).length() - 5.0).abs() < 1e-4);
}

#[test]
fn held_keys_are_released_with_the_focus_and_the_depth_is_bounded() {
    let mut s = state(1.0);
    s.input(key(Key::Back, true));
    s.input(Input::ReleaseAll);
    let before = s.camera();
    s.tick(0.1);
    assert_eq!(s.camera(), before);
    for _ in 0..40 {
        s.input(key(Key::MoreDepth, true));
    }
    assert_eq!(s.settings().max_depth, MAX_VIEW_DEPTH);
    for _ in 0..40 {
        s.input(key(Key::LessDepth, true));
    }
    assert_eq!(s.settings().max_depth, 0);
    // A minimised window keeps the last size.
    s.input(Input::Resize { width: 0, height: 0 });
    assert_eq!((s.job().camera.width, s.job().camera.height), (200, 100));
}

#[test]
fn a_scene_of_planes_moves_at_the_camera_distance() {
    let camera = Camera::new(
        Vec3::new(0.0, 3.0, 0.0),
        Vec3::new(0.0, 0.0, -4.0),
        Vec3::Y,
        45.0,
        8,
        8,
    );
    let mut scene = Scene::new(camera);
    scene.add_plane(Vec3::ZERO, Vec3::Z, Vec3::X, 0);
    assert_eq!(scene_size(&scene), 5.0);
}
