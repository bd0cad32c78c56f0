//! What `bench` prints: each accelerator's frame times and report, and with --compare their speed
//! ratio, as text or as one JSON object.

use std::fmt::Write;

use serde_json::Value;

use super::timing::{Timed, spread};
use crate::cli::console::out;
use crate::cli::report::Report;

/// The frames' times and each report as lines, and with two accelerators their speed ratio.
pub fn text(timed: &[Timed], reports: &[Report]) -> whitted::Result<()> {
    let mut page = format!("frames     {} timed after one of warm-up\n", timed[0].ms.len());
    for (t, report) in timed.iter().zip(reports) {
        if timed.len() == 2 {
            let _ = writeln!(page, "\n{}:", report.accel);
        }
        let (median, min, max) = spread(&t.ms);
        let fps = 1e3 / median;
        let _ = writeln!(
            page,
            "frame      median {median:.1} ms (min {min:.1}, max {max:.1}), {fps:.2} fps"
        );
        page += &report.text();
    }
    if let ([first, second], [a, b]) = (timed, reports) {
        let (a, b) = (a.accel, b.accel);
        let _ = writeln!(
            page,
            "\nspeed      {a} / {b}: {:.3}x (median {:.1} ms against {:.1} ms; frames alternated)",
            second.median() / first.median(),
            first.median(),
            second.median()
        );
    }
    out(page)
}

/// One JSON object of the first accelerator's frames and report; with two, the second's under
/// `compare` and their speed ratio.
pub fn json(timed: &[Timed], reports: &[Report]) -> whitted::Result<()> {
    let mut json = frames_json(&reports[0], &timed[0].ms);
    if let ([first, second], [_, report]) = (timed, reports) {
        json["compare"] = frames_json(report, &second.ms);
        json["speed_ratio"] = (second.median() / first.median()).into();
    }
    out(format_args!("{json}\n"))
}

/// The frames' times, then the report's figures.
fn frames_json(report: &Report, ms: &[f64]) -> Value {
    let (median, min, max) = spread(ms);
    let mut out = serde_json::Map::new();
    out.insert("frames".into(), ms.len().into());
    out.insert("frame_ms".into(), ms.into());
    out.insert("frame_ms_median".into(), median.into());
    out.insert("frame_ms_min".into(), min.into());
    out.insert("frame_ms_max".into(), max.into());
    out.insert("fps_median".into(), (1e3 / median).into());
    out.extend(report.json());
    Value::Object(out)
}
