//! Report stage: collision events (messages and opt-in observer events), errors, and the
//! contact queue that responses consume.
//!
//! # Reading events
//! As messages, in any system (runs after [`CollisionSystems::Report`] see them in the same
//! frame; [`Contact`] messages only with
//! [`CollisionConfig::contact_messages`](super::CollisionConfig::contact_messages), else read
//! contacts through [`CollisionPairs`](super::CollisionPairs)):
//! ```
//! # use bevy_ecs::prelude::*;
//! # use stochastic_collision::prelude::*;
//! fn on_hits(mut started: MessageReader<CollisionStarted>, mut contacts: MessageReader<Contact>) {
//!     for e in started.read() {
//!         println!("{:?} started touching {:?}", e.entity, e.other);
//!     }
//!     for c in contacts.read() {
//!         println!("contact at {} depth {} (p = {})", c.point, c.depth, c.probability);
//!     }
//! }
//! # bevy_ecs::system::assert_is_system(on_hits);
//! ```
//! Or per entity, with an observer, for entities with [`ObserveCollisions`]:
//! ```
//! # use bevy_ecs::prelude::*;
//! # use stochastic_collision::prelude::*;
//! # let mut world = World::new();
//! world
//!     .spawn(ObserveCollisions)
//!     .observe(|hit: On<CollisionStarted>| println!("{:?} hit me", hit.other));
//! ```
//! Messages follow Bevy's rule: a message stays readable for two app updates, so a reader
//! running every update, or every other update, sees every event even when the collision
//! schedule runs several times per update (fixed time steps).
//!
//! [`CollisionSystems::Report`]: super::CollisionSystems::Report

use bevy_ecs::prelude::*;
use bevy_ecs::system::SystemParam;
use bevy_reflect::prelude::*;
use glam::Vec3;

use super::budget::BudgetController;
use super::components::{CollisionSensor, ObserveCollisions, TouchingEntities};
use super::config::CollisionConfig;
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::narrow_phase::Method;
use super::pairs::PairTable;
use super::response::ContactQueue;
use crate::bvh::TrianglePair;
use crate::mesh::MeshError;

/// Two entities started touching (or a deformable mesh started touching itself:
/// `entity == other`). Written once per contact interval.
///
/// As a message, `entity < other`. As an observer event (entities with
/// [`ObserveCollisions`]), `entity` is the observed entity.
///
/// `method` and `probability` say how sure the start is: an exact answer (`Exact`,
/// `SelfCollision`: probability 1), an ADB estimate, a tracked contact, a box overlap
/// (`Bounds`), or an exact pair's answer from memory under overload (`Coherence`, 0.5 when
/// only the oriented boxes overlapped). Gameplay that must act on certain contacts only
/// checks [`CollisionStarted::is_certain`].
#[derive(Message, EntityEvent, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Clone, Debug, PartialEq)]
pub struct CollisionStarted {
    /// The first entity (the observed one for observer events).
    #[event_target]
    pub entity: Entity,
    /// The other entity.
    pub other: Entity,
    /// How the answer that started the contact was found.
    pub method: Method,
    /// Its confidence that the pair collides.
    pub probability: f64,
    /// For a pair with a swept collider ([`ContinuousCollision`](super::ContinuousCollision)):
    /// when in the run's step the surfaces first met, a fraction in `[0, 1]` (a contact the
    /// discrete test alone would have missed when the surfaces are apart again at the run's
    /// poses). `None` otherwise.
    pub time_of_impact: Option<f32>,
}

impl CollisionStarted {
    /// Whether the contact was found by an exact test (not estimated, guessed from boxes, or
    /// answered from memory).
    pub fn is_certain(&self) -> bool {
        self.method.is_certain(self.probability)
    }
}

/// Two entities stopped touching: written once at the end of each contact interval, also
/// when one of them was despawned or became invalid. Same conventions as [`CollisionStarted`].
#[derive(Message, EntityEvent, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Clone, Debug, PartialEq)]
pub struct CollisionEnded {
    /// The first entity (the observed one for observer events).
    #[event_target]
    pub entity: Entity,
    /// The other entity.
    pub other: Entity,
    /// How the answer that ended the contact was found; [`Method::Bounds`] when the pair
    /// was removed (world boxes parted, an entity despawned, removed or invalid).
    pub method: Method,
    /// That answer's confidence that the pair still collides (0 for a removed pair).
    pub probability: f64,
}

/// One contact point of a colliding pair answered in this run (written only with
/// [`CollisionConfig::contact_messages`](super::CollisionConfig::contact_messages)).
#[derive(Message, Reflect, Clone, Copy, Debug, PartialEq)]
#[reflect(Clone, Debug, PartialEq)]
pub struct Contact {
    /// First entity.
    pub a: Entity,
    /// Second entity (`a` itself for a self-contact of a deformable mesh).
    pub b: Entity,
    /// Contact point, world space.
    pub point: Vec3,
    /// Unit direction to push `b` away from `a`, world space.
    pub normal: Vec3,
    /// Estimated penetration depth along `normal`.
    pub depth: f32,
    /// Confidence that the pair collides (1 for exact answers).
    pub probability: f64,
    /// How the pair's answer was found.
    pub method: Method,
    /// The triangle pair (`a`'s, `b`'s) when the contact comes from one.
    #[reflect(remote = super::reflect::OptionTrianglePairReflect)]
    pub triangles: Option<TrianglePair>,
    /// Priority for responses (higher first): the pair's priority, deeper contacts higher.
    pub priority: f32,
    /// When in the run's step the surfaces met, for a pair tested over a swept collider's
    /// motion ([`ContactPoint::time_of_impact`](super::ContactPoint::time_of_impact)).
    pub time_of_impact: Option<f32>,
    /// Run at whose poses the contact was found (see [`CollisionDiagnostics::frame`]):
    /// earlier than the current run for a pair whose last answer was kept (not tested in
    /// this run), whose contact then has depth 0.
    pub frame: u64,
}

/// Why an entity was skipped in a run.
#[derive(Reflect, Debug, Clone, PartialEq, thiserror::Error)]
#[reflect(opaque, Clone, Debug, PartialEq)]
pub enum CollisionErrorKind {
    /// The pose has a NaN or infinite component, or a rotation far from unit length.
    #[error("invalid pose: translation {translation:?}, rotation {rotation:?}")]
    InvalidPose {
        /// The translation.
        translation: [f32; 3],
        /// The rotation quaternion (x, y, z, w).
        rotation: [f32; 4],
    },
    /// The [`ColliderScale`](super::ColliderScale) has a factor that is zero, not finite,
    /// or below `1e-6` in magnitude.
    #[error("invalid scale {scale:?}: every factor must be finite and at least 1e-6 in magnitude")]
    InvalidScale {
        /// The scale.
        scale: [f32; 3],
    },
    /// A deformable mesh's new positions were rejected (for example a non-finite vertex).
    #[error("deformable mesh rejected: {0}")]
    Mesh(MeshError),
    /// The entity's `Mesh3d` asset cannot be made into a collider (its
    /// [`MeshColliderConstructor`](super::MeshColliderConstructor) is removed).
    #[cfg(feature = "bevy_mesh")]
    #[error("Mesh3d asset rejected: {0}")]
    BevyMesh(super::BevyMeshError),
}

/// An entity was skipped because its data is bad; the other entities go on. Written once when
/// the entity becomes invalid (again after it recovered and broke again); its contacts end.
#[derive(Message, Reflect, Clone, Debug, PartialEq)]
#[reflect(Clone, Debug, PartialEq)]
pub struct CollisionError {
    /// The entity.
    pub entity: Entity,
    /// What is wrong.
    pub kind: CollisionErrorKind,
}

/// Writes the events of this run's transitions (pairs whose touching state flipped, in pair
/// order: the ends first, then the starts), updates [`TouchingEntities`], triggers observer
/// events, and hands this run's contacts (of the pairs answered in this run) to the
/// [`ContactQueue`] and, if [`CollisionConfig::contact_messages`], as [`Contact`] messages.
#[allow(clippy::too_many_arguments)]
pub fn report_collisions(
    mut pairs: ResMut<PairTable>,
    mut queue: ResMut<ContactQueue>,
    config: Res<CollisionConfig>,
    mut colliding: Query<&mut TouchingEntities>,
    observed: Query<(), With<ObserveCollisions>>,
    sensors: Query<(), With<CollisionSensor>>,
    mut writers: ReportWriters,
    mut commands: Commands,
    mut budget: ResMut<BudgetController>,
    mut diag: ResMut<CollisionDiagnostics>,
    mut fresh: Local<Vec<Contact>>,
    mut flips: Local<TouchingFlips>,
) {
    let start = budget.now();
    let frame = budget.run();
    let pairs = &mut *pairs;
    pairs
        .transitions
        .sort_unstable_by_key(|t| (t.a, t.b, t.started));
    let (mut started, mut ended) = (0u64, 0u64);
    // Each end's touching list takes this run's flips in one merge (below), in the order
    // found: ends, then starts.
    let TouchingFlips {
        flips,
        one_entity,
        merged,
    } = &mut *flips;
    flips.clear();
    for pass_started in [false, true] {
        for t in pairs
            .transitions
            .iter()
            .filter(|t| t.started == pass_started)
        {
            let (a, b, method, probability, time_of_impact) =
                (t.a, t.b, t.method, t.probability, t.time_of_impact);
            if a != b {
                flips.extend([(a, b, t.started), (b, a, t.started)]);
            }
            if t.started {
                started += 1;
                let event = |entity, other| CollisionStarted {
                    entity,
                    other,
                    method,
                    probability,
                    time_of_impact,
                };
                writers.started.write(event(a, b));
                notify(&mut commands, &observed, a, b, event);
            } else {
                ended += 1;
                let event = |entity, other| CollisionEnded {
                    entity,
                    other,
                    method,
                    probability,
                };
                writers.ended.write(event(a, b));
                notify(&mut commands, &observed, a, b, event);
            }
        }
    }
    // A stable sort keeps the order of one pair's end and start within a run.
    flips.sort_by_key(|f| (f.0, f.1));
    for group in flips.chunk_by(|x, y| x.0 == y.0) {
        if let Ok(mut touching) = colliding.get_mut(group[0].0) {
            one_entity.clear();
            one_entity.extend(group.iter().map(|f| (f.1, f.2)));
            touching.apply(one_entity, merged);
        }
    }
    // This run's contacts, in pair order.
    let slots = &pairs.slots;
    pairs
        .colliding
        .sort_unstable_by_key(|&p| (slots[p as usize].a, slots[p as usize].b));
    pairs.colliding.dedup();
    fresh.clear();
    let wanted = config.contact_messages || queue.is_enabled();
    for &p in pairs.colliding.iter().filter(|_| wanted) {
        let o = &slots[p as usize].outcome;
        if !o.collides {
            continue;
        }
        // An answer kept from an earlier run gives its contacts without depth (they stop
        // approach without pushing the same correction twice) and the run they were found in.
        let kept = o.run < frame;
        for c in &o.contacts {
            let depth = if kept { 0.0 } else { c.depth };
            fresh.push(Contact {
                a: o.a,
                b: o.b,
                point: c.point,
                normal: c.normal,
                depth,
                probability: o.probability,
                method: o.method,
                triangles: c.triangles,
                priority: o.priority * (1.0 + depth.max(0.0)),
                frame: o.computed_run,
                time_of_impact: c.time_of_impact,
            });
        }
    }
    let counters = &mut diag.counters;
    if config.contact_messages {
        writers.contacts.write_batch(fresh.iter().copied());
        counters.contacts += fresh.len() as u64;
    }
    // Sensors' contacts are reported, never responded to.
    if !sensors.is_empty() {
        fresh.retain(|c| !sensors.contains(c.a) && !sensors.contains(c.b));
    }
    counters.started += started;
    counters.ended += ended;
    queue.refill(&mut fresh, config.response_budget, budget.clock());
    let time = budget.stage_done(Stage::Report, start);
    diag.record(Stage::Report, time, started + ended);
    let end = budget.end_run(config.budget);
    diag.end_run(end.collision_time, end.overran);
}

/// The messages the Report stage writes.
#[derive(SystemParam)]
pub struct ReportWriters<'w> {
    started: MessageWriter<'w, CollisionStarted>,
    ended: MessageWriter<'w, CollisionEnded>,
    contacts: MessageWriter<'w, Contact>,
}

/// The Report's memory for the touching lists, reused from run to run: this run's flips
/// (entity, other, touching now), one entity's flips, and the merged list.
#[derive(Default)]
pub struct TouchingFlips {
    flips: Vec<(Entity, Entity, bool)>,
    one_entity: Vec<(Entity, bool)>,
    merged: Vec<Entity>,
}

/// Triggers the observer event on each endpoint that opted in, as `(observed, other)`.
fn notify<E>(
    commands: &mut Commands,
    observed: &Query<(), With<ObserveCollisions>>,
    a: Entity,
    b: Entity,
    make: impl Fn(Entity, Entity) -> E,
) where
    E: EntityEvent,
    for<'t> <E as Event>::Trigger<'t>: Default,
{
    let ends = [(a, b), (b, a)];
    for &(x, y) in &ends[..if a == b { 1 } else { 2 }] {
        if observed.contains(x) {
            commands.trigger(make(x, y));
        }
    }
}
