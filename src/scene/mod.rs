//! Scenes: the file formats and the structure-of-arrays store they fill.

mod fingerprint;
mod finite;
mod include;
pub mod lex;
pub mod obj;
pub mod p3f;
pub mod ply;
pub mod polygon;
#[cfg(test)]
mod polygon_checks;
pub mod store;

use std::path::Path;

use glam::Vec3;

pub use finite::Counts;
pub use store::*;

use crate::error::{Error, Result};

/// An indexed triangle mesh as read from a PLY or OBJ file (polygons already triangulated).
///
/// Normals have their own index space because OBJ faces index positions and normals separately (PLY's
/// per-vertex normals share the position indices). A zero entry of `normals` stands for "no normal": PLY
/// exporters write `0 0 0` where they have none, so such a vertex makes its faces flat rather than failing
/// the whole file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`, each checked to be in range.
    pub triangles: Vec<[u32; 3]>,
    /// Unit shading normals, or zero where the file's normal had no length.
    pub normals: Vec<Vec3>,
    /// The corners' indices into `normals` for each triangle, `None` for a flat one (a face where some corner
    /// has no normal, or a zero one). Empty when no triangle has normals (so meshes without them pay
    /// nothing); otherwise parallel to `triangles`.
    pub normal_triangles: Vec<Option<[u32; 3]>>,
}

impl MeshData {
    /// Records the corner normals of the triangle just pushed onto `triangles`.
    fn push_normals(&mut self, normals: Option<[u32; 3]>) {
        if normals.is_some() || !self.normal_triangles.is_empty() {
            // The first smooth triangle gives every flat one before it its `None`.
            self.normal_triangles.resize(self.triangles.len() - 1, None);
            self.normal_triangles.push(normals);
        }
    }

    /// Appends `part`, read apart from this mesh: its vertices after this mesh's, its triangles as they
    /// are (they index the vertices of both).
    fn append(&mut self, part: MeshData) {
        if !(self.normal_triangles.is_empty() && part.normal_triangles.is_empty()) {
            // Either side may have no smooth triangle, and so no list: its triangles are flat.
            self.normal_triangles.resize(self.triangles.len(), None);
            let count = self.triangles.len() + part.triangles.len();
            join(&mut self.normal_triangles, part.normal_triangles);
            self.normal_triangles.resize(count, None);
        }
        join(&mut self.positions, part.positions);
        join(&mut self.normals, part.normals);
        join(&mut self.triangles, part.triangles);
    }
}

/// `b` after `a`; moved, not copied, when `a` is empty (a mesh's first part).
fn join<T>(a: &mut Vec<T>, mut b: Vec<T>) {
    if a.is_empty() {
        *a = b;
    } else {
        a.append(&mut b);
    }
}

/// `n` scaled to unit length, or zero if it has none. Dividing by the largest component first keeps
/// huge and tiny (subnormal) normals from overflowing or underflowing in the length.
fn unit_normal(n: Vec3) -> Vec3 {
    let largest = n.abs().max_element();
    if largest > 0.0 {
        (n / largest).normalize()
    } else {
        Vec3::ZERO
    }
}

/// The kinds of file `whitted` reads, told apart by extension (a `.gz` suffix is looked through).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// A `.p3f` or `.nff` scene.
    Scene,
    /// A `.ply` mesh.
    Ply,
    /// A `.obj` mesh.
    Obj,
}

impl Format {
    /// The format a `--format` value names: `p3f` and `nff` are one grammar.
    pub fn named(name: &str) -> Option<Format> {
        match name {
            "p3f" | "nff" => Some(Format::Scene),
            "ply" => Some(Format::Ply),
            "obj" => Some(Format::Obj),
            _ => None,
        }
    }

    /// The format whose first statement starts `head` (decompressed; comments and blank lines are
    /// skipped): `ply` is PLY; an OBJ-only word (`vn`, `vt`, `o`, `g`, `mtllib`, `usemtl`), or `v` with
    /// numbers on its line, is OBJ (NFF's `v` stands alone); a .p3f/NFF keyword is a scene. `None`
    /// where it is none of these.
    pub fn sniff(head: &[u8]) -> Option<Format> {
        let line = head
            .split(|&b| b == b'\n')
            .map(|l| l.trim_ascii())
            .find(|l| !l.is_empty() && !l.starts_with(b"#"))?;
        let mut words = line.split(|b| b.is_ascii_whitespace()).filter(|w| !w.is_empty());
        let first = words.next()?;
        match first {
            b"ply" => Some(Format::Ply),
            b"vn" | b"vt" | b"vp" | b"o" | b"g" | b"mtllib" | b"usemtl" => Some(Format::Obj),
            b"v" if words.next().is_some() => Some(Format::Obj),
            _ if p3f::KEYWORDS.split(", ").any(|k| k.as_bytes() == first) => Some(Format::Scene),
            _ => None,
        }
    }

    /// The format of `path` from its extension, if it is one of ours.
    pub fn of(path: &Path) -> Option<Format> {
        // Lossy: a name that is not UTF-8 still ends in an ASCII extension.
        let name = path.file_name()?.to_string_lossy().to_ascii_lowercase();
        let name = name.strip_suffix(".gz").unwrap_or(&name);
        let ext = name.rsplit_once('.')?.1;
        match ext {
            "p3f" | "nff" => Some(Format::Scene),
            "ply" => Some(Format::Ply),
            "obj" => Some(Format::Obj),
            _ => None,
        }
    }
}

/// Loads a PLY or OBJ mesh (gzipped or not).
pub fn load_mesh(path: &Path) -> Result<MeshData> {
    load_mesh_on(path, ply::Threads::All)
}

/// [`load_mesh`], a PLY body read on `threads`.
pub fn load_mesh_on(path: &Path, threads: ply::Threads) -> Result<MeshData> {
    match Format::of(path) {
        Some(Format::Ply) => ply::load_on(path, threads),
        Some(Format::Obj) => obj::load(path),
        _ => Err(Error::file(
            path,
            "not a mesh file: expected a .ply, .ply.gz, .obj or .obj.gz name",
        )),
    }
}

/// Loads a scene: a `.p3f`/`.nff` file (gzipped or not), or a bare PLY/OBJ mesh, which gets a camera
/// looking at it, a light and a diffuse material so that it renders as it is.
///
/// ```
/// let scene = whitted::scene::load(std::path::Path::new("scenes/balls_low.p3f")).unwrap();
/// assert_eq!(scene.spheres.radius.len(), 10);
/// ```
pub fn load(path: &Path) -> Result<Scene> {
    match Format::of(path) {
        Some(format) => load_as(path, format),
        None => Err(Error::file(
            path,
            "unknown scene format: expected a .p3f, .nff, .ply or .obj name (optionally .gz), or give \
             the format (--format)",
        )),
    }
}

/// Loads the file `path` as a scene of `format`, whatever its name.
pub fn load_as(path: &Path, format: Format) -> Result<Scene> {
    parse(path, lex::open(path)?, format)
}

/// How standard input is named in errors (`<stdin>:3:7: ...`) and reports.
pub const STDIN: &str = "<stdin>";

/// Reads a scene from `reader` (standard input, say), gzipped or not, in `format`, or in the format
/// its first statement names ([`Format::sniff`]); it is named [`STDIN`] in errors, and relative
/// `include` and `env` paths are relative to the current directory.
pub fn read(reader: Box<dyn std::io::Read + Send>, format: Option<Format>) -> Result<Scene> {
    let name = Path::new(STDIN);
    let mut reader = lex::decompressed(name, reader)?;
    let head = lex::head(name, &mut reader)?;
    let format = match format {
        Some(format) => format,
        None => Format::sniff(&head).ok_or_else(|| {
            Error::file(
                name,
                "cannot tell the scene's format from its first statement: expected a .p3f or NFF \
                 statement, \"ply\" or an OBJ statement; give it with --format p3f|nff|ply|obj",
            )
        })?,
    };
    let reader = std::io::Read::chain(std::io::Cursor::new(head), reader);
    parse(name, Box::new(reader), format)
}

/// Parses `reader` (decompressed) as a scene of `format`; `path` names it in errors and anchors
/// relative paths.
fn parse(path: &Path, reader: Box<dyn std::io::Read + Send>, format: Format) -> Result<Scene> {
    let mesh = match format {
        Format::Scene => return p3f::parse(path, reader),
        Format::Ply => ply::parse(path, reader)?,
        Format::Obj => obj::parse(path, reader)?,
    };
    let scene = p3f::scene_around_mesh(&mesh);
    match scene.overflow_since(Counts::default()) {
        Some(what) => Err(Error::file(
            path,
            format!(
                "a {what} reaches past the largest finite coordinate, {:e}",
                f32::MAX
            ),
        )),
        None => Ok(scene),
    }
}
