//! Self-intersection of one mesh: the tree descended against itself.
use glam::DVec3;

use super::collision_mesh::CollisionMesh;
use super::tree::BvhNode;
use super::workspace::{QueryWorkspace, TrianglePair, triangle_f64};
use crate::geometry::{closest_points_triangle_triangle, triangles_intersect};

/// All pairs of non-adjacent triangles of `mesh` that intersect or touch, appended to `out`
/// (each pair once, `a < b`); returns how many were appended.
///
/// Triangles sharing a vertex index are adjacent and excluded (they touch by construction).
/// Triangles that merely have corners at the same position (unwelded seams) are not adjacent,
/// so an unwelded mesh reports its seams.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::bvh::self_intersections;
/// let ball = CollisionMesh::new(generate::icosphere(1.0, 2));
/// let mut pairs = Vec::new();
/// assert_eq!(self_intersections(&ball, &mut QueryWorkspace::new(), &mut pairs), 0);
/// ```
pub fn self_intersections(
    mesh: &CollisionMesh,
    ws: &mut QueryWorkspace,
    out: &mut Vec<TrianglePair>,
) -> usize {
    let before = out.len();
    descend_self(mesh, ws, 0.0, intersect_test, |pair, _| {
        out.push(pair);
        false
    });
    out.len() - before
}

/// Whether any two non-adjacent triangles of `mesh` intersect or touch (stops at the first).
pub fn self_intersects(mesh: &CollisionMesh, ws: &mut QueryWorkspace) -> bool {
    let mut hit = false;
    descend_self(mesh, ws, 0.0, intersect_test, |_, _| {
        hit = true;
        true
    });
    hit
}

/// A pair of non-adjacent triangles of one mesh closer than a thickness, with their distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfContact {
    /// The two triangles, `a < b`.
    pub pair: TrianglePair,
    /// Their distance (0 when they intersect).
    pub distance: f64,
}

/// All pairs of non-adjacent triangles of `mesh` that intersect or are at most `thickness`
/// apart, appended to `out` (each pair once, `a < b`); returns how many were appended.
///
/// This is the exact self-collision pass of a surface with a thickness (cloth, tissue): with
/// `thickness == 0` it finds the same pairs as [`self_intersections`]. Adjacency is by shared
/// vertex index, as there. A negative or NaN `thickness` counts as 0.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::bvh::self_contacts;
/// // Two parallel unit squares 0.05 apart, in one mesh.
/// let sheet = TriMesh::new(
///     vec![
///         Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0),
///         Vec3::new(0.0, 0.05, 0.0), Vec3::new(1.0, 0.05, 0.0), Vec3::new(0.0, 0.05, 1.0),
///     ],
///     vec![[0, 1, 2], [3, 4, 5]],
/// ).unwrap();
/// let mesh = CollisionMesh::new(sheet);
/// let mut ws = QueryWorkspace::new();
/// let mut out = Vec::new();
/// assert_eq!(self_contacts(&mesh, 0.01, &mut ws, &mut out), 0);
/// assert_eq!(self_contacts(&mesh, 0.1, &mut ws, &mut out), 1);
/// assert!((out[0].distance - 0.05).abs() < 1e-6);
/// ```
pub fn self_contacts(
    mesh: &CollisionMesh,
    thickness: f32,
    ws: &mut QueryWorkspace,
    out: &mut Vec<SelfContact>,
) -> usize {
    let h = if thickness > 0.0 { thickness } else { 0.0 };
    if h == 0.0 {
        let before = out.len();
        descend_self(mesh, ws, 0.0, intersect_test, |pair, _| {
            out.push(SelfContact {
                pair,
                distance: 0.0,
            });
            false
        });
        return out.len() - before;
    }
    let before = out.len();
    let test = |a: [DVec3; 3], b: [DVec3; 3]| -> Option<f64> {
        let (mut lo_a, mut hi_a) = (a[0], a[0]);
        let (mut lo_b, mut hi_b) = (b[0], b[0]);
        for k in 1..3 {
            (lo_a, hi_a) = (lo_a.min(a[k]), hi_a.max(a[k]));
            (lo_b, hi_b) = (lo_b.min(b[k]), hi_b.max(b[k]));
        }
        let hd = h as f64;
        if (lo_a - hi_b).max_element() > hd || (lo_b - hi_a).max_element() > hd {
            return None;
        }
        let c = closest_points_triangle_triangle(&a, &b);
        (c.distance <= hd).then_some(c.distance)
    };
    descend_self(mesh, ws, h, test, |pair, distance| {
        out.push(SelfContact { pair, distance });
        false
    });
    out.len() - before
}

fn intersect_test(a: [DVec3; 3], b: [DVec3; 3]) -> Option<f64> {
    triangles_intersect(&a, &b).then_some(0.0)
}

/// Whether the boxes, the first grown by `margin`, overlap.
fn overlap(a: &BvhNode, b: &BvhNode, margin: f32) -> bool {
    (a.min - margin).cmple(b.max).all() && b.min.cmple(a.max + margin).all()
}

/// Descends node pairs `(i, j)` whose boxes are within `margin`; `pair_test` decides a pair of
/// non-adjacent triangles (`Some(distance)` for a hit); `on_hit` returns `true` to stop.
fn descend_self(
    mesh: &CollisionMesh,
    ws: &mut QueryWorkspace,
    margin: f32,
    mut pair_test: impl FnMut([DVec3; 3], [DVec3; 3]) -> Option<f64>,
    mut on_hit: impl FnMut(TrianglePair, f64) -> bool,
) {
    let bvh = mesh.bvh();
    let nodes = bvh.nodes();
    let (pos, tris) = (mesh.mesh().positions(), mesh.mesh().triangles());
    let mut test = |t: u32, u: u32| -> bool {
        let (ta, tb) = (tris[t as usize], tris[u as usize]);
        if ta.iter().any(|v| tb.contains(v)) {
            return false;
        }
        if let Some(d) = pair_test(triangle_f64(ta, pos), triangle_f64(tb, pos)) {
            return on_hit(
                TrianglePair {
                    a: t.min(u),
                    b: t.max(u),
                },
                d,
            );
        }
        false
    };
    ws.stack.clear();
    ws.stack.push((0, 0));
    ws.node_pairs_visited = 1;
    while let Some((i, j)) = ws.stack.pop() {
        let (ni, nj) = (&nodes[i as usize], &nodes[j as usize]);
        if i == j {
            if ni.is_leaf() {
                let ts = bvh.triangles_of(ni);
                for (k, &t) in ts.iter().enumerate() {
                    for &u in &ts[k + 1..] {
                        if test(t, u) {
                            return;
                        }
                    }
                }
            } else {
                let l = ni.left();
                ws.stack.push((l, l));
                ws.stack.push((l + 1, l + 1));
                ws.node_pairs_visited += 1;
                if overlap(&nodes[l as usize], &nodes[l as usize + 1], margin) {
                    ws.stack.push((l, l + 1));
                }
            }
            continue;
        }
        if ni.is_leaf() && nj.is_leaf() {
            for &t in bvh.triangles_of(ni) {
                for &u in bvh.triangles_of(nj) {
                    if test(t, u) {
                        return;
                    }
                }
            }
            continue;
        }
        let split_i = !ni.is_leaf()
            && (nj.is_leaf() || (ni.max - ni.min).element_sum() >= (nj.max - nj.min).element_sum());
        let (keep, split) = if split_i { (j, ni) } else { (i, nj) };
        let l = split.left();
        for c in [l, l + 1] {
            ws.node_pairs_visited += 1;
            let other = &nodes[keep as usize];
            if overlap(&nodes[c as usize], other, margin) {
                ws.stack.push(if split_i { (c, keep) } else { (keep, c) });
            }
        }
    }
}
