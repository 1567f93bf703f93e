//! Regenerates the project's own assets (the only meshes `assets/` may hold): a torus, a
//! coarser torus, and near-contact poses for the README's `query` example command.
//!
//! ```text
//! cargo run --release --example make_assets [-- DIR]   # default: assets/
//! ```
use std::path::PathBuf;

use stochastic_collision::bvh::CollisionMesh;
use stochastic_collision::mesh::generate;
use stochastic_collision::poses::{near_contact_poses, write_poses_csv};

fn main() -> std::io::Result<()> {
    let dir = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("assets"));
    std::fs::create_dir_all(&dir)?;
    let torus = generate::torus(1.0, 0.3, 128, 48);
    torus.write_obj(std::fs::File::create(dir.join("torus.obj"))?)?;
    let cm = CollisionMesh::new(torus);
    // 64 poses within ±3 % of the torus's size from first contact, seeded: half of them collide.
    let poses = near_contact_poses(&cm, &cm, 64, 0.03, 2026);
    write_poses_csv(
        std::fs::File::create(dir.join("torus_poses.csv"))?,
        poses.iter().map(|p| p.pose),
    )?;
    println!(
        "wrote {} ({} triangles) and {} ({} poses)",
        dir.join("torus.obj").display(),
        cm.mesh().triangle_count(),
        dir.join("torus_poses.csv").display(),
        poses.len()
    );
    Ok(())
}
