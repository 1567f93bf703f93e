//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

pub mod cli;
pub mod shapes;

/// The shared meshes the exact-query and ADB issues name for checks against parry and for
/// the benchmarks, smallest first.
pub const QUERY_MESHES: [&str; 6] = [
    "bunny.obj",
    "armadillo.obj",
    "dragon_50k.obj",
    "stanford-bunny.obj",
    "small_intestine_100k.obj",
    "ogre.obj",
];

/// Environment variable that turns a missing shared mesh into a test failure (set by `.ci/run`).
pub const REQUIRE_SHARED: &str = "STOCHASTIC_COLLISION_REQUIRE_SHARED_MESHES";

/// Directory of the shared third-party meshes (`../shared/assets/meshes` beside the project),
/// overridable with `STOCHASTIC_COLLISION_MESHES`.
pub fn shared_mesh_dir() -> PathBuf {
    match std::env::var_os("STOCHASTIC_COLLISION_MESHES") {
        Some(dir) => PathBuf::from(dir),
        None => PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/meshes"),
    }
}

/// Path of a shared mesh file, or `None` (with a printed note) when the shared meshes are not
/// there, as on a user's fresh clone. Panics instead when [`REQUIRE_SHARED`] is set, so CI
/// cannot pass by skipping.
pub fn shared_mesh(file: &str) -> Option<PathBuf> {
    let path = shared_mesh_dir().join(file);
    if path.is_file() {
        return Some(path);
    }
    if std::env::var_os(REQUIRE_SHARED).is_some() {
        panic!(
            "shared mesh {} is missing and {REQUIRE_SHARED} is set",
            path.display()
        );
    }
    eprintln!(
        "note: skipping: shared mesh {} not found (a fresh clone has no ../shared)",
        path.display()
    );
    None
}

/// A 14 × 14 cloth grid folded through itself (its halves cross along a curve): a mesh with
/// self-intersections and near pairs at every distance.
pub fn folded_cloth() -> stochastic_collision::mesh::TriMesh {
    let mut cloth = stochastic_collision::mesh::generate::cloth_grid(2.0, 2.0, 14, 14);
    let folded: Vec<glam::Vec3> = cloth
        .positions()
        .iter()
        .map(|p| {
            let a = p.x * 2.6;
            glam::Vec3::new(
                0.5 * a.sin(),
                0.5 * (1.0 - a.cos()) * a.signum() * 0.9,
                p.z + 0.2 * p.x,
            )
        })
        .collect();
    cloth.set_positions(&folded).unwrap();
    cloth
}

/// `mesh`'s triangles with corners at one position (bit for bit, -0 as 0) joined under the
/// lowest index: the reference for self-collision's adjacency, by a map of positions.
pub fn joined_triangles(mesh: &stochastic_collision::mesh::TriMesh) -> Vec<[u32; 3]> {
    let mut first: std::collections::HashMap<[u32; 3], u32> = std::collections::HashMap::new();
    let representative: Vec<u32> = mesh
        .positions()
        .iter()
        .enumerate()
        .map(|(v, p)| {
            *first
                .entry((*p + glam::Vec3::ZERO).to_array().map(f32::to_bits))
                .or_insert(v as u32)
        })
        .collect();
    mesh.triangles()
        .iter()
        .map(|t| t.map(|v| representative[v as usize]))
        .collect()
}
