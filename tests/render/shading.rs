//! Render-level closed-form checks of the Whitted integrator (`src/render/whitted.rs`).
//!
//! Each test builds a tiny scene in code, renders a pixel (or traces a hand-made ray) through brute force
//! (`AccelKind::None`), and compares the linear colour with a value worked out by hand from the documented
//! model (`docs/scene-format.md`, "Rendering conventions", and the doc comments of `whitted.rs` / `optics.rs`):
//!
//! - local colour: Σ_lights C_light · (Kd·Cd·max(0, n·L) + Ks·Cs·max(0, n·h)^shine), h = |L + V|, no
//!   ambient, no falloff, nothing from a light behind the shading normal or in shadow;
//! - opaque surfaces: + Ks · colour(mirror ray); transparent ones: Kr from Schlick, + Ks·Kr · colour(mirror
//!   ray) + T·(1 − Kr) · colour(refracted ray), Kr = 1 under total internal reflection;
//! - Beer: inside a transparent object the colour is multiplied by Cd^distance;
//! - `max_depth` D: at most D bounces after the primary hit; at the limit only the local colour.
//!
//! References are computed in f64; the tolerance is 1e-5 relative (plus 1e-6 absolute for values near 0)
//! unless a test says why it needs another.

use glam::{DVec3, Vec3};
use whitted::accel::{Accel, AccelKind, Prims};
use whitted::geometry::ray::Ray;
use whitted::render::EPSILON;
use whitted::render::{Options, Renderer};
use whitted::scene::{Camera, Material, Scene};

use crate::common::blinn_phong;

// ---------------------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------------------

/// Builds a brute-force renderer over `scene` at the camera's resolution with `max_depth`, and hands it to `f`.
fn with_renderer<R>(scene: &Scene, max_depth: u32, f: impl FnOnce(&Renderer) -> R) -> R {
    let accel = Accel::build(Prims::new(scene), AccelKind::None);
    let options = Options {
        max_depth,
        ..Options::new(scene)
    };
    let renderer = Renderer::new(scene, &accel, options);
    f(&renderer)
}

/// The colour of pixel `(x, y)` with `max_depth`.
fn pixel(scene: &Scene, max_depth: u32, x: u32, y: u32) -> Vec3 {
    with_renderer(scene, max_depth, |r| r.pixel(x, y))
}

/// Asserts `got ≈ want` channel by channel: |got − want| ≤ rel·|want| + abs.
#[track_caller]
fn assert_close_tol(got: Vec3, want: DVec3, rel: f64, abs: f64, what: &str) {
    let g = got.as_dvec3();
    for i in 0..3 {
        let err = (g[i] - want[i]).abs();
        assert!(
            err <= rel * want[i].abs() + abs,
            "{what}: channel {i}: got {got:?}, want {want:?} (error {err:e})"
        );
    }
}

/// `assert_close_tol` with the default 1e-5 relative, 1e-6 absolute.
#[track_caller]
fn assert_close(got: Vec3, want: DVec3, what: &str) {
    assert_close_tol(got, want, 1e-5, 1e-6, what);
}

fn d(v: Vec3) -> DVec3 {
    v.as_dvec3()
}

/// The primary ray of pixel `(x, y)` in f64, by the documented pinhole formula (`render/camera.rs`):
/// forward = |at − from|, right = |forward × up|, up' = right × forward, tan = tan(fov_y / 2),
/// sx = (2(x + ½)/W − 1)·tan·W/H, sy = (1 − 2(y + ½)/H)·tan, dir = |forward + sx·right + sy·up'|.
fn camera_ray(cam: &Camera, x: u32, y: u32) -> (DVec3, DVec3) {
    let (from, at, up) = (d(cam.from), d(cam.at), d(cam.up));
    let forward = (at - from).normalize();
    let right = forward.cross(up).normalize();
    let up = right.cross(forward);
    let tan = ((cam.fov_y as f64).to_radians() * 0.5).tan();
    let (w, h) = (cam.width as f64, cam.height as f64);
    let sx = (2.0 * (x as f64 + 0.5) / w - 1.0) * tan * w / h;
    let sy = (1.0 - 2.0 * (y as f64 + 0.5) / h) * tan;
    (from, (forward + sx * right + sy * up).normalize())
}

/// The nearest positive root of |o + t·dir − c|² = r² (unit `dir`), if any.
fn ray_sphere(o: DVec3, dir: DVec3, c: DVec3, r: f64) -> Option<f64> {
    let oc = o - c;
    let b = oc.dot(dir);
    let disc = b * b - (oc.length_squared() - r * r);
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    [-b - s, -b + s].into_iter().find(|&t| t > 0.0)
}

/// True if the segment `a`–`b` passes within `r` of `c`.
fn segment_near_point(a: DVec3, b: DVec3, c: DVec3, r: f64) -> bool {
    let ab = b - a;
    let s = ((c - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    (a + s * ab - c).length() < r
}

/// Schlick's Fresnel in f64, as documented in `optics.rs`: R0 = ((η_i − η_t)/(η_i + η_t))², Kr = R0 +
/// (1 − R0)(1 − cos θ)^5 with θ the larger (transmitted, when leaving the denser medium) angle, and 1 beyond
/// the critical angle.
fn schlick(cos_i: f64, eta_i: f64, eta_t: f64) -> f64 {
    let r0 = ((eta_i - eta_t) / (eta_i + eta_t)).powi(2);
    let cos = if eta_i > eta_t {
        let sin2_t = (eta_i / eta_t).powi(2) * (1.0 - cos_i * cos_i);
        if sin2_t >= 1.0 {
            return 1.0;
        }
        (1.0 - sin2_t).sqrt()
    } else {
        cos_i
    };
    r0 + (1.0 - r0) * (1.0 - cos).powi(5)
}

/// A material that only transmits: Kd = Ks = 0, T = 1, colour `cd`, index `ior`.
fn glass(cd: Vec3, ior: f32, ks: f32) -> Material {
    Material {
        diffuse: cd,
        kd: 0.0,
        specular: Vec3::ONE,
        ks,
        shininess: 1.0,
        transmission: 1.0,
        ior,
        roughness: None,
    }
}

/// The 33×33 view from (0, 0, 5) toward the origin: pixel (16, 16) looks exactly down −z.
fn front_camera(fov: f32) -> Camera {
    Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, fov, 33, 33)
}

const CENTRE: u32 = 16;

// ---------------------------------------------------------------------------------------------------------
// 1. Head-on Blinn-Phong
// ---------------------------------------------------------------------------------------------------------

/// A sphere lit head-on by a white point light at the eye: at the centre pixel n·L = n·h = 1, so the local
/// colour is Kd·Cd + Ks·Cs (no ambient, no falloff). With `max_depth` > 0 the mirror ray goes straight back
/// toward the eye and leaves the scene, adding exactly Ks × background (Ks a scalar, not tinted by Cs).
#[test]
fn head_on_sphere_is_kd_cd_plus_ks_cs() {
    let mut scene = Scene::new(front_camera(30.0));
    scene.background = Vec3::new(0.1, 0.2, 0.3);
    let m = Material {
        diffuse: Vec3::new(0.6, 0.3, 0.2),
        kd: 0.7,
        specular: Vec3::new(1.0, 0.9, 0.8),
        ks: 0.25,
        shininess: 50.0,
        ..Material::default()
    };
    let id = scene.add_material(m);
    scene.add_sphere(Vec3::ZERO, 1.0, id);
    scene.add_point_light(Vec3::new(0.0, 0.0, 5.0), Vec3::ONE);

    // local = Kd·Cd·1 + Ks·Cs·1^50
    let local = m.kd as f64 * d(m.diffuse) + m.ks as f64 * d(m.specular);
    assert_close(pixel(&scene, 0, CENTRE, CENTRE), local, "max_depth 0");
    // + Ks·background from the mirror ray (which misses everything)
    for depth in [1, 2, 6] {
        let want = local + m.ks as f64 * d(scene.background);
        assert_close(
            pixel(&scene, depth, CENTRE, CENTRE),
            want,
            &format!("max_depth {depth}"),
        );
    }
}

// ---------------------------------------------------------------------------------------------------------
// 2. Off-centre Blinn-Phong
// ---------------------------------------------------------------------------------------------------------

/// Off-centre pixels of a lit sphere: the hit point from the analytic ray-sphere root, n = p − c, L, V and
/// h = |L + V| give the Blinn-Phong value C_light·(Kd·Cd·n·L + Ks·Cs·(n·h)^shine) (0 past the terminator),
/// and a pixel that misses the sphere is the background.
#[test]
fn off_centre_pixels_match_blinn_phong() {
    let mut scene = Scene::new(front_camera(30.0));
    scene.background = Vec3::new(0.05, 0.1, 0.15);
    let m = Material {
        diffuse: Vec3::new(0.7, 0.2, 0.1),
        kd: 0.8,
        specular: Vec3::new(0.9, 0.9, 1.0),
        ks: 0.4,
        shininess: 20.0,
        ..Material::default()
    };
    let id = scene.add_material(m);
    scene.add_sphere(Vec3::ZERO, 1.0, id);
    let (light, light_color) = (Vec3::new(3.0, 4.0, 6.0), Vec3::new(1.0, 0.8, 0.6));
    scene.add_point_light(light, light_color);

    let pixels = [
        (16, 16),
        (20, 13), // near the highlight
        (22, 12),
        (10, 20),
        (16, 5),
        (25, 16),
        (5, 16),
        (8, 24), // past the terminator: n·L < 0
        (1, 1),  // misses the sphere
    ];
    let (mut hits, mut dark) = (0, 0);
    with_renderer(&scene, 0, |r| {
        for (x, y) in pixels {
            let (o, dir) = camera_ray(&scene.camera, x, y);
            let want = match ray_sphere(o, dir, DVec3::ZERO, 1.0) {
                None => d(scene.background),
                Some(t) => {
                    hits += 1;
                    let p = o + t * dir;
                    let n = p; // unit sphere at the origin
                    let v = -dir;
                    let c = blinn_phong(&m, p, n, v, d(light), d(light_color));
                    if c == DVec3::ZERO {
                        dark += 1;
                    }
                    c
                }
            };
            assert_close(r.pixel(x, y), want, &format!("pixel ({x}, {y})"));
        }
    });
    assert_eq!(
        (hits, dark),
        (8, 1),
        "the pixel list covers hits, a dark side and a miss"
    );
}

// ---------------------------------------------------------------------------------------------------------
// 3. Shadows
// ---------------------------------------------------------------------------------------------------------

/// A ground square (two triangles, y = 0) seen from above, an occluding sphere at (2, 2, 0).
fn shadow_scene() -> (Scene, Material) {
    let cam = Camera::new(Vec3::new(0.0, 10.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, 60.0, 33, 33);
    let mut scene = Scene::new(cam);
    let ground = Material {
        diffuse: Vec3::ONE,
        kd: 1.0,
        ks: 0.0,
        ..Material::default()
    };
    let g = scene.add_material(ground);
    // The shared diagonal runs along z = x + 1, away from every pixel used below.
    let (a, b, c, e) = (
        Vec3::new(-10.0, 0.0, -9.0),
        Vec3::new(10.0, 0.0, -9.0),
        Vec3::new(10.0, 0.0, 11.0),
        Vec3::new(-10.0, 0.0, 11.0),
    );
    scene.add_triangle(a, c, b, g);
    scene.add_triangle(a, e, c, g);
    let s = scene.add_material(Material::default());
    scene.add_sphere(OCCLUDER, OCCLUDER_R, s);
    (scene, ground)
}

const OCCLUDER: Vec3 = Vec3::new(2.0, 2.0, 0.0);
const OCCLUDER_R: f32 = 0.5;

/// The ground point seen through pixel `(x, y)` of the shadow scene (checking that the occluder is not in
/// the way of the camera ray).
fn ground_point(scene: &Scene, x: u32, y: u32) -> DVec3 {
    let (o, dir) = camera_ray(&scene.camera, x, y);
    let t = -o.y / dir.y;
    let q = o + t * dir;
    assert!(!segment_near_point(o, q, d(OCCLUDER), OCCLUDER_R as f64 + 0.05));
    q
}

/// Hard shadows with no ambient term: a ground point whose only light is blocked by a sphere is exactly
/// black; an unblocked point is Kd·Cd·(n·L)·C_light with n = +y; with a second light, the half-shadowed point
/// gets the unoccluded light's term only, and an unshadowed point the sum of both.
#[test]
fn shadows_are_black_and_lights_add() {
    let (mut scene, ground) = shadow_scene();
    let light_a = (Vec3::new(4.0, 4.0, 0.0), Vec3::ONE);
    scene.add_point_light(light_a.0, light_a.1);

    // Pixel (16, 16) sees the origin; the segment to light A passes through the occluder's centre.
    let o = ground_point(&scene, CENTRE, CENTRE);
    assert!(o.length() < 1e-6);
    assert!(segment_near_point(o, d(light_a.0), d(OCCLUDER), 0.01));
    assert_eq!(pixel(&scene, 3, CENTRE, CENTRE), Vec3::ZERO, "shadowed point");

    // Unshadowed points: n·L by hand.
    let n = DVec3::Y;
    let lit = [(16, 6), (26, 16), (20, 24)];
    for (x, y) in lit {
        let q = ground_point(&scene, x, y);
        assert!(!segment_near_point(
            q,
            d(light_a.0),
            d(OCCLUDER),
            OCCLUDER_R as f64 + 0.05
        ));
        let v = (d(scene.camera.from) - q).normalize();
        let want = blinn_phong(&ground, q, n, v, d(light_a.0), d(light_a.1));
        // Kd = Cd = 1, Ks = 0: just n·L
        let n_dot_l = (d(light_a.0) - q).normalize().y;
        assert!((want.x - n_dot_l).abs() < 1e-12 && n_dot_l > 0.1);
        assert_close(pixel(&scene, 3, x, y), want, &format!("lit pixel ({x}, {y})"));
    }

    // A second, coloured light on the other side.
    let light_b = (Vec3::new(-4.0, 4.0, 0.0), Vec3::new(0.5, 0.25, 1.0));
    scene.add_point_light(light_b.0, light_b.1);
    // Half-shadowed origin: light B only, n·L_B = 4/√32 = 1/√2.
    assert!(!segment_near_point(
        o,
        d(light_b.0),
        d(OCCLUDER),
        OCCLUDER_R as f64 + 0.05
    ));
    let want = std::f64::consts::FRAC_1_SQRT_2 * d(light_b.1);
    assert_close(pixel(&scene, 3, CENTRE, CENTRE), want, "half-shadowed point");
    for (x, y) in lit {
        let q = ground_point(&scene, x, y);
        assert!(!segment_near_point(
            q,
            d(light_b.0),
            d(OCCLUDER),
            OCCLUDER_R as f64 + 0.05
        ));
        let v = (d(scene.camera.from) - q).normalize();
        let want = blinn_phong(&ground, q, n, v, d(light_a.0), d(light_a.1))
            + blinn_phong(&ground, q, n, v, d(light_b.0), d(light_b.1));
        assert_close(
            pixel(&scene, 3, x, y),
            want,
            &format!("two lights, pixel ({x}, {y})"),
        );
    }
}

// ---------------------------------------------------------------------------------------------------------
// 4. Lights behind the surface
// ---------------------------------------------------------------------------------------------------------

/// A light behind the shading normal contributes nothing, neither diffuse nor highlight, even where
/// h = |L + V| still leans toward the normal (so (n·h)^shine alone would be positive) and where the shadow
/// ray (offset to the light's side of a single triangle) is not blocked. A light in front adds its own
/// Blinn-Phong term only.
#[test]
fn light_behind_surface_adds_nothing() {
    let cam = Camera::new(Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, Vec3::Y, 40.0, 33, 33);
    let mut scene = Scene::new(cam);
    let m = Material {
        diffuse: Vec3::ONE,
        kd: 1.0,
        specular: Vec3::ONE,
        ks: 1.0,
        shininess: 1.0,
        ..Material::default()
    };
    let id = scene.add_material(m);
    // One triangle in y = 0 around the origin (seen from above, counter-clockwise from +y).
    scene.add_triangle(
        Vec3::new(-10.0, 0.0, -9.0),
        Vec3::new(0.0, 0.0, 11.0),
        Vec3::new(10.0, 0.0, -9.0),
        id,
    );
    let below = Vec3::new(0.0, -0.5, -5.0);
    scene.add_point_light(below, Vec3::ONE);

    // The centre pixel sees the origin; there n·L < 0 but n·h > 0.
    let (eye, dir) = camera_ray(&scene.camera, CENTRE, CENTRE);
    let p = eye - eye.y / dir.y * dir;
    assert!(p.length() < 1e-6);
    let (n, l, v) = (DVec3::Y, (d(below) - p).normalize(), -dir);
    let h = (l + v).normalize();
    assert!(
        n.dot(l) < 0.0 && n.dot(h) > 0.05,
        "n·L = {}, n·h = {}",
        n.dot(l),
        n.dot(h)
    );
    assert_eq!(pixel(&scene, 0, CENTRE, CENTRE), Vec3::ZERO);

    // Add a light in front: the pixel is that light's term only.
    let above = Vec3::new(1.0, 5.0, 2.0);
    scene.add_point_light(above, Vec3::ONE);
    let want = blinn_phong(&m, p, n, v, d(above), DVec3::ONE);
    assert_close(pixel(&scene, 0, CENTRE, CENTRE), want, "front light only");
}

// ---------------------------------------------------------------------------------------------------------
// 5. Beer's law
// ---------------------------------------------------------------------------------------------------------

/// Beer–Lambert absorption through an index-1 slab (an axis-aligned box, no bending, R0 = 0 so Kr = 0 at
/// normal incidence), Kd = Ks = 0, T = 1, white background, seen straight through its normal: the pixel is
/// e^(−a·d) = Cd^d with a = −ln Cd per unit, for two thicknesses.
///
/// Tolerance: the refracted ray starts EPSILON = 1e-4 past the entry face (the documented offset), so the
/// path inside is d − EPSILON; the reference is Cd^(d − EPSILON) at 1e-5 relative, and the physical Cd^d is
/// met to |ln Cd|·EPSILON relative (7e-5 for Cd = 0.5). With `max_depth` 1 the exit face is at the depth
/// limit: only its local colour (0), so the pixel is black.
#[test]
fn beer_absorption_through_a_slab() {
    let cd = Vec3::new(0.5, 0.8, 0.95);
    for thickness in [1.0f32, 2.5] {
        let mut scene = Scene::new(front_camera(30.0));
        scene.background = Vec3::ONE;
        let id = scene.add_material(glass(cd, 1.0, 0.0));
        scene.add_box(Vec3::new(-2.0, -2.0, -thickness), Vec3::new(2.0, 2.0, 0.0), id);
        let got = pixel(&scene, 2, CENTRE, CENTRE);
        let path = thickness as f64 - EPSILON as f64;
        let want = d(cd).powf(path);
        assert_close(got, want, &format!("d = {thickness}, path d − ε"));
        let physical = d(cd).powf(thickness as f64);
        let rel = -(cd.x as f64).ln() * EPSILON as f64 + 1e-5;
        assert_close_tol(got, physical, rel, 1e-6, &format!("d = {thickness}, Cd^d"));
        assert_eq!(
            pixel(&scene, 1, CENTRE, CENTRE),
            Vec3::ZERO,
            "exit at the depth limit"
        );
    }
}

// ---------------------------------------------------------------------------------------------------------
// 6. Fresnel at normal incidence
// ---------------------------------------------------------------------------------------------------------

/// Refraction through a glass slab (ior 1.5) at normal incidence: Kr = R0 = ((1 − 1.5)/(1 + 1.5))² = 0.04
/// at both faces. With Ks = 0 (reflection weight Ks·Kr = 0), T = 1, white Cd and white background, the pixel
/// is T(1 − Kr) at entry × T(1 − Kr) at exit = 0.96² = 0.9216.
///
/// With Ks = 1 every mirror ray is computable: the background is uniform (B) and each bounce goes back along
/// the axis. With G(k) the colour of an internal ray reaching a face at depth k (the same at both faces) and
/// a = Cd^(d − ε) the Beer factor of one crossing:
///   P = 0.04·B + 0.96·G(1),   G(k) = a·(0.96·B + 0.04·G(k + 1)) for k < D,   G(D) = 0 (local colour 0).
/// White Cd (a = 1): G(k) = B·(1 − 0.04^(D−k)), so P = 0.04·B + 0.96·B·(1 − 0.04^(D−1)):
/// D = 1: 0.04·B; D = 2: 0.9616·B; D = 3: 0.998464·B; D → ∞: B (energy is conserved).
#[test]
fn fresnel_at_normal_incidence() {
    let b = Vec3::new(1.0, 0.5, 0.25);
    let slab = |ks: f32, cd: Vec3, bg: Vec3| {
        let mut scene = Scene::new(front_camera(30.0));
        scene.background = bg;
        let id = scene.add_material(glass(cd, 1.5, ks));
        scene.add_box(Vec3::new(-2.0, -2.0, -1.0), Vec3::new(2.0, 2.0, 0.0), id);
        scene
    };
    let r0 = schlick(1.0, 1.0, 1.5);
    assert!((r0 - 0.04).abs() < 1e-15);

    // Ks = 0: two transmissions.
    let scene = slab(0.0, Vec3::ONE, Vec3::ONE);
    for depth in [2, 3, 6] {
        let got = pixel(&scene, depth, CENTRE, CENTRE);
        assert_close(got, DVec3::splat(0.9216), &format!("Ks = 0, max_depth {depth}"));
    }

    // Ks = 1, white glass: the series above, in closed form.
    let scene = slab(1.0, Vec3::ONE, b);
    for (depth, factor) in [(1, 0.04), (2, 0.9616), (3, 0.998464)] {
        let closed = 0.04 + 0.96 * (1.0 - 0.04f64.powi(depth as i32 - 1));
        assert!((closed - factor).abs() < 1e-12);
        let got = pixel(&scene, depth, CENTRE, CENTRE);
        assert_close(got, factor * d(b), &format!("Ks = 1, max_depth {depth}"));
    }
    let got = pixel(&scene, 12, CENTRE, CENTRE);
    assert_close(got, d(b), "Ks = 1, max_depth 12: all the light comes out");

    // Ks = 1, tinted glass, thickness 1: the recursion with a = Cd^(1 − ε) per crossing.
    let cd = Vec3::new(0.5, 0.7, 0.9);
    let scene = slab(1.0, cd, b);
    let a = d(cd).powf(1.0 - EPSILON as f64);
    for depth in 1..=5u32 {
        let mut g = DVec3::ZERO; // G(D)
        for _ in 1..depth {
            g = a * (0.96 * d(b) + 0.04 * g);
        }
        let want = 0.04 * d(b) + 0.96 * g;
        let got = pixel(&scene, depth, CENTRE, CENTRE);
        assert_close(got, want, &format!("tinted, max_depth {depth}"));
    }
}

// ---------------------------------------------------------------------------------------------------------
// 7. Total internal reflection
// ---------------------------------------------------------------------------------------------------------

/// Total internal reflection in a glass block (ior 1.5, white, Kd = 0, T = 1, background B): a ray entering
/// the top face (z = 0) at 45° refracts to θt = asin(sin 45°/1.5) ≈ 28.1° and meets the side face x = 0.5 at
/// 90° − θt ≈ 61.9°, beyond the critical angle asin(1/1.5) ≈ 41.8°: nothing is transmitted there, Kr = 1 and
/// the reflection weight is Ks·1. The reflected ray leaves through the bottom face (z = −10) at θt, where
/// Schlick (on the transmitted angle, 45°) gives the same Kr as at entry. With max_depth 3:
///   P = Ks·Kr·B + T(1 − Kr) · [Ks·1 · (T(1 − Kr)·B + Ks·Kr·(local 0 at the depth limit))]
///     = Ks·Kr·B + Ks·(1 − Kr)²·B,   Kr = 0.04 + 0.96·(1 − cos 45°)^5.
/// So with Ks = 0 the TIR path contributes nothing and the result is exactly 0; a ray at 10° that leaves
/// through the bottom face directly shows the difference: (1 − Kr(10°))²·B.
#[test]
fn total_internal_reflection_reflects() {
    let b = Vec3::new(0.9, 0.6, 0.3);
    let block = |ks: f32| {
        let mut scene = Scene::new(front_camera(30.0));
        scene.background = b;
        let id = scene.add_material(glass(Vec3::ONE, 1.5, ks));
        scene.add_box(Vec3::new(-5.0, -5.0, -10.0), Vec3::new(0.5, 5.0, 0.0), id);
        scene
    };
    let ray_at = |deg: f64| {
        let (s, c) = deg.to_radians().sin_cos();
        let dir = DVec3::new(s, 0.0, -c);
        Ray::new((-dir).as_vec3(), dir.as_vec3()) // hits the top face at the origin
    };

    // The geometry of the 45° path, by hand.
    let sin_t = 45f64.to_radians().sin() / 1.5;
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let side_angle = 90.0 - sin_t.asin().to_degrees();
    let critical = (1.0f64 / 1.5).asin().to_degrees();
    assert!(side_angle > critical + 10.0);
    let z_side = -0.5 * cos_t / sin_t; // where the ray meets x = 0.5
    let x_bottom = 0.5 - sin_t * (10.0 + z_side) / cos_t; // where the mirrored ray meets z = −10
    assert!(z_side > -10.0 && x_bottom > -5.0, "{z_side} {x_bottom}");
    let kr = schlick(45f64.to_radians().cos(), 1.0, 1.5);
    assert!((schlick(cos_t, 1.5, 1.0) - kr).abs() < 1e-12);

    for ks in [0.0f32, 0.5, 1.0] {
        let scene = block(ks);
        let got = with_renderer(&scene, 3, |r| r.radiance(&ray_at(45.0)));
        let ks = ks as f64;
        let want = (ks * kr + ks * (1.0 - kr).powi(2)) * d(b);
        assert_close(got, want, &format!("45°, Ks = {ks}"));
        if ks == 0.0 {
            assert_eq!(got, Vec3::ZERO, "Ks = 0: the TIR path is dark");
        }
    }

    // At 10° the refracted ray (θt ≈ 6.6°) entering at the origin would still meet the side face x = 0.5
    // (at z ≈ −4.3, beyond the critical angle), so it enters at x = −2 and reaches the bottom face z = −10
    // at x ≈ −0.84, leaving there at 10° again.
    let scene = block(0.0);
    let deg = 10f64;
    let (s, c) = deg.to_radians().sin_cos();
    let dir = DVec3::new(s, 0.0, -c);
    let entry = DVec3::new(-2.0, 0.0, 0.0);
    let ray = Ray::new((entry - dir).as_vec3(), dir.as_vec3());
    let sin_t = s / 1.5;
    let x_exit = -2.0 + 10.0 * sin_t / (1.0 - sin_t * sin_t).sqrt();
    assert!(x_exit < 0.5 && x_exit > -5.0);
    let kr = schlick(c, 1.0, 1.5);
    let got = with_renderer(&scene, 3, |r| r.radiance(&ray));
    assert_close(got, (1.0 - kr).powi(2) * d(b), "10°, Ks = 0: two transmissions");
}

// ---------------------------------------------------------------------------------------------------------
// 8. Background and a single mirror
// ---------------------------------------------------------------------------------------------------------

/// A ray that hits nothing returns exactly the background colour (empty scene, and the pixels beside a
/// sphere); a mirror plane (Kd = 0, Ks = 0.7, no lights) facing the camera returns Ks·background over the
/// whole frame, since every mirrored ray leaves the scene (Ks scalar: the specular colour Cs does not tint
/// it); at max_depth 0 the mirror shows only its local colour, 0.
#[test]
fn background_and_mirror() {
    let bg = Vec3::new(0.2, 0.4, 0.6);

    let mut empty = Scene::new(front_camera(60.0));
    empty.background = bg;
    let film = with_renderer(&empty, 6, |r| r.render());
    assert!(film.pixels.iter().all(|&p| p == bg), "empty scene");

    let mut scene = Scene::new(front_camera(30.0));
    scene.background = bg;
    let id = scene.add_material(Material::default());
    scene.add_sphere(Vec3::ZERO, 1.0, id);
    scene.add_point_light(Vec3::new(0.0, 0.0, 5.0), Vec3::ONE);
    for (x, y) in [(0, 0), (32, 0), (0, 32), (32, 32), (16, 0), (0, 16)] {
        let (o, dir) = camera_ray(&scene.camera, x, y);
        assert!(ray_sphere(o, dir, DVec3::ZERO, 1.0).is_none());
        assert_eq!(pixel(&scene, 6, x, y), bg, "miss at ({x}, {y})");
    }

    let mut scene = Scene::new(front_camera(60.0));
    scene.background = bg;
    let mirror = Material {
        diffuse: Vec3::ONE,
        kd: 0.0,
        specular: Vec3::new(0.1, 0.2, 0.3),
        ks: 0.7,
        shininess: 10.0,
        ..Material::default()
    };
    let id = scene.add_material(mirror);
    assert!(scene.add_plane(Vec3::ZERO, Vec3::X, Vec3::Y, id));
    let film = with_renderer(&scene, 6, |r| r.render());
    let want = 0.7 * d(bg);
    for y in 0..33 {
        for x in 0..33 {
            assert_close(film.get(x, y), want, &format!("mirror pixel ({x}, {y})"));
        }
    }
    assert_eq!(
        pixel(&scene, 0, 5, 7),
        Vec3::ZERO,
        "max_depth 0: local colour only"
    );
}

// ---------------------------------------------------------------------------------------------------------
// 9. max_depth and parallel mirrors
// ---------------------------------------------------------------------------------------------------------

/// Two parallel mirror planes (z = 0 and z = 10) with the eye and a white light between them on the axis:
/// the centre ray bounces straight back and forth, and at every hit n·L = n·h = 1, so each mirror's local
/// colour is a = Kd·Cd + Ks·Cs. With max_depth D the pixel is the finite series
///   c_D = a_0 + Ks_0·(a_1 + Ks_1·(a_0 + …)) with D + 1 local terms (c_0 = a_0),
/// and for two identical mirrors c_D = a·(1 − Ks^(D+1))/(1 − Ks). The background is black and never seen.
#[test]
fn parallel_mirrors_sum_a_geometric_series() {
    let build = |m0: Material, m1: Material| {
        let mut scene = Scene::new(front_camera(30.0));
        let (i0, i1) = (scene.add_material(m0), scene.add_material(m1));
        assert!(scene.add_plane(Vec3::ZERO, Vec3::X, Vec3::Y, i0));
        let far = Vec3::new(0.0, 0.0, 10.0);
        assert!(scene.add_plane(far, far + Vec3::Y, far + Vec3::X, i1));
        scene.add_point_light(Vec3::new(0.0, 0.0, 5.0), Vec3::ONE);
        scene
    };
    let local = |m: &Material| m.kd as f64 * d(m.diffuse) + m.ks as f64 * d(m.specular);
    let a = Material {
        diffuse: Vec3::new(1.0, 0.5, 0.25),
        kd: 0.3,
        specular: Vec3::new(0.2, 0.4, 0.8),
        ks: 0.5,
        shininess: 10.0,
        ..Material::default()
    };
    let b = Material {
        diffuse: Vec3::new(0.1, 0.9, 0.5),
        kd: 0.6,
        specular: Vec3::ONE,
        ks: 0.8,
        shininess: 3.0,
        ..Material::default()
    };

    // Identical mirrors: the closed form.
    let scene = build(a, a);
    let (la, ks) = (local(&a), a.ks as f64);
    for depth in 0..=8u32 {
        let want = la * (1.0 - ks.powi(depth as i32 + 1)) / (1.0 - ks);
        assert_close(
            pixel(&scene, depth, CENTRE, CENTRE),
            want,
            &format!("identical, D = {depth}"),
        );
    }

    // Different mirrors: the alternating series, summed term by term.
    let scene = build(a, b);
    let ms = [a, b];
    for depth in 0..=8u32 {
        let (mut want, mut weight) = (DVec3::ZERO, 1.0);
        for k in 0..=depth as usize {
            let m = &ms[k % 2];
            want += weight * local(m);
            weight *= m.ks as f64;
        }
        assert_close(
            pixel(&scene, depth, CENTRE, CENTRE),
            want,
            &format!("alternating, D = {depth}"),
        );
    }
}
