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
///
/// Only a pair with a moved box can be new, so each lane is swept from its moved boxes: each
/// moved box against the boxes after it in sorted order that start within its extent, and
/// each box that did not move against the moved boxes after it that do. The work follows the
/// moved boxes and their neighbours, not every overlapping pair of the lane.
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
    let proxies = &state.proxies;
    let (lo, hi) = state
        .order
        .iter()
        .fold((f32::MAX, f32::MIN), |(lo, hi), &i| {
            let b = &proxies[i as usize].fat;
            (lo.min(b.min[second]), hi.max(b.max[second]))
        });
    let lanes = ((state.order.len() as f32).sqrt() as usize / 2).clamp(1, 32);
    let scale = (lanes as f32 - 1e-3) / (hi - lo).max(1e-6);
    let lane = |v: f32| (((v - lo) * scale).max(0.0) as usize).min(lanes - 1);
    state.lanes.resize_with(lanes, Vec::new);
    state.lanes.iter_mut().for_each(Vec::clear);
    state.lanes_moved.resize_with(lanes, Vec::new);
    state.lanes_moved.iter_mut().for_each(Vec::clear);
    for &i in &state.order {
        let p = &proxies[i as usize];
        let (l0, l1) = (lane(p.fat.min[second]), lane(p.fat.max[second]));
        let moved = p.moved_run == now;
        let swept = SweepBox {
            aabb: p.fat,
            old: if moved { p.old_fat } else { p.fat },
            layers: p.layers,
            index: i,
            first_lane: l0 as u16,
            moved,
        };
        for l in l0..=l1 {
            let members = &mut state.lanes[l];
            if moved {
                state.lanes_moved[l].push(members.len() as u32);
            }
            members.push(swept);
        }
    }
    let lane_ids: [u32; 32] = std::array::from_fn(|l| l as u32);
    let (members, moved_members) = (&state.lanes, &state.lanes_moved);
    let (table, pair_table) = (colliders, pairs);
    pool.map_chunks_into(&lane_ids[..lanes], 1, &mut state.found, |ls, found| {
        for &l in ls {
            let (boxes, moved) = (&members[l as usize], &moved_members[l as usize]);
            let first = found.len();
            // Sorted positions `(k, m)`, `k` before `m`, of the lane's new pairs.
            let mut consider = |k: usize, m: usize| {
                let (bi, bj) = (&boxes[k], &boxes[m]);
                // Boxes that overlapped before this run's moves have their pair already
                // (pairs go only when the boxes part).
                if u32::from(bi.first_lane.max(bj.first_lane)) == l
                    && bi.aabb.intersects(&bj.aabb)
                    && !bi.old.intersects(&bj.old)
                    && bi.layers.interacts_with(&bj.layers)
                    && !linked(table, pair_table, bi.index, bj.index)
                {
                    found.push((k as u32, m as u32));
                }
            };
            // A moved box and the boxes after it that start within its extent.
            for &k in moved {
                let k = k as usize;
                let max = boxes[k].aabb.max[axis];
                for (m, bj) in boxes.iter().enumerate().skip(k + 1) {
                    if bj.aabb.min[axis] > max {
                        break;
                    }
                    consider(k, m);
                }
            }
            // A box that did not move and the moved boxes after it that start within its
            // extent (`next`: the first moved box after position `k`).
            let mut next = 0;
            for (k, bi) in boxes.iter().enumerate() {
                while next < moved.len() && moved[next] as usize <= k {
                    next += 1;
                }
                if bi.moved {
                    continue;
                }
                let max = bi.aabb.max[axis];
                for &m in &moved[next..] {
                    if boxes[m as usize].aabb.min[axis] > max {
                        break;
                    }
                    consider(k, m as usize);
                }
            }
            // In sorted order of the first box, then the second (the order of a sweep over
            // every pair of the lane), as slots.
            let lane_found = &mut found[first..];
            lane_found.sort_unstable();
            for f in lane_found {
                *f = (boxes[f.0 as usize].index, boxes[f.1 as usize].index);
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
    let proxies = &state.proxies;
    let chunk = pool.chunk_size(state.moved.len(), 16);
    pool.map_chunks_into(&state.moved, chunk, &mut state.found, |moved, found| {
        for &i in moved {
            let pi = &proxies[i as usize];
            let b = &pi.fat;
            let mut consider = |j: u32| {
                if j == i {
                    return;
                }
                let pj = &proxies[j as usize];
                let (bj, j_moved) = (&pj.fat, pj.moved_run == now);
                // Of two moved boxes, the one of the smaller slot reports.
                let old_j = if j_moved { &pj.old_fat } else { bj };
                if (j_moved && j < i)
                    || !b.intersects(bj)
                    || pi.old_fat.intersects(old_j)
                    || !pi.layers.interacts_with(&pj.layers)
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
        let proxies = &mut state.proxies;
        state.order.retain(|&i| {
            let p = &mut proxies[i as usize];
            p.listed = p.present;
            p.present
        });
        state.removed = 0;
    }
    let new = state.added.len();
    state.order.append(&mut state.added);
    let mut order = std::mem::take(&mut state.order);
    if new * 4 > order.len() {
        choose_axes(state, &order);
        let (proxies, axis) = (&state.proxies, state.axis);
        order.sort_unstable_by(|&x, &y| {
            proxies[x as usize].fat.min[axis]
                .total_cmp(&proxies[y as usize].fat.min[axis])
                .then(x.cmp(&y))
        });
    } else {
        let (proxies, axis) = (&state.proxies, state.axis);
        let key = |i: u32| proxies[i as usize].fat.min[axis];
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
    let (proxies, axis) = (&state.proxies, state.axis);
    let extent = |i: u32| {
        let b = &proxies[i as usize].fat;
        b.max[axis] - b.min[axis]
    };
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
        let b = &proxies[i as usize].fat;
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
/// interquartile range of all of them: one body falling away must not swing the axis), and
/// the lanes' axis, the next most spread one. Every box counts: a sample at a fixed stride can
/// alias with a regular layout (bodies spawned in rows of 16 and sampled every 16th all share
/// one coordinate, which then looks like no spread at all).
fn choose_axes(state: &mut BroadPhaseState, order: &[u32]) {
    if order.len() < 2 {
        return;
    }
    let mut spread = [0.0f32; 3];
    let mut centres: Vec<f32> = Vec::with_capacity(order.len());
    for (axis, s) in spread.iter_mut().enumerate() {
        centres.clear();
        centres.extend(
            order
                .iter()
                .map(|&i| state.proxies[i as usize].fat.center()[axis]),
        );
        *s = interquartile_range(&mut centres);
    }
    state.axis = (0..3).fold(0, |b, a| if spread[a] > spread[b] { a } else { b });
    let (u, v) = ((state.axis + 1) % 3, (state.axis + 2) % 3);
    state.second = if spread[u] >= spread[v] { u } else { v };
}

/// The interquartile range of `values` (at least one; reordered).
fn interquartile_range(values: &mut [f32]) -> f32 {
    let last = values.len() - 1;
    let mut quantile = |f: f32| {
        let k = (last as f32 * f) as usize;
        *values.select_nth_unstable_by(k, f32::total_cmp).1
    };
    let q1 = quantile(0.25);
    quantile(0.75) - q1
}

/// A fat box in a lane of the sweep: what the sweep reads of a box, copied in sorted order
/// (64 bytes).
#[derive(Debug, Clone, Copy)]
pub(super) struct SweepBox {
    aabb: Aabb,
    /// The fat box before this run's move (the same when it did not move).
    old: Aabb,
    layers: ContactLayers,
    /// The collider's slot.
    index: u32,
    /// The first lane the box is in (a pair is reported there).
    first_lane: u16,
    /// The fat box moved in this run (only pairs with a moved box can be new).
    moved: bool,
}

const _: () = assert!(std::mem::size_of::<SweepBox>() == 64);

#[cfg(test)]
mod tests {
    use super::super::{BroadPhaseState, Proxy};
    use super::*;
    use glam::Vec3;

    #[test]
    fn the_axes_follow_the_spread_of_every_box_even_in_rows() {
        // 1024 boxes in 4 layers (y) of 16 × 16 (x fastest, then z), as bodies are spawned in
        // rows: they spread along x and z, less along y. Every 16th box in slot order has the
        // same x: a sample at that stride sees no spread along x and picks y for the lanes.
        let mut state = BroadPhaseState::default();
        for i in 0..1024u32 {
            let (layer, k) = (i / 256, i % 256);
            let c = Vec3::new(
                (k % 16) as f32 * 0.6,
                layer as f32 * 1.2,
                (k / 16) as f32 * 0.6,
            );
            state.proxies.push(Proxy {
                fat: Aabb::new(c - 0.25, c + 0.25),
                ..Proxy::default()
            });
        }
        let order: Vec<u32> = (0..1024).collect();
        choose_axes(&mut state, &order);
        let mut chosen = [state.axis, state.second];
        chosen.sort_unstable();
        assert_eq!(chosen, [0, 2], "sweep and lanes along x and z");
    }

    #[test]
    fn the_interquartile_range_ignores_the_outliers() {
        let mut v = [5.0, 1.0, 2.0, 3.0, 4.0, -1000.0, 1000.0, 2.5, 3.5];
        assert_eq!(interquartile_range(&mut v), 2.0);
        assert_eq!(interquartile_range(&mut [7.0]), 0.0);
    }
}
