//! Stanford PLY meshes: ascii and binary (either byte order), gzipped or not.
//!
//! The header is read with the text [`Lexer`]; the body streams through it too, token by token (ascii) or
//! value by value (binary), in pieces read side by side (`split`), so memory stays at the size of the mesh
//! and a few windows of text whatever counts a header claims.
//! Only the `vertex` x, y, z (and nx, ny, nz, the normals for smooth shading, when there are all three) and
//! the `face` vertex indices are kept; every other element and property is read and dropped, so that the
//! files of scanners (confidence, intensity, edges, materials) load as they are.

use std::fmt;
use std::io::Read;
use std::ops::Range;
use std::path::Path;

use glam::Vec3;

use super::lex::{self, Lexer, Tok, show};
use super::polygon::triangulate;
use super::{MeshData, unit_normal};
use crate::error::{Error, Location, Result};

/// The most elements reserved up front from a header's count: plenty for big meshes, harmless when a
/// corrupt header claims billions.
const MAX_RESERVE: u64 = 1 << 20;

/// What the `format` line accepts, for error messages.
const FORMATS: &str = "\"format ascii 1.0\", \"binary_little_endian 1.0\" or \"binary_big_endian 1.0\"";

/// Loads a PLY mesh (ascii, binary little or big endian; gzipped or not), triangulating its polygons.
///
/// Errors say where: `path:line:col` in the header and in an ascii body, `path: byte N` in a binary body.
pub fn load(path: &Path) -> Result<MeshData> {
    load_on(path, Threads::All)
}

/// [`load`] on `threads`.
pub fn load_on(path: &Path, threads: Threads) -> Result<MeshData> {
    read(path, lex::open(path)?, threads)
}

/// Parses a PLY mesh from `reader` (decompressed); `path` names it in errors.
pub fn parse(path: &Path, reader: Box<dyn Read + Send>) -> Result<MeshData> {
    read(path, reader, Threads::All)
}

/// The threads that read a body: all of the current pool's, in pieces, or the calling one alone, where
/// the others have meshes of their own to read and cutting would only add work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Threads {
    All,
    One,
}

fn read(path: &Path, reader: Box<dyn Read + Send>, threads: Threads) -> Result<MeshData> {
    let mut lx = Lexer::new(path, reader);
    let header = read_header(&mut lx)?;
    if let Format::Binary { .. } = header.format {
        // The body starts right after the line break of `end_header`.
        lx.skip_line()?;
    }
    // On a pool of one thread, pieces would only add the cutting.
    match threads {
        Threads::All if rayon::current_num_threads() > 1 => split::read(lx, &header),
        _ => {
            let mut mesh = MeshData::default();
            read_rest(&mut lx, &header, RowAt::default(), &mut mesh)?;
            Ok(mesh)
        }
    }
}

/// Scratch space for triangulating polygons, reused from face to face so that no face allocates (shared
/// with the OBJ reader).
#[derive(Default)]
pub(super) struct Polygons {
    points: Vec<Vec3>,
    local: Vec<[u32; 3]>,
}

impl Polygons {
    /// Appends the triangles of the polygon `indices` (at least 3, each in range of `vertices.positions`)
    /// to `out`. `normals` are the corners' indices into `vertices.normals` (in range too); they are kept
    /// only if every corner's normal is non-zero, so that a face is smooth or flat as a whole.
    pub(super) fn push(
        &mut self,
        vertices: &MeshData,
        out: &mut MeshData,
        indices: &[u32],
        normals: Option<&[u32]>,
    ) {
        let normals = normals.filter(|n| n.iter().all(|&i| vertices.normals[i as usize] != Vec3::ZERO));
        self.local.clear();
        if indices.len() == 3 {
            self.local.push([0, 1, 2]);
        } else {
            self.points.clear();
            self.points
                .extend(indices.iter().map(|&i| vertices.positions[i as usize]));
            triangulate(&self.points, &mut self.local);
        }
        // `triangulate` numbers the polygon's own corners; map them back to the mesh's vertices and normals.
        for t in &self.local {
            out.triangles.push(t.map(|k| indices[k as usize]));
            out.push_normals(normals.map(|n| t.map(|k| n[k as usize])));
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    Binary { big_endian: bool },
}

/// A scalar type of the header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &[u8]) -> Option<Scalar> {
        Some(match name {
            b"char" | b"int8" => Scalar::I8,
            b"uchar" | b"uint8" => Scalar::U8,
            b"short" | b"int16" => Scalar::I16,
            b"ushort" | b"uint16" => Scalar::U16,
            b"int" | b"int32" => Scalar::I32,
            b"uint" | b"uint32" => Scalar::U32,
            b"float" | b"float32" => Scalar::F32,
            b"double" | b"float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// Bytes a value takes in a binary body.
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// The value of `bytes` (exactly [`Scalar::size`] of them) as `f64`, which holds every integer type
    /// exactly.
    fn decode(self, bytes: &[u8], big_endian: bool) -> f64 {
        macro_rules! decode {
            ($t:ty) => {{
                let bytes = bytes.try_into().expect("a value's bytes");
                (if big_endian {
                    <$t>::from_be_bytes(bytes)
                } else {
                    <$t>::from_le_bytes(bytes)
                }) as f64
            }};
        }
        match self {
            Scalar::I8 => decode!(i8),
            Scalar::U8 => decode!(u8),
            Scalar::I16 => decode!(i16),
            Scalar::U16 => decode!(u16),
            Scalar::I32 => decode!(i32),
            Scalar::U32 => decode!(u32),
            Scalar::F32 => decode!(f32),
            Scalar::F64 => decode!(f64),
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

impl Kind {
    /// Bytes a value takes in a binary body, if that does not depend on a list's length.
    fn size(self) -> Option<usize> {
        match self {
            Kind::Scalar(ty) => Some(ty.size()),
            Kind::List { .. } => None,
        }
    }
}

/// What the reader does with a property.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    Skip,
    /// A vertex coordinate: 0, 1, 2 for x, y, z.
    Axis(usize),
    /// A component of the vertex normal: 0, 1, 2 for nx, ny, nz.
    Normal(usize),
    /// The vertex indices of a face.
    Indices,
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
    role: Role,
    /// The `property` keyword, for errors (only its line and column are used).
    at: Tok,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
    /// The `element` keyword, for errors.
    at: Tok,
}

/// A checked header: it has a vertex element with x, y, z before a face element with vertex indices.
#[derive(Debug)]
struct Header {
    format: Format,
    elements: Vec<Element>,
    vertex: usize,
    face: usize,
    /// The vertex element has nx, ny and nz.
    normals: bool,
}

fn read_header(lx: &mut Lexer) -> Result<Header> {
    const MAGIC: &str = "not a PLY file: expected \"ply\" on the first line";
    match lx.next_token()? {
        Some(tok) if tok.line == 1 && lx.text(&tok) == b"ply" => {}
        Some(tok) => return Err(lx.error_at(&tok, format!("{MAGIC}, found {}", show(lx.text(&tok))))),
        None => {
            return Err(Error::file(
                lx.path(),
                format!("{MAGIC}, found nothing but white space"),
            ));
        }
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let tok = lx.expect_token("\"end_header\"")?;
        match lx.text(&tok) {
            b"format" => {
                if format.is_some() {
                    return Err(lx.error_at(&tok, "expected one \"format\" line, found a second one"));
                }
                format = Some(read_format(lx)?);
            }
            b"comment" | b"obj_info" => lx.skip_line()?,
            b"element" => {
                let name = lx.expect_token("an element name")?;
                let name = String::from_utf8_lossy(lx.text(&name)).into_owned();
                let count =
                    lx.expect_uint(&format!("the number of \"{name}\" elements"), 0..=u32::MAX.into())?;
                elements.push(Element {
                    name,
                    count,
                    props: Vec::new(),
                    at: tok,
                });
            }
            b"property" => {
                let Some(element) = elements.last_mut() else {
                    return Err(lx.error_at(
                        &tok,
                        "expected an \"element\" line before \"property\", found none",
                    ));
                };
                element.props.push(read_property(lx, tok)?);
            }
            b"end_header" => {
                let Some(format) = format else {
                    return Err(lx.error_at(&tok, "expected a \"format\" line in the header, found none"));
                };
                return check_header(lx, format, elements, tok);
            }
            other => {
                return Err(lx.error_at(
                    &tok,
                    format!(
                        "expected \"format\", \"comment\", \"obj_info\", \"element\", \"property\" or \
                         \"end_header\", found {}",
                        show(other)
                    ),
                ));
            }
        }
    }
}

/// The rest of a `format` line.
fn read_format(lx: &mut Lexer) -> Result<Format> {
    let tok = lx.expect_token(FORMATS)?;
    let format = match lx.text(&tok) {
        b"ascii" => Format::Ascii,
        b"binary_little_endian" => Format::Binary { big_endian: false },
        b"binary_big_endian" => Format::Binary { big_endian: true },
        other => return Err(lx.error_at(&tok, format!("expected {FORMATS}, found {}", show(other)))),
    };
    let context = format!("after \"format {}\"", String::from_utf8_lossy(lx.text(&tok)));
    lx.expect_word("1.0", &context)?;
    Ok(format)
}

/// The rest of a `property` line; `at` is its keyword.
fn read_property(lx: &mut Lexer, at: Tok) -> Result<Property> {
    let first = lx.expect_token("a property type or \"list\"")?;
    let kind = if lx.text(&first) == b"list" {
        let tok = lx.expect_token("a list length type")?;
        let count = scalar_type(lx, &tok, "a list length type")?;
        if !count.is_integer() {
            return Err(lx.error_at(
                &tok,
                format!(
                    "expected an integer list length type, found {}",
                    show(lx.text(&tok))
                ),
            ));
        }
        let tok = lx.expect_token("a list item type")?;
        Kind::List {
            count,
            item: scalar_type(lx, &tok, "a list item type")?,
        }
    } else {
        Kind::Scalar(scalar_type(lx, &first, "a property type or \"list\"")?)
    };
    let name = lx.expect_token("a property name")?;
    Ok(Property {
        name: String::from_utf8_lossy(lx.text(&name)).into_owned(),
        kind,
        role: Role::Skip,
        at,
    })
}

/// The type named by `tok`, which stands for `what`.
fn scalar_type(lx: &Lexer, tok: &Tok, what: &str) -> Result<Scalar> {
    Scalar::parse(lx.text(tok)).ok_or_else(|| {
        lx.error_at(
            tok,
            format!(
                "expected {what} (char, uchar, short, ushort, int, uint, float, double, int8, uint8, int16, \
                 uint16, int32, uint32, float32 or float64), found {}",
                show(lx.text(tok))
            ),
        )
    })
}

/// Finds the vertex and face elements, checks them, and marks the properties the reader keeps.
fn check_header(lx: &Lexer, format: Format, mut elements: Vec<Element>, end: Tok) -> Result<Header> {
    let vertex = find_element(lx, &elements, "vertex", &end)?;
    let vertices = &mut elements[vertex];
    for (axis, name) in ["x", "y", "z"].into_iter().enumerate() {
        if !mark_scalar(lx, vertices, name, Role::Axis(axis))? {
            return Err(lx.error_at(
                &vertices.at,
                format!("expected a \"{name}\" property in the \"vertex\" element, found none"),
            ));
        }
    }
    let mut has_normal = [false; 3];
    for (axis, name) in ["nx", "ny", "nz"].into_iter().enumerate() {
        has_normal[axis] = mark_scalar(lx, vertices, name, Role::Normal(axis))?;
    }
    // Part of a normal is a broken file, not a mesh without normals: say so rather than render it flat.
    let normals = has_normal.contains(&true);
    if let Some(axis) = has_normal.iter().position(|&found| !found)
        && normals
    {
        return Err(lx.error_at(
            &vertices.at,
            format!(
                "expected \"nx\", \"ny\" and \"nz\" together in the \"vertex\" element, found no \"{}\"",
                ["nx", "ny", "nz"][axis]
            ),
        ));
    }

    let face = find_element(lx, &elements, "face", &end)?;
    if face < vertex {
        return Err(lx.error_at(
            &elements[face].at,
            "expected the \"vertex\" element before the \"face\" element, found it after",
        ));
    }
    let faces = &mut elements[face];
    let Some(indices) = faces
        .props
        .iter_mut()
        .find(|p| p.name == "vertex_indices" || p.name == "vertex_index")
    else {
        return Err(lx.error_at(
            &faces.at,
            "expected a \"vertex_indices\" list property in the \"face\" element, found none",
        ));
    };
    match indices.kind {
        Kind::List { item, .. } if item.is_integer() => indices.role = Role::Indices,
        Kind::List { .. } => {
            return Err(lx.error_at(
                &indices.at,
                format!(
                    "expected integer items in list \"{}\", found numbers",
                    indices.name
                ),
            ));
        }
        Kind::Scalar(_) => {
            return Err(lx.error_at(
                &indices.at,
                format!(
                    "expected \"property list\" for \"{}\", found a single value",
                    indices.name
                ),
            ));
        }
    }

    Ok(Header {
        format,
        elements,
        vertex,
        face,
        normals,
    })
}

/// Gives the scalar properties called `name` of `element` the role `role`; false if there is none.
fn mark_scalar(lx: &Lexer, element: &mut Element, name: &str, role: Role) -> Result<bool> {
    let mut found = false;
    for prop in element.props.iter_mut().filter(|p| p.name == name) {
        if let Kind::List { .. } = prop.kind {
            return Err(lx.error_at(
                &prop.at,
                format!("expected a number type for vertex property \"{name}\", found a list"),
            ));
        }
        prop.role = role;
        found = true;
    }
    Ok(found)
}

/// The index of the one element called `name`.
fn find_element(lx: &Lexer, elements: &[Element], name: &str, end: &Tok) -> Result<usize> {
    let mut found = elements.iter().enumerate().filter(|(_, e)| e.name == name);
    let Some((index, _)) = found.next() else {
        return Err(lx.error_at(
            end,
            format!("expected an \"element {name}\" line in the header, found \"end_header\""),
        ));
    };
    if let Some((_, second)) = found.next() {
        return Err(lx.error_at(
            &second.at,
            format!("expected one \"{name}\" element, found a second one"),
        ));
    }
    Ok(index)
}

/// The data after the header, ascii or binary, one value at a time. Each read says what the value is for,
/// lazily formatted, so that errors can say what was expected where at no cost on the happy path.
trait Body {
    /// Starts the next element (a line of its own in ascii).
    fn start_row(&mut self);
    /// A number of type `ty`, converted to `f32` (non-finite values are returned for the caller to reject).
    fn float(&mut self, ty: Scalar, what: fmt::Arguments) -> Result<f32>;
    /// A whole number of the integer type `ty` (the header was checked for that).
    fn int(&mut self, ty: Scalar, what: fmt::Arguments) -> Result<i64>;
    /// A value that is not kept.
    fn skip(&mut self, ty: Scalar, what: fmt::Arguments) -> Result<()>;
    /// An error at the value read last.
    fn error(&self, message: String) -> Error;
    /// Checks that nothing follows the last element.
    fn finish(&mut self) -> Result<()>;
}

/// Where a part of the body starts: an element of the header, and a row of it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct RowAt {
    element: usize,
    row: u64,
}

/// The body from `from` to the end of `lx`'s stream, appended to `mesh`, and the check that nothing
/// follows it.
fn read_rest(lx: &mut Lexer, header: &Header, from: RowAt, mesh: &mut MeshData) -> Result<()> {
    match header.format {
        Format::Ascii => read_body(&mut Ascii::new(lx, false), header, from, mesh),
        Format::Binary { big_endian } => read_body(&mut Binary::new(lx, big_endian), header, from, mesh),
    }
}

fn read_body(body: &mut impl Body, header: &Header, from: RowAt, mesh: &mut MeshData) -> Result<()> {
    // The faces read the vertices, so they go apart and join the mesh at the end.
    let mut faces = MeshData::default();
    for (index, element) in header.elements.iter().enumerate().skip(from.element) {
        let rows = if index == from.element { from.row } else { 0 }..element.count;
        if index == header.face {
            read_rows(body, header, index, rows, mesh, &mut faces)?;
        } else {
            read_rows(body, header, index, rows, &MeshData::default(), mesh)?;
        }
    }
    body.finish()?;
    mesh.append(faces);
    Ok(())
}

/// The rows `rows` of element `index`, appended to `out`. A face's vertices are those of `vertices`,
/// which holds all of them by then (the header puts the vertex element first).
fn read_rows(
    body: &mut impl Body,
    header: &Header,
    index: usize,
    rows: Range<u64>,
    vertices: &MeshData,
    out: &mut MeshData,
) -> Result<()> {
    let element = &header.elements[index];
    if index == header.vertex {
        read_vertices(body, element, rows, header.normals, out)
    } else if index == header.face {
        read_faces(body, element, rows, header.normals, vertices, out)
    } else {
        for row in rows {
            body.start_row();
            for prop in &element.props {
                skip_property(body, element, prop, row)?;
            }
        }
        Ok(())
    }
}

/// The positions and, if the header has them, the normals of the vertices `rows`.
fn read_vertices(
    body: &mut impl Body,
    element: &Element,
    rows: Range<u64>,
    normals: bool,
    mesh: &mut MeshData,
) -> Result<()> {
    let reserve = (rows.end - rows.start).min(MAX_RESERVE) as usize;
    mesh.positions.reserve(reserve);
    if normals {
        mesh.normals.reserve(reserve);
    }
    for row in rows {
        body.start_row();
        let mut p = Vec3::ZERO;
        let mut n = Vec3::ZERO;
        for prop in &element.props {
            let (out, axis, what, ty) = match (prop.role, prop.kind) {
                (Role::Axis(axis), Kind::Scalar(ty)) => (&mut p, axis, "coordinate", ty),
                (Role::Normal(axis), Kind::Scalar(ty)) => (&mut n, axis, "normal component", ty),
                _ => {
                    skip_property(body, element, prop, row)?;
                    continue;
                }
            };
            let v = body.float(ty, format_args!("the {} {what} of vertex {row}", prop.name))?;
            // NaN and infinities would poison the bounding boxes, the shading and every ray that meets them.
            if !v.is_finite() {
                return Err(body.error(format!(
                    "expected a finite number for the {} {what} of vertex {row}, found {v}",
                    prop.name
                )));
            }
            out[axis] = v;
        }
        mesh.positions.push(p);
        if normals {
            mesh.normals.push(unit_normal(n));
        }
    }
    Ok(())
}

/// The faces `rows` of `vertices`, triangulated into `out`; with per-vertex normals (`normals`), a face's
/// normal indices are its vertex indices.
fn read_faces(
    body: &mut impl Body,
    element: &Element,
    rows: Range<u64>,
    normals: bool,
    vertices: &MeshData,
    out: &mut MeshData,
) -> Result<()> {
    out.triangles
        .reserve((rows.end - rows.start).min(MAX_RESERVE) as usize);
    let vertex_count = vertices.positions.len() as i64;
    let mut polygons = Polygons::default();
    let mut indices: Vec<u32> = Vec::new();
    for row in rows {
        body.start_row();
        for prop in &element.props {
            match (prop.role, prop.kind) {
                (Role::Indices, Kind::List { count, item }) => {
                    let n = body.int(count, format_args!("the number of vertices of face {row}"))?;
                    if n < 3 {
                        return Err(body.error(format!(
                            "expected 3 or more vertex indices in face {row}, found {n}"
                        )));
                    }
                    indices.clear();
                    for _ in 0..n {
                        let index = body.int(item, format_args!("a vertex index of face {row}"))?;
                        if !(0..vertex_count).contains(&index) {
                            return Err(body.error(format!(
                                "expected a vertex index below {vertex_count}, found {index}"
                            )));
                        }
                        indices.push(index as u32);
                    }
                    polygons.push(vertices, out, &indices, normals.then_some(&indices[..]));
                }
                _ => skip_property(body, element, prop, row)?,
            }
        }
    }
    Ok(())
}

fn skip_property(body: &mut impl Body, element: &Element, prop: &Property, row: u64) -> Result<()> {
    match prop.kind {
        Kind::Scalar(ty) => body.skip(ty, format_args!("\"{}\" of {} {row}", prop.name, element.name)),
        Kind::List { count, item } => {
            let n = body.int(
                count,
                format_args!("the length of list \"{}\" of {} {row}", prop.name, element.name),
            )?;
            if n < 0 {
                return Err(body.error(format!(
                    "expected a length of 0 or more for list \"{}\" of {} {row}, found {n}",
                    prop.name, element.name
                )));
            }
            for _ in 0..n {
                body.skip(
                    item,
                    format_args!("an item of list \"{}\" of {} {row}", prop.name, element.name),
                )?;
            }
            Ok(())
        }
    }
}

/// An ascii body, or a part of one: one element per line, values separated by spaces.
struct Ascii<'a> {
    lx: &'a mut Lexer,
    /// More of the body follows the lexer's text (a piece cut at a line end): its end is a line's end.
    more: bool,
    /// The next token starts a new element, and so must be on a later line.
    new_row: bool,
    /// The line of the current element.
    row_line: u64,
    /// Column of the last token, and the column just after it.
    last_col: u64,
    end_col: u64,
}

impl<'a> Ascii<'a> {
    /// The body from the lexer's position on: the start of a line, or the rest of the `end_header` line,
    /// where data is an extra value, like data after a row.
    fn new(lx: &'a mut Lexer, more: bool) -> Self {
        let (line, col) = lx.position();
        Ascii {
            lx,
            more,
            new_row: true,
            row_line: if col > 1 { line } else { line - 1 },
            last_col: 0,
            end_col: 0,
        }
    }

    /// The next token, which must be on the line of the current element (a new one for a new element):
    /// that way a row with a missing or an extra value is reported on its own line, not where the counts
    /// run out many lines later.
    fn token(&mut self, what: fmt::Arguments) -> Result<Tok> {
        match self.lx.next_token()? {
            Some(tok) if self.new_row => {
                if tok.line == self.row_line {
                    return Err(self.extra(&tok));
                }
                self.row_line = tok.line;
                self.new_row = false;
                self.accept(tok)
            }
            Some(tok) if tok.line == self.row_line => self.accept(tok),
            None if !self.more => Err(self
                .lx
                .error_here(format!("expected {what}, found the end of the file"))),
            _ => Err(Error::at(
                self.lx.path(),
                self.row_line,
                self.end_col,
                format!("expected {what}, found the end of the line"),
            )),
        }
    }

    fn accept(&mut self, tok: Tok) -> Result<Tok> {
        self.last_col = tok.col;
        self.end_col = tok.col + self.lx.text(&tok).len() as u64;
        Ok(tok)
    }

    /// A token on the line of the element read last.
    fn extra(&self, tok: &Tok) -> Error {
        self.lx.error_at(
            tok,
            format!("expected the end of the line, found {}", show(self.lx.text(tok))),
        )
    }

    /// Checks that the last row of a piece ends its line. A piece holds as many lines with tokens as it
    /// has rows, so a token left is on that line.
    fn end_piece(&mut self) -> Result<()> {
        match self.lx.next_token()? {
            Some(tok) => Err(self.extra(&tok)),
            None => Ok(()),
        }
    }

    fn found(&self, tok: &Tok, expected: fmt::Arguments) -> Error {
        self.lx.error_at(
            tok,
            format!("expected {expected}, found {}", show(self.lx.text(tok))),
        )
    }
}

impl Body for Ascii<'_> {
    fn start_row(&mut self) {
        self.new_row = true;
    }

    fn float(&mut self, _ty: Scalar, what: fmt::Arguments) -> Result<f32> {
        let tok = self.token(what)?;
        lex::parse_f32(self.lx.text(&tok))
            .ok_or_else(|| self.found(&tok, format_args!("a number for {what}")))
    }

    fn int(&mut self, _ty: Scalar, what: fmt::Arguments) -> Result<i64> {
        let tok = self.token(what)?;
        lex::parse_int(self.lx.text(&tok))
            .ok_or_else(|| self.found(&tok, format_args!("a whole number for {what}")))
    }

    fn skip(&mut self, ty: Scalar, what: fmt::Arguments) -> Result<()> {
        let tok = self.token(what)?;
        let text = self.lx.text(&tok);
        let ok = if ty.is_integer() {
            lex::parse_int(text).is_some()
        } else {
            lex::parse_f32(text).is_some()
        };
        if ok {
            Ok(())
        } else {
            Err(self.found(&tok, format_args!("a number for {what}")))
        }
    }

    fn error(&self, message: String) -> Error {
        Error::at(self.lx.path(), self.row_line, self.last_col, message)
    }

    fn finish(&mut self) -> Result<()> {
        match self.lx.next_token()? {
            Some(tok) => Err(self.found(&tok, format_args!("the end of the file after the last element"))),
            None => Ok(()),
        }
    }
}

/// A binary body: values packed back to back in the header's order, little or big endian.
struct Binary<'a> {
    lx: &'a mut Lexer,
    big_endian: bool,
    /// Offset of the value read last.
    last: u64,
}

impl<'a> Binary<'a> {
    fn new(lx: &'a mut Lexer, big_endian: bool) -> Self {
        Binary {
            lx,
            big_endian,
            last: 0,
        }
    }

    fn value(&mut self, ty: Scalar, what: fmt::Arguments) -> Result<f64> {
        self.last = self.lx.offset();
        let mut bytes = [0; 8];
        let bytes = &mut bytes[..ty.size()];
        if self.lx.read_exact(bytes)? {
            Ok(ty.decode(bytes, self.big_endian))
        } else {
            Err(self.error(format!("expected {what}, found the end of the file")))
        }
    }
}

impl Body for Binary<'_> {
    fn start_row(&mut self) {}

    fn float(&mut self, ty: Scalar, what: fmt::Arguments) -> Result<f32> {
        Ok(self.value(ty, what)? as f32)
    }

    fn int(&mut self, ty: Scalar, what: fmt::Arguments) -> Result<i64> {
        Ok(self.value(ty, what)? as i64)
    }

    fn skip(&mut self, ty: Scalar, what: fmt::Arguments) -> Result<()> {
        self.value(ty, what).map(drop)
    }

    fn error(&self, message: String) -> Error {
        Error {
            path: Some(self.lx.path().to_path_buf()),
            location: Location::Byte(self.last),
            message,
        }
    }

    fn finish(&mut self) -> Result<()> {
        self.last = self.lx.offset();
        if self.lx.read_exact(&mut [0])? {
            Err(self.error("expected the end of the file after the last element, found more data".into()))
        } else {
            Ok(())
        }
    }
}

mod split;
#[cfg(test)]
mod tests;
