//! The peer both benches measure against: the `obvhs` crate (0.4, a dev-dependency only), built from our
//! scene's triangles with its own presets. Its CWBVH (Ylitie et al. 2017, "Efficient Incoherent Ray
//! Traversal on GPUs Through Compressed Wide BVHs": 8-wide, quantised child boxes) and its BVH2 both come
//! from PLOC (Meister & Bittner 2018) with reinsertion; `very_slow_build` adds pre-splitting.

use std::time::Duration;

use obvhs::BvhBuildParams;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::builder::build_bvh2_from_tris;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::builder::build_cwbvh_from_tris;
use obvhs::triangle::Triangle;
use whitted::scene::Scene;

/// The scene's triangles as obvhs takes them.
pub fn triangles(scene: &Scene) -> Vec<Triangle> {
    (0..scene.triangles.len())
        .map(|i| {
            let [v0, v1, v2] = scene.triangles.vertices(i);
            Triangle {
                v0: v0.into(),
                v1: v1.into(),
                v2: v2.into(),
            }
        })
        .collect()
}

/// obvhs' CWBVH over `tris` with `params`, as its helper builds it (on the current rayon pool).
pub fn cwbvh(tris: &[Triangle], params: BvhBuildParams) -> CwBvh {
    build_cwbvh_from_tris(tris, params, &mut Duration::default())
}

/// obvhs' BVH2 over `tris` with `params` (leaves collapsed by its SAH, up to 8 triangles).
pub fn bvh2(tris: &[Triangle], params: BvhBuildParams) -> Bvh2 {
    build_bvh2_from_tris(tris, params, &mut Duration::default())
}
