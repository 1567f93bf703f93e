//! The oracle descent of the `accuracy_vs_time` report (the bound on what a better order can
//! gain): it answers exactly when the meshes intersect, it walks one root-to-leaf path of each
//! tree, and neither the exact query nor the ADB traversal, which must test an intersecting
//! triangle pair to answer "collision" with `p_min = 1` (without its interpenetration
//! certificate), visits fewer node pairs.
#[path = "../examples/support/oracle_descent.rs"]
mod oracle_descent;

use oracle_descent::{LeafDepths, oracle_descent_pairs};
use stochastic_collision::adb::{AdbQuery, AdbTree, AdbWorkspace, Order, adb_intersects};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, intersects};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::generate;
use stochastic_collision::poses::near_contact_poses;

/// The shallowest and the deepest leaf of a mesh's tree (the root at depth 0).
fn leaf_depth_range(mesh: &CollisionMesh) -> (u64, u64) {
    let nodes = mesh.bvh().nodes();
    let mut depth = vec![0u64; nodes.len()];
    let (mut lo, mut hi) = (u64::MAX, 0);
    // Parents come before their children.
    for (i, n) in nodes.iter().enumerate() {
        if n.is_leaf() {
            lo = lo.min(depth[i]);
            hi = hi.max(depth[i]);
        } else {
            depth[n.left() as usize] = depth[i] + 1;
            depth[n.left() as usize + 1] = depth[i] + 1;
        }
    }
    (lo, hi)
}

#[test]
fn oracle_descent_is_exact_and_no_traversal_beats_it() {
    let ball = AdbTree::new(CollisionMesh::new(generate::icosphere(1.0, 3)));
    let torus = AdbTree::new(CollisionMesh::new(generate::torus(1.0, 0.3, 48, 16)));
    let mut ws = QueryWorkspace::new();
    let mut adb_ws = AdbWorkspace::new();
    let mut hits = Vec::new();
    // Only exact hits count: a "collision" answer needs an intersecting triangle pair. (The
    // interpenetration certificate answers deep overlaps without one, below this bound: it is
    // not a traversal to a triangle pair.)
    let certain = |order| AdbQuery {
        p_min: 1.0,
        order,
        interior_after: None,
        ..AdbQuery::default()
    };
    for (ta, tb) in [(&ball, &ball), (&torus, &torus), (&ball, &torus)] {
        let (a, b) = (ta.collision_mesh(), tb.collision_mesh());
        let (depths_a, depths_b) = (LeafDepths::new(a), LeafDepths::new(b));
        let ((min_a, max_a), (min_b, max_b)) = (leaf_depth_range(a), leaf_depth_range(b));
        let mut colliding = 0;
        for p in near_contact_poses(a, b, 40, 0.15, 7) {
            let truth = intersects(a, &Pose::IDENTITY, b, &p.pose, &mut ws);
            let exact_pairs = ws.node_pairs_visited();
            let pairs =
                oracle_descent_pairs((a, &depths_a), (b, &depths_b), &p.pose, &mut ws, &mut hits);
            assert_eq!(pairs.is_some(), truth, "offset {}", p.offset);
            let Some(n) = pairs else { continue };
            colliding += 1;
            // The root pair, then two child pairs per level down one tree or the other.
            assert_eq!(n % 2, 1, "{n} node pairs");
            let steps = (n - 1) / 2;
            assert!(
                (min_a + min_b..=max_a + max_b).contains(&steps),
                "{steps} steps, leaf depths {min_a}..={max_a} and {min_b}..={max_b}"
            );
            assert!(n <= exact_pairs, "oracle {n} > exact query {exact_pairs}");
            for order in [
                Order::Straddle,
                Order::DepthFirst,
                Order::EvidenceFirst,
                Order::BestFirst,
            ] {
                let q = certain(order);
                let out = adb_intersects(ta, &Pose::IDENTITY, tb, &p.pose, &q, &mut adb_ws);
                assert!(out.collides);
                assert!(
                    n <= out.node_pairs_visited,
                    "oracle {n} > ADB {order:?} {}",
                    out.node_pairs_visited
                );
            }
        }
        assert!(colliding >= 10, "only {colliding} colliding poses");
    }
}
