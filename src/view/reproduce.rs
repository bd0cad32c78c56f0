//! What the viewer prints beside a saved screenshot, so that a view found by moving around can be kept:
//! the camera as a `v` block to paste into a scene, and the `whitted render` command that renders the
//! same image from the command line. Numbers are written in their shortest form that reads back as the
//! same `f32`, so both give back the camera bit for bit.

use std::fmt::Write;
use std::path::Path;

use glam::Vec3;

use super::state::Job;
use crate::scene::Camera;

/// The bounce limit `whitted render` takes when `--max-depth` is not given.
const RENDER_DEPTH: u32 = 6;

/// `camera` as a p3f `v` block (NFF's lines, then `aperture` and `focal` when it has a lens).
pub fn view_block(camera: &Camera) -> String {
    let c = camera;
    let mut out = format!(
        "v\nfrom {}\nat {}\nup {}\nangle {}\nhither {}\nresolution {} {}\n",
        spaced(c.from),
        spaced(c.at),
        spaced(c.up),
        c.fov_y,
        c.hither,
        c.width,
        c.height
    );
    if c.aperture > 0.0 {
        let _ = writeln!(out, "aperture {}\nfocal {}", c.aperture, c.focal);
    }
    out
}

/// The `whitted render` command that renders `job`'s image after `passes` passes: `scene` as given to
/// the viewer (`None`: the built-in scene), `file` the scene file's camera (its lens is what `render`
/// uses unless told otherwise). A still camera's passes are `render --passes`'s, bit for bit; one pass
/// is one jittered sample per pixel, `--spp 1`. The accelerator and kernel change no pixel and are left
/// out; hard shadows (H) have no `render` option, which a note says.
pub fn render_command(scene: Option<&Path>, file: &Camera, job: &Job, passes: u32, srgb: bool) -> String {
    let c = &job.camera;
    let mut out = "whitted render".to_string();
    if let Some(scene) = scene {
        let _ = write!(out, " {}", shell_word(&scene.to_string_lossy()));
    }
    let _ = write!(
        out,
        " --from {} --at {} --up {} --fov {} --width {} --height {}",
        commas(c.from),
        commas(c.at),
        commas(c.up),
        c.fov_y,
        c.width,
        c.height
    );
    if job.options.max_depth != RENDER_DEPTH {
        let _ = write!(out, " --max-depth {}", job.options.max_depth);
    }
    if passes == 1 {
        out += " --spp 1";
    } else {
        let _ = write!(out, " --passes {passes}");
    }
    if c.aperture != file.aperture {
        let _ = write!(out, " --aperture {}", c.aperture);
    }
    if srgb {
        out += " --srgb";
    }
    if !job.soft_shadows {
        out += "\n(the view has hard shadows, which render has no option for: it draws soft ones)";
    }
    out
}

/// `s` as one word of a POSIX shell: as it is when it has no character the shell treats specially,
/// else in single quotes (a quote in it written `'\''`).
pub fn shell_word(s: &str) -> String {
    let plain = |ch: char| ch.is_ascii_alphanumeric() || "_-+=.,/:@%".contains(ch);
    if !s.is_empty() && s.chars().all(plain) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

/// `x y z`, as the `v` block writes a point.
fn spaced(v: Vec3) -> String {
    format!("{} {} {}", v.x, v.y, v.z)
}

/// `x,y,z`, as `--from`, `--at` and `--up` take a point.
fn commas(v: Vec3) -> String {
    format!("{},{},{}", v.x, v.y, v.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::AccelKind;
    use crate::render::{DEFAULT_DEPTH, Kernel, Options};
    use crate::scene::Scene;
    use crate::view::state::{Input, Key, Settings, ViewState};

    /// A view of a one-sphere scene moved off the file's camera, with numbers that have no short
    /// decimal form.
    fn moved() -> (Camera, ViewState) {
        let mut camera = Camera::new(Vec3::new(0.1, 0.2, 5.0), Vec3::ZERO, Vec3::Y, 45.0, 64, 48);
        camera.hither = 0.01;
        let scene = Scene::new(camera);
        let settings = Settings::new(AccelKind::Bvh4, Kernel::Packet, DEFAULT_DEPTH);
        let mut view = ViewState::new(&scene, Options::new(&scene), settings);
        view.input(Input::Drag { dx: 13.0, dy: -7.0 });
        view.input(Input::Scroll(1.0));
        (camera, view)
    }

    #[test]
    fn the_view_block_reads_back_as_the_same_camera() {
        let (_, view) = moved();
        let mut camera = view.job().camera;
        for aperture in [0.0, 2.5] {
            camera.aperture = aperture;
            camera.focal = 0.75;
            let block = view_block(&camera);
            let path = Path::new("view.p3f");
            let scene = crate::scene::p3f::parse(path, Box::new(std::io::Cursor::new(block.clone())))
                .unwrap_or_else(|e| panic!("{e}\n{block}"));
            let mut want = camera;
            if aperture == 0.0 {
                // A pinhole's focal ratio is not written: the parser's default.
                want.focal = 1.0;
            }
            assert_eq!(scene.camera, want, "{block}");
        }
    }

    #[test]
    fn the_command_writes_each_setting_the_image_depends_on() {
        let (file, mut view) = moved();
        let job = view.job();
        let c = job.camera;
        let points = format!(
            "--from {},{},{} --at {},{},{} --up 0,1,0 --fov {}",
            c.from.x, c.from.y, c.from.z, c.at.x, c.at.y, c.at.z, c.fov_y
        );
        assert_eq!(
            render_command(Some(Path::new("scenes/a b.p3f")), &file, &job, 1, false),
            format!("whitted render 'scenes/a b.p3f' {points} --width 64 --height 48 --spp 1")
        );
        view.input(Input::Key {
            key: Key::MoreDepth,
            pressed: true,
        });
        let deeper = view.job();
        let mut lens = file;
        lens.aperture = 3.0;
        assert_eq!(
            render_command(None, &lens, &deeper, 12, true),
            format!(
                "whitted render {points} --width 64 --height 48 --max-depth 7 --passes 12 --aperture 0 --srgb"
            )
        );
        let hard = Job {
            soft_shadows: false,
            ..job
        };
        let command = render_command(None, &file, &hard, 1, false);
        assert!(
            command.ends_with(
                "\n(the view has hard shadows, which render has no option for: it draws soft ones)"
            )
        );
    }

    #[test]
    fn shell_words_are_quoted_only_when_needed() {
        assert_eq!(shell_word("scenes/dragon.p3f"), "scenes/dragon.p3f");
        assert_eq!(shell_word("my scene.p3f"), "'my scene.p3f'");
        assert_eq!(shell_word("it's.p3f"), r"'it'\''s.p3f'");
        assert_eq!(shell_word("$HOME/a.nff"), "'$HOME/a.nff'");
        assert_eq!(shell_word(""), "''");
    }
}
