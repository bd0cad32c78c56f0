//! Rendering a frame in parts (`--tiles K/N`, `--passes-range A..B`) and merging them: the merge is the
//! single render, bit for bit, whatever the split and the threads; bad parts are refused by name with
//! nothing written; the recipes of docs/scale-out.md run as written.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{self, ok as run, root, whitted};

/// The scene with every effect on: AA, a quad light's soft shadows, depth of field, a rough mirror.
const SCENE: &str = "scenes/distribution.p3f";

fn path(dir: &Path, name: &str) -> String {
    dir.join(name).to_string_lossy().into_owned()
}

/// The linear pixels of an EXR, exactly.
fn exr(path: &str) -> Vec<f32> {
    common::images::exr(std::path::Path::new(path)).2.into_flattened()
}

/// Renders `opts` whole to `single.{png,exr}`, and in the `parts` given (each its own extra arguments,
/// rendered with 1 or 2 threads in turn), merged into `merged.{png,exr}`; asserts they are the same.
fn assert_merge_is_single(dir: &Path, opts: &[&str], parts: &[Vec<String>]) {
    for ext in ["png", "exr"] {
        let single = path(dir, &format!("single.{ext}"));
        run(&[&["render", SCENE, "-q", "-o", &single], opts].concat());
    }
    let mut files = Vec::new();
    for (i, extra) in parts.iter().enumerate() {
        let file = path(dir, &format!("part-{i}.partial"));
        let threads = if i % 2 == 0 { "1" } else { "2" };
        let extra: Vec<&str> = extra.iter().map(String::as_str).collect();
        run(&[
            &["render", SCENE, "-q", "--threads", threads, "-o", &file][..],
            opts,
            &extra,
        ]
        .concat());
        files.push(file);
    }
    for ext in ["png", "exr"] {
        let merged = path(dir, &format!("merged.{ext}"));
        let files: Vec<&str> = files.iter().map(String::as_str).collect();
        run(&[&["merge", "-q", &merged][..], &files].concat());
    }
    assert!(
        std::fs::read(dir.join("merged.png")).unwrap() == std::fs::read(dir.join("single.png")).unwrap(),
        "{opts:?} in {parts:?}: the merged PNG differs from the single render"
    );
    assert!(
        exr(&path(dir, "merged.exr")) == exr(&path(dir, "single.exr")),
        "{opts:?} in {parts:?}: the merged linear pixels differ from the single render"
    );
}

fn tiles(n: u32) -> Vec<Vec<String>> {
    (0..n)
        .map(|k| vec!["--tiles".into(), format!("{k}/{n}")])
        .collect()
}

#[test]
fn tile_parts_merge_into_the_single_render() {
    let dir = tempfile::tempdir().unwrap();
    for n in [1, 3, 7] {
        assert_merge_is_single(dir.path(), &["--width", "96", "--spp", "4"], &tiles(n));
    }
}

#[test]
fn pass_ranges_merge_into_the_single_render() {
    let dir = tempfile::tempdir().unwrap();
    let opts = ["--width", "64", "--passes", "16"];
    let ranges = |rs: &[&str]| -> Vec<Vec<String>> {
        rs.iter()
            .map(|r| vec!["--passes-range".into(), r.to_string()])
            .collect()
    };
    assert_merge_is_single(dir.path(), &opts, &ranges(&["0..5", "5..16"]));
    assert_merge_is_single(dir.path(), &opts, &ranges(&["0..1", "1..2", "2..9", "9..16"]));
    // Both ways at once: two halves of the tiles, each in two pass ranges.
    let mut grid = Vec::new();
    for t in tiles(2) {
        for r in ranges(&["0..7", "7..16"]) {
            grid.push([t.clone(), r].concat());
        }
    }
    assert_merge_is_single(dir.path(), &opts, &grid);
}

/// Runs a merge expected to fail: non-zero exit, the message names `culprit`, no image written.
fn assert_merge_fails(dir: &Path, parts: &[&str], culprit: &str, says: &str) {
    let out = path(dir, "refused.png");
    let result = whitted(&[&["merge", &out][..], parts].concat());
    let err = String::from_utf8_lossy(&result.stderr);
    assert!(!result.status.success(), "{parts:?}: merged");
    assert!(err.contains(culprit), "{parts:?}: does not name {culprit}: {err}");
    assert!(err.contains(says), "{parts:?}: does not say \"{says}\": {err}");
    assert!(!Path::new(&out).exists(), "{parts:?}: an image was written");
    assert_eq!(
        std::fs::read_dir(dir)
            .unwrap()
            .filter(|e| e.as_ref().unwrap().file_name().to_string_lossy().starts_with('.'))
            .count(),
        0,
        "a temporary file was left behind"
    );
}

#[test]
fn merge_refuses_bad_parts_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let opts = ["--width", "64", "--spp", "1"];
    let part = |name: &str, extra: &[&str]| -> String {
        let file = path(d, name);
        run(&[&["render", SCENE, "-q", "-o", &file][..], &opts, extra].concat());
        file
    };
    let p: Vec<String> = (0..3)
        .map(|k| part(&format!("p{k}.partial"), &["--tiles", &format!("{k}/3")]))
        .collect();
    run(&["merge", "-q", &path(d, "ok.png"), &p[0], &p[1], &p[2]]);

    // A missing part: the merge says which one to render again.
    assert_merge_fails(d, &[&p[0], &p[2]], "--tiles 1/3", "no part renders passes 0..1");
    // The same part twice.
    let copy = path(d, "copy.partial");
    std::fs::copy(&p[1], &copy).unwrap();
    assert_merge_fails(d, &[&p[0], &p[1], &p[2], &copy], "copy.partial", "overlap");
    // Parts of another render: another seed, another scene at the same size.
    let seed = part("seed.partial", &["--tiles", "1/3", "--seed", "1"]);
    assert_merge_fails(d, &[&p[0], &seed, &p[2]], "seed.partial", "seed 0 vs 1");
    let other = path(d, "other.partial");
    run(&[
        "render",
        "scenes/dof.p3f",
        "-q",
        "-o",
        &other,
        "--width",
        "64",
        "--height",
        "48",
        "--spp",
        "1",
        "--tiles",
        "1/3",
    ]);
    assert_merge_fails(d, &[&p[0], &other, &p[2]], "other.partial", "scene fingerprint");
    // A truncated file, a flipped bit, a missing file, a file that is not a part at all.
    let bytes = std::fs::read(&p[1]).unwrap();
    let cut = path(d, "cut.partial");
    std::fs::write(&cut, &bytes[..bytes.len() - 100]).unwrap();
    // 64x48 is 4 x 3 tiles of 16 x 16; part 1/3 holds 4 of them, 1024 pixels: 88 bytes of header, 4
    // tile indices of 4 bytes, 28 bytes a pixel and an 8-byte checksum make 28,784 bytes.
    assert_eq!(bytes.len(), 88 + 4 * 4 + 28 * 1024 + 8);
    assert_merge_fails(
        d,
        &[&p[0], &cut, &p[2]],
        "cut.partial",
        "truncated: 28684 bytes where its header describes 28784",
    );
    // Lengths are compared before anything past the tile list is read: a 64 GiB (sparse) file whose
    // header describes 28,784 bytes, and a device that never ends, are refused without reading them.
    let long = path(d, "long.partial");
    std::fs::write(&long, &bytes).unwrap();
    std::fs::File::options()
        .write(true)
        .open(&long)
        .unwrap()
        .set_len(1 << 36)
        .unwrap();
    assert_merge_fails(
        d,
        &[&p[0], &long, &p[2]],
        "long.partial",
        "68719476736 bytes, but its header describes 28784",
    );
    assert_merge_fails(
        d,
        &[&p[0], "/dev/zero", &p[2]],
        "/dev/zero",
        "it is not a regular file",
    );
    let mut flipped = bytes.clone();
    flipped[bytes.len() / 2] ^= 4;
    let flip = path(d, "flip.partial");
    std::fs::write(&flip, &flipped).unwrap();
    assert_merge_fails(d, &[&p[0], &flip, &p[2]], "flip.partial", "checksum");
    assert_merge_fails(
        d,
        &[&p[0], &path(d, "gone.partial"), &p[2]],
        "gone.partial",
        "cannot read",
    );
    assert_merge_fails(
        d,
        &[&p[0], &path(d, "ok.png"), &p[2]],
        "ok.png",
        "not a whitted partial file",
    );
}

/// The output is checked before any part is read (here /dev/zero, which is never read): a name of no
/// image format, a missing directory.
#[test]
fn merge_checks_its_output_first() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let stderr = |out: &str| {
        let result = whitted(&["merge", out, "/dev/zero"]);
        assert_eq!(result.status.code(), Some(1));
        String::from_utf8(result.stderr).unwrap()
    };
    let gif = path(d, "out.gif");
    assert_eq!(
        stderr(&gif),
        format!(
            "whitted: {gif}: unknown image format: expected a .png, .ppm, .jpg, .jpeg or .exr file name\n"
        )
    );
    let missing = path(d, "missing/out.png");
    assert_eq!(
        stderr(&missing),
        format!(
            "whitted: {missing}: the directory {} does not exist\n",
            path(d, "missing")
        )
    );
}

#[test]
fn render_checks_the_split_and_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fails = |args: &[&str], says: &str| {
        let out = whitted(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(says), "{args:?}: {err}");
    };
    let file = path(d, "p.partial");
    fails(
        &["render", SCENE, "--tiles", "3/3", "-o", &file],
        "does not exist",
    );
    fails(&["render", SCENE, "--tiles", "3", "-o", &file], "expected K/N");
    fails(&["render", SCENE, "--passes-range", "5..5", "-o", &file], "empty");
    fails(
        &["render", SCENE, "--passes-range", "0..5", "-o", &file],
        "beyond the render's 1 passes",
    );
    fails(
        &["render", SCENE, "--tiles", "0/2", "-o", &path(d, "p.png")],
        ".partial",
    );
    assert!(!Path::new(&file).exists());

    let args = [
        "render", SCENE, "--width", "48", "--spp", "1", "--tiles", "1/2", "-o", &file, "--resume",
    ];
    let first = run(&args);
    assert!(!String::from_utf8_lossy(&first.stderr).contains("already"));
    let again = run(&args);
    assert!(String::from_utf8_lossy(&again.stderr).contains("holds this part already"));
    // A damaged part, or one of other settings, is rendered again.
    let whole = std::fs::read(&file).unwrap();
    std::fs::write(&file, &whole[..whole.len() / 2]).unwrap();
    let redone = run(&args);
    assert!(!String::from_utf8_lossy(&redone.stderr).contains("already"));
    assert_eq!(std::fs::read(&file).unwrap(), whole);
    let seed1 = run(&[&args[..], &["--seed", "1"]].concat());
    assert!(!String::from_utf8_lossy(&seed1.stderr).contains("already"));
}

/// The ```bash block after `<!-- recipe: NAME -->` in docs/scale-out.md.
pub(crate) fn recipe(name: &str) -> String {
    let doc = std::fs::read_to_string(root().join("docs/scale-out.md")).unwrap();
    let marker = format!("<!-- recipe: {name} -->");
    let after = &doc[doc.find(&marker).unwrap_or_else(|| panic!("no {marker}")) + marker.len()..];
    let body = &after[after.find("```bash\n").expect("a bash block") + 8..];
    body[..body.find("```").expect("the block ends")].to_string()
}

/// Runs a recipe with bash in `dir`, with the built `whitted` first on the PATH.
fn bash(dir: &Path, script: &str, env: &[(&str, &str)]) {
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_whitted"));
    let path = format!(
        "{}:{}",
        bin.parent().unwrap().display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let out = Command::new("bash")
        .args(["-euo", "pipefail", "-c", script])
        .current_dir(dir)
        .env("PATH", path)
        .envs(env.iter().copied())
        .output()
        .expect("bash runs");
    assert!(
        out.status.success(),
        "{script}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The Slurm script, driven by the doc's plain loop (32 parts) standing in for the nodes, and the
/// GNU parallel line if `parallel` is installed: each merge is the single render.
#[test]
fn scale_out_recipes_run_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::os::unix::fs::symlink(root().join("scenes"), d.join("scenes")).unwrap();
    let opts = "--width 64 --spp 4";
    let env = [("SCENE", SCENE), ("OPTS", opts)];
    run(&[
        "render",
        SCENE,
        "-q",
        "--width",
        "64",
        "--spp",
        "4",
        "-o",
        &path(d, "single.png"),
    ]);
    let single = std::fs::read(d.join("single.png")).unwrap();

    std::fs::write(d.join("render-part.sbatch"), recipe("slurm")).unwrap();
    bash(d, &recipe("loop"), &env);
    assert!(
        std::fs::read(d.join("dragon.png")).unwrap() == single,
        "Slurm recipe"
    );
    // Rerun: every part is whole, so none is written again (a rewrite renames a new file into place,
    // which changes its inode), and the merge gives the same image.
    let inodes = |d: &Path| {
        use std::os::unix::fs::MetadataExt;
        let mut v: Vec<_> = std::fs::read_dir(d.join("parts"))
            .unwrap()
            .map(|e| {
                let e = e.unwrap();
                (e.file_name(), e.metadata().unwrap().ino())
            })
            .collect();
        v.sort();
        v
    };
    let before = inodes(d);
    assert_eq!(before.len(), 32, "the loop writes 32 parts");
    bash(d, &recipe("loop"), &env);
    assert_eq!(inodes(d), before, "--resume rendered a whole part again");
    assert!(
        std::fs::read(d.join("dragon.png")).unwrap() == single,
        "Slurm recipe, rerun"
    );

    if !common::have("parallel", &[], "apt-get install parallel") {
        return;
    }
    std::fs::remove_dir_all(d.join("parts")).unwrap();
    std::fs::remove_file(d.join("dragon.png")).unwrap();
    bash(
        d,
        &recipe("parallel"),
        &[("SCENE", SCENE), ("OPTS", opts), ("N", "5")],
    );
    assert!(
        std::fs::read(d.join("dragon.png")).unwrap() == single,
        "GNU parallel recipe"
    );
}
