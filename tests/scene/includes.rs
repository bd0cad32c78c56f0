//! `include`s load side by side on the pool's threads: the store must be the one that loading them in
//! turn gives (triangles in file order, each with the material current at its statement, smooth
//! normals numbered in order), whatever the number of threads, and the error reported must be the
//! first in file order.

use std::path::Path;

use glam::Vec3;
use whitted::scene::store::NO_NORMALS;
use whitted::scene::{self, Scene};

const CAMERA: &str = "v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 64 48\n";
const THREADS: [usize; 4] = [1, 2, 3, 8];

fn load_on(threads: usize, path: &Path) -> whitted::Result<Scene> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| scene::load(path))
}

/// Meshes of one, two and one smooth triangle: `one.obj`, `two.obj`, `smooth.obj`.
fn meshes(dir: &Path) {
    std::fs::write(dir.join("one.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(
        dir.join("two.obj"),
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("smooth.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 1 0\nvn 1 0 0\nf 1//1 2//2 3//3\n",
    )
    .unwrap();
}

#[test]
fn includes_join_in_file_order_on_any_number_of_threads() {
    let dir = tempfile::tempdir().unwrap();
    meshes(dir.path());
    let path = dir.path().join("s.p3f");
    let text = format!(
        "{CAMERA}f 1 0 0 1 0 0 0 0\n\
         include one.obj translate 10 0 0\n\
         include two.obj\n\
         f 0 1 0 1 0 0 0 0\n\
         include smooth.obj scale 2\n\
         p 3\n5 5 5\n6 5 5\n5 6 5\n\
         s 0 0 0 1\n\
         include one.obj translate 20 0 0\n\
         include smooth.obj\n"
    );
    std::fs::write(&path, text).unwrap();
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let expected = [
        // (corners, material, vertex-normal index)
        ([10.0 * x, 11.0 * x, 10.0 * x + y], 0, NO_NORMALS),
        ([Vec3::ZERO, x, x + y], 0, NO_NORMALS),
        ([Vec3::ZERO, x + y, y], 0, NO_NORMALS),
        ([Vec3::ZERO, 2.0 * x, 2.0 * y], 1, 0),
        (
            [
                Vec3::splat(5.0),
                Vec3::new(6.0, 5.0, 5.0),
                Vec3::new(5.0, 6.0, 5.0),
            ],
            1,
            NO_NORMALS,
        ),
        ([20.0 * x, 21.0 * x, 20.0 * x + y], 1, NO_NORMALS),
        ([Vec3::ZERO, x, y], 1, 1),
    ];
    let mut fingerprints = Vec::new();
    for threads in THREADS {
        let s = load_on(threads, &path).unwrap();
        let t = &s.triangles;
        assert_eq!(t.len(), expected.len(), "{threads} threads");
        for (i, (corners, material, normals)) in expected.iter().enumerate() {
            assert_eq!(t.vertices(i), *corners, "triangle {i}, {threads} threads");
            assert_eq!(t.material[i], *material, "triangle {i}, {threads} threads");
            assert_eq!(t.normals[i], *normals, "triangle {i}, {threads} threads");
        }
        assert_eq!(t.vertex_normals, vec![[z, y, x]; 2], "{threads} threads");
        assert_eq!(s.spheres.radius.len(), 1);
        fingerprints.push(s.fingerprint());
    }
    assert!(fingerprints.windows(2).all(|w| w[0] == w[1]), "{fingerprints:?}");
}

#[test]
fn the_first_error_in_file_order_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    meshes(dir.path());
    let bad = |name: &str, face: &str| {
        std::fs::write(
            dir.path().join(name),
            format!("v 0 0 0\nv 1 0 0\nv 0 1 0\n{face}\n"),
        )
        .unwrap()
    };
    bad("early.obj", "f 1 2 9");
    bad("late.obj", "f 1 2 7");
    let path = dir.path().join("s.p3f");
    let load = |body: &str| {
        std::fs::write(&path, format!("{CAMERA}{body}")).unwrap();
        THREADS.map(|threads| load_on(threads, &path).unwrap_err().to_string())
    };
    // The first bad mesh's error, not a later mesh's, nor a later statement's.
    for e in load(
        "include two.obj\ninclude one.obj\ninclude early.obj\ninclude two.obj\ninclude late.obj\n\
         s 0 0 0 x\n",
    ) {
        assert!(e.contains("early.obj:4:"), "{e}");
    }
    // A later statement's error, once every include before it loaded.
    for e in load("include two.obj\ninclude one.obj\ns 0 0 0 x\ninclude late.obj\n") {
        assert!(e.starts_with(&format!("{}:10:", path.display())), "{e}");
    }
    // Geometry past the largest float: at its include's line, the third of five.
    for e in load(
        "include one.obj\ninclude two.obj\ninclude one.obj scale 3e38 translate 3.4e38 0 0\n\
         include two.obj\ninclude late.obj\n",
    ) {
        assert!(e.starts_with(&format!("{}:10:", path.display())), "{e}");
        assert!(
            e.contains("the triangle reaches past the largest finite coordinate"),
            "{e}"
        );
    }
}
