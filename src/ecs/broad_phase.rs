//! Broad phase: each collider has a *fat* box (its world box grown by a margin and stretched
//! along its last motion) that it keeps while its world box stays inside. Only colliders whose
//! world box left their fat box (or whose layers changed) make the broad phase work, and the
//! pairs they are in are created and removed at that moment; colliders at rest, or moving
//! inside their fat box, cost nothing here.
//!
//! New pairs are found by sweep and prune over the fat boxes, kept sorted along one axis from
//! run to run (an insertion sort, linear when little moved) and split into lanes along a
//! second axis; a sweep runs only in runs where some fat box moved, and reports only pairs
//! with a moved box that do not exist yet.
//!
//! Invariant (checked by `tests/plugin_pair_table.rs` against brute force): the
//! [`PairTable`] holds a pair for every two valid colliders whose world boxes overlap and
//! whose layers interact, and only pairs whose fat boxes overlap and whose layers interact
//! (plus one pair `(e, e)` per self-colliding deformable mesh).
use std::time::Instant;

use bevy_ecs::prelude::*;
use glam::Vec3;

use super::config::CollisionConfig;
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::layers::ContactLayers;
use super::pairs::PairTable;
use super::pool::CollisionTaskPool;
use super::prepare::{ColliderEntry, ColliderTable};
use super::stamp::{age_stamp, stamp, stamp_sweep_due};
use crate::geometry::Aabb;

/// The broad phase's persistent state: every collider's fat box, their sorted order, and
/// reused buffers.
#[derive(Resource, Debug, Default)]
pub struct BroadPhaseState {
    /// Per collider slot: its fat box, layers, the run its fat box was last set in (a stamp),
    /// and whether it is in the broad phase.
    fat: Vec<Aabb>,
    /// The fat box before this run's move ([`Aabb::EMPTY`] when new or refiltered: its pairs
    /// are not known from it).
    old_fat: Vec<Aabb>,
    layers: Vec<ContactLayers>,
    moved_run: Vec<u32>,
    present: Vec<bool>,
    /// Whether the slot is in `order` (a removed one stays there until the next sweep).
    listed: Vec<bool>,
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
    /// lanes' boxes, the new pairs found per lane.
    moved: Vec<u32>,
    dropped: Vec<u32>,
    lanes: Vec<Vec<SweepBox>>,
    found: Vec<Vec<(u32, u32)>>,
}

impl BroadPhaseState {
    /// Number of colliders in the broad phase.
    pub fn len(&self) -> usize {
        self.present.iter().filter(|&&p| p).count()
    }

    /// Whether no collider is in the broad phase.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The fat box of `entity`'s collider, if it is in the broad phase (`colliders`: the
    /// same world's [`ColliderTable`]).
    pub fn fat_box(&self, colliders: &ColliderTable, entity: Entity) -> Option<Aabb> {
        let i = colliders.slot_of(entity)? as usize;
        self.present
            .get(i)
            .copied()
            .unwrap_or(false)
            .then(|| self.fat[i])
    }

    /// Makes room for slot `i`.
    fn grow_to(&mut self, i: u32) {
        let n = i as usize + 1;
        if self.fat.len() < n {
            self.fat.resize(n, Aabb::EMPTY);
            self.old_fat.resize(n, Aabb::EMPTY);
            self.layers.resize(n, ContactLayers::ALL);
            self.moved_run.resize(n, 0);
            self.present.resize(n, false);
            self.listed.resize(n, false);
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
    mut diag: ResMut<CollisionDiagnostics>,
) {
    let start = Instant::now();
    let run = diag.frame;
    let now = stamp(run);
    let (colliders, pairs, state) = (&mut *colliders, &mut *pairs, &mut *state);
    pairs.begin_run(run);
    if stamp_sweep_due(run) {
        for s in &mut state.moved_run {
            age_stamp(s, now);
        }
    }
    // Removed colliders: their pairs go (touching pairs end), then their slots.
    for (slot, entry) in std::mem::take(&mut colliders.removed) {
        if state.present.get(slot as usize).copied().unwrap_or(false) {
            state.present[slot as usize] = false;
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
        let slot = i as usize;
        if !state.present[slot] {
            // A new collider's fat box is its world box: one that never moves (level
            // geometry) stays as tight as it can be.
            state.old_fat[slot] = Aabb::EMPTY;
            state.fat[slot] = e.aabb;
            state.present[slot] = true;
            if !state.listed[slot] {
                state.listed[slot] = true;
                state.added.push(i);
            }
        } else if refilter || !contains(&state.fat[slot], &e.aabb) {
            state.old_fat[slot] = if refilter {
                Aabb::EMPTY
            } else {
                state.fat[slot]
            };
            state.fat[slot] = fat_box(e, config.proxy_margin);
        } else {
            continue;
        }
        state.layers[slot] = e.layers;
        state.moved_run[slot] = now;
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
    diag.record(
        Stage::BroadPhase,
        start.elapsed(),
        state.moved.len() as u64 + created,
    );
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
            let (a, b) = (i as usize, other as usize);
            if !state.fat[a].intersects(&state.fat[b])
                || !state.layers[a].interacts_with(&state.layers[b])
            {
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
        let p = pairs.create((e.entity, i), (o.entity, j), run);
        link(colliders, pairs, p);
        created += 1;
    }
    created
}

/// Finds the new pairs of the moved boxes by sweep and prune over every fat box, in lanes.
fn sweep(
    colliders: &ColliderTable,
    pairs: &PairTable,
    state: &mut BroadPhaseState,
    pool: &CollisionTaskPool,
    run: u64,
) {
    let now = stamp(run);
    // Lanes along the second axis, each swept on its own over compact copies in sorted order:
    // a box is in every lane it covers, and a pair is reported in the first lane both are in.
    // Far fewer boxes overlap along the sweep axis within a lane than in the whole world.
    let (axis, second) = (state.axis, state.second);
    let fat = &state.fat;
    let (lo, hi) = state
        .order
        .iter()
        .fold((f32::MAX, f32::MIN), |(lo, hi), &i| {
            let b = &fat[i as usize];
            (lo.min(b.min[second]), hi.max(b.max[second]))
        });
    let lanes = ((state.order.len() as f32).sqrt() as usize / 2).clamp(1, 32);
    let scale = (lanes as f32 - 1e-3) / (hi - lo).max(1e-6);
    let lane = |v: f32| (((v - lo) * scale).max(0.0) as usize).min(lanes - 1);
    state.lanes.resize_with(lanes, Vec::new);
    state.lanes.iter_mut().for_each(Vec::clear);
    for &i in &state.order {
        let b = &fat[i as usize];
        let (l0, l1) = (lane(b.min[second]), lane(b.max[second]));
        for m in &mut state.lanes[l0..=l1] {
            let moved = state.moved_run[i as usize] == now;
            m.push(SweepBox {
                aabb: *b,
                old: if moved { state.old_fat[i as usize] } else { *b },
                layers: state.layers[i as usize],
                index: i,
                first_lane: l0 as u32,
                moved,
            });
        }
    }
    let lane_ids: [u32; 32] = std::array::from_fn(|l| l as u32);
    let (members, table, pair_table) = (&state.lanes, colliders, pairs);
    pool.map_chunks_into(&lane_ids[..lanes], 1, &mut state.found, |ls, found| {
        for &l in ls {
            let boxes = &members[l as usize];
            for (k, bi) in boxes.iter().enumerate() {
                let max = bi.aabb.max[axis];
                for bj in &boxes[k + 1..] {
                    if bj.aabb.min[axis] > max {
                        break;
                    }
                    // Boxes that overlapped before this run's moves have their pair already
                    // (pairs go only when the boxes part).
                    if (bi.moved || bj.moved)
                        && bi.first_lane.max(bj.first_lane) == l
                        && bi.aabb.intersects(&bj.aabb)
                        && !bi.old.intersects(&bj.old)
                        && bi.layers.interacts_with(&bj.layers)
                        && !linked(table, pair_table, bi.index, bj.index)
                    {
                        found.push((bi.index, bj.index));
                    }
                }
            }
        }
    });
}

/// Finds the new pairs of the moved boxes (few of them) by searching, for each, the window of
/// the sorted order where boxes overlapping it along the sweep axis can start, and the long
/// boxes.
fn find_near_moved(
    colliders: &ColliderTable,
    pairs: &PairTable,
    state: &mut BroadPhaseState,
    pool: &CollisionTaskPool,
    run: u64,
) {
    let now = stamp(run);
    let axis = state.axis;
    let (order, bounds, long, reach) = (&state.order, &state.bounds, &state.long, state.reach);
    let (fat, old, layers, moved_run) =
        (&state.fat, &state.old_fat, &state.layers, &state.moved_run);
    let chunk = pool.chunk_size(state.moved.len(), 16);
    pool.map_chunks_into(&state.moved, chunk, &mut state.found, |moved, found| {
        for &i in moved {
            let b = &fat[i as usize];
            let mut consider = |j: u32| {
                if j == i {
                    return;
                }
                let (bj, j_moved) = (&fat[j as usize], moved_run[j as usize] == now);
                // Of two moved boxes, the one of the smaller slot reports.
                let old_j = if j_moved { &old[j as usize] } else { bj };
                if (j_moved && j < i)
                    || !b.intersects(bj)
                    || old[i as usize].intersects(old_j)
                    || !layers[i as usize].interacts_with(&layers[j as usize])
                    || linked(colliders, pairs, i, j)
                {
                    return;
                }
                found.push((i.min(j), i.max(j)));
            };
            let end = bounds.partition_point(|k| k[0] <= b.max[axis]);
            for k in (0..end).rev() {
                if bounds[k][0] < b.min[axis] - reach {
                    break;
                }
                if bounds[k][1] >= b.min[axis] {
                    consider(order[k]);
                }
            }
            for &j in long {
                consider(j);
            }
        }
    });
}

/// Brings `order` up to date: the removed slots left out, the added ones in, sorted by the fat
/// boxes' lower bounds along the sweep axis (an insertion sort, linear when little moved; a
/// full sort, with the axes chosen again, when much is new).
fn sort_order(state: &mut BroadPhaseState) {
    if state.removed > 0 {
        let (present, listed) = (&state.present, &mut state.listed);
        state.order.retain(|&i| {
            listed[i as usize] = present[i as usize];
            present[i as usize]
        });
        state.removed = 0;
    }
    let new = state.added.len();
    state.order.append(&mut state.added);
    let mut order = std::mem::take(&mut state.order);
    if new * 4 > order.len() {
        choose_axes(state, &order);
        let (fat, axis) = (&state.fat, state.axis);
        order.sort_unstable_by(|&x, &y| {
            fat[x as usize].min[axis]
                .total_cmp(&fat[y as usize].min[axis])
                .then(x.cmp(&y))
        });
    } else {
        let (fat, axis) = (&state.fat, state.axis);
        let key = |i: u32| fat[i as usize].min[axis];
        // Ties by slot (deterministic).
        for k in 1..order.len() {
            let mut j = k;
            let v = order[k];
            while j > 0
                && key(order[j - 1])
                    .total_cmp(&key(v))
                    .then(order[j - 1].cmp(&v))
                    .is_gt()
            {
                order[j] = order[j - 1];
                j -= 1;
            }
            order[j] = v;
        }
    }
    // The bounds along the axis per position; the long boxes apart (longer than 8 times the
    // median: searched for every moved box instead of widening every window).
    let (fat, axis) = (&state.fat, state.axis);
    let extent = |i: u32| fat[i as usize].max[axis] - fat[i as usize].min[axis];
    let mut sample: Vec<f32> = order
        .iter()
        .step_by(order.len().div_ceil(64).max(1))
        .map(|&i| extent(i))
        .collect();
    sample.sort_unstable_by(f32::total_cmp);
    let limit = 8.0 * sample.get(sample.len() / 2).copied().unwrap_or(0.0);
    state.bounds.clear();
    state.long.clear();
    state.reach = 0.0;
    for &i in &order {
        let b = &fat[i as usize];
        let e = extent(i);
        if e > limit {
            state.long.push(i);
            // A long box never starts a window: its bounds say nothing can start there.
            state.bounds.push([b.min[axis], f32::NEG_INFINITY]);
        } else {
            state.reach = state.reach.max(e);
            state.bounds.push([b.min[axis], b.max[axis]]);
        }
    }
    state.order = order;
}

/// Picks the sweep axis, along which the fat boxes' centres spread most (by the
/// interquartile range of a sample: one body falling away must not swing the axis), and the
/// lanes' axis, the next most spread one.
fn choose_axes(state: &mut BroadPhaseState, order: &[u32]) {
    if order.len() < 2 {
        return;
    }
    let step = order.len().div_ceil(64);
    let mut spread = [0.0f32; 3];
    let mut sample: Vec<f32> = Vec::with_capacity(64);
    for (axis, s) in spread.iter_mut().enumerate() {
        sample.clear();
        sample.extend(
            order
                .iter()
                .step_by(step)
                .map(|&i| state.fat[i as usize].center()[axis]),
        );
        sample.sort_unstable_by(f32::total_cmp);
        let q = |f: f32| sample[((sample.len() - 1) as f32 * f) as usize];
        *s = q(0.75) - q(0.25);
    }
    state.axis = (0..3).fold(0, |b, a| if spread[a] > spread[b] { a } else { b });
    let (u, v) = ((state.axis + 1) % 3, (state.axis + 2) % 3);
    state.second = if spread[u] >= spread[v] { u } else { v };
}

/// A fat box in a lane of the sweep.
#[derive(Debug, Clone, Copy)]
struct SweepBox {
    aabb: Aabb,
    /// The fat box before this run's move (the same when it did not move).
    old: Aabb,
    layers: ContactLayers,
    /// The collider's slot.
    index: u32,
    /// The first lane the box is in (a pair is reported there).
    first_lane: u32,
    /// The fat box moved in this run (only pairs with a moved box can be new).
    moved: bool,
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
