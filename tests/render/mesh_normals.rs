//! Meshes that carry normals (OBJ `vn`, PLY `nx ny nz`) become smooth triangles wherever a mesh enters a
//! scene (`include`, a bare mesh given as the scene), and render with the interpolated normal, as do the
//! p3f/NFF `pp` patches (a polygon with a normal per vertex).
//!
//! The render check follows `shading.rs`: a scene rendered through brute force (`AccelKind::None`), one
//! pixel compared with the Blinn-Phong value worked out in f64 from the documented model, C_light ·
//! (Kd·Cd·max(0, n·L) + Ks·Cs·max(0, n·h)^shine), with n the interpolated normal computed by hand.

use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};
use whitted::accel::{Accel, AccelKind, Prims};
use whitted::render::{Options, Renderer};
use whitted::scene::{NO_NORMALS, Scene};

use crate::common::blinn_phong;

/// A 1 × 1 quad at z = 0 (counter-clockwise seen from +z) as two triangles, its corner normals bent
/// outward by 54.7° (each (±1, ±1, 1)); a third triangle, below the quad and without normals, stays flat.
const QUAD_OBJ: &str = "\
v -0.5 -0.5 0
v 0.5 -0.5 0
v 0.5 0.5 0
v -0.5 0.5 0
v 0 0 -1
vn -1 -1 1
vn 1 -1 1
vn 1 1 1
vn -1 1 1
f 1//1 2//2 3//3
f 1//1 3//3 4//4
f 1 2 5
";

/// The same mesh as an ascii PLY: per-vertex normals; the flat triangle uses vertex 4, whose normal is zero
/// ("no normal").
const QUAD_PLY: &str = "\
ply
format ascii 1.0
element vertex 5
property float x
property float y
property float z
property float nx
property float ny
property float nz
element face 3
property list uchar int vertex_indices
end_header
-0.5 -0.5 0 -1 -1 1
0.5 -0.5 0 1 -1 1
0.5 0.5 0 1 1 1
-0.5 0.5 0 -1 1 1
0 0 -1 0 0 0
3 0 1 2
3 0 2 3
3 0 1 4
";

/// The quad's corner normals at unit length, by hand: (±1, ±1, 1)/√3.
fn corner_normals() -> [Vec3; 4] {
    let k = 1.0 / 3f32.sqrt();
    [
        Vec3::new(-k, -k, k),
        Vec3::new(k, -k, k),
        Vec3::new(k, k, k),
        Vec3::new(-k, k, k),
    ]
}

/// Writes `files` into a fresh folder; returns it (kept alive by the guard).
fn folder(files: &[(&str, &str)]) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let path = dir.path().to_path_buf();
    (dir, path)
}

/// A scene that looks at `at` from 5 units above it, with a light, a material and `include`.
fn scene_text(at: Vec3, light: Vec3, include: &str) -> String {
    let from = at + Vec3::new(0.0, 0.0, 5.0);
    format!(
        "v\nfrom {} {} {}\nat {} {} {}\nup 0 1 0\nangle 30\nhither 0.01\nresolution 33 33\nb 0 0 0\n\
         l {} {} {} 1 0.9 0.8\nf 0.8 0.6 0.4 0.7 1 1 1 0.3 20 0 1\n{include}\n",
        from.x, from.y, from.z, at.x, at.y, at.z, light.x, light.y, light.z
    )
}

fn load_scene(dir: &Path, include: &str) -> Scene {
    let path = dir.join("scene.p3f");
    std::fs::write(&path, scene_text(Vec3::ZERO, Vec3::new(0.0, 0.0, 5.0), include)).unwrap();
    whitted::scene::load(&path).unwrap()
}

/// Asserts the scene holds the quad's two smooth triangles with `sign` times its normals, then the flat one.
#[track_caller]
fn assert_smooth_quad(scene: &Scene, sign: f32) {
    let t = &scene.triangles;
    assert_eq!(t.len(), 3);
    assert_eq!(t.normals, [0, 1, NO_NORMALS]);
    let n = corner_normals().map(|n| sign * n);
    for (got, want) in t
        .vertex_normals
        .iter()
        .zip([[n[0], n[1], n[2]], [n[0], n[2], n[3]]])
    {
        for (g, w) in got.iter().zip(want) {
            assert!((*g - w).length() < 1e-6, "{:?}", t.vertex_normals);
        }
    }
    assert_eq!(t.vertex_normals.len(), 2);
}

#[test]
fn include_makes_smooth_triangles() {
    let (_guard, dir) = folder(&[("quad.obj", QUAD_OBJ), ("quad.ply", QUAD_PLY)]);
    for mesh in ["quad.obj", "quad.ply"] {
        // A positive uniform scale and a translation keep the normals' directions.
        let scene = load_scene(&dir, &format!("include {mesh} scale 2 translate 1 2 3"));
        assert_smooth_quad(&scene, 1.0);
        assert_eq!(
            scene.triangles.vertices(0),
            [
                Vec3::new(0.0, 1.0, 3.0),
                Vec3::new(2.0, 1.0, 3.0),
                Vec3::new(2.0, 3.0, 3.0)
            ]
        );
        // A negative scale is a point reflection: normals transform by 1/S and turn around.
        let scene = load_scene(&dir, &format!("include {mesh} scale -2"));
        assert_smooth_quad(&scene, -1.0);
    }
}

#[test]
fn bare_mesh_makes_smooth_triangles() {
    let (_guard, dir) = folder(&[("quad.obj", QUAD_OBJ), ("quad.ply", QUAD_PLY)]);
    for mesh in ["quad.obj", "quad.ply"] {
        let scene = whitted::scene::load(&dir.join(mesh)).unwrap();
        assert_smooth_quad(&scene, 1.0);
    }
}

/// The centre pixel of a [`scene_text`] scene looking straight down at `p` with its light at `light`,
/// rendered through brute force with no bounces, is the Blinn-Phong colour of its material with the
/// normal `smooth`, to 1e-5, which the flat normal (0, 0, 1) is not.
fn assert_renders_smooth(scene: &Scene, p: Vec3, light: Vec3, smooth: DVec3) {
    let accel = Accel::build(Prims::new(scene), AccelKind::None);
    let options = Options {
        max_depth: 0,
        ..Options::new(scene)
    };
    let got = Renderer::new(scene, &accel, options).pixel(16, 16);

    let m = scene.materials[0];
    let (p, v, light, color) = (
        p.as_dvec3(),
        DVec3::Z,
        light.as_dvec3(),
        DVec3::new(1.0, 0.9, 0.8),
    );
    let want = blinn_phong(&m, p, smooth, v, light, color);
    let flat = blinn_phong(&m, p, DVec3::Z, v, light, color);
    let got = got.as_dvec3();
    for i in 0..3 {
        let err = (got[i] - want[i]).abs();
        assert!(
            err <= 1e-5 * want[i],
            "channel {i}: got {got}, want {want} (flat {flat})"
        );
    }
    assert!(
        (want - flat).abs().min_element() > 0.05,
        "the check must tell smooth from flat: {want} vs {flat}"
    );
}

/// The quad, included at scale 2 and lifted to z = 1, seen straight down through the centre pixel at
/// P = (0.5, −0.5, 1): in triangle (v0, v1, v2) = ((−1, −1), (1, −1), (1, 1)) at z = 1, P = 0.25·v0 + 0.5·v1 +
/// 0.25·v2, so the interpolated normal is |0.25·(−1, −1, 1) + 0.5·(1, −1, 1) + 0.25·(1, 1, 1)| =
/// |(0.5, −0.5, 1)| = (1, −1, 2)/√6, against the flat (0, 0, 1).
#[test]
fn smooth_quad_renders_with_the_interpolated_normal() {
    let (_guard, dir) = folder(&[("quad.obj", QUAD_OBJ)]);
    let p = Vec3::new(0.5, -0.5, 1.0);
    let light = Vec3::new(3.5, -1.5, 7.0);
    let path = dir.join("scene.p3f");
    let text = scene_text(p, light, "include quad.obj scale 2 translate 0 0 1");
    std::fs::write(&path, text).unwrap();
    let scene = whitted::scene::load(&path).unwrap();
    assert_renders_smooth(&scene, p, light, DVec3::new(1.0, -1.0, 2.0) / 6f64.sqrt());
}

/// A p3f/NFF `pp` patch (a polygon with a normal per vertex) renders with the interpolated normal too:
/// the quad with corners (±1, ±1, 1), counter-clockwise seen from +z, whose corner normals are (x, y, 1)
/// at corner (x, y) (normalised when read: each is (±1, ±1, 1)/√3). The corner (1, 1) gives its normal as
/// (−1, −1, −1), against the winding, and the renderer turns it to the geometric normal's side first
/// (`docs/scene-format.md`). These normals are an affine function of the position, n = (x, y, 1)/√3, so
/// the interpolation gives the same normal in either triangle of either diagonal split: at P = (0.5,
/// −0.25, 1), seen straight down through the centre pixel (on neither diagonal), it is |(0.5, −0.25, 1)| =
/// (2, −1, 4)/√21, against the flat (0, 0, 1).
#[test]
fn smooth_pp_patch_renders_with_the_interpolated_normal() {
    let (_guard, dir) = folder(&[]);
    let p = Vec3::new(0.5, -0.25, 1.0);
    let light = Vec3::new(3.5, -1.75, 5.0);
    let patch = "pp 4\n-1 -1 1  -1 -1 1\n1 -1 1  1 -1 1\n1 1 1  -1 -1 -1\n-1 1 1  -1 1 1\n";
    let path = dir.join("scene.p3f");
    std::fs::write(&path, scene_text(p, light, patch)).unwrap();
    let scene = whitted::scene::load(&path).unwrap();
    assert_eq!(scene.triangles.len(), 2);
    assert_eq!(scene.triangles.vertex_normals.len(), 2, "two smooth triangles");
    assert_renders_smooth(&scene, p, light, DVec3::new(2.0, -1.0, 4.0) / 21f64.sqrt());
}
