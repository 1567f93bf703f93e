//! Self-intersection of one mesh: the tree descended against itself.
use glam::{DVec3, Vec3A};

use super::collision_mesh::CollisionMesh;
use super::tree::BvhNode;
use super::workspace::{QueryWorkspace, TrianglePair, triangle_f64};
use crate::geometry::{closest_points_triangle_triangle, triangles_intersect};
use crate::mesh::{MeshError, SelfExclusion, adjacent};

/// All pairs of non-adjacent triangles of `mesh` that intersect or touch, appended to `out`
/// (each pair once, `a < b`); returns how many were appended.
///
/// Triangles sharing a vertex are adjacent and excluded (they touch by construction), on the
/// [welded](crate::mesh::TriMesh::welded) mesh: corners at the same position (an unwelded seam
/// or pole) count as one vertex ([`CollisionMesh::welded_triangles`]), so seams are not
/// reported.
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
    descend_crossing(mesh, ws, |pair| {
        out.push(pair);
        false
    });
    out.len() - before
}

/// Whether any two non-adjacent triangles of `mesh` intersect or touch (stops at the first).
pub fn self_intersects(mesh: &CollisionMesh, ws: &mut QueryWorkspace) -> bool {
    let mut hit = false;
    descend_crossing(mesh, ws, |_| {
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
/// vertex of the welded mesh, as there. A negative or NaN `thickness` counts as 0.
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
    let pos = mesh.mesh().positions();
    let h = if thickness > 0.0 { thickness } else { 0.0 };
    if h == 0.0 {
        let before = out.len();
        descend_crossing(mesh, ws, |pair| {
            out.push(SelfContact {
                pair,
                distance: 0.0,
            });
            false
        });
        return out.len() - before;
    }
    let before = out.len();
    let hd = h as f64;
    descend_self(
        mesh,
        ws,
        h,
        |_, _, a, b| within_thickness(&triangle_f64(a, pos), &triangle_f64(b, pos), hd),
        |pair, distance| {
            out.push(SelfContact { pair, distance });
            false
        },
    );
    out.len() - before
}

/// All pairs of triangles of `mesh` outside `exclusion` (pairs within its rings along the
/// surface are left out) that intersect or are at most `thickness` apart, appended to `out`
/// (each pair once, `a < b`); returns how many were appended.
///
/// The same pairs as [`self_contacts`] followed by dropping the excluded ones, faster: a pair
/// is excluded before any geometric test, and cheap separation tests (the triangles' boxes,
/// each triangle's plane, the directions across each edge within its plane, all with a margin
/// far above rounding) drop pairs that are clearly farther apart than `thickness` before the
/// exact distance decides the rest. This is the exact self-collision pass of a tracked
/// surface. A negative or NaN `thickness` counts as 0.
///
/// # Errors
/// [`MeshError::TopologyMismatch`] if `exclusion` was built for a mesh with other vertex or
/// triangle counts.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::bvh::self_contacts_excluding;
/// use stochastic_collision::mesh::{SelfExclusion, generate};
/// // A sheet folded onto itself: its two halves 0.05 apart.
/// let mut sheet = generate::cloth_grid(2.0, 1.0, 20, 10);
/// let folded: Vec<Vec3> = sheet
///     .positions()
///     .iter()
///     .map(|p| if p.x > 0.0 { Vec3::new(-p.x, 0.05, p.z) } else { *p })
///     .collect();
/// sheet.set_positions(&folded).unwrap();
/// let exclusion = SelfExclusion::new(&sheet, 2);
/// let mesh = CollisionMesh::new(sheet);
/// let mut out = Vec::new();
/// let n = self_contacts_excluding(&mesh, 0.06, &exclusion, &mut QueryWorkspace::new(), &mut out)
///     .unwrap();
/// assert!(n > 0 && out.iter().all(|c| c.distance <= 0.06));
/// ```
pub fn self_contacts_excluding(
    mesh: &CollisionMesh,
    thickness: f32,
    exclusion: &SelfExclusion,
    ws: &mut QueryWorkspace,
    out: &mut Vec<SelfContact>,
) -> Result<usize, MeshError> {
    let pos = mesh.mesh().positions();
    let size = (mesh.mesh().vertex_count(), mesh.mesh().triangle_count());
    if exclusion.mesh_size() != size {
        return Err(MeshError::TopologyMismatch {
            expected: exclusion.mesh_size(),
            got: size,
        });
    }
    let h = if thickness > 0.0 { thickness } else { 0.0 };
    let before = out.len();
    let hd = h as f64;
    descend_self(
        mesh,
        ws,
        h,
        |t, u, ta, tb| {
            // The exclusion first: one merge of two cached lists, cheaper than converting
            // and projecting the triangles, and decisive for most pairs that reach it.
            if exclusion.excludes(t, u) {
                return None;
            }
            let (a, b) = (triangle_f64(ta, pos), triangle_f64(tb, pos));
            if hd == 0.0 {
                intersect_test(a, b)
            } else {
                within_thickness(&a, &b, hd)
            }
        },
        |pair, distance| {
            out.push(SelfContact { pair, distance });
            false
        },
    );
    Ok(out.len() - before)
}

/// `Some(distance)` when triangles `a` and `b` are at most `h` apart: first separation filters
/// that only drop pairs whose distance exceeds `h` by far more than rounding, then the exact
/// distance.
#[inline]
pub(crate) fn within_thickness(a: &[DVec3; 3], b: &[DVec3; 3], h: f64) -> Option<f64> {
    let (lo_a, hi_a) = (a[0].min(a[1]).min(a[2]), a[0].max(a[1]).max(a[2]));
    let (lo_b, hi_b) = (b[0].min(b[1]).min(b[2]), b[0].max(b[1]).max(b[2]));
    // Rounding in the projections below is ~1e-16 of the extent; the margin is 1e-9 of it.
    let extent = hi_a.max(hi_b) - lo_a.min(lo_b);
    let slack = 1e-9 * extent.max_element();
    let (gap, na, nb) = (h + slack, normal(a), normal(b));
    // Each plane first (cheap, and decisive for layers apart), then the directions across the
    // edges (decisive for pieces of one plane).
    if separated_along_normal(a, b, na, gap)
        || separated_along_normal(b, a, nb, gap)
        || separated_across_edges(a, b, na, gap)
        || separated_across_edges(b, a, nb, gap)
    {
        return None;
    }
    let c = closest_points_triangle_triangle(a, b);
    (c.distance <= h).then_some(c.distance)
}

/// The (unnormalised) normal of triangle `t`.
#[inline]
fn normal(t: &[DVec3; 3]) -> DVec3 {
    (t[1] - t[0]).cross(t[2] - t[0])
}

/// Whether `b` lies farther than `gap` from the plane of `a` (normal `n`), all on one side.
#[inline]
fn separated_along_normal(a: &[DVec3; 3], b: &[DVec3; 3], n: DVec3, gap: f64) -> bool {
    n.length_squared() > 0.0 && separated_on_axis(a, b, n, gap)
}

/// Whether `b` lies farther than `gap` from `a` along one of the three directions in `a`'s
/// plane (normal `n`) across an edge (each a lower bound of the distance).
#[inline]
fn separated_across_edges(a: &[DVec3; 3], b: &[DVec3; 3], n: DVec3, gap: f64) -> bool {
    // A degenerate `a` (zero or NaN normal) has no in-plane directions to test.
    let usable = n.length_squared() > 0.0;
    usable && (0..3).any(|i| separated_on_axis(a, b, n.cross(a[(i + 1) % 3] - a[i]), gap))
}

/// Whether `a` and `b` are more than `gap` apart along the direction of `axis` (any length:
/// compared in squares, no square root). Projected relative to `a[0]`, so rounding scales
/// with the triangles' extent, not their coordinates.
#[inline]
fn separated_on_axis(a: &[DVec3; 3], b: &[DVec3; 3], axis: DVec3, gap: f64) -> bool {
    let o = a[0];
    let pa = [0.0, axis.dot(a[1] - o), axis.dot(a[2] - o)];
    let pb = [axis.dot(b[0] - o), axis.dot(b[1] - o), axis.dot(b[2] - o)];
    let (min_a, max_a) = (pa[0].min(pa[1]).min(pa[2]), pa[0].max(pa[1]).max(pa[2]));
    let (min_b, max_b) = (pb[0].min(pb[1]).min(pb[2]), pb[0].max(pb[1]).max(pb[2]));
    let d = (min_b - max_a).max(min_a - max_b);
    d > 0.0 && d * d > gap * gap * axis.length_squared()
}

/// [`descend_self`] for pairs that intersect or touch; `on_hit` returns `true` to stop.
fn descend_crossing(
    mesh: &CollisionMesh,
    ws: &mut QueryWorkspace,
    mut on_hit: impl FnMut(TrianglePair) -> bool,
) {
    let pos = mesh.mesh().positions();
    descend_self(
        mesh,
        ws,
        0.0,
        |_, _, a, b| intersect_test(triangle_f64(a, pos), triangle_f64(b, pos)),
        |pair, _| on_hit(pair),
    );
}

fn intersect_test(a: [DVec3; 3], b: [DVec3; 3]) -> Option<f64> {
    triangles_intersect(&a, &b).then_some(0.0)
}

/// Whether the boxes, the first grown by `margin`, overlap.
#[inline]
fn overlap(a: &BvhNode, b: &BvhNode, margin: f32) -> bool {
    let gap =
        (Vec3A::from(a.min) - Vec3A::from(b.max)).max(Vec3A::from(b.min) - Vec3A::from(a.max));
    !gap.cmpgt(Vec3A::splat(margin)).any()
}

/// The slots of a leaf's triangles in [`Bvh::leaf_triangles`](super::Bvh::leaf_triangles).
#[inline]
fn leaf_slots(leaf: &BvhNode) -> std::ops::Range<usize> {
    leaf.first as usize..(leaf.first + leaf.count) as usize
}

/// Descends node pairs `(i, j)` whose boxes are within `margin`; `pair_test` decides a pair of
/// non-adjacent triangles whose boxes are within `margin` (indices and corners; `Some(distance)`
/// for a hit); `on_hit` returns `true` to stop.
fn descend_self(
    mesh: &CollisionMesh,
    ws: &mut QueryWorkspace,
    margin: f32,
    mut pair_test: impl FnMut(u32, u32, [u32; 3], [u32; 3]) -> Option<f64>,
    mut on_hit: impl FnMut(TrianglePair, f64) -> bool,
) {
    let bvh = mesh.bvh();
    let nodes = bvh.nodes();
    let (pos, tris) = (mesh.mesh().positions(), mesh.mesh().triangles());
    let order = bvh.leaf_triangles();
    // Every triangle's box and corners, once, in the order the leaves list them: a leaf's
    // triangles sit side by side in memory, and most of a leaf pair's triangle pairs are
    // rejected on these alone.
    ws.triangle_boxes.clear();
    ws.leaf_corners.clear();
    ws.leaf_welded.clear();
    for &t in order {
        let corners = tris[t as usize];
        let [p, q, r] = corners.map(|v| Vec3A::from(pos[v as usize]));
        ws.triangle_boxes.push([p.min(q).min(r), p.max(q).max(r)]);
        ws.leaf_corners.push(corners);
    }
    // Adjacency on the welded mesh: triangles meeting along an unwelded seam touch by
    // construction too.
    if let Some(welded) = mesh.welded_triangles() {
        ws.leaf_welded
            .extend(order.iter().map(|&t| welded[t as usize]));
    }
    // Rejects only boxes farther apart than `margin` (an `f32` difference above a margin
    // enlarged far beyond its rounding), so the exact tests see every pair they would accept.
    let cull = Vec3A::splat(if margin > 0.0 {
        margin * (1.0 + 1e-5)
    } else {
        0.0
    });
    let (boxes, corners, welded) = (&ws.triangle_boxes, &ws.leaf_corners, &ws.leaf_welded);
    // `k`, `m`: slots in the leaf order.
    let mut test = |k: usize, m: usize| -> bool {
        let ([lo_a, hi_a], [lo_b, hi_b]) = (boxes[k], boxes[m]);
        if ((lo_a - hi_b).max(lo_b - hi_a)).cmpgt(cull).any() {
            return false;
        }
        let (mut ta, mut tb) = (corners[k], corners[m]);
        let touching = if welded.is_empty() {
            adjacent(ta, tb)
        } else {
            adjacent(welded[k], welded[m])
        };
        if touching {
            return false;
        }
        // The lower index first, so the test's rounding does not depend on the tree's layout.
        let (mut t, mut u) = (order[k], order[m]);
        if u < t {
            (t, u) = (u, t);
            (ta, tb) = (tb, ta);
        }
        if let Some(d) = pair_test(t, u, ta, tb) {
            return on_hit(TrianglePair { a: t, b: u }, d);
        }
        false
    };
    let stack = &mut ws.stack;
    stack.clear();
    stack.push((0, 0));
    let mut visited = 1u64;
    'descend: while let Some((i, j)) = stack.pop() {
        let (ni, nj) = (&nodes[i as usize], &nodes[j as usize]);
        if i == j {
            if ni.is_leaf() {
                let slots = leaf_slots(ni);
                for k in slots.clone() {
                    for m in k + 1..slots.end {
                        if test(k, m) {
                            break 'descend;
                        }
                    }
                }
            } else {
                let l = ni.left();
                stack.push((l, l));
                stack.push((l + 1, l + 1));
                visited += 1;
                if overlap(&nodes[l as usize], &nodes[l as usize + 1], margin) {
                    stack.push((l, l + 1));
                }
            }
            continue;
        }
        if ni.is_leaf() && nj.is_leaf() {
            for k in leaf_slots(ni) {
                for m in leaf_slots(nj) {
                    if test(k, m) {
                        break 'descend;
                    }
                }
            }
            continue;
        }
        if !ni.is_leaf() && !nj.is_leaf() {
            // Both split at once: four child pairs from two cache lines.
            let (li, lj) = (ni.left(), nj.left());
            for c in [li, li + 1] {
                let nc = &nodes[c as usize];
                for d in [lj, lj + 1] {
                    visited += 1;
                    if overlap(nc, &nodes[d as usize], margin) {
                        stack.push((c, d));
                    }
                }
            }
            continue;
        }
        let split_i = !ni.is_leaf();
        let (keep, split) = if split_i { (j, ni) } else { (i, nj) };
        let l = split.left();
        for c in [l, l + 1] {
            visited += 1;
            let other = &nodes[keep as usize];
            if overlap(&nodes[c as usize], other, margin) {
                stack.push(if split_i { (c, keep) } else { (keep, c) });
            }
        }
    }
    ws.node_pairs_visited = visited;
}
