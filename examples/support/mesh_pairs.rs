//! Pairs of different meshes for the accuracy report's held-out evaluation
//! (`accuracy_vs_time --pairs`): sizes one 10–30× the other, smooth scans against spiky and
//! thin shapes, and generated CAD-like parts. None of these meshes is one the ADB defaults were
//! chosen on (the report's same-mesh set); every generated shape is seeded.
use std::path::Path;

use glam::Vec3;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::mesh::{MeshError, TriMesh, generate};

/// One held-out pair: a name for the tables, and the two meshes (sized as the name says; the
/// first is the smaller).
pub struct MeshPair {
    pub name: String,
    pub first: TriMesh,
    pub second: TriMesh,
}

/// The diagonal of a mesh's bounding box.
pub fn size(mesh: &TriMesh) -> f32 {
    let (lo, hi) = mesh.positions().iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    (hi - lo).length()
}

/// `mesh` scaled uniformly so that its box diagonal is `target`.
pub fn sized(mesh: &TriMesh, target: f32) -> Result<TriMesh, MeshError> {
    mesh.scaled(Vec3::splat(target / size(mesh)))
}

/// An icosphere whose vertices are pushed out along their direction by up to `spike` of its
/// radius, one vertex in `every` (seeded): a closed, spiky ball.
pub fn spiky_sphere(radius: f32, subdivisions: u32, spike: f32, every: u32, seed: u64) -> TriMesh {
    let ball = generate::icosphere(radius, subdivisions);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let positions = ball
        .positions()
        .iter()
        .map(|&p| {
            if rng.random_range(0..every) == 0 {
                p * (1.0 + spike * rng.random_range(0.3f32..1.0))
            } else {
                p
            }
        })
        .collect();
    TriMesh::new(positions, ball.triangles().to_vec()).expect("the icosphere's triangles")
}

/// A bundle of `n × n` parallel closed pipes (CAD-like: many thin parallel parts).
pub fn pipe_bundle(n: u32, radius: f32, length: f32) -> TriMesh {
    let pitch = 2.6 * radius;
    let parts: Vec<TriMesh> = (0..n * n)
        .map(|k| {
            let (i, j) = ((k % n) as f32, (k / n) as f32);
            generate::tube(radius, length, 24, 24, true)
                .translated(Vec3::new(i * pitch, 0.0, j * pitch))
                .expect("finite offset")
        })
        .collect();
    TriMesh::merged(&parts).expect("few vertices")
}

/// A box of thin walls: five plates (a floor and four sides, an open top), each a closed thin
/// cuboid (CAD-like: thin layered parts).
pub fn thin_walled_box(half: f32, wall: f32) -> TriMesh {
    let plate = |half_extents: Vec3, centre: Vec3| {
        generate::cuboid(half_extents, 6)
            .translated(centre)
            .expect("finite offset")
    };
    let t = wall / 2.0;
    let parts = [
        plate(Vec3::new(half, t, half), Vec3::new(0.0, -half, 0.0)),
        plate(Vec3::new(t, half, half), Vec3::new(-half, 0.0, 0.0)),
        plate(Vec3::new(t, half, half), Vec3::new(half, 0.0, 0.0)),
        plate(Vec3::new(half, half, t), Vec3::new(0.0, 0.0, -half)),
        plate(Vec3::new(half, half, t), Vec3::new(0.0, 0.0, half)),
    ];
    TriMesh::merged(&parts).expect("few vertices")
}

/// A plate cut by parallel slots: `bars` closed thin bars side by side with gaps between them
/// (CAD-like: a perforated sheet).
pub fn slotted_plate(bars: u32, half: f32, thickness: f32) -> TriMesh {
    let pitch = 2.0 * half / bars as f32;
    let parts: Vec<TriMesh> = (0..bars)
        .map(|i| {
            let x = -half + pitch * (i as f32 + 0.5);
            generate::cuboid(Vec3::new(0.3 * pitch, thickness / 2.0, half), 4)
                .translated(Vec3::new(x, 0.0, 0.0))
                .expect("finite offset")
        })
        .collect();
    TriMesh::merged(&parts).expect("few vertices")
}

/// `layers` thin closed sheets stacked with gaps between them, each slightly bent (CAD-like:
/// layered body panels).
pub fn layered_sheets(layers: u32, half: f32, thickness: f32, gap: f32) -> TriMesh {
    let parts: Vec<TriMesh> = (0..layers)
        .map(|k| {
            let sheet = generate::cuboid(Vec3::new(half, thickness / 2.0, half), 12);
            let bend = 0.1 * half;
            let positions = sheet
                .positions()
                .iter()
                .map(|&p| {
                    let y = p.y + k as f32 * (thickness + gap) + bend * (p.x / half).powi(2);
                    Vec3::new(p.x, y, p.z)
                })
                .collect();
            TriMesh::new(positions, sheet.triangles().to_vec()).expect("the cuboid's triangles")
        })
        .collect();
    TriMesh::merged(&parts).expect("few vertices")
}

/// Generated CAD-like parts, each for a benchmark of the part against itself as in the
/// papers (which used a car body, pipes and a door lock): a pipe bundle, a box of thin walls, a
/// slotted plate and layered sheets.
pub fn cad_parts() -> Vec<(String, TriMesh)> {
    vec![
        ("pipe bundle".into(), pipe_bundle(4, 0.1, 1.5)),
        ("thin-walled box".into(), thin_walled_box(1.0, 0.02)),
        ("slotted plate".into(), slotted_plate(12, 1.0, 0.04)),
        ("layered sheets".into(), layered_sheets(6, 1.0, 0.02, 0.05)),
    ]
}

/// The held-out pairs; a shared mesh that cannot be read skips its pairs with a note.
pub fn held_out_pairs(shared_dir: &Path) -> Vec<MeshPair> {
    let load = |name: &str| TriMesh::from_obj(shared_dir.join(format!("{name}.obj")));
    let mut out = Vec::new();
    let mut push = |name: &str, pair: Result<(TriMesh, TriMesh), MeshError>| match pair {
        Ok((first, second)) => out.push(MeshPair {
            name: name.to_string(),
            first,
            second,
        }),
        Err(e) => eprintln!("note: skipping {name}: {e}"),
    };
    let spiky = spiky_sphere(1.0, 5, 0.6, 12, 0x5B1C);
    // The first mesh of each pair is the smaller: the poses' offsets from first contact are in
    // units of its size. "/k": sized to 1/k of the other's box diagonal.
    push(
        "spot/20 vs large_intestine_20k",
        load("large_intestine_20k").and_then(|big| {
            let small = sized(&load("spot")?, size(&big) / 20.0)?;
            Ok((small, big))
        }),
    );
    push(
        "spiky sphere vs teapot",
        load("teapot").and_then(|big| Ok((sized(&spiky, size(&big))?, big))),
    );
    push(
        "suzanne/10 vs pipe bundle",
        Ok(pipe_bundle(4, 0.1, 1.5)).and_then(|big| {
            let small = sized(&load("suzanne")?, size(&big) / 10.0)?;
            Ok((small, big))
        }),
    );
    push(
        "spiky sphere/30 vs thin-walled box",
        Ok(thin_walled_box(1.0, 0.02)).and_then(|big| Ok((sized(&spiky, size(&big) / 30.0)?, big))),
    );
    push(
        "teapot vs spot",
        load("spot").and_then(|spot| {
            let teapot = sized(&load("teapot")?, size(&spot))?;
            Ok((teapot, spot))
        }),
    );
    out
}
