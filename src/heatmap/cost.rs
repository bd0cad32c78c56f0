//! What a cost heatmap shows ([`CostKind`]: nodes visited, primitives tested or rays traced, by all of
//! a pixel's rays or by one kind of them) and the per-pixel figures it is made of, with their
//! statistics for the heatmap's JSON summary.

use std::str::FromStr;

use serde_json::{Map, Value, json};

use super::{Heatmap, Ramp, Scale, nearest_rank};
use crate::render::{RayCounts, RayKind};

/// A per-pixel count of a heatmap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Measure {
    /// Inner nodes visited ([`crate::accel::counters`]).
    Nodes,
    /// Primitives tested.
    Prims,
    /// Rays traced.
    Rays,
}

/// What `--heatmap` shows: `nodes`, `prims` or `rays`, summed over every ray a pixel sends, or over one
/// kind of them (`nodes:shadow`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CostKind {
    /// The count.
    pub measure: Measure,
    /// The rays it sums: one kind, or all (`None`).
    pub rays: Option<RayKind>,
}

/// The ray kinds, as `--heatmap` and the summary name them.
const KINDS: [(&str, RayKind); 4] = [
    ("camera", RayKind::Camera),
    ("shadow", RayKind::Shadow),
    ("reflected", RayKind::Reflected),
    ("refracted", RayKind::Refracted),
];

impl FromStr for CostKind {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        let expected = "expected nodes, prims or rays, optionally with a ray kind: nodes:camera, \
                        prims:shadow, rays:reflected, nodes:refracted";
        let (measure, kind) = s.split_once(':').map_or((s, None), |(m, k)| (m, Some(k)));
        let measure = match measure {
            "nodes" => Measure::Nodes,
            "prims" => Measure::Prims,
            "rays" => Measure::Rays,
            _ => return Err(format!("unknown heatmap \"{s}\": {expected}")),
        };
        let rays = match kind {
            None => None,
            Some(k) => match KINDS.iter().find(|(name, _)| *name == k) {
                Some((_, kind)) => Some(*kind),
                None => return Err(format!("unknown ray kind \"{k}\": {expected}")),
            },
        };
        Ok(CostKind { measure, rays })
    }
}

impl CostKind {
    /// The count of `r`, a pixel's rays.
    pub fn of(&self, r: &RayCounts) -> u64 {
        let steps = &r.steps;
        let count = |kind: RayKind| match kind {
            RayKind::Camera => r.primary,
            RayKind::Shadow => r.shadow,
            RayKind::Reflected => r.reflected,
            RayKind::Refracted => r.refracted,
        };
        match (self.measure, self.rays) {
            (Measure::Nodes, None) => steps.total().nodes,
            (Measure::Prims, None) => steps.total().prims,
            (Measure::Rays, None) => r.total(),
            (Measure::Nodes, Some(k)) => steps.get(k).nodes,
            (Measure::Prims, Some(k)) => steps.get(k).prims,
            (Measure::Rays, Some(k)) => count(k),
        }
    }

    /// What the heatmap shows, for its legend: "BVH nodes visited per pixel (shadow rays)".
    pub fn describe(&self) -> String {
        let what = match self.measure {
            Measure::Nodes => "nodes visited",
            Measure::Prims => "primitives tested",
            Measure::Rays => "rays traced",
        };
        match self.rays.and_then(|k| KINDS.iter().find(|(_, kind)| *kind == k)) {
            Some((name, _)) => format!("{what} per pixel ({name} rays)"),
            None => format!("{what} per pixel (all rays)"),
        }
    }

    /// The heatmap of a `width` x `height` frame's `pixels` (row-major), coloured on `scale`.
    pub fn heatmap(&self, width: u32, height: u32, pixels: &[RayCounts], scale: Scale) -> Heatmap {
        Heatmap {
            width,
            height,
            values: pixels.iter().map(|r| self.of(r) as f32).collect(),
            what: self.describe(),
            scale,
        }
    }

    /// The heatmap's summary: what it shows, for each ray kind and for all of them the mean, median,
    /// 99th percentile (nearest rank) and largest of this measure over the pixels, and the scale of
    /// its colours with the count at the top of their bar (`ramp`, the heatmap's).
    pub fn summary(&self, width: u32, height: u32, pixels: &[RayCounts], ramp: &Ramp) -> Value {
        let mut per_kind = Map::new();
        for (name, kind) in KINDS.iter().map(|(n, k)| (*n, Some(*k))).chain([("all", None)]) {
            let cost = CostKind { rays: kind, ..*self };
            per_kind.insert(name.into(), stats(pixels.iter().map(|r| cost.of(r)).collect()));
        }
        json!({
            "measure": self.describe(),
            "width": width,
            "height": height,
            "per_pixel": per_kind,
            "scale": ramp.scale.to_string(),
            // One of the counts, or 0: a whole number.
            "scale_top": ramp.top as u64,
        })
    }
}

/// Mean, median, 99th percentile and largest of `values` (nearest rank; nulls for none).
fn stats(mut values: Vec<u64>) -> Value {
    if values.is_empty() {
        return json!({"mean": null, "median": null, "p99": null, "max": null});
    }
    values.sort_unstable();
    let n = values.len();
    let rank = |p: u32| values[nearest_rank(n, p)];
    let mean = values.iter().map(|&v| v as f64).sum::<f64>() / n as f64;
    json!({"mean": mean, "median": rank(50), "p99": rank(99), "max": values[n - 1]})
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::counters::Steps;

    #[test]
    fn kinds_parse_and_refuse_with_the_accepted_values() {
        let parse = |s: &str| s.parse::<CostKind>();
        assert_eq!(
            parse("nodes"),
            Ok(CostKind {
                measure: Measure::Nodes,
                rays: None
            })
        );
        assert_eq!(
            parse("prims:shadow"),
            Ok(CostKind {
                measure: Measure::Prims,
                rays: Some(RayKind::Shadow)
            })
        );
        assert!(
            parse("steps")
                .unwrap_err()
                .starts_with("unknown heatmap \"steps\": expected nodes")
        );
        assert!(
            parse("rays:diffuse")
                .unwrap_err()
                .starts_with("unknown ray kind \"diffuse\"")
        );
    }

    #[test]
    fn a_pixels_count_and_the_summary_statistics() {
        let mut r = RayCounts {
            primary: 2,
            shadow: 3,
            ..Default::default()
        };
        r.steps.camera = Steps { nodes: 10, prims: 4 };
        r.steps.shadow = Steps { nodes: 5, prims: 1 };
        let k = |s: &str| s.parse::<CostKind>().unwrap();
        assert_eq!(k("nodes").of(&r), 15);
        assert_eq!(k("nodes:shadow").of(&r), 5);
        assert_eq!(k("prims:camera").of(&r), 4);
        assert_eq!(k("rays").of(&r), 5);
        assert_eq!(k("rays:camera").of(&r), 2);
        // 1..=100: mean 50.5, nearest-rank median 50, p99 99, max 100.
        let s = stats((1..=100).collect());
        assert_eq!(s, json!({"mean": 50.5, "median": 50, "p99": 99, "max": 100}));
        assert_eq!(
            stats(vec![7]),
            json!({"mean": 7.0, "median": 7, "p99": 7, "max": 7})
        );
        assert_eq!(stats(Vec::new())["max"], Value::Null);
        let pixels = vec![r; 4];
        let map = k("nodes").heatmap(2, 2, &pixels, Scale::default());
        let summary = k("nodes").summary(2, 2, &pixels, &map.ramp());
        assert_eq!(summary["per_pixel"]["shadow"]["max"], 5);
        assert_eq!(summary["per_pixel"]["all"]["median"], 15);
        assert_eq!(summary["measure"], "nodes visited per pixel (all rays)");
        assert_eq!(
            (&summary["scale"], &summary["scale_top"]),
            (&json!("log:p99"), &json!(15))
        );
    }
}
