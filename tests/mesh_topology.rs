//! Mesh adjacency (`Topology`) and the generators' shape, closure and orientation.
mod common;

use std::collections::{HashMap, HashSet};
use std::f64::consts::PI;

use glam::{DVec3, Vec3};
use stochastic_collision::mesh::{Topology, TriMesh, generate};

/// Volume enclosed by a closed mesh, positive when it is oriented outward.
fn signed_volume(mesh: &TriMesh) -> f64 {
    (0..mesh.triangle_count())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t).map(|p| p.as_dvec3());
            a.dot(b.cross(c))
        })
        .sum::<f64>()
        / 6.0
}

fn normal(mesh: &TriMesh, t: usize) -> DVec3 {
    let [a, b, c] = mesh.triangle(t).map(|p| p.as_dvec3());
    (b - a).cross(c - a)
}

fn centroid(mesh: &TriMesh, t: usize) -> DVec3 {
    let [a, b, c] = mesh.triangle(t).map(|p| p.as_dvec3());
    (a + b + c) / 3.0
}

/// Checks every adjacency list against the triangles, exhaustively.
fn check_consistent(mesh: &TriMesh, topo: &Topology) {
    let tris = mesh.triangles();
    assert_eq!(topo.vertex_count(), mesh.vertex_count());
    assert_eq!(topo.triangle_count(), mesh.triangle_count());
    // Edges: sorted, distinct, smaller vertex first, no self-edges, triangles ascending.
    for pair in topo.edges().windows(2) {
        assert!(pair[0].vertices < pair[1].vertices);
    }
    for (id, edge) in topo.edges().iter().enumerate() {
        let [a, b] = edge.vertices;
        assert!(a < b);
        assert!(!edge.triangles.is_empty());
        assert!(edge.triangles.windows(2).all(|w| w[0] < w[1]));
        for &t in &edge.triangles {
            assert!(topo.triangle_edges(t).contains(&(id as u32)));
        }
        assert_eq!(topo.edge_between(a, b), Some(id as u32));
        assert_eq!(topo.edge_between(b, a), Some(id as u32));
    }
    // Triangle edges: side i joins corners i and i + 1.
    for (t, tri) in tris.iter().enumerate() {
        let sides = topo.triangle_edges(t as u32);
        for i in 0..3 {
            let (a, b) = (tri[i], tri[(i + 1) % 3]);
            if a == b {
                assert_eq!(sides[i], Topology::NO_EDGE);
                continue;
            }
            let edge = topo.edge(sides[i]);
            assert_eq!(edge.vertices, [a.min(b), a.max(b)]);
            assert!(edge.triangles.contains(&(t as u32)));
        }
        let neighbours = topo.triangle_neighbours(t as u32);
        assert!(neighbours.windows(2).all(|w| w[0] < w[1]));
        assert!(!neighbours.contains(&(t as u32)));
        let mut expected: Vec<u32> = sides
            .iter()
            .filter(|&&e| e != Topology::NO_EDGE)
            .flat_map(|&e| topo.edge(e).triangles.iter().copied())
            .filter(|&o| o != t as u32)
            .collect();
        expected.sort_unstable();
        expected.dedup();
        assert_eq!(neighbours, expected.as_slice());
    }
    // Vertex lists.
    let mut vertex_triangles = vec![Vec::new(); mesh.vertex_count()];
    for (t, tri) in tris.iter().enumerate() {
        for (i, &v) in tri.iter().enumerate() {
            if !tri[..i].contains(&v) {
                vertex_triangles[v as usize].push(t as u32);
            }
        }
    }
    for v in 0..mesh.vertex_count() as u32 {
        assert_eq!(
            topo.vertex_triangles(v),
            vertex_triangles[v as usize].as_slice()
        );
        let neighbours = topo.vertex_neighbours(v);
        let edges = topo.vertex_edges(v);
        assert_eq!(neighbours.len(), edges.len());
        assert!(
            neighbours.windows(2).all(|w| w[0] < w[1]),
            "sorted, distinct"
        );
        assert!(!neighbours.contains(&v));
        for (&u, &e) in neighbours.iter().zip(edges) {
            assert_eq!(topo.edge(e).vertices, [u.min(v), u.max(v)]);
            assert!(
                topo.vertex_neighbours(u).binary_search(&v).is_ok(),
                "neighbours are symmetric"
            );
        }
        let on_boundary = edges.iter().any(|&e| topo.edge(e).triangles.len() == 1);
        assert_eq!(topo.is_boundary_vertex(v), on_boundary);
    }
    assert_eq!(topo.boundary_edges().count(), topo.boundary_edge_count());
    assert_eq!(
        topo.non_manifold_edges().count(),
        topo.non_manifold_edge_count()
    );
    assert!(
        topo.boundary_edges()
            .all(|e| topo.edge(e).triangles.len() == 1)
    );
    assert!(
        topo.non_manifold_edges()
            .all(|e| topo.edge(e).triangles.len() > 2)
    );
}

/// Checks that every interior edge is traversed in opposite directions by its two triangles
/// (consistent orientation) and no two vertices share a position (welded).
fn check_oriented_and_welded(mesh: &TriMesh) {
    let mut directed = HashSet::new();
    for tri in mesh.triangles() {
        for i in 0..3 {
            assert!(
                directed.insert((tri[i], tri[(i + 1) % 3])),
                "an edge is traversed twice the same way"
            );
        }
    }
    let mut seen = HashMap::new();
    for (i, p) in mesh.positions().iter().enumerate() {
        let key = (*p * 1e5).round().as_ivec3().to_array();
        if let Some(j) = seen.insert(key, i) {
            panic!("vertices {j} and {i} share position {p}");
        }
    }
}

fn euler(mesh: &TriMesh) -> i64 {
    Topology::new(mesh).euler_characteristic()
}

// ---------------------------------------------------------------- generators

#[test]
fn icosphere_is_a_closed_outward_sphere() {
    for s in 0..4 {
        let mesh = generate::icosphere(1.5, s);
        let topo = Topology::new(&mesh);
        let f = 20 * 4usize.pow(s);
        assert_eq!(mesh.triangle_count(), f);
        assert_eq!(mesh.vertex_count(), f / 2 + 2);
        assert_eq!(topo.edges().len(), f * 3 / 2);
        assert!(topo.is_closed());
        assert!(mesh.is_closed());
        assert_eq!(topo.euler_characteristic(), 2);
        check_consistent(&mesh, &topo);
        check_oriented_and_welded(&mesh);
        for p in mesh.positions() {
            assert!((p.length() - 1.5).abs() < 1e-5);
        }
        for t in 0..mesh.triangle_count() {
            assert!(normal(&mesh, t).dot(centroid(&mesh, t)) > 0.0);
        }
    }
    let fine = generate::icosphere(2.0, 4);
    let exact = 4.0 / 3.0 * PI * 8.0;
    let v = signed_volume(&fine);
    assert!(
        v > 0.0 && (v - exact).abs() < 0.01 * exact,
        "{v} vs {exact}"
    );
    // Clamped: no overflow, no panic for absurd levels (checked without building them).
    assert_eq!(generate::MAX_ICOSPHERE_SUBDIVISIONS, 10);
}

#[test]
fn torus_is_closed_genus_one_and_outward() {
    let (big, small) = (2.0f32, 0.5f32);
    let mesh = generate::torus(big, small, 48, 24);
    let topo = Topology::new(&mesh);
    assert_eq!(mesh.triangle_count(), 2 * 48 * 24);
    assert_eq!(mesh.vertex_count(), 48 * 24);
    assert_eq!(topo.edges().len(), 3 * 48 * 24);
    assert!(topo.is_closed());
    assert_eq!(topo.euler_characteristic(), 0);
    check_consistent(&mesh, &topo);
    check_oriented_and_welded(&mesh);
    // Axis Y: symmetric in y, extends to big + small in X and Z.
    let aabb = mesh.aabb();
    assert!((aabb.max.y - small).abs() < 1e-5 && (aabb.min.y + small).abs() < 1e-5);
    assert!((aabb.max.x - (big + small)).abs() < 1e-5);
    for t in 0..mesh.triangle_count() {
        let c = centroid(&mesh, t);
        let core = DVec3::new(c.x, 0.0, c.z).normalize() * f64::from(big);
        assert!(
            normal(&mesh, t).dot(c - core) > 0.0,
            "triangle {t} faces inward"
        );
    }
    let exact = 2.0 * PI * PI * f64::from(big) * f64::from(small).powi(2);
    let v = signed_volume(&mesh);
    assert!(
        v > 0.0 && (v - exact).abs() < 0.03 * exact,
        "{v} vs {exact}"
    );
    // Minimum segment counts are clamped, not refused.
    let tiny = generate::torus(1.0, 0.2, 0, 2);
    assert_eq!(tiny.vertex_count(), 9);
    assert!(tiny.is_closed());
    assert_eq!(euler(&tiny), 0);
}

#[test]
fn cuboid_is_a_closed_welded_box() {
    let h = Vec3::new(1.0, 2.0, 0.5);
    for s in 0..4u32 {
        let n = (s + 1) as usize;
        let mesh = generate::cuboid(h, s);
        let topo = Topology::new(&mesh);
        assert_eq!(mesh.triangle_count(), 12 * n * n);
        assert_eq!(mesh.vertex_count(), 6 * n * n + 2);
        assert_eq!(topo.edges().len(), 18 * n * n);
        assert!(topo.is_closed());
        assert_eq!(topo.euler_characteristic(), 2);
        check_consistent(&mesh, &topo);
        check_oriented_and_welded(&mesh);
        let aabb = mesh.aabb();
        assert_eq!(aabb.min, -h);
        assert_eq!(aabb.max, h);
        for t in 0..mesh.triangle_count() {
            assert!(normal(&mesh, t).dot(centroid(&mesh, t)) > 0.0);
        }
        let v = signed_volume(&mesh);
        assert!((v - 8.0).abs() < 1e-4, "{v}");
    }
}

#[test]
fn cloth_grid_is_an_open_disc_facing_up() {
    for (nx, nz) in [(1, 1), (3, 5), (50, 50), (7, 1)] {
        let mesh = generate::cloth_grid(2.0, 3.0, nx, nz);
        let topo = Topology::new(&mesh);
        let (nxu, nzu) = (nx as usize, nz as usize);
        assert_eq!(mesh.triangle_count(), 2 * nxu * nzu);
        assert_eq!(mesh.vertex_count(), (nxu + 1) * (nzu + 1));
        // Horizontal + vertical + diagonal edges.
        assert_eq!(
            topo.edges().len(),
            nxu * (nzu + 1) + nzu * (nxu + 1) + nxu * nzu
        );
        assert_eq!(topo.boundary_edge_count(), 2 * (nxu + nzu));
        assert_eq!(topo.non_manifold_edge_count(), 0);
        assert!(!topo.is_closed());
        assert_eq!(topo.euler_characteristic(), 1);
        check_consistent(&mesh, &topo);
        check_oriented_and_welded(&mesh);
        for t in 0..mesh.triangle_count() {
            let n = normal(&mesh, t);
            assert!(n.y > 0.0 && n.x == 0.0 && n.z == 0.0);
        }
        let aabb = mesh.aabb();
        assert_eq!(aabb.min, Vec3::new(-1.0, 0.0, -1.5));
        assert_eq!(aabb.max, Vec3::new(1.0, 0.0, 1.5));
        // Interior vertices are not on the boundary, corners are.
        assert!(topo.is_boundary_vertex(0));
        if nx > 1 && nz > 1 {
            assert!(!topo.is_boundary_vertex(nx + 2));
        }
    }
    // Clamped to at least one quad.
    assert_eq!(generate::cloth_grid(1.0, 1.0, 0, 0).triangle_count(), 2);
}

#[test]
fn tube_is_open_or_closed_by_its_caps() {
    let (r, len, rs, ls) = (0.5f32, 3.0f32, 40u32, 6u32);
    let open = generate::tube(r, len, rs, ls, false);
    let topo = Topology::new(&open);
    assert_eq!(open.triangle_count(), (2 * rs * ls) as usize);
    assert_eq!(open.vertex_count(), (rs * (ls + 1)) as usize);
    assert_eq!(topo.boundary_edge_count(), 2 * rs as usize);
    assert_eq!(topo.non_manifold_edge_count(), 0);
    assert!(!topo.is_closed());
    assert_eq!(topo.euler_characteristic(), 0);
    check_consistent(&open, &topo);
    check_oriented_and_welded(&open);
    for t in 0..open.triangle_count() {
        let c = centroid(&open, t);
        assert!(normal(&open, t).dot(DVec3::new(c.x, 0.0, c.z)) > 0.0);
    }
    let aabb = open.aabb();
    assert!((aabb.min.y + len / 2.0).abs() < 1e-6 && (aabb.max.y - len / 2.0).abs() < 1e-6);

    let capped = generate::tube(r, len, rs, ls, true);
    let topo = Topology::new(&capped);
    assert_eq!(capped.triangle_count(), (2 * rs * ls + 2 * rs) as usize);
    assert_eq!(capped.vertex_count(), (rs * (ls + 1) + 2) as usize);
    assert!(topo.is_closed());
    assert_eq!(topo.euler_characteristic(), 2);
    check_consistent(&capped, &topo);
    check_oriented_and_welded(&capped);
    let exact = PI * f64::from(r * r * len);
    let v = signed_volume(&capped);
    assert!(
        v > 0.0 && (v - exact).abs() < 0.01 * exact,
        "{v} vs {exact}"
    );
    // Clamped minimum counts.
    let min = generate::tube(1.0, 1.0, 0, 0, true);
    assert_eq!(min.triangle_count(), 2 * 3 + 2 * 3);
    assert!(min.is_closed());
}

#[test]
fn negative_sizes_are_taken_as_absolute() {
    assert_eq!(generate::icosphere(-1.0, 1), generate::icosphere(1.0, 1));
    assert_eq!(
        generate::cuboid(Vec3::new(-1.0, 2.0, -3.0), 1),
        generate::cuboid(Vec3::new(1.0, 2.0, 3.0), 1)
    );
    assert!(signed_volume(&generate::tube(-1.0, -2.0, 8, 2, true)) > 0.0);
}

// ---------------------------------------------------------------- hand-made meshes

fn mesh(vertices: usize, triangles: Vec<[u32; 3]>) -> TriMesh {
    let positions = (0..vertices)
        .map(|i| Vec3::new(i as f32, (i % 3) as f32, (i % 5) as f32))
        .collect();
    TriMesh::new(positions, triangles).unwrap()
}

#[test]
fn degenerate_triangles_make_no_self_edges() {
    // A square (0 1 2 3) plus a triangle with a repeated index and one with a single vertex.
    let m = mesh(6, vec![[0, 1, 2], [0, 2, 3], [3, 3, 5], [4, 4, 4]]);
    let topo = Topology::new(&m);
    check_consistent(&m, &topo);
    assert_eq!(topo.triangle_edges(2)[0], Topology::NO_EDGE);
    assert_eq!(topo.triangle_edges(3), [Topology::NO_EDGE; 3]);
    assert_eq!(topo.vertex_triangles(3), &[1, 2]);
    assert_eq!(topo.vertex_triangles(4), &[3]);
    assert_eq!(topo.vertex_neighbours(4), &[] as &[u32]);
    assert_eq!(topo.vertex_neighbours(3), &[0, 2, 5]);
    assert_eq!(topo.edge_between(3, 3), None);
    assert_eq!(topo.edge_between(4, 4), None);
    let e = topo.edge_between(5, 3).unwrap();
    assert_eq!(topo.edge(e).triangles.as_slice(), &[2]);
    assert!(topo.edge(e).is_boundary());
    assert_eq!(topo.edges().len(), 6);
    assert_eq!(topo.boundary_edge_count(), 5);
    assert!(topo.edges().iter().all(|e| e.vertices[0] != e.vertices[1]));
}

#[test]
fn only_degenerate_triangles_is_not_closed() {
    let m = mesh(1, vec![[0, 0, 0]]);
    let topo = Topology::new(&m);
    assert!(topo.edges().is_empty());
    assert!(!topo.is_closed());
    assert_eq!(topo.triangle_neighbours(0), &[] as &[u32]);
}

#[test]
fn three_triangles_on_one_edge_are_non_manifold() {
    // A "book" of three pages on the spine 0–1.
    let m = mesh(5, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]);
    let topo = Topology::new(&m);
    check_consistent(&m, &topo);
    let spine = topo.edge_between(0, 1).unwrap();
    assert_eq!(topo.edge(spine).triangles.as_slice(), &[0, 1, 2]);
    assert_eq!(topo.non_manifold_edges().collect::<Vec<_>>(), vec![spine]);
    assert_eq!(topo.boundary_edge_count(), 6);
    assert!(!topo.is_closed());
    assert_eq!(topo.triangle_neighbours(1), &[0, 2]);
}

#[test]
fn duplicate_triangles_in_a_closed_mesh_make_non_manifold_edges() {
    let base = generate::icosphere(1.0, 1);
    let mut triangles = base.triangles().to_vec();
    triangles.push(triangles[7]);
    let m = TriMesh::new(base.positions().to_vec(), triangles).unwrap();
    let topo = Topology::new(&m);
    check_consistent(&m, &topo);
    assert_eq!(topo.non_manifold_edge_count(), 3);
    assert_eq!(topo.boundary_edge_count(), 0);
    assert!(!topo.is_closed());
    let last = (m.triangle_count() - 1) as u32;
    assert!(topo.triangle_neighbours(7).contains(&last));
}

#[test]
fn unreferenced_vertices_have_empty_lists() {
    let m = mesh(6, vec![[1, 2, 4]]);
    let topo = Topology::new(&m);
    check_consistent(&m, &topo);
    for v in [0, 3, 5] {
        assert!(topo.vertex_triangles(v).is_empty());
        assert!(topo.vertex_neighbours(v).is_empty());
        assert!(topo.vertex_edges(v).is_empty());
        assert!(!topo.is_boundary_vertex(v));
    }
    assert_eq!(topo.euler_characteristic(), 1);
}

// ---------------------------------------------------------------- real meshes

/// (file, boundary edges, non-manifold edges, closed, Euler characteristic) from the README.
const SHARED: &[(&str, usize, usize, bool, i64)] = &[
    ("suzanne.obj", 42, 1, false, 3),
    ("torus.obj", 0, 0, true, 0),
    ("plane_50x50.obj", 200, 0, false, 1),
    ("spot.obj", 0, 0, true, 2),
    ("teapot.obj", 1_036, 0, false, -34),
    ("bunny.obj", 0, 0, true, 2),
    ("large_intestine_20k.obj", 0, 0, true, 0),
    ("armadillo.obj", 0, 0, true, 2),
    ("large-intestine-sf+-hf-.obj", 240, 0, false, -6),
    ("dragon_50k.obj", 0, 16, false, 23),
    ("stanford-bunny.obj", 223, 0, false, -3),
    ("small_intestine_100k.obj", 0, 0, true, 2),
    ("ogre.obj", 236, 0, false, 72),
];

#[test]
fn shared_meshes_have_the_documented_topology() {
    for &(file, boundary, non_manifold, closed, chi) in SHARED {
        let Some(path) = common::shared_mesh(file) else {
            continue;
        };
        let mesh = TriMesh::from_obj(&path).unwrap();
        let topo = Topology::new(&mesh);
        assert_eq!(
            topo.boundary_edge_count(),
            boundary,
            "{file} boundary edges"
        );
        assert_eq!(
            topo.non_manifold_edge_count(),
            non_manifold,
            "{file} non-manifold"
        );
        assert_eq!(topo.is_closed(), closed, "{file} closed");
        assert_eq!(
            topo.euler_characteristic(),
            chi,
            "{file} Euler characteristic"
        );
    }
}

#[test]
fn stanford_bunny_unreferenced_vertices_have_no_adjacency() {
    let Some(path) = common::shared_mesh("stanford-bunny.obj") else {
        return;
    };
    let mesh = TriMesh::from_obj(&path).unwrap();
    let topo = Topology::new(&mesh);
    let lonely = (0..mesh.vertex_count() as u32)
        .filter(|&v| topo.vertex_triangles(v).is_empty())
        .inspect(|&v| assert!(topo.vertex_neighbours(v).is_empty()))
        .count();
    assert_eq!(lonely, 1_113);
}

#[test]
fn adjacency_of_a_real_mesh_is_consistent() {
    // Exhaustive checks on a real, irregular, open mesh with a non-manifold edge.
    let Some(path) = common::shared_mesh("suzanne.obj") else {
        return;
    };
    let mesh = TriMesh::from_obj(&path).unwrap();
    check_consistent(&mesh, &Topology::new(&mesh));
}
