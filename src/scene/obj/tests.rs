use std::io::Write;

use flate2::Compression;
use flate2::write::GzEncoder;

use super::*;
use crate::error::Location;
use crate::scene::polygon_checks::{assert_quad_split, assert_triangulates};

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

/// An L-shaped hexagon in the plane z = 1, counter-clockwise seen from +z, of area 3: the unit squares
/// [0, 2] x [0, 1] and [0, 1] x [1, 2]. It starts at (2, 0), from where a fan would wind its second
/// triangle backwards across the notch [1, 2] x [1, 2] (a fan from (0, 0) or (1, 1) would be right).
const L_SHAPE: &str = "v 2 0 1\nv 2 1 1\nv 1 1 1\nv 1 2 1\nv 0 2 1\nv 0 0 1\n";

#[test]
fn triangles_quads_and_concave_polygons() {
    let mesh = load_text(&format!("{SQUARE}{L_SHAPE}f 1 2 3\nf 1 2 3 4\nf 5 6 7 8 9 10\n")).unwrap();
    assert_eq!(mesh.positions.len(), 10);
    assert_eq!(mesh.positions[7], Vec3::new(1.0, 2.0, 1.0));
    assert_eq!(mesh.triangles.len(), 1 + 2 + 4);
    assert_eq!(mesh.triangles[0], [0, 1, 2]);
    assert_quad_split(&mesh.triangles[1..3], [0, 1, 2, 3]);
    assert_triangulates(&mesh.positions, &[4, 5, 6, 7, 8, 9], &mesh.triangles[3..], 3.0);
}

#[test]
fn reference_forms_and_negative_indices() {
    let text = format!(
        "{SQUARE}vn 1 0 0\nvn 0 1 0\nvn 0 0 1\nvn -1 0 0\n\
         f 1/1/1 2/2/2 3/3/3\nf 1//1 3//3 4//4\nf 2/5 3/6 4/7\nf -4 -3 -2\nv 5 5 5\nf -1 -2/1 -3//2\n"
    );
    let mesh = load_text(&text).unwrap();
    assert_eq!(mesh.positions.len(), 5);
    assert_eq!(
        mesh.triangles,
        [[0, 1, 2], [0, 2, 3], [1, 2, 3], [0, 1, 2], [4, 3, 2]]
    );
    // The last face has a normal on one corner only: flat.
    assert_eq!(
        mesh.normal_triangles,
        [Some([0, 1, 2]), Some([0, 2, 3]), None, None, None]
    );
}

/// Asserts that `got` are the unit vectors `want` (worked out by hand, to 7 digits).
#[track_caller]
fn assert_normals(got: &[Vec3], want: &[Vec3]) {
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (g, w) in got.iter().zip(want) {
        assert!((*g - *w).length() < 1e-6, "{got:?} vs {want:?}");
    }
}

/// `vn` normals are stored at unit length and faces index them apart from the positions (negative
/// indices count back from the last `vn`). A face with a corner lacking a normal, or naming a zero one, is
/// flat as a whole.
#[test]
fn normals_smooth_and_flat_faces() {
    let text = format!(
        "{SQUARE}vn 0 0 2\nvn 3 0 4\nvn 0 -3 4\nvn 0 0 0\n\
         f 1//1 2//2 3//3\nf 1 3 4\nf 1//3 3//2 4\nf 1/1/-2 2/1/-3 3/1/-4\nf 1//1 3//2 4//4\n"
    );
    let mesh = load_text(&text).unwrap();
    let unit = [
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.6, 0.0, 0.8),
        Vec3::new(0.0, -0.6, 0.8),
        Vec3::ZERO,
    ];
    assert_normals(&mesh.normals, &unit);
    assert_eq!(
        mesh.triangles,
        [[0, 1, 2], [0, 2, 3], [0, 2, 3], [0, 1, 2], [0, 2, 3]]
    );
    assert_eq!(
        mesh.normal_triangles,
        [Some([0, 1, 2]), None, None, Some([2, 1, 0]), None]
    );
}

/// The normal indices of a concave polygon go through the ear clipping with its vertices; a flat face
/// before the first smooth one is recorded as flat.
#[test]
fn polygon_normals_follow_the_triangulation() {
    let normals = "vn 1 0 1\nvn 2 0 1\nvn 3 0 1\nvn 4 0 1\nvn 5 0 1\nvn 6 0 1\n";
    // Vertex i (1-based) has normal 7 - i.
    let mesh = load_text(&format!(
        "{L_SHAPE}{normals}f 1 2 3\nf 1//6 2//5 3//4 4//3 5//2 6//1\n"
    ))
    .unwrap();
    assert_eq!(mesh.triangles.len(), 5);
    assert_eq!(mesh.triangles[0], [0, 1, 2]);
    assert_triangulates(&mesh.positions, &[0, 1, 2, 3, 4, 5], &mesh.triangles[1..], 3.0);
    assert_eq!(mesh.normal_triangles.len(), 5);
    assert_eq!(mesh.normal_triangles[0], None);
    for k in 1..5 {
        assert_eq!(
            mesh.normal_triangles[k],
            Some(mesh.triangles[k].map(|i| 5 - i)),
            "triangle {k}"
        );
    }
}

/// Normals are normalised without overflow or underflow in their length.
#[test]
fn tiny_and_huge_normals() {
    let mesh = load_text(&format!(
        "{SQUARE}vn 1e-30 0 0\nvn 3e38 0 -3e38\nf 1//1 2//2 3//2\n"
    ))
    .unwrap();
    let half = std::f32::consts::FRAC_1_SQRT_2;
    assert_normals(&mesh.normals, &[Vec3::X, Vec3::new(half, 0.0, -half)]);
    assert_eq!(mesh.normal_triangles, [Some([0, 1, 1])]);
}

#[test]
fn normal_errors() {
    let vn = "vn 0 0 1\nvn 0 1 0\n";
    let face_error = |face: &str| load_text(&format!("{SQUARE}{vn}{face}\n")).unwrap_err();
    let e = face_error("f 1//1 2//3 3//1");
    assert_eq!(
        e.message,
        "expected a normal index between 1 and 2 (or -2..-1), found 3"
    );
    assert_eq!(e.location, Location::LineCol(7, 8));
    let e = face_error("f 1//1 2//2 3/4/-3");
    assert_eq!(
        e.message,
        "expected a normal index between 1 and 2 (or -2..-1), found -3"
    );
    assert_eq!(e.location, Location::LineCol(7, 13));
    let e = face_error("f 1//0 2//1 3//1");
    assert!(e.message.ends_with("found 0"), "{e}");
    let e = face_error("f 1//x 2//1 3//1");
    assert!(e.message.starts_with("expected a vertex reference"), "{e}");
    // Normal indices count the `vn` lines before the face, as vertex indices count the `v` lines.
    let e = load_text(&format!("{SQUARE}f 1//1 2//1 3//1\n{vn}")).unwrap_err();
    assert_eq!(
        e.message,
        "expected a \"vn\" line before normal index 1, found none"
    );
    assert_eq!(e.location, Location::LineCol(5, 3));
    let e = load_text(&format!("{SQUARE}vn 0 0 1\nf 1//1 2//1 3//2\nvn 0 1 0\n")).unwrap_err();
    assert_eq!(
        e.message,
        "expected a normal index between 1 and 1 (or -1..-1), found 2"
    );
    assert_eq!(e.line(), Some(6));
}

#[test]
fn normal_value_errors() {
    let e = error_on_line_5("vn nan 0 1");
    assert_eq!(
        e.message,
        "expected a finite number for the x normal component, found \"nan\""
    );
    assert_eq!(e.location, Location::LineCol(5, 4));
    let e = error_on_line_5("vn 0 0 inf");
    assert_eq!(
        e.message,
        "expected a finite number for the z normal component, found \"inf\""
    );
    let e = error_on_line_5("vn 1 x 0");
    assert_eq!(
        e.message,
        "expected a number for the y normal component, found \"x\""
    );
    let e = error_on_line_5("vn 1 0");
    assert_eq!(e.message, "expected 3 normal components after \"vn\", found 2");
    assert_eq!(e.location, Location::LineCol(5, 1));
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
        normals: vec![Vec3::Z],
        normal_triangles: vec![Some([0, 0, 0])],
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

/// A face before any vertex is told that it needs a `v` line first, not a range from 1 to 0.
#[test]
fn a_face_before_any_vertex() {
    for (face, index) in [("f 1 2 3", "1"), ("f -1/1 -2/2 -3/3", "-1"), ("f 0 1 2", "0")] {
        let e = load_text(&format!("# no vertex yet\n  {face}\n{SQUARE}")).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!(
                "{}:2:5: expected a \"v\" line before vertex index {index}, found none",
                e.path.as_ref().unwrap().display()
            )
        );
    }
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
