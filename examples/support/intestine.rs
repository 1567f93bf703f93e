//! Intestine: a deforming intestine (the shared `small_intestine_100k` when present, else a
//! generated tube coiled so that its turns touch) with a peristaltic wave, self-collision and
//! the built-in penalty response.
use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use stochastic_collision::prelude::*;

use super::{Options, normalized, shared_mesh};

/// Default number of intestines.
pub const DEFAULT_COUNT: usize = 1;

/// The peristaltic wave: per vertex, its direction of motion and phase.
#[derive(Component, Debug, Clone)]
pub struct Peristalsis {
    normals: Vec<Vec3>,
    phase: Vec<f32>,
    time: f32,
    amplitude: f32,
}

/// The mesh: the shared intestine if present, else a coiled tube; and its name.
pub fn intestine_mesh() -> (TriMesh, &'static str) {
    match shared_mesh("small_intestine_100k.obj") {
        Some(m) => (normalized(&m, 6.0), "small_intestine_100k"),
        None => (coiled_tube(), "generated coiled tube"),
    }
}

/// A tube of radius 0.3 wound in a helix of pitch 0.58: its turns touch.
pub fn coiled_tube() -> TriMesh {
    let (radius, length, coil) = (0.3f32, 24.0f32, 1.5f32);
    let tube = generate::tube(radius, length, 24, 320, false);
    let pitch = 0.58;
    let positions = tube
        .positions()
        .iter()
        .map(|p| {
            let s = p.y + length / 2.0;
            let theta = s / coil;
            let centre = Vec3::new(
                coil * theta.cos(),
                pitch * theta / std::f32::consts::TAU,
                coil * theta.sin(),
            );
            let tangent = Vec3::new(
                -theta.sin(),
                pitch / (std::f32::consts::TAU * coil),
                theta.cos(),
            )
            .normalize();
            let normal = Vec3::new(theta.cos(), 0.0, theta.sin());
            let binormal = tangent.cross(normal);
            centre + normal * p.x + binormal * p.z
        })
        .collect();
    TriMesh::new(positions, tube.triangles().to_vec()).expect("a bent tube is a valid mesh")
}

fn vertex_normals(mesh: &TriMesh) -> Vec<Vec3> {
    let p = mesh.positions();
    let mut n = vec![Vec3::ZERO; p.len()];
    for t in mesh.triangles() {
        let f = (p[t[1] as usize] - p[t[0] as usize]).cross(p[t[2] as usize] - p[t[0] as usize]);
        for &v in t {
            n[v as usize] += f;
        }
    }
    n.into_iter().map(|v| v.normalize_or_zero()).collect()
}

pub fn setup(app: &mut App, options: &Options) {
    app.add_plugins(PenaltyResponsePlugin::default())
        .add_systems(PostUpdate, peristalsis.before(CollisionSystems::Prepare));
    let (mesh, _) = intestine_mesh();
    let size = mesh.aabb().extents().max_element();
    let normals = vertex_normals(&mesh);
    let phase: Vec<f32> = mesh
        .positions()
        .iter()
        .map(|p| 2.0 * (p.x + 0.5 * p.z) / size * 6.0)
        .collect();
    let world = app.world_mut();
    for k in 0..options.count(DEFAULT_COUNT) {
        world.spawn((
            Deformable::new(mesh.clone()),
            SelfCollision,
            // Self-collision by stochastic tracking, as in the surgery simulators.
            Fidelity::Tracking {
                pairs_per_frame: 256,
            },
            Peristalsis {
                normals: normals.clone(),
                phase: phase.clone(),
                time: 0.0,
                amplitude: 0.02 * size,
            },
            ColliderPose::from_translation(Vec3::new(k as f32 * size * 1.1, 0.0, 0.0)),
        ));
    }
}

/// Moves every vertex by the change of the wave since the last step (so the penalty
/// response's corrections persist).
fn peristalsis(mut q: Query<(&mut Deformable, &mut Peristalsis)>) {
    for (mut mesh, mut w) in &mut q {
        let w = &mut *w;
        let (t0, t1) = (w.time, w.time + 1.0 / 60.0);
        w.time = t1;
        let p = mesh.positions_mut();
        for ((x, n), ph) in p.iter_mut().zip(&w.normals).zip(&w.phase) {
            let wave = |t: f32| (ph - 4.0 * t).sin();
            *x += *n * (w.amplitude * (wave(t1) - wave(t0)));
        }
    }
}
