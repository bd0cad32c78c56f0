//! Reading scenes: `info --json`'s counts against an independent reader (`formats`), one clear error
//! with file, line and column for every class of bad input (`errors`), includes loaded side by side
//! into the store loading them in turn gives (`includes`), and the parsers on mangled input,
//! property tests that they never panic, hang or over-allocate (`fuzz_parsers`).

#[path = "../common/mod.rs"]
mod common;

mod errors;
mod formats;
mod fuzz_parsers;
mod includes;
