//! Scenes: the file formats and the structure-of-arrays store they fill.

mod fingerprint;
pub mod lex;
pub mod obj;
pub mod p3f;
pub mod ply;
pub mod polygon;
pub mod store;

use std::path::Path;

use glam::Vec3;

pub use store::*;

use crate::error::{Error, Result};

/// An indexed triangle mesh as read from a PLY or OBJ file (polygons already triangulated).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshData {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`, each checked to be in range.
    pub triangles: Vec<[u32; 3]>,
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
    /// The format of `path` from its extension, if it is one of ours.
    pub fn of(path: &Path) -> Option<Format> {
        let name = path.file_name()?.to_str()?.to_ascii_lowercase();
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
    match Format::of(path) {
        Some(Format::Ply) => ply::load(path),
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
        Some(Format::Scene) => p3f::load(path),
        Some(Format::Ply | Format::Obj) => {
            let mesh = load_mesh(path)?;
            Ok(p3f::scene_around_mesh(&mesh))
        }
        None => Err(Error::file(
            path,
            "unknown scene format: expected a .p3f, .nff, .ply or .obj name (optionally .gz)",
        )),
    }
}
