//! Broad phase: each collider has a *fat* box (its world box grown by a margin and stretched
//! along its last motion) that it keeps while its world box stays inside. Only colliders whose
//! world box left their fat box (or whose layers changed) make the broad phase work, and the
//! pairs they are in are created and removed at that moment; colliders at rest, or moving
//! inside their fat box, cost nothing here. A new pair whose world boxes are still apart (most
//! new pairs of a collider that moved far) is answered at once, as the narrow phase would
//! answer it, and needs no work until the boxes meet.
//!
//! New pairs are found by sweep and prune over the fat boxes, kept sorted along one axis from
//! run to run (an insertion sort, linear when little moved) and split into lanes along a
//! second axis; a sweep runs only in runs where some fat box moved, goes from the moved boxes
//! (each against its neighbours along the sweep axis), and reports only pairs with a moved box
//! that do not exist yet.
//!
//! Invariant (checked by `tests/plugin_pair_table.rs` against brute force): the
//! [`PairTable`] holds a pair for every two valid colliders whose world boxes overlap and
//! whose layers interact, and only pairs whose fat boxes overlap and whose layers interact
//! (plus one pair `(e, e)` per self-colliding deformable mesh).

mod sweep;

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::budget::BudgetController;
use super::config::CollisionConfig;
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::layers::ContactLayers;
use super::narrow_phase::answer_if_apart;
use super::pairs::PairTable;
use super::parallel::CollisionTaskPool;
use super::prepare::{ColliderEntry, ColliderTable};
use super::stamp::{age_stamp, stamp, stamp_sweep_due};
use crate::geometry::Aabb;
use sweep::{SweepBox, find_near_moved, sort_order, sweep};

/// One collider slot in the broad phase: everything a sweep or a windowed search reads of it,
/// in one 64-byte record, so that a search visiting the boxes in sorted order (scattered slots)
/// loads one record per box rather than one array element per field.
#[derive(Debug, Clone, Copy)]
pub(super) struct Proxy {
    /// The fat box.
    fat: Aabb,
    /// The fat box before this run's move ([`Aabb::EMPTY`] when new or refiltered: its pairs
    /// are not known from it).
    old_fat: Aabb,
    layers: ContactLayers,
    /// The run its fat box was last set in (a stamp).
    moved_run: u32,
    /// Whether the slot is in the broad phase.
    present: bool,
    /// Whether the slot is in `order` (a removed one stays there until the next sweep).
    listed: bool,
}

const _: () = assert!(std::mem::size_of::<Proxy>() == 64);

impl Default for Proxy {
    fn default() -> Self {
        Self {
            fat: Aabb::EMPTY,
            old_fat: Aabb::EMPTY,
            layers: ContactLayers::ALL,
            moved_run: 0,
            present: false,
            listed: false,
        }
    }
}

/// The broad phase's persistent state: every collider's fat box, their sorted order, and
/// reused buffers.
#[derive(Resource, Debug, Default)]
pub struct BroadPhaseState {
    /// Per collider slot: its fat box, layers, the run its fat box was last set in, and
    /// whether it is in the broad phase.
    proxies: Vec<Proxy>,
    /// The slots in the broad phase, sorted by their fat box's lower bound along `axis`, and
    /// per sorted position the box's bounds along `axis` (for windowed searches).
    order: Vec<u32>,
    bounds: Vec<[f32; 2]>,
    /// The slots whose fat box is far longer along `axis` than most (level geometry: a floor,
    /// walls), checked against every moved box; the longest extent along `axis` of the others.
    long: Vec<u32>,
    reach: f32,
    /// Slots added since the last sweep (merged into `order` at the next sweep).
    added: Vec<u32>,
    /// Slots removed since the last sweep (left out of `order` at the next sweep).
    removed: usize,
    axis: usize,
    second: usize,
    /// Reused buffers: the colliders whose fat box moved in this run, the pairs to drop, the
    /// lanes' boxes and their moved boxes, the new pairs found per lane.
    moved: Vec<u32>,
    dropped: Vec<u32>,
    lanes: Vec<Vec<SweepBox>>,
    lanes_moved: Vec<Vec<u32>>,
    found: Vec<Vec<(u32, u32)>>,
}

impl BroadPhaseState {
    /// Number of colliders in the broad phase.
    pub fn len(&self) -> usize {
        self.proxies.iter().filter(|p| p.present).count()
    }

    /// Whether no collider is in the broad phase.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The fat box of `entity`'s collider, if it is in the broad phase (`colliders`: the
    /// same world's [`ColliderTable`]).
    pub fn fat_box(&self, colliders: &ColliderTable, entity: Entity) -> Option<Aabb> {
        let i = colliders.slot_of(entity)? as usize;
        self.proxies.get(i).filter(|p| p.present).map(|p| p.fat)
    }

    /// Makes room for slot `i`.
    fn grow_to(&mut self, i: u32) {
        let n = i as usize + 1;
        if self.proxies.len() < n {
            self.proxies.resize(n, Proxy::default());
        }
    }
}

/// Updates fat boxes and pairs for the colliders removed and changed in this run.
pub fn update_broad_phase(
    mut colliders: ResMut<ColliderTable>,
    mut pairs: ResMut<PairTable>,
    mut state: ResMut<BroadPhaseState>,
    config: Res<CollisionConfig>,
    pool: Res<CollisionTaskPool>,
    mut budget: ResMut<BudgetController>,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    let start = budget.now();
    let run = budget.run();
    let now = stamp(run);
    let (colliders, pairs, state) = (&mut *colliders, &mut *pairs, &mut *state);
    pairs.begin_run(run);
    if stamp_sweep_due(run) {
        for p in &mut state.proxies {
            age_stamp(&mut p.moved_run, now);
        }
    }
    // Removed colliders: their pairs go (touching pairs end), then their slots.
    for (slot, entry) in std::mem::take(&mut colliders.removed) {
        if let Some(p) = state.proxies.get_mut(slot as usize)
            && p.present
        {
            p.present = false;
            state.removed += 1;
        }
        for &p in entry.pair_slots() {
            let s = pairs.ends(p);
            if !s.live {
                // Already gone with the other collider, removed in this run too.
                continue;
            }
            let other = if s.body_a == slot { s.body_b } else { s.body_a };
            if other != slot && colliders.is_live(other) {
                unlink(colliders, pairs, p, other);
            }
            pairs.remove(p);
        }
        colliders.free_slot(slot);
    }
    // Changed colliders: fat boxes left behind move; self pairs follow the marker (new
    // colliders and those whose layers or marker changed).
    state.moved.clear();
    for k in 0..colliders.changed().len() {
        let i = colliders.changed()[k];
        state.grow_to(i);
        let e = colliders.entry(i);
        let refilter = e.filter_run == run;
        let p = &mut state.proxies[i as usize];
        if !p.present {
            // A new collider's fat box is its world box: one that never moves (level
            // geometry) stays as tight as it can be.
            p.old_fat = Aabb::EMPTY;
            p.fat = e.aabb;
            p.present = true;
            if !p.listed {
                p.listed = true;
                state.added.push(i);
            }
        } else if refilter || !contains(&p.fat, &e.aabb) {
            p.old_fat = if refilter { Aabb::EMPTY } else { p.fat };
            p.fat = fat_box(e, config.proxy_margin);
        } else {
            continue;
        }
        p.layers = e.layers;
        p.moved_run = now;
        state.moved.push(i);
        if refilter {
            update_self_pair(colliders, pairs, i, run);
        }
    }
    let mut created = 0u64;
    if !state.moved.is_empty() {
        drop_parted(colliders, pairs, state);
        created = create_found(colliders, pairs, state, &pool, run);
    }
    let time = budget.stage_done(Stage::BroadPhase, start);
    diag.record(Stage::BroadPhase, time, state.moved.len() as u64 + created);
}

/// Removes the pairs of moved fat boxes that no longer overlap the other's (or whose layers
/// no longer interact).
fn drop_parted(colliders: &mut ColliderTable, pairs: &mut PairTable, state: &mut BroadPhaseState) {
    state.dropped.clear();
    for &i in &state.moved {
        for &p in colliders.entry(i).pair_slots() {
            let s = pairs.ends(p);
            let other = if s.body_a == i { s.body_b } else { s.body_a };
            if other == i {
                continue;
            }
            let (a, b) = (&state.proxies[i as usize], &state.proxies[other as usize]);
            if !a.fat.intersects(&b.fat) || !a.layers.interacts_with(&b.layers) {
                state.dropped.push(p);
            }
        }
    }
    state.dropped.sort_unstable();
    state.dropped.dedup();
    for &p in &state.dropped {
        let s = pairs.ends(p);
        let (a, b) = (s.body_a, s.body_b);
        unlink(colliders, pairs, p, a);
        unlink(colliders, pairs, p, b);
        pairs.remove(p);
    }
}

/// Sweeps the fat boxes and creates the pairs of a moved box that do not exist yet; returns
/// how many.
fn create_found(
    colliders: &mut ColliderTable,
    pairs: &mut PairTable,
    state: &mut BroadPhaseState,
    pool: &CollisionTaskPool,
    run: u64,
) -> u64 {
    sort_order(state);
    if state.moved.len() * 10 < state.order.len() {
        find_near_moved(colliders, pairs, state, pool, run);
    } else {
        sweep(colliders, pairs, state, pool, run);
    }
    let mut created = 0;
    for &(i, j) in state.found.iter().flatten() {
        let (e, o) = (colliders.entry(i), colliders.entry(j));
        let p = pairs.insert((e.entity, i), (o.entity, j), run);
        link(colliders, pairs, p);
        // Most new pairs of a box that moved far are still apart: answered here, no job.
        if !answer_if_apart(colliders, pairs, p, run) {
            pairs.mark_pending(p, run);
        }
        created += 1;
    }
    created
}

/// The fat box of a collider that moved: its world box grown by `margin` of its size, and
/// stretched along six times its last motion (where it is likely to be over the next runs).
fn fat_box(e: &ColliderEntry, margin: f32) -> Aabb {
    let grown = e.aabb.inflated(margin * e.aabb.extents().max_element());
    let ahead = 6.0 * e.motion;
    Aabb::new(
        grown.min + ahead.min(Vec3::ZERO),
        grown.max + ahead.max(Vec3::ZERO),
    )
}

/// Whether `outer` contains `inner`.
fn contains(outer: &Aabb, inner: &Aabb) -> bool {
    outer.min.cmple(inner.min).all() && inner.max.cmple(outer.max).all()
}

/// Adds pair `p` to its colliders' lists of pairs (once for a self pair), noting where.
fn link(colliders: &mut ColliderTable, pairs: &mut PairTable, p: u32) {
    let e = pairs.ends[p as usize];
    let list = &mut colliders.entry_mut(e.body_a).pairs;
    pairs.ends[p as usize].pos_a = list.len() as u32;
    list.push(p);
    if e.body_b != e.body_a {
        let list = &mut colliders.entry_mut(e.body_b).pairs;
        pairs.ends[p as usize].pos_b = list.len() as u32;
        list.push(p);
    }
}

/// Removes pair `p` from collider `body`'s list of pairs, in constant time (the last pair of
/// the list takes its place).
fn unlink(colliders: &mut ColliderTable, pairs: &mut PairTable, p: u32, body: u32) {
    let e = pairs.ends[p as usize];
    let pos = if e.body_a == body { e.pos_a } else { e.pos_b } as usize;
    let list = &mut colliders.entry_mut(body).pairs;
    debug_assert_eq!(list.get(pos), Some(&p), "a pair knows where it is listed");
    list.swap_remove(pos);
    if let Some(&moved) = list.get(pos) {
        let m = &mut pairs.ends[moved as usize];
        if m.body_a == body {
            m.pos_a = pos as u32;
        } else {
            m.pos_b = pos as u32;
        }
    }
}

/// Creates or removes collider `i`'s self pair as its marker says.
fn update_self_pair(colliders: &mut ColliderTable, pairs: &mut PairTable, i: u32, run: u64) {
    let own = colliders
        .entry(i)
        .pair_slots()
        .iter()
        .copied()
        .find(|&p| pairs.ends(p).body_a == pairs.ends(p).body_b);
    let e = colliders.entry(i);
    match (e.self_collision, own) {
        (true, None) => {
            let p = pairs.create((e.entity, i), (e.entity, i), run);
            link(colliders, pairs, p);
        }
        (false, Some(p)) => {
            unlink(colliders, pairs, p, i);
            pairs.remove(p);
        }
        _ => {}
    }
}

/// Whether colliders `i` and `j` already have a pair (the shorter list is searched).
fn linked(colliders: &ColliderTable, pairs: &PairTable, i: u32, j: u32) -> bool {
    let (ei, ej) = (colliders.entry(i), colliders.entry(j));
    let (list, other) = if ei.pairs.len() <= ej.pairs.len() {
        (&ei.pairs, j)
    } else {
        (&ej.pairs, i)
    };
    list.iter().any(|&p| {
        let s = pairs.ends(p);
        s.body_a == other || s.body_b == other
    })
}
