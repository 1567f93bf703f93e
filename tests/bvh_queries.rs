//! The BVH queries against brute force (every triangle pair) on generated meshes, including
//! degenerate input, extreme scales and far-from-origin placements, plus refit and solid checks.
mod common;

use std::collections::BTreeSet;

use glam::{DVec3, Quat, Vec3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::bvh::{
    CollisionMesh, ExactOptions, QueryWorkspace, TrianglePair, closest_points, contains_point,
    intersecting_pairs, intersects, intersects_with, self_intersections, self_intersects,
    triangle_pair_intersects,
};
use stochastic_collision::geometry::{Pose, closest_points_triangle_triangle, triangles_intersect};
use stochastic_collision::mesh::{TriMesh, generate};
use stochastic_collision::poses::{near_contact_poses, random_direction, random_rotation};

/// Every triangle of `m` at `pose` relative to the identity frame, in f64 as the queries see it.
fn triangles_at(m: &TriMesh, pose: &Pose) -> Vec<[DVec3; 3]> {
    let p = pose.to_f64();
    m.triangles()
        .iter()
        .map(|t| t.map(|i| p.transform_point(m.positions()[i as usize])))
        .collect()
}

fn brute_pairs(a: &TriMesh, b: &TriMesh, pose_b: &Pose) -> BTreeSet<TrianglePair> {
    let ta = triangles_at(a, &Pose::IDENTITY);
    let tb = triangles_at(b, pose_b);
    let mut out = BTreeSet::new();
    for (i, x) in ta.iter().enumerate() {
        for (j, y) in tb.iter().enumerate() {
            if triangles_intersect(x, y) {
                out.insert(TrianglePair {
                    a: i as u32,
                    b: j as u32,
                });
            }
        }
    }
    out
}

fn brute_distance(a: &TriMesh, b: &TriMesh, pose_b: &Pose) -> f64 {
    let ta = triangles_at(a, &Pose::IDENTITY);
    let tb = triangles_at(b, pose_b);
    let mut best = f64::INFINITY;
    for x in &ta {
        for y in &tb {
            best = best.min(closest_points_triangle_triangle(x, y).distance);
        }
    }
    best
}

fn transformed(mesh: &TriMesh, scale: f32, offset: Vec3) -> TriMesh {
    TriMesh::new(
        mesh.positions()
            .iter()
            .map(|p| *p * scale + offset)
            .collect(),
        mesh.triangles().to_vec(),
    )
    .unwrap()
}

/// A mesh with the nastiest valid input: zero-area triangles (collinear and point-like),
/// duplicate vertices, duplicate triangles, unreferenced vertices.
fn nasty_mesh() -> TriMesh {
    let base = generate::icosphere(1.0, 1);
    let mut pos = base.positions().to_vec();
    let mut tris = base.triangles().to_vec();
    let n = pos.len() as u32;
    pos.push(Vec3::new(0.0, 0.0, 1.2)); // unreferenced
    pos.push(pos[0]); // duplicate of vertex 0
    pos.push((pos[0] + pos[1]) * 0.5); // on the segment 0-1: a collinear triangle
    tris.push([0, 1, n + 2]);
    tris.push([n + 1, n + 1, n + 1]); // point-like
    tris.push([2, 2, 3]); // segment-like, repeated index
    tris.push(base.triangles()[5]); // duplicate triangle
    tris.push([n + 1, 1, 2]); // uses the duplicate vertex
    TriMesh::new(pos, tris).unwrap()
}

fn small_meshes() -> Vec<(&'static str, TriMesh)> {
    vec![
        ("icosphere", generate::icosphere(1.0, 2)),
        ("torus", generate::torus(1.0, 0.35, 24, 10)),
        ("cuboid", generate::cuboid(Vec3::new(1.0, 0.5, 0.7), 2)),
        ("cloth", generate::cloth_grid(2.0, 2.0, 12, 12)),
        ("tube", generate::tube(0.4, 2.0, 12, 6, false)),
        ("nasty", nasty_mesh()),
    ]
}

#[test]
fn intersects_and_pairs_equal_brute_force_near_contact() {
    let mut ws = QueryWorkspace::new();
    let meshes = small_meshes();
    for (k, (name_a, a)) in meshes.iter().enumerate() {
        let (name_b, b) = &meshes[(k + 1) % meshes.len()];
        let ca = CollisionMesh::new(a.clone());
        let cb = CollisionMesh::new(b.clone());
        let poses = near_contact_poses(&ca, &cb, 12, 0.03, 11 + k as u64);
        assert!(!poses.is_empty(), "{name_a} vs {name_b}: no poses");
        let mut collisions = 0;
        for p in &poses {
            let brute = brute_pairs(a, b, &p.pose);
            let hit = intersects(&ca, &Pose::IDENTITY, &cb, &p.pose, &mut ws);
            assert_eq!(
                hit,
                !brute.is_empty(),
                "{name_a} vs {name_b} at {:?}",
                p.pose
            );
            let mut pairs = Vec::new();
            intersecting_pairs(&ca, &Pose::IDENTITY, &cb, &p.pose, &mut ws, &mut pairs);
            let set: BTreeSet<_> = pairs.iter().copied().collect();
            assert_eq!(
                set.len(),
                pairs.len(),
                "{name_a} vs {name_b}: a pair reported twice"
            );
            assert_eq!(set, brute, "{name_a} vs {name_b}: pairs differ");
            let outcome = intersects_with(
                &ca,
                &Pose::IDENTITY,
                &cb,
                &p.pose,
                &ExactOptions::default(),
                &mut ws,
            );
            if let Some(w) = outcome.witness {
                assert!(brute.contains(&w));
            }
            collisions += usize::from(hit);
        }
        // Near contact, both answers must occur: otherwise the test would prove little.
        assert!(
            collisions > 0 && collisions < poses.len(),
            "{name_a} vs {name_b}: {collisions}/{}",
            poses.len()
        );
    }
}

#[test]
fn one_triangle_pair_is_decided_as_the_query_decides_it() {
    // Near-contact poses placed away from the origin (both poses matter): every crossing pair
    // the query reports is crossing alone, and pairs it does not report are not; a triangle
    // the mesh does not have is never crossing.
    let mut ws = QueryWorkspace::new();
    let meshes = small_meshes();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(17);
    let (mut crossing, mut apart) = (0, 0);
    for (k, (name_a, a)) in meshes.iter().enumerate() {
        let (name_b, b) = &meshes[(k + 2) % meshes.len()];
        let (ca, cb) = (CollisionMesh::new(a.clone()), CollisionMesh::new(b.clone()));
        for p in near_contact_poses(&ca, &cb, 8, 0.03, 40 + k as u64) {
            let pose_a = Pose::new(random_direction(&mut rng) * 5.0, random_rotation(&mut rng));
            let pose_b = pose_a.mul(&p.pose);
            let mut pairs = Vec::new();
            intersecting_pairs(&ca, &pose_a, &cb, &pose_b, &mut ws, &mut pairs);
            let found: BTreeSet<_> = pairs.iter().copied().collect();
            for i in 0..a.triangle_count() as u32 {
                for j in (0..b.triangle_count() as u32).step_by(3) {
                    let t = TrianglePair { a: i, b: j };
                    let one = triangle_pair_intersects(&ca, &pose_a, &cb, &pose_b, t);
                    assert_eq!(one, found.contains(&t), "{name_a} vs {name_b}: {t:?}");
                    crossing += usize::from(one);
                    apart += usize::from(!one);
                }
            }
            for &t in &found {
                assert!(triangle_pair_intersects(&ca, &pose_a, &cb, &pose_b, t));
            }
            let missing = TrianglePair {
                a: a.triangle_count() as u32,
                b: 0,
            };
            assert!(!triangle_pair_intersects(
                &ca, &pose_a, &cb, &pose_b, missing
            ));
        }
    }
    assert!(
        crossing > 0 && apart > 0,
        "{crossing} crossing, {apart} apart"
    );
}

#[test]
fn both_poses_matter_not_only_the_relative_one() {
    let a = CollisionMesh::new(generate::torus(1.0, 0.3, 20, 8));
    let b = CollisionMesh::new(generate::icosphere(0.5, 2));
    let mut ws = QueryWorkspace::new();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
    for _ in 0..20 {
        let pose_a = Pose::new(random_direction(&mut rng) * 3.0, random_rotation(&mut rng));
        let rel = Pose::new(
            random_direction(&mut rng) * rng.random_range(0.5..1.8),
            random_rotation(&mut rng),
        );
        let pose_b = pose_a.mul(&rel);
        assert_eq!(
            intersects(&a, &pose_a, &b, &pose_b, &mut ws),
            !brute_pairs(a.mesh(), b.mesh(), &rel).is_empty()
        );
    }
}

#[test]
fn extreme_scales_and_far_from_origin_equal_brute_force() {
    let mut ws = QueryWorkspace::new();
    let base_a = generate::icosphere(1.0, 2);
    let base_b = generate::torus(0.8, 0.25, 20, 8);
    for (scale, offset) in [
        (1e-4, Vec3::ZERO),
        (1e6, Vec3::ZERO),
        (1.0, Vec3::splat(1e5)),
        (1e-2, Vec3::new(3e3, -2e3, 1e3)),
    ] {
        let a = CollisionMesh::new(transformed(&base_a, scale, offset));
        let b = CollisionMesh::new(transformed(&base_b, scale, offset));
        let poses = near_contact_poses(&a, &b, 10, 0.02, 5);
        assert!(poses.len() >= 8);
        for p in &poses {
            let brute = !brute_pairs(a.mesh(), b.mesh(), &p.pose).is_empty();
            assert_eq!(
                intersects(&a, &Pose::IDENTITY, &b, &p.pose, &mut ws),
                brute,
                "scale {scale} offset {offset}"
            );
        }
    }
}

#[test]
fn closest_points_equal_brute_force() {
    let mut ws = QueryWorkspace::new();
    let a = CollisionMesh::new(generate::icosphere(1.0, 2));
    let b = CollisionMesh::new(nasty_mesh());
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(9);
    for _ in 0..12 {
        let pose = Pose::new(
            random_direction(&mut rng) * rng.random_range(1.5..3.5),
            random_rotation(&mut rng),
        );
        let brute = brute_distance(a.mesh(), b.mesh(), &pose);
        let d = closest_points(&a, &Pose::IDENTITY, &b, &pose, f32::INFINITY, &mut ws).unwrap();
        assert!(
            (f64::from(d.distance) - brute).abs() <= 1e-6 * (1.0 + brute),
            "{} vs {brute}",
            d.distance
        );
        assert!(((d.point_a - d.point_b).length() - d.distance).abs() < 1e-4);
        // The points lie on the triangles reported.
        let ta = a
            .mesh()
            .triangle(d.triangles.a as usize)
            .map(|p| p.as_dvec3());
        let tb = triangles_at(b.mesh(), &pose)[d.triangles.b as usize];
        assert!(closest_points_triangle_triangle(&ta, &[d.point_a.as_dvec3(); 3]).distance < 1e-5);
        assert!(closest_points_triangle_triangle(&tb, &[d.point_b.as_dvec3(); 3]).distance < 1e-5);
        // A limit below the distance gives nothing; above it, the same answer.
        assert!(
            closest_points(&a, &Pose::IDENTITY, &b, &pose, d.distance * 0.9, &mut ws).is_none()
        );
        let capped = closest_points(
            &a,
            &Pose::IDENTITY,
            &b,
            &pose,
            d.distance * 1.1 + 1e-6,
            &mut ws,
        )
        .unwrap();
        assert_eq!(capped.distance, d.distance);
    }
    // Intersecting: distance 0.
    let d = closest_points(
        &a,
        &Pose::IDENTITY,
        &a,
        &Pose::from_translation(Vec3::X),
        f32::INFINITY,
        &mut ws,
    )
    .unwrap();
    assert_eq!(d.distance, 0.0);
}

#[test]
fn refit_after_deformation_matches_a_fresh_build() {
    let mut ws = QueryWorkspace::new();
    let mut cloth = CollisionMesh::new(generate::cloth_grid(2.0, 2.0, 16, 16));
    let ball = CollisionMesh::new(generate::icosphere(0.5, 2));
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(21);
    for step in 0..6 {
        let t = step as f32 * 0.4;
        let bent: Vec<Vec3> = cloth
            .mesh()
            .positions()
            .iter()
            .map(|p| Vec3::new(p.x, 0.4 * (p.x * 2.0 + t).sin() * (p.z * 1.5).cos(), p.z))
            .collect();
        cloth.set_positions(&bent).unwrap();
        // Every node box holds its triangles.
        let bvh = cloth.bvh();
        for node in bvh.nodes().iter().filter(|n| n.is_leaf()) {
            for &tri in bvh.triangles_of(node) {
                for p in cloth.mesh().triangle(tri as usize) {
                    assert!(node.aabb().contains_point(p));
                }
            }
        }
        let fresh = CollisionMesh::new(cloth.mesh().clone());
        for _ in 0..8 {
            let pose = Pose::new(
                random_direction(&mut rng) * rng.random_range(0.0..0.9),
                random_rotation(&mut rng),
            );
            let refit = intersects(&cloth, &Pose::IDENTITY, &ball, &pose, &mut ws);
            assert_eq!(
                refit,
                intersects(&fresh, &Pose::IDENTITY, &ball, &pose, &mut ws)
            );
            assert_eq!(
                refit,
                !brute_pairs(cloth.mesh(), ball.mesh(), &pose).is_empty()
            );
        }
    }
    assert!(cloth.set_positions(&[Vec3::ZERO]).is_err());
}

#[test]
fn self_intersections_equal_brute_force() {
    let mut ws = QueryWorkspace::new();
    // A cloth folded through itself, and a sphere (no self-intersection).
    let cloth = CollisionMesh::new(common::folded_cloth());
    for mesh in [
        cloth,
        CollisionMesh::new(generate::icosphere(1.0, 2)),
        CollisionMesh::new(nasty_mesh()),
    ] {
        let tris = triangles_at(mesh.mesh(), &Pose::IDENTITY);
        // Adjacent: a corner in common once corners at one position are joined.
        let ids = common::joined_triangles(mesh.mesh());
        let mut brute = BTreeSet::new();
        for i in 0..tris.len() {
            for j in i + 1..tris.len() {
                let adjacent = ids[i].iter().any(|v| ids[j].contains(v));
                if !adjacent && triangles_intersect(&tris[i], &tris[j]) {
                    brute.insert(TrianglePair {
                        a: i as u32,
                        b: j as u32,
                    });
                }
            }
        }
        let mut pairs = Vec::new();
        self_intersections(&mesh, &mut ws, &mut pairs);
        let set: BTreeSet<_> = pairs.iter().copied().collect();
        assert_eq!(set.len(), pairs.len());
        assert_eq!(set, brute);
        assert_eq!(self_intersects(&mesh, &mut ws), !brute.is_empty());
    }
}

#[test]
fn solid_option_counts_containment_only_for_closed_containers() {
    let mut ws = QueryWorkspace::new();
    let big = CollisionMesh::new(generate::icosphere(2.0, 3));
    let small = CollisionMesh::new(generate::torus(0.5, 0.2, 16, 8));
    let open = CollisionMesh::new(generate::tube(2.0, 4.0, 16, 4, false));
    let inside = Pose::new(Vec3::new(0.3, -0.2, 0.1), Quat::from_rotation_x(0.4));
    let outside = Pose::from_translation(Vec3::new(5.0, 0.0, 0.0));
    let solid = ExactOptions { solid: true };
    assert!(!intersects(&big, &Pose::IDENTITY, &small, &inside, &mut ws));
    let o = intersects_with(&big, &Pose::IDENTITY, &small, &inside, &solid, &mut ws);
    assert!(o.collides && o.contained && o.witness.is_none());
    // Either order.
    let o = intersects_with(&small, &inside, &big, &Pose::IDENTITY, &solid, &mut ws);
    assert!(o.collides && o.contained);
    assert!(!intersects_with(&big, &Pose::IDENTITY, &small, &outside, &solid, &mut ws).collides);
    // An open tube has no inside.
    assert!(!intersects_with(&open, &Pose::IDENTITY, &small, &inside, &solid, &mut ws).collides);
    // Point containment, including points on the surface and on grid-aligned edges.
    let cube = CollisionMesh::new(generate::cuboid(Vec3::ONE, 2));
    assert!(contains_point(&cube, Vec3::ZERO));
    assert!(contains_point(&cube, Vec3::new(1.0, 1.0, 1.0)));
    assert!(contains_point(&cube, Vec3::new(0.0, 0.0, -1.0)));
    assert!(!contains_point(&cube, Vec3::new(0.0, 0.0, -1.0001)));
    assert!(!contains_point(&open, Vec3::ZERO));
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(2);
    for _ in 0..200 {
        let p = Vec3::new(
            rng.random_range(-2.5..2.5),
            rng.random_range(-2.5..2.5),
            rng.random_range(-2.5..2.5),
        );
        assert_eq!(
            contains_point(&cube, p),
            p.abs().max_element() <= 1.0,
            "{p}"
        );
    }
}

#[test]
fn workspace_stops_growing_after_warm_up() {
    let a = CollisionMesh::new(generate::icosphere(1.0, 3));
    let mut ws = QueryWorkspace::new();
    let poses = near_contact_poses(&a, &a, 20, 0.05, 1);
    for p in &poses {
        intersects(&a, &Pose::IDENTITY, &a, &p.pose, &mut ws);
        closest_points(&a, &Pose::IDENTITY, &a, &p.pose, f32::INFINITY, &mut ws);
    }
    let before = ws.retained_bytes();
    for p in &poses {
        intersects(&a, &Pose::IDENTITY, &a, &p.pose, &mut ws);
        closest_points(&a, &Pose::IDENTITY, &a, &p.pose, f32::INFINITY, &mut ws);
    }
    assert_eq!(before, ws.retained_bytes());
    assert!(ws.node_pairs_visited() > 0);
}

/// Checks the tree's invariants: a permutation of the triangles, children after their parent
/// and adjacent, every box holding its children's boxes and its triangles, leaves within size.
fn check_tree(mesh: &TriMesh, bvh: &stochastic_collision::bvh::Bvh, max_leaf: u32) {
    let mut seen = vec![false; mesh.triangle_count()];
    for &t in bvh.leaf_triangles() {
        assert!(
            !std::mem::replace(&mut seen[t as usize], true),
            "triangle {t} twice"
        );
    }
    assert!(seen.iter().all(|&s| s));
    let nodes = bvh.nodes();
    let mut reached = vec![false; nodes.len()];
    reached[0] = true;
    for (i, n) in nodes.iter().enumerate() {
        assert!(reached[i], "node {i} unreachable");
        if n.is_leaf() {
            assert!(n.count <= max_leaf);
            for &t in bvh.triangles_of(n) {
                mesh.triangle(t as usize)
                    .iter()
                    .for_each(|p| assert!(n.aabb().contains_point(*p)));
            }
        } else {
            let l = n.left() as usize;
            assert!(l > i && l + 1 < nodes.len());
            for c in [l, l + 1] {
                reached[c] = true;
                assert!(
                    n.aabb().contains_point(nodes[c].min) && n.aabb().contains_point(nodes[c].max)
                );
            }
        }
    }
}

#[test]
fn parallel_build_equals_serial_build_and_keeps_invariants() {
    use stochastic_collision::bvh::{Bvh, BvhBuildOptions};
    for mesh in [
        generate::torus(1.0, 0.3, 96, 40),
        nasty_mesh(),
        generate::cloth_grid(1.0, 1.0, 60, 60),
    ] {
        let serial = Bvh::build_with(
            &mesh,
            BvhBuildOptions {
                parallel_threshold: usize::MAX,
                ..Default::default()
            },
        );
        let parallel = Bvh::build_with(
            &mesh,
            BvhBuildOptions {
                parallel_threshold: 1024,
                ..Default::default()
            },
        );
        check_tree(&mesh, &serial, 4);
        assert_eq!(serial, parallel);
        let big_leaves = Bvh::build_with(
            &mesh,
            BvhBuildOptions {
                max_leaf_size: 1,
                bins: 4,
                ..Default::default()
            },
        );
        check_tree(&mesh, &big_leaves, 1);
    }
    // All centroids coincide: split by count, leaves still bounded.
    let pos: Vec<Vec3> = (0..40)
        .map(|i| Vec3::new(i as f32 * 1e-3, 0.0, 0.0))
        .collect();
    let stacked = TriMesh::new(pos, (0..20).map(|i| [i, 39 - i, 20]).collect()).unwrap();
    check_tree(
        &stacked,
        &stochastic_collision::bvh::Bvh::build(&stacked),
        4,
    );
}
