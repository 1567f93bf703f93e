//! Exact intersection between two meshes: simultaneous descent of both trees.
use std::ops::ControlFlow;

use super::box_test::{RelativeFrame, node_size};
use super::collision_mesh::CollisionMesh;
use super::solid::contained_in;
use super::workspace::{QueryWorkspace, TrianglePair, triangle_f64};
use crate::geometry::{Pose, triangles_intersect};

/// Options of [`intersects_with`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ExactOptions {
    /// Also count a mesh entirely inside the other as colliding.
    ///
    /// Surfaces are what collide (as in parry), so without this a small mesh floating inside a
    /// big closed one does not collide. With it, when no surfaces touch, one vertex of every
    /// connected component of each mesh is tested for containment in the other mesh, which only
    /// has an inside if it is closed ([`CollisionMesh::is_closed`]): an open container never
    /// contains anything. Costs one ray cast per component, only when surfaces are apart.
    pub solid: bool,
}

/// The answer of [`intersects_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ExactOutcome {
    /// Whether the meshes collide.
    pub collides: bool,
    /// The first intersecting triangle pair found (`None` if the surfaces do not touch).
    pub witness: Option<TrianglePair>,
    /// Whether the collision is a containment found by [`ExactOptions::solid`].
    pub contained: bool,
    /// Node pairs whose boxes were tested.
    pub node_pairs_visited: u64,
}

/// Whether the surfaces of `a` at `pose_a` and `b` at `pose_b` touch or intersect: exact, stops
/// at the first intersecting triangle pair. A pose that is not [finite](Pose::is_finite) places
/// its mesh nowhere: `false` (and likewise no pairs, no containment for the other queries here).
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// let ball = CollisionMesh::new(generate::icosphere(1.0, 2));
/// let mut ws = QueryWorkspace::new();
/// let near = Pose::from_translation(Vec3::new(1.9, 0.0, 0.0));
/// let far = Pose::from_translation(Vec3::new(2.1, 0.0, 0.0));
/// assert!(intersects(&ball, &Pose::IDENTITY, &ball, &near, &mut ws));
/// assert!(!intersects(&ball, &Pose::IDENTITY, &ball, &far, &mut ws));
/// ```
pub fn intersects(
    a: &CollisionMesh,
    pose_a: &Pose,
    b: &CollisionMesh,
    pose_b: &Pose,
    ws: &mut QueryWorkspace,
) -> bool {
    intersects_with(a, pose_a, b, pose_b, &ExactOptions::default(), ws).collides
}

/// [`intersects`] with options, a witness triangle pair and statistics.
pub fn intersects_with(
    a: &CollisionMesh,
    pose_a: &Pose,
    b: &CollisionMesh,
    pose_b: &Pose,
    options: &ExactOptions,
    ws: &mut QueryWorkspace,
) -> ExactOutcome {
    let mut witness = None;
    descend(a, pose_a, b, pose_b, ws, |pair| {
        witness = Some(pair);
        ControlFlow::Break(())
    });
    let rel = pose_a.inverse_mul(pose_b);
    let contained = witness.is_none()
        && options.solid
        && rel.is_finite()
        && (contained_in(b, a, &rel.to_f64()) || contained_in(a, b, &rel.to_f64().inverse()));
    ExactOutcome {
        collides: witness.is_some() || contained,
        witness,
        contained,
        node_pairs_visited: ws.node_pairs_visited,
    }
}

/// Whether the root boxes of `a` and `b` overlap at these poses (oriented-box test, touching
/// counts): the cheapest necessary condition for a collision, and the papers' criterion for
/// which queries count in an error rate.
pub fn root_boxes_overlap(
    a: &CollisionMesh,
    pose_a: &Pose,
    b: &CollisionMesh,
    pose_b: &Pose,
) -> bool {
    let rel = pose_a.inverse_mul(pose_b);
    rel.is_finite()
        && RelativeFrame::new(&rel, a.bvh(), b.bvh())
            .overlap(&a.bvh().nodes()[0], &b.bvh().nodes()[0])
}

/// Whether triangle `pair.a` of `a` and triangle `pair.b` of `b` intersect (or touch) at these
/// poses, decided exactly as [`intersects`] decides it for that pair (the same relative pose
/// and arithmetic): `true` proves that the meshes collide, in a few hundred nanoseconds. A pair
/// naming a triangle the mesh does not have, or a pose that is not finite, is `false`.
pub fn triangle_pair_intersects(
    a: &CollisionMesh,
    pose_a: &Pose,
    b: &CollisionMesh,
    pose_b: &Pose,
    pair: TrianglePair,
) -> bool {
    let rel = pose_a.inverse_mul(pose_b);
    let (ma, mb) = (a.mesh(), b.mesh());
    let (Some(&ta), Some(&tb)) = (
        ma.triangles().get(pair.a as usize),
        mb.triangles().get(pair.b as usize),
    ) else {
        return false;
    };
    if !rel.is_finite() {
        return false;
    }
    let rel64 = rel.to_f64();
    let tri_a = triangle_f64(ta, ma.positions());
    let tri_b = tb.map(|i| rel64.transform_point(mb.positions()[i as usize]));
    triangles_intersect(&tri_a, &tri_b)
}

/// All intersecting (or touching) triangle pairs of `a` and `b`, appended to `out` in
/// traversal order; returns how many were appended.
pub fn intersecting_pairs(
    a: &CollisionMesh,
    pose_a: &Pose,
    b: &CollisionMesh,
    pose_b: &Pose,
    ws: &mut QueryWorkspace,
    out: &mut Vec<TrianglePair>,
) -> usize {
    let before = out.len();
    descend(a, pose_a, b, pose_b, ws, |pair| {
        out.push(pair);
        ControlFlow::Continue(())
    });
    out.len() - before
}

/// Descends both trees, calling `on_hit` for every intersecting triangle pair until it breaks.
fn descend(
    a: &CollisionMesh,
    pose_a: &Pose,
    b: &CollisionMesh,
    pose_b: &Pose,
    ws: &mut QueryWorkspace,
    on_hit: impl FnMut(TrianglePair) -> ControlFlow<()>,
) {
    descend_from(a, b, &pose_a.inverse_mul(pose_b), (0, 0), ws, on_hit);
}

/// Whether the subtree of node `node_a` of `a` and that of `node_b` of `b` contain an
/// intersecting triangle pair, `rel` placing `b` in `a`'s frame (the ground truth for one
/// node pair of a probabilistic traversal).
pub(crate) fn subtrees_intersect(
    a: &CollisionMesh,
    b: &CollisionMesh,
    rel: &Pose,
    node_a: u32,
    node_b: u32,
    ws: &mut QueryWorkspace,
) -> bool {
    let mut hit = false;
    descend_from(a, b, rel, (node_a, node_b), ws, |_| {
        hit = true;
        ControlFlow::Break(())
    });
    hit
}

/// [`descend`] from the node pair `start`, with `rel` placing `b` in `a`'s frame.
fn descend_from(
    a: &CollisionMesh,
    b: &CollisionMesh,
    rel: &Pose,
    start: (u32, u32),
    ws: &mut QueryWorkspace,
    mut on_hit: impl FnMut(TrianglePair) -> ControlFlow<()>,
) {
    let rel = *rel;
    if !rel.is_finite() {
        ws.node_pairs_visited = 0;
        return; // a pose that is not finite places its mesh nowhere
    }
    let (ta, tb) = (a.bvh(), b.bvh());
    let frame = RelativeFrame::new(&rel, ta, tb);
    let rel64 = rel.to_f64();
    let (mesh_a, mesh_b) = (a.mesh(), b.mesh());
    let (pos_a, pos_b) = (mesh_a.positions(), mesh_b.positions());
    let (tris_a, tris_b) = (mesh_a.triangles(), mesh_b.triangles());
    let (na, nb) = (ta.nodes(), tb.nodes());
    ws.cache.begin(pos_b.len());
    ws.stack.clear();
    ws.node_pairs_visited = 1;
    if !frame.overlap(&na[start.0 as usize], &nb[start.1 as usize]) {
        return;
    }
    ws.stack.push(start);
    while let Some((ia, ib)) = ws.stack.pop() {
        let (node_a, node_b) = (&na[ia as usize], &nb[ib as usize]);
        if node_a.is_leaf() && node_b.is_leaf() {
            for &t in ta.triangles_of(node_a) {
                let tri_a = triangle_f64(tris_a[t as usize], pos_a);
                for &u in tb.triangles_of(node_b) {
                    let tri_b = ws.cache.triangle(tris_b[u as usize], pos_b, &rel64);
                    if triangles_intersect(&tri_a, &tri_b)
                        && on_hit(TrianglePair { a: t, b: u }).is_break()
                    {
                        return;
                    }
                }
            }
            continue;
        }
        let split_a =
            !node_a.is_leaf() && (node_b.is_leaf() || node_size(node_a) >= node_size(node_b));
        if split_a {
            let l = node_a.left();
            for c in [l + 1, l] {
                ws.node_pairs_visited += 1;
                if frame.overlap(&na[c as usize], node_b) {
                    ws.stack.push((c, ib));
                }
            }
        } else {
            let l = node_b.left();
            for c in [l + 1, l] {
                ws.node_pairs_visited += 1;
                if frame.overlap(node_a, &nb[c as usize]) {
                    ws.stack.push((ia, c));
                }
            }
        }
    }
}
