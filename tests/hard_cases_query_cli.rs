//! Issue 6's geometric hard cases through the public mesh API and the `query` example.
//!
//! `geometry_hard_cases.rs` checks the triangle–triangle primitive on many more configurations
//! (down to one-ulp gaps in `f64`). Here each configuration of the list is a pair of
//! one-triangle meshes whose answer is certain in exact arithmetic, stored in `f32` without
//! rounding, and checked with the meshes in both orders:
//!
//! * through [`intersects`], [`intersecting_pairs`] and [`closest_points`] on
//!   [`CollisionMesh`]es, at identity poses and at an identical non-trivial pose (a half-turn,
//!   whose relative pose is exactly the identity);
//! * through the `query` example in exact mode, many cases per invocation.
//!
//! Every configuration is replayed at its own size, scaled by about 1e-4 and 1e6 and moved 1e5
//! from the origin. "A hair" is the smallest power of two `h` (at most 2^-16 of a size-4
//! triangle) for which every coordinate of every case stays exact in `f32` under the transform:
//! 2^-16 at the origin, one `f32` ulp (2^-7) at 1e5 from it. Slivers have aspect ratio `16/h`
//! (2^20 ≈ 1e6 at the origin) or `8/h`.
mod common;

use std::fmt::Write as _;

use common::cli::{run_exact, scratch, write_obj};
use glam::{DVec3, Quat, Vec3};
use stochastic_collision::bvh::{
    CollisionMesh, QueryWorkspace, closest_points, intersecting_pairs, intersects,
};
use stochastic_collision::geometry::{Pose, triangles_intersect, triangles_intersect_f32};
use stochastic_collision::mesh::{TriMesh, generate};

type Tri = [DVec3; 3];

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// One configuration: two triangles (possibly degenerate) and whether they share a point.
struct Case {
    name: &'static str,
    a: Tri,
    b: Tri,
    hit: bool,
}

fn hit(name: &'static str, a: Tri, b: Tri) -> Case {
    Case {
        name,
        a,
        b,
        hit: true,
    }
}

fn miss(name: &'static str, a: Tri, b: Tri) -> Case {
    Case {
        name,
        a,
        b,
        hit: false,
    }
}

fn lift(t: Tri, d: DVec3) -> Tri {
    t.map(|p| p + d)
}

/// The list, with "a hair" `h` (a power of two).
fn cases(h: f64) -> Vec<Case> {
    let a = [v(0., 0., 0.), v(4., 0., 0.), v(0., 4., 0.)];
    let up = v(0., 0., h);
    // Slivers of aspect ratio 16/h (and 8/h) in the plane z = 0.
    let (len, w) = (16.0, h);
    let sliver = [v(0., 0., 0.), v(len, 0., 0.), v(0., w, 0.)];
    let wide = [v(0., 0., 0.), v(len, 0., 0.), v(0., 2. * w, 0.)];
    // A sliver of aspect ratio 16/h standing in the plane y = y0, crossing z = 0 along
    // x ∈ [len/4, len/4 + w].
    let standing = |y0: f64| {
        [
            v(len / 4., y0, -len / 2.),
            v(len / 4., y0, len / 2.),
            v(len / 4. + w, y0, 0.),
        ]
    };
    let point = |p: DVec3| [p; 3];
    // The segment from `p` to `2q − p`, with `q` its middle corner (no halving: exact).
    let segment = |p: DVec3, q: DVec3| [p, q * 2.0 - p, q];
    vec![
        // Coplanar.
        hit(
            "coplanar overlapping",
            a,
            [v(1., 1., 0.), v(5., 1., 0.), v(1., 5., 0.)],
        ),
        hit(
            "coplanar touching at a corner",
            a,
            [v(2., 2., 0.), v(6., 2., 0.), v(6., 6., 0.)],
        ),
        miss(
            "coplanar disjoint by a hair",
            a,
            [v(2. + h, 2., 0.), v(6., 2., 0.), v(6., 6., 0.)],
        ),
        hit(
            "coplanar sharing an edge",
            a,
            [v(0., 0., 0.), v(4., 0., 0.), v(2., -2., 0.)],
        ),
        miss(
            "coplanar, edges parallel a hair apart",
            a,
            [v(0., -h, 0.), v(4., -h, 0.), v(2., -2., 0.)],
        ),
        hit(
            "coplanar, one inside the other",
            a,
            [v(1., 1., 0.), v(2., 1., 0.), v(1., 2., 0.)],
        ),
        hit(
            "coplanar, inside and touching the hypotenuse",
            a,
            [v(1., 1., 0.), v(2., 2., 0.), v(1., 2., 0.)],
        ),
        hit("identical", a, a),
        // Parallel planes.
        miss("parallel, a hair apart", a, lift(a, up)),
        miss(
            "parallel, overlapping in projection, a hair apart",
            a,
            [v(1., 1., -h), v(5., 1., -h), v(1., 5., -h)],
        ),
        // Vertex on the face.
        hit(
            "vertex on the face",
            a,
            [v(1., 1., 0.), v(1., 1., 2.), v(3., 0., 2.)],
        ),
        miss(
            "vertex a hair above the face",
            a,
            [v(1., 1., h), v(1., 1., 2.), v(3., 0., 2.)],
        ),
        hit(
            "vertex a hair below the face (piercing)",
            a,
            [v(1., 1., -h), v(1., 1., 2.), v(3., 0., 2.)],
        ),
        // Edges through the face.
        hit(
            "edge through the face interior",
            a,
            [v(1., 1., -1.), v(1., 1., 1.), v(9., 9., 0.)],
        ),
        hit(
            "slanted edge through the face interior",
            a,
            [v(1., 1., -1.), v(2., 1., 1.), v(-5., -5., 3.)],
        ),
        hit(
            "edge lying on the face",
            a,
            [v(1., 1., 0.), v(2., 1., 0.), v(1., 1., 3.)],
        ),
        // Perpendicular near misses.
        miss(
            "perpendicular, edge a hair above the face",
            a,
            [v(1., 0.5, h), v(1., 3., h), v(1., 1., 3.)],
        ),
        hit(
            "perpendicular, edge on the face",
            a,
            [v(1., 0.5, 0.), v(1., 3., 0.), v(1., 1., 3.)],
        ),
        miss(
            "perpendicular, a hair beyond the hypotenuse",
            a,
            [v(2. + h, 2., -1.), v(2. + h, 2., 1.), v(3. + h, 1., 0.)],
        ),
        hit(
            "perpendicular, through the hypotenuse",
            a,
            [v(2., 2., -1.), v(2., 2., 1.), v(3., 1., 0.)],
        ),
        miss(
            "perpendicular, edge crossing over an edge a hair above",
            a,
            [v(2., -1., h), v(2., 1., h), v(2., 0., 3.)],
        ),
        hit(
            "perpendicular, edge crossing an edge",
            a,
            [v(2., -1., 0.), v(2., 1., 0.), v(2., 0., 3.)],
        ),
        miss(
            "perpendicular, corner a hair short of an edge",
            a,
            [v(2., -h, 0.), v(2., -1., 1.), v(2., -1., -1.)],
        ),
        // Slivers of aspect ratio 16/h.
        hit("sliver through sliver", wide, standing(w)),
        miss("sliver past sliver", wide, standing(2. * w)),
        hit("sliver against its copy", sliver, sliver),
        miss("sliver a hair above its copy", sliver, lift(sliver, up)),
        hit(
            "sliver corner on sliver edge",
            sliver,
            [v(8., 0., 0.), v(8. + w, -w, len), v(8. - w, -w, len)],
        ),
        miss(
            "sliver corner a hair off sliver edge",
            sliver,
            [v(8., -h, 0.), v(8. + w, -w, len), v(8. - w, -w, len)],
        ),
        // Degenerate triangles: points and segments.
        hit("point on the face", a, point(v(1., 1., 0.))),
        miss("point a hair above the face", a, point(v(1., 1., h))),
        hit("point on a corner", a, point(v(4., 0., 0.))),
        miss("point a hair past a corner", a, point(v(4. + h, 0., 0.))),
        hit(
            "segment crossing the face",
            a,
            segment(v(1., 1., -1.), v(1., 1., 1.)),
        ),
        miss(
            "segment ending a hair above the face",
            a,
            segment(v(1., 1., h), v(1., 1., 2.)),
        ),
        miss(
            "segment a hair beyond the hypotenuse",
            a,
            segment(v(2. + h, 2., -1.), v(2. + h, 2., 1.)),
        ),
        hit(
            "segment along an edge",
            a,
            segment(v(1., 0., 0.), v(6., 0., 0.)),
        ),
        hit(
            "segments crossing",
            segment(v(0., 0., 0.), v(2., 2., 0.)),
            segment(v(0., 2., 0.), v(2., 0., 0.)),
        ),
        miss(
            "segments skew by a hair",
            segment(v(0., 0., 0.), v(2., 2., 0.)),
            segment(v(0., 2., h), v(2., 0., h)),
        ),
        hit("equal points", point(v(1., 2., 3.)), point(v(1., 2., 3.))),
        miss(
            "points a hair apart",
            point(v(1., 2., 3.)),
            point(v(1., 2., 3. + h)),
        ),
    ]
}

/// `p ↦ scale · p + offset`.
#[derive(Debug, Clone, Copy)]
struct Xf {
    name: &'static str,
    scale: f64,
    offset: DVec3,
}

/// The transforms. Scales are chosen so that the hair stays exact: 2^-13 and
/// `13·2^-17` (≈ 1.2e-4 and 0.99e-4, the latter's mantissa 4 bits), 2^20 and 10^6 (≈ 1e6, the
/// latter exactly, its mantissa 14 bits); offsets of 1e5 along the axes.
fn transforms() -> Vec<Xf> {
    let xf = |name, scale, offset| Xf {
        name,
        scale,
        offset,
    };
    vec![
        xf("identity", 1.0, DVec3::ZERO),
        xf("scaled by 2^-13", 2f64.powi(-13), DVec3::ZERO),
        xf("scaled by 13·2^-17", 13.0 * 2f64.powi(-17), DVec3::ZERO),
        xf("scaled by 2^20", 2f64.powi(20), DVec3::ZERO),
        xf("scaled by 1e6", 1e6, DVec3::ZERO),
        xf("moved 1e5", 1.0, v(1e5, 1e5, 1e5)),
        xf("moved 1e5 (mixed signs)", 1.0, v(-1e5, 1e5, -1e5)),
    ]
}

/// The `f32` image of `p` under `xf` after `shift`, or `None` when it would be rounded.
fn exact_f32(xf: &Xf, shift: DVec3, p: DVec3) -> Option<Vec3> {
    let q = (p + shift) * xf.scale + xf.offset;
    let f = q.as_vec3();
    (f.as_dvec3() == q && p + shift == (q - xf.offset) / xf.scale).then_some(f)
}

fn tri_f32(xf: &Xf, shift: DVec3, t: &Tri) -> Option<[Vec3; 3]> {
    Some([
        exact_f32(xf, shift, t[0])?,
        exact_f32(xf, shift, t[1])?,
        exact_f32(xf, shift, t[2])?,
    ])
}

/// The smallest hair `2^-k` (k ≤ 16) for which every case, alone at the origin's slot, is
/// exact in `f32` under `xf`.
fn hair_for(xf: &Xf) -> f64 {
    let exact = |cs: Vec<Case>| {
        cs.iter().all(|c| {
            tri_f32(xf, DVec3::ZERO, &c.a).is_some() && tri_f32(xf, DVec3::ZERO, &c.b).is_some()
        })
    };
    (0..=16)
        .rev()
        .map(|k| 2f64.powi(-k))
        .find(|&h| exact(cases(h)))
        .unwrap_or_else(|| panic!("{}: no exact hair", xf.name))
}

fn triangle_mesh(t: [Vec3; 3]) -> CollisionMesh {
    CollisionMesh::new(TriMesh::new(t.to_vec(), vec![[0, 1, 2]]).unwrap())
}

/// Both orders through the mesh API at `pose` (both meshes there): intersects,
/// intersecting_pairs, and closest_points (distance 0 exactly on a hit, positive on a miss).
fn check_mesh_api(name: &str, a: [Vec3; 3], b: [Vec3; 3], hit: bool, pose: &Pose) {
    let mut ws = QueryWorkspace::new();
    let (ma, mb) = (triangle_mesh(a), triangle_mesh(b));
    for (first, second, order) in [(&ma, &mb, "a,b"), (&mb, &ma, "b,a")] {
        let ctx = format!("{name} ({order}) at {pose:?}: {a:?} {b:?}");
        assert_eq!(triangles_intersect_f32(a, b), hit, "{ctx}: primitive");
        assert_eq!(intersects(first, pose, second, pose, &mut ws), hit, "{ctx}");
        let mut pairs = Vec::new();
        let n = intersecting_pairs(first, pose, second, pose, &mut ws, &mut pairs);
        assert_eq!(n, usize::from(hit), "{ctx}: pairs");
        let d = closest_points(first, pose, second, pose, f32::INFINITY, &mut ws).unwrap();
        assert!(d.distance.is_finite(), "{ctx}: {d:?}");
        if hit {
            assert_eq!(d.distance, 0.0, "{ctx}: {d:?}");
        } else {
            assert!(d.distance > 0.0, "{ctx}: {d:?}");
        }
    }
}

#[test]
fn every_case_is_exact_in_f32_at_the_origin_with_the_finest_hair() {
    let h = hair_for(&transforms()[0]);
    assert_eq!(h, 2f64.powi(-16));
    for c in cases(h) {
        assert_eq!(triangles_intersect(&c.a, &c.b), c.hit, "{}", c.name);
        assert_eq!(
            triangles_intersect(&c.b, &c.a),
            c.hit,
            "{} (swapped)",
            c.name
        );
    }
}

#[test]
fn hard_cases_through_the_mesh_api_both_orders_at_every_scale_and_offset() {
    // An identical non-trivial pose for both meshes: a half-turn about z (exact quaternion)
    // and a translation; the relative pose is exactly the identity.
    let half_turn = Pose::new(
        Vec3::new(3.0, -5.0, 0.5),
        Quat::from_xyzw(0.0, 0.0, 1.0, 0.0),
    );
    assert_eq!(half_turn.inverse_mul(&half_turn), Pose::IDENTITY);
    let mut checked = 0;
    for xf in transforms() {
        let h = hair_for(&xf);
        assert!(h <= 2f64.powi(-7), "{}: hair {h}", xf.name);
        for c in cases(h) {
            let a = tri_f32(&xf, DVec3::ZERO, &c.a).unwrap();
            let b = tri_f32(&xf, DVec3::ZERO, &c.b).unwrap();
            let name = format!("{} {} (hair {h})", c.name, xf.name);
            for pose in [Pose::IDENTITY, half_turn] {
                check_mesh_api(&name, a, b, c.hit, &pose);
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 2 * transforms().len() * cases(1.0).len());
}

#[test]
fn identical_meshes_at_identical_poses_collide() {
    let mut ws = QueryWorkspace::new();
    let meshes = [
        generate::icosphere(1.0, 2),
        generate::torus(1.0, 0.3, 24, 8),
        TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0], vec![[0, 1, 2]]).unwrap(),
        TriMesh::new(vec![Vec3::ONE; 3], vec![[0, 1, 2]]).unwrap(),
    ];
    let poses = [
        Pose::IDENTITY,
        Pose::from_translation(Vec3::splat(1e5)),
        Pose::new(Vec3::new(0.25, -7.0, 3.0), Quat::from_rotation_y(0.7)),
        Pose::new(Vec3::splat(-1e5), Quat::from_rotation_x(-2.0)),
    ];
    for (i, m) in meshes.into_iter().enumerate() {
        let mesh = CollisionMesh::new(m);
        let copy = mesh.clone();
        for pose in &poses {
            assert!(
                intersects(&mesh, pose, &copy, pose, &mut ws),
                "mesh {i} at {pose:?}"
            );
            let d = closest_points(&mesh, pose, &copy, pose, f32::INFINITY, &mut ws).unwrap();
            assert_eq!(d.distance, 0.0, "mesh {i} at {pose:?}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Through the `query` example.

/// Cases laid out for one invocation: case `i`'s first triangle at `P_i = (i·S, 0, 0)` in the
/// first mesh, its second triangle at `Q_i = (0, i·S, 0)` in the second mesh, and pose row `i`
/// translating the second mesh by `P_i − Q_i`. Under row `i` the other cases' second triangles
/// land at `P_i + (0, (j − i)·S, 0)`, at least `S − 2·extent` from every first triangle.
struct Batch {
    first: Vec<[Vec3; 3]>,
    second: Vec<[Vec3; 3]>,
    poses: Vec<Vec3>,
    expected: Vec<(String, bool)>,
}

/// Slot spacing: more than twice the largest coordinate of any case (16 for the slivers).
const SPACING: f64 = 64.0;

/// Greedily packs `cases` (in order `swap`ped or not) into batches whose every coordinate and
/// pose stays exact in `f32` under `xf`.
fn batches(xf: &Xf, cs: &[Case], swap: bool) -> Vec<Batch> {
    let place = |c: &Case, slot: usize| -> Option<([Vec3; 3], [Vec3; 3], Vec3)> {
        let (t1, t2) = if swap { (&c.b, &c.a) } else { (&c.a, &c.b) };
        let s = slot as f64 * SPACING;
        let (p, q) = (v(s, 0., 0.), v(0., s, 0.));
        let first = tri_f32(xf, p, t1)?;
        let second = tri_f32(xf, q, t2)?;
        let t = (p - q) * xf.scale;
        let tf = t.as_vec3();
        (tf.as_dvec3() == t).then_some((first, second, tf))
    };
    let mut out: Vec<Batch> = Vec::new();
    for c in cs {
        let placed = out.last().and_then(|b| place(c, b.first.len()));
        let (batch, placed) = match placed {
            Some(p) => (out.last_mut().unwrap(), p),
            None => {
                let p = place(c, 0).unwrap_or_else(|| panic!("{}: not exact", c.name));
                out.push(Batch {
                    first: Vec::new(),
                    second: Vec::new(),
                    poses: Vec::new(),
                    expected: Vec::new(),
                });
                (out.last_mut().unwrap(), p)
            }
        };
        batch.first.push(placed.0);
        batch.second.push(placed.1);
        batch.poses.push(placed.2);
        batch.expected.push((c.name.to_string(), c.hit));
    }
    out
}

fn soup(tris: &[[Vec3; 3]]) -> TriMesh {
    let positions = tris.iter().flatten().copied().collect();
    let triangles = (0..tris.len() as u32)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    TriMesh::new(positions, triangles).unwrap()
}

#[test]
fn hard_cases_through_the_query_example_both_orders_at_every_scale_and_offset() {
    let mut invocations = 0;
    let mut rows_checked = 0;
    for (x, xf) in transforms().iter().enumerate() {
        let h = hair_for(xf);
        let cs = cases(h);
        for swap in [false, true] {
            for (k, batch) in batches(xf, &cs, swap).iter().enumerate() {
                let tag = format!("hard_{x}_{swap}_{k}");
                let (pa, pb) = (
                    scratch(&format!("{tag}_a.obj")),
                    scratch(&format!("{tag}_b.obj")),
                );
                write_obj(&pa, &soup(&batch.first));
                write_obj(&pb, &soup(&batch.second));
                let mut csv = String::from("tx,ty,tz,qx,qy,qz,qw\n");
                for t in &batch.poses {
                    writeln!(csv, "{},{},{},0,0,0,1", t.x, t.y, t.z).unwrap();
                }
                let poses = scratch(&format!("{tag}_poses.csv"));
                std::fs::write(&poses, csv).unwrap();
                let rows = run_exact(&pa, &pb, &poses);
                invocations += 1;
                assert_eq!(rows.len(), batch.expected.len());
                for (row, (name, hit)) in rows.iter().zip(&batch.expected) {
                    let want = if *hit { "1" } else { "0" };
                    assert_eq!(
                        row[1], want,
                        "{name} {} swap={swap} (hair {h}): row {row:?}",
                        xf.name
                    );
                    rows_checked += 1;
                }
            }
        }
    }
    assert_eq!(rows_checked, 2 * transforms().len() * cases(1.0).len());
    eprintln!("{rows_checked} rows in {invocations} invocations");
}

#[test]
fn identical_meshes_at_the_identity_collide_through_the_query_example() {
    let path = scratch("identical_torus.obj");
    write_obj(&path, &generate::torus(1.0, 0.3, 24, 8));
    let poses = scratch("identical_poses.csv");
    std::fs::write(&poses, "tx,ty,tz,qx,qy,qz,qw\n0,0,0,0,0,0,1\n").unwrap();
    assert_eq!(run_exact(&path, &path, &poses)[0][1], "1");
}
