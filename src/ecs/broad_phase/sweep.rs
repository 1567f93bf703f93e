//! Finding the new pairs of the moved fat boxes: sweep and prune over every fat box in lanes,
//! or, when few moved, a windowed search of the boxes kept sorted along one axis.
use super::super::layers::ContactLayers;
use super::super::pairs::PairTable;
use super::super::parallel::CollisionTaskPool;
use super::super::prepare::ColliderTable;
use super::super::stamp::stamp;
use super::{BroadPhaseState, linked};
use crate::geometry::Aabb;

/// Finds the new pairs of the moved boxes by sweep and prune over every fat box, in lanes.
pub(super) fn sweep(
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
pub(super) fn find_near_moved(
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
pub(super) fn sort_order(state: &mut BroadPhaseState) {
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
pub(super) struct SweepBox {
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
