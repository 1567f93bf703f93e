//! Both preludes glob-imported in one scope, every name of this crate's prelude used: a name
//! that both define would be an ambiguity error here (the test is that this compiles).
#![allow(dead_code)]
use avian3d::prelude::*;
use bevy::prelude::*;
use stochastic_collision::prelude::*;

type OursCore = (
    AdbOutcome,
    AdbQuery,
    AdbTree,
    AdbWorkspace,
    Budget,
    Bvh,
    CollisionMesh,
    ExactOptions,
    ExactOutcome,
    MeshDistance,
    QueryWorkspace,
    TrianglePair,
    Aabb,
    Pose,
    MeshError,
    Topology,
    TriMesh,
    Quat,
    Vec3,
);

type OursPlugin = (
    BodyAngularVelocity,
    BodyInertia,
    BodyMass,
    BodyVelocity,
    ColliderPose,
    ColliderScale,
    ContinuousCollision,
    CollisionConfig,
    CollisionDiagnostics,
    CollisionEnded,
    CollisionError,
    CollisionSensor,
    CollisionStarted,
    CollisionSystems,
    Contact,
    ContactLayers,
    ContactQueue,
    Deformable,
    Fidelity,
    FrameBudget,
    ImpulseResponsePlugin,
    MeshCollider,
    Method,
    ObserveCollisions,
    PairFilterPlugin<AcceptAll>,
    PenaltyResponsePlugin,
    RefilterPairs,
    SelfCollision,
    StochasticCollisionPlugin,
    StochasticCollisionPlugins,
    TouchingEntities,
);

/// The `bevy_mesh` feature's names (avian's are `ColliderConstructor` and
/// `ColliderConstructorHierarchy`).
type OursBevyMesh = (
    BevyMeshError,
    MeshColliderConstructor,
    MeshColliderConstructorHierarchy,
    MeshNameFilter,
);

/// The `debug_render` feature's names (avian's are `PhysicsDebugPlugin` and
/// `PhysicsGizmos`).
type OursDebug = (CollisionDebugPlugin, CollisionGizmos);

/// The traits of this crate's prelude (avian's are `PhysicsLayer` and `CollisionHooks`).
fn our_traits<L: ContactLayer, F: PairFilter>() {}

#[derive(bevy::ecs::system::SystemParam)]
struct AcceptAll;

impl PairFilter for AcceptAll {
    fn test_pair(&self, _: Entity, _: Entity) -> bool {
        true
    }
}

/// Avian's names that ours were renamed away from, still avian's.
type Theirs = (
    Collider,
    CollisionLayers,
    CollidingEntities,
    CollisionEventsEnabled,
    Sensor,
    Mass,
    ColliderConstructor,
    ColliderConstructorHierarchy,
    CollisionStart,
    CollisionEnd,
    LinearVelocity,
);

fn reads_pairs(_ours: CollisionPairs, _theirs: Collisions) {}

#[test]
fn both_preludes_in_one_scope() {
    let _ = (
        closest_points,
        intersecting_pairs,
        intersects,
        intersects_with,
        self_intersections,
        adb_intersects,
    );
    let mesh = generate::icosphere(1.0, 1);
    let _ours = MeshCollider::new(mesh);
    let _theirs = Collider::sphere(1.0);
    bevy::ecs::system::assert_is_system(reads_pairs);
}
