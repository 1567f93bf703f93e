//! A bound on what any order of a traversal can gain on a colliding pose: the node pairs an
//! *oracle descent* visits before it tests its first intersecting triangle pair. The oracle
//! knows the answer and goes straight down to the intersecting leaf pair closest to the roots,
//! looking at every child pair of each pair it expands, as the exact query and the ADB
//! traversal do.
//!
//! Reaching a leaf pair at depths `d_a`, `d_b` (the roots at 0) that way visits `1 + 2(d_a +
//! d_b)` node pairs, whichever node is split first: the root pair, then two child pairs for
//! each level one tree goes down (the exact query splits one node at a time and looks at its
//! 2 children; the ADB traversal splits both while both are inner nodes and looks at 4). So no
//! traversal that answers "collision" from a triangle test, as the ADB default does with exact
//! leaves, visits fewer node pairs, whatever its order. Used by the `accuracy_vs_time` report.
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, TrianglePair, intersecting_pairs};
use stochastic_collision::geometry::Pose;

/// The depth of the leaf that holds each triangle of a mesh (the root at depth 0).
pub struct LeafDepths(Vec<u32>);

impl LeafDepths {
    /// The leaf depths of `mesh`'s tree.
    pub fn new(mesh: &CollisionMesh) -> Self {
        let bvh = mesh.bvh();
        let nodes = bvh.nodes();
        let mut node_depth = vec![0u32; nodes.len()];
        let mut by_triangle = vec![0u32; mesh.mesh().triangle_count()];
        // Parents come before their children.
        for (i, n) in nodes.iter().enumerate() {
            if n.is_leaf() {
                for &t in bvh.triangles_of(n) {
                    by_triangle[t as usize] = node_depth[i];
                }
            } else {
                node_depth[n.left() as usize] = node_depth[i] + 1;
                node_depth[n.left() as usize + 1] = node_depth[i] + 1;
            }
        }
        Self(by_triangle)
    }

    fn of(&self, triangle: u32) -> u64 {
        u64::from(self.0[triangle as usize])
    }
}

/// The node pairs the oracle descent visits for `b` at `pose` against `a` at the identity,
/// counted as the exact query and the ADB traversal count them; `None` when the meshes do not
/// intersect. `hits` is scratch memory.
pub fn oracle_descent_pairs(
    (a, depths_a): (&CollisionMesh, &LeafDepths),
    (b, depths_b): (&CollisionMesh, &LeafDepths),
    pose: &Pose,
    ws: &mut QueryWorkspace,
    hits: &mut Vec<TrianglePair>,
) -> Option<u64> {
    hits.clear();
    intersecting_pairs(a, &Pose::IDENTITY, b, pose, ws, hits);
    hits.iter()
        .map(|h| 1 + 2 * (depths_a.of(h.a) + depths_b.of(h.b)))
        .min()
}
