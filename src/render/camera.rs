//! Primary rays: the pinhole (and, with an aperture, thin-lens) camera of the `v` block.

use glam::{Vec2, Vec3};

use crate::geometry::length_and_direction;
use crate::geometry::ray::Ray;
use crate::render::lanes::{Fx, Lanes, V3};
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
    /// Radius of the thin lens (0: a pinhole).
    lens_radius: f32,
    /// Distance from the eye to the plane in focus, along the view direction.
    focal_distance: f32,
}

impl RayCamera {
    /// Sets up the frame: `forward` toward `at`, `right = forward × up`, `up` re-orthogonalised; `angle`
    /// is the vertical field of view edge to edge, and pixels are square.
    ///
    /// The lens follows the course's camera: the view plane lies at `at` (distance d = |at − from|), the
    /// aperture is the lens diameter in pixels of that plane (pixel size 2·d·tan(angle/2) / height), and
    /// the plane in focus lies at `focal` · d.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        // Robust against cameras far from their target, or with a huge `up` (validated finite).
        let (view_distance, forward) = length_and_direction(camera.at - camera.from);
        let right = length_and_direction(forward.cross(camera.up)).1;
        let up = right.cross(forward);
        let tan = (camera.fov_y.to_radians() * 0.5).tan();
        let pixel_size = 2.0 * view_distance * tan / height as f32;
        RayCamera {
            eye: camera.from,
            forward,
            right,
            up,
            half: (tan * width as f32 / height as f32, tan),
            width,
            height,
            lens_radius: 0.5 * camera.aperture * pixel_size,
            focal_distance: camera.focal * view_distance,
        }
    }

    /// True when the camera has a lens (aperture above zero): its rays need lens samples.
    pub fn has_lens(&self) -> bool {
        self.lens_radius > 0.0
    }

    /// The ray through the image point `(x, y)` in pixels (`(0.5, 0.5)` is the centre of the top-left
    /// pixel), with a unit direction.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        self.rays::<f32, 1>([x], [y])[0]
    }

    /// The thin-lens ray (Cook et al. 1984; Potmesil and Chakravarty 1981) through image point
    /// `(x, y)` from lens point `lens` of the unit disc: it starts on the lens and passes through the
    /// point of the focal plane that the pinhole ray through `(x, y)` meets, so whatever lies on that
    /// plane is sharp and the rest blurs with its distance from it. A pinhole camera ignores `lens`.
    #[inline]
    pub fn lens_ray(&self, x: f32, y: f32, lens: Vec2) -> Ray {
        if !self.has_lens() {
            return self.ray(x, y);
        }
        let focus = self.eye + self.focal_distance * self.through(x, y);
        let lens = self.lens_radius * lens;
        let origin = self.eye + lens.x * self.right + lens.y * self.up;
        Ray::new(origin, (focus - origin).normalize())
    }

    /// The pinhole rays through image points `(x[k], y[k])`, `N` at once: [`ray`](Self::ray) in lanes.
    #[inline(always)]
    pub(crate) fn rays<L: Lanes<N>, const N: usize>(&self, x: [f32; N], y: [f32; N]) -> [Ray; N] {
        let d = self
            .through_lanes::<L, N>(Fx::from(x), Fx::from(y))
            .normalize()
            .lanes();
        std::array::from_fn(|k| Ray::new(self.eye, d[k]))
    }

    /// The ray of a sample that passes through image point `at`: from lens point `lens` where the
    /// camera has a lens ([`lens_ray`](Self::lens_ray)), else the pinhole's ([`ray`](Self::ray)).
    #[inline]
    pub fn sample_ray(&self, at: Vec2, lens: Option<Vec2>) -> Ray {
        match lens {
            Some(lens) => self.lens_ray(at.x, at.y, lens),
            None => self.ray(at.x, at.y),
        }
    }

    /// The direction through image point `(x, y)`, scaled to reach the plane one unit ahead.
    #[inline]
    fn through(&self, x: f32, y: f32) -> Vec3 {
        self.through_lanes::<f32, 1>(Fx(x), Fx(y)).lanes()[0]
    }

    /// [`through`](Self::through) in lanes.
    #[inline(always)]
    fn through_lanes<L: Lanes<N>, const N: usize>(&self, x: Fx<L, N>, y: Fx<L, N>) -> V3<L, N> {
        let s = Fx::<L, N>::splat;
        let sx = (s(2.0) * x / s(self.width as f32) - s(1.0)) * s(self.half.0);
        let sy = (s(1.0) - s(2.0) * y / s(self.height as f32)) * s(self.half.1);
        V3::splat(self.forward) + V3::splat(self.right) * sx + V3::splat(self.up) * sy
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dragon workload's camera formula (`docs/dragon-workload.md`), pixel by pixel.
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

    /// Every lens ray of an image point meets the pinhole ray through it on the focal plane; they start
    /// within the lens radius (aperture 4 pixels: radius 2 pixels of the view plane).
    #[test]
    fn lens_rays_converge_on_the_focal_plane() {
        let mut cam = Camera::new(Vec3::ZERO, Vec3::new(0.0, 0.0, -5.0), Vec3::Y, 60.0, 200, 100);
        (cam.aperture, cam.focal) = (4.0, 1.5);
        let rc = RayCamera::new(&cam, 200, 100);
        assert!(rc.has_lens());
        let pixel = 2.0 * 5.0 * 30f32.to_radians().tan() / 100.0;
        for (x, y) in [(100.0, 50.0), (13.5, 80.25)] {
            let pin = rc.ray(x, y);
            // The focal plane is z = -7.5.
            let focus = pin.at(7.5 / -pin.dir.z);
            for lens in [Vec2::new(1.0, 0.0), Vec2::new(-0.3, 0.7), Vec2::ZERO] {
                let r = rc.lens_ray(x, y, lens);
                assert!((r.origin.length() - 2.0 * pixel * lens.length()).abs() < 1e-5);
                let p = r.at((focus.z - r.origin.z) / r.dir.z);
                assert!((p - focus).length() < 1e-4, "{p} vs {focus}");
            }
        }
        cam.aperture = 0.0;
        let pinhole = RayCamera::new(&cam, 200, 100);
        assert_eq!(
            pinhole.lens_ray(3.0, 4.0, Vec2::ONE).dir,
            pinhole.ray(3.0, 4.0).dir
        );
    }

    /// Eight pinhole rays at once, on every lane type the CPU runs, are the single rays, bit for bit,
    /// all over the image and beyond it.
    #[test]
    fn rays_in_lanes_are_the_single_rays() {
        use crate::accel::lanes::{Lanes8, OnLanes8};
        use crate::accel::{Isa, Simd};

        struct Eight<'a>(&'a RayCamera, [f32; 8], [f32; 8]);
        impl OnLanes8 for Eight<'_> {
            type Output = [Ray; 8];
            fn run<L: Lanes8>(self) -> [Ray; 8] {
                self.0.rays::<L, 8>(self.1, self.2)
            }
        }
        let cam = Camera::new(
            Vec3::new(2.3, 1.6, 1.1),
            Vec3::new(0.1, -0.2, 0.0),
            Vec3::Y,
            50.0,
            800,
            600,
        );
        let rc = RayCamera::new(&cam, 800, 600);
        let mut rng = crate::render::sampler::Sampler::new(5, 1, 0, 1);
        for simd in [Isa::Portable, Isa::Avx2, Isa::Avx512]
            .into_iter()
            .filter_map(Simd::new)
        {
            for _ in 0..1000 {
                let x: [f32; 8] = std::array::from_fn(|_| rng.uniform() * 900.0 - 50.0);
                let y: [f32; 8] = std::array::from_fn(|_| rng.uniform() * 700.0 - 50.0);
                let lanes = simd.run8(Eight(&rc, x, y));
                for k in 0..8 {
                    let one = rc.ray(x[k], y[k]);
                    assert_eq!(
                        lanes[k].dir.to_array().map(f32::to_bits),
                        one.dir.to_array().map(f32::to_bits)
                    );
                    assert_eq!(lanes[k].origin, one.origin);
                }
            }
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
