//! What a render traced, on what, and how fast: `render --stats` and every `bench` print this one
//! report, so that the two commands give the same figures under the same names, as text or JSON.

use std::path::Path;
use std::time::Duration;

use serde_json::{Map, Value, json};
use whitted::accel::counters::Steps;
use whitted::accel::{Accel, Isa};
use whitted::render::spd::{self, Counts};
use whitted::render::{Options, RayCounts};

use super::console::{note, out};

/// The program's version, as `whitted --version` prints it.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
/// The Readme's tolerance: a renderer's counts should be within 10% of its table.
pub const SPD_TOLERANCE: f64 = 0.10;

/// How the report is printed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Lines for people, on stderr.
    Text,
    /// One JSON object, on stdout.
    Json,
}

/// A finished render's or benchmark's figures.
pub struct Report {
    /// The scene as given, or `(default scene)`.
    pub scene: String,
    /// The CPU it ran on ([`whitted::machine::cpu`]).
    pub cpu: String,
    /// What was rendered (an SPD frame's size is its corners').
    pub options: Options,
    /// The structure built (a wide BVH too large for its references is a BVH2).
    pub accel: &'static str,
    /// The wide BVHs' instruction set, `scalar` for the other structures.
    pub simd: &'static str,
    /// Worker threads.
    pub threads: usize,
    /// Passes rendered (`--passes`).
    pub passes: u32,
    /// Seconds to load the scene, build the structure, and render (`bench`: the median frame).
    pub times: [f64; 3],
    /// Rays traced (`bench`: by one frame).
    pub rays: RayCounts,
    /// A `bench` report: rays and render time are one frame's.
    pub per_frame: bool,
}

impl Report {
    /// The report of one pass of `scene` (`None`: the built-in one).
    pub fn new(
        scene: Option<&Path>,
        options: &Options,
        accel: &Accel,
        threads: usize,
        times: [Duration; 3],
        rays: RayCounts,
    ) -> Report {
        Report {
            scene: scene.map_or("(default scene)".into(), crate::cli::setup::scene_name),
            cpu: whitted::machine::cpu(),
            options: *options,
            accel: accel_name(accel),
            simd: simd_name(accel),
            threads,
            passes: 1,
            times: times.map(|t| t.as_secs_f64()),
            rays,
            per_frame: false,
        }
    }

    /// Prints the report: text on stderr (dropped if stderr cannot take it), JSON on stdout.
    pub fn print(&self, format: Format) -> whitted::Result<()> {
        match format {
            Format::Text => {
                note(self.text().trim_end());
                Ok(())
            }
            Format::Json => out(format_args!("{}\n", Value::Object(self.json()))),
        }
    }

    /// The image's size: an SPD frame's pixels lie between its corner rays.
    pub fn size(&self) -> (u32, u32) {
        image_size(&self.options)
    }

    /// Millions of rays per second of `count` rays over the render time.
    fn mrays(&self, count: u64) -> f64 {
        count as f64 / self.times[2].max(1e-9) / 1e6
    }

    /// With `--spd`: our SPD counts and the Readme's row for the scene's file name, if it has one.
    fn spd(&self) -> Option<(Counts, Option<Counts>)> {
        self.options.spd.then(|| {
            let name = Path::new(&self.scene).file_name().unwrap_or_default();
            (
                Counts::of(&self.rays),
                spd::readme_counts(&name.to_string_lossy()),
            )
        })
    }

    /// Lines for people: what ran, the times, the rays by kind with their rates, and the SPD counts.
    pub fn text(&self) -> String {
        let (w, h) = self.size();
        let kernel = self.options.kernel.name();
        let (accel, simd, threads) = (self.accel, self.simd, self.threads);
        let mut out = format!(
            "whitted {VERSION}: {}, {w}x{h}, spp {}, depth {}, {accel} ({simd}), {kernel} kernel, {threads} threads\n",
            self.scene,
            self.options.spp_taken(),
            self.options.max_depth
        );
        out += &format!("cpu        {}\n", self.cpu);
        let [load, build, render] = self.times;
        let (what, passes) = match (self.per_frame, self.passes) {
            (true, _) => ("frame (median)", String::new()),
            (false, 1) => ("render", String::new()),
            (false, n) => ("render", format!(", {n} passes")),
        };
        out += &format!("time       load {load:.3} s, build {build:.3} s, {what} {render:.3} s{passes}\n");
        let rays = if self.per_frame { "rays a frame" } else { "rays" };
        let counted = self.options.count_steps;
        let steps = if counted {
            format!(" {:>10} {:>10}", "nodes/ray", "prims/ray")
        } else {
            String::new()
        };
        out += &format!("{rays:<13}{:>12} {:>10}{steps}\n", "count", "Mrays/s");
        let r = &self.rays;
        for (kind, count, s) in by_kind(r) {
            let steps = if counted {
                let (nodes, prims) = per_ray(s, count);
                format!(" {nodes:>10.2} {prims:>10.2}")
            } else {
                String::new()
            };
            out += &format!("  {kind:<11}{count:>12} {:>10.2}{steps}\n", self.mrays(count));
            if kind == "primary" {
                out += &format!("    hits     {:>12}\n", r.primary_hits);
            }
        }
        if let Some((ours, readme)) = self.spd() {
            out += &spd_text(&ours, readme.as_ref());
        }
        out
    }

    /// One JSON object of the same figures (keys in the README); numbers that are not finite are null.
    pub fn json(&self) -> Map<String, Value> {
        let (w, h) = self.size();
        let r = &self.rays;
        let mut rays: Map<String, Value> = by_kind(r).map(|(k, n, _)| (k.into(), n.into())).collect();
        rays.shift_insert(1, "primary_hits".into(), r.primary_hits.into());
        let rates: Map<String, Value> = by_kind(r)
            .map(|(k, n, _)| (k.into(), self.mrays(n).into()))
            .collect();
        let [load, build, render] = self.times;
        let mut out = match json!({
            "version": VERSION,
            "cpu": self.cpu,
            "scene": self.scene,
            "width": w,
            "height": h,
            "spp": self.options.spp_taken(),
            "max_depth": self.options.max_depth,
            "accel": self.accel,
            "simd": self.simd,
            "kernel": self.options.kernel.name(),
            "threads": self.threads,
            "passes": self.passes,
            "load_s": load,
            "build_s": build,
            "render_s": render,
        }) {
            Value::Object(map) => map,
            _ => unreachable!("json! of an object literal"),
        };
        out.insert(rays_key(self.per_frame).into(), rays.into());
        out.insert("mrays_per_s".into(), self.mrays(r.total()).into());
        out.insert("mrays_per_s_by_kind".into(), rates.into());
        if self.options.count_steps {
            let steps: Map<String, Value> = by_kind(r)
                .map(|(k, n, s)| {
                    let (nodes, prims) = per_ray(s, n);
                    (k.into(), json!({"nodes": nodes, "prims": prims}))
                })
                .collect();
            out.insert("steps_per_ray".into(), steps.into());
        }
        if let Some((ours, readme)) = self.spd() {
            out.insert("spd".into(), spd_json(&ours, readme.as_ref()));
        }
        out
    }
}

/// Mean nodes visited and primitives tested per ray of `rays` rays (0 without rays).
fn per_ray(s: Steps, rays: u64) -> (f64, f64) {
    let n = rays.max(1) as f64;
    (s.nodes as f64 / n, s.prims as f64 / n)
}

/// The image size of a frame rendered with `options` (an SPD frame's corners are one more a side).
pub fn image_size(options: &Options) -> (u32, u32) {
    let less = u32::from(options.spd);
    (options.width - less, options.height - less)
}

/// What the structure built is called on the command line.
pub fn accel_name(accel: &Accel) -> &'static str {
    match accel {
        Accel::Brute(_) => "none",
        Accel::Grid(_) => "grid",
        Accel::Bvh2(_) => "bvh2",
        Accel::Bvh4(_) => "bvh4",
        Accel::Bvh8(_) => "bvh8",
        #[cfg(feature = "embree")]
        Accel::Embree(_) => "embree",
    }
}

/// The instruction set of a wide BVH's kernels; `scalar` for the structures that test one box at a
/// time; `embree` for Embree, which picks its own (SSE2 to AVX-512) when its device is created.
pub fn simd_name(accel: &Accel) -> &'static str {
    #[cfg(feature = "embree")]
    if let Accel::Embree(_) = accel {
        return "embree";
    }
    match accel.simd() {
        Some(Isa::Avx512) => "avx512",
        Some(Isa::Avx2) => "avx2",
        Some(Isa::Portable) => "portable",
        None => "scalar",
    }
}

/// The JSON key of the rays: a bench's are one frame's.
fn rays_key(per_frame: bool) -> &'static str {
    if per_frame { "rays_per_frame" } else { "rays" }
}

/// The rays by kind, then all of them (the primary hits are primary rays, not a kind of their own),
/// each with their steps (zero unless the render counted them).
fn by_kind(r: &RayCounts) -> impl Iterator<Item = (&'static str, u64, Steps)> {
    let s = &r.steps;
    [
        ("primary", r.primary, s.camera),
        ("shadow", r.shadow, s.shadow),
        ("reflected", r.reflected, s.reflected),
        ("refracted", r.refracted, s.refracted),
        ("total", r.total(), s.total()),
    ]
    .into_iter()
}

/// The four counts of the SPD Readme's table, in its order.
fn spd_counts(c: &Counts) -> [(&'static str, u64); 4] {
    [
        ("eye_hits", c.eye_hits),
        ("reflected", c.reflected),
        ("refracted", c.refracted),
        ("shadow", c.shadow),
    ]
}

/// Ours over the Readme's; `None` where the Readme counts none (the ratio has no value).
fn ratio(ours: u64, readme: u64) -> Option<f64> {
    (readme > 0).then(|| ours as f64 / readme as f64)
}

/// The SPD counts beside the Readme's row, as a table.
fn spd_text(ours: &Counts, readme: Option<&Counts>) -> String {
    let Some(readme) = readme else {
        let mut out = "SPD counts   (the Readme has no row for this file name)\n".to_string();
        for (kind, n) in spd_counts(ours) {
            out += &format!("  {:<11}{n:>12}\n", kind.replace('_', " "));
        }
        return out;
    };
    let mut out = format!(
        "{:<13}{:>12} {:>10} {:>7}\n",
        "SPD counts", "ours", "Readme", "ratio"
    );
    for ((kind, n), (_, want)) in spd_counts(ours).into_iter().zip(spd_counts(readme)) {
        let ratio = ratio(n, want).map_or("-".to_string(), |r| format!("{r:.3}"));
        out += &format!("  {:<11}{n:>12} {want:>10} {ratio:>7}\n", kind.replace('_', " "));
    }
    let within = if ours.within(readme, SPD_TOLERANCE) {
        "yes"
    } else {
        "no"
    };
    out + &format!("  within the Readme's 10%: {within} (its counts hold for the default size)\n")
}

/// The SPD counts, the Readme's and their ratios (null where the Readme counts none, and all three
/// null without a row for the file name).
fn spd_json(ours: &Counts, readme: Option<&Counts>) -> Value {
    let object = |c: &Counts| -> Map<String, Value> {
        spd_counts(c)
            .into_iter()
            .map(|(k, n)| (k.into(), n.into()))
            .collect()
    };
    let ratios = readme.map(|want| {
        let pairs = spd_counts(ours).into_iter().zip(spd_counts(want));
        pairs
            .map(|((k, n), (_, w))| (k.to_string(), ratio(n, w).into()))
            .collect::<Map<_, _>>()
    });
    json!({
        "counts": object(ours),
        "readme": readme.map(object),
        "ratio": ratios,
        "within_10_percent": readme.map(|want| ours.within(want, SPD_TOLERANCE)),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use whitted::render::Kernel;

    /// A report of made-up figures whose rates are exact: 0.5 s of render.
    fn report(spd: bool) -> Report {
        let options = Options {
            width: 513,
            height: 513,
            max_depth: 4,
            kernel: Kernel::Packet,
            spp: 0,
            seed: 0,
            roughness: 0.0,
            spd,
            count_steps: false,
        };
        let rays = RayCounts {
            primary: 1000,
            primary_hits: 500,
            shadow: 2000,
            reflected: 300,
            refracted: 200,
            steps: Default::default(),
        };
        Report {
            scene: "scenes/spd/tetra_x.nff".into(),
            cpu: "Test CPU (family 6, model 1), 2 logical CPUs".into(),
            options,
            accel: "bvh4",
            simd: "portable",
            threads: 2,
            passes: 1,
            times: [0.25, 0.125, 0.5],
            rays,
            per_frame: false,
        }
    }

    #[test]
    fn json_has_the_figures_and_the_rates_over_the_render_time() {
        let want = json!({
            "version": VERSION, "cpu": "Test CPU (family 6, model 1), 2 logical CPUs",
            "scene": "scenes/spd/tetra_x.nff", "width": 513, "height": 513,
            "spp": 0, "max_depth": 4, "accel": "bvh4", "simd": "portable", "kernel": "packet",
            "threads": 2, "passes": 1, "load_s": 0.25, "build_s": 0.125, "render_s": 0.5,
            "rays": {"primary": 1000, "primary_hits": 500, "shadow": 2000, "reflected": 300,
                     "refracted": 200, "total": 3500},
            "mrays_per_s": 0.007,
            "mrays_per_s_by_kind": {"primary": 0.002, "shadow": 0.004, "reflected": 0.0006,
                                    "refracted": 0.0004, "total": 0.007},
        });
        let got = Value::Object(report(false).json());
        assert_eq!(got, want);
        // In the order written, as the README lists them.
        let json = report(false).json();
        let keys: Vec<&str> = json.keys().map(String::as_str).collect();
        assert_eq!(keys[..4], ["version", "cpu", "scene", "width"]);
    }

    #[test]
    fn an_spd_report_has_the_image_size_and_the_readmes_row_with_ratios() {
        let v = Value::Object(report(true).json());
        assert_eq!((&v["width"], &v["height"]), (&json!(512), &json!(512)));
        let want = json!({
            "counts": {"eye_hits": 500, "reflected": 300, "refracted": 200, "shadow": 2000},
            "readme": {"eye_hits": 49_788, "reflected": 0, "refracted": 0, "shadow": 46_112},
            "ratio": {"eye_hits": 500.0 / 49_788.0, "reflected": null, "refracted": null,
                      "shadow": 2000.0 / 46_112.0},
            "within_10_percent": false,
        });
        assert_eq!(v["spd"], want);
        let jacks = Report {
            scene: "jacks_1.nff".into(),
            ..report(true)
        };
        let v = Value::Object(jacks.json());
        assert_eq!(
            (
                &v["spd"]["readme"],
                &v["spd"]["ratio"],
                &v["spd"]["within_10_percent"]
            ),
            (&Value::Null, &Value::Null, &Value::Null)
        );
    }

    #[test]
    fn text_is_a_table_of_the_same_figures() {
        let want = format!(
            "whitted {VERSION}: scenes/spd/tetra_x.nff, 512x512, spp 0, depth 4, bvh4 (portable), packet kernel, 2 threads
cpu        Test CPU (family 6, model 1), 2 logical CPUs
time       load 0.250 s, build 0.125 s, render 0.500 s
rays                count    Mrays/s
  primary            1000       0.00
    hits              500
  shadow             2000       0.00
  reflected           300       0.00
  refracted           200       0.00
  total              3500       0.01
SPD counts           ours     Readme   ratio
  eye hits            500      49788   0.010
  reflected           300          0       -
  refracted           200          0       -
  shadow             2000      46112   0.043
  within the Readme's 10%: no (its counts hold for the default size)
"
        );
        assert_eq!(report(true).text(), want);
        let bench = Report {
            per_frame: true,
            passes: 1,
            ..report(false)
        };
        let text = bench.text();
        assert!(!text.contains("render 0.500 s"), "{text}");
        assert!(text.contains("frame (median) 0.500 s\nrays a frame "), "{text}");
        let passes = Report {
            passes: 3,
            ..report(false)
        };
        assert!(passes.text().contains("render 0.500 s, 3 passes\n"));
    }
}
