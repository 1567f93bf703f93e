//! The impulse response for simple rigid bodies: integration under gravity, impulses at the
//! contact point (restitution, Coulomb friction, turning by the inertia from the mesh), linear
//! position correction, a body moved back to its time of impact for a contact found by the
//! continuous query, sleep.
use std::collections::HashMap;

use bevy_ecs::entity::EntityHashSet;
use std::sync::{Arc, Weak};

use bevy_app::prelude::*;
use bevy_ecs::intern::Interned;
use bevy_ecs::prelude::*;
use bevy_ecs::query::QueryItem;
use bevy_ecs::schedule::ScheduleLabel;
use bevy_reflect::prelude::*;
use bevy_time::Time;
use glam::{Mat3, Quat, Vec3};

use super::super::budget::BudgetController;
use super::super::components::{ColliderPose, ColliderScale, Deformable, MeshCollider};
use super::super::config::CollisionConfig;
use super::super::diagnostics::{CollisionDiagnostics, Stage};
use super::super::events::Contact;
use super::super::narrow_phase::Method;
use super::super::prepare::{Parents, Placement, place, shift};
use super::super::schedule::CollisionSystems;
use super::body::{BodyAngularVelocity, BodyInertia, BodyMass, BodyVelocity, InertiaSource, Rest};
use super::queue::ContactQueue;
use super::response_schedule;
use crate::adb::AdbTree;
use crate::geometry::Pose;
use crate::mesh::MassProperties;

/// The largest angle a body turns in one step, radians: faster spins are clamped (one contact
/// point per pair and a step of 1/60 s cannot resolve them, and they would be unstable).
pub const MAX_TURN_PER_STEP: f32 = 0.5;

/// Settings of [`ImpulseResponsePlugin`] (a resource).
#[derive(Resource, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Resource, Clone, Debug, Default, PartialEq)]
pub struct ImpulseSettings {
    /// Gravity applied to bodies with [`BodyVelocity`].
    pub gravity: Vec3,
    /// Time step of the integration. `None` (default): bevy_time's `Time` of the schedule
    /// (`Time<Fixed>`'s step in `FixedPostUpdate`, the frame's delta elsewhere), or
    /// [`DEFAULT_STEP`] in an app without `TimePlugin` or before time has advanced.
    pub dt: Option<f32>,
    /// Bounciness in `[0, 1]`, for contacts approaching faster than gravity accelerates in
    /// two steps (slower ones, a body resting on another, do not bounce).
    pub restitution: f32,
    /// Fraction of the penetration corrected per run.
    pub correction: f32,
    /// Penetration left uncorrected (avoids jitter).
    pub slop: f32,
    /// Linear velocity damping per second (air drag, rolling friction).
    pub damping: f32,
    /// Angular velocity damping per second.
    pub angular_damping: f32,
    /// Coulomb friction coefficient at contacts.
    pub friction: f32,
    /// Linear speed below which a body counts as still (with [`ImpulseSettings::sleep_spin`]).
    pub sleep_speed: f32,
    /// Angular speed (radians per second) below which a body counts as still (with
    /// [`ImpulseSettings::sleep_speed`]; 0.5 as rapier's default).
    pub sleep_spin: f32,
    /// Runs a body must stay still to fall asleep (0: never sleeps).
    pub sleep_frames: u32,
    /// Approach speed at which an awake body wakes a sleeping one.
    pub wake_speed: f32,
}

/// The time step without a `Time` to read: `Time<Fixed>`'s default (64 Hz).
pub const DEFAULT_STEP: f32 = 1.0 / 64.0;

impl ImpulseSettings {
    /// The time step of this run (see [`ImpulseSettings::dt`]).
    pub fn step(&self, time: Option<&Time>) -> f32 {
        self.dt.unwrap_or_else(|| {
            let delta = time.map_or(0.0, Time::delta_secs);
            if delta > 0.0 { delta } else { DEFAULT_STEP }
        })
    }
}

impl Default for ImpulseSettings {
    fn default() -> Self {
        Self {
            gravity: Vec3::new(0.0, -9.81, 0.0),
            dt: None,
            restitution: 0.2,
            correction: 0.4,
            slop: 0.005,
            damping: 0.1,
            angular_damping: 2.0,
            friction: 0.5,
            sleep_speed: 0.2,
            sleep_spin: 0.5,
            sleep_frames: 30,
            wake_speed: 0.5,
        }
    }
}

/// Impulse response for simple rigid bodies (see [`ContactQueue`]): bodies move and turn
/// under gravity, contacts push them apart at the contact point. Add it after
/// [`StochasticCollisionPlugin`](crate::ecs::StochasticCollisionPlugin); `default()` runs it in
/// the collision plugin's schedule.
#[derive(Default)]
pub struct ImpulseResponsePlugin {
    /// The schedule of the collision plugin (`None`, the default: the schedule the
    /// [`StochasticCollisionPlugin`](crate::ecs::StochasticCollisionPlugin) was added to).
    pub schedule: Option<Interned<dyn ScheduleLabel>>,
    /// Initial settings.
    pub settings: ImpulseSettings,
}

impl ImpulseResponsePlugin {
    /// The response in `schedule` with default settings (it must be the collision
    /// plugin's; [`Default`] takes it from the collision plugin).
    pub fn in_schedule(schedule: impl ScheduleLabel) -> Self {
        Self {
            schedule: Some(schedule.intern()),
            settings: ImpulseSettings::default(),
        }
    }

    /// With these settings.
    pub fn with_settings(mut self, settings: ImpulseSettings) -> Self {
        self.settings = settings;
        self
    }
}

impl Plugin for ImpulseResponsePlugin {
    fn build(&self, app: &mut App) {
        let schedule = response_schedule(app, self.schedule, "ImpulseResponsePlugin");
        // Turning bodies needs contacts at the centre of their contact regions.
        if let Some(mut config) = app.world_mut().get_resource_mut::<CollisionConfig>() {
            config.contact_regions = true;
        }
        super::super::reflect::register_response_types(app);
        app.insert_resource(self.settings)
            .init_resource::<ContactQueue>()
            .add_systems(
                schedule,
                (
                    integrate_velocities.before(CollisionSystems::Prepare),
                    // After Prepare: the scale of this run is known.
                    (update_body_inertia, impulse_response, sleep_bodies)
                        .chain()
                        .in_set(CollisionSystems::Response),
                ),
            );
        app.world_mut().resource_mut::<ContactQueue>().enable();
    }
}

/// Mass properties of the meshes in use, by tree and scale (one mesh shared by many bodies is
/// integrated once).
#[derive(Default)]
pub struct InertiaCache {
    entries: HashMap<(usize, [u32; 3]), (Weak<AdbTree>, MassProperties)>,
    pruned_at: usize,
}

impl InertiaCache {
    fn get(&mut self, tree: &Arc<AdbTree>, scale: Vec3) -> MassProperties {
        let key = (
            Arc::as_ptr(tree) as usize,
            scale.to_array().map(f32::to_bits),
        );
        if let Some((weak, properties)) = self.entries.get(&key)
            && weak.upgrade().is_some_and(|t| Arc::ptr_eq(&t, tree))
        {
            return *properties;
        }
        let properties = tree.collision_mesh().mesh().mass_properties(scale);
        self.entries.insert(key, (Arc::downgrade(tree), properties));
        if self.entries.len() > 2 * self.pruned_at.max(32) {
            self.entries.retain(|_, (weak, _)| weak.strong_count() > 0);
            self.pruned_at = self.entries.len();
        }
        properties
    }
}

/// Bodies whose inertia must be (re)computed from their mesh.
type InertiaChanged = Or<(
    Added<BodyInertia>,
    Changed<MeshCollider>,
    Changed<ColliderScale>,
)>;

/// Computes [`BodyInertia`] from the collider's mesh and scale for bodies whose inertia comes
/// from the mesh ([`InertiaSource::FromMesh`]): new bodies, and bodies whose mesh or scale
/// changed. Runs in the Response stage, before the impulses (after Prepare has set this
/// run's scale). A body without a collider yet keeps a zero inverse inertia (contacts do not
/// turn it) until its collider arrives.
pub fn update_body_inertia(
    mut cache: Local<InertiaCache>,
    mut bodies: Query<
        (
            &mut BodyInertia,
            Option<&MeshCollider>,
            Option<&ColliderScale>,
        ),
        InertiaChanged,
    >,
) {
    for (mut inertia, collider, scale) in &mut bodies {
        if inertia.source != InertiaSource::FromMesh {
            continue;
        }
        if let Some(collider) = collider {
            let scale = scale.map_or(Vec3::ONE, |s| s.0);
            *inertia = BodyInertia::computed(&cache.get(collider.tree(), scale));
        }
    }
}

/// Moves the awake bodies with [`BodyVelocity`] by one step under gravity and turns them by
/// their [`BodyAngularVelocity`] about their centre of mass: their pose, and their
/// `Transform` when they have one (what the game draws, and where the next run reads the
/// pose).
pub fn integrate_velocities(
    settings: Res<ImpulseSettings>,
    time: Option<Res<Time>>,
    mut q: Query<(
        &mut BodyVelocity,
        &mut BodyAngularVelocity,
        &BodyInertia,
        &mut ColliderPose,
        &Rest,
        Placement,
    )>,
    parents: Parents,
) {
    let dt = settings.step(time.as_deref());
    let keep = (1.0 - settings.damping * dt).clamp(0.0, 1.0);
    let keep_turning = (1.0 - settings.angular_damping * dt).clamp(0.0, 1.0);
    let max_spin = MAX_TURN_PER_STEP / dt;
    for (mut v, mut w, inertia, mut pose, rest, mut placement) in &mut q {
        if rest.asleep {
            continue;
        }
        v.0 = (v.0 + settings.gravity * dt) * keep;
        if inertia.source == InertiaSource::Locked {
            w.0 = Vec3::ZERO;
        } else {
            w.0 = (w.0 * keep_turning).clamp_length_max(max_spin);
        }
        if w.0 == Vec3::ZERO {
            shift(&mut pose, &mut placement, &parents, v.0 * dt);
            continue;
        }
        let p = pose.0;
        let center = p.translation + p.rotation * inertia.center;
        let rotation = (Quat::from_scaled_axis(w.0 * dt) * p.rotation).normalize();
        let translation = center + v.0 * dt - rotation * inertia.center;
        place(
            &mut pose,
            &mut placement,
            &parents,
            Pose::new(translation, rotation),
        );
    }
}

/// Whether a body's inertia lets it turn.
fn turns(inertia: &BodyInertia) -> bool {
    inertia.ready
        && inertia.source != InertiaSource::Locked
        && inertia.inverse_inertia != Mat3::ZERO
}

/// Counts still runs and puts bodies to sleep (after the impulses).
pub fn sleep_bodies(
    settings: Res<ImpulseSettings>,
    mut q: Query<(&mut BodyVelocity, &mut BodyAngularVelocity, &mut Rest)>,
) {
    if settings.sleep_frames == 0 {
        return;
    }
    for (mut v, mut w, mut rest) in &mut q {
        if rest.asleep {
            continue;
        }
        if v.0.length() < settings.sleep_speed && w.0.length() < settings.sleep_spin {
            rest.still_frames += 1;
            if rest.still_frames >= settings.sleep_frames {
                rest.asleep = true;
                v.0 = Vec3::ZERO;
                w.0 = Vec3::ZERO;
            }
        } else {
            rest.still_frames = 0;
        }
    }
}

/// Resolves rigid contacts (neither entity deformable) in priority order.
#[allow(clippy::too_many_arguments)]
pub fn impulse_response(
    settings: Res<ImpulseSettings>,
    time: Option<Res<Time>>,
    mut queue: ResMut<ContactQueue>,
    mut bodies: Query<BodyData>,
    deformables: Query<(), With<Deformable>>,
    parents: Parents,
    mut budget: ResMut<BudgetController>,
    mut diag: ResMut<CollisionDiagnostics>,
    mut rewound: Local<EntityHashSet>,
) {
    let start = budget.now();
    // Contacts approaching slower than gravity accelerates in two steps are resting: no bounce.
    let dt = settings.step(time.as_deref());
    let resting_speed = 2.0 * settings.gravity.length() * dt;
    let run = budget.run();
    rewound.clear();
    let n = queue.consume(|c| {
        if c.a == c.b || deformables.contains(c.a) || deformables.contains(c.b) {
            return false;
        }
        if let Ok([mut a, mut b]) = bodies.get_many_mut([c.a, c.b]) {
            if let Some(t) = c.time_of_impact.filter(|_| c.frame == run) {
                for (entity, body) in [(c.a, &mut a), (c.b, &mut b)] {
                    if rewound.insert(entity) {
                        rewind(body, t, dt, &parents);
                    }
                }
            }
            resolve(&settings, (resting_speed, run), c, a, b, &parents);
        }
        true
    });
    let time = budget.stage_done(Stage::Response, start);
    diag.record(Stage::Response, time, n as u64);
}

/// What the impulse response reads and writes of a body.
type BodyData = (
    &'static mut ColliderPose,
    Option<&'static mut BodyVelocity>,
    Option<&'static mut BodyAngularVelocity>,
    Option<&'static BodyInertia>,
    Option<&'static BodyMass>,
    Option<&'static mut Rest>,
    Placement,
);

type Body<'a> = QueryItem<'a, 'a, BodyData>;

/// A body's state at a contact: how it answers an impulse there.
struct AtContact {
    inverse_mass: f32,
    /// World inverse inertia divided by the mass (zero: does not turn).
    inverse_inertia: Mat3,
    /// From the centre of mass to the contact point.
    arm: Vec3,
    velocity: Vec3,
    spin: Vec3,
}

impl AtContact {
    /// The body at `point`; a body that may not `turn` there answers as if it could not.
    fn of(body: &Body<'_>, point: Vec3, turn: bool) -> AtContact {
        let (pose, v, w, inertia, m, rest, _) = body;
        let asleep = rest.as_ref().is_some_and(|r| r.asleep);
        let inverse_mass = match (v, m) {
            _ if asleep => 0.0,
            (None, _) => 0.0,
            (Some(_), Some(m)) if m.0 > 0.0 => 1.0 / m.0,
            (Some(_), _) => 1.0,
        };
        // A body that does not turn at this contact answers at its centre of mass: neither
        // its spin nor the point (which may lie anywhere) enters.
        let (arm, inverse_inertia) = match inertia {
            Some(i) if turn && inverse_mass > 0.0 && turns(i) => (
                point - (pose.0.translation + pose.0.rotation * i.center),
                i.world_inverse(pose.0.rotation, inverse_mass),
            ),
            _ => (Vec3::ZERO, Mat3::ZERO),
        };
        AtContact {
            inverse_mass,
            inverse_inertia,
            arm,
            velocity: v.as_ref().map_or(Vec3::ZERO, |v| v.0),
            spin: w.as_ref().map_or(Vec3::ZERO, |w| w.0),
        }
    }

    /// Velocity of the body's material point at the contact.
    fn point_velocity(&self) -> Vec3 {
        self.velocity + self.spin.cross(self.arm)
    }

    /// How much an impulse along `dir` changes the point's velocity along `dir`.
    fn response(&self, dir: Vec3) -> f32 {
        self.inverse_mass + dir.dot((self.inverse_inertia * self.arm.cross(dir)).cross(self.arm))
    }

    /// Applies `impulse` at the contact.
    fn apply(&self, body: &mut Body<'_>, impulse: Vec3) {
        if self.inverse_mass == 0.0 {
            return;
        }
        if let Some(v) = body.1.as_mut() {
            v.0 += impulse * self.inverse_mass;
        }
        if let Some(w) = body.2.as_mut() {
            w.0 += self.inverse_inertia * self.arm.cross(impulse);
        }
    }
}

/// Wakes a sleeping body that an awake one approaches faster than the wake speed.
fn wake_if_hit<'w>(s: &ImpulseSettings, approach: f32, a: &mut Body<'w>, b: &mut Body<'w>) {
    if approach > s.wake_speed {
        for r in [a.5.as_mut(), b.5.as_mut()].into_iter().flatten() {
            if r.asleep {
                r.wake();
            }
        }
    }
}

/// Moves an awake body with a velocity back to where it was at `time_of_impact` of this
/// run's step of `dt` (along its velocity; its turn is not undone): a contact found by the
/// continuous query, which the body may have passed through since.
fn rewind(body: &mut Body<'_>, time_of_impact: f32, dt: f32, parents: &Parents) {
    let (pose, v, _, _, _, rest, placement) = body;
    if rest.as_ref().is_some_and(|r| r.asleep) {
        return;
    }
    if let Some(v) = v {
        let back = -v.0 * dt * (1.0 - time_of_impact.clamp(0.0, 1.0));
        if back != Vec3::ZERO {
            shift(pose, placement, parents, back);
        }
    }
}

/// Resolves one contact of this `run`'s queue.
fn resolve<'w>(
    s: &ImpulseSettings,
    (resting_speed, run): (f32, u64),
    c: &Contact,
    mut a: Body<'w>,
    mut b: Body<'w>,
    parents: &Parents,
) {
    let n = c.normal;
    if !n.is_finite() || n == Vec3::ZERO || !c.point.is_finite() {
        return;
    }
    // Only an exact contact found in this run (the centre of its region, see
    // `CollisionConfig::contact_regions`) has a point worth turning about; an ADB witness
    // lies anywhere in its region, a node estimate, a bounds overlap or an interpenetration
    // sample anywhere near it, a kept answer's point where the bodies were: they push
    // without turning.
    let exact = c.method == Method::Exact && c.triangles.is_some() && c.frame == run;
    let approach = {
        let (at_a, at_b) = (
            AtContact::of(&a, c.point, exact),
            AtContact::of(&b, c.point, exact),
        );
        -(at_b.point_velocity() - at_a.point_velocity()).dot(n)
    };
    wake_if_hit(s, approach, &mut a, &mut b);
    // A resting contact (approaching slower than gravity accelerates in two steps) pushes
    // without turning: one contact point per pair cannot balance a body at rest, and its
    // noise would rock it forever.
    let turn = exact && approach > resting_speed;
    let (at_a, at_b) = (
        AtContact::of(&a, c.point, turn),
        AtContact::of(&b, c.point, turn),
    );
    let inv = at_a.inverse_mass + at_b.inverse_mass;
    if inv == 0.0 {
        return;
    }
    let rel = at_b.point_velocity() - at_a.point_velocity();
    let vn = rel.dot(n);
    if vn < 0.0 {
        let restitution = if -vn > resting_speed {
            s.restitution
        } else {
            0.0
        };
        let j = -(1.0 + restitution) * vn / (at_a.response(n) + at_b.response(n));
        // Friction: remove tangential relative velocity, at most `friction × j`.
        let vt = rel - n * vn;
        let t = vt.normalize_or_zero();
        let jt = if t == Vec3::ZERO {
            0.0
        } else {
            (vt.length() / (at_a.response(t) + at_b.response(t))).min(s.friction * j)
        };
        let impulse = n * j - t * jt;
        at_a.apply(&mut a, -impulse);
        at_b.apply(&mut b, impulse);
    }
    let push = (c.depth - s.slop).max(0.0) * s.correction / inv;
    if push > 0.0 {
        let (pa, _, _, _, _, _, place_a) = &mut a;
        if at_a.inverse_mass > 0.0 {
            shift(pa, place_a, parents, -n * push * at_a.inverse_mass);
        }
        let (pb, _, _, _, _, _, place_b) = &mut b;
        if at_b.inverse_mass > 0.0 {
            shift(pb, place_b, parents, n * push * at_b.inverse_mass);
        }
    }
}
