//! Broad phase: sweep and prune over world boxes, with temporal coherence.
//!
//! The entities stay sorted by their box's lower bound on one axis from run to run; each run
//! re-sorts with an insertion sort, which is linear when little moved (the usual case), then
//! sweeps. The axis is the one along which the box centres spread most, chosen once and
//! re-chosen only when another axis spreads twice as much (a change of axis costs one full sort).
use std::time::Instant;

use bevy_ecs::prelude::*;

use super::components::CollisionLayers;
use crate::geometry::Aabb;

use super::diagnostics::{CollisionDiagnostics, Stage};
use super::pool::CollisionTaskPool;
use super::prepare::ColliderFrame;

/// A candidate pair: indices into the run's [`ColliderFrame`] entries, `a < b` (so the first is
/// the smaller entity).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct CandidatePair {
    /// Index of the first entry.
    pub a: u32,
    /// Index of the second entry.
    pub b: u32,
}

/// The candidate pairs of the current run (boxes overlap, layers interact), sorted.
#[derive(Resource, Debug, Default)]
pub struct CandidatePairs {
    pub(crate) pairs: Vec<CandidatePair>,
    /// The pairs are the last run's, reused: no entity came, went, or changed its box or layers.
    pub(crate) reused: bool,
}

impl CandidatePairs {
    /// The pairs, sorted.
    pub fn pairs(&self) -> &[CandidatePair] {
        &self.pairs
    }
}

/// What the broad phase keeps between runs: the sorted order and the axis.
#[derive(Resource, Debug, Default)]
pub struct BroadPhaseState {
    order: Vec<Entity>,
    axis: usize,
    second: usize,
    last_axis: usize,
    /// Reused buffers (no fresh memory every run): the lanes' boxes, the pairs found per lane,
    /// the pairs sorted by their second index.
    lanes: Vec<Vec<SweepBox>>,
    found: Vec<Vec<CandidatePair>>,
    by_b: Vec<CandidatePair>,
    /// What the last run's pairs were found from: each entry's entity, box and layers, in
    /// entry order. The same again (nothing moved, came, went or changed layers: a scene at
    /// rest) gives the same pairs, so the sweep is skipped.
    last_input: Vec<(Entity, Aabb, CollisionLayers)>,
}

/// Collects the candidate pairs of the run.
pub fn sweep_and_prune(
    frame: Res<ColliderFrame>,
    mut state: ResMut<BroadPhaseState>,
    mut out: ResMut<CandidatePairs>,
    pool: Res<CollisionTaskPool>,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    let start = Instant::now();
    let entries = &frame.entries;
    let state = &mut *state;
    let unchanged = state.last_input.len() == entries.len()
        && state
            .last_input
            .iter()
            .zip(entries)
            .all(|(&(e, aabb, layers), x)| e == x.entity && aabb == x.aabb && layers == x.layers);
    out.reused = unchanged;
    if unchanged {
        diag.record(Stage::BroadPhase, start.elapsed(), out.pairs.len() as u64);
        return;
    }
    state.last_input.clear();
    state
        .last_input
        .extend(entries.iter().map(|e| (e.entity, e.aabb, e.layers)));
    choose_axis(frame.as_ref(), state);
    let axis = state.axis;
    // Last run's order, minus the entities gone, plus the new ones at the end.
    let mut seen = vec![false; entries.len()];
    let mut order: Vec<u32> = Vec::with_capacity(entries.len());
    for e in &state.order {
        if let Some(&i) = frame.index.get(e) {
            seen[i as usize] = true;
            order.push(i);
        }
    }
    order.extend((0..entries.len() as u32).filter(|&i| !seen[i as usize]));
    let key = |i: u32| entries[i as usize].aabb.min[axis];
    let axis_changed = std::mem::replace(&mut state.last_axis, axis) != axis;
    let new = order.len() - seen.iter().filter(|&&s| s).count();
    if axis_changed || new > order.len() / 4 {
        order.sort_by(|&x, &y| key(x).total_cmp(&key(y)).then(x.cmp(&y)));
    } else {
        // Insertion sort: linear for an almost sorted order; ties by index (deterministic).
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
    // Lanes along the second axis, each swept on its own over compact copies in sorted order
    // (the entries are large and scattered): a box is in every lane it covers, and a pair is
    // reported in the first lane both are in. Far fewer boxes overlap along the sweep axis
    // within a lane than in the whole world (rows of a pile).
    let second = state.second;
    let (lo, hi) = entries.iter().fold((f32::MAX, f32::MIN), |(lo, hi), e| {
        (lo.min(e.aabb.min[second]), hi.max(e.aabb.max[second]))
    });
    let lanes = ((entries.len() as f32).sqrt() as usize / 2).clamp(1, 32);
    let scale = (lanes as f32 - 1e-3) / (hi - lo).max(1e-6);
    let lane = |v: f32| (((v - lo) * scale).max(0.0) as usize).min(lanes - 1);
    let members = &mut state.lanes;
    members.resize_with(lanes, Vec::new);
    members.iter_mut().for_each(Vec::clear);
    for &i in &order {
        let e = &entries[i as usize];
        let (l0, l1) = (lane(e.aabb.min[second]), lane(e.aabb.max[second]));
        for m in &mut members[l0..=l1] {
            m.push(SweepBox {
                aabb: e.aabb,
                layers: e.layers,
                index: i,
                first_lane: l0 as u32,
            });
        }
    }
    let lane_ids: Vec<u32> = (0..lanes as u32).collect();
    let members = &state.lanes;
    pool.map_chunks_into(&lane_ids, 1, &mut state.found, |ls, found| {
        for &l in ls {
            let boxes = &members[l as usize];
            for (k, bi) in boxes.iter().enumerate() {
                let max = bi.aabb.max[axis];
                for bj in &boxes[k + 1..] {
                    if bj.aabb.min[axis] > max {
                        break;
                    }
                    if bi.first_lane.max(bj.first_lane) == l
                        && bi.aabb.intersects(&bj.aabb)
                        && bi.layers.interacts_with(&bj.layers)
                    {
                        found.push(CandidatePair {
                            a: bi.index.min(bj.index),
                            b: bi.index.max(bj.index),
                        });
                    }
                }
            }
        }
    });
    sort_pairs(&state.found, entries.len(), &mut state.by_b, &mut out.pairs);
    let pairs = &out.pairs;
    state.order = order.iter().map(|&i| entries[i as usize].entity).collect();
    diag.record(Stage::BroadPhase, start.elapsed(), pairs.len() as u64);
}

/// A box in a lane of the sweep.
#[derive(Debug, Clone, Copy)]
struct SweepBox {
    aabb: Aabb,
    layers: CollisionLayers,
    /// Index of the entry.
    index: u32,
    /// The first lane the box is in (a pair is reported there).
    first_lane: u32,
}

/// Sorts `found` (entry indices below `n`) into `out` by `(a, b)`: two counting sorts, by `b`
/// (into `by_b`) then stably by `a` (linear; a comparison sort of thousands of pairs costs several times
/// more).
fn sort_pairs(
    found: &[Vec<CandidatePair>],
    n: usize,
    by_b: &mut Vec<CandidatePair>,
    out: &mut Vec<CandidatePair>,
) {
    let total: usize = found.iter().map(Vec::len).sum();
    by_b.clear();
    by_b.resize(total, CandidatePair { a: 0, b: 0 });
    counting_sort(found.iter().flatten(), n, |p| p.b, by_b);
    out.clear();
    out.resize(total, CandidatePair { a: 0, b: 0 });
    counting_sort(by_b.iter(), n, |p| p.a, out);
}

/// Stable counting sort of `items` by `key` (below `n`) into `out` (of the same length).
fn counting_sort<'a>(
    items: impl Iterator<Item = &'a CandidatePair> + Clone,
    n: usize,
    key: impl Fn(&CandidatePair) -> u32,
    out: &mut [CandidatePair],
) {
    let mut next = vec![0u32; n + 1];
    for p in items.clone() {
        next[key(p) as usize + 1] += 1;
    }
    for i in 1..=n {
        next[i] += next[i - 1];
    }
    for p in items {
        let slot = &mut next[key(p) as usize];
        out[*slot as usize] = *p;
        *slot += 1;
    }
}

/// Picks the sweep axis: the one along which the box centres spread most, measured by the
/// interquartile range of a sample (robust: one body falling away must not swing the axis).
/// Re-chosen only when another axis spreads 1.5 times as much. The second axis (for the slab
/// masks) is the next most spread one.
fn choose_axis(frame: &ColliderFrame, state: &mut BroadPhaseState) {
    let n = frame.entries.len();
    if n < 2 {
        return;
    }
    let step = n.div_ceil(64);
    let mut spread = [0.0f32; 3];
    let mut sample: Vec<f32> = Vec::with_capacity(64);
    for (axis, s) in spread.iter_mut().enumerate() {
        sample.clear();
        sample.extend(
            frame
                .entries
                .iter()
                .step_by(step)
                .map(|e| e.aabb.center()[axis]),
        );
        sample.sort_unstable_by(f32::total_cmp);
        let q = |f: f32| sample[((sample.len() - 1) as f32 * f) as usize];
        *s = q(0.75) - q(0.25);
    }
    let best = (0..3).fold(0, |b, a| if spread[a] > spread[b] { a } else { b });
    if state.order.is_empty() || spread[best] > 1.5 * spread[state.axis] {
        state.axis = best;
    }
    let (u, v) = ((state.axis + 1) % 3, (state.axis + 2) % 3);
    state.second = if spread[u] >= spread[v] { u } else { v };
}
