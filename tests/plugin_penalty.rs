//! The penalty response for deformables in a real app (time, transforms, the default
//! schedule): a scaled sheet lowered onto a rigid ball every frame. The response's step bound
//! holds per vertex, whatever the number of contacts around it, and its velocity term keeps
//! the sheet from sinking into the ball where the depth term alone lets it, from above and
//! from below (where the sheet's face normals point into the ball). A sheet wholly inside a
//! box, which no surface crossing reports, is pushed out through the nearest face.
mod plugin_support;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_transform::components::Transform;
use plugin_support::*;
use stochastic_collision::ecs::PenaltySettings;
use stochastic_collision::prelude::*;

/// Lowers a deformable's vertices by this much per frame (local units).
#[derive(Component)]
struct Lowered(f32);

/// The sheet's positions just before the response, and the largest world displacement the
/// response gave a vertex in any run.
#[derive(Resource, Default)]
struct Watch {
    before: Vec<Vec3>,
    largest_move: f32,
    moved_runs: usize,
}

fn lower(mut q: Query<(&mut Deformable, &Lowered)>) {
    for (mut mesh, lowered) in &mut q {
        for p in mesh.positions_mut() {
            p.y -= lowered.0;
        }
    }
}

fn before_response(mut watch: ResMut<Watch>, q: Query<&Deformable, With<Lowered>>) {
    if let Ok(mesh) = q.single() {
        watch.before.clear();
        watch.before.extend_from_slice(mesh.positions());
    }
}

fn after_response(mut watch: ResMut<Watch>, q: Query<(&Deformable, &Transform), With<Lowered>>) {
    let Ok((mesh, transform)) = q.single() else {
        return;
    };
    let largest = mesh
        .positions()
        .iter()
        .zip(&watch.before)
        .map(|(p, b)| ((*p - *b) * transform.scale).length())
        .fold(0.0f32, f32::max);
    watch.largest_move = watch.largest_move.max(largest);
    watch.moved_runs += usize::from(largest > 0.0);
}

const RADIUS: f32 = 0.5;
const SCALE: f32 = 1.5;
/// World descent per frame: 0.0075 local units at scale 1.5.
const LOCAL_SPEED: f32 = 0.0075;

/// Runs the sheet onto the ball for `frames` with `settings`, from above (or from below,
/// rising: then the sheet's face normals point into the ball); the deepest any sheet vertex
/// got inside the ball's inscribed sphere, and the watch.
fn onto_ball(settings: PenaltySettings, frames: usize, from_below: bool) -> (f32, Watch) {
    let side = if from_below { -1.0 } else { 1.0 };
    let mut app = game();
    app.add_plugins(PenaltyResponsePlugin::default().with_settings(settings))
        .init_resource::<Watch>()
        .add_systems(FixedUpdate, lower)
        .add_systems(
            FixedPostUpdate,
            (
                before_response.before(CollisionSystems::Response),
                after_response.after(CollisionSystems::Response),
            ),
        );
    spawn(
        &mut app,
        (
            MeshCollider::new(generate::icosphere(RADIUS, 3)),
            Transform::default(),
            Fidelity::Exact,
        ),
    );
    let sheet = spawn(
        &mut app,
        (
            Deformable::new(generate::cloth_grid(1.0, 1.0, 16, 16)),
            Lowered(side * LOCAL_SPEED),
            Transform::from_xyz(0.05, side * (RADIUS + 0.05), -0.03).with_scale(Vec3::splat(SCALE)),
        ),
    );
    // The icosphere's faces lie inside its corners' sphere: measure against the inscribed one.
    let inscribed = RADIUS * 0.98;
    let mut deepest = 0.0f32;
    for _ in 0..frames {
        app.update();
        let world = app.world();
        let (mesh, t) = (
            world.get::<Deformable>(sheet).unwrap(),
            world.get::<Transform>(sheet).unwrap(),
        );
        assert!(mesh.error().is_none(), "{:?}", mesh.error());
        for p in mesh.positions() {
            assert!(p.is_finite(), "the response wrote {p:?}");
            let x = t.transform_point(*p);
            deepest = deepest.max(inscribed - x.length());
        }
    }
    let watch = app.world_mut().remove_resource::<Watch>().unwrap();
    (deepest, watch)
}

#[test]
fn the_step_bound_holds_per_vertex_in_a_scaled_sheet() {
    // A strong response with a small bound: many contacts around each vertex ask for more.
    let settings = PenaltySettings {
        stiffness: 1.0,
        damping: 1.0,
        max_step: 0.004,
    };
    let (_, watch) = onto_ball(settings, 60, false);
    assert!(
        watch.moved_runs > 10,
        "the response ran: {}",
        watch.moved_runs
    );
    assert!(
        watch.largest_move <= settings.max_step * (1.0 + 1e-4),
        "a vertex moved {} in one run (bound {})",
        watch.largest_move,
        settings.max_step
    );
    assert!(watch.largest_move > 0.5 * settings.max_step);
}

#[test]
fn cancelling_the_approach_keeps_the_sheet_out_of_the_ball() {
    let frames = 90; // 0.0113 a frame: 1.0 in all, twice the ball's radius
    let depth_only = PenaltySettings {
        damping: 0.0,
        ..PenaltySettings::default()
    };
    for from_below in [false, true] {
        let (sunk, _) = onto_ball(depth_only, frames, from_below);
        let (held, _) = onto_ball(PenaltySettings::default(), frames, from_below);
        // Without the velocity term each frame's correction lags the motion and the sheet
        // sinks until its vertices are wholly inside the ball, where their own contacts push
        // them back out; with it, the sheet stays within two frames' motion of the surface.
        let per_frame = LOCAL_SPEED * SCALE;
        assert!(
            held < 2.0 * per_frame,
            "with damping the sheet sank {held} (a frame's motion: {per_frame}), from below: {from_below}"
        );
        assert!(
            held < 0.5 * sunk && sunk < 0.2 * RADIUS,
            "damping 1 sank {held}, damping 0 sank {sunk}, from below: {from_below}"
        );
    }
}

/// A sheet wholly inside a floor box, just under its top face (no triangle crosses the
/// surface): its vertices' own contacts push it up out of the box, and it stays out.
#[test]
fn a_sheet_wholly_inside_a_box_is_pushed_out() {
    let mut app = game();
    app.add_plugins(PenaltyResponsePlugin::default());
    spawn(
        &mut app,
        (
            MeshCollider::new(generate::cuboid(Vec3::new(2.0, 0.5, 2.0), 2)),
            Transform::from_xyz(0.0, -0.5, 0.0),
            Fidelity::Exact,
        ),
    );
    // Top face at y = 0; the sheet 0.04 below it, rotated and off-centre.
    let sheet = spawn(
        &mut app,
        (
            Deformable::new(generate::cloth_grid(1.0, 1.0, 8, 8)),
            Transform::from_xyz(0.3, -0.04, -0.2).with_rotation(Quat::from_rotation_y(0.3)),
            Fidelity::Exact,
        ),
    );
    let lowest = |app: &mut App| {
        let world = app.world();
        let (mesh, t) = (
            world.get::<Deformable>(sheet).unwrap(),
            world.get::<Transform>(sheet).unwrap(),
        );
        mesh.positions()
            .iter()
            .map(|p| t.transform_point(*p).y)
            .fold(f32::INFINITY, f32::min)
    };
    assert!(lowest(&mut app) < -0.039);
    // Each contact corrects half its depth (the default stiffness), a vertex gets one every
    // other run (64 contacts a run for 81 vertices inside): an eighth of the depth is left
    // after 10 runs, under a thousandth of a unit after 30, and it stays out.
    for _ in 0..10 {
        app.update();
    }
    let after = lowest(&mut app);
    assert!(
        after > -0.04 / 8.0,
        "the sheet's lowest vertex is still at {after}"
    );
    for _ in 0..20 {
        app.update();
    }
    let after = lowest(&mut app);
    assert!(
        after > -1e-3,
        "the sheet's lowest vertex is still at {after}"
    );
    for _ in 0..10 {
        app.update();
    }
    assert!(lowest(&mut app) > -1e-3);
}
