//! The oracle descent of the `accuracy_vs_time` report (the bound on what a probability-guided
//! ordering can gain): it answers exactly when the meshes intersect, and it walks one
//! root-to-leaf path of each tree, looking at two child pairs per step.
#[path = "../examples/support/oracle_descent.rs"]
mod oracle_descent;

use oracle_descent::{SubtreeRanges, oracle_descent_pairs};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, intersects};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::generate;
use stochastic_collision::poses::near_contact_poses;

/// The shallowest and the deepest leaf of a mesh's tree (the root at depth 0).
fn leaf_depths(mesh: &CollisionMesh) -> (u64, u64) {
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
fn oracle_descent_answers_exactly_and_walks_one_path_per_tree() {
    let ball = CollisionMesh::new(generate::icosphere(1.0, 3));
    let torus = CollisionMesh::new(generate::torus(1.0, 0.3, 48, 16));
    let mut ws = QueryWorkspace::new();
    let mut hits = Vec::new();
    for (a, b) in [(&ball, &ball), (&torus, &torus), (&ball, &torus)] {
        let (ranges_a, ranges_b) = (SubtreeRanges::new(a), SubtreeRanges::new(b));
        let ((min_a, max_a), (min_b, max_b)) = (leaf_depths(a), leaf_depths(b));
        let mut colliding = 0;
        for p in near_contact_poses(a, b, 40, 0.15, 7) {
            let truth = intersects(a, &Pose::IDENTITY, b, &p.pose, &mut ws);
            let pairs =
                oracle_descent_pairs((a, &ranges_a), (b, &ranges_b), &p.pose, &mut ws, &mut hits);
            assert_eq!(pairs.is_some(), truth, "offset {}", p.offset);
            let Some(n) = pairs else { continue };
            colliding += 1;
            // The root pair, then two child pairs per step down one tree or the other.
            assert_eq!(n % 2, 1, "{n} node pairs");
            let steps = (n - 1) / 2;
            assert!(
                (min_a + min_b..=max_a + max_b).contains(&steps),
                "{steps} steps, leaf depths {min_a}..={max_a} and {min_b}..={max_b}"
            );
        }
        assert!(colliding >= 10, "only {colliding} colliding poses");
    }
}
