//! Primary rays: the pinhole (and, with an aperture, thin-lens) camera of the `v` block.

use glam::Vec3;

use crate::geometry::ray::Ray;
use crate::scene::Camera;

/// A camera ready to generate rays: an orthonormal frame and the view-plane scale, computed once.
#[derive(Clone, Copy, Debug)]
pub struct RayCamera {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// Half-width and half-height of the image on the plane one unit in front of the eye.
    half: (f32, f32),
    width: u32,
    height: u32,
}

impl RayCamera {
    /// Sets up the frame: `forward` toward `at`, `right = forward × up`, `up` re-orthogonalised; `angle`
    /// is the vertical field of view edge to edge, and pixels are square.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let forward = (camera.at - camera.from).normalize();
        let right = forward.cross(camera.up).normalize();
        let up = right.cross(forward);
        let tan = (camera.fov_y.to_radians() * 0.5).tan();
        RayCamera {
            eye: camera.from,
            forward,
            right,
            up,
            half: (tan * width as f32 / height as f32, tan),
            width,
            height,
        }
    }

    /// The ray through the image point `(x, y)` in pixels (`(0.5, 0.5)` is the centre of the top-left
    /// pixel), with a unit direction.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.half.0;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.half.1;
        Ray::new(
            self.eye,
            (self.forward + sx * self.right + sy * self.up).normalize(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dragon workload's camera formula (`shared/bench/dragon-workload.md`), pixel by pixel.
    #[test]
    #[allow(clippy::excessive_precision)] // the workload document's figures, as written
    fn matches_the_workload_formula() {
        let from = Vec3::new(-0.005878899, 0.176738496, 0.202545588);
        let at = Vec3::new(-0.005878899, 0.124951249, -0.004603401);
        let cam = Camera::new(from, at, Vec3::Y, 40.0, 1280, 720);
        let rc = RayCamera::new(&cam, 1280, 720);
        let fwd = (at - from).normalize();
        let right = fwd.cross(Vec3::Y).normalize();
        let up = right.cross(fwd);
        let t = 20f32.to_radians().tan();
        for (x, y) in [(0, 0), (639, 359), (1279, 719), (100, 600)] {
            let sx = (2.0 * (x as f32 + 0.5) / 1280.0 - 1.0) * (1280.0 / 720.0) * t;
            let sy = (1.0 - 2.0 * (y as f32 + 0.5) / 720.0) * t;
            let want = (fwd + sx * right + sy * up).normalize();
            let got = rc.ray(x as f32 + 0.5, y as f32 + 0.5);
            assert!((got.dir - want).length() < 1e-6);
            assert_eq!(got.origin, from);
        }
    }

    /// The image centre looks at `at`; the top edge is half the field of view above it.
    #[test]
    fn centre_and_field_of_view() {
        let cam = Camera::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -5.0), Vec3::Y, 60.0, 200, 100);
        let rc = RayCamera::new(&cam, 200, 100);
        assert!((rc.ray(100.0, 50.0).dir - Vec3::NEG_Z).length() < 1e-6);
        let top = rc.ray(100.0, 0.0).dir;
        assert!((top.angle_between(Vec3::NEG_Z).to_degrees() - 30.0).abs() < 1e-3);
    }
}
