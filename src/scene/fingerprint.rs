//! A scene's fingerprint: a digest of everything that decides its image (geometry, materials, lights,
//! camera, background), taken from the loaded store rather than the file's bytes, so that the meshes a
//! `.p3f` includes count too and a scene built in code has one as well. Parts of a frame rendered on
//! different machines carry it, and `whitted merge` refuses to mix parts whose fingerprints differ.

use glam::Vec3;

use super::{Scene, Vec3s};
use crate::digest::Digest;

fn vec3(d: &mut Digest, v: Vec3) {
    d.floats(&v.to_array());
}

fn vec3s(d: &mut Digest, v: &Vec3s) {
    d.word(v.len() as u64);
    for axis in [&v.x, &v.y, &v.z] {
        d.floats(axis);
    }
}

fn bools(d: &mut Digest, v: &[bool]) {
    d.word(v.len() as u64);
    d.bytes(&v.iter().map(|&b| u8::from(b)).collect::<Vec<_>>());
}

impl Scene {
    /// The digest of what this scene renders (not its warnings, nor the accelerator it suggests, which
    /// do not change the image). The cube map counts by its directory's name only: the same scene read
    /// from another mount point on another machine has the same fingerprint.
    pub fn fingerprint(&self) -> u64 {
        let mut d = Digest::new();
        let c = &self.camera;
        for v in [c.from, c.at, c.up] {
            vec3(&mut d, v);
        }
        d.floats(&[c.fov_y, c.hither, c.aperture, c.focal]);
        d.u32s(&[c.width, c.height, self.spp]);
        vec3(&mut d, self.background);
        let env = self.env.as_ref().and_then(|p| p.file_name());
        d.bytes(env.map(|n| n.as_encoded_bytes()).unwrap_or_default());
        d.word(self.materials.len() as u64);
        for m in &self.materials {
            vec3(&mut d, m.diffuse);
            vec3(&mut d, m.specular);
            d.floats(&[m.kd, m.ks, m.shininess, m.transmission, m.ior]);
            d.floats(&[m.roughness.unwrap_or(f32::NAN)]);
        }
        d.word(self.point_lights.len() as u64);
        for l in &self.point_lights {
            vec3(&mut d, l.position);
            vec3(&mut d, l.color);
        }
        d.word(self.area_lights.len() as u64);
        for l in &self.area_lights {
            for v in [l.corner, l.edge_u, l.edge_v, l.color] {
                vec3(&mut d, v);
            }
            d.u32s(&[l.grid]);
        }
        let s = &self.spheres;
        vec3s(&mut d, &s.center);
        d.floats(&s.radius);
        bools(&mut d, &s.inside_only);
        d.u32s(&s.material);
        let t = &self.triangles;
        for v in [&t.v0, &t.e1, &t.e2] {
            vec3s(&mut d, v);
        }
        d.u32s(&t.material);
        d.u32s(&t.normals);
        d.word(t.vertex_normals.len() as u64);
        for n in &t.vertex_normals {
            for v in n {
                vec3(&mut d, *v);
            }
        }
        let b = &self.boxes;
        vec3s(&mut d, &b.min);
        vec3s(&mut d, &b.max);
        d.u32s(&b.material);
        let p = &self.planes;
        vec3s(&mut d, &p.normal);
        d.floats(&p.offset);
        d.u32s(&p.material);
        let k = &self.cones;
        vec3s(&mut d, &k.base);
        d.floats(&k.base_radius);
        vec3s(&mut d, &k.apex);
        d.floats(&k.apex_radius);
        bools(&mut d, &k.inside_only);
        d.u32s(&k.material);
        d.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, Material};

    fn scene() -> Scene {
        let mut s = Scene::new(Camera::new(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 45.0, 32, 32));
        let m = s.add_material(Material::default());
        s.add_sphere(Vec3::ZERO, 1.0, m);
        s.add_triangle(Vec3::X, Vec3::Y, Vec3::Z, m);
        s.add_point_light(Vec3::ONE, Vec3::ONE);
        s
    }

    #[test]
    fn anything_that_renders_differently_changes_it() {
        let base = scene().fingerprint();
        assert_eq!(scene().fingerprint(), base);
        let mut s = scene();
        s.triangles.e1.x[0] = 1.0 + f32::EPSILON;
        assert_ne!(s.fingerprint(), base);
        let mut s = scene();
        s.materials[0].ior = 1.5;
        assert_ne!(s.fingerprint(), base);
        let mut s = scene();
        s.camera.width = 33;
        assert_ne!(s.fingerprint(), base);
        let mut s = scene();
        s.spheres.inside_only[0] = true;
        assert_ne!(s.fingerprint(), base);
        let mut s = scene();
        s.warnings.push("not part of the image".into());
        assert_eq!(s.fingerprint(), base);
    }
}
