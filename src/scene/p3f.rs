//! The `.p3f` / NFF scene parser: one function per keyword, reading tokens (never lines) from the
//! streaming [`Lexer`], so a polygon may spread over any number of lines and a 3 MB scene never sits in
//! memory as text. The grammar is `docs/scene-format.md` (Haines' NFF plus the course's extensions).

use std::io::Read;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::MeshData;
use super::finite::overflow_message;
use super::include::{self, Include};
use super::lex::{self, Lexer, Tok, show};
use super::polygon::triangulate;
use super::store::{AccelHint, Camera, MAX_LIGHT_SAMPLES, Material, MaterialId, Scene, check_resolution};
use crate::error::{Error, Result};

/// The keywords a scene may use, for the unknown-keyword message.
pub(crate) const KEYWORDS: &str =
    "v, b, bclr, env, accel, spp, l, lq, f, s, p, pp, c, box, pl, mesh, include";
/// More vertices than any sane polygon or mesh has; larger counts are typos or garbage.
const MAX_COUNT: u64 = 1 << 30;
/// Vertex buffers grow with the data instead of trusting a count this much larger than what was read.
const TRUSTED_CAPACITY: usize = 1 << 16;

/// Loads a `.p3f` or `.nff` scene file (gzipped or not).
pub fn load(path: &Path) -> Result<Scene> {
    parse(path, lex::open(path)?)
}

/// Parses a scene from `reader`; `path` names it in errors and anchors relative `include`/`env` paths.
pub fn parse(path: &Path, reader: Box<dyn Read + Send>) -> Result<Scene> {
    let mut parser = Parser {
        lx: Lexer::new(path, reader),
        dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
        scene: Scene::new(Camera::new(Vec3::Z, Vec3::ZERO, Vec3::Y, 45.0, 1, 1)),
        material: None,
        camera_seen: false,
        light_samples: 0,
        points: Vec::new(),
        normals: Vec::new(),
        tris: Vec::new(),
        includes: Vec::new(),
    };
    parser.run()?;
    Ok(parser.scene)
}

/// A scene that shows a bare mesh: the dragon workload's framing (camera on the bounding box's diagonal,
/// 40° vertical field of view, a white light above and behind the eye) with a grey diffuse material.
pub fn scene_around_mesh(mesh: &MeshData) -> Scene {
    let mut bounds = crate::geometry::aabb::Aabb::EMPTY;
    for &p in &mesh.positions {
        bounds.grow(p);
    }
    let (center, diag) = if bounds.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (bounds.center(), bounds.extent().length().max(1e-6))
    };
    let from = center + Vec3::new(0.0, 0.25, 1.0).normalize() * 0.8 * diag;
    let mut scene = Scene::new(Camera::new(from, center, Vec3::Y, 40.0, 1280, 720));
    scene.background = Vec3::splat(0.1);
    scene.add_point_light(center + Vec3::new(1.0, 2.0, 1.5) * diag, Vec3::ONE);
    let material = scene.add_material(Material::default());
    scene
        .add_mesh(mesh, material)
        .expect("mesh loaders check their indices");
    scene
}

/// "vertex i of n of the polygon", formatted only when an error needs it.
#[derive(Clone, Copy)]
struct Vertex {
    index: usize,
    count: usize,
    of: &'static str,
}

impl std::fmt::Display for Vertex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "vertex {} of {} of the {}", self.index, self.count, self.of)
    }
}

struct Parser {
    lx: Lexer,
    dir: PathBuf,
    scene: Scene,
    material: Option<MaterialId>,
    camera_seen: bool,
    /// The light samples so far, bounded by [`MAX_LIGHT_SAMPLES`].
    light_samples: u64,
    // Scratch buffers reused by every polygon.
    points: Vec<Vec3>,
    normals: Vec<Vec3>,
    tris: Vec<[u32; 3]>,
    /// Includes read and not yet loaded.
    includes: Vec<Include>,
}

impl Parser {
    fn run(&mut self) -> Result<()> {
        let statements = self.statements();
        // An include's error comes before any later statement's.
        self.load_includes()?;
        let any = statements?;
        if !any {
            return Err(Error::file(
                self.lx.path(),
                "empty scene file: expected a \"v\" camera block and objects",
            ));
        }
        if !self.camera_seen {
            return Err(self
                .lx
                .error_here("expected a \"v\" camera block, found the end of the file"));
        }
        Ok(())
    }

    /// The statements to the end of the file; whether there was one.
    fn statements(&mut self) -> Result<bool> {
        let mut any = false;
        while let Some(tok) = self.lx.next_token()? {
            any = true;
            self.statement(tok)?;
        }
        Ok(any)
    }

    /// One statement; what it added must lie within the range of `f32` ([`Scene::overflow_since`]).
    /// The includes read so far are loaded before a statement that adds triangles after theirs.
    fn statement(&mut self, tok: Tok) -> Result<()> {
        if !self.includes.is_empty() && matches!(self.lx.text(&tok), b"p" | b"pp" | b"mesh") {
            self.load_includes()?;
        }
        let before = self.scene.counts();
        self.statement_body(tok)?;
        match self.scene.overflow_since(before) {
            Some(what) => Err(self.lx.error_at(&tok, overflow_message(what))),
            None => Ok(()),
        }
    }

    /// Loads the includes read so far, side by side ([`include::load`]).
    fn load_includes(&mut self) -> Result<()> {
        let includes = std::mem::take(&mut self.includes);
        include::load(&includes, self.lx.path(), &mut self.scene)
    }

    fn statement_body(&mut self, tok: Tok) -> Result<()> {
        match self.lx.text(&tok) {
            b"v" => self.view(tok),
            b"b" | b"bclr" => {
                self.scene.background = self.color("the background colour")?;
                Ok(())
            }
            b"env" => self.env(),
            b"accel" => self.accel(),
            b"spp" => {
                self.scene.spp = self.lx.expect_uint("the samples per pixel", 0..=1 << 16)? as u32;
                Ok(())
            }
            b"l" => self.point_light(tok),
            b"lq" => self.quad_light(tok),
            b"f" => self.material(tok),
            b"s" => self.sphere(),
            b"p" => self.polygon(tok, false),
            b"pp" => self.polygon(tok, true),
            b"c" => self.cone(tok),
            b"box" => self.cuboid(tok),
            b"pl" => self.plane(tok),
            b"mesh" => self.mesh(),
            b"include" => self.include(),
            text if text
                .first()
                .is_some_and(|b| b.is_ascii_digit() || matches!(b, b'-' | b'+' | b'.')) =>
            {
                Err(self.lx.error_at(
                    &tok,
                    format!(
                        "expected a keyword, found the number {} (does the statement before it have more \
                         numbers than it announced?)",
                        show(text)
                    ),
                ))
            }
            text => Err(self.lx.error_at(
                &tok,
                format!("unknown keyword {}; expected one of {KEYWORDS}", show(text)),
            )),
        }
    }

    /// The current material, creating the default grey one for objects that come before any `f`.
    fn current_material(&mut self) -> MaterialId {
        *self
            .material
            .get_or_insert_with(|| self.scene.add_material(Material::default()))
    }

    fn color(&mut self, what: &str) -> Result<Vec3> {
        let tok = self.lx.peek()?;
        let c = self.lx.expect_vec3(what)?;
        if c.min_element() < 0.0 {
            let tok = tok.expect("a number was read");
            return Err(self
                .lx
                .error_at(&tok, format!("{what} must not be negative, found {c}")));
        }
        Ok(c)
    }

    fn view(&mut self, v: Tok) -> Result<()> {
        if self.camera_seen {
            return Err(self
                .lx
                .error_at(&v, "a second \"v\" camera block; a scene has one camera"));
        }
        let ctx = "in the \"v\" camera block";
        let from_tok = self.lx.expect_word("from", ctx)?;
        let from = self.lx.expect_vec3("the eye position (from)")?;
        let at_tok = self.lx.expect_word("at", ctx)?;
        let at = self.lx.expect_vec3("the look-at point (at)")?;
        let up_tok = self.lx.expect_word("up", ctx)?;
        let up = self.lx.expect_vec3("the up vector")?;
        let angle_tok = self.lx.expect_word("angle", ctx)?;
        let fov_y = self.lx.expect_f32("the field of view (angle)")?;
        self.lx.expect_word("hither", ctx)?;
        let hither = self.lx.expect_f32("the near distance (hither)")?;
        let res_tok = self.lx.expect_word("resolution", ctx)?;
        let width = self.lx.expect_uint("the image width", 0..=u32::MAX as u64)? as u32;
        let height = self.lx.expect_uint("the image height", 0..=u32::MAX as u64)? as u32;
        if let Err(e) = check_resolution(width, height) {
            return Err(self.lx.error_at(&res_tok, e));
        }
        let mut camera = Camera::new(from, at, up, fov_y, width, height);
        camera.hither = hither;
        let mut aperture_tok = None;
        let mut focal_tok = None;
        if self.peek_word(b"aperture")? {
            aperture_tok = self.lx.next_token()?;
            camera.aperture = self.lx.expect_f32("the aperture")?;
        }
        if self.peek_word(b"focal")? {
            focal_tok = self.lx.next_token()?;
            camera.focal = self.lx.expect_f32("the focal distance ratio")?;
        }
        if let Err(e) = camera.validate() {
            // Point at the line that holds the offending value.
            let tok = match e.field {
                "from" => from_tok,
                "at" => at_tok,
                "up" => up_tok,
                "angle" => angle_tok,
                "aperture" => aperture_tok.unwrap_or(v),
                "focal" => focal_tok.unwrap_or(v),
                _ => res_tok,
            };
            return Err(self.lx.error_at(&tok, e.message));
        }
        self.scene.camera = camera;
        self.camera_seen = true;
        Ok(())
    }

    fn peek_word(&mut self, word: &[u8]) -> Result<bool> {
        Ok(match self.lx.peek()? {
            Some(tok) => self.lx.text(&tok) == word,
            None => false,
        })
    }

    fn path_token(&mut self, what: &str) -> Result<(Tok, PathBuf)> {
        let tok = self.lx.expect_token(what)?;
        let name = String::from_utf8_lossy(self.lx.text(&tok)).into_owned();
        Ok((tok, self.dir.join(name)))
    }

    fn env(&mut self) -> Result<()> {
        let (tok, dir) = self.path_token("a directory name after \"env\"")?;
        if !dir.is_dir() {
            self.scene.warnings.push(format!(
                "{}:{}:{}: environment map directory \"{}\" not found; using the background colour",
                self.lx.path().display(),
                tok.line,
                tok.col,
                dir.display()
            ));
        }
        self.scene.env = Some(dir);
        Ok(())
    }

    fn accel(&mut self) -> Result<()> {
        let value = self
            .lx
            .expect_uint("the accelerator (0 none, 1 grid, 2 BVH, 3 4-wide BVH)", 0..=3)?;
        self.scene.accel = Some(match value {
            0 => AccelHint::None,
            1 => AccelHint::Grid,
            2 => AccelHint::Bvh2,
            _ => AccelHint::Bvh4,
        });
        Ok(())
    }

    /// Counts the `samples` of the light at `tok` (`what` says how many, for the error) against
    /// [`MAX_LIGHT_SAMPLES`].
    fn light_samples(&mut self, tok: &Tok, samples: u64, what: &str) -> Result<()> {
        let total = self.light_samples + samples;
        if total > MAX_LIGHT_SAMPLES {
            return Err(self.lx.error_at(
                tok,
                format!(
                    "{what} the scene's light samples to {total}, more than the {MAX_LIGHT_SAMPLES} \
                     allowed: expected fewer lights or smaller grids"
                ),
            ));
        }
        self.light_samples = total;
        Ok(())
    }

    fn point_light(&mut self, l: Tok) -> Result<()> {
        let position = self.lx.expect_vec3("the light position")?;
        // NFF lights may omit the colour: white.
        let color = if self.lx.peek_is_number()? {
            self.color("the light colour")?
        } else {
            Vec3::ONE
        };
        self.light_samples(&l, 1, "this point light brings")?;
        self.scene.add_point_light(position, color);
        Ok(())
    }

    fn quad_light(&mut self, lq: Tok) -> Result<()> {
        let corner = self.lx.expect_vec3("the area light corner")?;
        let edge_tok = self.lx.peek()?;
        let edge_u = self.lx.expect_vec3("the area light's first edge")?;
        let edge_v = self.lx.expect_vec3("the area light's second edge")?;
        let color = self.color("the area light colour")?;
        let grid = self
            .lx
            .expect_uint("the area light's grid resolution", 1..=1024)? as u32;
        if edge_u.cross(edge_v).length_squared() == 0.0 {
            let tok = edge_tok.expect("a number was read");
            return Err(self.lx.error_at(
                &tok,
                "the area light's edges are parallel or zero: the quad has no area",
            ));
        }
        let samples = u64::from(grid) * u64::from(grid);
        self.light_samples(
            &lq,
            samples,
            &format!("this area light's {grid} x {grid} samples bring"),
        )?;
        self.scene.area_lights.push(super::QuadLight {
            corner,
            edge_u,
            edge_v,
            color,
            grid,
        });
        Ok(())
    }

    /// `f`: 8 numbers (NFF), 11 (p3f) or 12 (p3f plus our roughness).
    fn material(&mut self, f: Tok) -> Result<()> {
        let mut values = [(f, 0.0f32); 13];
        let mut n = 0;
        while n < values.len() && self.lx.peek_is_number()? {
            let tok = self.lx.peek()?.expect("peeked");
            values[n] = (tok, self.lx.expect_f32("the material")?);
            n += 1;
        }
        let v = |i: usize| values[i].1;
        let (diffuse, kd, specular, ks, rest) = match n {
            8 => {
                let c = Vec3::new(v(0), v(1), v(2));
                (c, v(3), c, v(4), 5)
            }
            11 | 12 => (
                Vec3::new(v(0), v(1), v(2)),
                v(3),
                Vec3::new(v(4), v(5), v(6)),
                v(7),
                8,
            ),
            _ => {
                return Err(self.lx.error_at(
                    &f,
                    format!(
                        "expected 8 numbers (NFF: r g b Kd Ks shine T ior) or 11 (p3f: Rd Gd Bd Kd Rs Gs Bs Ks \
                         shine T ior, optionally a 12th: roughness) after \"f\", found {n}"
                    ),
                ));
            }
        };
        if let Some(&(tok, x)) = values[..n].iter().find(|&&(_, x)| x < 0.0) {
            return Err(self
                .lx
                .error_at(&tok, format!("material values must not be negative, found {x}")));
        }
        let (shininess, transmission, mut ior) = (v(rest), v(rest + 1), v(rest + 2));
        if transmission > 0.0 && ior <= 0.0 {
            let tok = values[rest + 2].0;
            return Err(self.lx.error_at(
                &tok,
                format!("expected a positive index of refraction for a transparent material, found {ior}"),
            ));
        }
        if transmission == 0.0 {
            // Opaque materials often carry `ior 0` (SPD and course files): it means nothing.
            ior = 1.0;
        }
        let roughness = (n == 12).then(|| v(11));
        let id = self.scene.add_material(Material {
            diffuse,
            kd,
            specular,
            ks,
            shininess,
            transmission,
            ior,
            roughness,
        });
        self.material = Some(id);
        Ok(())
    }

    fn sphere(&mut self) -> Result<()> {
        let center = self.lx.expect_vec3("the sphere centre")?;
        let tok = self.lx.peek()?;
        let radius = self.lx.expect_f32("the sphere radius")?;
        if radius == 0.0 {
            let tok = tok.expect("a number was read");
            return Err(self
                .lx
                .error_at(&tok, "expected a non-zero sphere radius, found 0"));
        }
        let m = self.current_material();
        self.scene.add_sphere(center, radius, m);
        Ok(())
    }

    /// A vertex count: at least `min`, at most [`MAX_COUNT`].
    fn count(&mut self, what: &str, min: u64) -> Result<usize> {
        let (tok, n) = self.lx.expect_int(what)?;
        if n < min as i64 || n as u64 > MAX_COUNT {
            return Err(self.lx.error_at(
                &tok,
                format!("expected {what} between {min} and {MAX_COUNT}, found {n}"),
            ));
        }
        Ok(n as usize)
    }

    /// `p N` (flat) or `pp N` (with per-vertex normals; `p` is the keyword), triangulated by ear clipping.
    fn polygon(&mut self, p: Tok, smooth: bool) -> Result<()> {
        let n = self.count("the polygon's vertex count", 3)?;
        self.points.clear();
        self.normals.clear();
        for i in 0..n {
            // Described lazily: the text is only formatted if there is an error to report.
            let what = Vertex {
                index: i + 1,
                count: n,
                of: "polygon",
            };
            self.points.push(self.lx.expect_vec3(what)?);
            if smooth {
                let tok = self.lx.peek()?;
                let normal = self.lx.expect_vec3(format_args!("the normal of {what}"))?;
                if normal.length_squared() == 0.0 {
                    let tok = tok.expect("a number was read");
                    return Err(self
                        .lx
                        .error_at(&tok, format!("the normal of {what} is the zero vector")));
                }
                self.normals.push(normal.normalize());
            }
        }
        self.tris.clear();
        if !triangulate(&self.points, &mut self.tris).exact {
            self.scene.warnings.push(format!(
                "{}:{}:{}: polygon of {n} vertices intersects itself or is degenerate: its {} triangles may \
                 overlap or stick out of it",
                self.lx.path().display(),
                p.line,
                p.col,
                self.tris.len()
            ));
        }
        let m = self.current_material();
        for t in &self.tris {
            let [a, b, c] = t.map(|i| self.points[i as usize]);
            if smooth {
                let normals = t.map(|i| self.normals[i as usize]);
                self.scene.add_smooth_triangle([a, b, c], normals, m);
            } else {
                self.scene.add_triangle(a, b, c, m);
            }
        }
        Ok(())
    }

    fn cone(&mut self, c: Tok) -> Result<()> {
        let base = self.lx.expect_vec3("the cone's base centre")?;
        let base_radius = self.lx.expect_f32("the cone's base radius")?;
        let apex = self.lx.expect_vec3("the cone's apex centre")?;
        let apex_radius = self.lx.expect_f32("the cone's apex radius")?;
        let message = if (base_radius < 0.0) != (apex_radius < 0.0)
            && base_radius != 0.0
            && apex_radius != 0.0
        {
            Some(format!(
                "cone radii must both be negative (inside only) or both non-negative, found {base_radius} and \
                 {apex_radius}"
            ))
        } else if base_radius == 0.0 && apex_radius == 0.0 {
            Some("a cone needs a non-zero radius at one end at least".to_string())
        } else if base == apex {
            Some("the cone's base and apex are the same point".to_string())
        } else {
            None
        };
        if let Some(message) = message {
            return Err(self.lx.error_at(&c, message));
        }
        let m = self.current_material();
        self.scene.add_cone(base, base_radius, apex, apex_radius, m);
        Ok(())
    }

    fn cuboid(&mut self, b: Tok) -> Result<()> {
        let min = self.lx.expect_vec3("the box's smallest corner")?;
        let max = self.lx.expect_vec3("the box's largest corner")?;
        if min.cmpgt(max).any() {
            return Err(self.lx.error_at(
                &b,
                format!("the box's smallest corner {min} exceeds its largest corner {max}: negative size"),
            ));
        }
        let m = self.current_material();
        self.scene.add_box(min, max, m);
        Ok(())
    }

    fn plane(&mut self, pl: Tok) -> Result<()> {
        let p0 = self.lx.expect_vec3("the plane's first point")?;
        let p1 = self.lx.expect_vec3("the plane's second point")?;
        let p2 = self.lx.expect_vec3("the plane's third point")?;
        let m = self.current_material();
        if !self.scene.add_plane(p0, p1, p2, m) {
            return Err(self.lx.error_at(
                &pl,
                "the plane's three points are collinear: they define no plane",
            ));
        }
        Ok(())
    }

    /// `mesh NV NF`, NV vertices then NF index triples (1-based; negative counts back from the end).
    fn mesh(&mut self) -> Result<()> {
        let nv = self.count("the mesh's vertex count", 1)?;
        let nf = self.count("the mesh's triangle count", 0)?;
        let mut positions = Vec::with_capacity(nv.min(TRUSTED_CAPACITY));
        for i in 0..nv {
            positions.push(self.lx.expect_vec3(Vertex {
                index: i + 1,
                count: nv,
                of: "mesh",
            })?);
        }
        let m = self.current_material();
        for _ in 0..nf {
            let mut v = [Vec3::ZERO; 3];
            for corner in &mut v {
                let (tok, i) = self.lx.expect_int("a mesh vertex index")?;
                let k = if i > 0 { i - 1 } else { nv as i64 + i };
                if i == 0 || k < 0 || k >= nv as i64 {
                    return Err(self.lx.error_at(
                        &tok,
                        format!("expected a vertex index between 1 and {nv} (or -{nv}..-1), found {i}"),
                    ));
                }
                *corner = positions[k as usize];
            }
            self.scene.add_triangle(v[0], v[1], v[2], m);
        }
        Ok(())
    }

    /// `include model.{ply,obj}[.gz] [scale S] [translate X Y Z]`: its mesh is loaded with the
    /// includes around it ([`mod@include`]).
    fn include(&mut self) -> Result<()> {
        let (tok, path) = self.path_token("a file name after \"include\"")?;
        let mut scale = 1.0;
        let mut translate = Vec3::ZERO;
        loop {
            if self.peek_word(b"scale")? {
                self.lx.next_token()?;
                let tok = self.lx.peek()?;
                scale = self.lx.expect_f32("the include scale")?;
                if scale == 0.0 {
                    let tok = tok.expect("a number was read");
                    return Err(self.lx.error_at(&tok, "expected a non-zero scale, found 0"));
                }
            } else if self.peek_word(b"translate")? {
                self.lx.next_token()?;
                translate = self.lx.expect_vec3("the include translation")?;
            } else {
                break;
            }
        }
        if !path.is_file() {
            let reason = match std::fs::metadata(&path) {
                Ok(_) => "it is not a file".to_string(),
                Err(e) => crate::files::io_reason(&e),
            };
            return Err(self.lx.error_at(
                &tok,
                format!("cannot open include file \"{}\": {reason}", path.display()),
            ));
        }
        let material = self.current_material();
        self.includes.push(Include {
            tok,
            path,
            scale,
            translate,
            material,
        });
        Ok(())
    }
}
