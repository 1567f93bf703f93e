//! Broad phase: sweep and prune over world boxes, with temporal coherence.
//!
//! The entities stay sorted by their box's lower bound on one axis from run to run; each run
//! re-sorts with an insertion sort, which is linear when little moved (the usual case), then
//! sweeps. The axis is the one along which the box centres spread most, chosen once and
//! re-chosen only when another axis spreads twice as much (a change of axis costs one full sort).
use std::time::Instant;

use bevy_ecs::prelude::*;

use super::diagnostics::{CollisionDiagnostics, Stage};
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
    last_axis: usize,
}

/// Collects the candidate pairs of the run.
pub fn sweep_and_prune(
    frame: Res<ColliderFrame>,
    mut state: ResMut<BroadPhaseState>,
    mut out: ResMut<CandidatePairs>,
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
    let pairs = &mut out.pairs;
    pairs.clear();
    for (k, &i) in order.iter().enumerate() {
        let ei = &entries[i as usize];
        let max = ei.aabb.max[axis];
        for &j in &order[k + 1..] {
            let ej = &entries[j as usize];
            if ej.aabb.min[axis] > max {
                break;
            }
            if !ei.aabb.intersects(&ej.aabb) || !ei.layers.interacts_with(&ej.layers) {
                continue;
            }
            pairs.push(CandidatePair {
                a: i.min(j),
                b: i.max(j),
            });
        }
    }
    pairs.sort_unstable();
    state.order = order.iter().map(|&i| entries[i as usize].entity).collect();
    diag.record(Stage::BroadPhase, start.elapsed(), pairs.len() as u64);
}

fn choose_axis(frame: &ColliderFrame, state: &mut BroadPhaseState) {
    let n = frame.entries.len() as f32;
    if n < 2.0 {
        return;
    }
    let (mut sum, mut sq) = (glam::Vec3::ZERO, glam::Vec3::ZERO);
    for e in &frame.entries {
        let c = e.aabb.center();
        sum += c;
        sq += c * c;
    }
    let var = sq / n - (sum / n) * (sum / n);
    let best = if var.x >= var.y && var.x >= var.z {
        0
    } else if var.y >= var.z {
        1
    } else {
        2
    };
    if state.order.is_empty() || var[best] > 2.0 * var[state.axis] {
        state.axis = best;
    }
}
