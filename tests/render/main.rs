//! The renderer: every scene with every accelerator and kernel against the recorded images and brute
//! force (`render_scenes`), the Whitted integrator against closed forms (`shading`), smooth normals
//! (`mesh_normals`), distribution ray tracing and progressive passes (`sampling`), the skybox (`env`),
//! the SPD procedure's ray counts (`spd`), and deep ray trees and option bounds (`limits`).

#[path = "../common/mod.rs"]
mod common;

mod counters;
mod env;
mod limits;
mod mesh_normals;
mod render_scenes;
mod sampling;
mod shading;
mod spd;
