//! The exact self-collision pass with neighbours excluded first (`self_contacts_excluding`) and
//! its exclusion (`SelfExclusion`) against brute force: every pair of triangles, the ring walk
//! of `triangles_within_rings` (on the mesh with corners at one position joined), and the f64
//! closest-points distance, on folded, whirled, spiky, coplanar, far-from-the-origin and
//! defective meshes.
mod common;

use std::collections::BTreeMap;

use glam::{Quat, Vec3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::bvh::{
    CollisionMesh, QueryWorkspace, SelfContact, self_contacts, self_contacts_excluding,
    self_intersections,
};
use stochastic_collision::deform::Whirl;
use stochastic_collision::geometry::{closest_points_triangle_triangle, triangles_intersect};
use stochastic_collision::mesh::{
    MeshError, SelfExclusion, Topology, TriMesh, generate, triangles_within_rings,
};
use stochastic_collision::tracking::TrackedSurface;

fn whirled_tube(frame: usize) -> TriMesh {
    let mut tube = generate::tube(0.15, 2.0, 12, 30, false);
    let whirl = Whirl::new(&tube, 40, 7);
    let mut p = Vec::new();
    whirl.positions(frame, &mut p);
    tube.set_positions(&p).unwrap();
    tube
}

/// An icosphere whose vertices are pushed in and out at random: spikes and pits.
fn spiky_sphere() -> TriMesh {
    let mut ball = generate::icosphere(1.0, 3);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    let p: Vec<Vec3> = ball
        .positions()
        .iter()
        .map(|v| *v * if rng.random::<f32>() < 0.2 { 1.6 } else { 0.95 })
        .collect();
    ball.set_positions(&p).unwrap();
    ball
}

/// Two unwelded sheets in one plane, overlapping: coplanar pairs everywhere.
fn coplanar_sheets() -> TriMesh {
    let a = generate::cloth_grid(1.0, 1.0, 8, 8);
    let mut b = generate::cloth_grid(1.0, 1.0, 7, 9);
    let shifted: Vec<Vec3> = b
        .positions()
        .iter()
        .map(|p| *p + Vec3::new(0.31, 0.0, 0.17))
        .collect();
    b.set_positions(&shifted).unwrap();
    TriMesh::merged(&[a, b]).unwrap()
}

/// The folded cloth, turned and carried far from the origin.
fn far_cloth() -> TriMesh {
    let mut m = common::folded_cloth();
    let q = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
    let p: Vec<Vec3> = m
        .positions()
        .iter()
        .map(|v| q * *v + Vec3::new(1.0e4, -3.0e3, 7.0e3))
        .collect();
    m.set_positions(&p).unwrap();
    m
}

/// Two parallel triangles exactly 0.25 apart (the tested thicknesses include 0.25), plus a
/// high-valence fan (40 triangles round one vertex: its neighbourhoods are long lists).
fn exact_gap_and_fan() -> TriMesh {
    let mut pos = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 0.25, 0.0),
        Vec3::new(1.0, 0.25, 0.0),
        Vec3::new(0.0, 0.25, 1.0),
    ];
    let mut tris = vec![[0, 1, 2], [3, 4, 5]];
    let centre = pos.len() as u32;
    pos.push(Vec3::new(3.0, 0.1, 0.0));
    let n = 40;
    for k in 0..n {
        let a = std::f32::consts::TAU * k as f32 / n as f32;
        pos.push(Vec3::new(
            3.0 + 0.8 * a.cos(),
            0.1 + 0.3 * (3.0 * a).sin(),
            0.8 * a.sin(),
        ));
    }
    for k in 0..n {
        tris.push([centre, centre + 1 + k, centre + 1 + (k + 1) % n]);
    }
    TriMesh::new(pos, tris).unwrap()
}

/// An icosphere with degenerate, repeated and duplicate-vertex triangles.
fn defective() -> TriMesh {
    let base = generate::icosphere(1.0, 1);
    let mut pos = base.positions().to_vec();
    let mut tris = base.triangles().to_vec();
    let n = pos.len() as u32;
    pos.push(pos[0]);
    pos.push((pos[0] + pos[1]) * 0.5);
    tris.push([0, 1, n + 1]);
    tris.push([n, n, n]);
    tris.push([2, 2, 3]);
    tris.push(base.triangles()[5]);
    tris.push([n, 1, 2]);
    TriMesh::new(pos, tris).unwrap()
}

fn meshes() -> Vec<(&'static str, TriMesh)> {
    vec![
        ("folded cloth", common::folded_cloth()),
        ("whirled tube 12", whirled_tube(12)),
        ("whirled tube 30", whirled_tube(30)),
        ("spiky sphere", spiky_sphere()),
        ("coplanar sheets", coplanar_sheets()),
        ("far cloth", far_cloth()),
        ("exact gap and fan", exact_gap_and_fan()),
        ("defective", defective()),
    ]
}

/// The mean edge length, as the tracker measures it.
fn mean_edge(mesh: &TriMesh) -> f32 {
    TrackedSurface::new(mesh.clone()).mean_edge_length()
}

/// `mesh` with corners at one position joined (`common::joined_triangles`).
fn joined(mesh: &TriMesh) -> TriMesh {
    TriMesh::new(mesh.positions().to_vec(), common::joined_triangles(mesh)).unwrap()
}

/// Every non-adjacent pair `(a, b)` with `a < b` (no common corner once corners at one
/// position are joined), with its f64 distance (0 when they cross).
fn all_distances(mesh: &TriMesh) -> Vec<((u32, u32), f64)> {
    let welded = joined(mesh);
    let tris = welded.triangles();
    let tri = |t: usize| mesh.triangle(t).map(|p| p.as_dvec3());
    let mut out = Vec::new();
    for a in 0..tris.len() {
        for b in a + 1..tris.len() {
            if tris[a].iter().any(|v| tris[b].contains(v)) {
                continue;
            }
            let (ta, tb) = (tri(a), tri(b));
            let d = if triangles_intersect(&ta, &tb) {
                0.0
            } else {
                closest_points_triangle_triangle(&ta, &tb).distance
            };
            out.push(((a as u32, b as u32), d));
        }
    }
    out
}

fn as_map(contacts: &[SelfContact]) -> BTreeMap<(u32, u32), f64> {
    let map: BTreeMap<_, _> = contacts
        .iter()
        .map(|c| ((c.pair.a, c.pair.b), c.distance))
        .collect();
    assert_eq!(map.len(), contacts.len(), "a pair reported twice");
    map
}

#[test]
fn excluding_pass_equals_brute_force_for_every_ring_count_and_thickness() {
    let mut ws = QueryWorkspace::new();
    for (name, mesh) in meshes() {
        let distances = all_distances(&mesh);
        let welded = joined(&mesh);
        let topology = Topology::new(&welded);
        let tris = welded.triangles();
        let cm = CollisionMesh::new(mesh.clone());
        let edge = mean_edge(&mesh);
        for thickness in [0.0, 0.1 * edge, 0.5 * edge, 0.25] {
            let mut plain = Vec::new();
            self_contacts(&cm, thickness, &mut ws, &mut plain);
            for rings in 0..=3 {
                let exclusion = SelfExclusion::from_topology(&mesh, &Topology::new(&mesh), rings);
                let mut out = Vec::new();
                let n =
                    self_contacts_excluding(&cm, thickness, &exclusion, &mut ws, &mut out).unwrap();
                assert_eq!(n, out.len());
                let got = as_map(&out);
                let want: BTreeMap<_, _> = distances
                    .iter()
                    .filter(|((a, b), d)| {
                        *d <= thickness as f64
                            && !triangles_within_rings(
                                &topology,
                                tris[*a as usize],
                                tris[*b as usize],
                                rings,
                            )
                    })
                    .copied()
                    .collect();
                assert_eq!(
                    got.keys().collect::<Vec<_>>(),
                    want.keys().collect::<Vec<_>>(),
                    "{name}, thickness {thickness}, {rings} rings"
                );
                for (pair, d) in &got {
                    if thickness > 0.0 {
                        assert_eq!(*d, want[pair], "{name}: distance of {pair:?}");
                    } else {
                        assert_eq!(*d, 0.0);
                    }
                }
                if rings == 0 {
                    assert_eq!(
                        as_map(&plain),
                        got,
                        "{name}: self_contacts, thickness {thickness}"
                    );
                }
            }
        }
        let mut crossing = Vec::new();
        self_intersections(&cm, &mut ws, &mut crossing);
        let want: Vec<(u32, u32)> = distances
            .iter()
            .filter(|(_, d)| *d == 0.0)
            .map(|(p, _)| *p)
            .collect();
        let mut got: Vec<(u32, u32)> = crossing.iter().map(|p| (p.a, p.b)).collect();
        got.sort_unstable();
        assert_eq!(got, want, "{name}: self_intersections");
    }
}

#[test]
fn exclusion_answers_as_the_ring_walk_on_irregular_meshes() {
    for (name, mesh) in [
        ("fan", exact_gap_and_fan()),
        ("defective", defective()),
        ("spiky", spiky_sphere()),
        ("coplanar", coplanar_sheets()),
    ] {
        let welded = joined(&mesh);
        let topology = Topology::new(&welded);
        let tris = welded.triangles();
        for rings in 0..=4 {
            let exclusion = SelfExclusion::new(&mesh, rings);
            assert_eq!(exclusion.rings(), rings);
            assert_eq!(
                exclusion.mesh_size(),
                (mesh.vertex_count(), mesh.triangle_count())
            );
            // The spiky sphere has 1280 triangles: every pair for the smaller meshes, a
            // stride through the pairs for it.
            let step = if tris.len() > 500 { 7 } else { 1 };
            for a in (0..tris.len()).step_by(step) {
                for b in 0..tris.len() {
                    assert_eq!(
                        exclusion.excludes(a as u32, b as u32),
                        triangles_within_rings(&topology, tris[a], tris[b], rings),
                        "{name}: {rings} rings, triangles {a} and {b}"
                    );
                }
            }
        }
    }
}

#[test]
fn an_exclusion_built_for_another_mesh_is_refused() {
    let small = generate::cloth_grid(1.0, 1.0, 4, 4);
    let big = CollisionMesh::new(generate::cloth_grid(1.0, 1.0, 5, 5));
    let exclusion = SelfExclusion::new(&small, 2);
    let mut out = Vec::new();
    let err = self_contacts_excluding(&big, 0.1, &exclusion, &mut QueryWorkspace::new(), &mut out)
        .unwrap_err();
    assert!(matches!(err, MeshError::TopologyMismatch { .. }), "{err}");
    assert!(err.to_string().contains("25 vertices"), "{err}");
    assert!(out.is_empty());
}

#[test]
fn the_pass_allocates_nothing_once_its_workspace_has_grown() {
    let mut tube = generate::tube(0.15, 2.0, 12, 30, false);
    let whirl = Whirl::new(&tube, 40, 7);
    let exclusion = SelfExclusion::new(&tube, 2);
    let thickness = 0.1 * mean_edge(&tube);
    let mut p = Vec::new();
    whirl.positions(0, &mut p);
    tube.set_positions(&p).unwrap();
    let mut cm = CollisionMesh::new(tube);
    let mut ws = QueryWorkspace::new();
    let mut out = Vec::with_capacity(1 << 16);
    let mut retained = Vec::new();
    for f in 0..40 {
        whirl.positions(f, &mut p);
        cm.set_positions(&p).unwrap();
        out.clear();
        self_contacts_excluding(&cm, thickness, &exclusion, &mut ws, &mut out).unwrap();
        retained.push(ws.retained_bytes());
    }
    // The stack is the only part that depends on the frame; after the deepest frames it stays.
    let last = *retained.last().unwrap();
    assert!(retained[20..].iter().all(|&r| r == last), "{retained:?}");
}
