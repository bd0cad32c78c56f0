//! `include` statements loaded side by side: the meshes of consecutive includes are read and moved on
//! the threads of the pool the scene is loaded in, and join the scene in file order as they come, so
//! the store (and every image) is the one that loading them in turn gives.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use super::finite::overflow_message;
use super::lex::Tok;
use super::ply::Threads;
use super::store::{MaterialId, Scene};
use super::{MeshData, load_mesh_on};
use crate::error::{Error, Location, Result};

/// An `include model [scale S] [translate X Y Z]` read, its mesh not yet loaded.
pub(super) struct Include {
    /// The statement's file name, where its errors point.
    pub tok: Tok,
    pub path: PathBuf,
    pub scale: f32,
    pub translate: Vec3,
    /// The material current at the statement.
    pub material: MaterialId,
}

impl Include {
    /// An error at the statement in the scene file `scene`.
    fn error(&self, scene: &Path, message: impl Into<String>) -> Error {
        Error::at(scene, self.tok.line, self.tok.col, message)
    }

    /// The mesh, scaled and moved, its PLY body read on `threads`.
    fn mesh(&self, scene: &Path, threads: Threads) -> Result<MeshData> {
        let mut mesh = load_mesh_on(&self.path, threads).map_err(|e| match e.location {
            // A mesh of an unknown kind: say so at the include line.
            Location::File if e.path.as_deref() == Some(self.path.as_path()) => self.error(scene, e.message),
            _ => e,
        })?;
        for p in &mut mesh.positions {
            *p = *p * self.scale + self.translate;
        }
        // Normals transform by the inverse transpose, 1/S here: a uniform scale keeps their direction,
        // a negative one (a point reflection) reverses it.
        if self.scale < 0.0 {
            for n in &mut mesh.normals {
                *n = -*n;
            }
        }
        Ok(mesh)
    }
}

/// Loads `includes`, statements of the scene file `file`, on the current pool's threads and adds
/// their meshes to `scene` in their order. The error is the first include's, in file order.
pub(super) fn load(includes: &[Include], file: &Path, scene: &mut Scene) -> Result<()> {
    let joiner = Joiner {
        ready: Mutex::new((0, BTreeMap::new())),
        scene: Mutex::new(Ok(scene)),
        includes,
        file,
    };
    // Each thread takes the next include in file order, so that meshes wait in line for few others.
    let taken = AtomicUsize::new(0);
    let pool = rayon::current_num_threads();
    (0..pool.min(includes.len())).into_par_iter().for_each(|_| {
        loop {
            let k = taken.fetch_add(1, Ordering::Relaxed);
            let Some(include) = includes.get(k) else {
                break;
            };
            // A PLY is cut into pieces for the threads only where some will have no include of their
            // own: cutting costs some 8% more instructions, which busy threads would pay for nothing.
            let threads = if includes.len() - k < pool {
                Threads::All
            } else {
                Threads::One
            };
            joiner.offer(k, include.mesh(file, threads));
        }
    });
    // Every mesh was taken by the thread that found it next in line; an error stopped the adding.
    let (next, _) = joiner.ready.into_inner().unwrap_or_else(|e| e.into_inner());
    debug_assert_eq!(next, includes.len(), "a mesh left in line");
    joiner
        .scene
        .into_inner()
        .unwrap_or_else(|e| e.into_inner())
        .map(drop)
}

/// Adds the meshes of includes to the scene in file order as they are loaded, out of order: whichever
/// thread holds the scene adds every mesh next in line, while the others go on loading.
struct Joiner<'a> {
    /// The index of the next include to add, and the meshes loaded before their turn.
    ready: Mutex<(usize, BTreeMap<usize, Result<MeshData>>)>,
    /// The scene, or the first error in file order (after which nothing more is added).
    scene: Mutex<Result<&'a mut Scene>>,
    includes: &'a [Include],
    file: &'a Path,
}

impl Joiner<'_> {
    /// Takes the mesh of include `k` and adds what is next in line, unless another thread is adding.
    fn offer(&self, k: usize, mesh: Result<MeshData>) {
        self.lock_ready().1.insert(k, mesh);
        // A thread that finds the scene taken leaves its mesh in line: the holder looks again after
        // letting go, so a mesh offered meanwhile is never left behind.
        while let Ok(mut scene) = self.scene.try_lock() {
            while let Some((k, mesh)) = self.next_in_line() {
                if let Ok(s) = &mut *scene
                    && let Err(e) = mesh.and_then(|m| self.add(k, &m, s))
                {
                    *scene = Err(e);
                }
            }
            drop(scene);
            let (next, loaded) = &*self.lock_ready();
            if !loaded.contains_key(next) {
                return;
            }
        }
    }

    /// The mesh whose turn it is, if loaded.
    fn next_in_line(&self) -> Option<(usize, Result<MeshData>)> {
        let mut ready = self.lock_ready();
        let (next, loaded) = &mut *ready;
        let mesh = loaded.remove(next)?;
        *next += 1;
        Some((*next - 1, mesh))
    }

    fn lock_ready(&self) -> std::sync::MutexGuard<'_, (usize, BTreeMap<usize, Result<MeshData>>)> {
        self.ready.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Adds the mesh of include `k` to `scene`; what it added must lie within the range of `f32`.
    fn add(&self, k: usize, mesh: &MeshData, scene: &mut Scene) -> Result<()> {
        let include = &self.includes[k];
        let before = scene.counts();
        scene
            .add_mesh(mesh, include.material)
            .map_err(|e| include.error(self.file, e.message))?;
        match scene.overflow_since(before) {
            Some(what) => Err(include.error(self.file, overflow_message(what))),
            None => Ok(()),
        }
    }
}
