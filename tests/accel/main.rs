//! The accelerators: the hierarchies' invariants and the slab test on random input (`accel_props`,
//! property tests), and every accelerator and kernel against brute force on seeded test rays over real
//! and random geometry (`accel_vs_brute`; its exhaustive tier is `cargo test --release --test accel --
//! --ignored`).

#[path = "../common/mod.rs"]
mod common;

mod accel_props;
mod accel_vs_brute;
mod counters;
