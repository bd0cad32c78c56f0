//! `whitted info`: what a scene holds, as text or as one JSON object with the same fields.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use glam::Vec3;
use serde_json::{Map, Value, json};
use whitted::accel::bvh2::Stats;
use whitted::accel::quality::TreeView;
use whitted::accel::{Accel, AccelKind, Prims};
use whitted::render::spd::{self, Counts};
use whitted::scene::Scene;

use super::Failure;
use super::console;
use super::frame::{BuildKind, build_options};
use super::report::{accel_name, image_size, simd_name};
use super::setup::{load_scene, scene_name, warn};

/// Arguments of `whitted info`.
#[derive(Args)]
pub struct InfoArgs {
    /// The scene: .p3f, .nff, .ply or .obj, optionally gzipped; `-` reads it from standard input.
    scene: PathBuf,
    /// The scene's format, whatever its name: p3f, nff, ply or obj (for `-`, standard input, the
    /// format is otherwise told from its first statement).
    #[arg(long, value_parser = crate::cli::values::scene_format)]
    pub format: Option<whitted::scene::Format>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Also build this accelerator (none, grid, bvh2, bvh4, bvh8, embree with the `embree` feature) and
    /// report its build time and shape.
    #[arg(long)]
    accel: Option<AccelKind>,
    /// How the BVHs are built: auto (today optimized), sah, optimized (binned SAH, then
    /// reinsertion) or midpoint (the BVH2 only; the wide BVHs collapse a binned-SAH BVH2).
    #[arg(long, default_value = "auto")]
    build: BuildKind,
    /// SAH bins per axis (2 to 64).
    #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u32).range(2..=64),
          allow_negative_numbers = true)]
    bins: u32,
    /// Also print the frame `render --spd` would render (the SPD test procedure's) and the SPD Readme's
    /// ray counts for the scene's file name. Nothing is rendered: `render --spd --stats` counts ours.
    #[arg(long)]
    spd: bool,
    /// With a BVH (`--accel bvh2`, `bvh4` or `bvh8`): also its end-point overlap (EPO; Aila, Karras
    /// and Laine 2013), the surface of other subtrees' triangles inside each node's box, weighted as
    /// SAH: the other half of a tree's quality (seconds on a large mesh; where measuring it exactly
    /// would take too long, estimated from a sample of triangles, which the output says).
    #[arg(long, requires = "accel")]
    epo: bool,
}

/// Loads the scene and prints its summary.
pub fn run(args: &InfoArgs) -> Result<(), Failure> {
    if args.epo
        && !matches!(
            args.accel,
            Some(AccelKind::Bvh2 | AccelKind::Bvh4 | AccelKind::Bvh8)
        )
    {
        return Err(Failure::Usage(whitted::Error::msg(
            "--epo measures a BVH: it needs --accel bvh2, bvh4 or bvh8",
        )));
    }
    let start = Instant::now();
    let scene = load_scene(Some(&args.scene), args.format)?;
    let load_s = start.elapsed().as_secs_f64();
    warn(&scene.warnings);
    let built = match args.accel {
        Some(kind) => {
            let start = Instant::now();
            let options = build_options(args.build, args.bins as usize);
            let accel = Accel::try_build_with(Prims::new(&scene), kind, options)?;
            Some((start.elapsed().as_secs_f64(), accel))
        }
        None => None,
    };
    let readme = args.spd.then(|| readme(&args.scene));
    if args.json {
        let mut out = json(&args.scene, &scene, load_s);
        if let Some((build_s, accel)) = &built {
            out.insert("build_s".into(), (*build_s).into());
            let mut shape = accel_json(accel);
            if let (Some(view), Value::Object(map)) = (tree_view(accel), &mut shape) {
                map.insert("leaf_depths".into(), view.leaf_depths().into());
                if args.epo {
                    let epo = view.epo(&accel.prims());
                    map.insert("epo_cost".into(), epo.cost.into());
                    map.insert("epo_sampled".into(), epo.sampled.into());
                }
            }
            out.insert("accel".into(), shape);
        }
        if let Some(readme) = readme {
            out.insert("spd".into(), spd_json(&scene, readme.as_ref()));
        }
        console::out(format_args!("{}\n", Value::Object(out)))?;
    } else {
        let mut page = text(&args.scene, &scene, load_s);
        if let Some((build_s, accel)) = built {
            page += &format!(
                "accelerator   {}\nbuild time    {build_s:.3} s\n",
                accel.describe()
            );
            if let Some(view) = tree_view(&accel) {
                let depths = view.leaf_depths();
                let listed: Vec<String> = (0..depths.len())
                    .filter(|&d| depths[d] > 0)
                    .map(|d| format!("{d}:{}", depths[d]))
                    .collect();
                page += &format!("leaf depths   {}\n", listed.join(" "));
                if args.epo {
                    let epo = view.epo(&accel.prims());
                    page += &format!("EPO cost      {:.2}", epo.cost);
                    if let Some(k) = epo.sampled {
                        page += &format!(" (estimated from {k} of {} triangles)", epo.triangles);
                    }
                    page += "\n";
                }
            }
        }
        if let Some(readme) = readme {
            page += &spd_text(&scene, readme.as_ref());
        }
        console::out(page)?;
    }
    Ok(())
}

/// A BVH as [`whitted::accel::quality`] reads it; `None` for the other structures.
fn tree_view(accel: &Accel) -> Option<TreeView> {
    match accel {
        Accel::Bvh2(b) => Some(TreeView::from(b)),
        Accel::Bvh4(b) => Some(TreeView::from(b)),
        Accel::Bvh8(b) => Some(TreeView::from(b)),
        _ => None,
    }
}

/// The counts printed first, as (JSON key, value).
fn counts(scene: &Scene) -> [(&'static str, usize); 8] {
    [
        ("spheres", scene.spheres.radius.len()),
        ("triangles", scene.triangles.len()),
        ("boxes", scene.boxes.material.len()),
        ("planes", scene.planes.material.len()),
        ("cones", scene.cones.material.len()),
        ("point_lights", scene.point_lights.len()),
        ("area_lights", scene.area_lights.len()),
        ("materials", scene.materials.len()),
    ]
}

/// A float as JSON: its shortest decimal form (the one `{}` prints, which reads back as the same
/// `f32`), or null if it is not finite (JSON has no infinity).
fn number(v: f32) -> Value {
    v.to_string().parse::<f64>().map_or(Value::Null, Value::from)
}

fn vec3_json(v: Vec3) -> Value {
    Value::Array(v.to_array().map(number).to_vec())
}

fn vec3(v: Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

/// One JSON object with the text's fields, in its order. Bounds are null for a scene with nothing
/// bounded (planes alone).
fn json(path: &Path, scene: &Scene, load_s: f64) -> Map<String, Value> {
    let mut out = Map::new();
    out.insert("scene".into(), scene_name(path).into());
    for (k, v) in counts(scene) {
        out.insert(k.into(), v.into());
    }
    let c = &scene.camera;
    let b = scene.bounds();
    let bound = |v| if b.is_empty() { Value::Null } else { vec3_json(v) };
    let rest = json!({
        "degenerate_triangles": scene.degenerate_triangles(),
        "width": c.width,
        "height": c.height,
        "from": vec3_json(c.from),
        "at": vec3_json(c.at),
        "up": vec3_json(c.up),
        "fov_y": number(c.fov_y),
        "aperture": number(c.aperture),
        "focal": number(c.focal),
        "spp": scene.spp,
        "bounds_min": bound(b.min),
        "bounds_max": bound(b.max),
        "load_s": load_s,
    });
    if let Value::Object(rest) = rest {
        out.extend(rest);
    }
    out
}

/// The built structure: its kind and instruction set, and its shape (the BVHs' nodes, leaves, depth,
/// leaf sizes and SAH cost; the grid's cells and references).
fn accel_json(accel: &Accel) -> Value {
    let mut out = Map::new();
    out.insert("kind".into(), accel_name(accel).into());
    out.insert("simd".into(), simd_name(accel).into());
    let shape = match accel {
        Accel::Brute(_) => json!({}),
        Accel::Grid(g) => {
            let s = g.stats();
            json!({
                "resolution": s.resolution,
                "cells": s.cells,
                "empty_cells": s.empty_cells,
                "references": s.references,
                "loose": s.loose,
            })
        }
        Accel::Bvh2(b) => tree_json(&b.stats()),
        Accel::Bvh4(b) => tree_json(&b.stats()),
        Accel::Bvh8(b) => tree_json(&b.stats()),
        #[cfg(feature = "embree")]
        Accel::Embree(e) => {
            let (triangles, others) = e.counts();
            json!({
                "version": e.version(),
                "quality": e.quality().name(),
                "triangles": triangles,
                "user_primitives": others,
            })
        }
    };
    if let Value::Object(shape) = shape {
        out.extend(shape);
    }
    Value::Object(out)
}

/// A hierarchy's shape: `leaf_sizes[k]` counts the leaves of k primitives, the last those of 16 or more.
fn tree_json(s: &Stats) -> Value {
    json!({
        "nodes": s.nodes,
        "leaves": s.leaves,
        "depth": s.depth,
        "leaf_sizes": s.histogram,
        "sah_cost": s.sah,
    })
}

/// The Readme's counts for the scene's file name, if it names one of its databases.
fn readme(path: &Path) -> Option<Counts> {
    spd::readme_counts(&path.file_name().unwrap_or_default().to_string_lossy())
}

/// The SPD frame and the Readme's counts, as `info --json`'s `spd` object.
fn spd_json(scene: &Scene, readme: Option<&Counts>) -> Value {
    let options = spd::options(scene);
    let (w, h) = image_size(&options);
    json!({
        "width": w,
        "height": h,
        "corner_rays": u64::from(options.width) * u64::from(options.height),
        "spp": options.spp,
        "max_depth": options.max_depth,
        "readme": readme.map(|c| json!({
            "eye_hits": c.eye_hits,
            "reflected": c.reflected,
            "refracted": c.refracted,
            "shadow": c.shadow,
        })),
    })
}

/// The SPD frame and the Readme's counts, as lines.
fn spd_text(scene: &Scene, readme: Option<&Counts>) -> String {
    let options = spd::options(scene);
    let (w, h) = image_size(&options);
    let mut out = format!(
        "spd           {w}x{h} pixels from {}x{} corner rays, spp {}, {} bounces\n",
        options.width, options.height, options.spp, options.max_depth
    );
    out += &match readme {
        Some(c) => format!(
            "spd readme    eye hits {}, reflected {}, refracted {}, shadow {} (at the default size)\n",
            c.eye_hits, c.reflected, c.refracted, c.shadow
        ),
        None => "spd readme    (no row for this file name)\n".to_string(),
    };
    out
}

fn text(path: &Path, scene: &Scene, load_s: f64) -> String {
    let mut out = format!("scene         {}\n", scene_name(path));
    for (k, v) in counts(scene) {
        out += &format!("{:<13} {v}\n", k.replace('_', " "));
    }
    let degenerate = scene.degenerate_triangles();
    if degenerate > 0 {
        out += &format!("              ({degenerate} triangles have zero area and are never hit)\n");
    }
    let c = &scene.camera;
    out += &format!("resolution    {}x{}\n", c.width, c.height);
    out += &format!(
        "camera        from {} at {} up {}, fov {}°, aperture {}, focal {}\n",
        vec3(c.from),
        vec3(c.at),
        vec3(c.up),
        c.fov_y,
        c.aperture,
        c.focal
    );
    out += &format!("spp           {}\n", scene.spp);
    let b = scene.bounds();
    if b.is_empty() {
        out += "bounds        (no bounded primitives)\n";
    } else {
        out += &format!("bounds        {} .. {}\n", vec3(b.min), vec3(b.max));
    }
    out += &format!("load time     {:.3} s\n", load_s);
    out
}
