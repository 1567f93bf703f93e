//! The persistent pair table against brute force, run after run, while colliders appear,
//! disappear, move (a little, inside their broad-phase box, or far), rest, and change layers,
//! on 1 and 2 threads (proptest over the sequence of changes):
//! - every two valid colliders whose world boxes overlap and whose layers interact have a
//!   pair, once; every pair's broad-phase (fat) boxes overlap and its layers interact;
//! - with exact fidelity and no budget, every pair touches exactly when the exact query says
//!   the meshes intersect at the current poses, whether it was worked on in this run or kept
//!   its answer from an earlier one, and `TouchingEntities` says the same;
//! - `CollisionPairs` finds each pair from both of its entities.
mod plugin_support;

use std::collections::BTreeSet;

use bevy_app::App;
use bevy_ecs::entity::Entity;
use bevy_ecs::system::RunSystemOnce;
use plugin_support::*;
use proptest::prelude::*;
use stochastic_collision::bvh::{QueryWorkspace, intersects};
use stochastic_collision::ecs::{BroadPhaseState, ColliderTable, ContactLayers, PairTable};
use stochastic_collision::prelude::*;

const LAYERS: [ContactLayers; 3] = [
    ContactLayers::ALL,
    ContactLayers::new(0b01, 0b01),
    ContactLayers::new(0b10, 0b11),
];

fn shapes() -> [MeshCollider; 3] {
    [
        MeshCollider::new(generate::icosphere(0.5, 1)),
        MeshCollider::new(generate::cuboid(Vec3::new(1.5, 0.1, 0.2), 1)),
        MeshCollider::new(generate::torus(0.6, 0.15, 12, 6)),
    ]
}

/// One change to the world between two runs.
#[derive(Debug, Clone)]
enum Change {
    Spawn {
        shape: usize,
        layers: usize,
        at: [f32; 3],
        turn: f32,
    },
    Despawn(usize),
    /// Moves a collider by this much (small steps stay inside the broad-phase box).
    Move(usize, [f32; 3]),
    Layers(usize, usize),
    Rest,
}

fn change() -> impl Strategy<Value = Change> {
    let place = [0.0f32..8.0, 0.0f32..2.0, 0.0f32..8.0];
    prop_oneof![
        (0..3usize, 0..3usize, place, 0.0f32..6.3).prop_map(|(shape, layers, at, turn)| {
            Change::Spawn {
                shape,
                layers,
                at,
                turn,
            }
        }),
        (0..64usize).prop_map(Change::Despawn),
        (0..64usize, [-0.05f32..0.05, -0.05f32..0.05, -0.05f32..0.05])
            .prop_map(|(k, d)| Change::Move(k, d)),
        (0..64usize, [-2.0f32..2.0, -0.5f32..0.5, -2.0f32..2.0])
            .prop_map(|(k, d)| Change::Move(k, d)),
        (0..64usize, 0..3usize).prop_map(|(k, l)| Change::Layers(k, l)),
        Just(Change::Rest),
    ]
}

fn apply(app: &mut App, bodies: &mut Vec<Entity>, shapes: &[MeshCollider; 3], c: &Change) {
    let world = app.world_mut();
    match *c {
        Change::Spawn {
            shape,
            layers,
            at,
            turn,
        } => {
            let pose = Pose::new(Vec3::from(at), Quat::from_rotation_y(turn));
            bodies.push(
                world
                    .spawn((
                        shapes[shape].clone(),
                        ColliderPose(pose),
                        LAYERS[layers],
                        Fidelity::Exact,
                    ))
                    .id(),
            );
        }
        Change::Despawn(k) if !bodies.is_empty() => {
            let e = bodies.swap_remove(k % bodies.len());
            world.despawn(e);
        }
        Change::Move(k, d) if !bodies.is_empty() => {
            let e = bodies[k % bodies.len()];
            world.get_mut::<ColliderPose>(e).unwrap().0.translation += Vec3::from(d);
        }
        Change::Layers(k, l) if !bodies.is_empty() => {
            let e = bodies[k % bodies.len()];
            world.entity_mut(e).insert(LAYERS[l]);
        }
        _ => {}
    }
}

/// Checks every invariant of the module documentation after a run.
fn check(app: &mut App, bodies: &[Entity], ws: &mut QueryWorkspace) -> Result<(), TestCaseError> {
    let world = app.world();
    let (colliders, table, broad) = (
        world.resource::<ColliderTable>(),
        world.resource::<PairTable>(),
        world.resource::<BroadPhaseState>(),
    );
    let mut listed = BTreeSet::new();
    for o in table.outcomes() {
        prop_assert!(
            listed.insert((o.a, o.b)),
            "pair {:?} listed twice",
            (o.a, o.b)
        );
        let (ea, eb) = (colliders.get(o.a).unwrap(), colliders.get(o.b).unwrap());
        let (fa, fb) = (
            broad.fat_box(colliders, o.a).unwrap(),
            broad.fat_box(colliders, o.b).unwrap(),
        );
        prop_assert!(fa.intersects(&fb), "pair {:?}: fat boxes apart", (o.a, o.b));
        prop_assert!(ea.layers.interacts_with(&eb.layers));
    }
    for (k, &a) in bodies.iter().enumerate() {
        for &b in &bodies[k + 1..] {
            let (ea, eb) = (colliders.get(a).unwrap(), colliders.get(b).unwrap());
            let close = ea.aabb.intersects(&eb.aabb) && ea.layers.interacts_with(&eb.layers);
            let key = (a.min(b), a.max(b));
            if close {
                prop_assert!(listed.contains(&key), "pair {key:?} missing");
            }
            let touching =
                listed.contains(&key) && world.get::<TouchingEntities>(a).unwrap().contains(b);
            let exact = close
                && intersects(
                    ea.geometry.mesh(),
                    &ea.pose,
                    eb.geometry.mesh(),
                    &eb.pose,
                    ws,
                );
            prop_assert_eq!(touching, exact, "pair {:?}", key);
            prop_assert_eq!(world.get::<TouchingEntities>(b).unwrap().contains(a), exact);
        }
    }
    // CollisionPairs, as a system would read it: each pair from both ends.
    let pairs: Vec<(Entity, Entity)> = listed.iter().copied().collect();
    let found = app
        .world_mut()
        .run_system_once(move |c: CollisionPairs| {
            pairs.iter().all(|&(a, b)| {
                c.get(a, b).is_some()
                    && c.get(b, a).is_some()
                    && c.of(a).any(|p| p.other(a) == b)
                    && c.of(b).any(|p| p.other(b) == a)
            })
        })
        .unwrap();
    prop_assert!(found);
    Ok(())
}

/// The test app, without a budget (every pair that needs a test gets one).
fn unbudgeted(threads: usize) -> App {
    app_with(
        CollisionConfig {
            budget: FrameBudget::Unlimited,
            ..Default::default()
        },
        threads,
    )
}

fn run_case(threads: usize, setup: &[Change], changes: &[Change]) -> Result<(), TestCaseError> {
    let mut app = unbudgeted(threads);
    let shapes = shapes();
    let mut bodies = Vec::new();
    let mut ws = QueryWorkspace::new();
    for c in setup {
        apply(&mut app, &mut bodies, &shapes, c);
    }
    for c in changes {
        apply(&mut app, &mut bodies, &shapes, c);
        app.update();
        check(&mut app, &bodies, &mut ws)?;
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn the_pair_table_matches_brute_force_run_after_run(
        setup in proptest::collection::vec(change(), 30..60),
        changes in proptest::collection::vec(change(), 6..14),
        threads in 1..=2usize,
    ) {
        let spawns: Vec<Change> = setup
            .into_iter()
            .filter(|c| matches!(c, Change::Spawn { .. }))
            .collect();
        run_case(threads, &spawns, &changes)?;
    }
}

/// Many colliders moving a little each run, a third at a time, some going and coming: the
/// same invariants on a denser world than the proptest's (deterministic).
#[test]
fn a_busy_world_keeps_the_invariants() {
    for threads in [1, 2] {
        let mut app = unbudgeted(threads);
        let shapes = shapes();
        let mut bodies = Vec::new();
        let mut ws = QueryWorkspace::new();
        let mut seed = 7u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 40) as f32) / (1u64 << 24) as f32
        };
        for k in 0..150 {
            let at = [next() * 12.0, next() * 2.0, next() * 12.0];
            let c = Change::Spawn {
                shape: k % 3,
                layers: (k / 3) % 3,
                at,
                turn: next() * 6.0,
            };
            apply(&mut app, &mut bodies, &shapes, &c);
        }
        for run in 0..8 {
            app.update();
            check(&mut app, &bodies, &mut ws).unwrap();
            for k in (run % 3..bodies.len()).step_by(3) {
                let d = [next() - 0.5, 0.0, next() - 0.5].map(|v| v * 0.3);
                apply(&mut app, &mut bodies, &shapes, &Change::Move(k, d));
            }
            for _ in 0..4 {
                apply(&mut app, &mut bodies, &shapes, &Change::Despawn(run * 7));
                let at = [next() * 12.0, next() * 2.0, next() * 12.0];
                let c = Change::Spawn {
                    shape: run % 3,
                    layers: 0,
                    at,
                    turn: 0.0,
                };
                apply(&mut app, &mut bodies, &shapes, &c);
            }
        }
    }
}
