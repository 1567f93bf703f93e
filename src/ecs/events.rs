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
use std::sync::Arc;
use std::time::Duration;

use bevy_ecs::prelude::*;
use bevy_ecs::system::SystemParam;
use bevy_reflect::prelude::*;
use glam::Vec3;

use super::budget::{BudgetClock, BudgetController, SystemClock};
use super::components::{CollisionSensor, ObserveCollisions, TouchingEntities};
use super::config::{CollisionConfig, ResponseBudget};
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::narrow_phase::Method;
use super::pairs::PairTable;
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

/// Contacts waiting for a response, highest priority first.
///
/// Filled by the Report stage (when some response is registered: the built-in response
/// plugins do it, a custom response calls [`ContactQueue::enable`] once). A response consumes
/// contacts with [`ContactQueue::consume`] inside the per-run response budget
/// ([`CollisionConfig::response_budget`]: a time, or a number of contacts); what it leaves
/// stays queued, counted, for the next run. A newer contact of the same pair replaces a
/// waiting one.
#[derive(Resource, Debug, Default)]
pub struct ContactQueue {
    enabled: bool,
    queue: Vec<Contact>,
    /// Contacts left to consume in this run (`None`: no count).
    remaining: Option<usize>,
    /// Time left to consume contacts in this run (`None`: no time limit).
    remaining_time: Option<Duration>,
    /// The budget's clock (the system clock until the first run).
    clock: Option<Arc<dyn BudgetClock>>,
    /// Contacts left unconsumed at the end of a run (carried into the next, or superseded
    /// there by a newer contact of the same pair), summed over runs.
    pub deferred_total: u64,
    /// Contacts consumed by responses.
    pub consumed_total: u64,
    /// Waiting contacts replaced by a newer contact of the same pair.
    pub superseded_total: u64,
    /// Reused buffers: the pairs of the fresh contacts, the sort keys, the sorted queue.
    fresh_pairs: Vec<(Entity, Entity)>,
    keys: Vec<(f32, u32)>,
    sorted: Vec<Contact>,
}

impl ContactQueue {
    /// Starts filling the queue (call once when adding a response system).
    pub fn enable(&mut self) {
        self.enabled = true;
    }

    /// Whether the queue is filled.
    pub fn is_enabled(&self) -> bool {
        self.enabled
    }

    /// Contacts waiting, highest priority first.
    pub fn waiting(&self) -> &[Contact] {
        &self.queue
    }

    /// Number of contacts waiting.
    pub fn len(&self) -> usize {
        self.queue.len()
    }

    /// Whether no contact is waiting.
    pub fn is_empty(&self) -> bool {
        self.queue.is_empty()
    }

    /// Contacts this run's response budget still allows (`None`: it counts no contacts).
    pub fn remaining_contacts(&self) -> Option<usize> {
        self.remaining
    }

    /// Time this run's response budget still allows (`None`: it has no time limit).
    pub fn remaining_time(&self) -> Option<Duration> {
        self.remaining_time
    }

    /// Whether this run's response budget is spent (no contact will be offered).
    pub fn budget_spent(&self) -> bool {
        self.remaining == Some(0) || self.remaining_time == Some(Duration::ZERO)
    }

    /// Offers the waiting contacts to `respond`, highest priority first, until this run's
    /// response budget is spent. `respond` returns `true` if it consumed the contact (it
    /// leaves the queue and costs one unit of a count budget), `false` to leave it to another
    /// response. Under a time budget the time spent in this call is charged, and a contact is
    /// offered only while some is left.
    pub fn consume(&mut self, mut respond: impl FnMut(&Contact) -> bool) -> usize {
        if self.budget_spent() {
            return 0;
        }
        let clock = self.clock.clone().unwrap_or_else(|| Arc::new(SystemClock));
        let start = self.remaining_time.map(|_| clock.now());
        let deadline = start.zip(self.remaining_time).map(|(s, t)| s + t);
        let (mut consumed, mut offered, mut stopped) = (0, false, false);
        let mut remaining = self.remaining;
        self.queue.retain(|c| {
            stopped = stopped
                || remaining == Some(0)
                || (offered && deadline.is_some_and(|d| clock.now() >= d));
            if stopped {
                return true;
            }
            offered = true;
            if !respond(c) {
                return true;
            }
            consumed += 1;
            if let Some(r) = &mut remaining {
                *r -= 1;
            }
            false
        });
        self.remaining = remaining;
        if let (Some(start), Some(left)) = (start, &mut self.remaining_time) {
            *left = left.saturating_sub(clock.now().saturating_duration_since(start));
        }
        self.consumed_total += consumed as u64;
        consumed
    }

    fn refill(
        &mut self,
        fresh: &mut Vec<Contact>,
        budget: ResponseBudget,
        clock: Arc<dyn BudgetClock>,
    ) {
        (self.remaining, self.remaining_time) = match budget {
            ResponseBudget::Unlimited => (None, None),
            ResponseBudget::Time(t) => (None, Some(t)),
            ResponseBudget::Contacts(n) => (Some(n), None),
        };
        self.clock = Some(clock);
        if !self.enabled {
            return;
        }
        let before = self.queue.len();
        self.deferred_total += before as u64;
        if before > 0 {
            let fresh_pairs = &mut self.fresh_pairs;
            fresh_pairs.clear();
            fresh_pairs.extend(fresh.iter().map(|c| (c.a, c.b)));
            fresh_pairs.dedup();
            self.queue
                .retain(|c| fresh_pairs.binary_search(&(c.a, c.b)).is_err());
            self.superseded_total += (before - self.queue.len()) as u64;
        }
        // Sorted by small keys, then moved once (contacts are large): by priority, ties in
        // queue order (waiting contacts first, then the fresh ones in pair order), the same
        // for any thread count. Keys are unique (the index), so an unstable sort is exact.
        let keys = &mut self.keys;
        keys.clear();
        let all = self.queue.iter().chain(fresh.iter());
        keys.extend(all.enumerate().map(|(i, c)| (c.priority, i as u32)));
        keys.sort_unstable_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        let waiting = self.queue.len();
        let sorted = &mut self.sorted;
        sorted.clear();
        sorted.extend(
            keys.iter()
                .map(|&(_, i)| match (i as usize).checked_sub(waiting) {
                    None => self.queue[i as usize],
                    Some(f) => fresh[f],
                }),
        );
        std::mem::swap(&mut self.queue, sorted);
        fresh.clear();
    }
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
) {
    let start = budget.now();
    let frame = budget.run();
    let pairs = &mut *pairs;
    pairs
        .transitions
        .sort_unstable_by_key(|t| (t.a, t.b, t.started));
    let (mut started, mut ended) = (0u64, 0u64);
    for pass_started in [false, true] {
        for t in pairs
            .transitions
            .iter()
            .filter(|t| t.started == pass_started)
        {
            let (a, b, method, probability, time_of_impact) =
                (t.a, t.b, t.method, t.probability, t.time_of_impact);
            set_colliding(&mut colliding, a, b, t.started);
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

/// Updates both entities' [`TouchingEntities`] (not for a self-collision).
fn set_colliding(q: &mut Query<&mut TouchingEntities>, a: Entity, b: Entity, touching: bool) {
    if a == b {
        return;
    }
    for (x, y) in [(a, b), (b, a)] {
        if let Ok(mut c) = q.get_mut(x) {
            if touching {
                c.insert(y);
            } else {
                c.remove(y);
            }
        }
    }
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
