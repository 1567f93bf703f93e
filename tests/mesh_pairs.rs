//! The accuracy report's held-out pairs of different meshes (`examples/support/mesh_pairs.rs`,
//! `accuracy_vs_time --pairs`): the generated shapes are valid closed meshes (so the
//! interpenetration certificate is exact on them), and each pair is sized as its name says, the
//! smaller mesh first; the CAD-like parts (`accuracy_vs_time --cad`) are closed and made of
//! the parts their names say (apart from each other, but for the walls of the box, which meet
//! along its edges).
mod common;
#[path = "../examples/support/mesh_pairs.rs"]
mod mesh_pairs;

use glam::Vec3;
use mesh_pairs::{
    cad_parts, held_out_pairs, layered_sheets, pipe_bundle, slotted_plate, spiky_sphere,
    thin_walled_box,
};
use stochastic_collision::bvh::CollisionMesh;
use stochastic_collision::mesh::TriMesh;

fn diagonal(mesh: &TriMesh) -> f32 {
    let (lo, hi) = mesh.positions().iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    (hi - lo).length()
}

#[test]
fn generated_shapes_are_closed_and_seeded() {
    let spiky = spiky_sphere(1.0, 3, 0.6, 12, 1);
    assert!(spiky.is_closed());
    let radii: Vec<f32> = spiky.positions().iter().map(|p| p.length()).collect();
    let spikes = radii.iter().filter(|&&r| r > 1.1).count();
    assert!(spikes > 0 && spikes < radii.len() / 4, "{spikes} spikes");
    assert!(radii.iter().all(|&r| (0.999..=1.61).contains(&r)));
    assert_eq!(
        spiky.positions(),
        spiky_sphere(1.0, 3, 0.6, 12, 1).positions()
    );
    assert_ne!(
        spiky.positions(),
        spiky_sphere(1.0, 3, 0.6, 12, 2).positions()
    );

    let bundle = pipe_bundle(3, 0.1, 1.5);
    assert!(bundle.is_closed());
    let one_pipe = pipe_bundle(1, 0.1, 1.5).triangle_count();
    assert_eq!(bundle.triangle_count(), 9 * one_pipe);

    let walls = thin_walled_box(1.0, 0.02);
    assert!(walls.is_closed());
    // x and z span the side plates' outer faces, y the floor's underside to the sides' top.
    let expected = (2.0 * 2.02f32 * 2.02 + 2.01 * 2.01).sqrt();
    assert!((diagonal(&walls) - expected).abs() < 1e-3);
}

#[test]
fn held_out_pairs_are_sized_as_named() {
    // Skips (or fails in CI) without the shared meshes, like every test that reads them.
    for file in [
        "spot.obj",
        "teapot.obj",
        "suzanne.obj",
        "large_intestine_20k.obj",
    ] {
        if common::shared_mesh(file).is_none() {
            return;
        }
    }
    let pairs = held_out_pairs(&common::shared_mesh_dir());
    assert_eq!(pairs.len(), 5);
    for pair in &pairs {
        let ratio = diagonal(&pair.second) / diagonal(&pair.first);
        let named = pair
            .name
            .split_once('/')
            .and_then(|(_, rest)| rest.split(' ').next())
            .map_or(1.0, |k| k.parse::<f32>().unwrap());
        assert!(
            (ratio - named).abs() < 1e-3 * named,
            "{}: the second is {ratio}x the first",
            pair.name
        );
    }
}

#[test]
fn cad_parts_are_closed_and_made_of_separate_parts() {
    let plate = slotted_plate(12, 1.0, 0.04);
    assert!(plate.is_closed());
    // 12 bars side by side with slots between them: the plate spans its width.
    let one_bar = slotted_plate(1, 1.0, 0.04).triangle_count();
    assert_eq!(plate.triangle_count(), 12 * one_bar);
    let sheets = layered_sheets(6, 1.0, 0.02, 0.05);
    assert!(sheets.is_closed());
    // Six sheets, each bent upwards by a tenth of its half-width at its edges, stacked with
    // gaps: the stack's height is 5 gaps and 6 thicknesses plus the bend.
    let ys: Vec<f32> = sheets.positions().iter().map(|p| p.y).collect();
    let height = ys.iter().cloned().fold(f32::NEG_INFINITY, f32::max)
        - ys.iter().cloned().fold(f32::INFINITY, f32::min);
    assert!(
        (height - (6.0 * 0.02 + 5.0 * 0.05 + 0.1)).abs() < 0.01,
        "{height}"
    );
    let parts = cad_parts();
    assert_eq!(parts.len(), 4);
    for (name, part) in parts {
        assert!(part.is_closed(), "{name}");
        if name == "thin-walled box" {
            continue; // its plates meet along the box's edges, by construction
        }
        // The parts do not touch each other: the mesh does not intersect itself.
        let mesh = CollisionMesh::new(part);
        let mut ws = stochastic_collision::bvh::QueryWorkspace::new();
        assert!(
            !stochastic_collision::bvh::self_intersects(&mesh, &mut ws),
            "{name} intersects itself"
        );
    }
}
