//! Wavefront OBJ meshes, gzipped or not.
//!
//! Only vertex positions (`v`) and faces (`f`) matter to a ray tracer without textures; every other
//! statement (texture coordinates, normals, groups, materials, lines...) is skipped to the end of its line.
//! OBJ is line oriented, so a statement ends where the next token starts a later line.

use std::path::Path;

use glam::Vec3;

use super::MeshData;
use super::lex::{self, Lexer, Tok, show};
use super::ply::Polygons;
use crate::error::{Error, Result};

/// Loads an OBJ mesh (gzipped or not), triangulating its polygons.
///
/// Face references `i`, `i/t`, `i//n` and `i/t/n` are accepted; only the position index `i` is used. It is
/// 1-based, or negative to count back from the last vertex read so far (-1 is the last one). Errors say
/// `path:line:col`.
pub fn load(path: &Path) -> Result<MeshData> {
    let mut lx = Lexer::open(path)?;
    let mut mesh = MeshData::default();
    let mut polygons = Polygons::default();
    let mut face: Vec<u32> = Vec::new();
    while let Some(tok) = lx.next_token()? {
        match lx.text(&tok) {
            b"v" => {
                // Indices are u32: a vertex beyond that could not be referenced.
                if mesh.positions.len() > u32::MAX as usize {
                    return Err(lx.error_at(&tok, "expected at most 4294967296 vertices, found more"));
                }
                mesh.positions.push(read_vertex(&mut lx, &tok)?);
                // An optional w (and anything after it) does not matter.
                lx.skip_line()?;
            }
            b"f" => {
                read_face(&mut lx, &tok, mesh.positions.len(), &mut face)?;
                polygons.push(&mesh.positions, &face, &mut mesh.triangles);
            }
            _ => lx.skip_line()?,
        }
    }
    if mesh.triangles.is_empty() {
        return Err(Error::file(
            path,
            "expected at least one face (an \"f\" line), found none",
        ));
    }
    Ok(mesh)
}

/// The next token if it is on `line`: a statement ends with its line.
fn next_on(lx: &mut Lexer, line: u32) -> Result<Option<Tok>> {
    match lx.peek()? {
        Some(tok) if tok.line == line => lx.next_token(),
        _ => Ok(None),
    }
}

/// The x, y, z after `v` (the keyword).
fn read_vertex(lx: &mut Lexer, v: &Tok) -> Result<Vec3> {
    let mut p = Vec3::ZERO;
    for (axis, name) in ["x", "y", "z"].into_iter().enumerate() {
        let Some(tok) = next_on(lx, v.line)? else {
            return Err(lx.error_at(v, format!("expected 3 coordinates after \"v\", found {axis}")));
        };
        let text = lx.text(&tok);
        match lex::parse_f32(text) {
            // NaN and infinities would poison the bounding boxes and every ray that meets them.
            Some(value) if value.is_finite() => p[axis] = value,
            Some(_) => {
                return Err(lx.error_at(
                    &tok,
                    format!(
                        "expected a finite number for the {name} coordinate, found {}",
                        show(text)
                    ),
                ));
            }
            None => {
                return Err(lx.error_at(
                    &tok,
                    format!(
                        "expected a number for the {name} coordinate, found {}",
                        show(text)
                    ),
                ));
            }
        }
    }
    Ok(p)
}

/// The vertex references after `f` (the keyword) into `face`, as 0-based indices below `vertex_count`.
fn read_face(lx: &mut Lexer, f: &Tok, vertex_count: usize, face: &mut Vec<u32>) -> Result<()> {
    face.clear();
    while let Some(tok) = next_on(lx, f.line)? {
        face.push(vertex_ref(lx, &tok, vertex_count)?);
    }
    if face.len() < 3 {
        return Err(lx.error_at(
            f,
            format!("expected 3 or more vertices after \"f\", found {}", face.len()),
        ));
    }
    Ok(())
}

/// One `i`, `i/t`, `i//n` or `i/t/n` reference, resolved to a 0-based vertex index.
fn vertex_ref(lx: &Lexer, tok: &Tok, vertex_count: usize) -> Result<u32> {
    let text = lx.text(tok);
    let mut parts = text.split(|&b| b == b'/');
    let position = parts.next().and_then(lex::parse_int);
    let is_int = |part: &[u8]| lex::parse_int(part).is_some();
    // The texture and normal indices are not used, but a malformed reference is still an error.
    let well_formed = match (parts.next(), parts.next(), parts.next()) {
        (None, _, _) => true,
        (Some(t), None, _) => is_int(t),
        (Some(t), Some(n), None) => (t.is_empty() || is_int(t)) && is_int(n),
        _ => false,
    };
    let index = match position {
        Some(index) if well_formed => index,
        _ => {
            return Err(lx.error_at(
                tok,
                format!(
                    "expected a vertex reference (i, i/t, i//n or i/t/n), found {}",
                    show(text)
                ),
            ));
        }
    };
    let n = vertex_count as i64;
    // 0 is neither a 1-based nor a relative index; it resolves to `n`, out of range like the others.
    let resolved = if index > 0 { index - 1 } else { n + index };
    if !(0..n).contains(&resolved) {
        return Err(lx.error_at(
            tok,
            format!("expected a vertex index between 1 and {n} (or -{n}..-1), found {index}"),
        ));
    }
    Ok(resolved as u32)
}

#[cfg(test)]
mod tests {
    use std::io::Write;

    use flate2::Compression;
    use flate2::write::GzEncoder;

    use super::*;
    use crate::error::Location;
    use crate::scene::polygon::triangulate;

    fn load_bytes(name: &str, bytes: &[u8]) -> Result<MeshData> {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        load(&path)
    }

    fn load_text(text: &str) -> Result<MeshData> {
        load_bytes("mesh.obj", text.as_bytes())
    }

    const SQUARE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

    /// The triangles `triangulate` gives for the polygon of mesh vertices `first..first + n`.
    fn polygon(positions: &[Vec3], first: u32, n: u32) -> Vec<[u32; 3]> {
        let mut local = vec![];
        triangulate(&positions[first as usize..(first + n) as usize], &mut local);
        local.iter().map(|t| t.map(|k| k + first)).collect()
    }

    #[test]
    fn triangles_quads_and_concave_polygons() {
        // An L-shaped hexagon: a fan from its first corner would cover the notch.
        let l_shape = "v 0 0 1\nv 2 0 1\nv 2 1 1\nv 1 1 1\nv 1 2 1\nv 0 2 1\n";
        let mesh = load_text(&format!("{SQUARE}{l_shape}f 1 2 3\nf 1 2 3 4\nf 5 6 7 8 9 10\n")).unwrap();
        assert_eq!(mesh.positions.len(), 10);
        assert_eq!(mesh.positions[8], Vec3::new(1.0, 2.0, 1.0));
        let mut want = vec![[0, 1, 2]];
        want.extend(polygon(&mesh.positions, 0, 4));
        want.extend(polygon(&mesh.positions, 4, 6));
        assert_eq!(mesh.triangles, want);
        assert_eq!(mesh.triangles.len(), 1 + 2 + 4);
        let area: f32 = mesh.triangles[3..]
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                (b - a).cross(c - a).length() / 2.0
            })
            .sum();
        assert!(
            (area - 3.0).abs() < 1e-6,
            "the L covers 3 unit squares, not {area}"
        );
    }

    #[test]
    fn reference_forms_and_negative_indices() {
        let text = format!(
            "{SQUARE}f 1/1/1 2/2/2 3/3/3\nf 1//1 3//3 4//4\nf 2/5 3/6 4/7\nf -4 -3 -2\nv 5 5 5\nf -1 -2/1 -3//2\n"
        );
        let mesh = load_text(&text).unwrap();
        assert_eq!(mesh.positions.len(), 5);
        assert_eq!(
            mesh.triangles,
            [[0, 1, 2], [0, 2, 3], [1, 2, 3], [0, 1, 2], [4, 3, 2]]
        );
    }

    #[test]
    fn other_statements_are_skipped() {
        let text = "\
# a comment
mtllib scene.mtl
o thing
g group one
s off
usemtl red
v 1 2 3 1.0
v 4 5 6 # trailing comment
v 7 8 9
vt 0.5 0.5
vn 0 0 1
vp 0.5
l 1 2
p 1
curv 0 1 2 3
f 1/1/1 2/1/1 3/1/1 # comment after a face
frobnicate 1 2 3 4
";
        let want = MeshData {
            positions: vec![
                Vec3::new(1.0, 2.0, 3.0),
                Vec3::new(4.0, 5.0, 6.0),
                Vec3::new(7.0, 8.0, 9.0),
            ],
            triangles: vec![[0, 1, 2]],
        };
        assert_eq!(load_text(text).unwrap(), want);
        let mut gz = GzEncoder::new(Vec::new(), Compression::default());
        gz.write_all(text.as_bytes()).unwrap();
        assert_eq!(load_bytes("mesh.obj.gz", &gz.finish().unwrap()).unwrap(), want);
    }

    /// Loads the square plus `line` (line 5), expecting an error there.
    fn error_on_line_5(line: &str) -> Error {
        let e = load_text(&format!("{SQUARE}{line}\nf 1 2 3\n")).unwrap_err();
        assert_eq!(e.line(), Some(5), "{e}");
        e
    }

    #[test]
    fn index_errors() {
        let e = error_on_line_5("f 1 2 7");
        assert_eq!(
            e.message,
            "expected a vertex index between 1 and 4 (or -4..-1), found 7"
        );
        assert_eq!(e.location, Location::LineCol(5, 7));
        let e = error_on_line_5("f 0 1 2");
        assert_eq!(
            e.message,
            "expected a vertex index between 1 and 4 (or -4..-1), found 0"
        );
        let e = error_on_line_5("f 1 2 -5/1");
        assert_eq!(
            e.message,
            "expected a vertex index between 1 and 4 (or -4..-1), found -5"
        );
        // Negative indices count back from the vertices read so far, not from the whole file.
        let e = load_text("v 0 0 0\nf -1 -2 -3\nv 1 0 0\nv 0 1 0\n").unwrap_err();
        assert_eq!(e.location, Location::LineCol(2, 6));
    }

    #[test]
    fn face_errors() {
        let e = error_on_line_5("f 1 2");
        assert_eq!(e.message, "expected 3 or more vertices after \"f\", found 2");
        assert_eq!(e.location, Location::LineCol(5, 1));
        let e = error_on_line_5("f 1 x 3");
        assert_eq!(
            e.message,
            "expected a vertex reference (i, i/t, i//n or i/t/n), found \"x\""
        );
        assert_eq!(e.location, Location::LineCol(5, 5));
        for bad in [
            "f 1 2 3/1/1/1",
            "f 1 2/ 3",
            "f 1 2 3//",
            "f 1 /2 3",
            "f 1 2 3/x/1",
        ] {
            let e = error_on_line_5(bad);
            assert!(e.message.starts_with("expected a vertex reference"), "{bad}: {e}");
        }
    }

    #[test]
    fn vertex_errors() {
        let e = error_on_line_5("v 1 abc 3");
        assert_eq!(e.message, "expected a number for the y coordinate, found \"abc\"");
        assert_eq!(e.location, Location::LineCol(5, 5));
        let e = error_on_line_5("v nan 0 0");
        assert_eq!(
            e.message,
            "expected a finite number for the x coordinate, found \"nan\""
        );
        let e = error_on_line_5("v 0 0 -inf");
        assert!(e.message.starts_with("expected a finite number for the z"), "{e}");
        let e = error_on_line_5("v 1 2");
        assert_eq!(e.message, "expected 3 coordinates after \"v\", found 2");
        assert_eq!(e.location, Location::LineCol(5, 1));
    }

    #[test]
    fn no_faces() {
        let e = load_text(SQUARE).unwrap_err();
        assert_eq!(
            e.message,
            "expected at least one face (an \"f\" line), found none"
        );
        assert_eq!(e.location, Location::File);
    }
}
