//! The seeded shapes and motions of the held-out tracking evaluation: random-centre-line
//! tubes and noisy spheres are valid closed surfaces that do not touch themselves at rest
//! (checked by the exact self pass with the tracker's thickness and exclusion, and by an
//! intersection test), differ from seed to seed and are reproducible; the crumple folds a
//! cloth into contact (the exact pass finds contacts) and returns it flat; the tracker finds
//! contacts on each.

use stochastic_collision::bvh::{
    CollisionMesh, QueryWorkspace, self_contacts_excluding, self_intersections,
};
use stochastic_collision::deform::{Animation, Crumple, Whirl};
use stochastic_collision::mesh::{SelfExclusion, Topology, TriMesh, generate};
use stochastic_collision::tracking::{TrackedSurface, Tracker, TrackerConfig};

/// Pairs of triangles (outside the tracker's exclusion rings) closer than its thickness.
fn exact_contacts(mesh: &TriMesh) -> usize {
    let surface = TrackedSurface::new(mesh.clone());
    let config = TrackerConfig::for_surface(&surface);
    let exclusion = SelfExclusion::new(mesh, config.exclusion_rings);
    let cm = CollisionMesh::new(mesh.clone());
    let mut out = Vec::new();
    self_contacts_excluding(
        &cm,
        config.thickness,
        &exclusion,
        &mut QueryWorkspace::new(),
        &mut out,
    )
    .unwrap();
    out.len()
}

fn crossings(mesh: &TriMesh) -> usize {
    let cm = CollisionMesh::new(mesh.clone());
    let mut out = Vec::new();
    self_intersections(&cm, &mut QueryWorkspace::new(), &mut out);
    out.len()
}

#[test]
fn random_tubes_and_noisy_spheres_are_clean_closed_surfaces_at_rest() {
    for seed in [3u64, 4, 5, 17] {
        for mesh in [
            generate::random_tube(0.06, 2.0, 24, 240, seed),
            generate::noisy_sphere(1.0, 4, 0.25, seed),
        ] {
            let topology = Topology::new(&mesh);
            assert!(mesh.is_closed() && topology.non_manifold_edge_count() == 0);
            assert_eq!(crossings(&mesh), 0, "seed {seed}: crosses itself at rest");
            assert_eq!(
                exact_contacts(&mesh),
                0,
                "seed {seed}: touches itself at rest"
            );
        }
    }
    let tube = |seed| generate::random_tube(0.06, 2.0, 24, 240, seed);
    assert_eq!(tube(3).positions(), tube(3).positions());
    assert_ne!(tube(3).positions(), tube(4).positions());
    // The centre line wanders: the tube is not the straight one.
    let straight = generate::tube(0.06, 2.0, 24, 240, true);
    let moved = tube(3)
        .positions()
        .iter()
        .zip(straight.positions())
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0f32, f32::max);
    assert!(
        moved > 0.06,
        "largest offset from the straight tube {moved}"
    );
    let sphere = |seed| generate::noisy_sphere(1.0, 4, 0.25, seed);
    assert_ne!(sphere(3).positions(), sphere(4).positions());
}

#[test]
fn a_crumpled_cloth_comes_into_contact_and_the_tracker_finds_it() {
    let cloth = generate::cloth_grid(1.0, 1.0, 40, 40);
    for seed in [1u64, 3] {
        let crumple = Crumple::new(&cloth, 80, seed);
        assert_eq!(crumple.frames(), 80);
        let mut positions = Vec::new();
        crumple.positions(0, &mut positions);
        assert_eq!(positions, cloth.positions());
        let mut surface = TrackedSurface::new(cloth.clone());
        let mut tracker = Tracker::new(TrackerConfig::for_surface(&surface));
        let (mut exact_frames, mut tracked_frames) = (0, 0);
        for f in 0..80 {
            crumple.positions(f, &mut positions);
            assert!(positions.iter().all(|p| p.is_finite()));
            let mut mesh = cloth.clone();
            mesh.set_positions(&positions).unwrap();
            if exact_contacts(&mesh) > 0 {
                exact_frames += 1;
            }
            surface.set_positions(&positions).unwrap();
            if !tracker.step_self(&surface).is_empty() {
                tracked_frames += 1;
            }
        }
        assert!(
            exact_frames >= 5,
            "seed {seed}: {exact_frames} frames in contact"
        );
        assert!(
            tracked_frames * 2 >= exact_frames,
            "seed {seed}: tracked {tracked_frames} of {exact_frames} frames in contact"
        );
        // Edge lengths away from the fold lines are kept: the folds are rigid turns.
        crumple.positions(20, &mut positions);
        let kept = Topology::new(&cloth)
            .edges()
            .iter()
            .filter(|e| {
                let [a, b] = e.vertices.map(|v| v as usize);
                let rest = (cloth.positions()[a] - cloth.positions()[b]).length();
                ((positions[a] - positions[b]).length() - rest).abs() < 1e-4
            })
            .count();
        assert!(kept * 10 >= Topology::new(&cloth).edges().len() * 9);
    }
    // A whirl is an animation too.
    let whirl = Whirl::new(&cloth, 40, 1);
    let animation: &dyn Animation = &whirl;
    assert_eq!(animation.frames(), 40);
    let mut p = Vec::new();
    animation.positions(0, &mut p);
    assert_eq!(p, cloth.positions());
}
