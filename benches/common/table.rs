//! The side-by-side table a bench prints after criterion's own report: each row's median read back from
//! the estimates criterion just wrote, so the table and criterion's lines are the same measurement.

use std::path::PathBuf;
use std::time::SystemTime;

/// Where criterion keeps its results (its own rule: `CRITERION_HOME`, else the target directory's
/// `criterion/`).
pub fn criterion_home() -> PathBuf {
    if let Some(home) = std::env::var_os("CRITERION_HOME") {
        return PathBuf::from(home);
    }
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"))
        .join("criterion")
}

/// The median time in seconds of bench `id` of `group`, if it ran since `since` (a filtered-out bench
/// keeps an older result, which is not shown).
pub fn median(group: &str, id: &str, since: SystemTime) -> Option<f64> {
    // criterion's file-name rule for ids (`make_filename_safe`).
    let safe = id.replace(['?', '"', '/', '\\', '*', '<', '>', ':', '|', '^'], "_");
    let path = criterion_home().join(group).join(safe).join("new/estimates.json");
    if std::fs::metadata(&path).ok()?.modified().ok()? < since {
        return None;
    }
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).ok()?).ok()?;
    Some(json["median"]["point_estimate"].as_f64()? * 1e-9)
}

/// Prints a Markdown table: `header`, then each row's label and cells (`-` where a bench did not run).
pub fn print(title: &str, header: &[&str], rows: &[(String, Vec<Option<String>>)]) {
    // Figures mean little without the CPU they were measured on.
    println!("\n{title}, on {}\n", whitted::machine::cpu());
    println!("| {} |", header.join(" | "));
    println!("|{}", "---|".repeat(header.len()));
    for (label, cells) in rows {
        let cells: Vec<String> = cells
            .iter()
            .map(|c| c.clone().unwrap_or_else(|| "-".into()))
            .collect();
        println!("| {label} | {} |", cells.join(" | "));
    }
}
