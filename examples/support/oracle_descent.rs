//! A bound on what any probability-guided ordering can gain on a colliding pose: the node pairs
//! an *oracle descent* visits before its first intersecting triangle pair. The descent runs as
//! the exact query does (from the root pair, split the larger node, look at both child pairs),
//! but knows the answer: it always steps into a child pair whose subtrees truly hold an
//! intersecting triangle pair, so it never backtracks. A traversal that answers "collision"
//! from a triangle test (the ADB default, with exact leaves) must at least descend to one leaf
//! pair, so it cannot visit fewer node pairs than this unless it looks at fewer children per
//! step. Used by the `accuracy_vs_time` report.
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, TrianglePair, intersecting_pairs};
use stochastic_collision::geometry::Pose;

/// Which triangles lie under each node of a mesh's tree: each node covers one range of
/// [`Bvh::leaf_triangles`](stochastic_collision::bvh::Bvh::leaf_triangles) slots.
pub struct SubtreeRanges {
    /// Per node, its half-open range of leaf-triangle slots.
    range: Vec<(u32, u32)>,
    /// Per triangle, its slot.
    slot: Vec<u32>,
}

impl SubtreeRanges {
    /// The ranges of `mesh`'s tree.
    pub fn new(mesh: &CollisionMesh) -> Self {
        let nodes = mesh.bvh().nodes();
        let mut range = vec![(0, 0); nodes.len()];
        // Children come after their parent: a reverse sweep sees them first.
        for i in (0..nodes.len()).rev() {
            let n = &nodes[i];
            range[i] = if n.is_leaf() {
                (n.first, n.first + n.count)
            } else {
                let (l, r) = (range[n.left() as usize], range[n.left() as usize + 1]);
                (l.0.min(r.0), l.1.max(r.1))
            };
        }
        let mut slot = vec![0; mesh.mesh().triangle_count()];
        for (s, &t) in mesh.bvh().leaf_triangles().iter().enumerate() {
            slot[t as usize] = s as u32;
        }
        Self { range, slot }
    }

    fn covers(&self, node: u32, triangle: u32) -> bool {
        let (lo, hi) = self.range[node as usize];
        (lo..hi).contains(&self.slot[triangle as usize])
    }
}

/// The node pairs the oracle descent visits for `b` at `pose` against `a` at the identity,
/// counted as the exact query counts them (the root pair, then both child pairs of each split);
/// `None` when the meshes do not intersect. `hits` is scratch memory.
pub fn oracle_descent_pairs(
    (a, ranges_a): (&CollisionMesh, &SubtreeRanges),
    (b, ranges_b): (&CollisionMesh, &SubtreeRanges),
    pose: &Pose,
    ws: &mut QueryWorkspace,
    hits: &mut Vec<TrianglePair>,
) -> Option<u64> {
    hits.clear();
    if intersecting_pairs(a, &Pose::IDENTITY, b, pose, ws, hits) == 0 {
        return None;
    }
    let (na, nb) = (a.bvh().nodes(), b.bvh().nodes());
    let holds_hit = |ia: u32, ib: u32| {
        hits.iter()
            .any(|h| ranges_a.covers(ia, h.a) && ranges_b.covers(ib, h.b))
    };
    // The exact query's rule: split the node whose box has the larger summed side lengths.
    let size = |n: &stochastic_collision::bvh::BvhNode| (n.max - n.min).element_sum();
    let (mut ia, mut ib, mut visited) = (0u32, 0u32, 1u64);
    loop {
        let (x, y) = (&na[ia as usize], &nb[ib as usize]);
        if x.is_leaf() && y.is_leaf() {
            return Some(visited);
        }
        visited += 2;
        let children = if !x.is_leaf() && (y.is_leaf() || size(x) >= size(y)) {
            [(x.left(), ib), (x.left() + 1, ib)]
        } else {
            [(ia, y.left()), (ia, y.left() + 1)]
        };
        // The parent pair holds an intersecting triangle pair, so one of its children does.
        (ia, ib) = children
            .into_iter()
            .find(|&(ca, cb)| holds_hit(ca, cb))
            .expect("a pair holding a hit has a child pair holding it");
    }
}
