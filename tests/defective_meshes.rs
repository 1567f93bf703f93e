//! Real meshes with defects (issue 6): the shared ogre (zero-area triangles), dragon_50k
//! (non-manifold edges, duplicate triangles), stanford-bunny (holes, unreferenced vertices) and
//! teapot (unwelded seams).
//!
//! For each: the defect is really there; the BVH and the ADB tree build; the exact queries of
//! the mesh against itself at near-contact poses (and at the identical pose) equal an
//! independent reference, a uniform grid over the triangles' boxes with every candidate pair
//! tested exactly; the self-intersection query equals the same reference over non-adjacent
//! pairs (adjacent: a corner in common once corners at one position are joined); distances
//! are finite; ADB answers are probabilities in [0, 1] (never NaN) and, with
//! exact leaves, `p_min = 1` and no budget, equal the exact answers.
mod common;

use std::collections::{HashMap, HashSet};

use glam::{DVec3, I64Vec3, Vec3};
use stochastic_collision::adb::{
    AdbBuildOptions, AdbQuery, AdbTree, AdbWorkspace, Budget, FitOptions, adb_intersects,
};
use stochastic_collision::bvh::{
    CollisionMesh, QueryWorkspace, closest_points, intersecting_pairs, intersects,
    self_intersections,
};
use stochastic_collision::geometry::{Aabb, Pose, triangles_intersect};
use stochastic_collision::mesh::{Topology, TriMesh};
use stochastic_collision::poses::near_contact_poses;

type Tri = [DVec3; 3];

/// Triangle pairs `(i, j)` of `a` × `b` that intersect, found through a uniform grid of cells of
/// side `cell` over the triangles' boxes: a candidate pair is tested exactly once, in the first
/// cell (lowest corner) its two cell ranges share. With `same`, `a` and `b` are one mesh: only
/// `i < j` with no shared vertex index (`indices`).
fn grid_pairs(a: &[Tri], b: &[Tri], cell: f64, same: Option<&[[u32; 3]]>) -> HashSet<(u32, u32)> {
    let key = |p: DVec3| (p / cell).floor().as_i64vec3();
    let range = |t: &Tri| (key(t[0].min(t[1]).min(t[2])), key(t[0].max(t[1]).max(t[2])));
    let cells = |(lo, hi): (I64Vec3, I64Vec3)| {
        (lo.x..=hi.x).flat_map(move |x| {
            (lo.y..=hi.y).flat_map(move |y| (lo.z..=hi.z).map(move |z| I64Vec3::new(x, y, z)))
        })
    };
    let ranges_a: Vec<_> = a.iter().map(range).collect();
    let mut grid: HashMap<I64Vec3, Vec<u32>> = HashMap::new();
    for (i, r) in ranges_a.iter().enumerate() {
        for c in cells(*r) {
            grid.entry(c).or_default().push(i as u32);
        }
    }
    let mut hits = HashSet::new();
    for (j, t) in b.iter().enumerate() {
        let rj = range(t);
        for c in cells(rj) {
            for &i in grid.get(&c).map_or(&[][..], Vec::as_slice) {
                if ranges_a[i as usize].0.max(rj.0) != c {
                    continue; // tested in an earlier shared cell
                }
                if let Some(idx) = same {
                    let (ti, tj) = (idx[i as usize], idx[j]);
                    if i as usize >= j || ti.iter().any(|v| tj.contains(v)) {
                        continue;
                    }
                }
                if triangles_intersect(&a[i as usize], t) {
                    hits.insert((i, j as u32));
                }
            }
        }
    }
    hits
}

/// Triangles of `mesh` placed by `pose`, in `f64` as the queries place them.
fn placed(mesh: &TriMesh, pose: &Pose) -> Vec<Tri> {
    let p = pose.to_f64();
    (0..mesh.triangle_count())
        .map(|t| mesh.triangle(t).map(|v| p.transform_point(v)))
        .collect()
}

/// A grid cell side: twice the mean triangle box diagonal.
fn cell_size(mesh: &TriMesh) -> f64 {
    let total: f64 = (0..mesh.triangle_count())
        .map(|t| f64::from(Aabb::from_points(mesh.triangle(t)).extents().length()))
        .sum();
    2.0 * total / mesh.triangle_count() as f64 + 1e-9
}

/// Every check of the module doc on `mesh` against itself; `poses` near-contact poses.
fn check_mesh(name: &str, mesh: &TriMesh, poses: usize) {
    let cm = CollisionMesh::new(mesh.clone());
    let mut ws = QueryWorkspace::new();
    let cell = cell_size(mesh);
    let at_identity = placed(mesh, &Pose::IDENTITY);

    // Self-intersections against the reference.
    let mut pairs = Vec::new();
    self_intersections(&cm, &mut ws, &mut pairs);
    let ours: HashSet<(u32, u32)> = pairs.iter().map(|p| (p.a.min(p.b), p.a.max(p.b))).collect();
    assert_eq!(ours.len(), pairs.len(), "{name}: self pairs reported twice");
    // Adjacent: a corner in common once corners at one position are joined.
    let joined = common::joined_triangles(mesh);
    let reference = grid_pairs(&at_identity, &at_identity, cell, Some(&joined));
    assert_eq!(ours, reference, "{name}: self-intersections");
    eprintln!("{name}: {} self-intersecting pairs", ours.len());

    // The identical pose: every triangle touches its copy.
    assert!(
        intersects(&cm, &Pose::IDENTITY, &cm, &Pose::IDENTITY, &mut ws),
        "{name}"
    );
    let d = closest_points(
        &cm,
        &Pose::IDENTITY,
        &cm,
        &Pose::IDENTITY,
        f32::INFINITY,
        &mut ws,
    );
    assert_eq!(d.map(|d| d.distance), Some(0.0), "{name}");

    // Near-contact poses (and a clearly separated one) against the reference.
    let options = AdbBuildOptions {
        fit: Some(FitOptions {
            poses: 8,
            walks_per_pose: 8,
            ..FitOptions::default()
        }),
        ..AdbBuildOptions::default()
    };
    let tree = AdbTree::build_with(cm.clone(), options);
    for n in tree.nodes() {
        assert!(
            n.sides.iter().all(|s| s.is_finite()) && n.planarity.is_finite(),
            "{name}"
        );
    }
    let mut adb_ws = AdbWorkspace::new();
    let size = cm.bvh().root_aabb().extents().length();
    // Each near-contact pose, and the same approach a little deeper and a little farther.
    let mut test_poses: Vec<Pose> = near_contact_poses(&cm, &cm, poses, 0.02, 0xDEFEC7)
        .iter()
        .flat_map(|p| {
            let step = 0.01 * p.size;
            [
                p.pose,
                p.at_offset(p.offset - step),
                p.at_offset(p.offset + step),
            ]
        })
        .collect();
    test_poses.push(Pose::from_translation(Vec3::X * 2.0 * size));
    let (mut colliding, mut apart) = (0, 0);
    for pose in &test_poses {
        let ctx = format!("{name} at {pose:?}");
        let mut pairs = Vec::new();
        intersecting_pairs(&cm, &Pose::IDENTITY, &cm, pose, &mut ws, &mut pairs);
        let ours: HashSet<(u32, u32)> = pairs.iter().map(|p| (p.a, p.b)).collect();
        assert_eq!(ours.len(), pairs.len(), "{ctx}: pairs reported twice");
        let reference = grid_pairs(&at_identity, &placed(mesh, pose), cell, None);
        assert_eq!(ours, reference, "{ctx}: intersecting pairs");
        let hit = intersects(&cm, &Pose::IDENTITY, &cm, pose, &mut ws);
        assert_eq!(hit, !reference.is_empty(), "{ctx}");
        let d = closest_points(&cm, &Pose::IDENTITY, &cm, pose, f32::INFINITY, &mut ws).unwrap();
        assert!(d.distance.is_finite() && d.distance >= 0.0, "{ctx}: {d:?}");
        assert_eq!(d.distance == 0.0, hit, "{ctx}: {d:?}");
        colliding += usize::from(hit);
        apart += usize::from(!hit);

        for query in [AdbQuery::default(), AdbQuery::paper()] {
            let out = adb_intersects(&tree, &Pose::IDENTITY, &tree, pose, &query, &mut adb_ws);
            assert!((0.0..=1.0).contains(&out.probability), "{ctx}: {out:?}");
            assert!(
                (0.0..=1.0).contains(&out.max_pair_probability),
                "{ctx}: {out:?}"
            );
            if let Some(w) = out.witness {
                assert!(
                    w.point.is_finite() && w.normal.is_finite(),
                    "{ctx}: {out:?}"
                );
            }
        }
        let exact = AdbQuery {
            p_min: 1.0,
            exact_leaves: true,
            budget: Budget::Unlimited,
            ..AdbQuery::default()
        };
        let out = adb_intersects(&tree, &Pose::IDENTITY, &tree, pose, &exact, &mut adb_ws);
        assert_eq!(out.collides, hit, "{ctx}: ADB with exact leaves: {out:?}");
    }
    assert!(
        colliding >= 1 && apart >= 1,
        "{name}: {colliding} colliding, {apart} apart"
    );
}

fn load(file: &str) -> Option<TriMesh> {
    common::shared_mesh(file).map(|p| TriMesh::from_obj(p).unwrap())
}

/// Triangles with exactly zero area (collinear or coincident corners, in exact arithmetic).
fn zero_area_triangles(mesh: &TriMesh) -> usize {
    (0..mesh.triangle_count())
        .filter(|&t| {
            let [a, b, c] = mesh.triangle(t).map(|p| p.as_dvec3());
            (b - a).cross(c - a) == DVec3::ZERO
        })
        .count()
}

#[test]
fn ogre_with_zero_area_triangles() {
    let Some(mesh) = load("ogre.obj") else { return };
    assert!(
        zero_area_triangles(&mesh) >= 4,
        "README: 4 exactly zero-area triangles"
    );
    check_mesh("ogre", &mesh, 2);
}

#[test]
fn dragon_with_non_manifold_edges_and_duplicate_triangles() {
    let Some(mesh) = load("dragon_50k.obj") else {
        return;
    };
    let topo = Topology::new(&mesh);
    assert_eq!(
        topo.non_manifold_edge_count(),
        16,
        "README: 16 non-manifold edges"
    );
    let mut seen = HashSet::new();
    let duplicates = mesh
        .triangles()
        .iter()
        .filter(|t| {
            let mut k = **t;
            k.sort_unstable();
            !seen.insert(k)
        })
        .count();
    assert_eq!(duplicates, 11, "README: 11 duplicate triangles");
    check_mesh("dragon_50k", &mesh, 2);
}

#[test]
fn stanford_bunny_with_holes_and_unreferenced_vertices() {
    let Some(mesh) = load("stanford-bunny.obj") else {
        return;
    };
    let topo = Topology::new(&mesh);
    assert_eq!(
        topo.boundary_edge_count(),
        223,
        "README: 223 boundary edges"
    );
    let used: HashSet<u32> = mesh.triangles().iter().flatten().copied().collect();
    assert_eq!(
        mesh.vertex_count() - used.len(),
        1113,
        "README: 1,113 unreferenced"
    );
    // Unreferenced vertices do not count in the bounds (or anywhere else).
    let referenced = Aabb::from_points(used.iter().map(|&v| mesh.positions()[v as usize]));
    assert_eq!(mesh.aabb(), referenced);
    check_mesh("stanford-bunny", &mesh, 2);
}

#[test]
fn teapot_with_unwelded_seams() {
    let Some(mesh) = load("teapot.obj") else {
        return;
    };
    let mut groups: HashMap<[u32; 3], usize> = HashMap::new();
    for p in mesh.positions() {
        // `+ 0.0` makes -0 and +0 one key.
        *groups
            .entry((*p + 0.0).to_array().map(f32::to_bits))
            .or_default() += 1;
    }
    let duplicated = mesh.vertex_count() - groups.len();
    assert_eq!(
        duplicated, 403,
        "README: 403 vertices duplicate another's position"
    );
    check_mesh("teapot", &mesh, 3);
    // Seams are made of distinct vertices at one position: self-collision joins them, so the
    // triangles along a seam are adjacent, not intersecting.
    let cm = CollisionMesh::new(mesh.clone());
    let welded = cm.welded_triangles().expect("the seams weld");
    let mut pairs = Vec::new();
    self_intersections(&cm, &mut QueryWorkspace::new(), &mut pairs);
    let shares = |a: [u32; 3], b: [u32; 3]| a.iter().any(|v| b.contains(v));
    assert!(
        pairs
            .iter()
            .all(|p| !shares(welded[p.a as usize], welded[p.b as usize]))
    );
    // Without the joining, the seams themselves would be reported: triangles that share a
    // position but no vertex index, and touch there.
    let tris = mesh.triangles();
    let seam_pairs = (0..tris.len())
        .flat_map(|a| (a + 1..tris.len()).map(move |b| (a, b)))
        .filter(|&(a, b)| !shares(tris[a], tris[b]) && shares(welded[a], welded[b]))
        .count();
    assert!(
        seam_pairs > 100,
        "{seam_pairs} triangle pairs meet along the seams"
    );
}
