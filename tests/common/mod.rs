//! Helpers shared by the integration tests: each test binary (`tests/*/main.rs`) includes this file as
//! its module `common`.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use glam::DVec3;
use serde_json::Value;
use whitted::scene::Material;

// The image readers, shared with the library's unit tests (`image/codecs.rs`).
pub mod images;

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

/// The number in the environment variable `name` (a longer run than the default), else `default`.
pub fn env_number<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// Runs the `whitted` binary.
pub fn whitted(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_whitted"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("the binary runs")
}

/// Makes a FIFO at `path` (Unix).
#[cfg(unix)]
pub fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.as_os_str().as_encoded_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(
        unsafe { libc::mkfifo(c.as_ptr(), 0o600) },
        0,
        "mkfifo {}",
        path.display()
    );
}

/// Waits for `child` (its stdout and stderr piped or not), killing it and failing the test if it runs
/// for more than a minute: for commands given what must neither hang them nor eat the machine.
pub fn wait_a_minute(mut child: std::process::Child, what: &str) -> Output {
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > std::time::Duration::from_secs(60) {
            child.kill().unwrap();
            let out = child.wait_with_output().unwrap();
            panic!(
                "{what} still ran after a minute: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// The names in `dir`, sorted.
pub fn names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
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

/// The stdout of `whitted ARGS`, which must succeed.
pub fn stdout(args: &[&str]) -> String {
    String::from_utf8(ok(args).stdout).unwrap()
}

/// The one JSON object that `whitted ARGS`, which must succeed, prints on stdout.
pub fn json(args: &[&str]) -> Value {
    let text = stdout(args);
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{e}: {text}"))
}

/// The stderr of a run that must have failed with exit status `status`, and without a panic.
pub fn failed(out: &Output, status: i32) -> String {
    let err = String::from_utf8(out.stderr.clone()).unwrap();
    assert_eq!(out.status.code(), Some(status), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// The stderr of `whitted ARGS`, which must fail with exit status `status` and no panic.
pub fn fails(args: &[&str], status: i32) -> String {
    let out = whitted(args);
    assert_eq!(
        out.status.code(),
        Some(status),
        "whitted {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    failed(&out, status)
}

/// The error line of a failed run: exit status 1, no panic, and a `whitted: ` line last, returned.
pub fn failure(out: &Output) -> String {
    failure_with(out, 1)
}

/// The error line of a run the command line's own fault failed once the scene was read: exit status
/// 2 (a usage error), no panic, and a `whitted: ` line last, returned.
pub fn usage_failure(out: &Output) -> String {
    failure_with(out, 2)
}

fn failure_with(out: &Output, status: i32) -> String {
    let err = failed(out, status);
    let last = err.lines().last().unwrap_or_default().to_string();
    assert!(last.starts_with("whitted: "), "{err}");
    last
}

/// An unsigned integer of a JSON report.
pub fn int(v: &Value) -> u64 {
    v.as_u64()
        .unwrap_or_else(|| panic!("not an unsigned integer: {v}"))
}

/// Blinn-Phong term of one unoccluded light at `p` (unit normal `n` facing the viewer, unit `v` toward
/// the viewer): C_light · (Kd·Cd·max(0, n·L) + Ks·Cs·max(0, n·h)^shine), 0 when n·L ≤ 0, in f64.
pub fn blinn_phong(m: &Material, p: DVec3, n: DVec3, v: DVec3, light: DVec3, color: DVec3) -> DVec3 {
    let l = (light - p).normalize();
    let n_dot_l = n.dot(l);
    if n_dot_l <= 0.0 {
        return DVec3::ZERO;
    }
    let h = (l + v).normalize();
    let spec = n.dot(h).max(0.0).powf(m.shininess as f64);
    color * (m.kd as f64 * n_dot_l * m.diffuse.as_dvec3() + m.ks as f64 * spec * m.specular.as_dvec3())
}
