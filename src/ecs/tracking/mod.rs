//! Tracking stage: pairs with [`Fidelity::Tracking`] and self-collision of deformable meshes.
//!
//! A self-colliding deformable mesh with [`Fidelity::Tracking`] and every pair whose fidelity
//! is `Tracking` run the stochastic closest-feature [`Tracker`]: its pairs persist from run to
//! run (in [`TrackingState`], one tracker per pair or mesh, seeded from the configured seed
//! and the two entities, so results do not depend on thread scheduling), and its contacts come
//! with points, normals and depths. Other self-colliding meshes get the exact BVH pass
//! (`self_intersections`). Trackers and surfaces run in parallel; the outcomes are merged in
//! pair order. Each entity's [`FeaturePairs`] lists the triangle pairs in contact with each
//! partner, as of the last run.
//!
//! [`Fidelity::Tracking`]: super::Fidelity::Tracking
//! [`SelfCollision`]: super::SelfCollision
mod feature_pairs;
mod trackers;

use std::sync::Arc;
use std::time::Duration;

use bevy_ecs::entity::EntityHashSet;
use bevy_ecs::prelude::*;
use smallvec::SmallVec;

use super::budget::BudgetController;
use super::components::Fidelity;
use super::config::CollisionConfig;
use super::contact::triangle_pair_contact;
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::narrow_phase::{Method, PairOutcome, spread, with_workspaces};
use super::pairs::PairTable;
use super::parallel::CollisionTaskPool;
use super::prepare::{ColliderEntry, ColliderTable};
use crate::bvh::self_intersections;

pub use feature_pairs::{FeaturePairs, prune_feature_pairs};
use feature_pairs::{NewFeaturePairs, record_pairs};
pub use trackers::TrackingState;
use trackers::{Job, job, run_jobs, update_surfaces};

/// The tracked pairs of this run: `(pair, collider a, collider b)`, self-collisions
/// (`a == b`) or pairs of two colliders.
fn tracked(pairs: &PairTable, self_pairs: bool) -> Vec<(u32, u32, u32)> {
    pairs
        .tracked
        .iter()
        .map(|&p| (p, pairs.ends(p).body_a, pairs.ends(p).body_b))
        .filter(|&(_, a, b)| (a == b) == self_pairs)
        .collect()
}

/// Run condition: the narrow phase handed over some self-colliding mesh.
pub fn needs_self_pass(pairs: Res<PairTable>) -> bool {
    pairs
        .tracked
        .iter()
        .any(|&p| pairs.ends(p).body_a == pairs.ends(p).body_b)
}

/// Run condition: the narrow phase handed over some tracked pair of two colliders.
pub fn needs_tracking(pairs: Res<PairTable>) -> bool {
    pairs
        .tracked
        .iter()
        .any(|&p| pairs.ends(p).body_a != pairs.ends(p).body_b)
}

/// What the Tracking stage's systems share: the tables, the trackers, the task pool.
#[derive(bevy_ecs::system::SystemParam)]
pub struct TrackingContext<'w, 's> {
    colliders: Res<'w, ColliderTable>,
    pairs: ResMut<'w, PairTable>,
    config: Res<'w, CollisionConfig>,
    pool: Res<'w, CollisionTaskPool>,
    state: ResMut<'w, TrackingState>,
    features: Query<'w, 's, &'static mut FeaturePairs>,
    commands: Commands<'w, 's>,
    budget: ResMut<'w, BudgetController>,
    diag: ResMut<'w, CollisionDiagnostics>,
}

/// Self-collision of every [`SelfCollision`] deformable mesh, in parallel per mesh: the
/// stochastic tracker for meshes with [`Fidelity::Tracking`], the exact pass for the others.
pub fn self_collision(mut cx: TrackingContext) {
    let start = cx.budget.now();
    let run = cx.budget.run();
    let meshes = tracked(&cx.pairs, true);
    let colliders = &*cx.colliders;
    let (stochastic, exact): (Vec<_>, Vec<_>) = meshes
        .iter()
        .partition(|&&(_, i, _)| matches!(colliders.entry(i).fidelity, Fidelity::Tracking { .. }));
    let max = cx.config.max_self_contacts;
    let results = cx.pool.map_chunks(&exact, 1, |chunk| {
        let (pair, i, _) = chunk[0];
        let e = colliders.entry(i);
        let mesh = e.geometry.mesh();
        with_workspaces(|ws, _, pairs| {
            pairs.clear();
            self_intersections(mesh, ws, pairs);
            let contacts: SmallVec<_> = spread(pairs, max)
                .map(|t| triangle_pair_contact(mesh, &e.pose, mesh, &e.pose, t))
                .collect();
            let ends = (e.entity, e.entity);
            let nodes = ws.node_pairs_visited();
            let o = PairOutcome::exact(ends, Method::SelfCollision, nodes, 1.0, contacts, run);
            (pair, o)
        })
    });
    cx.diag.counters.node_pairs += results.iter().map(|(_, o)| o.node_pairs).sum::<u64>();
    for (pair, o) in results {
        cx.pairs.answer(pair, o, None, run);
    }
    // The tracked pairs of the Tracking stage after this one share the time left too.
    let later = tracked(&cx.pairs, false).len();
    let jobs = tracked_jobs(&mut cx, &stochastic, later);
    finish_jobs(&mut cx, jobs, Method::SelfCollision);
    let time = cx.budget.stage_done(Stage::SelfCollision, start);
    cx.diag
        .record(Stage::SelfCollision, time, meshes.len() as u64);
}

/// The tracker jobs of `pairs` (`(pair, collider a, collider b)`; `a == b` for a
/// self-colliding mesh), run: the surfaces of the colliders involved brought up to date
/// first, at most `max_self_contacts` contacts each. Under a time budget each tracker spends
/// its share of the time left before the run's tracking deadline (shared with the `later`
/// trackers of the next stage, [`tracker_share`]) as its own time budget: its pairs per frame
/// grow where the share allows more and shrink where it allows less
/// ([`TrackerConfig::time_budget`](crate::tracking::TrackerConfig::time_budget)), and its
/// search is cut at the deadline.
fn tracked_jobs(cx: &mut TrackingContext, pairs: &[(u32, u32, u32)], later: usize) -> Vec<Job> {
    let (seed, max, run) = (cx.config.seed, cx.config.max_self_contacts, cx.budget.run());
    let deadline = cx.budget.tracking_deadline(cx.config.budget);
    let share = deadline.map(|d| {
        let left = d.saturating_duration_since(cx.budget.now());
        tracker_share(left, cx.pool.threads(), pairs.len() + later)
    });
    let mut involved: Vec<u32> = pairs.iter().flat_map(|&(_, a, b)| [a, b]).collect();
    involved.sort_unstable();
    involved.dedup();
    let colliders = &*cx.colliders;
    let entries: Vec<&ColliderEntry> = involved.iter().map(|&i| colliders.entry(i)).collect();
    let state = &mut *cx.state;
    update_surfaces(state, &entries, &cx.pool);
    let mut jobs: Vec<Job> = pairs
        .iter()
        .map(|&ends| job(state, colliders, ends, seed, share))
        .collect();
    run_jobs(&mut jobs, colliders, state, &cx.pool, (max, run), deadline);
    jobs
}

/// One tracker's share of `left`, the time until the run's tracking deadline, when `trackers`
/// trackers run on `threads` threads: `left` as long as each has a thread, else the part of
/// the threads' time that falls to each.
fn tracker_share(left: Duration, threads: usize, trackers: usize) -> Duration {
    let threads = threads.max(1);
    left.mul_f64(threads as f64 / trackers.max(threads) as f64)
}

/// Records finished jobs: answers in pair order, feature pairs, trackers kept.
fn finish_jobs(cx: &mut TrackingContext, jobs: Vec<Job>, method: Method) {
    let run = cx.budget.run();
    let mut new = NewFeaturePairs::default();
    for job in jobs {
        cx.diag.counters.tracker_steps_cut += u64::from(job.tracker.stats().cut);
        let evaluations = job.tracker.stats().evaluations;
        let o = PairOutcome::exact(job.key, method, evaluations, 1.0, job.contacts, run);
        cx.pairs.answer(job.pair, o, None, run);
        record_pairs(&mut cx.features, &mut new, job.key, &job.pairs);
        cx.state.trackers.insert(job.key, job.tracker);
    }
    new.insert(&mut cx.commands);
}

/// Tracked pairs: the stochastic tracker between the two meshes, in parallel per pair; its
/// contacts become the pair's contacts, at most `max_self_contacts` of them.
pub fn track_pairs(mut cx: TrackingContext) {
    let start = cx.budget.now();
    let pairs = tracked(&cx.pairs, false);
    let jobs = tracked_jobs(&mut cx, &pairs, 0);
    finish_jobs(&mut cx, jobs, Method::Tracking);
    let time = cx.budget.stage_done(Stage::Tracking, start);
    cx.diag.record(Stage::Tracking, time, pairs.len() as u64);
}

/// Run condition: something is being tracked (or was until now), so [`forget_untracked`]
/// has something to drop.
pub fn holds_tracking_state(state: Res<TrackingState>) -> bool {
    !(state.trackers.is_empty() && state.surfaces.is_empty() && state.shared.is_empty())
}

/// Drops trackers and surfaces of entities that are no longer tracked (despawned, or moved to
/// another fidelity), after the Tracking stage: memory stays bounded however long the app runs.
pub fn forget_untracked(pairs: Res<PairTable>, mut state: ResMut<TrackingState>) {
    let mut live: EntityHashSet = EntityHashSet::default();
    let mut keys: std::collections::HashSet<(Entity, Entity)> = Default::default();
    for &p in &pairs.tracked {
        let s = pairs.slot(p);
        live.insert(s.a);
        live.insert(s.b);
        keys.insert((s.a, s.b));
    }
    state.trackers.retain(|k, _| keys.contains(k));
    state.surfaces.retain(|e, _| live.contains(e));
    let used: std::collections::HashSet<usize> = state
        .surfaces
        .values()
        .map(|s| Arc::as_ptr(&s.surface) as usize)
        .collect();
    state
        .shared
        .retain(|_, s| used.contains(&(Arc::as_ptr(s) as usize)));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_tracker_gets_its_part_of_the_threads_time() {
        let ms = Duration::from_millis;
        // As many trackers as threads or fewer: each has a thread for the whole time.
        assert_eq!(tracker_share(ms(2), 2, 1), ms(2));
        assert_eq!(tracker_share(ms(2), 2, 2), ms(2));
        // More: the threads' time shared out.
        assert_eq!(tracker_share(ms(2), 2, 8), Duration::from_micros(500));
        assert_eq!(tracker_share(ms(3), 1, 3), ms(1));
        // No tracker or no thread counted: as one.
        assert_eq!(tracker_share(ms(2), 0, 0), ms(2));
    }
}
