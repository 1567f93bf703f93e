//! Mesh queries on arbitrary small meshes and poses, built through the validating
//! constructors: never panics; the exact BVH queries equal brute force over all triangle
//! pairs; ADB answers are probabilities in [0, 1] and, with exact leaves, `p_min = 1` and no
//! budget, equal the exact answer.
#![no_main]

use arbitrary::Arbitrary;
use glam::{Quat, Vec3};
use libfuzzer_sys::fuzz_target;
use stochastic_collision::adb::{
    AdbBuildOptions, AdbQuery, AdbTree, AdbWorkspace, Budget, FitOptions, adb_intersects,
};
use stochastic_collision::bvh::{
    CollisionMesh, QueryWorkspace, closest_points, intersecting_pairs, intersects,
    self_intersections,
};
use stochastic_collision::geometry::{Pose, closest_points_triangle_triangle, triangles_intersect};
use stochastic_collision::mesh::TriMesh;

#[derive(Debug, Arbitrary)]
struct Mesh {
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u8; 3]>,
    /// Snap coordinates to a grid of this many steps (0: raw floats), for touching cases.
    grid: u8,
}

#[derive(Debug, Arbitrary)]
struct Input {
    a: Mesh,
    b: Mesh,
    same: bool,
    pose_a: ([f32; 3], [f32; 4]),
    pose_b: ([f32; 3], [f32; 4]),
    fit: bool,
    budget: u8,
}

fn build(m: &Mesh) -> Option<TriMesh> {
    let positions: Vec<Vec3> = m
        .positions
        .iter()
        .take(16)
        .map(|p| {
            let v = Vec3::from_array(*p);
            if m.grid > 0 && v.is_finite() {
                (v.clamp(Vec3::splat(-1e3), Vec3::splat(1e3)) * f32::from(m.grid)).round()
                    / f32::from(m.grid)
            } else {
                v
            }
        })
        .collect();
    let n = positions.len().max(1);
    let triangles: Vec<[u32; 3]> = m
        .triangles
        .iter()
        .take(24)
        .map(|t| t.map(|i| u32::from(i) % (n as u32 + 1)))
        .collect();
    // Out-of-range indices and non-finite coordinates must be refused, not panic.
    TriMesh::new(positions, triangles).ok()
}

fn pose(p: &([f32; 3], [f32; 4])) -> Pose {
    Pose::new(Vec3::from_array(p.0), Quat::from_array(p.1))
}

fuzz_target!(|input: Input| {
    let Some(mesh_a) = build(&input.a) else {
        return;
    };
    let mesh_b = if input.same {
        mesh_a.clone()
    } else {
        match build(&input.b) {
            Some(m) => m,
            None => return,
        }
    };
    let (pa, pb) = (pose(&input.pose_a), pose(&input.pose_b));
    let a = CollisionMesh::new(mesh_a.clone());
    let b = CollisionMesh::new(mesh_b.clone());
    let mut ws = QueryWorkspace::new();
    let hit = intersects(&a, &pa, &b, &pb, &mut ws);
    let mut pairs = Vec::new();
    intersecting_pairs(&a, &pa, &b, &pb, &mut ws, &mut pairs);
    let dist = closest_points(&a, &pa, &b, &pb, f32::INFINITY, &mut ws);
    let mut self_pairs = Vec::new();
    self_intersections(&a, &mut ws, &mut self_pairs);

    let finite_pose = |p: &Pose| p.translation.is_finite() && p.rotation.is_finite();
    let valid_poses = finite_pose(&pa) && finite_pose(&pb);

    // Brute force, in the same frame and arithmetic as the crate (b placed in a's frame).
    if valid_poses {
        let rel = pa.inverse_mul(&pb).to_f64();
        let tri_a = |t: usize| mesh_a.triangle(t).map(|p| p.as_dvec3());
        let tri_b = |t: usize| mesh_b.triangle(t).map(|p| rel.transform_point(p));
        let finite_b = (0..mesh_b.triangle_count()).all(|u| tri_b(u).iter().all(|p| p.is_finite()));
        if finite_b {
            let mut brute_pairs = Vec::new();
            let mut brute_dist = f64::INFINITY;
            for t in 0..mesh_a.triangle_count() {
                for u in 0..mesh_b.triangle_count() {
                    if triangles_intersect(&tri_a(t), &tri_b(u)) {
                        brute_pairs.push((t as u32, u as u32));
                    }
                    brute_dist = brute_dist
                        .min(closest_points_triangle_triangle(&tri_a(t), &tri_b(u)).distance);
                }
            }
            assert_eq!(hit, !brute_pairs.is_empty(), "intersects vs brute force");
            let mut got: Vec<(u32, u32)> = pairs.iter().map(|p| (p.a, p.b)).collect();
            got.sort_unstable();
            assert_eq!(got, brute_pairs, "intersecting_pairs vs brute force");
            let d = dist.expect("no distance limit: always an answer");
            assert!(d.distance.is_finite() && d.distance >= 0.0, "{d:?}");
            if hit {
                assert_eq!(d.distance, 0.0, "{d:?}");
            }
            let want = brute_dist as f32;
            assert!(
                (d.distance - want).abs()
                    <= 1e-5 * (1.0 + want.abs()) + 1e-6 * want.max(d.distance),
                "closest_points {} vs brute force {want}",
                d.distance
            );
        }
    }
    let mut brute_self = Vec::new();
    for t in 0..mesh_a.triangle_count() {
        for u in t + 1..mesh_a.triangle_count() {
            let (ta, tb) = (mesh_a.triangles()[t], mesh_a.triangles()[u]);
            if ta.iter().any(|i| tb.contains(i)) {
                continue;
            }
            let (x, y) = (mesh_a.triangle(t), mesh_a.triangle(u));
            if triangles_intersect(&x.map(|p| p.as_dvec3()), &y.map(|p| p.as_dvec3())) {
                brute_self.push((t as u32, u as u32));
            }
        }
    }
    let mut got: Vec<(u32, u32)> = self_pairs
        .iter()
        .map(|p| (p.a.min(p.b), p.a.max(p.b)))
        .collect();
    got.sort_unstable();
    assert_eq!(got, brute_self, "self_intersections vs brute force");

    // ADB.
    let options = AdbBuildOptions {
        threads: 1,
        fit: input.fit.then_some(FitOptions {
            poses: 3,
            walks_per_pose: 3,
            ..FitOptions::default()
        }),
        ..AdbBuildOptions::default()
    };
    let ta = AdbTree::build_with(a, options);
    let tb = AdbTree::build_with(b, options);
    let mut aws = AdbWorkspace::new();
    let query = AdbQuery {
        budget: if input.budget == 0 {
            Budget::Unlimited
        } else {
            Budget::NodePairs(u64::from(input.budget))
        },
        ..AdbQuery::default()
    };
    for q in [query, AdbQuery::paper()] {
        let out = adb_intersects(&ta, &pa, &tb, &pb, &q, &mut aws);
        assert!((0.0..=1.0).contains(&out.probability), "{out:?}");
        assert!((0.0..=1.0).contains(&out.max_pair_probability), "{out:?}");
        if let Some(w) = out.witness {
            assert!(
                !valid_poses || (w.point.is_finite() && w.normal.is_finite()),
                "{out:?}"
            );
        }
    }
    if valid_poses {
        let exact = AdbQuery {
            p_min: 1.0,
            exact_leaves: true,
            budget: Budget::Unlimited,
            ..AdbQuery::default()
        };
        let out = adb_intersects(&ta, &pa, &tb, &pb, &exact, &mut aws);
        assert_eq!(
            out.collides, hit,
            "ADB with exact leaves and p_min = 1: {out:?}"
        );
    }
});
