//! Narrow phase: the active pairs of the [`PairTable`] answered by their fidelity, in
//! parallel, inside the budget.
//!
//! Only active pairs are worked on (new, moved, unsettled, or waiting for a test): a pair
//! whose colliders did not change keeps its settled answer and costs nothing. Each active
//! pair gets a priority ([`pair_priority`](super::pair_priority): last confidence,
//! closeness, speed, waiting). Under a time budget the [`BudgetController`] plans how many
//! tests fit (by the measured cost of a test): the exact pairs, then a quarter of the rest
//! for the pairs that waited longest and the others by priority, run longest waiting first
//! so that a deadline cuts the freshest answers; the rest keep their last answer, one run
//! older, and wait for a test (an exact pair past its deadline gets an answer from memory,
//! [`Method::Coherence`]). Tested ADB pairs get node-pair slices of the budget in
//! proportion to their priority, and an ADB traversal stops at its slice and reports its
//! best estimate. Jobs are planned, then tested, on the task pool, each thread with its own
//! workspaces and each run of jobs writing its answers in place; they are recorded in the
//! table in job order, so the outcome is the same for any number of threads.
mod contained;
mod continuous;
mod execute;
mod memory;
mod outcome;
mod plan;

use bevy_ecs::prelude::*;

use super::budget::{BudgetController, SliceShare, TestsDone};
use super::config::{CollisionConfig, FrameBudget};
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::pairs::{PairEnds, PairTable};
use super::parallel::CollisionTaskPool;
use super::prepare::ColliderTable;
use super::stamp::stamp;
use execute::{Answer, ChunkWork, Context, Deadlines, RunCounts, apart_answer};
pub(crate) use execute::{spread, with_workspaces};
pub(crate) use memory::{PairMemory, decayed_probability};
pub use outcome::{Method, PairOutcome};
use plan::{Job, PlanCounts, choose_tests, pair_method, plan_jobs};

/// What the narrow phase keeps between runs: reused buffers (the measured costs are the
/// [`BudgetController`]'s).
#[derive(Resource, Debug, Default)]
pub struct NarrowPhaseState {
    jobs: Vec<Job>,
    found: Vec<Vec<u32>>,
    work: Vec<Job>,
    answers: Vec<Answer>,
    plan_counts: Vec<PlanCounts>,
    run_counts: Vec<RunCounts>,
    oldest: Vec<(u32, u32)>,
    /// The run of the last change of configuration: answers found before it are not reused
    /// as they are.
    config_run: u64,
}

/// Answers the active pairs (all but tracked ones) in parallel.
///
/// Under a time budget, the pairs tested are the most urgent ones that fit, as the
/// [`BudgetController`] plans them; the others keep their last answer and wait less next
/// time. The deadline stays as a safety net for the tests themselves.
pub fn narrow_phase(
    colliders: Res<ColliderTable>,
    mut pairs: ResMut<PairTable>,
    config: Res<CollisionConfig>,
    pool: Res<CollisionTaskPool>,
    mut state: ResMut<NarrowPhaseState>,
    mut budget: ResMut<BudgetController>,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    let start = budget.now();
    let state = &mut *state;
    let run = budget.run();
    let config_changed = config.is_changed();
    if config_changed {
        state.config_run = run;
    }
    let config_run = state.config_run;
    // Under a time budget, the waiting pairs taken are about twice as many as could be
    // tested (the rest waits).
    let quota = budget.waiting_quota(config.budget, pool.threads());
    activate(
        &colliders,
        &mut pairs,
        &pool,
        &mut state.found,
        quota,
        run,
        config_changed,
    );
    // Each active pair's job, planned in parallel over runs of them.
    let jobs = &mut state.jobs;
    jobs.clear();
    jobs.resize(pairs.active.len(), Job::new(0, 0, 0));
    let chunk = pool.chunk_size(jobs.len(), 256);
    let plans = &mut state.plan_counts;
    plans.clear();
    plans.resize(jobs.len().div_ceil(chunk), PlanCounts::default());
    {
        let (colliders, pairs) = (&*colliders, &*pairs);
        let mut work: Vec<_> = jobs
            .chunks_mut(chunk)
            .zip(pairs.active.chunks(chunk))
            .zip(plans.iter_mut())
            .collect();
        pool.for_each_mut(&mut work, 1, |((c, active), counts)| {
            for (job, &p) in c.iter_mut().zip(active.iter()) {
                let e = pairs.ends(p);
                *job = Job::new(p, e.body_a, e.body_b);
            }
            **counts = plan_jobs(c, colliders, pairs, run, config_run);
        });
    }
    let plan = plans.iter().fold(PlanCounts::default(), PlanCounts::add);
    // Tracked pairs and self-collisions go to the Tracking stage; the others keep their order.
    if plan.tracked > 0 {
        let tracked = &mut pairs.tracked;
        jobs.retain(|j| {
            if j.tracked() {
                tracked.push(j.pair);
            }
            !j.tracked()
        });
    }
    // Which pairs are tested: all of them, or under a time budget the exact pairs (asked for:
    // level geometry, things that must not pass through each other) and the most urgent of
    // the others that fit.
    let (fit, deadlines, nodes) = match config.budget {
        FrameBudget::Time(time) => {
            let testable = plan.testable as usize;
            let exact = testable - plan.optional.iter().sum::<u32>() as usize;
            let tests = budget.plan_tests(time, jobs.len(), testable, exact);
            let deadlines = Deadlines::at(tests.deadline, tests.exact_deadline);
            let fit = (tests.optional, plan.optional);
            (Some(fit), deadlines, Some(tests.node_pairs))
        }
        FrameBudget::NodePairs(n) => (None, Deadlines::default(), Some(n)),
        FrameBudget::Unlimited => (None, Deadlines::default(), None),
    };
    let chosen_at = budget.now();
    let chosen = choose_tests(jobs, fit, &mut state.oldest);
    // ADB slices: the node pairs of the budget shared among the tested ADB pairs by priority.
    // In time mode the tests were chosen by what a test costs, so each gets enough to settle
    // (an eighth of the largest slice at least): a test cut short is wasted, tested again
    // next run and never answered from memory; the deadline still bounds the whole.
    let min_slice = match config.budget {
        FrameBudget::Time(_) => config.timed_slice_floor(),
        _ => config.min_slice,
    };
    let share = nodes.map(|total| {
        SliceShare::from_sum(
            chosen.adb,
            chosen.adb_priority,
            total,
            min_slice,
            config.max_slice,
        )
    });
    // The jobs that need work: the chosen tests, the pairs whose boxes came apart, the
    // bounds-only pairs. The others keep their last answer, as it is (cached: nothing moved)
    // or one run older.
    let work = &mut state.work;
    work.clear();
    let (mut kept, mut cached) = (0u64, 0u64);
    for job in jobs.iter() {
        if job.chosen || job.apart || job.method == Method::Bounds {
            work.push(*job);
        } else {
            pairs.keep(job.pair, job.cached, run);
            cached += u64::from(job.cached);
            kept += u64::from(!job.cached);
        }
    }
    // A deadline cuts the tests that come last: the longest waiting come first (ties in job
    // order), so that a cut falls on the freshest answers and none starves.
    if deadlines.others.is_some() {
        work.sort_by_key(|j| std::cmp::Reverse(if j.chosen { j.stale } else { 0 }));
    }
    // Tests in parallel, each run of jobs writing its own slots.
    let n = work.len();
    let answers = &mut state.answers;
    answers.clear();
    answers.resize(n, Answer::Kept);
    let chunk = pool.chunk_size(n, 8);
    let counts = &mut state.run_counts;
    counts.clear();
    counts.resize(n.div_ceil(chunk), RunCounts::default());
    let run_start = budget.now();
    let clock = budget.clock();
    {
        let ctx = Context {
            colliders: &colliders,
            pairs: &pairs,
            config: &config,
            run,
            share,
            deadlines,
            node_pairs_per_us: budget.node_pairs_per_us(),
            clock: &*clock,
        };
        let mut chunks: Vec<_> = work
            .chunks(chunk)
            .zip(answers.chunks_mut(chunk))
            .zip(counts.iter_mut())
            .map(|((jobs, answers), counts)| ChunkWork {
                jobs,
                answers,
                counts,
            })
            .collect();
        pool.for_each_mut(&mut chunks, 1, |w| ctx.run_chunk(w));
    }
    let wall = budget.now().saturating_duration_since(run_start);
    for (job, answer) in work.iter().zip(answers.drain(..)) {
        match answer {
            Answer::Computed(outcome, record) => pairs.answer(job.pair, outcome, record, run),
            Answer::Kept => pairs.keep(job.pair, false, run),
        }
    }
    let total = counts.iter().fold(RunCounts::default(), RunCounts::add);
    // Wall-clock costs: the threads' times over the parallelism the section had.
    let busy = total.test_time + total.memory_time;
    let parallel =
        (busy.as_secs_f64() / wall.as_secs_f64().max(1e-9)).clamp(1.0, pool.threads() as f64);
    let test_time = total.test_time.div_f64(parallel);
    // What the jobs cost besides their tests once chosen (answers kept, apart, recorded).
    let bookkeeping = budget
        .now()
        .saturating_duration_since(chosen_at)
        .saturating_sub(test_time);
    let c = &mut diag.counters;
    c.node_pairs += total.node_pairs;
    c.adb_pairs += u64::from(plan.adb);
    c.exact_pairs += total.exact_pairs;
    c.budget_exhausted_pairs += total.budget_exhausted;
    c.coherence_pairs += total.coherence + kept;
    c.confirmed_pairs += total.confirmed;
    c.swept_pairs += total.swept;
    c.caught_by_sweep += total.caught;
    c.cached_pairs += cached;
    c.tested_pairs += total.tested;
    c.test_time += test_time;
    budget.learn_tests(TestsDone {
        tested: total.tested as usize,
        node_pairs: total.node_pairs,
        exact_node_pairs: total.exact_node_pairs,
        test_time,
        jobs: jobs.len(),
        bookkeeping,
    });
    let time = budget.stage_done(Stage::NarrowPhase, start);
    diag.record(Stage::NarrowPhase, time, n as u64);
}

/// Answers the new pair `p` of two different colliders at once when their world boxes are
/// apart, as this run's narrow phase would (not colliding, exactly; quiet until a collider's
/// world box meets the other's), so that it needs no job; returns whether it did. A broad
/// phase whose boxes moved far in one run creates thousands of such pairs (their fat boxes
/// overlap, their world boxes not yet).
pub(crate) fn answer_if_apart(
    colliders: &ColliderTable,
    pairs: &mut PairTable,
    p: u32,
    run: u64,
) -> bool {
    let e = pairs.ends(p);
    let (a, b) = (e.body_a, e.body_b);
    let plans = colliders.plans();
    let (pa, pb) = (&plans[a as usize], &plans[b as usize]);
    if a == b || pa.aabb.intersects(&pb.aabb) {
        return false;
    }
    let mut job = Job::new(p, a, b);
    (job.method, job.p_min) = pair_method(pa, pb);
    job.apart = true;
    let (o, r) = apart_answer(&job, (colliders.entry(a), colliders.entry(b)), run);
    pairs.answer(p, o, Some(r), run);
    true
}

/// Builds this run's active list: every pair after a change of configuration; otherwise the
/// pairs of the colliders that changed in this run and the pairs left pending by the last
/// run (new, unsettled, answered from memory, tracked), each once, in an order that depends
/// only on the history of the table.
///
/// Most pairs of a moving collider are close but apart (their fat boxes overlap, their world
/// boxes do not): where such a pair was apart already, its answer stands, confirmed, without
/// a job. When most colliders changed, every pair is checked in one parallel pass in slot
/// order; otherwise the changed colliders' pairs are.
fn activate(
    colliders: &ColliderTable,
    pairs: &mut PairTable,
    pool: &CollisionTaskPool,
    found: &mut Vec<Vec<u32>>,
    quota: Option<usize>,
    run: u64,
    config_changed: bool,
) {
    pairs.active.clear();
    let mut pending = std::mem::take(&mut pairs.pending);
    let (boxes, now) = (colliders.boxes(), stamp(run));
    let check = |p: u32, e: &mut PairEnds, active: &mut Vec<u32>| {
        if e.excluded {
            // Rejected by the pair filter: never worked on.
        } else if e.quiet && !boxes[e.body_a as usize].intersects(&boxes[e.body_b as usize]) {
            e.checked_run = now;
        } else if e.active_run != now {
            e.active_run = now;
            active.push(p);
        }
    };
    let changed = colliders.changed();
    if config_changed {
        for i in 0..pairs.slots.len() as u32 {
            pairs.activate(i, run);
        }
    } else if changed.len() * 4 > colliders.len() {
        let chunk = pool.chunk_size(pairs.ends.len(), 4096);
        found.resize_with(pairs.ends.len().div_ceil(chunk), Vec::new);
        let mut work: Vec<_> = pairs
            .ends
            .chunks_mut(chunk)
            .zip(found.iter_mut())
            .enumerate()
            .map(|(k, (ends, out))| (k * chunk, ends, out))
            .collect();
        pool.for_each_mut(&mut work, 1, |(first, ends, out)| {
            out.clear();
            for (k, e) in ends.iter_mut().enumerate() {
                let (a, b) = (&boxes[e.body_a as usize], &boxes[e.body_b as usize]);
                if e.live && (a.stamp == now || b.stamp == now) {
                    check((*first + k) as u32, e, out);
                }
            }
        });
        drop(work);
        for f in found.iter() {
            pairs.active.extend_from_slice(f);
        }
    } else {
        for &body in changed {
            for &p in colliders.entry(body).pair_slots() {
                check(p, &mut pairs.ends[p as usize], &mut pairs.active);
            }
        }
    }
    for &p in &pending {
        pairs.activate(p, run);
    }
    // The longest waiting pairs, as many as this run may test.
    let quota = quota.unwrap_or(usize::MAX);
    let mut taken = 0;
    while taken < quota
        && let Some(p) = pairs.waiting.pop_front()
    {
        let e = &mut pairs.ends[p as usize];
        if e.live && e.waiting {
            e.waiting = false;
            taken += 1;
            pairs.activate(p, run);
        }
    }
    // Answers of this run put pairs on the pending list again, for the next run.
    for &p in &pending {
        pairs.ends[p as usize].pending_run = now.wrapping_sub(1);
    }
    pending.clear();
    pairs.pending = pending;
}
