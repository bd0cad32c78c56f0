//! Light samples: the points a shadow ray aims at.

use glam::{Vec2, Vec3};

use crate::scene::{QuadLight, Scene};

/// A point that emits light, with the colour it contributes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Where the light is.
    pub position: Vec3,
    /// What it emits (no distance falloff).
    pub color: Vec3,
}

/// The light samples one pixel sample sees: the fixed ones (point lights, and without stochastic
/// sampling each quad light's regular grid), then each quad light at the point `uv` of its square
/// paired with the pixel sample, with the light's whole colour. Indexed, so that the packet and
/// single-ray paths number the shadow rays alike.
#[derive(Clone, Copy, Debug)]
pub struct Lights<'a> {
    fixed: &'a [LightSample],
    quads: &'a [QuadLight],
    uv: Vec2,
}

impl<'a> Lights<'a> {
    /// `fixed` samples, then `quads` sampled at `uv` (in [0, 1)²).
    pub fn new(fixed: &'a [LightSample], quads: &'a [QuadLight], uv: Vec2) -> Self {
        Lights { fixed, quads, uv }
    }

    /// How many samples.
    pub fn len(&self) -> usize {
        self.fixed.len() + self.quads.len()
    }

    /// True when there is no light at all.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Whether sample `i` is a fixed one, the same for every pixel sample (else a quad light's point,
    /// which depends on the pixel sample's `uv`).
    #[inline]
    pub fn shared(&self, i: usize) -> bool {
        i < self.fixed.len()
    }

    /// Sample `i` (below [`len`](Self::len)).
    #[inline]
    pub fn get(&self, i: usize) -> LightSample {
        match self.fixed.get(i) {
            Some(l) => *l,
            None => {
                let q = &self.quads[i - self.fixed.len()];
                LightSample {
                    position: q.point(self.uv.x, self.uv.y),
                    color: q.color,
                }
            }
        }
    }

    /// The samples in order.
    pub fn iter(&self) -> impl Iterator<Item = LightSample> + '_ {
        (0..self.len()).map(|i| self.get(i))
    }
}

/// The point lights of a scene.
pub fn point_samples(scene: &Scene) -> Vec<LightSample> {
    scene
        .point_lights
        .iter()
        .map(|l| LightSample {
            position: l.position,
            color: l.color,
        })
        .collect()
}

/// The fixed light samples of a scene: every point light, and each quad light as grid × grid point lights
/// at the centres of its cells, each of colour / grid² (the course's regular sampling: bands in the
/// penumbra, no noise).
pub fn regular_samples(scene: &Scene) -> Vec<LightSample> {
    let mut out = point_samples(scene);
    for q in &scene.area_lights {
        let n = q.grid;
        let color = q.color / (n * n) as f32;
        for j in 0..n {
            for i in 0..n {
                let (s, t) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                out.push(LightSample {
                    position: q.point(s, t),
                    color,
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, QuadLight};

    #[test]
    fn quad_grid_samples_sum_to_the_light() {
        let mut scene = Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 8, 8));
        scene.add_point_light(Vec3::ONE, Vec3::ONE);
        scene.area_lights.push(QuadLight {
            corner: Vec3::ZERO,
            edge_u: Vec3::X * 2.0,
            edge_v: Vec3::Z * 2.0,
            color: Vec3::splat(9.0),
            grid: 3,
        });
        let s = regular_samples(&scene);
        assert_eq!(s.len(), 1 + 9);
        let total: Vec3 = s[1..].iter().map(|l| l.color).sum();
        assert!((total - Vec3::splat(9.0)).length() < 1e-5);
        assert!((s[1].position - Vec3::new(1.0 / 3.0, 0.0, 1.0 / 3.0)).length() < 1e-6);
        let centre: Vec3 = s[1..].iter().map(|l| l.position).sum::<Vec3>() / 9.0;
        assert!((centre - Vec3::new(1.0, 0.0, 1.0)).length() < 1e-6);

        // Sampled instead: the point light, then the quad at the pixel sample's point, whole colour.
        let points = point_samples(&scene);
        let lights = Lights::new(&points, &scene.area_lights, Vec2::new(0.25, 0.5));
        assert_eq!(lights.len(), 2);
        assert_eq!(lights.get(0).position, Vec3::ONE);
        assert_eq!(lights.get(1).position, Vec3::new(0.5, 0.0, 1.0));
        assert_eq!(lights.get(1).color, Vec3::splat(9.0));
    }
}
