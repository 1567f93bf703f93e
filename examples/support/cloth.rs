//! Cloth: sheets (deformable grids with self-collision) falling onto a ball and the floor,
//! folding onto themselves; a small position-based cloth solver moves the vertices, the
//! built-in penalty response pushes contacts apart.
use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use stochastic_collision::ecs::PenaltySettings;
use stochastic_collision::prelude::*;

use super::Options;

/// Default number of sheets.
pub const DEFAULT_SHEETS: usize = 2;

const DT: f32 = 1.0 / 60.0;

/// A radius inside every face of the ball (an icosphere of radius 0.5, 3 subdivisions, whose
/// faces come within about 0.002 of its corners' sphere).
pub const BALL_INSCRIBED: f32 = 0.49;
/// Height of the floor's top face.
pub const FLOOR_TOP: f32 = -0.6;
/// The penalty response's largest vertex displacement per run in this scene.
pub const MAX_STEP: f32 = 0.2;

/// Verlet state of a sheet: previous positions and the grid's edges with rest lengths.
#[derive(Component, Debug, Clone)]
pub struct ClothState {
    prev: Vec<Vec3>,
    edges: Vec<(u32, u32, f32)>,
}

impl ClothState {
    fn new(mesh: &TriMesh) -> Self {
        let p = mesh.positions();
        let mut edges: Vec<(u32, u32, f32)> = mesh
            .triangles()
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .map(|(a, b)| (a.min(b), a.max(b), 0.0))
            .collect();
        edges.sort_by_key(|e| (e.0, e.1));
        edges.dedup_by_key(|e| (e.0, e.1));
        for e in &mut edges {
            e.2 = p[e.0 as usize].distance(p[e.1 as usize]);
        }
        Self {
            prev: p.to_vec(),
            edges,
        }
    }
}

pub fn setup(app: &mut App, options: &Options) {
    // A sheet reaches the ball at about 0.06 units a frame and the floor at 0.09: the
    // response may move a vertex by more than that in a frame, so a contact can stop it where
    // it touches (the default, 0.05, lets it sink a little every frame).
    let penalty = PenaltySettings {
        max_step: MAX_STEP,
        ..PenaltySettings::default()
    };
    app.add_plugins(PenaltyResponsePlugin::default().with_settings(penalty))
        .add_systems(PostUpdate, step_cloth.before(CollisionSystems::Prepare));
    let world = app.world_mut();
    world.spawn((
        MeshCollider::new(generate::icosphere(0.5, 3)),
        ColliderPose::from_translation(Vec3::ZERO),
        Fidelity::Exact,
    ));
    world.spawn((
        MeshCollider::new(generate::cuboid(Vec3::new(3.0, 0.25, 3.0), 4)),
        ColliderPose::from_translation(Vec3::new(0.0, FLOOR_TOP - 0.25, 0.0)),
        Fidelity::Exact,
    ));
    for k in 0..options.count(DEFAULT_SHEETS) {
        let mesh = generate::cloth_grid(2.0, 2.0, 20, 20);
        let state = ClothState::new(&mesh);
        let turn = Quat::from_rotation_y(0.4 * k as f32);
        world.spawn((
            Deformable::new(mesh),
            state,
            SelfCollision,
            // Self-collision by stochastic tracking (the ball and the floor stay exact).
            Fidelity::Tracking {
                pairs_per_frame: 16,
            },
            ColliderPose(Pose::new(
                Vec3::new(0.1 * k as f32, 0.8 + 0.3 * k as f32, 0.0),
                turn,
            )),
        ));
    }
}

/// Verlet integration under gravity, then the edge lengths restored (a few iterations).
fn step_cloth(mut q: Query<(&mut Deformable, &mut ClothState, &ColliderPose)>) {
    for (mut cloth, mut state, pose) in &mut q {
        let gravity = pose.0.rotation.inverse() * Vec3::new(0.0, -9.81, 0.0);
        let state = &mut *state;
        let p = cloth.positions_mut();
        for (x, prev) in p.iter_mut().zip(&mut state.prev) {
            let v = (*x - *prev) * 0.99;
            *prev = *x;
            *x += v + gravity * DT * DT;
        }
        for _ in 0..4 {
            for &(a, b, rest) in &state.edges {
                let d = p[b as usize] - p[a as usize];
                let len = d.length();
                if len > 1e-6 {
                    let fix = d * (0.5 * (len - rest) / len);
                    p[a as usize] += fix;
                    p[b as usize] -= fix;
                }
            }
        }
    }
}
