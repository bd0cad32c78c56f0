//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The crate root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// True if the optional program `program` runs (`program --version`, or `probe` as its arguments).
/// When it does not, the test that asked says so and passes without having run, except under CI:
/// `.ci/run` installs every such program and sets `WHITTED_REQUIRE_ALL=1`, which turns the skip into
/// a failure, so a green CI run has run every test.
pub fn have(program: &str, probe: &[&str], install: &str) -> bool {
    let runs = Command::new(program)
        .args(if probe.is_empty() {
            &["--version"][..]
        } else {
            probe
        })
        .output()
        .is_ok();
    if !runs {
        let why = format!("`{program}` is not installed ({install} to run this test)");
        assert!(
            std::env::var_os("WHITTED_REQUIRE_ALL").is_none(),
            "{why}; WHITTED_REQUIRE_ALL is set, so this test must run"
        );
        eprintln!("skipped: {why}");
    }
    runs
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

/// The instruction set the wide BVHs' kernels should pick on this CPU, asked of the CPU here rather
/// than of the crate: `avx512` (AVX-512 F and VL with AVX2 and FMA), `avx2` (with FMA) or `portable`.
pub fn best_simd() -> &'static str {
    #[cfg(target_arch = "x86_64")]
    {
        let avx2 = is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma");
        if avx2 && is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl") {
            return "avx512";
        }
        if avx2 {
            return "avx2";
        }
    }
    "portable"
}

/// The CPU line the reports should print, read here from `/proc/cpuinfo` rather than asked of the
/// crate: the first processor's `model name (family F, model M)` and the logical CPUs this process
/// may use.
pub fn cpu_line() -> String {
    let logical = std::thread::available_parallelism().unwrap().get();
    let text = std::fs::read_to_string("/proc/cpuinfo").unwrap_or_default();
    let first = text.split("\n\n").next().unwrap_or_default();
    let field = |key: &str| {
        first
            .lines()
            .filter_map(|l| l.split_once(':'))
            .find(|(k, _)| k.trim() == key)
            .map(|(_, v)| v.trim().to_string())
    };
    let name = match (field("model name"), field("cpu family"), field("model")) {
        (Some(n), Some(f), Some(m)) => format!("{n} (family {f}, model {m})"),
        (Some(n), _, _) => n,
        _ => format!("unknown {} CPU", std::env::consts::ARCH),
    };
    format!("{name}, {logical} logical CPUs")
}

/// The output of `whitted ARGS`, which must succeed (its stderr in the panic message otherwise).
pub fn ok(args: &[&str]) -> Output {
    let out = whitted(args);
    assert!(
        out.status.success(),
        "whitted {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}
