//! The properties the fuzz targets check, shared by `fuzz/` (each target decodes its input and
//! calls one function here; the fuzz crate includes this file by path) and by
//! `tests/fuzz_regressions.rs`, which replays every input the fuzzer found through the same
//! function. Under `cfg(fuzzing)` (set by cargo-fuzz) the inputs derive `arbitrary`.
#![allow(dead_code)]

use std::path::Path;

use glam::{DVec3, Quat, Vec3};
use stochastic_collision::adb::probability::{
    CellCounts, box_overlap_volume, cell_counts, collision_probability, depth_lower_bound,
    node_volume, overlap_volume, prob_at_least, sphere_lens_volume, tail_probabilities,
};
use stochastic_collision::adb::tables::{ProbabilityTable, table};
use stochastic_collision::adb::{
    AdbBuildOptions, AdbQuery, AdbTree, AdbWorkspace, Budget, FitOptions, adb_intersects,
};
use stochastic_collision::bvh::{
    CollisionMesh, QueryWorkspace, closest_points, intersecting_pairs, intersects,
    self_intersections,
};
use stochastic_collision::geometry::{
    Pose, closest_point_on_triangle, closest_points_segment_segment,
    closest_points_triangle_triangle, triangles_intersect, triangles_intersect_f32,
};
use stochastic_collision::mesh::{MeshError, TriMesh};

// ---------------------------------------------------------------------------------------------
// OBJ parsing.

/// OBJ parsing on arbitrary bytes: never panics; an accepted mesh is valid and round-trips
/// through `write_obj`; a refusal is `Malformed`, naming the source and a line inside the input.
pub fn obj_parse(data: &[u8]) {
    let name = Path::new("fuzz.obj");
    match TriMesh::from_obj_reader(data, name) {
        Ok(mesh) => {
            assert!(mesh.triangle_count() > 0);
            let n = mesh.vertex_count();
            assert!(mesh.triangles().iter().flatten().all(|&i| (i as usize) < n));
            assert!(mesh.positions().iter().all(|p| p.is_finite()));
            let mut text = Vec::new();
            mesh.write_obj(&mut text).unwrap();
            let back = TriMesh::from_obj_reader(text.as_slice(), name).unwrap();
            assert_eq!(back, mesh);
        }
        Err(MeshError::Malformed {
            path,
            line,
            message,
        }) => {
            assert_eq!(path, name);
            let lines = data.split(|&b| b == b'\n').count();
            assert!(line <= lines, "line {line} of {lines}: {message}");
            assert!(!message.is_empty());
        }
        Err(other) => panic!("in-memory input gave {other:?}"),
    }
}

// ---------------------------------------------------------------------------------------------
// Triangle–triangle.

/// Six corners (two triangles) in one of three encodings.
#[derive(Debug, Clone)]
#[cfg_attr(fuzzing, derive(arbitrary::Arbitrary))]
pub enum TriTriInput {
    /// `f32` corners: every property is checked when they are finite.
    Single([[f32; 3]; 6]),
    /// Raw `f64` corners, any magnitude.
    Double([[f64; 3]; 6]),
    /// Small integer corners (many touching and coplanar configurations).
    Grid([[i8; 3]; 6]),
}

/// Triangle–triangle intersection and closest points on arbitrary floats: never panics; a NaN
/// or infinite corner gives "disjoint" and distance `+∞`; on corners in the `f32` range (where
/// the predicates are exact) the answer is symmetric, invariant under corner order and under
/// scaling by `2^800` (orientations overflow `f64`: the rescaling path), and agrees with the
/// closest-point query.
pub fn tri_tri(input: &TriTriInput) {
    let corners: [DVec3; 6] = match input {
        TriTriInput::Single(c) => c.map(|p| Vec3::from_array(p).as_dvec3()),
        TriTriInput::Double(c) => c.map(DVec3::from_array),
        TriTriInput::Grid(c) => c.map(|p| DVec3::new(p[0].into(), p[1].into(), p[2].into())),
    };
    let a = [corners[0], corners[1], corners[2]];
    let b = [corners[3], corners[4], corners[5]];
    let hit = triangles_intersect(&a, &b);
    let cp = closest_points_triangle_triangle(&a, &b);
    let _ = closest_point_on_triangle(b[0], &a);
    let _ = closest_points_segment_segment(a[0], a[1], b[0], b[1]);
    if !corners.iter().all(|p| p.is_finite()) {
        assert!(!hit, "a NaN or infinite corner intersects");
        assert_eq!(cp.distance, f64::INFINITY, "{cp:?}");
        return;
    }
    assert!(!cp.distance.is_nan(), "{cp:?}");
    let in_f32_range = corners.iter().all(|p| p.as_vec3().as_dvec3() == *p);
    if !in_f32_range {
        return;
    }
    assert_eq!(triangles_intersect(&b, &a), hit, "swap");
    assert_eq!(
        triangles_intersect(&[a[1], a[2], a[0]], &b),
        hit,
        "rotate a"
    );
    assert_eq!(
        triangles_intersect(&a, &[b[2], b[1], b[0]]),
        hit,
        "reverse b"
    );
    let f32s = |t: [DVec3; 3]| t.map(|p| p.as_vec3());
    assert_eq!(triangles_intersect_f32(f32s(a), f32s(b)), hit);
    // 2^800 keeps every f32 finite (f32::MAX · 2^800 < 1e280).
    let k = 2f64.powi(800);
    let big = |t: [DVec3; 3]| t.map(|p| p * k);
    assert_eq!(
        triangles_intersect(&big(a), &big(b)),
        hit,
        "scaled by 2^800"
    );
    assert!(cp.distance.is_finite() && cp.distance >= 0.0, "{cp:?}");
    assert!(cp.point_a.is_finite() && cp.point_b.is_finite(), "{cp:?}");
    if hit {
        assert_eq!(cp.distance, 0.0, "{cp:?}");
        assert_eq!(cp.point_a, cp.point_b);
    }
    assert!(
        closest_points_triangle_triangle(&b, &a)
            .distance
            .is_finite()
    );
    let p = closest_point_on_triangle(b[0], &a);
    assert!(p.is_finite(), "{p:?}");
    let s = closest_points_segment_segment(a[0], a[1], b[0], b[1]);
    assert!(s.distance.is_finite() && s.distance >= 0.0, "{s:?}");
}

// ---------------------------------------------------------------------------------------------
// Mesh queries.

/// A small mesh from raw parts (validated by `TriMesh::new`).
#[derive(Debug, Clone)]
#[cfg_attr(fuzzing, derive(arbitrary::Arbitrary))]
pub struct MeshInput {
    /// Vertex positions (the first 16 are used).
    pub positions: Vec<[f32; 3]>,
    /// Triangles (the first 24), indices taken modulo one more than the vertex count, so some
    /// are out of range.
    pub triangles: Vec<[u8; 3]>,
    /// Snap coordinates to a grid of this many steps per unit (0: raw floats), for touching
    /// configurations.
    pub grid: u8,
}

/// Two meshes and their poses.
#[derive(Debug, Clone)]
#[cfg_attr(fuzzing, derive(arbitrary::Arbitrary))]
pub struct MeshQueryInput {
    /// The first mesh.
    pub a: MeshInput,
    /// The second mesh (ignored with `same`).
    pub b: MeshInput,
    /// Query the first mesh against itself.
    pub same: bool,
    /// Translation and rotation (normalised by `Pose::new`) of the first mesh.
    pub pose_a: ([f32; 3], [f32; 4]),
    /// Of the second.
    pub pose_b: ([f32; 3], [f32; 4]),
    /// Fit the ADB calibration at build.
    pub fit: bool,
    /// ADB node-pair budget (0: unlimited).
    pub budget: u8,
}

fn build(m: &MeshInput) -> Option<TriMesh> {
    let positions: Vec<Vec3> = m
        .positions
        .iter()
        .take(16)
        .map(|p| {
            let v = Vec3::from_array(*p);
            if m.grid > 0 && v.is_finite() {
                let g = f32::from(m.grid);
                (v.clamp(Vec3::splat(-1e3), Vec3::splat(1e3)) * g).round() / g
            } else {
                v
            }
        })
        .collect();
    let n = positions.len() as u32 + 1;
    let triangles = m
        .triangles
        .iter()
        .take(24)
        .map(|t| t.map(|i| u32::from(i) % n))
        .collect();
    // Out-of-range indices and non-finite coordinates must be refused, not panic.
    TriMesh::new(positions, triangles).ok()
}

fn pose((t, q): &([f32; 3], [f32; 4])) -> Pose {
    Pose::new(Vec3::from_array(*t), Quat::from_array(*q))
}

/// Mesh queries on small meshes built through the validating constructor: never panics; the
/// exact queries equal brute force over all triangle pairs (in the crate's frame and
/// arithmetic); a pose that is not finite (or two poses farther apart than the `f32` range)
/// gives no collision and no distance; ADB answers are
/// probabilities in [0, 1] and, with exact leaves, `p_min = 1` and no budget, equal the exact
/// answer.
pub fn mesh_query(input: &MeshQueryInput) {
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
    // Not finite: a pose is not, or the two are farther apart than the f32 range.
    let finite = pa.inverse_mul(&pb).is_finite();
    if !(pa.is_finite() && pb.is_finite()) {
        assert!(!finite);
    }
    if !finite {
        assert!(!hit && pairs.is_empty() && dist.is_none(), "{dist:?}");
    } else {
        // Brute force, b placed in a's frame as the crate places it.
        let rel = pa.inverse_mul(&pb).to_f64();
        let tri_a = |t: usize| mesh_a.triangle(t).map(|p| p.as_dvec3());
        let tri_b = |t: usize| mesh_b.triangle(t).map(|p| rel.transform_point(p));
        let mut brute_pairs = Vec::new();
        let mut brute_dist = f64::INFINITY;
        for t in 0..mesh_a.triangle_count() {
            for u in 0..mesh_b.triangle_count() {
                if triangles_intersect(&tri_a(t), &tri_b(u)) {
                    brute_pairs.push((t as u32, u as u32));
                }
                let d = closest_points_triangle_triangle(&tri_a(t), &tri_b(u)).distance;
                brute_dist = brute_dist.min(d);
            }
        }
        assert_eq!(hit, !brute_pairs.is_empty(), "intersects vs brute force");
        let mut got: Vec<(u32, u32)> = pairs.iter().map(|p| (p.a, p.b)).collect();
        got.sort_unstable();
        assert_eq!(got, brute_pairs, "intersecting_pairs vs brute force");
        let d = dist.expect("no distance limit: always an answer");
        // (Infinite only when the distance exceeds the f32 range.)
        assert!(d.distance >= 0.0, "{d:?}");
        if hit {
            assert_eq!(d.distance, 0.0, "{d:?}");
        }
        let want = brute_dist as f32;
        assert!(
            d.distance == want || (d.distance - want).abs() <= 1e-5 * (1.0 + want.abs()),
            "closest_points {} vs brute force {want}",
            d.distance
        );
    }
    let mut self_pairs = Vec::new();
    self_intersections(&a, &mut ws, &mut self_pairs);
    // Adjacent: a corner in common once corners at one position are joined.
    let mut first = std::collections::HashMap::new();
    let joined: Vec<u32> = (0..mesh_a.vertex_count())
        .map(|v| {
            let p = mesh_a.positions()[v] + Vec3::ZERO;
            *first
                .entry(p.to_array().map(f32::to_bits))
                .or_insert(v as u32)
        })
        .collect();
    let mut brute_self = Vec::new();
    for t in 0..mesh_a.triangle_count() {
        for u in t + 1..mesh_a.triangle_count() {
            let (ta, tb) = (
                mesh_a.triangles()[t].map(|v| joined[v as usize]),
                mesh_a.triangles()[u].map(|v| joined[v as usize]),
            );
            let (x, y) = (mesh_a.triangle(t), mesh_a.triangle(u));
            if !ta.iter().any(|i| tb.contains(i)) && triangles_intersect_f32(x, y) {
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

    let options = AdbBuildOptions {
        threads: 1,
        fit: input.fit.then_some(FitOptions {
            poses: 3,
            walks_per_pose: 3,
            ..FitOptions::default()
        }),
        ..AdbBuildOptions::default()
    };
    let (ta, tb) = (
        AdbTree::build_with(a, options),
        AdbTree::build_with(b, options),
    );
    let mut aws = AdbWorkspace::new();
    let budget = match input.budget {
        0 => Budget::Unlimited,
        n => Budget::NodePairs(u64::from(n)),
    };
    for q in [AdbQuery::with_budget(budget), AdbQuery::paper()] {
        let out = adb_intersects(&ta, &pa, &tb, &pb, &q, &mut aws);
        assert!((0.0..=1.0).contains(&out.probability), "{out:?}");
        assert!((0.0..=1.0).contains(&out.max_pair_probability), "{out:?}");
        if !finite {
            assert!(!out.collides && out.probability == 0.0, "{out:?}");
        }
    }
    let exact = AdbQuery {
        p_min: 1.0,
        exact_leaves: true,
        ..AdbQuery::default()
    };
    let out = adb_intersects(&ta, &pa, &tb, &pb, &exact, &mut aws);
    assert_eq!(
        out.collides, hit,
        "ADB with exact leaves and p_min = 1: {out:?}"
    );
}

// ---------------------------------------------------------------------------------------------
// The probability model.

/// Counts and shapes for the probability model.
#[derive(Debug, Clone)]
#[cfg_attr(fuzzing, derive(arbitrary::Arbitrary))]
pub struct ProbabilityInput {
    /// Cells in the overlap.
    pub s: u32,
    /// Well-filled cells of A in it.
    pub s_a: u32,
    /// Of B.
    pub s_b: u32,
    /// The `x` of Eq. 8.
    pub x: u8,
    /// The cap on `x` in Eq. 9 (taken modulo 40).
    pub x_max: u8,
    /// The curvature term.
    pub lb: f64,
    /// Box sides of A.
    pub sides_a: [f32; 3],
    /// Of B.
    pub sides_b: [f32; 3],
    /// Centre distance.
    pub d: f32,
    /// Well-filled counts of the nodes.
    pub wf: [u32; 2],
    /// Cells per node.
    pub cells: u32,
    /// Node depths and maximum depths.
    pub depths: [u32; 4],
    /// Keep the counts under 80 (the table's range and a little beyond).
    pub small: bool,
}

fn unit(p: f64, what: &str) {
    assert!((0.0..=1.0).contains(&p), "{what} = {p}");
}

/// The ADB probability model on arbitrary counts and floats: every result is finite and in
/// [0, 1], symmetric and monotone in `x` where promised, the table agrees with the direct
/// evaluation, the counts stay consistent.
pub fn probability(i: &ProbabilityInput) {
    // The direct evaluation's cost grows with the law's width (about sqrt(s)): cap s.
    let (s, s_a, s_b) = if i.small {
        (i.s % 80, i.s_a % 80, i.s_b % 80)
    } else {
        (i.s % 2_000_000, i.s_a, i.s_b)
    };
    let x = u32::from(i.x);
    let x_max = u32::from(i.x_max % 40);
    let p = prob_at_least(s, s_a, s_b, x);
    unit(p, "prob_at_least");
    assert!(
        (p - prob_at_least(s, s_b, s_a, x)).abs() <= 1e-12,
        "symmetry"
    );
    if x > 0 {
        assert!(
            prob_at_least(s, s_a, s_b, x - 1) >= p - 1e-12,
            "non-increasing in x"
        );
    }
    let t = table().prob_at_least(s, s_a, s_b, x);
    unit(t, "tabled prob_at_least");
    assert!(
        (t - p).abs() <= ProbabilityTable::MAX_ERROR,
        "table {t} vs direct {p}"
    );
    let mut tails = [0.0; 12];
    tail_probabilities(s, s_a, s_b, &mut tails);
    for (k, w) in tails.iter().enumerate() {
        unit(*w, "tail");
        assert!(k == 0 || *w <= tails[k - 1]);
    }
    let counts = CellCounts {
        s,
        s_a: s_a.min(s),
        s_b: s_b.min(s),
    };
    let c = collision_probability(counts, i.lb, x_max);
    unit(c, "collision_probability");
    let ct = table().collision_probability(counts, i.lb, x_max);
    unit(ct, "tabled collision_probability");
    assert!(
        (c - ct).abs() <= ProbabilityTable::MAX_ERROR,
        "Eq. 9 table {ct} vs direct {c}"
    );

    // Volumes are never NaN, and finite unless a side is infinite (then the overlap of two
    // unbounded boxes may be infinite).
    let bounded = i.sides_a.iter().chain(&i.sides_b).all(|s| s.is_finite());
    let v = overlap_volume(i.sides_a, i.sides_b, i.d);
    assert!(v >= 0.0 && (v.is_finite() || !bounded), "overlap {v}");
    let bv = box_overlap_volume(i.sides_a, i.sides_b, i.d);
    assert!(
        bv >= 0.0 && (bv.is_finite() || !bounded),
        "box overlap {bv}"
    );
    let sl = sphere_lens_volume(i.sides_a[0].into(), i.sides_b[0].into(), i.d.into());
    assert!(!sl.is_nan() && sl >= 0.0, "lens {sl}");
    let (va, vb) = (node_volume(i.sides_a), node_volume(i.sides_b));
    assert!(va >= 0.0 && vb >= 0.0, "{va} {vb}");
    let cc = cell_counts(v, va, vb, i.wf[0], i.wf[1], i.cells);
    assert!(
        cc.s <= i.cells && cc.s_a <= cc.s && cc.s_b <= cc.s,
        "{cc:?}"
    );
    let [da, db, ma, mb] = i.depths;
    unit(depth_lower_bound(da, db, ma, mb), "depth_lower_bound");
}
