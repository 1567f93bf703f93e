//! Pile: rigid meshes (generated, and shared ones when present) falling into a box, with the
//! built-in impulse response.
use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::ecs::ImpulseSettings;
use stochastic_collision::prelude::*;

use super::{Options, normalized, shared_mesh};

/// Default number of bodies.
pub const DEFAULT_BODIES: usize = 1000;

/// The bodies' meshes: a few generated shapes, plus the shared Suzanne when present.
pub fn body_colliders() -> Vec<MeshCollider> {
    let mut meshes = vec![
        generate::icosphere(0.25, 1),
        generate::torus(0.2, 0.08, 16, 8),
        generate::cuboid(Vec3::splat(0.18), 1),
    ];
    if let Some(m) = shared_mesh("suzanne.obj") {
        meshes.push(normalized(&m, 0.5));
    }
    meshes.into_iter().map(MeshCollider::new).collect()
}

pub fn setup(app: &mut App, options: &Options) {
    // The scene the measurements were made on steps at 60 Hz (the examples run without
    // bevy_time: one collision run per app update).
    app.add_plugins(
        ImpulseResponsePlugin::default().with_settings(ImpulseSettings {
            dt: Some(1.0 / 60.0),
            ..Default::default()
        }),
    );
    let n = options.count(DEFAULT_BODIES);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(options.seed);
    // A box whose floor holds about a quarter of the bodies per layer.
    let per_row = ((n as f32 / 4.0).sqrt().ceil() as usize).max(2);
    let spacing = 0.6;
    // Layers fall from a little apart, so that they land one after the other.
    let layer_gap = 1.2;
    let half = per_row as f32 * spacing * 0.5 + 0.3;
    let world = app.world_mut();
    // Subdivided, so that its tree has small leaves (a few huge triangles make every exact
    // test against it slow).
    let slab = |h: Vec3| MeshCollider::new(generate::cuboid(h, 12));
    let height = 1.5;
    // The box is static level geometry of a few large triangles: tested exactly (cheap, and
    // nothing may fall through it); the bodies among themselves use the default fidelity.
    let exact = Fidelity::Exact;
    let floor = Vec3::new(half + 0.5, 0.5, half + 0.5);
    world.spawn((slab(floor), pose(0.0, -0.5, 0.0), exact));
    for (x, z, h) in [
        (half + 0.25, 0.0, Vec3::new(0.25, height, half + 0.5)),
        (-half - 0.25, 0.0, Vec3::new(0.25, height, half + 0.5)),
        (0.0, half + 0.25, Vec3::new(half + 0.5, height, 0.25)),
        (0.0, -half - 0.25, Vec3::new(half + 0.5, height, 0.25)),
    ] {
        world.spawn((slab(h), pose(x, height, z), exact));
    }
    let colliders = body_colliders();
    for i in 0..n {
        let (layer, k) = (i / (per_row * per_row), i % (per_row * per_row));
        let (row, col) = (k / per_row, k % per_row);
        let jitter = Vec3::new(
            rng.random_range(-0.05..0.05),
            0.0,
            rng.random_range(-0.05..0.05),
        );
        let position = Vec3::new(
            (col as f32 + 0.5) * spacing - half + 0.3,
            0.6 + layer as f32 * layer_gap,
            (row as f32 + 0.5) * spacing - half + 0.3,
        ) + jitter;
        let axis = Vec3::new(
            rng.random_range(-1.0..1.0),
            1.0,
            rng.random_range(-1.0..1.0),
        );
        let rotation = Quat::from_axis_angle(
            axis.normalize(),
            rng.random_range(0.0..std::f32::consts::TAU),
        );
        world.spawn((
            colliders[i % colliders.len()].clone(),
            ColliderPose(Pose::new(position, rotation)),
            BodyVelocity(Vec3::new(
                rng.random_range(-0.5..0.5),
                0.0,
                rng.random_range(-0.5..0.5),
            )),
            BodyMass(1.0),
        ));
    }
}

fn pose(x: f32, y: f32, z: f32) -> ColliderPose {
    ColliderPose::from_translation(Vec3::new(x, y, z))
}

/// Bodies with a velocity still above `speed` (how settled the pile is).
pub fn moving(world: &mut World, speed: f32) -> usize {
    let mut q = world.query::<&BodyVelocity>();
    q.iter(world).filter(|v| v.0.length() > speed).count()
}
