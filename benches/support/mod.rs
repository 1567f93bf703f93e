//! Shared set-up for the benches: the shared meshes (skipped with a note when absent) and
//! near-contact poses.
#![allow(dead_code)]

use stochastic_collision::bvh::CollisionMesh;
use stochastic_collision::mesh::{TriMesh, generate};
use stochastic_collision::poses::{ApproachPose, near_contact_poses};

// The tests' helpers: the list of shared meshes and where they live.
#[path = "../../tests/common/mod.rs"]
mod common;

/// `(name, mesh)` for every shared mesh present, plus two generated ones.
pub fn bench_meshes() -> Vec<(String, TriMesh)> {
    let mut out = vec![
        ("icosphere_20k".to_string(), generate::icosphere(1.0, 5)),
        ("torus_32k".to_string(), generate::torus(1.0, 0.3, 256, 64)),
    ];
    for file in common::QUERY_MESHES {
        let path = common::shared_mesh_dir().join(file);
        match TriMesh::from_obj(&path) {
            Ok(mesh) => out.push((file.trim_end_matches(".obj").to_string(), mesh)),
            Err(e) => eprintln!("note: skipping {file}: {e}"),
        }
    }
    out
}

/// A shared mesh by file name, or `None` (with a note) when it is not there.
pub fn shared_mesh(file: &str) -> Option<TriMesh> {
    let path = common::shared_mesh(file)?;
    match TriMesh::from_obj(&path) {
        Ok(mesh) => Some(mesh),
        Err(e) => {
            eprintln!("note: skipping {file}: {e}");
            None
        }
    }
}

/// Near-contact poses of a mesh against itself: offsets within ±2 % of the size.
pub fn bench_poses(mesh: &CollisionMesh, count: usize) -> Vec<ApproachPose> {
    near_contact_poses(mesh, mesh, count, 0.02, 0x5eed)
}
