//! The ADB traversal's answers, pinned: every field of every outcome of [`adb_intersects`]
//! (floats by their bits) on seeded near-contact poses of generated mesh pairs, under every
//! [`Order`], several deterministic node-pair budgets and query variants (decision rules,
//! estimated leaves, the certificate before, during or never, pruning), hashed per mesh pair
//! and variant and compared with the fingerprints the traversal gave when they were recorded.
//!
//! A change to the traversal that is meant to keep its answers (a refactoring) must keep every
//! fingerprint. A change meant to alter answers must say so and record the new fingerprints:
//! on a mismatch the test prints the whole table in the form of [`EXPECTED`].
use std::sync::Arc;

use glam::Vec3;
use stochastic_collision::adb::{
    AdbBuildOptions, AdbOutcome, AdbQuery, AdbTree, AdbWorkspace, Budget, Decision, Order,
    PaperEstimator, adb_intersects,
};
use stochastic_collision::bvh::CollisionMesh;
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::generate;
use stochastic_collision::poses::near_contact_poses;

/// Every traversal order.
const ORDERS: [Order; 4] = [
    Order::Straddle,
    Order::DepthFirst,
    Order::EvidenceFirst,
    Order::BestFirst,
];

/// Deterministic budgets: none, the root pair only, and node-pair budgets that cut the
/// traversal at various depths.
const BUDGETS: [Budget; 5] = [
    Budget::Unlimited,
    Budget::NodePairs(1),
    Budget::NodePairs(12),
    Budget::NodePairs(60),
    Budget::NodePairs(300),
];

/// Poses per mesh pair (near first contact, within ±15 % of the size).
const POSES: usize = 100;

/// The query variants, by name.
fn variants() -> Vec<(&'static str, AdbQuery)> {
    let d = AdbQuery::default();
    vec![
        ("default", d.clone()),
        (
            "evidence_estimated_leaves",
            AdbQuery {
                decision: Decision::Evidence,
                exact_leaves: false,
                ..d.clone()
            },
        ),
        (
            "estimated_leaves",
            AdbQuery {
                exact_leaves: false,
                ..d.clone()
            },
        ),
        (
            "certificate_at_pop_5",
            AdbQuery {
                interior_after: Some(5),
                ..d.clone()
            },
        ),
        (
            "no_certificate_k3",
            AdbQuery {
                interior_after: None,
                k_min: 3,
                ..d.clone()
            },
        ),
        (
            "pruned",
            AdbQuery {
                p_prune: 0.02,
                collide_at: 0.3,
                ..d.clone()
            },
        ),
        (
            "paper",
            AdbQuery {
                estimator: Arc::new(PaperEstimator::default()),
                ..AdbQuery::paper()
            },
        ),
    ]
}

/// The mesh pairs: a mesh against itself (the same tree: the failed-certificate calibration
/// applies), closed meshes of different shapes and sizes, and an open mesh.
fn pairs() -> Vec<(&'static str, Arc<AdbTree>, Arc<AdbTree>)> {
    let build = |mesh| {
        Arc::new(AdbTree::build_with(
            CollisionMesh::new(mesh),
            AdbBuildOptions::default(),
        ))
    };
    let ball = build(generate::icosphere(1.0, 3));
    let torus = build(generate::torus(1.0, 0.3, 32, 12));
    let brick = build(generate::cuboid(Vec3::new(1.0, 0.4, 0.7), 2));
    let pebble = build(generate::icosphere(0.12, 2));
    let cloth = build(generate::cloth_grid(2.0, 2.0, 12, 12));
    vec![
        ("ball_ball", ball.clone(), ball.clone()),
        ("torus_brick", torus.clone(), brick.clone()),
        ("brick_pebble", brick, pebble),
        ("cloth_ball", cloth, ball),
        ("torus_torus", torus.clone(), torus),
    ]
}

/// FNV-1a over 64-bit words.
struct Fingerprint(u64);

impl Fingerprint {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }

    fn word(&mut self, w: u64) {
        for byte in w.to_le_bytes() {
            self.0 ^= u64::from(byte);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }

    fn vec3(&mut self, v: Vec3) {
        for c in v.to_array() {
            self.word(u64::from(c.to_bits()));
        }
    }

    /// Every field of the outcome.
    fn outcome(&mut self, o: &AdbOutcome) {
        self.word(u64::from(o.collides));
        self.word(o.probability.to_bits());
        self.word(u64::from(o.pairs_found));
        self.word(o.node_pairs_visited);
        self.word(u64::from(o.budget_exhausted));
        self.word(o.max_pair_probability.to_bits());
        match &o.witness {
            None => self.word(0),
            Some(w) => {
                self.word(1);
                self.vec3(w.point);
                self.vec3(w.normal);
                self.word(u64::from(w.nodes.0) << 32 | u64::from(w.nodes.1));
                match w.triangles {
                    None => self.word(0),
                    Some(t) => self.word(1 << 63 | u64::from(t.a) << 32 | u64::from(t.b)),
                }
            }
        }
        match &o.interpenetration {
            None => self.word(0),
            Some(c) => {
                self.word(1);
                self.vec3(c.inside_point);
                self.word(u64::from(c.vertex));
                self.word(u64::from(c.exact));
                self.word(u64::from(c.depth.to_bits()));
            }
        }
    }
}

/// The fingerprints recorded: (mesh pair, variant, fingerprint over every pose, order and
/// budget).
const EXPECTED: &[(&str, &str, u64)] = &[
    ("ball_ball", "default", 0xb2efab80028f8341),
    ("ball_ball", "evidence_estimated_leaves", 0x8c1d63fb68a7d4c5),
    ("ball_ball", "estimated_leaves", 0x836715219e733e98),
    ("ball_ball", "certificate_at_pop_5", 0x2b1a7a1968f6eb1f),
    ("ball_ball", "no_certificate_k3", 0xb2c3b0e74a57bdc2),
    ("ball_ball", "pruned", 0x0a439c28eec8e8ad),
    ("ball_ball", "paper", 0x84315684d313015e),
    ("torus_brick", "default", 0x69a0f7270b07e17f),
    (
        "torus_brick",
        "evidence_estimated_leaves",
        0xf5210ed8c27db1a7,
    ),
    ("torus_brick", "estimated_leaves", 0xf5210ed8c27db1a7),
    ("torus_brick", "certificate_at_pop_5", 0x4802f7e22e2c8287),
    ("torus_brick", "no_certificate_k3", 0x4814c4e7cc588a54),
    ("torus_brick", "pruned", 0x29bbfb3c3309af89),
    ("torus_brick", "paper", 0xb94e0c957eaa38e3),
    ("brick_pebble", "default", 0x87ec98beb638c019),
    (
        "brick_pebble",
        "evidence_estimated_leaves",
        0x8725530956754788,
    ),
    ("brick_pebble", "estimated_leaves", 0x8725530956754788),
    ("brick_pebble", "certificate_at_pop_5", 0x7f79a5b3389c5ce7),
    ("brick_pebble", "no_certificate_k3", 0xc62ce328a3c3585d),
    ("brick_pebble", "pruned", 0xc492dac45adaab45),
    ("brick_pebble", "paper", 0xe1322463cdb5ef95),
    ("cloth_ball", "default", 0xcabc61f8d56c5fe8),
    (
        "cloth_ball",
        "evidence_estimated_leaves",
        0xc65e0caf05a0a73c,
    ),
    ("cloth_ball", "estimated_leaves", 0x71dcd8965bb27417),
    ("cloth_ball", "certificate_at_pop_5", 0xc9d19dfc54e13c00),
    ("cloth_ball", "no_certificate_k3", 0xad1f1eda770103e3),
    ("cloth_ball", "pruned", 0x0e58d6997f74fb0a),
    ("cloth_ball", "paper", 0x3261043733c65f52),
    ("torus_torus", "default", 0x32eeacf4a8485dc3),
    (
        "torus_torus",
        "evidence_estimated_leaves",
        0xe8c2339a29113924,
    ),
    ("torus_torus", "estimated_leaves", 0xe8c2339a29113924),
    ("torus_torus", "certificate_at_pop_5", 0xe9976b0a1df7dabf),
    ("torus_torus", "no_certificate_k3", 0xf2c942c043b2c543),
    ("torus_torus", "pruned", 0x9e9561c8942f116c),
    ("torus_torus", "paper", 0x83c57e6d179b68b8),
];

#[test]
fn adb_outcomes_are_unchanged() {
    let mut ws = AdbWorkspace::new();
    let mut found = Vec::new();
    for (pair, a, b) in pairs() {
        let poses = near_contact_poses(a.collision_mesh(), b.collision_mesh(), POSES, 0.15, 0x5EED);
        assert_eq!(poses.len(), POSES, "{pair}");
        let mut collided = 0usize;
        let mut total = 0usize;
        for (variant, base) in variants() {
            let mut f = Fingerprint::new();
            for order in ORDERS {
                for budget in BUDGETS {
                    let query = AdbQuery {
                        order,
                        budget,
                        ..base.clone()
                    };
                    for p in &poses {
                        let out = adb_intersects(&a, &Pose::IDENTITY, &b, &p.pose, &query, &mut ws);
                        collided += usize::from(out.collides);
                        total += 1;
                        f.outcome(&out);
                    }
                }
            }
            found.push((pair, variant, f.0));
        }
        // The poses are near contact: some answers say "collision", some do not (else the
        // fingerprints would pin little).
        assert!(
            collided > 0 && collided < total,
            "{pair}: {collided} of {total}"
        );
    }
    let table: String = found
        .iter()
        .map(|(p, v, h)| format!("    (\"{p}\", \"{v}\", {h:#018x}),\n"))
        .collect();
    let expected: Vec<_> = EXPECTED.to_vec();
    assert!(
        found == expected,
        "ADB outcomes changed; the fingerprints now are:\nconst EXPECTED: &[(&str, &str, u64)] = &[\n{table}];"
    );
}
