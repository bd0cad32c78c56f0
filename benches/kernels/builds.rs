//! The check that a native build is never slower than the portable one. The kernels bench knows which
//! of the two it was compiled as (`native`: AVX2 or better as the compile's baseline, as
//! `RUSTFLAGS="-C target-cpu=native"` gives on such CPUs; `portable`: the x86-64 baseline, where the
//! wide BVHs reach AVX2 and AVX-512 by run-time dispatch alone). Each run keeps its Mrays/s per row under
//! criterion's directory, named for its scene, thread count and build; once a run of the other build on
//! the same CPU is there, the report prints native / portable for every row and names the rows where the
//! native build is slower. The two builds cannot share a run, and the machine's speed drifts between
//! runs; with `--features bench-embree`, Embree's row (a system library, the same code in both builds)
//! measures that drift and every ratio is divided by it.

use std::collections::BTreeMap;
use std::path::PathBuf;

use crate::common::table;

/// What this bench binary was compiled as.
pub fn this_build() -> &'static str {
    if cfg!(target_feature = "avx2") {
        "native"
    } else {
        "portable"
    }
}

/// A kept run's figures: its CPU and, per row, Mrays/s per ray set.
type Record = (String, BTreeMap<String, Vec<Option<f64>>>);

/// Where the run of `build` for `key` (scene and thread count) is kept.
fn path(key: &str, build: &str) -> PathBuf {
    table::criterion_home().join(format!("{key}-{build}.json"))
}

/// Keeps this run's `rows` (each row's Mrays/s per ray set) for `key`, and, if the other build ran on
/// this CPU, prints native / portable per row with `header`'s ray sets, and the rows where native is
/// more than `TOLERANCE` slower.
pub fn record_and_compare(key: &str, header: &[&str], rows: &[(String, Vec<Option<f64>>)]) {
    let cpu = whitted::machine::cpu().to_string();
    let mine: BTreeMap<&String, &Vec<Option<f64>>> = rows.iter().map(|(id, v)| (id, v)).collect();
    let json = serde_json::json!({ "cpu": cpu, "rows": mine });
    let here = path(key, this_build());
    if let Err(e) = std::fs::write(&here, json.to_string()) {
        eprintln!("could not keep this run's figures in {}: {e}", here.display());
    }
    let other = if this_build() == "native" {
        "portable"
    } else {
        "native"
    };
    let Some((other_cpu, theirs)) = read(&path(key, other)) else {
        println!("\n(no {other} run of {key} kept yet: run the bench in the other build to compare the two)");
        return;
    };
    if other_cpu != cpu {
        println!("\n(the {other} run of {key} kept is from another CPU, {other_cpu}: not compared)");
        return;
    }
    // Each row of both runs as native / portable per ray set, in this run's order.
    let ratios: Vec<(&String, Vec<Option<f64>>)> = rows
        .iter()
        .filter_map(|(id, here)| {
            let there = theirs.get(id)?;
            let (native, portable) = if this_build() == "native" {
                (here, there)
            } else {
                (there, here)
            };
            let r = native
                .iter()
                .zip(portable)
                .map(|(n, p)| n.zip(*p).map(|(n, p)| n / p));
            Some((id, r.collect()))
        })
        .collect();
    // The two builds ran at different times, and these machines' speed drifts by more than the
    // differences looked for. Embree is the same library code in both builds: its own ratio is the
    // drift, and every row is divided by it.
    let yardstick = yardstick();
    let drift = ratios
        .iter()
        .find(|(id, _)| **id == yardstick)
        .map(|(_, r)| r.clone());
    match &drift {
        Some(d) => println!(
            "\n{yardstick}, the same code in both builds, measured {} native / portable: the machine's drift \
             between the runs, divided out below",
            d.iter()
                .map(|r| r.map_or("-".into(), |r| format!("{r:.2}x")))
                .collect::<Vec<_>>()
                .join(" / ")
        ),
        None => println!(
            "\n(no {yardstick} row, built with `--features bench-embree`, to divide out the machine's drift \
             between the two runs: the ratios below include it)"
        ),
    }
    let mut slower = Vec::new();
    let mut table_rows = Vec::new();
    for (id, r) in &ratios {
        let cells: Vec<Option<String>> = r
            .iter()
            .enumerate()
            .zip(header)
            .map(|((i, ratio), set)| {
                let ratio = match &drift {
                    Some(d) => ratio.zip(d[i]).map(|(r, d)| r / d)?,
                    None => (*ratio)?,
                };
                if ratio < 1.0 - TOLERANCE {
                    slower.push(format!("{id} {set} ({ratio:.2}x)"));
                }
                Some(format!("{ratio:.2}x"))
            })
            .collect();
        table_rows.push(((*id).clone(), cells));
    }
    let mut columns = vec!["native / portable"];
    columns.extend(header);
    table::print(
        &format!("{key}: native build over portable build, Mrays/s"),
        &columns,
        &table_rows,
    );
    if slower.is_empty() {
        println!(
            "\nthe native build is no slower than the portable one on any row (within {:.0}%)",
            TOLERANCE * 100.0
        );
    } else {
        println!(
            "\nthe NATIVE BUILD IS SLOWER than the portable one on: {}",
            slower.join(", ")
        );
    }
}

/// How much slower a native row may measure before it is named: criterion's medians of one run vary
/// by a few percent on these machines.
const TOLERANCE: f64 = 0.03;

/// The row whose code does not depend on the build: Embree's single rays (a system library).
fn yardstick() -> String {
    format!("embree-{}", crate::contestant::auto_set())
}

/// A kept run: its CPU and rows.
fn read(path: &std::path::Path) -> Option<Record> {
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()?;
    let rows = json["rows"]
        .as_object()?
        .iter()
        .map(|(id, v)| {
            let cells = v
                .as_array()
                .map_or_else(Vec::new, |a| a.iter().map(|x| x.as_f64()).collect());
            (id.clone(), cells)
        })
        .collect();
    Some((json["cpu"].as_str()?.to_string(), rows))
}
