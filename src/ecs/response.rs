//! Response stage: built-in responses that consume the [`ContactQueue`], as optional plugins.
//!
//! - [`ImpulseResponsePlugin`]: simple rigid bodies ([`BodyVelocity`], optional [`BodyMass`]):
//!   integrates velocities under gravity before the pipeline, and resolves contacts with
//!   restitution impulses and position correction. Bodies without `BodyVelocity` are static.
//! - [`PenaltyResponsePlugin`]: deformable meshes: pushes the vertices of the contact triangles
//!   apart along the contact normal (position correction), as a penalty force would.
//!
//! Each consumes contacts in priority order within the response budget
//! ([`CollisionConfig::response_budget`](super::CollisionConfig::response_budget)); the
//! contacts it leaves stay queued for the next run.
//!
//! # Writing your own response
//! A system in [`CollisionSystems::Response`] that takes the contacts it handles:
//! ```
//! use bevy_app::prelude::*;
//! use bevy_ecs::prelude::*;
//! use stochastic_collision::prelude::*;
//!
//! #[derive(Component)]
//! struct Health(f32);
//!
//! fn damage(mut queue: ResMut<ContactQueue>, mut health: Query<&mut Health>) {
//!     queue.consume(|c| match health.get_mut(c.b) {
//!         Ok(mut h) => {
//!             h.0 -= c.depth * c.probability as f32;
//!             true // consumed
//!         }
//!         Err(_) => false, // not ours: leave it to other responses
//!     });
//! }
//!
//! let mut app = App::new();
//! app.add_plugins(StochasticCollisionPlugin::in_schedule(PostUpdate))
//!     .add_systems(PostUpdate, damage.in_set(CollisionSystems::Response));
//! app.world_mut().resource_mut::<ContactQueue>().enable();
//! ```
//!
//! [`CollisionSystems::Response`]: super::CollisionSystems::Response
use std::time::Instant;

use bevy_app::prelude::*;
use bevy_ecs::intern::Interned;
use bevy_ecs::prelude::*;
use bevy_ecs::schedule::ScheduleLabel;
use bevy_reflect::prelude::*;
use glam::Vec3;

use bevy_ecs::query::QueryItem;
use bevy_time::Time;

use super::components::{ColliderPose, ColliderScale, Deformable};
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::events::{Contact, ContactQueue};
use super::prepare::{Parents, Placement, shift};
use super::schedule::{CollisionSchedule, CollisionSystems};

/// Linear velocity of a simple rigid body (units per second).
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
#[require(Rest)]
pub struct BodyVelocity(pub Vec3);

/// Sleep state of a body with [`BodyVelocity`]: a body slower than
/// [`ImpulseSettings::sleep_speed`] for [`ImpulseSettings::sleep_frames`] runs falls asleep:
/// it stops moving (so its pairs are not worked on: their answers stand) until an awake body
/// hits it faster than [`ImpulseSettings::wake_speed`].
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq, Eq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct Rest {
    still_frames: u32,
    asleep: bool,
}

impl Rest {
    /// Whether the body sleeps.
    pub fn is_asleep(&self) -> bool {
        self.asleep
    }

    /// Wakes the body up.
    pub fn wake(&mut self) {
        *self = Rest::default();
    }
}

/// BodyMass of a body with [`BodyVelocity`] (default 1).
#[derive(Component, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct BodyMass(pub f32);

impl Default for BodyMass {
    fn default() -> Self {
        Self(1.0)
    }
}

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
    /// Bounciness in `[0, 1]`.
    pub restitution: f32,
    /// Fraction of the penetration corrected per run.
    pub correction: f32,
    /// Penetration left uncorrected (avoids jitter).
    pub slop: f32,
    /// BodyVelocity damping per second (air drag, rolling friction).
    pub damping: f32,
    /// Coulomb friction coefficient at contacts.
    pub friction: f32,
    /// Speed below which a body counts as still.
    pub sleep_speed: f32,
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
            friction: 0.5,
            sleep_speed: 0.2,
            sleep_frames: 30,
            wake_speed: 0.5,
        }
    }
}

/// Impulse response for simple rigid bodies (see [`ContactQueue`]). Add it after
/// [`StochasticCollisionPlugin`](super::StochasticCollisionPlugin); `default()` runs it in
/// the collision plugin's schedule.
#[derive(Default)]
pub struct ImpulseResponsePlugin {
    /// The schedule of the collision plugin (`None`, the default: the schedule the
    /// [`StochasticCollisionPlugin`](super::StochasticCollisionPlugin) was added to).
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
        super::reflect::register_response_types(app);
        app.insert_resource(self.settings)
            .init_resource::<ContactQueue>()
            .add_systems(
                schedule,
                (
                    integrate_velocities.before(CollisionSystems::Prepare),
                    (impulse_response, sleep_bodies)
                        .chain()
                        .in_set(CollisionSystems::Response),
                ),
            );
        app.world_mut().resource_mut::<ContactQueue>().enable();
    }
}

/// The schedule a response plugin runs in: the collision plugin's ([`CollisionSchedule`]).
///
/// # Panics
/// When the collision plugin was not added first, or `given` is another schedule: the
/// response's systems would run unordered with the pipeline (a set of the same name in a
/// schedule the pipeline is not in), a mistake better seen at startup than as contacts that
/// are never resolved.
fn response_schedule(
    app: &App,
    given: Option<Interned<dyn ScheduleLabel>>,
    plugin: &str,
) -> Interned<dyn ScheduleLabel> {
    let Some(collision) = app.world().get_resource::<CollisionSchedule>() else {
        panic!("{plugin}: add StochasticCollisionPlugin before it (it runs in that schedule)");
    };
    match given {
        Some(s) if s != collision.0 => panic!(
            "{plugin} in {s:?}, but StochasticCollisionPlugin runs in {:?}: use \
             {plugin}::default(), which takes the collision plugin's schedule",
            collision.0
        ),
        _ => collision.0,
    }
}

/// Moves the awake bodies with [`BodyVelocity`] by one step under gravity: their pose, and their
/// `Transform` when they have one (what the game draws, and where the next run reads the
/// pose).
pub fn integrate_velocities(
    settings: Res<ImpulseSettings>,
    time: Option<Res<Time>>,
    mut q: Query<(&mut BodyVelocity, &mut ColliderPose, &Rest, Placement)>,
    parents: Parents,
) {
    let dt = settings.step(time.as_deref());
    let keep = (1.0 - settings.damping * dt).clamp(0.0, 1.0);
    for (mut v, mut pose, rest, mut placement) in &mut q {
        if rest.asleep {
            continue;
        }
        v.0 = (v.0 + settings.gravity * dt) * keep;
        shift(&mut pose, &mut placement, &parents, v.0 * dt);
    }
}

/// Counts still runs and puts bodies to sleep (after the impulses).
pub fn sleep_bodies(settings: Res<ImpulseSettings>, mut q: Query<(&mut BodyVelocity, &mut Rest)>) {
    if settings.sleep_frames == 0 {
        return;
    }
    for (mut v, mut rest) in &mut q {
        if rest.asleep {
            continue;
        }
        if v.0.length() < settings.sleep_speed {
            rest.still_frames += 1;
            if rest.still_frames >= settings.sleep_frames {
                rest.asleep = true;
                v.0 = Vec3::ZERO;
            }
        } else {
            rest.still_frames = 0;
        }
    }
}

/// Resolves rigid contacts (neither entity deformable) in priority order.
pub fn impulse_response(
    settings: Res<ImpulseSettings>,
    mut queue: ResMut<ContactQueue>,
    mut bodies: Query<BodyData>,
    deformables: Query<(), With<Deformable>>,
    parents: Parents,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    let start = Instant::now();
    let n = queue.consume(|c| {
        if c.a == c.b || deformables.contains(c.a) || deformables.contains(c.b) {
            return false;
        }
        if let Ok([a, b]) = bodies.get_many_mut([c.a, c.b]) {
            resolve(&settings, c, a, b, &parents);
        }
        true
    });
    diag.record(Stage::Response, start.elapsed(), n as u64);
}

/// What the impulse response reads and writes of a body.
type BodyData = (
    &'static mut ColliderPose,
    Option<&'static mut BodyVelocity>,
    Option<&'static BodyMass>,
    Option<&'static mut Rest>,
    Placement,
);

type Body<'a> = QueryItem<'a, 'a, BodyData>;

/// Inverse mass; 0 for static and sleeping bodies.
fn inverse_mass(
    v: &Option<Mut<BodyVelocity>>,
    m: Option<&BodyMass>,
    rest: &Option<Mut<Rest>>,
) -> f32 {
    if rest.as_ref().is_some_and(|r| r.asleep) {
        return 0.0;
    }
    match (v, m) {
        (None, _) => 0.0,
        (Some(_), Some(m)) if m.0 > 0.0 => 1.0 / m.0,
        (Some(_), _) => 1.0,
    }
}

/// Wakes a sleeping body that an awake one approaches faster than the wake speed.
fn wake_if_hit<'w>(s: &ImpulseSettings, c: &Contact, a: &mut Body<'w>, b: &mut Body<'w>) {
    let vel = |v: &Option<Mut<BodyVelocity>>| v.as_ref().map_or(Vec3::ZERO, |v| v.0);
    let approach = -(vel(&b.1) - vel(&a.1)).dot(c.normal);
    if approach > s.wake_speed {
        for r in [a.3.as_mut(), b.3.as_mut()].into_iter().flatten() {
            if r.asleep {
                r.wake();
            }
        }
    }
}

fn resolve<'w>(
    s: &ImpulseSettings,
    c: &Contact,
    mut a: Body<'w>,
    mut b: Body<'w>,
    parents: &Parents,
) {
    wake_if_hit(s, c, &mut a, &mut b);
    let (mut pa, mut va, ma, ra, mut place_a) = a;
    let (mut pb, mut vb, mb, rb, mut place_b) = b;
    let (ia, ib) = (inverse_mass(&va, ma, &ra), inverse_mass(&vb, mb, &rb));
    let inv = ia + ib;
    if inv == 0.0 || !c.normal.is_finite() || c.normal == Vec3::ZERO {
        return;
    }
    let n = c.normal;
    let vel = |v: &Option<Mut<BodyVelocity>>| v.as_ref().map_or(Vec3::ZERO, |v| v.0);
    let rel = vel(&vb) - vel(&va);
    let vn = rel.dot(n);
    if vn < 0.0 {
        let j = -(1.0 + s.restitution) * vn / inv;
        // Friction: remove tangential relative velocity, at most `friction × j`.
        let vt = rel - n * vn;
        let jt = (vt.length() / inv).min(s.friction * j);
        let impulse = n * j - vt.normalize_or_zero() * jt;
        if let Some(v) = &mut va {
            v.0 -= impulse * ia;
        }
        if let Some(v) = &mut vb {
            v.0 += impulse * ib;
        }
    }
    let push = (c.depth - s.slop).max(0.0) * s.correction / inv;
    if push > 0.0 {
        if ia > 0.0 {
            shift(&mut pa, &mut place_a, parents, -n * push * ia);
        }
        if ib > 0.0 {
            shift(&mut pb, &mut place_b, parents, n * push * ib);
        }
    }
}

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
    /// [`StochasticCollisionPlugin`](super::StochasticCollisionPlugin) was added to).
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
        super::reflect::register_response_types(app);
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
