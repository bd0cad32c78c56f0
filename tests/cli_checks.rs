//! `whitted render` refuses what it could not finish before it starts: a thread count out of range (a
//! usage error, never a panic).

mod common;

use std::process::Output;

/// The stderr of a run expected to fail with `status`.
fn fails(run: Output, status: i32) -> String {
    let err = String::from_utf8(run.stderr).unwrap();
    assert_eq!(run.status.code(), Some(status), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// `--threads` out of 1..=1024 is a usage error (exit status 2) in one line, for every subcommand that
/// takes it, before anything is loaded; 100000 used to print a panic of the standard library first.
#[test]
fn threads_out_of_range_are_a_usage_error() {
    for command in ["render", "bench"] {
        for n in ["0", "100000"] {
            let err = fails(
                common::whitted(&[command, "no-such-scene.p3f", "--threads", n]),
                2,
            );
            assert!(
                err.starts_with(&format!(
                    "error: invalid value '{n}' for '--threads <THREADS>': {n} is not in 1..=1024\n"
                )),
                "{command} --threads {n}: {err}"
            );
        }
    }
}
