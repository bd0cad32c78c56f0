//! `whitted info`: what a scene holds.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;
use whitted::accel::{Accel, AccelKind, Prims};
use whitted::scene::{self, Scene};

use super::args::{BuildKind, build_options};

/// Arguments of `whitted info`.
#[derive(Args)]
pub struct InfoArgs {
    /// The scene: .p3f, .nff, .ply or .obj, optionally gzipped.
    scene: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Also build this accelerator (none, grid, bvh2, bvh4, bvh8) and report its build time and shape.
    #[arg(long)]
    accel: Option<AccelKind>,
    /// The BVH2 builder when `--accel bvh2`: sah or midpoint.
    #[arg(long, default_value = "sah")]
    build: BuildKind,
    /// SAH bins per axis (2 to 64).
    #[arg(long, default_value_t = 12, value_parser = clap::value_parser!(u32).range(2..=64))]
    bins: u32,
}

/// Loads the scene and prints its summary.
pub fn run(args: &InfoArgs) -> whitted::Result<()> {
    let start = Instant::now();
    let scene = scene::load(&args.scene)?;
    let load_s = start.elapsed().as_secs_f64();
    for w in &scene.warnings {
        eprintln!("whitted: warning: {w}");
    }
    let built = args.accel.map(|kind| {
        let start = Instant::now();
        let options = build_options(args.build, args.bins as usize);
        let accel = Accel::build_with(Prims::new(&scene), kind, options);
        (start.elapsed().as_secs_f64(), accel.describe())
    });
    if args.json {
        let mut out = json(&scene, load_s);
        if let Some((build_s, _)) = &built {
            out.pop();
            out += &format!(", \"build_s\": {build_s:.6}}}");
        }
        println!("{out}");
    } else {
        print!("{}", text(&args.scene, &scene, load_s));
        if let Some((build_s, description)) = built {
            println!("accelerator   {description}");
            println!("build time    {build_s:.3} s");
        }
    }
    Ok(())
}

fn counts(scene: &Scene) -> [(&'static str, usize); 10] {
    let c = &scene.camera;
    [
        ("spheres", scene.spheres.radius.len()),
        ("triangles", scene.triangles.len()),
        ("boxes", scene.boxes.material.len()),
        ("planes", scene.planes.material.len()),
        ("cones", scene.cones.material.len()),
        ("point_lights", scene.point_lights.len()),
        ("area_lights", scene.area_lights.len()),
        ("materials", scene.materials.len()),
        ("width", c.width as usize),
        ("height", c.height as usize),
    ]
}

fn vec3(v: glam::Vec3) -> String {
    format!("[{}, {}, {}]", v.x, v.y, v.z)
}

/// One JSON object: the counts, then the camera, bounds and timings. Every value is a number or an array
/// of numbers, so no string escaping is needed.
fn json(scene: &Scene, load_s: f64) -> String {
    let mut fields: Vec<String> = counts(scene)
        .iter()
        .map(|(k, v)| format!("\"{k}\": {v}"))
        .collect();
    let c = &scene.camera;
    fields.push(format!(
        "\"degenerate_triangles\": {}",
        scene.degenerate_triangles()
    ));
    fields.push(format!("\"spp\": {}", scene.spp));
    fields.push(format!("\"fov_y\": {}", c.fov_y));
    fields.push(format!("\"from\": {}", vec3(c.from)));
    fields.push(format!("\"at\": {}", vec3(c.at)));
    fields.push(format!("\"up\": {}", vec3(c.up)));
    let b = scene.bounds();
    if !b.is_empty() {
        fields.push(format!("\"bounds_min\": {}", vec3(b.min)));
        fields.push(format!("\"bounds_max\": {}", vec3(b.max)));
    }
    fields.push(format!("\"load_s\": {load_s:.6}"));
    format!("{{{}}}", fields.join(", "))
}

fn text(path: &std::path::Path, scene: &Scene, load_s: f64) -> String {
    let mut out = format!("scene         {}\n", path.display());
    for (k, v) in counts(scene).iter().take(8) {
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
