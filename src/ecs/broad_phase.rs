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
    // Sweep over compact copies in sorted order (the entries are large and scattered). Each
    // box also gets a 64-bit mask of the slabs it covers along the second axis: one AND
    // rejects most boxes that overlap on the sweep axis only (rows of a pile).
    let second = state.second;
    let (lo, hi) = entries.iter().fold((f32::MAX, f32::MIN), |(lo, hi), e| {
        (lo.min(e.aabb.min[second]), hi.max(e.aabb.max[second]))
    });
    let scale = 63.999 / (hi - lo).max(1e-6);
    let slab = |v: f32| (((v - lo) * scale).clamp(0.0, 63.0)) as u32;
    let sweep: Vec<(f32, u64)> = order
        .iter()
        .map(|&i| {
            let b = &entries[i as usize].aabb;
            let (s0, s1) = (slab(b.min[second]), slab(b.max[second]));
            let mask = (u64::MAX >> (63 - s1)) & (u64::MAX << s0);
            (b.min[axis], mask)
        })
        .collect();
    let boxes: Vec<(Aabb, CollisionLayers)> = order
        .iter()
        .map(|&i| (entries[i as usize].aabb, entries[i as usize].layers))
        .collect();
    // Sweep in parallel over runs of the sorted order (the later boxes have fewer partners
    // ahead of them; a few chunks per thread even that out).
    let starts: Vec<usize> = (0..boxes.len()).collect();
    let found = pool.map_chunks(&starts, pool.chunk_size(boxes.len(), 64), |ks| {
        let mut found = Vec::new();
        for &k in ks {
            let (bi, li) = &boxes[k];
            let (max, mask) = (bi.max[axis], sweep[k].1);
            for (m, &(min, mj)) in sweep[k + 1..].iter().enumerate() {
                if min > max {
                    break;
                }
                if mask & mj == 0 {
                    continue;
                }
                let (bj, lj) = &boxes[k + 1 + m];
                if bi.intersects(bj) && li.interacts_with(lj) {
                    let (i, j) = (order[k], order[k + 1 + m]);
                    found.push(CandidatePair {
                        a: i.min(j),
                        b: i.max(j),
                    });
                }
            }
        }
        found
    });
    sort_pairs(
        found.iter().flatten().copied(),
        entries.len(),
        &mut out.pairs,
    );
    let pairs = &out.pairs;
    state.order = order.iter().map(|&i| entries[i as usize].entity).collect();
    diag.record(Stage::BroadPhase, start.elapsed(), pairs.len() as u64);
}

/// Sorts `found` into `out` by `(a, b)`: a counting sort by `a` (linear), then each run of
/// equal `a` (a box's few partners) by `b`.
fn sort_pairs(
    found: impl Iterator<Item = CandidatePair> + Clone,
    n: usize,
    out: &mut Vec<CandidatePair>,
) {
    let mut starts = vec![0u32; n + 1];
    let mut total = 0;
    for p in found.clone() {
        starts[p.a as usize + 1] += 1;
        total += 1;
    }
    for i in 1..=n {
        starts[i] += starts[i - 1];
    }
    out.clear();
    out.resize(total, CandidatePair { a: 0, b: 0 });
    let mut next = starts.clone();
    for p in found {
        out[next[p.a as usize] as usize] = p;
        next[p.a as usize] += 1;
    }
    for w in starts.windows(2) {
        out[w[0] as usize..w[1] as usize].sort_unstable_by_key(|p| p.b);
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
