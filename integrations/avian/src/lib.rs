//! stochastic_collision next to avian3d: the `cloth_and_balls` scene (avian simulates rigid
//! balls, this crate detects their contacts with a cloth mesh that deforms every step, which
//! avian cannot afford to treat as a trimesh, and hands them back to avian as velocity changes
//! and position corrections), and a compile test that both preludes can be glob-imported
//! together (`tests/preludes.rs`).
//!
//! Each fixed step avian moves the balls and writes their `Transform`s; this crate reads them
//! in the same step (its sets run after `PhysicsSystems::Last`), tests the balls against the
//! cloth exactly, and [`push_balls`] turns each contact into a change of the ball's
//! `LinearVelocity` and `Position`; `PenaltyResponsePlugin` pushes the cloth's vertices down and
//! [`relax_cloth`] lets the cloth spring back towards its rest shape.
//!
//! [`pile`] builds the main crate's pile scene (rigid meshes falling into a box) for both this
//! crate and avian3d, with the same triangles as trimesh colliders everywhere, and times each
//! side's collision stages per step; the `pile_vs_avian` example compares them over the falling
//! phase (`docs/plugin/avian_pile.sh` runs it, its output is `docs/plugin/runs/avian_pile.txt`).
use avian3d::prelude::*;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use stochastic_collision::ecs::{PenaltySettings, penalty_response};
use stochastic_collision::prelude::*;

pub mod pile;

/// Balls dropped on the cloth.
pub const BALLS: usize = 9;
/// Their radius.
pub const RADIUS: f32 = 0.2;
/// The cloth's side and cells per side.
pub const CLOTH: f32 = 3.0;
/// Cells per side of the cloth.
pub const CELLS: u32 = 24;

/// Layers: balls test only against the cloth (avian handles ball–ball contacts).
const BALL_LAYERS: ContactLayers = ContactLayers::new(0b01, 0b10);
const CLOTH_LAYERS: ContactLayers = ContactLayers::new(0b10, 0b01);

/// Marks the balls.
#[derive(Component)]
pub struct Ball;

/// Marks the cloth.
#[derive(Component)]
pub struct Cloth;

/// What the run saw.
#[derive(Resource, Default, Debug, Clone, Copy)]
pub struct Tally {
    /// Ball–cloth contacts handed to the responses, over all steps.
    pub contacts: u64,
    /// Contacts started.
    pub started: u64,
    /// The lowest ball centre at the last step.
    pub lowest_ball: f32,
}

/// The scene, headless, one fixed step per `App::update`.
pub fn cloth_and_balls_app() -> App {
    let mut app = App::new();
    app.add_plugins((
        bevy::app::TaskPoolPlugin::default(),
        bevy::time::TimePlugin,
        bevy::transform::TransformPlugin,
        PhysicsPlugins::default(),
        StochasticCollisionPlugin::default().with_threads(2),
        // A soft cloth: each contact's whole depth is corrected in one step.
        PenaltyResponsePlugin::default().with_settings(PenaltySettings {
            stiffness: 1.0,
            ..PenaltySettings::default()
        }),
    ))
    .insert_resource(TimeUpdateStrategy::FixedTimesteps(1))
    .init_resource::<Tally>()
    // Both run in FixedPostUpdate: this crate after avian has written the step's transforms.
    .configure_sets(
        FixedPostUpdate,
        CollisionSystems::Prepare.after(PhysicsSystems::Last),
    )
    .add_systems(
        FixedPostUpdate,
        (
            push_balls
                .in_set(CollisionSystems::Response)
                .before(penalty_response),
            relax_cloth.after(CollisionSystems::Response),
            count
                .after(CollisionSystems::Report)
                .before(CollisionSystems::Response),
        ),
    );
    // Plugins finish their setup (avian inserts resources there; `App::run` does this).
    app.finish();
    app.cleanup();
    let world = app.world_mut();
    let cloth = Deformable::new(generate::cloth_grid(CLOTH, CLOTH, CELLS, CELLS));
    world.spawn((
        cloth,
        Transform::IDENTITY,
        CLOTH_LAYERS,
        Fidelity::Exact,
        Cloth,
    ));
    let ball_mesh = MeshCollider::new(generate::icosphere(RADIUS, 2));
    for k in 0..BALLS {
        let (i, j) = ((k % 3) as f32 - 1.0, (k / 3) as f32 - 1.0);
        world.spawn((
            Ball,
            RigidBody::Dynamic,
            Collider::sphere(RADIUS),
            ball_mesh.clone(),
            BALL_LAYERS,
            Fidelity::Exact,
            Transform::from_xyz(0.7 * i, 0.6 + 0.25 * k as f32, 0.7 * j),
        ));
    }
    app
}

/// The balls' centres and the cloth's vertices (world space: the cloth is not moved).
pub fn positions(app: &mut App) -> (Vec<Vec3>, Vec<Vec3>) {
    let world = app.world_mut();
    let balls = world
        .query_filtered::<&Transform, With<Ball>>()
        .iter(world)
        .map(|t| t.translation)
        .collect();
    let cloth = world
        .query_filtered::<&Deformable, With<Cloth>>()
        .single(world)
        .expect("one cloth")
        .positions()
        .to_vec();
    (balls, cloth)
}

/// Each ball–cloth contact: the ball's approach along the normal is removed (a little
/// bounce), its penetration corrected; the contact stays queued for the cloth's penalty
/// response.
pub fn push_balls(
    mut queue: ResMut<ContactQueue>,
    mut balls: Query<(&mut LinearVelocity, &mut Position), With<Ball>>,
) {
    queue.consume(|c| {
        // `normal` pushes `b` away from `a`.
        for (entity, dir) in [(c.a, -c.normal), (c.b, c.normal)] {
            if let Ok((mut v, mut p)) = balls.get_mut(entity) {
                let approach = v.0.dot(dir);
                if approach < 0.0 {
                    v.0 -= 1.2 * approach * dir;
                }
                p.0 += dir * (c.depth * 0.5);
            }
        }
        false
    });
}

/// The cloth springs back towards its flat rest shape; its border is pinned.
pub fn relax_cloth(mut cloth: Query<&mut Deformable, With<Cloth>>) {
    for mut d in &mut cloth {
        let row = CELLS as usize + 1;
        for (k, p) in d.positions_mut().iter_mut().enumerate() {
            let (i, j) = (k % row, k / row);
            let border = i == 0 || j == 0 || i == row - 1 || j == row - 1;
            p.y = if border { 0.0 } else { p.y * 0.9 };
        }
    }
}

/// Counts contacts and starts, and the lowest ball.
fn count(
    mut tally: ResMut<Tally>,
    queue: Res<ContactQueue>,
    mut started: MessageReader<CollisionStarted>,
    balls: Query<&Transform, With<Ball>>,
) {
    tally.started += started.read().count() as u64;
    tally.contacts += queue.len() as u64;
    tally.lowest_ball = balls
        .iter()
        .map(|t| t.translation.y)
        .fold(f32::MAX, f32::min);
}
