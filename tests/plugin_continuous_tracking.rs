//! Continuous tracking in the plugin, in a real app (`TimePlugin`, `TransformPlugin`, the
//! default `FixedPostUpdate` at 64 Hz, entities placed with `Transform`): a fast needle
//! (`Fidelity::Tracking`) shot through a deformable cloth in one step is reported only with
//! `ContinuousCollision`, with a time of impact within 1e-3 of the exact continuous query's;
//! a fold of a deformable cloth pushed through the cloth between two runs is reported as a
//! self-collision with its time of impact only with the component.
#![cfg(feature = "transform")]
mod common;
mod plugin_support;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_transform::components::Transform;
use common::shapes::sheared_fold;
use plugin_support::*;
use stochastic_collision::bvh::CollisionMesh;
use stochastic_collision::ccd::{CcdOptions, CcdWorkspace, RigidMotion, time_of_impact};
use stochastic_collision::ecs::DEFAULT_STEP;
use stochastic_collision::geometry::Pose;
use stochastic_collision::prelude::*;

const TRACKED: Fidelity = Fidelity::Tracking {
    pairs_per_frame: 32,
};
/// Per fixed step: 0.9, three needle lengths.
const SPEED: f32 = 0.9 / DEFAULT_STEP;
/// The needle's centre when the plugin first sees it: after one fixed step from the spawn
/// height, 0.3 above the cloth; the next step takes it to 0.6 below.
const SPAWN_HEIGHT: f32 = 1.2;

fn needle_mesh() -> TriMesh {
    generate::tube(0.01, 0.3, 8, 6, true)
}

fn tilt() -> Quat {
    Quat::from_rotation_z(0.3)
}

/// A deformable cloth at the origin and a needle falling through it at `SPEED` (moved by the
/// scene, one step per fixed step), both tracked.
fn needle_scene(continuous: bool) -> (App, Entity, Entity) {
    let mut app = game();
    app.init_resource::<Starts>()
        .add_systems(Last, record_starts);
    app.add_systems(
        FixedUpdate,
        |mut q: Query<&mut Transform, With<BodyVelocity>>| {
            for mut t in &mut q {
                t.translation.y -= SPEED * DEFAULT_STEP;
            }
        },
    );
    let cloth = spawn(
        &mut app,
        (
            Deformable::new(generate::cloth_grid(1.0, 1.0, 24, 24)),
            Transform::default(),
            TRACKED,
        ),
    );
    let needle = spawn(
        &mut app,
        (
            MeshCollider::new(needle_mesh()),
            Transform::from_xyz(0.013, SPAWN_HEIGHT, -0.021).with_rotation(tilt()),
            BodyVelocity(Vec3::NEG_Y * SPEED),
            TRACKED,
        ),
    );
    if continuous {
        app.world_mut()
            .entity_mut(needle)
            .insert(ContinuousCollision::Always);
    }
    (app, cloth, needle)
}

#[test]
fn a_needle_shot_through_a_tracked_cloth_is_caught_only_with_continuous_collision() {
    let (mut app, _, needle) = needle_scene(false);
    for _ in 0..5 {
        app.update();
    }
    let y = app.world().get::<Transform>(needle).unwrap().translation.y;
    assert!(y < -1.0, "the needle went through: {y}");
    assert!(
        app.world().resource::<Starts>().0.is_empty(),
        "the discrete tracker sees nothing: {:?}",
        app.world().resource::<Starts>().0
    );

    // The reference: the exact continuous query over the step that crosses the cloth.
    let (above, below) = (
        Pose::new(Vec3::new(0.013, 0.3, -0.021), tilt()),
        Pose::new(Vec3::new(0.013, -0.6, -0.021), tilt()),
    );
    let reference = time_of_impact(
        &CollisionMesh::new(generate::cloth_grid(1.0, 1.0, 24, 24)),
        &RigidMotion::still(Pose::IDENTITY),
        &CollisionMesh::new(needle_mesh()),
        &RigidMotion::new(above, below),
        &CcdOptions::default(),
        &mut CcdWorkspace::default(),
    )
    .unwrap()
    .expect("the needle crosses the cloth");

    let (mut app, cloth, needle) = needle_scene(true);
    for _ in 0..5 {
        app.update();
    }
    let starts = &app.world().resource::<Starts>().0;
    assert_eq!(starts.len(), 1, "one contact: {starts:?}");
    let s = starts[0];
    assert_eq!(pair(s.entity, s.other), pair(cloth, needle));
    assert_eq!(s.method, Method::Tracking);
    let t = s.time_of_impact.expect("a time of impact");
    assert!(
        (t - reference.time).abs() < 1e-3,
        "time of impact {t}, exact {}",
        reference.time
    );
}

fn fold_run(continuous: bool) -> (Vec<CollisionStarted>, Entity) {
    let mut app = game();
    app.init_resource::<Starts>()
        .add_systems(Last, record_starts);
    let flat = generate::cloth_grid(1.0, 1.0, 20, 20);
    let mut cloth = Deformable::new(flat.clone());
    cloth
        .positions_mut()
        .copy_from_slice(&sheared_fold(&flat, 0.04));
    let cloth = spawn(
        &mut app,
        (cloth, SelfCollision, TRACKED, Transform::default()),
    );
    if continuous {
        app.world_mut()
            .entity_mut(cloth)
            .insert(ContinuousCollision::Always);
    }
    for _ in 0..5 {
        app.update();
    }
    assert!(
        app.world().resource::<Starts>().0.is_empty(),
        "apart: {:?}",
        app.world().resource::<Starts>().0
    );
    app.world_mut()
        .get_mut::<Deformable>(cloth)
        .unwrap()
        .positions_mut()
        .copy_from_slice(&sheared_fold(&flat, -0.04));
    for _ in 0..2 {
        app.update();
    }
    (app.world().resource::<Starts>().0.clone(), cloth)
}

#[test]
fn a_fold_pushed_through_a_tracked_cloth_is_a_self_collision_with_its_time_of_impact() {
    let (starts, _) = fold_run(false);
    assert!(
        starts.is_empty(),
        "the discrete tracker sees nothing: {starts:?}"
    );
    let (starts, cloth) = fold_run(true);
    assert_eq!(starts.len(), 1, "{starts:?}");
    let s = starts[0];
    assert_eq!((s.entity, s.other), (cloth, cloth));
    assert_eq!(s.method, Method::SelfCollision);
    // The flat part of the flap crosses the base at half the step; the slanted strip at the
    // fold line (from the base to the flap) may touch earlier, never later.
    let t = s.time_of_impact.expect("a time of impact");
    assert!(t > 0.0 && t <= 0.5 + 1e-3, "time of impact {t}");
}
