//! The budget controller: one resource that times every stage of a run with its clock, learns
//! what work costs, and plans how much of it fits in the frame budget.
use std::fmt;
use std::sync::Arc;
use std::time::{Duration, Instant};

use bevy_ecs::prelude::*;
use bevy_reflect::prelude::*;

use super::clock::{BudgetClock, SystemClock};
use super::costs::{PairCosts, WorkRate};
use crate::ecs::config::FrameBudget;
use crate::ecs::diagnostics::Stage;

/// What the controller planned for the last run under a time budget: read-only output (all
/// zero without a [`FrameBudget::Time`] budget, or before the narrow phase planned).
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Clone, Debug, Default, PartialEq)]
pub struct RunPlan {
    /// What the run aimed at: the budget less the margin learnt from overruns.
    pub target: Duration,
    /// What Prepare and BroadPhase took in the run (measured when the narrow phase planned).
    pub before_narrow: Duration,
    /// Time kept free after the narrow phase for Tracking and Report (what they took in the
    /// run before).
    pub after_narrow: Duration,
    /// Time the narrow phase's tests were given.
    pub tests: Duration,
    /// Pairs in the narrow phase's work list (active, not tracked).
    pub jobs: usize,
    /// Of those, pairs that needed a test, and how many the plan tests (every exact one and
    /// the most urgent others that fit).
    pub testable: usize,
    /// See [`RunPlan::testable`].
    pub planned_tests: usize,
    /// Pairs waiting for a test that the run took into its active list at most.
    pub waiting_quota: usize,
    /// When the trackers stop searching, from the run's start (`None`: no tracking ran).
    pub tracking_deadline: Option<Duration>,
    /// How far before the target that deadline was moved: what the trackers' steps went on
    /// for past their deadline in the runs before (moving average).
    pub tracking_overrun: Duration,
}

/// How many tests the narrow phase runs and until when, as planned by
/// [`BudgetController::plan_tests`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TestPlan {
    /// Tests of pairs that do not insist on one (all but exact pairs), most urgent first.
    pub optional: usize,
    /// When the optional tests stop.
    pub deadline: Instant,
    /// When the exact tests stop: later, since the time the answers from memory were planned
    /// for is theirs too.
    pub exact_deadline: Instant,
    /// ADB node pairs the measured rate gets done in the time for tests.
    pub node_pairs: u64,
}

/// What a finished narrow phase measured, for [`BudgetController::learn_tests`].
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct TestsDone {
    /// Pairs tested, and the node pairs they visited (of which by exact tests).
    pub tested: usize,
    pub node_pairs: u64,
    pub exact_node_pairs: u64,
    /// Wall-clock time of the tests (the threads' summed test time over their parallelism).
    pub test_time: Duration,
    /// Jobs of the run, and the time they took besides their tests (answers kept, apart,
    /// recorded).
    pub jobs: usize,
    pub bookkeeping: Duration,
}

/// How a run ended: its collision time (Prepare to Report) and whether it went over a time
/// budget.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct RunEnd {
    pub collision_time: Duration,
    pub overran: bool,
}

/// The one place where the pipeline's budget is decided (a resource of the plugin).
///
/// Every stage is timed with the controller's clock ([`BudgetClock`]; the system clock unless
/// [`BudgetController::set_clock`] installs another, such as a test's [`FakeClock`]). Under a
/// [`FrameBudget::Time`] budget it plans each run from what it measured:
/// - the **target**: the budget less a margin that grows by half of each overrun (and a
///   fiftieth of the budget) and shrinks by a thousandth of the budget per run within it, at
///   most a quarter of the budget, so that the noise of the stages mostly stays inside;
/// - what **Prepare and BroadPhase** took in this run (they must run: every moved collider is
///   placed and its pairs found), measured when the narrow phase plans;
/// - what **Tracking and Report** took in the last run, kept free after the narrow phase;
/// - the **narrow phase** gets the rest: the cost of an answer from memory (moving average)
///   for each of its pairs, then tests: every exact pair (level geometry and what must not
///   pass through it) and the most urgent others that fit at the measured cost of a test (at
///   least a sixteenth of the budget, so that something always settles); ADB tests share the
///   node pairs the measured rate gets done in that time by priority; the pairs waiting for a
///   test that a run takes in are about twice what it can test, oldest first, so none starves;
/// - the **trackers** stop searching at the target less what Report took last time and less
///   what their steps went on for past that deadline in the runs before (a step cut at its
///   deadline still finishes an eighth of its searches; moving average, at most a quarter of
///   the budget), no earlier than a sixteenth of the budget after they start.
///
/// Pairs not tested keep their last answer, one run older, with a confidence that decays with
/// the motion since it was computed ([`PairView`](crate::ecs::PairView)); they wait for a test.
/// [`CollisionDiagnostics`](crate::ecs::CollisionDiagnostics) is the read-only record of what
/// happened; [`BudgetController::plan`] what was planned.
///
/// [`FakeClock`]: super::FakeClock
#[derive(Resource)]
pub struct BudgetController {
    clock: Arc<dyn BudgetClock>,
    run: u64,
    run_start: Instant,
    /// The refit began this run (the collider update then does not begin another).
    begun_early: bool,
    /// Stage times of the current run, by [`Stage`].
    stage_times: [Duration; 8],
    margin: Duration,
    /// Kept free after the narrow phase: what came after it in the last run.
    after_narrow: Duration,
    /// The Report stage's time in the last run.
    report_time: Duration,
    narrow_end: Option<Instant>,
    /// When the last tracking stage of the run (self-collision or tracking) ended.
    tracking_end: Option<Instant>,
    /// What the trackers' steps went on for past their deadline (moving average).
    tracking_overrun: Duration,
    costs: PairCosts,
    rate: WorkRate,
    /// Node pairs of the exact tests per run (moving average): not in the ADB share.
    exact_node_pairs: f64,
    /// Pairs tested in the last run.
    last_tests: usize,
    plan: RunPlan,
}

impl Default for BudgetController {
    fn default() -> Self {
        Self::with_clock(SystemClock)
    }
}

impl fmt::Debug for BudgetController {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("BudgetController")
            .field("clock", &self.clock)
            .field("run", &self.run)
            .field("margin", &self.margin)
            .field("after_narrow", &self.after_narrow)
            .field("costs", &self.costs)
            .field("rate", &self.rate)
            .field("plan", &self.plan)
            .finish_non_exhaustive()
    }
}

impl BudgetController {
    /// A controller reading `clock`.
    pub fn with_clock(clock: impl BudgetClock) -> Self {
        let clock: Arc<dyn BudgetClock> = Arc::new(clock);
        let now = clock.now();
        Self {
            clock,
            run: 0,
            run_start: now,
            begun_early: false,
            stage_times: [Duration::ZERO; 8],
            margin: Duration::ZERO,
            after_narrow: Duration::ZERO,
            report_time: Duration::ZERO,
            narrow_end: None,
            tracking_end: None,
            tracking_overrun: Duration::ZERO,
            costs: PairCosts::default(),
            rate: WorkRate::default(),
            exact_node_pairs: 0.0,
            last_tests: 0,
            plan: RunPlan::default(),
        }
    }

    /// Reads time from `clock` from now on (what was learnt stays).
    pub fn set_clock(&mut self, clock: impl BudgetClock) {
        self.clock = Arc::new(clock);
        self.run_start = self.clock.now();
        self.narrow_end = None;
    }

    /// The current time on the controller's clock.
    #[inline]
    pub fn now(&self) -> Instant {
        self.clock.now()
    }

    /// A handle on the clock, for work that runs outside the controller (the parallel tests,
    /// the response budget).
    pub(crate) fn clock(&self) -> Arc<dyn BudgetClock> {
        self.clock.clone()
    }

    /// The current (or last) run's number, counted from 1.
    pub fn run(&self) -> u64 {
        self.run
    }

    /// What was planned for the last run under a time budget.
    pub fn plan(&self) -> &RunPlan {
        &self.plan
    }

    /// How far below a time budget runs aim now (learnt from overruns).
    pub fn margin(&self) -> Duration {
        self.margin
    }

    /// The measured cost of one pair test, µs of wall-clock time with every thread testing.
    pub fn test_cost_us(&self) -> f64 {
        self.costs.test_us
    }

    /// The measured cost of a pair answered without a test (from memory, apart, bounds), µs.
    pub fn answer_cost_us(&self) -> f64 {
        self.costs.memory_us
    }

    /// The measured rate of ADB tests, node pairs per µs of wall-clock time.
    pub fn node_pairs_per_us(&self) -> f64 {
        self.rate.node_pairs_per_us
    }

    /// Starts a run, unless the refit began it already: `early` when called by the refit (the
    /// first system of a run when deformables moved), else by the collider update. Returns the
    /// run's number.
    pub(crate) fn begin_run(&mut self, early: bool) -> u64 {
        if std::mem::take(&mut self.begun_early) && !early {
            return self.run;
        }
        self.begun_early = early;
        self.run += 1;
        self.run_start = self.clock.now();
        self.stage_times = [Duration::ZERO; 8];
        self.narrow_end = None;
        self.tracking_end = None;
        self.plan = RunPlan::default();
        self.run
    }

    /// Adds the time from `start` to now to `stage` in this run and returns it.
    pub(crate) fn stage_done(&mut self, stage: Stage, start: Instant) -> Duration {
        let now = self.clock.now();
        let time = now.saturating_duration_since(start);
        self.stage_times[stage as usize] += time;
        if matches!(stage, Stage::SelfCollision | Stage::Tracking) {
            self.tracking_end = Some(now);
        }
        time
    }

    /// What the run aims at under a time `budget`: below it by the learnt margin, at most a
    /// quarter of the budget below.
    pub fn time_target(&self, budget: Duration) -> Duration {
        budget.saturating_sub(self.margin.min(budget / 4))
    }

    /// The waiting pairs a run takes into its active list under `budget` with `threads`
    /// testing: about twice what it can test (by the measured cost of a test, or what was
    /// tested last time), and a few more; `None` (all of them) without a time budget.
    pub(crate) fn waiting_quota(&mut self, budget: FrameBudget, threads: usize) -> Option<usize> {
        let FrameBudget::Time(budget) = budget else {
            return None;
        };
        let fit = budget.as_secs_f64() * 1e6 / self.costs.test_us.max(0.1);
        let fit = fit as usize * threads;
        let quota = 2 * fit.max(self.last_tests) + 64;
        self.plan.waiting_quota = quota;
        Some(quota)
    }

    /// Plans the narrow phase's tests under a time `budget`: `jobs` pairs to answer, of
    /// which `testable` need a test and `exact` of those insist on one.
    pub(crate) fn plan_tests(
        &mut self,
        budget: Duration,
        jobs: usize,
        testable: usize,
        exact: usize,
    ) -> TestPlan {
        let target = self.time_target(budget);
        let now = self.clock.now();
        let spent = now.saturating_duration_since(self.run_start);
        let left_us = target
            .saturating_sub(spent)
            .saturating_sub(self.after_narrow)
            .as_secs_f64()
            * 1e6;
        // At least a sixteenth of the budget goes to tests, whatever the overhead: without
        // tests nothing ever settles (and pairs that stopped moving cannot be cached).
        let memory_us = jobs as f64 * self.costs.memory_us;
        let tests_us = (left_us - memory_us).max(budget.as_secs_f64() * 0.0625e6);
        let count = ((tests_us / self.costs.test_us.max(1e-3)) as usize).min(testable);
        let tests = Duration::from_secs_f64(tests_us * 1e-6);
        let deadline = now + tests;
        let node_pairs = (tests_us * self.rate.node_pairs_per_us - self.exact_node_pairs).max(0.0);
        self.plan = RunPlan {
            target,
            before_narrow: spent,
            after_narrow: self.after_narrow,
            tests,
            jobs,
            testable,
            planned_tests: count.max(exact.min(testable)),
            ..self.plan
        };
        TestPlan {
            optional: count.saturating_sub(exact),
            deadline,
            exact_deadline: deadline + Duration::from_secs_f64(memory_us * 1e-6),
            node_pairs: node_pairs as u64,
        }
    }

    /// Learns from a finished narrow phase: the cost of a test and of an answer without
    /// one, the rate of node pairs, the exact tests' share.
    pub(crate) fn learn_tests(&mut self, done: TestsDone) {
        self.last_tests = done.tested;
        self.rate
            .update(done.node_pairs, done.test_time.as_secs_f64() * 1e6);
        self.exact_node_pairs = 0.7 * self.exact_node_pairs + 0.3 * done.exact_node_pairs as f64;
        PairCosts::learn(&mut self.costs.test_us, done.tested, done.test_time);
        PairCosts::learn(&mut self.costs.memory_us, done.jobs, done.bookkeeping);
        self.narrow_end = Some(self.clock.now());
    }

    /// When the trackers of this run stop searching under `budget` (`None`: no time budget):
    /// the run's target less what the Report stage took last time and less what the trackers
    /// went on for past their deadline before, but no earlier than a sixteenth of the budget
    /// from now (without any search nothing converges).
    pub(crate) fn tracking_deadline(&mut self, budget: FrameBudget) -> Option<Instant> {
        let FrameBudget::Time(budget) = budget else {
            return None;
        };
        let now = self.clock.now();
        let end = self.run_start
            + self
                .time_target(budget)
                .saturating_sub(self.report_time)
                .saturating_sub(self.tracking_overrun);
        let deadline = end.max(now + budget / 16);
        self.plan.tracking_deadline = Some(deadline.saturating_duration_since(self.run_start));
        self.plan.tracking_overrun = self.tracking_overrun;
        Some(deadline)
    }

    /// Ends the collision stages of a run (at the end of the Report stage): the time kept
    /// free after the narrow phase next time, the margin under a time budget.
    pub(crate) fn end_run(&mut self, budget: FrameBudget) -> RunEnd {
        let now = self.clock.now();
        let collision_time = now.saturating_duration_since(self.run_start);
        let time = |s: Stage| self.stage_times[s as usize];
        self.report_time = time(Stage::Report);
        let after_stages = time(Stage::SelfCollision) + time(Stage::Tracking) + time(Stage::Report);
        self.after_narrow = match self.narrow_end.take() {
            Some(end) => now.saturating_duration_since(end).max(after_stages),
            None => after_stages,
        };
        let mut overran = false;
        if let (FrameBudget::Time(b), Some(deadline)) = (budget, self.plan.tracking_deadline) {
            // What the trackers did past their deadline (0 when they ended before it).
            let past = self.tracking_end.map_or(Duration::ZERO, |end| {
                end.saturating_duration_since(self.run_start + deadline)
            });
            self.tracking_overrun = self.tracking_overrun.mul_f64(0.8) + past.mul_f64(0.2);
            self.tracking_overrun = self.tracking_overrun.min(b / 4);
        }
        if let FrameBudget::Time(b) = budget {
            // Up by half the overrun and a fiftieth of the budget, down by a thousandth of
            // the budget per run within it: in balance, about one run in forty goes over, and
            // rarely by much (the margin follows a high quantile of the noise).
            if collision_time > b {
                overran = true;
                let over = collision_time - b;
                self.margin = (self.margin + over / 2 + b / 50).min(b / 4);
            } else {
                self.margin = self.margin.saturating_sub(b / 1000);
            }
        }
        RunEnd {
            collision_time,
            overran,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ecs::budget::FakeClock;

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    fn controller() -> (BudgetController, FakeClock) {
        let clock = FakeClock::new();
        (BudgetController::with_clock(clock.clone()), clock)
    }

    #[test]
    fn the_refit_and_the_update_begin_one_run() {
        let (mut c, _) = controller();
        assert_eq!(c.begin_run(true), 1);
        assert_eq!(c.begin_run(false), 1, "the update joins the refit's run");
        assert_eq!(c.begin_run(false), 2);
        assert_eq!(c.begin_run(false), 3);
    }

    #[test]
    fn the_narrow_phase_gets_what_the_other_stages_leave() {
        let (mut c, clock) = controller();
        let budget = ms(2);
        c.begin_run(false);
        clock.advance(Duration::from_micros(500));
        let plan = c.plan_tests(budget, 0, 1000, 0);
        // 1.5 ms left, a test costs 2 µs by default.
        assert_eq!(plan.optional, 750);
        assert_eq!(plan.deadline - c.run_start, ms(2));
        assert_eq!(c.plan().before_narrow, Duration::from_micros(500));
        // Answers from memory take their share first.
        c.begin_run(false);
        let plan = c.plan_tests(budget, 20_000, 1000, 0);
        // 2000 − 20 000 × 0.05 = 1000 µs of tests.
        assert_eq!(plan.optional, 500);
        // The exact pairs are all planned, and get the time of the answers too.
        let plan = c.plan_tests(budget, 20_000, 1000, 600);
        assert_eq!(plan.optional, 0);
        assert_eq!(c.plan().planned_tests, 600);
        assert!(plan.exact_deadline > plan.deadline);
    }

    #[test]
    fn stages_after_the_narrow_phase_are_kept_free_next_run() {
        let (mut c, clock) = controller();
        let budget = FrameBudget::Time(ms(2));
        c.begin_run(false);
        c.learn_tests(TestsDone::default());
        let t = c.now();
        clock.advance(Duration::from_micros(400));
        c.stage_done(Stage::Report, t);
        c.end_run(budget);
        c.begin_run(false);
        let plan = c.plan_tests(ms(2), 0, 10_000, 0);
        // 2000 − 400 µs of tests at 2 µs each.
        assert_eq!(plan.optional, 800);
        assert_eq!(c.plan().after_narrow, Duration::from_micros(400));
        // The trackers stop where the report's time begins.
        let deadline = c.tracking_deadline(budget).unwrap();
        assert_eq!(deadline - c.run_start, Duration::from_micros(1600));
    }

    /// Trackers that go on past their deadline have it moved earlier by about as much in the
    /// runs after; when they stop going over, it moves back.
    #[test]
    fn the_trackers_deadline_moves_earlier_by_what_they_ran_past_it() {
        let (mut c, clock) = controller();
        let budget = FrameBudget::Time(ms(2));
        let run = |c: &mut BudgetController, past: Duration| {
            c.begin_run(false);
            let start = c.now();
            let deadline = c.tracking_deadline(budget).unwrap();
            clock.advance((deadline - start) + past);
            c.stage_done(Stage::SelfCollision, start);
            c.end_run(budget);
            deadline - c.run_start
        };
        let first = run(&mut c, Duration::from_micros(300));
        assert_eq!(first, ms(2));
        let mut last = first;
        for _ in 0..40 {
            last = run(&mut c, Duration::from_micros(300));
        }
        // The overrun is learnt (the margin grows with the frames' overruns too).
        assert!(c.plan().tracking_overrun > Duration::from_micros(290));
        assert!(last <= first - Duration::from_micros(290), "{last:?}");
        // Never more than a quarter of the budget.
        for _ in 0..40 {
            run(&mut c, ms(10));
        }
        assert_eq!(c.plan().tracking_overrun, Duration::from_micros(500));
        // Trackers that stop in time bring it back.
        for _ in 0..100 {
            run(&mut c, Duration::ZERO);
        }
        assert!(c.plan().tracking_overrun < Duration::from_micros(5));
    }

    #[test]
    fn overruns_raise_the_margin_and_quiet_runs_lower_it() {
        let (mut c, clock) = controller();
        let budget = FrameBudget::Time(ms(2));
        c.begin_run(false);
        clock.advance(ms(20));
        let end = c.end_run(budget);
        assert!(end.overran);
        assert_eq!(end.collision_time, ms(20));
        // Capped at a quarter of the budget.
        assert_eq!(c.margin(), Duration::from_micros(500));
        assert_eq!(c.time_target(ms(2)), Duration::from_micros(1500));
        for _ in 0..100 {
            c.begin_run(false);
            clock.advance(ms(1));
            assert!(!c.end_run(budget).overran);
        }
        assert_eq!(c.margin(), Duration::from_micros(300));
        for _ in 0..300 {
            c.begin_run(false);
            c.end_run(budget);
        }
        assert_eq!(c.margin(), Duration::ZERO);
    }

    #[test]
    fn an_overloaded_run_still_tests_a_sixteenth_of_the_budget() {
        let (mut c, clock) = controller();
        c.begin_run(false);
        clock.advance(ms(30));
        let plan = c.plan_tests(ms(2), 100_000, 1000, 0);
        // 125 µs at 2 µs per test.
        assert_eq!(plan.optional, 62);
        assert_eq!(c.plan().tests, Duration::from_micros(125));
    }

    #[test]
    fn learnt_costs_change_the_plan() {
        let (mut c, _) = controller();
        c.begin_run(false);
        c.learn_tests(TestsDone {
            tested: 100,
            test_time: ms(1),
            node_pairs: 50_000,
            ..Default::default()
        });
        // 10 µs per test after one run of 100 tests at 10 µs: 0.8 × 2 + 0.2 × 10.
        assert!((c.test_cost_us() - 3.6).abs() < 1e-9);
        let quota = c.waiting_quota(FrameBudget::Time(ms(2)), 2).unwrap();
        assert_eq!(quota, 2 * (2000.0f64 / 3.6) as usize * 2 + 64);
        assert_eq!(c.waiting_quota(FrameBudget::Unlimited, 2), None);
    }
}
