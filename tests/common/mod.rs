//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The crate root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `../shared`, if it is there; tests that need it skip (saying so) when it is not.
pub fn shared() -> Option<PathBuf> {
    let p = root().join("../shared");
    if p.join("scenes").is_dir() {
        Some(p)
    } else {
        eprintln!("skipped: ../shared is not beside the checkout");
        None
    }
}

/// Runs the `whitted` binary.
pub fn whitted(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_whitted"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("the binary runs")
}

/// Every scene file (.p3f, .nff) under `dir`, sorted.
pub fn scene_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let p = entry.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if matches!(p.extension().and_then(|e| e.to_str()), Some("p3f" | "nff")) {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}
