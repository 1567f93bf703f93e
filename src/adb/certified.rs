//! The exact mesh–mesh test with the interpenetration certificate as a pre-pass: the exact
//! query's answer, found without a traversal where the certificate settles it.
use super::interior::{InteriorMap, PairCrossing, PairLookup};
use super::tree::AdbTree;
use crate::bvh::{QueryWorkspace, intersects};
use crate::geometry::Pose;

/// Whether the surfaces of two meshes intersect: always the answer of the exact query
/// [`intersects`] on the trees' meshes, found first by the interpenetration certificate
/// ([`InteriorMap::look_up_pair`]) where it can be trusted, then by the exact traversal.
///
/// The certificate is trusted only when the map its sample was found in is
/// [exact](InteriorMap::is_exact) (the mesh is closed: every edge used by an even number of
/// triangles); a crossing found in an open mesh's map, a pose it does not settle, trees built
/// without interior maps, and poses that are not finite all go to [`intersects`] (two open
/// meshes skip the certificate's lookups altogether). So the answer is the exact query's
/// (`tests/adb_exact.rs`); only the time differs, most on deep overlaps, which the
/// certificate settles with a few lookups. `ws` counts the node pairs the traversal visited
/// ([`QueryWorkspace::node_pairs_visited`]): 0 when the certificate answered.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::adb::certified_intersects;
/// use stochastic_collision::bvh::intersects;
/// let ball = AdbTree::new(CollisionMesh::new(generate::icosphere(1.0, 3)));
/// let mut ws = QueryWorkspace::new();
/// for x in [0.5, 1.2, 1.99, 2.5] {
///     let pose = Pose::from_translation(Vec3::new(x, 0.0, 0.0));
///     let exact = intersects(ball.collision_mesh(), &Pose::IDENTITY, ball.collision_mesh(), &pose, &mut ws);
///     assert_eq!(certified_intersects(&ball, &Pose::IDENTITY, &ball, &pose, &mut ws), exact);
/// }
/// ```
pub fn certified_intersects(
    a: &AdbTree,
    pose_a: &Pose,
    b: &AdbTree,
    pose_b: &Pose,
    ws: &mut QueryWorkspace,
) -> bool {
    if pose_a.is_finite()
        && pose_b.is_finite()
        && let (Some(map_a), Some(map_b)) = (a.interior(), b.interior())
        && (map_a.is_exact() || map_b.is_exact())
        && exact_crossing(map_a, map_b, &pose_a.inverse_mul(pose_b))
    {
        ws.node_pairs_visited = 0;
        return true;
    }
    intersects(a.collision_mesh(), pose_a, b.collision_mesh(), pose_b, ws)
}

/// Whether the certificate finds a crossing in a map that is exact (`rel` taking the second
/// mesh's frame to the first's). A sample of one mesh inside the other, with a sample of the
/// same connected surface outside, both classified by the other mesh's map: that map decides
/// whether the crossing is certain.
fn exact_crossing(map_a: &InteriorMap, map_b: &InteriorMap, rel: &Pose) -> bool {
    match InteriorMap::look_up_pair(map_a, map_b, rel) {
        PairLookup::Crossing(PairCrossing::SecondInFirst(_)) => map_a.is_exact(),
        PairLookup::Crossing(PairCrossing::FirstInSecond(_)) => map_b.is_exact(),
        PairLookup::Apart | PairLookup::Undecided => false,
    }
}
