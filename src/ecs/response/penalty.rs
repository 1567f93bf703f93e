//! The penalty response for deformable meshes: contact triangles' vertices pushed apart.
use std::time::Instant;

use bevy_app::prelude::*;
use bevy_ecs::intern::Interned;
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;
use bevy_reflect::prelude::*;
use glam::Vec3;

use super::super::components::{ColliderPose, ColliderScale, Deformable};
use super::super::diagnostics::{CollisionDiagnostics, Stage};
use super::super::events::ContactQueue;
use super::super::schedule::CollisionSystems;
use super::response_schedule;

/// Settings of [`PenaltyResponsePlugin`] (a resource).
#[derive(Resource, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Resource, Clone, Debug, Default, PartialEq)]
pub struct PenaltySettings {
    /// Fraction of the penetration corrected per run (a stiffness).
    pub stiffness: f32,
    /// Largest displacement of a vertex per contact.
    pub max_step: f32,
}

impl Default for PenaltySettings {
    fn default() -> Self {
        Self {
            stiffness: 0.5,
            max_step: 0.05,
        }
    }
}

/// Penalty response for deformable meshes (see [`ContactQueue`]).
#[derive(Default)]
pub struct PenaltyResponsePlugin {
    /// The schedule of the collision plugin (`None`, the default: the schedule the
    /// [`StochasticCollisionPlugin`](crate::ecs::StochasticCollisionPlugin) was added to).
    pub schedule: Option<Interned<dyn ScheduleLabel>>,
    /// Initial settings.
    pub settings: PenaltySettings,
}

impl PenaltyResponsePlugin {
    /// The response in `schedule` with default settings (it must be the collision
    /// plugin's; [`Default`] takes it from the collision plugin).
    pub fn in_schedule(schedule: impl ScheduleLabel) -> Self {
        Self {
            schedule: Some(schedule.intern()),
            settings: PenaltySettings::default(),
        }
    }

    /// With these settings.
    pub fn with_settings(mut self, settings: PenaltySettings) -> Self {
        self.settings = settings;
        self
    }
}

impl Plugin for PenaltyResponsePlugin {
    fn build(&self, app: &mut App) {
        let schedule = response_schedule(app, self.schedule, "PenaltyResponsePlugin");
        super::super::reflect::register_response_types(app);
        app.insert_resource(self.settings)
            .init_resource::<ContactQueue>()
            .add_systems(
                schedule,
                penalty_response.in_set(CollisionSystems::Response),
            );
        app.world_mut().resource_mut::<ContactQueue>().enable();
    }
}

/// Pushes apart the vertices of deformable contact triangles, in priority order.
pub fn penalty_response(
    settings: Res<PenaltySettings>,
    mut queue: ResMut<ContactQueue>,
    mut meshes: Query<(&mut Deformable, &ColliderPose, Option<&ColliderScale>)>,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    let start = Instant::now();
    let n = queue.consume(|c| {
        let Some(tris) = c.triangles else {
            return false;
        };
        let (da, db) = (meshes.contains(c.a), meshes.contains(c.b));
        if !da && !db {
            return false;
        }
        let step = (c.depth * settings.stiffness).min(settings.max_step);
        // Both sides move half if both are deformable (or it is a self-contact).
        let share = if da && db { 0.5 } else { 1.0 };
        for (entity, tri, sign) in [(c.a, tris.a, -1.0f32), (c.b, tris.b, 1.0)] {
            if let Ok((mut mesh, pose, scale)) = meshes.get_mut(entity) {
                // World displacement to the mesh's unscaled local frame.
                let scale = scale.map_or(Vec3::ONE, |s| s.0);
                let local = pose.0.rotation.inverse() * (c.normal * (sign * step * share)) / scale;
                let t = mesh.mesh.mesh().triangles()[tri as usize];
                let p = mesh.positions_mut();
                for v in t {
                    p[v as usize] += local;
                }
            }
        }
        true
    });
    diag.record(Stage::Response, start.elapsed(), n as u64);
}
