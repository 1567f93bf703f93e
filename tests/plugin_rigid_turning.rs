//! The built-in impulse response turns bodies: inertia from the mesh (at its scale), a box
//! landing on its edge tips onto a face, a body with locked inertia does not, and the turn is
//! written back to the entity's `Transform`. In a real app (`TimePlugin`, `TransformPlugin`,
//! the default `FixedPostUpdate`, entities placed with `Transform`).
#![cfg(feature = "transform")]
mod plugin_support;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_transform::components::Transform;
use glam::Mat3;
use plugin_support::*;
use stochastic_collision::ecs::{BodyInertia, InertiaSource, Rest};
use stochastic_collision::prelude::*;

const HALF: f32 = 0.25;

fn floor(app: &mut App) {
    let floor = MeshCollider::new(generate::cuboid(Vec3::new(3.0, 0.5, 3.0), 8));
    spawn(
        app,
        (floor, Transform::from_xyz(0.0, -0.5, 0.0), Fidelity::Exact),
    );
}

/// A cube tilted by 35° about z, its lowest edge 0.2 above the floor.
fn tilted_cube(app: &mut App, inertia: Option<BodyInertia>) -> Entity {
    let cube = MeshCollider::new(generate::cuboid(Vec3::splat(HALF), 2));
    let rotation = Quat::from_rotation_z(35f32.to_radians());
    let lowest = (0..8)
        .map(|k| {
            let corner = Vec3::new(
                if k & 1 == 0 { -HALF } else { HALF },
                if k & 2 == 0 { -HALF } else { HALF },
                if k & 4 == 0 { -HALF } else { HALF },
            );
            (rotation * corner).y
        })
        .fold(f32::INFINITY, f32::min);
    let transform = Transform::from_xyz(0.0, 0.2 - lowest, 0.0).with_rotation(rotation);
    let id = spawn(
        app,
        (cube, transform, BodyVelocity(Vec3::ZERO), Fidelity::Exact),
    );
    if let Some(i) = inertia {
        app.world_mut().entity_mut(id).insert(i);
    }
    id
}

/// How well one of the body's axes points up (1: a face lies flat).
fn flatness(rotation: Quat) -> f32 {
    [Vec3::X, Vec3::Y, Vec3::Z]
        .iter()
        .map(|a| (rotation * *a).y.abs())
        .fold(0.0, f32::max)
}

#[test]
fn a_cube_landing_on_its_edge_tips_onto_a_face_and_the_transform_follows() {
    let mut app = game();
    app.add_plugins(ImpulseResponsePlugin::default());
    floor(&mut app);
    let cube = tilted_cube(&mut app, None);
    steps(&mut app, 2);
    let inertia = *app.world().get::<BodyInertia>(cube).unwrap();
    assert!(inertia.ready && inertia.source == InertiaSource::FromMesh);
    // 3 s at 64 Hz.
    steps(&mut app, 192);
    let t = *app.world().get::<Transform>(cube).unwrap();
    let pose = app.world().get::<ColliderPose>(cube).unwrap().0;
    assert!(
        flatness(t.rotation) > 0.99,
        "the cube should rest on a face: {:?} (flatness {})",
        t.rotation,
        flatness(t.rotation)
    );
    assert!(
        (t.translation.y - HALF).abs() < 0.04,
        "resting on a face, its centre is {HALF} above the floor: {}",
        t.translation.y
    );
    assert!(
        t.rotation.angle_between(pose.rotation) < 1e-4,
        "Transform written back"
    );
    assert!((t.translation - pose.translation).length() < 1e-4);
    assert!(app.world().get::<Rest>(cube).unwrap().is_asleep());
}

#[test]
fn a_locked_body_lands_without_turning() {
    let mut app = game();
    app.add_plugins(ImpulseResponsePlugin::default());
    floor(&mut app);
    let cube = tilted_cube(&mut app, Some(BodyInertia::locked()));
    let start = app.world().get::<Transform>(cube).unwrap().rotation;
    steps(&mut app, 192);
    let t = *app.world().get::<Transform>(cube).unwrap();
    assert!(t.rotation.angle_between(start) < 1e-5, "{:?}", t.rotation);
    assert!(flatness(t.rotation) < 0.9);
    assert!(t.translation.y > 0.0, "it still lands: {}", t.translation.y);
}

#[test]
fn inertia_comes_from_the_mesh_at_its_scale_and_follows_a_new_scale() {
    let mut app = game();
    app.add_plugins(ImpulseResponsePlugin::default());
    let mesh = generate::cuboid(Vec3::new(0.5, 0.25, 1.0), 2);
    let body = spawn(
        &mut app,
        (
            MeshCollider::new(mesh.clone()),
            Transform::from_xyz(0.0, 5.0, 0.0).with_scale(Vec3::splat(2.0)),
            BodyVelocity(Vec3::ZERO),
        ),
    );
    let close = |a: Mat3, b: Mat3| {
        (a - b)
            .to_cols_array()
            .iter()
            .all(|d| d.abs() < 1e-3 * b.x_axis.x.abs().max(1.0))
    };
    steps(&mut app, 2);
    let expected = mesh.mass_properties(Vec3::splat(2.0));
    let got = *app.world().get::<BodyInertia>(body).unwrap();
    assert!(
        close(got.inverse_inertia, expected.inverse_inertia()),
        "{got:?}"
    );
    assert!((got.radius - expected.radius).abs() < 1e-4);
    app.world_mut().get_mut::<Transform>(body).unwrap().scale = Vec3::new(1.0, 3.0, 1.0);
    steps(&mut app, 2);
    let expected = mesh.mass_properties(Vec3::new(1.0, 3.0, 1.0));
    let got = *app.world().get::<BodyInertia>(body).unwrap();
    assert!(
        close(got.inverse_inertia, expected.inverse_inertia()),
        "{got:?}"
    );
}
