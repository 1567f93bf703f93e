//! The fastest exact mesh–mesh test of the crate: the exact answer from ADB-trees, with the
//! interpenetration certificate, the nodes' slabs and the straddle order doing what they can
//! without ever deciding from an estimate.
use std::sync::LazyLock;

use super::traverse::{AdbQuery, AdbWorkspace, adb_intersects};
use super::tree::AdbTree;
use crate::geometry::Pose;

/// [`AdbQuery::exact`], made once (its estimator is never asked: an exact query settles
/// every answer without one).
static EXACT: LazyLock<AdbQuery> = LazyLock::new(AdbQuery::exact);

/// Whether the surfaces of two meshes intersect: always the answer of the exact query
/// [`crate::bvh::intersects`] on the trees' meshes, found by [`adb_intersects`] with
/// [`AdbQuery::exact`].
///
/// What makes it faster than [`crate::bvh::intersects`] and
/// [`certified_intersects`](super::certified_intersects), and why each step is exact: the interpenetration
/// certificate first, trusted only in an [exact](super::InteriorMap::is_exact) map (a closed
/// mesh; two open meshes skip its lookups); node pairs culled by their boxes and by the slab
/// each node's triangles lie in along their mean normal (both conservative); children
/// visited depth first, those that straddle each other's surface most squarely first, so a
/// crossing is found after few node pairs; every leaf pair tested exactly; no estimate made.
/// A "no" comes only from an emptied queue, a "yes" only from a crossing triangle pair or an
/// exact certificate. `tests/adb_exact.rs` checks it against [`crate::bvh::intersects`] on
/// closed, open, nested and grid-aligned meshes at random and touching poses.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::adb::exact_intersects;
/// use stochastic_collision::bvh::intersects;
/// let ball = AdbTree::new(CollisionMesh::new(generate::icosphere(1.0, 3)));
/// let (mut adb_ws, mut ws) = (AdbWorkspace::new(), QueryWorkspace::new());
/// for x in [0.5, 1.2, 1.99, 2.5] {
///     let pose = Pose::from_translation(Vec3::new(x, 0.0, 0.0));
///     let exact = intersects(ball.collision_mesh(), &Pose::IDENTITY, ball.collision_mesh(), &pose, &mut ws);
///     assert_eq!(exact_intersects(&ball, &Pose::IDENTITY, &ball, &pose, &mut adb_ws), exact);
/// }
/// ```
pub fn exact_intersects(
    a: &AdbTree,
    pose_a: &Pose,
    b: &AdbTree,
    pose_b: &Pose,
    ws: &mut AdbWorkspace,
) -> bool {
    adb_intersects(a, pose_a, b, pose_b, &EXACT, ws).collides
}
