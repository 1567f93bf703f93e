//! The penalty response for deformable meshes: contact triangles' vertices pushed apart, each
//! contact's correction spread to its corners by barycentric weights.

use bevy_app::prelude::*;
use bevy_ecs::entity::EntityHashMap;
use bevy_ecs::intern::Interned;
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;
use bevy_reflect::prelude::*;
use glam::Vec3;

use super::super::budget::BudgetController;
use super::super::components::{ColliderPose, ColliderScale, Deformable};
use super::super::diagnostics::{CollisionDiagnostics, Stage};
use super::super::schedule::CollisionSystems;
use super::queue::ContactQueue;
use super::response_schedule;
use crate::geometry::{Pose, barycentric_weights, spread_to_corners};

/// Settings of [`PenaltyResponsePlugin`] (a resource).
#[derive(Resource, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Resource, Clone, Debug, Default, PartialEq)]
pub struct PenaltySettings {
    /// Fraction of a contact's penetration corrected per run (a stiffness).
    pub stiffness: f32,
    /// Fraction of a contact's approach along its normal since the last run (how much closer
    /// its two sides came, at the contact point) added to the correction: 1 cancels the
    /// approach, 0 corrects the penetration only.
    pub damping: f32,
    /// Largest displacement of a vertex per run (world units), whatever the number of
    /// contacts around it.
    pub max_step: f32,
}

impl Default for PenaltySettings {
    fn default() -> Self {
        Self {
            stiffness: 0.5,
            damping: 1.0,
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

/// What the penalty response keeps between runs.
#[derive(Default)]
pub struct PenaltyState {
    /// Per deformable: its pose, scale and positions at the end of the last run.
    previous: EntityHashMap<Snapshot>,
    /// Per deformable touched in this run: the corrections gathered per vertex.
    pending: EntityHashMap<Pending>,
}

struct Snapshot {
    pose: Pose,
    scale: Vec3,
    positions: Vec<Vec3>,
    /// The run it was taken in (snapshots of despawned entities are dropped).
    run: u64,
}

impl Snapshot {
    /// Where vertex `v` was, world space (`None` if the mesh changed size).
    fn world(&self, v: u32) -> Option<Vec3> {
        let p = self.positions.get(v as usize)?;
        Some(self.pose.transform_point(*p * self.scale))
    }
}

/// Corrections of one deformable's vertices in a run, local frame (unscaled): per vertex the
/// sum of `weight · displacement` over its contacts and the sum of the weights.
#[derive(Default)]
struct Pending {
    sum: Vec<Vec3>,
    weight: Vec<f32>,
    touched: Vec<u32>,
}

impl Pending {
    fn add(&mut self, vertices: usize, v: u32, weight: f32, displacement: Vec3) {
        // A corner of weight 0 takes no part in the contact (and must not average to 0 / 0).
        let usable = weight > 0.0 && displacement.is_finite();
        if !usable {
            return;
        }
        if self.sum.len() != vertices {
            self.sum = vec![Vec3::ZERO; vertices];
            self.weight = vec![0.0; vertices];
            self.touched.clear();
        }
        let k = v as usize;
        if self.weight[k] == 0.0 {
            self.touched.push(v);
        }
        self.sum[k] += displacement * weight;
        self.weight[k] += weight;
    }

    /// Each touched vertex's weighted mean correction, bounded to `max_step` in world units
    /// (local corrections times `scale`), handed to `apply`; then empty again.
    fn drain(&mut self, scale: Vec3, max_step: f32, mut apply: impl FnMut(usize, Vec3)) {
        for &v in &self.touched {
            let k = v as usize;
            let mut d = self.sum[k] / self.weight[k];
            let world_len = (d * scale).length();
            if world_len > max_step {
                d *= max_step / world_len;
            }
            apply(k, d);
            self.sum[k] = Vec3::ZERO;
            self.weight[k] = 0.0;
        }
        self.touched.clear();
    }
}

/// One side of a contact: a deformable's triangle, where it is and where it was.
struct Side {
    corners: [u32; 3],
    /// The contact point's barycentric weights on the triangle.
    weights: [f64; 3],
    /// The contact point's motion since the last run, world space (zero without a snapshot).
    motion: Vec3,
}

/// Pushes apart deformable contact triangles, in priority order (Raghupathi et al.'s local
/// response): each contact asks its two sides to move apart along its normal by
/// `stiffness · depth + damping · approach` (the approach: how much closer the two sides came
/// at the contact point since the last run), capped at `max_step`, half each when both sides
/// are deformable. A side's share is spread to its triangle's corners by the contact point's
/// barycentric weights so that the point moves by exactly that share; the contacts around a
/// vertex are averaged by those weights (a vertex shared by many contact triangles moves once,
/// not once per triangle), and no vertex moves more than `max_step` in a run. A contact kept
/// from an earlier run has no depth: it only stops the approach.
pub fn penalty_response(
    settings: Res<PenaltySettings>,
    mut queue: ResMut<ContactQueue>,
    mut meshes: Query<(
        Entity,
        &mut Deformable,
        &ColliderPose,
        Option<&ColliderScale>,
    )>,
    mut budget: ResMut<BudgetController>,
    mut diag: ResMut<CollisionDiagnostics>,
    mut state: Local<PenaltyState>,
) {
    let start = budget.now();
    let run = budget.run();
    let state = &mut *state;
    let (previous, pending) = (&state.previous, &mut state.pending);
    let n = queue.consume(|c| {
        let Some(tris) = c.triangles else {
            return false;
        };
        let (da, db) = (meshes.contains(c.a), meshes.contains(c.b));
        if !da && !db {
            return false;
        }
        let side = |entity: Entity, triangle: u32| -> Option<Side> {
            let (_, mesh, pose, scale) = meshes.get(entity).ok()?;
            let scale = scale.map_or(Vec3::ONE, |s| s.0);
            let corners = *mesh.mesh.mesh().triangles().get(triangle as usize)?;
            let p = mesh.positions();
            let mut world = [Vec3::ZERO; 3];
            for (w, &v) in world.iter_mut().zip(&corners) {
                *w = pose.0.transform_point(*p.get(v as usize)? * scale);
            }
            let weights = barycentric_weights(c.point.as_dvec3(), &world.map(|x| x.as_dvec3()));
            let motion = previous.get(&entity).map_or(Vec3::ZERO, |snap| {
                (0..3).fold(Vec3::ZERO, |m, k| {
                    let before = snap.world(corners[k]).unwrap_or(world[k]);
                    m + (world[k] - before) * weights[k] as f32
                })
            });
            Some(Side {
                corners,
                weights,
                motion,
            })
        };
        let sides = [
            da.then(|| side(c.a, tris.a)).flatten(),
            db.then(|| side(c.b, tris.b)).flatten(),
        ];
        let motion = |s: &Option<Side>| s.as_ref().map_or(Vec3::ZERO, |s| s.motion);
        // How much closer the sides came along the normal (from a towards b).
        let approach = (-(motion(&sides[1]) - motion(&sides[0])).dot(c.normal)).max(0.0);
        let wanted = settings.stiffness * c.depth.max(0.0) + settings.damping * approach;
        let step = wanted.min(settings.max_step);
        // Nothing to do (also for a NaN depth or normal).
        let moves = step > 0.0;
        if !moves {
            return true;
        }
        // Both sides move half if both are deformable (or it is a self-contact).
        let share = if da && db { 0.5 } else { 1.0 };
        for ((entity, sign), s) in [(c.a, -1.0f32), (c.b, 1.0)].into_iter().zip(&sides) {
            let Some(s) = s else { continue };
            let Ok((_, mesh, pose, scale)) = meshes.get(entity) else {
                continue;
            };
            // World displacement to the mesh's unscaled local frame.
            let scale = scale.map_or(Vec3::ONE, |s| s.0);
            let local = pose.0.rotation.inverse() * (c.normal * (sign * step * share)) / scale;
            let corner_moves = spread_to_corners(s.weights, local);
            let vertices = mesh.positions().len();
            let acc = pending.entry(entity).or_default();
            for ((&v, &w), &d) in s.corners.iter().zip(&s.weights).zip(&corner_moves) {
                acc.add(vertices, v, w as f32, d);
            }
        }
        true
    });
    // Apply each vertex's weighted mean correction, bounded, then remember where everything is.
    for (entity, mut mesh, pose, scale) in &mut meshes {
        let scale = scale.map_or(Vec3::ONE, |s| s.0);
        if let Some(acc) = pending.get_mut(&entity)
            && !acc.touched.is_empty()
        {
            let p = mesh.positions_mut();
            acc.drain(scale, settings.max_step, |k, d| {
                if let Some(x) = p.get_mut(k) {
                    *x += d;
                }
            });
        }
        let snap = state.previous.entry(entity).or_insert_with(|| Snapshot {
            pose: pose.0,
            scale,
            positions: Vec::new(),
            run,
        });
        snap.pose = pose.0;
        snap.scale = scale;
        snap.run = run;
        snap.positions.clear();
        snap.positions.extend_from_slice(mesh.positions());
    }
    state.previous.retain(|_, s| s.run == run);
    state.pending.retain(|e, _| state.previous.contains_key(e));
    let time = budget.stage_done(Stage::Response, start);
    diag.record(Stage::Response, time, n as u64);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::barycentric_weights;
    use crate::mesh::generate;

    /// The corrections of `contacts` (triangle, point, world displacement), as the system
    /// gathers them, per vertex.
    fn resolve(
        mesh: &crate::mesh::TriMesh,
        contacts: &[(usize, Vec3, Vec3)],
        max_step: f32,
    ) -> Vec<Vec3> {
        let mut acc = Pending::default();
        let n = mesh.vertex_count();
        for &(t, point, delta) in contacts {
            let corners = mesh.triangles()[t];
            let tri = mesh.triangle(t).map(|p| p.as_dvec3());
            let w = barycentric_weights(point.as_dvec3(), &tri);
            let moves = spread_to_corners(w, delta);
            for k in 0..3 {
                acc.add(n, corners[k], w[k] as f32, moves[k]);
            }
        }
        let mut out = vec![Vec3::ZERO; n];
        acc.drain(Vec3::ONE, max_step, |k, d| out[k] = d);
        assert!(acc.touched.is_empty() && acc.weight.iter().all(|&w| w == 0.0));
        out
    }

    #[test]
    fn one_contact_moves_its_point_by_exactly_the_correction() {
        let sheet = generate::cloth_grid(1.0, 1.0, 4, 4);
        let t = 5;
        let tri = sheet.triangle(t);
        let point = tri[0] * 0.6 + tri[1] * 0.3 + tri[2] * 0.1;
        let delta = Vec3::new(0.0, 0.02, 0.0);
        let moved = resolve(&sheet, &[(t, point, delta)], 1.0);
        let w = barycentric_weights(point.as_dvec3(), &tri.map(|p| p.as_dvec3()));
        let corners = sheet.triangles()[t];
        let at_point: Vec3 = (0..3)
            .map(|k| moved[corners[k] as usize] * w[k] as f32)
            .sum();
        assert!((at_point - delta).length() < 1e-6, "{at_point:?}");
        // Only the triangle's corners move.
        let others = (0..sheet.vertex_count() as u32).filter(|v| !corners.contains(v));
        assert!(others.into_iter().all(|v| moved[v as usize] == Vec3::ZERO));
    }

    #[test]
    fn shared_vertices_move_once_not_once_per_contact() {
        // Every triangle of a sheet in contact at its centroid, all asking the same lift: the
        // sheet moves up by that lift, interior vertices (six triangles each) included.
        let sheet = generate::cloth_grid(1.0, 1.0, 6, 6);
        let delta = Vec3::new(0.0, 0.01, 0.0);
        let contacts: Vec<_> = (0..sheet.triangle_count())
            .map(|t| {
                let c = sheet.triangle(t);
                (t, (c[0] + c[1] + c[2]) / 3.0, delta)
            })
            .collect();
        let moved = resolve(&sheet, &contacts, 1.0);
        for (v, d) in moved.iter().enumerate() {
            assert!((*d - delta).length() < 1e-6, "vertex {v}: {d:?}");
        }
    }

    #[test]
    fn no_vertex_moves_more_than_the_step_bound() {
        let sheet = generate::cloth_grid(1.0, 1.0, 6, 6);
        // Contacts near corners ask their nearest corner for most of a large correction.
        let contacts: Vec<_> = (0..sheet.triangle_count())
            .map(|t| {
                let c = sheet.triangle(t);
                (
                    t,
                    c[0] * 0.98 + c[1] * 0.01 + c[2] * 0.01,
                    Vec3::new(0.0, 0.5, 0.0),
                )
            })
            .collect();
        let moved = resolve(&sheet, &contacts, 0.03);
        assert!(moved.iter().any(|d| d.length() > 0.029));
        assert!(moved.iter().all(|d| d.length() <= 0.03 + 1e-6));
    }
}
