//! Wavefront OBJ meshes, gzipped or not.
//!
//! Vertex positions (`v`), normals (`vn`) and faces (`f`) are what a ray tracer without textures uses; every
//! other statement (texture coordinates, groups, materials, lines...) is skipped to the end of its line.
//! OBJ is line oriented, so a statement ends where the next token starts a later line.

use std::io::Read;
use std::path::Path;

use glam::Vec3;

use super::lex::{self, Lexer, Tok, show};
use super::ply::Polygons;
use super::{MeshData, unit_normal};
use crate::error::{Error, Result};

/// Loads an OBJ mesh (gzipped or not), triangulating its polygons.
///
/// Face references `i`, `i/t`, `i//n` and `i/t/n` are accepted; the position index `i` and the normal index
/// `n` are used. Each is 1-based, or negative to count back from the last vertex (or normal) read so far (-1
/// is the last one). A face is smooth if every corner names a normal and none of those is zero, else flat.
/// Errors say `path:line:col`.
pub fn load(path: &Path) -> Result<MeshData> {
    parse(path, lex::open(path)?)
}

/// Parses a OBJ mesh from `reader` (decompressed); `path` names it in errors.
pub fn parse(path: &Path, reader: Box<dyn Read + Send>) -> Result<MeshData> {
    let mut lx = Lexer::new(path, reader);
    let mut mesh = MeshData::default();
    // The triangles apart from the vertices they index, so that a face reads the one while it adds to
    // the other.
    let mut faces = MeshData::default();
    let mut polygons = Polygons::default();
    let mut face = Face::default();
    while let Some(tok) = lx.next_token()? {
        match lx.text(&tok) {
            b"v" => {
                check_room(&lx, &tok, mesh.positions.len())?;
                let p = read_triple(&mut lx, &tok, ["coordinates", "coordinate"])?;
                mesh.positions.push(p);
                // An optional w (and anything after it) does not matter.
                lx.skip_line()?;
            }
            b"vn" => {
                check_room(&lx, &tok, mesh.normals.len())?;
                let n = read_triple(&mut lx, &tok, ["normal components", "normal component"])?;
                mesh.normals.push(unit_normal(n));
                lx.skip_line()?;
            }
            b"f" => {
                read_face(&mut lx, &tok, &mesh, &mut face)?;
                // Corners without normals beside ones with: the face is flat, as if none had one.
                let normals = (face.normals.len() == face.positions.len()).then_some(&face.normals[..]);
                polygons.push(&mesh, &mut faces, &face.positions, normals);
            }
            _ => lx.skip_line()?,
        }
    }
    if faces.triangles.is_empty() {
        return Err(Error::file(
            path,
            "expected at least one face (an \"f\" line), found none",
        ));
    }
    mesh.append(faces);
    Ok(mesh)
}

/// The corners of one face, as 0-based indices; `normals` holds those of the corners that name one.
#[derive(Default)]
struct Face {
    positions: Vec<u32>,
    normals: Vec<u32>,
}

/// Checks that a `v` or `vn` (the keyword `tok`) after `len` others can still be referenced: indices are u32.
fn check_room(lx: &Lexer, tok: &Tok, len: usize) -> Result<()> {
    if len > u32::MAX as usize {
        return Err(lx.error_at(
            tok,
            format!(
                "expected at most 4294967296 {} lines, found more",
                show(lx.text(tok))
            ),
        ));
    }
    Ok(())
}

/// The next token if it is on `line`: a statement ends with its line.
fn next_on(lx: &mut Lexer, line: u64) -> Result<Option<Tok>> {
    match lx.peek()? {
        Some(tok) if tok.line == line => lx.next_token(),
        _ => Ok(None),
    }
}

/// The x, y, z after the keyword `v` or `vn`, named `nouns` (plural, singular) in errors.
fn read_triple(lx: &mut Lexer, keyword: &Tok, [plural, noun]: [&str; 2]) -> Result<Vec3> {
    let mut p = Vec3::ZERO;
    for (axis, name) in ["x", "y", "z"].into_iter().enumerate() {
        let Some(tok) = next_on(lx, keyword.line)? else {
            let keyword_text = show(lx.text(keyword));
            return Err(lx.error_at(
                keyword,
                format!("expected 3 {plural} after {keyword_text}, found {axis}"),
            ));
        };
        let text = lx.text(&tok);
        match lex::parse_f32(text) {
            // NaN and infinities would poison the bounding boxes, the shading and every ray that meets them.
            Some(value) if value.is_finite() => p[axis] = value,
            Some(_) => {
                return Err(lx.error_at(
                    &tok,
                    format!(
                        "expected a finite number for the {name} {noun}, found {}",
                        show(text)
                    ),
                ));
            }
            None => {
                return Err(lx.error_at(
                    &tok,
                    format!("expected a number for the {name} {noun}, found {}", show(text)),
                ));
            }
        }
    }
    Ok(p)
}

/// The vertex references after `f` (the keyword) into `face`, resolved against what `mesh` has so far.
fn read_face(lx: &mut Lexer, f: &Tok, mesh: &MeshData, face: &mut Face) -> Result<()> {
    face.positions.clear();
    face.normals.clear();
    while let Some(tok) = next_on(lx, f.line)? {
        let (position, normal) = vertex_ref(lx, &tok, mesh)?;
        face.positions.push(position);
        face.normals.extend(normal);
    }
    if face.positions.len() < 3 {
        return Err(lx.error_at(
            f,
            format!(
                "expected 3 or more vertices after \"f\", found {}",
                face.positions.len()
            ),
        ));
    }
    Ok(())
}

/// One `i`, `i/t`, `i//n` or `i/t/n` reference, resolved to a 0-based position index and, for the forms
/// that have one, a 0-based normal index.
fn vertex_ref(lx: &Lexer, tok: &Tok, mesh: &MeshData) -> Result<(u32, Option<u32>)> {
    let text = lx.text(tok);
    let mut parts = text.split(|&b| b == b'/');
    let int = lex::parse_int;
    // The texture index is not used, but a malformed reference is still an error.
    let parsed = match (
        parts.next().and_then(int),
        parts.next(),
        parts.next(),
        parts.next(),
    ) {
        (Some(i), None, _, _) => Some((i, None)),
        (Some(i), Some(t), None, _) if int(t).is_some() => Some((i, None)),
        (Some(i), Some(t), Some(n), None) if t.is_empty() || int(t).is_some() => int(n).map(|n| (i, Some(n))),
        _ => None,
    };
    let Some((index, normal)) = parsed else {
        return Err(lx.error_at(
            tok,
            format!(
                "expected a vertex reference (i, i/t, i//n or i/t/n), found {}",
                show(text)
            ),
        ));
    };
    let position = resolve(index, mesh.positions.len()).ok_or_else(|| {
        let n = mesh.positions.len();
        let message = if n == 0 {
            format!("expected a \"v\" line before vertex index {index}, found none")
        } else {
            format!("expected a vertex index between 1 and {n} (or -{n}..-1), found {index}")
        };
        lx.error_at(tok, message)
    })?;
    let normal = match normal {
        None => None,
        Some(index) => Some(resolve(index, mesh.normals.len()).ok_or_else(|| {
            let n = mesh.normals.len();
            let message = if n == 0 {
                format!("expected a \"vn\" line before normal index {index}, found none")
            } else {
                format!("expected a normal index between 1 and {n} (or -{n}..-1), found {index}")
            };
            lx.error_at(tok, message)
        })?),
    };
    Ok((position, normal))
}

/// A 1-based or negative (relative) OBJ index into a list of `count` items, as a 0-based one if in range. 0
/// is neither: it resolves to `count`, out of range like the others.
fn resolve(index: i64, count: usize) -> Option<u32> {
    let n = count as i64;
    let resolved = if index > 0 { index - 1 } else { n + index };
    (0..n).contains(&resolved).then_some(resolved as u32)
}

#[cfg(test)]
mod tests;
