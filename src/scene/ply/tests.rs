use std::io::Write;

use flate2::Compression;
use flate2::write::GzEncoder;

use super::*;
use crate::scene::polygon_checks::assert_quad_split;

/// A value of the test mesh, written as text or as bytes of its type.
#[derive(Clone, Copy)]
enum V {
    U8(u8),
    I32(i32),
    F32(f32),
    F64(f64),
}

const HEADER: &str = "\
element vertex 5
property float x
property float y
property uchar confidence
property double z
element edge 1
property int vertex1
property int vertex2
property list uchar float weights
element face 2
property list uchar int vertex_indices
property uchar material
end_header
";

/// A quad and a triangle, with a vertex property, an element and a face property that are skipped.
fn rows() -> Vec<Vec<V>> {
    use V::*;
    vec![
        vec![F32(0.0), F32(0.0), U8(10), F64(0.0)],
        vec![F32(1.0), F32(0.0), U8(20), F64(0.0)],
        vec![F32(1.0), F32(1.0), U8(30), F64(0.5)],
        vec![F32(0.0), F32(1.0), U8(40), F64(0.5)],
        vec![F32(2.0), F32(0.5), U8(50), F64(0.25)],
        vec![I32(0), I32(1), U8(2), F32(0.5), F32(0.25)],
        vec![U8(4), I32(0), I32(1), I32(2), I32(3), U8(7)],
        vec![U8(3), I32(1), I32(4), I32(2), U8(0)],
    ]
}

fn header(format: &str, body: &str) -> String {
    format!("ply\nformat {format} 1.0\ncomment a quad and a triangle\nobj_info test\n{body}")
}

fn ascii(rows: &[Vec<V>]) -> Vec<u8> {
    ascii_with(HEADER, rows)
}

/// An ascii file with the elements and properties `elements` (up to `end_header`).
fn ascii_with(elements: &str, rows: &[Vec<V>]) -> Vec<u8> {
    let mut text = header("ascii", elements);
    for row in rows {
        let values: Vec<String> = row
            .iter()
            .map(|v| match *v {
                V::U8(v) => v.to_string(),
                V::I32(v) => v.to_string(),
                V::F32(v) => v.to_string(),
                V::F64(v) => v.to_string(),
            })
            .collect();
        text.push_str(&values.join(" "));
        text.push('\n');
    }
    text.into_bytes()
}

fn binary(rows: &[Vec<V>], big_endian: bool) -> Vec<u8> {
    binary_with(HEADER, rows, big_endian)
}

/// A binary file with the elements and properties `elements` (up to `end_header`).
fn binary_with(elements: &str, rows: &[Vec<V>], big_endian: bool) -> Vec<u8> {
    let format = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut bytes = header(format, elements).into_bytes();
    for v in rows.iter().flatten() {
        let (le, be) = match *v {
            V::U8(v) => (vec![v], vec![v]),
            V::I32(v) => (v.to_le_bytes().to_vec(), v.to_be_bytes().to_vec()),
            V::F32(v) => (v.to_le_bytes().to_vec(), v.to_be_bytes().to_vec()),
            V::F64(v) => (v.to_le_bytes().to_vec(), v.to_be_bytes().to_vec()),
        };
        bytes.extend(if big_endian { be } else { le });
    }
    bytes
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = GzEncoder::new(Vec::new(), Compression::default());
    encoder.write_all(bytes).unwrap();
    encoder.finish().unwrap()
}

/// Loads `bytes` as a file. The body is also read whole on one thread (window 0 in a failure), and in
/// windows of a few bytes, cut into many pieces, which must give the same mesh or the same error.
fn load_bytes(bytes: &[u8]) -> Result<MeshData> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("mesh.ply");
    std::fs::write(&path, bytes).unwrap();
    let whole = load(&path);
    assert_same(&whole, &load_on(&path, Threads::One), 0);
    for window in [1, 2, 3, 5, 8, 13, 40, 100, 1000] {
        if let Some(cut) = load_in_windows(&path, window) {
            assert_same(&whole, &cut, window);
        }
    }
    whole
}

/// `path` read with its body cut into windows of `window` bytes; `None` where the header is wrong.
fn load_in_windows(path: &Path, window: usize) -> Option<Result<MeshData>> {
    let mut lx = Lexer::open(path).unwrap();
    let header = read_header(&mut lx).ok()?;
    if header.format != Format::Ascii && lx.skip_line().is_err() {
        return None;
    }
    Some(split::read_in_windows(lx, &header, window))
}

#[track_caller]
fn assert_same(whole: &Result<MeshData>, cut: &Result<MeshData>, window: usize) {
    match (whole, cut) {
        (Ok(a), Ok(b)) => assert!(a == b, "window {window}: the meshes differ"),
        (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string(), "window {window}"),
        (Ok(_), Err(e)) => panic!("window {window}: read whole, but in pieces: {e}"),
        (Err(e), Ok(_)) => panic!("window {window}: read in pieces, but whole: {e}"),
    }
}

fn load_text(text: &str) -> Result<MeshData> {
    load_bytes(text.as_bytes())
}

/// The positions of [`rows`].
fn positions() -> Vec<Vec3> {
    vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, 0.5),
        Vec3::new(0.0, 1.0, 0.5),
        Vec3::new(2.0, 0.5, 0.25),
    ]
}

/// Asserts that `mesh` has the positions and faces of [`rows`]: the quad 0-1-2-3 split along either
/// diagonal, then the triangle 1-4-2.
#[track_caller]
fn assert_faces(mesh: &MeshData) {
    assert_eq!(mesh.positions, positions());
    assert_eq!(mesh.triangles.len(), 3, "{:?}", mesh.triangles);
    assert_quad_split(&mesh.triangles[..2], [0, 1, 2, 3]);
    assert_eq!(mesh.triangles[2], [1, 4, 2]);
}

/// Asserts that `mesh` is the mesh of [`rows`]: its faces and no normals.
#[track_caller]
fn assert_expected(mesh: &MeshData) {
    assert_faces(mesh);
    assert!(mesh.normals.is_empty() && mesh.normal_triangles.is_empty());
}

#[test]
fn ascii_and_binary_agree() {
    let rows = rows();
    let mesh = load_bytes(&ascii(&rows)).unwrap();
    assert_expected(&mesh);
    assert_eq!(load_bytes(&binary(&rows, false)).unwrap(), mesh);
    assert_eq!(load_bytes(&binary(&rows, true)).unwrap(), mesh);
}

#[test]
fn gzipped() {
    let rows = rows();
    assert_expected(&load_bytes(&gzip(&ascii(&rows))).unwrap());
    assert_expected(&load_bytes(&gzip(&binary(&rows, true))).unwrap());
}

/// Header and body can use CR LF line breaks; the binary body starts after the LF.
#[test]
fn crlf_header() {
    let rows = rows();
    let text = String::from_utf8(ascii(&rows)).unwrap().replace('\n', "\r\n");
    assert_expected(&load_text(&text).unwrap());
    let bytes = binary(&rows, false);
    let body = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let header = String::from_utf8(bytes[..body].to_vec())
        .unwrap()
        .replace('\n', "\r\n");
    let bytes = [header.as_bytes(), &bytes[body..]].concat();
    assert_expected(&load_bytes(&bytes).unwrap());
}

#[test]
fn bad_magic() {
    let e = load_text("plx\nformat ascii 1.0\n").unwrap_err();
    assert_eq!(
        e.message,
        "not a PLY file: expected \"ply\" on the first line, found \"plx\""
    );
    assert_eq!(e.location, Location::LineCol(1, 1));
    let e = load_text("").unwrap_err();
    assert!(e.message.starts_with("not a PLY file"), "{e}");
}

#[test]
fn bad_format_line() {
    let e = load_text("ply\nformat binary 1.0\nend_header\n").unwrap_err();
    assert_eq!(
        e.message,
        "expected \"format ascii 1.0\", \"binary_little_endian 1.0\" or \"binary_big_endian 1.0\", \
         found \"binary\""
    );
    assert_eq!(e.location, Location::LineCol(2, 8));
    let e = load_text("ply\nformat ascii 2.0\nend_header\n").unwrap_err();
    assert_eq!(
        e.message,
        "expected \"1.0\" after \"format ascii\", found \"2.0\""
    );
    assert_eq!(e.line(), Some(2));
}

#[test]
fn header_errors() {
    let e = load_text("ply\nformat ascii 1.0\nproperty float x\nend_header\n").unwrap_err();
    assert_eq!(
        e.message,
        "expected an \"element\" line before \"property\", found none"
    );
    assert_eq!(e.line(), Some(3));
    let e = load_text("ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\n").unwrap_err();
    assert!(
        e.message
            .starts_with("expected a property type or \"list\" (char"),
        "{e}"
    );
    assert_eq!(e.location, Location::LineCol(4, 10));
    let e = load_text("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n").unwrap_err();
    assert_eq!(e.message, "expected \"end_header\", found the end of the file");
    let e = load_text("ply\nformat ascii 1.0\nelements vertex 1\n").unwrap_err();
    assert!(e.message.contains("found \"elements\""), "{e}");
    assert_eq!(e.line(), Some(3));
}

#[test]
fn missing_elements_and_properties() {
    let e = load_text(&header(
        "ascii",
        "element vertex 0\nproperty float x\nproperty float y\nend_header\n",
    ))
    .unwrap_err();
    assert_eq!(
        e.message,
        "expected a \"z\" property in the \"vertex\" element, found none"
    );
    assert_eq!(e.line(), Some(5));
    let vertex = "element vertex 0\nproperty float x\nproperty float y\nproperty float z\n";
    let e = load_text(&header("ascii", &format!("{vertex}end_header\n"))).unwrap_err();
    assert_eq!(
        e.message,
        "expected an \"element face\" line in the header, found \"end_header\""
    );
    assert_eq!(e.line(), Some(9));
    let faces = "element face 0\nproperty list uchar float vertex_indices\n";
    let e = load_text(&header("ascii", &format!("{vertex}{faces}end_header\n"))).unwrap_err();
    assert_eq!(
        e.message,
        "expected integer items in list \"vertex_indices\", found numbers"
    );
    assert_eq!(e.line(), Some(10));
    let faces = "element face 0\nproperty list uchar int vertex_index\n";
    let e = load_text(&header("ascii", &format!("{faces}{vertex}end_header\n"))).unwrap_err();
    assert!(
        e.message.starts_with("expected the \"vertex\" element before"),
        "{e}"
    );
    let mesh = load_text(&header("ascii", &format!("{vertex}{faces}end_header\n"))).unwrap();
    assert_eq!(mesh, MeshData::default());
}

/// The ascii rows of the test mesh as text, one string per line of the body.
fn ascii_lines() -> Vec<String> {
    let text = String::from_utf8(ascii(&rows())).unwrap();
    text.lines().map(str::to_string).collect()
}

fn with_line(lines: &[String], index: usize, line: &str) -> String {
    let mut lines = lines.to_vec();
    lines[index] = line.to_string();
    lines.join("\n") + "\n"
}

/// Line numbers of the test mesh's ascii body (1-based).
const FIRST_FACE_LINE: u64 = 24;

#[test]
fn index_out_of_range() {
    let lines = ascii_lines();
    assert_eq!(lines[FIRST_FACE_LINE as usize - 1], "4 0 1 2 3 7");
    let e = load_text(&with_line(&lines, FIRST_FACE_LINE as usize - 1, "4 0 1 9 3 7")).unwrap_err();
    assert_eq!(e.message, "expected a vertex index below 5, found 9");
    assert_eq!(e.location, Location::LineCol(FIRST_FACE_LINE, 7));
    let e = load_text(&with_line(&lines, FIRST_FACE_LINE as usize, "3 1 -1 2 0")).unwrap_err();
    assert_eq!(e.message, "expected a vertex index below 5, found -1");
    assert_eq!(e.line(), Some(FIRST_FACE_LINE + 1));

    let mut rows = rows();
    rows[6][2] = V::I32(5);
    let e = load_bytes(&binary(&rows, true)).unwrap_err();
    assert_eq!(e.message, "expected a vertex index below 5, found 5");
    assert!(matches!(e.location, Location::Byte(_)), "{e}");
}

#[test]
fn face_with_two_vertices() {
    let lines = ascii_lines();
    let e = load_text(&with_line(&lines, FIRST_FACE_LINE as usize, "2 1 4 0")).unwrap_err();
    assert_eq!(e.message, "expected 3 or more vertex indices in face 1, found 2");
    assert_eq!(e.location, Location::LineCol(FIRST_FACE_LINE + 1, 1));
}

#[test]
fn rows_with_missing_or_extra_values() {
    let lines = ascii_lines();
    // Vertex 1 lacks its z: reported at the end of its own line, not where the data runs out.
    let e = load_text(&with_line(&lines, 18, "1 0 20")).unwrap_err();
    assert_eq!(
        e.message,
        "expected the z coordinate of vertex 1, found the end of the line"
    );
    assert_eq!(e.location, Location::LineCol(19, 7));
    let e = load_text(&with_line(&lines, 18, "1 0 20 0 0")).unwrap_err();
    assert_eq!(e.message, "expected the end of the line, found \"0\"");
    assert_eq!(e.location, Location::LineCol(19, 10));
    let e = load_text(&with_line(&lines, 18, "1 zero 20 0")).unwrap_err();
    assert_eq!(
        e.message,
        "expected a number for the y coordinate of vertex 1, found \"zero\""
    );
    assert_eq!(e.location, Location::LineCol(19, 3));
    let e = load_text(&with_line(&lines, 22, "0 1 2 0.5 x")).unwrap_err();
    assert_eq!(
        e.message,
        "expected a number for an item of list \"weights\" of edge 0, found \"x\""
    );
    let e = load_text(&(lines.join("\n") + "\n0\n")).unwrap_err();
    assert_eq!(
        e.message,
        "expected the end of the file after the last element, found \"0\""
    );
    assert_eq!(e.line(), Some(26));
}

#[test]
fn truncated_ascii() {
    let lines = ascii_lines();
    let text = lines[..lines.len() - 1].join("\n");
    let e = load_text(&text).unwrap_err();
    assert_eq!(
        e.message,
        "expected the number of vertices of face 1, found the end of the file"
    );
    assert_eq!(e.line(), Some(FIRST_FACE_LINE));
}

#[test]
fn truncated_binary() {
    let bytes = binary(&rows(), false);
    // Cut the last value (the material of face 1, one byte) and half of the index before it.
    let e = load_bytes(&bytes[..bytes.len() - 3]).unwrap_err();
    assert_eq!(
        e.message,
        "expected a vertex index of face 1, found the end of the file"
    );
    assert_eq!(e.location, Location::Byte(bytes.len() as u64 - 5));
    // One byte too many is an error too: the counts must describe the data.
    let e = load_bytes(&[&bytes[..], &[0]].concat()).unwrap_err();
    assert_eq!(e.location, Location::Byte(bytes.len() as u64));
}

#[test]
fn nan_coordinate() {
    let lines = ascii_lines();
    let e = load_text(&with_line(&lines, 19, "1 nan 30 0.5")).unwrap_err();
    assert_eq!(
        e.message,
        "expected a finite number for the y coordinate of vertex 2, found NaN"
    );
    assert_eq!(e.location, Location::LineCol(20, 3));
    let mut rows = rows();
    rows[3][3] = V::F64(f64::INFINITY);
    let e = load_bytes(&binary(&rows, false)).unwrap_err();
    assert_eq!(
        e.message,
        "expected a finite number for the z coordinate of vertex 3, found inf"
    );
    assert!(matches!(e.location, Location::Byte(_)), "{e}");
}

/// A count the data does not hold is an end-of-file error, without reserving memory for it.
#[test]
fn huge_element_count() {
    let text = header(
        "ascii",
        "element vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n\
         element face 4000000000\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n0 1 0\n",
    );
    let e = load_text(&text).unwrap_err();
    assert_eq!(
        e.message,
        "expected the x coordinate of vertex 3, found the end of the file"
    );
    let e = load_text(&text.replace("4000000000", "5000000000")).unwrap_err();
    assert!(e.message.contains("between 0 and 4294967295"), "{e}");
}

#[test]
fn corrupt_gzip() {
    let mut text = header(
        "ascii",
        "element vertex 3000\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1000\nproperty list uchar int vertex_indices\nend_header\n",
    );
    for i in 0..3000 {
        text.push_str(&format!("{} {} {}\n", i as f32 * 0.5, i % 7, i % 13));
    }
    for i in 0..1000 {
        text.push_str(&format!("3 {} {} {}\n", 3 * i, 3 * i + 1, 3 * i + 2));
    }
    let mut bytes = gzip(text.as_bytes());
    assert_eq!(load_bytes(&bytes).unwrap().triangles.len(), 1000);
    let middle = bytes.len() / 2;
    for b in &mut bytes[middle..middle + 8] {
        *b ^= 0x5a;
    }
    assert!(load_bytes(&bytes).is_err());
}

/// The vertex and face elements of a quad and a triangle with normals of type `ty` (a skipped property
/// between them).
fn normals_header(ty: &str) -> String {
    format!(
        "element vertex 5\nproperty float x\nproperty float y\nproperty float z\nproperty {ty} nx\n\
         property uchar confidence\nproperty {ty} ny\nproperty {ty} nz\n\
         element face 2\nproperty list uchar int vertex_indices\nend_header\n"
    )
}

/// Rows for [`normals_header`], the normals made by `n`. Vertex 4's normal is zero: the triangle, which
/// uses it, is flat; the quad is smooth.
fn normals_rows(n: fn(i32) -> V) -> Vec<Vec<V>> {
    use V::*;
    let vertex = |[x, y, z]: [f32; 3], [nx, ny, nz]: [i32; 3]| {
        vec![F32(x), F32(y), F32(z), n(nx), U8(9), n(ny), n(nz)]
    };
    vec![
        vertex([0.0, 0.0, 0.0], [0, 0, 2]),
        vertex([1.0, 0.0, 0.0], [3, 0, 4]),
        vertex([1.0, 1.0, 0.5], [0, -3, 4]),
        vertex([0.0, 1.0, 0.5], [1, 1, 1]),
        vertex([2.0, 0.5, 0.25], [0, 0, 0]),
        vec![U8(4), I32(0), I32(1), I32(2), I32(3)],
        vec![U8(3), I32(1), I32(4), I32(2)],
    ]
}

/// Asserts that `mesh` is the mesh of [`normals_rows`]; the unit normals are worked out by hand.
#[track_caller]
fn assert_normals_mesh(mesh: &MeshData) {
    let third = 1.0 / 3f32.sqrt();
    let want = [
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.6, 0.0, 0.8),
        Vec3::new(0.0, -0.6, 0.8),
        Vec3::splat(third),
        Vec3::ZERO,
    ];
    assert_eq!(mesh.normals.len(), want.len());
    for (got, want) in mesh.normals.iter().zip(want) {
        assert!((*got - want).length() < 1e-6, "{:?}", mesh.normals);
    }
    assert_faces(mesh);
    // Per-vertex normals: a smooth triangle's normal indices are its vertex indices.
    let quad = &mesh.triangles[..2];
    assert_eq!(mesh.normal_triangles, [Some(quad[0]), Some(quad[1]), None]);
}

/// Normals of any numeric type, in ascii and in binary of both byte orders.
#[test]
fn vertex_normals() {
    // Each header type with the maker of its values.
    type Make = fn(i32) -> V;
    let types: [(&str, Make); 3] = [
        ("float", |v| V::F32(v as f32)),
        ("double", |v| V::F64(v as f64)),
        ("int", V::I32),
    ];
    for (ty, n) in types {
        let (elements, rows) = (normals_header(ty), normals_rows(n));
        assert_normals_mesh(&load_bytes(&ascii_with(&elements, &rows)).unwrap());
        for big_endian in [false, true] {
            let bytes = binary_with(&elements, &rows, big_endian);
            assert_normals_mesh(&load_bytes(&bytes).unwrap());
        }
    }
}

#[test]
fn normal_errors() {
    let elements = normals_header("float");
    let text = String::from_utf8(ascii_with(&elements, &normals_rows(|v| V::F32(v as f32)))).unwrap();
    let lines: Vec<String> = text.lines().map(str::to_string).collect();
    assert_eq!(lines[16], "1 0 0 3 9 0 4");
    let e = load_text(&with_line(&lines, 16, "1 0 0 3 9 nan 4")).unwrap_err();
    assert_eq!(
        e.message,
        "expected a finite number for the ny normal component of vertex 1, found NaN"
    );
    assert_eq!(e.location, Location::LineCol(17, 11));
    let e = load_text(&with_line(&lines, 16, "1 0 0 3 9 0")).unwrap_err();
    assert_eq!(
        e.message,
        "expected the nz normal component of vertex 1, found the end of the line"
    );

    // Vertex 1's nz in binary: after vertex 0 (3 floats, a double, a byte, 2 doubles: 37 bytes) and
    // vertex 1's first 29.
    let mut rows = normals_rows(|v| V::F64(v as f64));
    rows[1][6] = V::F64(f64::INFINITY);
    let bytes = binary_with(&normals_header("double"), &rows, true);
    let body = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let e = load_bytes(&bytes).unwrap_err();
    assert_eq!(
        e.message,
        "expected a finite number for the nz normal component of vertex 1, found inf"
    );
    assert_eq!(e.location, Location::Byte(body as u64 + 37 + 29));

    // Part of a normal, or a list for one, is an error in the header.
    let e = load_text(&header("ascii", &elements.replace("property float nz\n", ""))).unwrap_err();
    assert_eq!(
        e.message,
        "expected \"nx\", \"ny\" and \"nz\" together in the \"vertex\" element, found no \"nz\""
    );
    assert_eq!(e.line(), Some(5));
    let e = load_text(&header(
        "ascii",
        &elements.replace("float nx", "list uchar float nx"),
    ))
    .unwrap_err();
    assert_eq!(
        e.message,
        "expected a number type for vertex property \"nx\", found a list"
    );
    assert_eq!(e.line(), Some(9));
}

/// A Stanford model shipped in `scenes/models` (always there: the tests do not skip).
fn dragon(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes/models")
        .join(name)
}

fn check_indices(mesh: &MeshData) {
    let n = mesh.positions.len() as u32;
    assert!(mesh.triangles.iter().flatten().all(|&i| i < n));
    // The dragons carry no normals: they render flat, as the golden images recorded them.
    assert!(mesh.normals.is_empty() && mesh.normal_triangles.is_empty());
}

#[test]
fn stanford_dragon_res2() {
    let mesh = load(&dragon("dragon_vrip_res2.ply.gz")).unwrap();
    assert_eq!(mesh.positions.len(), 100_250);
    assert_eq!(mesh.triangles.len(), 202_520);
    check_indices(&mesh);
}

/// The full dragon: 871,414 triangles (the test suite runs in release builds, where this is quick).
#[test]
fn stanford_dragon_full() {
    let mesh = load(&dragon("dragon_vrip.ply.gz")).unwrap();
    assert_eq!(mesh.positions.len(), 437_645);
    assert_eq!(mesh.triangles.len(), 871_414);
    check_indices(&mesh);
}

/// The header of the many-row test mesh: vertices with normals, an element without properties and one
/// that is skipped between them and the faces, and a face property after the indices.
fn many_rows_header(vertices: usize, faces: usize) -> String {
    header("ascii", &many_rows_elements(vertices, faces))
}

fn many_rows_elements(vertices: usize, faces: usize) -> String {
    format!(
        "element vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\nelement empty 7\n\
         element edge 3\nproperty int a\nproperty int b\nelement face {faces}\n\
         property list uchar int vertex_indices\nproperty uchar flag\nend_header\n"
    )
}

/// The many-row test mesh in binary.
fn many_rows_binary(vertices: usize, faces: usize, big_endian: bool) -> Vec<u8> {
    use V::*;
    let mut rows = Vec::new();
    for i in 0..vertices {
        let (p, n) = (many_rows_position(i), many_rows_normal(i) * (i % 3 + 1) as f32);
        rows.push([p.x, p.y, p.z, n.x, n.y, n.z].map(F32).to_vec());
    }
    rows.extend([[0, 1], [2, 3], [4, 5]].map(|e| e.map(I32).to_vec()));
    for j in 0..faces {
        let corners = many_rows_face(j, vertices);
        let mut row = vec![U8(corners.len() as u8)];
        row.extend(corners.iter().map(|&c| I32(c as i32)));
        row.push(U8((j % 3) as u8));
        rows.push(row);
    }
    binary_with(&many_rows_elements(vertices, faces), &rows, big_endian)
}

fn many_rows_position(i: usize) -> Vec3 {
    Vec3::new(i as f32 * 0.5, (i % 7) as f32, (i % 13) as f32 * 0.25)
}

/// Every fifth vertex has a zero normal, which makes its faces flat.
fn many_rows_normal(i: usize) -> Vec3 {
    if i.is_multiple_of(5) { Vec3::ZERO } else { Vec3::Z }
}

/// Face `j`'s corners: a quad for every tenth, a triangle otherwise.
fn many_rows_face(j: usize, vertices: usize) -> Vec<usize> {
    let corners = if j.is_multiple_of(10) { 4 } else { 3 };
    (0..corners).map(|k| (j * 3 + k) % vertices).collect()
}

/// A body of thousands of rows, with comments, blank lines, white space of every kind, an element
/// without properties and a skipped one, read in windows of many sizes: the pieces join into the
/// mesh that was written.
#[test]
fn a_body_cut_into_pieces_reads_as_written() {
    let (vertices, faces) = (3000, 2000);
    let mut text = many_rows_header(vertices, faces);
    for i in 0..vertices {
        let (p, n) = (many_rows_position(i), many_rows_normal(i));
        // Normals of any length are made unit ones.
        let scale = (i % 3 + 1) as f32;
        text.push_str(&format!(
            "{} {}\t{} {} {} {}\n",
            p.x,
            p.y,
            p.z,
            n.x * scale,
            n.y,
            n.z * scale
        ));
        if i.is_multiple_of(97) {
            text.push_str("# a comment line\n\n   \t\r\n");
        }
    }
    text.push_str("0 1\n  2 3 # an edge\n4 5\r\n");
    for j in 0..faces {
        let corners = many_rows_face(j, vertices);
        let list: Vec<String> = corners.iter().map(usize::to_string).collect();
        text.push_str(&format!("{} {} {}\n", corners.len(), list.join(" "), j % 3));
    }
    text.push_str("# the end\n\n");

    let mut triangles = 0;
    let check = |mesh: &MeshData, what: &str| {
        assert_eq!(mesh.positions.len(), vertices, "{what}");
        for i in 0..vertices {
            assert_eq!(mesh.positions[i], many_rows_position(i), "{what}: vertex {i}");
            assert_eq!(mesh.normals[i], many_rows_normal(i), "{what}: normal {i}");
        }
        let mut t = 0;
        for j in 0..faces {
            let corners = many_rows_face(j, vertices);
            let smooth = corners.iter().all(|&c| many_rows_normal(c) != Vec3::ZERO);
            let count = corners.len() - 2;
            let got = &mesh.triangles[t..t + count];
            let corners: Vec<u32> = corners.iter().map(|&c| c as u32).collect();
            if count == 1 {
                assert_eq!(got[0], [corners[0], corners[1], corners[2]], "{what}: face {j}");
            } else {
                assert_quad_split(got, corners[..].try_into().unwrap());
            }
            for k in t..t + count {
                let want = smooth.then_some(mesh.triangles[k]);
                assert_eq!(mesh.normal_triangles[k], want, "{what}: face {j}");
            }
            t += count;
        }
        assert_eq!(mesh.triangles.len(), t, "{what}");
        t
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("many.ply");
    let bodies = [
        ("ascii", text.into_bytes()),
        ("little endian", many_rows_binary(vertices, faces, false)),
        ("big endian", many_rows_binary(vertices, faces, true)),
    ];
    for (format, bytes) in bodies {
        std::fs::write(&path, &bytes).unwrap();
        for window in [30, 64, 500, 4096, 1 << 16] {
            let mesh = load_in_windows(&path, window).unwrap().unwrap();
            triangles = check(&mesh, &format!("{format}, window {window}"));
        }
        // 200 quads of two triangles, 1,800 triangles.
        assert_eq!(triangles, 2200);
        check(&load_bytes(&bytes).unwrap(), format);
    }
}

/// A wrong value in any row of a binary body cut into pieces is reported at its byte, with the error a
/// reading of the whole gives (`load_bytes` compares them); so is a body cut short anywhere.
#[test]
fn an_error_in_any_binary_piece_is_reported_where_it_is() {
    let (vertices, faces) = (40, 30);
    let bytes = many_rows_binary(vertices, faces, false);
    let body = bytes.len() - (vertices * 24 + 3 * 8 + faces * 2 + 4 * (faces * 3 + 3));
    for i in 0..vertices {
        let mut wrong = bytes.clone();
        let at = body + i * 24 + 4;
        wrong[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        let e = load_bytes(&wrong).unwrap_err();
        let want = format!("expected a finite number for the y coordinate of vertex {i}, found NaN");
        assert_eq!((e.message, e.location), (want, Location::Byte(at as u64)));
    }
    let mut at = body + vertices * 24 + 3 * 8;
    for j in 0..faces {
        let mut wrong = bytes.clone();
        let corners = many_rows_face(j, vertices).len();
        wrong[at + 1..at + 5].copy_from_slice(&99i32.to_le_bytes());
        let e = load_bytes(&wrong).unwrap_err();
        let want = "expected a vertex index below 40, found 99".to_string();
        assert_eq!(
            (e.message, e.location),
            (want, Location::Byte(at as u64 + 1)),
            "face {j}"
        );
        at += 2 + 4 * corners;
    }
    assert_eq!(at, bytes.len());
    for end in (body..bytes.len()).step_by(5) {
        let e = load_bytes(&bytes[..end]).unwrap_err();
        assert!(e.message.ends_with("found the end of the file"), "{e}");
    }
    let e = load_bytes(&[&bytes[..], b"x"].concat()).unwrap_err();
    assert_eq!(e.location, Location::Byte(bytes.len() as u64));
    // A list of negative length cannot be sized: the body from there is read as a whole.
    let mut signed = bytes.clone();
    let list = bytes.windows(5).position(|w| w == b"uchar").unwrap();
    signed[list..list + 5].copy_from_slice(b" char");
    let last = bytes.len() - 2 - 4 * 3;
    signed[last] = (-1i8) as u8;
    let e = load_bytes(&signed).unwrap_err();
    assert_eq!(
        e.message,
        "expected 3 or more vertex indices in face 29, found -1"
    );
}

/// A wrong line anywhere in a body cut into pieces is reported on that line, with the error a reading
/// of the whole gives (`load_bytes` compares them), whichever piece holds it.
#[test]
fn an_error_in_any_piece_is_reported_on_its_line() {
    let (vertices, faces) = (40, 30);
    let header = many_rows_header(vertices, faces);
    let header_lines = header.lines().count();
    let mut lines: Vec<String> = Vec::new();
    for i in 0..vertices {
        let p = many_rows_position(i);
        lines.push(format!("{} {} {} 0 0 1", p.x, p.y, p.z));
    }
    lines.extend(["0 1", "2 3", "4 5"].map(String::from));
    for j in 0..faces {
        let corners = many_rows_face(j, vertices);
        let list: Vec<String> = corners.iter().map(usize::to_string).collect();
        lines.push(format!("{} {} 0", corners.len(), list.join(" ")));
    }
    let file = |lines: &[String]| format!("{header}{}\n", lines.join("\n"));
    assert_eq!(load_text(&file(&lines)).unwrap().positions.len(), vertices);
    for k in 0..lines.len() {
        let line = (header_lines + k + 1) as u64;
        let mut wrong = lines.clone();
        for (bad, what) in [
            (format!("{} 7", lines[k]), "an extra value"),
            (
                lines[k].rsplit_once(' ').unwrap().0.to_string(),
                "a missing value",
            ),
            (lines[k].replacen(' ', " x ", 1), "a word"),
        ] {
            wrong[k] = bad;
            let e = load_text(&file(&wrong)).unwrap_err();
            // The last row's missing value is met at the end of the file, after its line break.
            let at = if k + 1 == lines.len() && what == "a missing value" {
                line + 1
            } else {
                line
            };
            assert_eq!(e.line(), Some(at), "{what} on line {line}: {e}");
        }
    }
    // A row too many after the last, and a body that stops among the vertices.
    let e = load_text(&(file(&lines) + "3 0 1 2 0\n")).unwrap_err();
    assert_eq!(
        e.message,
        "expected the end of the file after the last element, found \"3\""
    );
    let e = load_text(&file(&lines[..25])).unwrap_err();
    assert_eq!(
        e.message,
        "expected the x coordinate of vertex 25, found the end of the file"
    );
}
