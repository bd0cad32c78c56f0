//! `whitted info --json` against counts computed independently: a deliberately naive reader (the whole
//! file split on whitespace, each keyword skipping the numbers it owns) that shares no code with the
//! streaming parser.

use std::io::Read;
use std::path::Path;

use crate::common::{root, scene_files, whitted};

#[derive(Debug, Default, PartialEq)]
struct Counts {
    spheres: u64,
    triangles: u64,
    boxes: u64,
    planes: u64,
    cones: u64,
    point_lights: u64,
    area_lights: u64,
    materials: u64,
    width: u64,
    height: u64,
}

fn read_text(path: &Path) -> String {
    let bytes = std::fs::read(path).unwrap();
    let mut text = String::new();
    if bytes.starts_with(&[0x1f, 0x8b]) {
        flate2::read::MultiGzDecoder::new(&bytes[..])
            .read_to_string(&mut text)
            .unwrap();
    } else {
        text = String::from_utf8(bytes).unwrap();
    }
    text
}

/// Triangles of a PLY file: Σ (n − 2) over the face rows (ascii).
fn ply_triangles(path: &Path) -> u64 {
    let text = read_text(path);
    let (header, body) = text.split_once("end_header").unwrap();
    let count = |name: &str| -> usize {
        header
            .lines()
            .find_map(|l| l.strip_prefix(&format!("element {name} ")))
            .map(|n| n.trim().parse().unwrap())
            .unwrap_or(0)
    };
    let (nv, nf) = (count("vertex"), count("face"));
    body.lines()
        .filter(|l| !l.trim().is_empty())
        .skip(nv)
        .take(nf)
        .map(|l| l.split_whitespace().next().unwrap().parse::<u64>().unwrap() - 2)
        .sum()
}

fn independent_counts(path: &Path) -> Counts {
    let text = read_text(path);
    let words: Vec<&str> = text
        .lines()
        .map(|l| l.split('#').next().unwrap())
        .flat_map(str::split_whitespace)
        .collect();
    let is_num = |w: &str| w.parse::<f64>().is_ok();
    let mut c = Counts::default();
    let mut have_material = false;
    let object = |c: &mut Counts, have: &mut bool| {
        if !*have {
            c.materials += 1;
            *have = true;
        }
    };
    let mut i = 0;
    while i < words.len() {
        let w = words[i];
        i += 1;
        match w {
            "resolution" => {
                c.width = words[i].parse().unwrap();
                c.height = words[i + 1].parse().unwrap();
                i += 2;
            }
            "f" => {
                c.materials += 1;
                have_material = true;
                while i < words.len() && is_num(words[i]) {
                    i += 1;
                }
            }
            "l" => {
                c.point_lights += 1;
                while i < words.len() && is_num(words[i]) {
                    i += 1;
                }
            }
            "lq" => {
                c.area_lights += 1;
                i += 13;
            }
            "s" => {
                object(&mut c, &mut have_material);
                c.spheres += 1;
                i += 4;
            }
            "p" | "pp" => {
                object(&mut c, &mut have_material);
                let n: u64 = words[i].parse().unwrap();
                c.triangles += n - 2;
                i += 1 + n as usize * if w == "p" { 3 } else { 6 };
            }
            "c" => {
                object(&mut c, &mut have_material);
                c.cones += 1;
                i += 8;
            }
            "box" => {
                object(&mut c, &mut have_material);
                c.boxes += 1;
                i += 6;
            }
            "pl" => {
                object(&mut c, &mut have_material);
                c.planes += 1;
                i += 9;
            }
            "mesh" => {
                object(&mut c, &mut have_material);
                let nv: usize = words[i].parse().unwrap();
                let nf: usize = words[i + 1].parse().unwrap();
                c.triangles += nf as u64;
                i += 2 + 3 * nv + 3 * nf;
            }
            "include" => {
                object(&mut c, &mut have_material);
                c.triangles += ply_triangles(&path.parent().unwrap().join(words[i]));
                i += 1;
            }
            _ => {}
        }
    }
    c
}

fn info_json(path: &Path) -> Counts {
    let out = whitted(&["info", "--json", path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let count = |key: &str| {
        v[key]
            .as_u64()
            .unwrap_or_else(|| panic!("{key} is not a count: {v}"))
    };
    Counts {
        spheres: count("spheres"),
        triangles: count("triangles"),
        boxes: count("boxes"),
        planes: count("planes"),
        cones: count("cones"),
        point_lights: count("point_lights"),
        area_lights: count("area_lights"),
        materials: count("materials"),
        width: count("width"),
        height: count("height"),
    }
}

fn check_dir(dir: &Path) {
    let files = scene_files(dir);
    assert!(!files.is_empty(), "no scenes in {}", dir.display());
    for f in files {
        let want = independent_counts(&f);
        assert_eq!(info_json(&f), want, "{}", f.display());
    }
}

#[test]
fn info_counts_for_every_scene_in_scenes() {
    check_dir(&root().join("scenes"));
}

/// Known figures, not only agreement: the course dragon and the full Stanford dragon.
#[test]
fn known_counts() {
    let dragon = info_json(&root().join("scenes/dragon.p3f"));
    assert_eq!((dragon.spheres, dragon.triangles, dragon.boxes), (2, 100_002, 1));
    assert_eq!((dragon.width, dragon.height), (800, 600));
    let full = info_json(&root().join("scenes/dragon_full.p3f"));
    assert_eq!(full.triangles, 871_414);
    assert_eq!((full.width, full.height, full.point_lights), (1280, 720, 1));
    let gears = info_json(&root().join("scenes/spd/gears_1.nff"));
    // 147 polygons, concave 144-gons among them: Σ (n − 2) after ear clipping is 574 (counted from
    // the file's `p N` lines with awk).
    assert_eq!(gears.triangles, 574);
}

/// A bare mesh is a scene too: framed by a camera, lit, with a grey material.
#[test]
fn bare_mesh_scene() {
    let res2 = root().join("scenes/models/dragon_vrip_res2.ply.gz");
    let c = info_json(&res2);
    assert_eq!(c.triangles, 202_520);
    assert_eq!((c.point_lights, c.materials), (1, 1));
}

/// A UTF-8 byte-order mark (EF BB BF) before the text, as some Windows editors write, is not part of
/// the first word: each text format, gzipped or not, loads the same with one as without.
#[test]
fn a_byte_order_mark_is_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let obj = "v 0 0 0\nv 2 0 0\nv 0 3 0\nv 1 1 4\nf 1 2 3\nf 1 2 4\nf 4 -2 -1\n";
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
               property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n\
               0 0 0\n2 0 0\n0 3 0\n1 1 4\n3 0 1 2\n4 0 1 3 2\n";
    let p3f = "v from 0 0 5 at 0 0 0 up 0 1 0 angle 45 hither 1 resolution 64 48\n\
               l 1 1 1\nf 1 0 0 1 0 0 0 0\ns 0 0 0 1\np 3 0 0 0 1 0 0 0 1 0\n";
    for (name, text) in [("m.obj", obj), ("m.ply", ply), ("s.p3f", p3f)] {
        for gz in [false, true] {
            let info = |bom: &[u8]| {
                let mut bytes = [bom, text.as_bytes()].concat();
                let mut name = format!("{}{name}", if bom.is_empty() { "plain_" } else { "bom_" });
                if gz {
                    let mut enc = flate2::write::GzEncoder::new(Vec::new(), Default::default());
                    std::io::Write::write_all(&mut enc, &bytes).unwrap();
                    bytes = enc.finish().unwrap();
                    name += ".gz";
                }
                let path = dir.path().join(name);
                std::fs::write(&path, bytes).unwrap();
                let out = whitted(&["info", "--json", path.to_str().unwrap()]);
                assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
                let mut v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
                let map = v.as_object_mut().unwrap();
                map.remove("scene");
                map.remove("load_s");
                v
            };
            assert_eq!(info(b"\xef\xbb\xbf"), info(b""), "{name}, gzipped: {gz}");
        }
    }
}
