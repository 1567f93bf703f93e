//! Planning a run of the narrow phase: each active pair's method, whether its last answer
//! still holds, its priority; which pairs are tested under the budget.
use super::super::budget::pair_priority;
use super::super::components::Fidelity;
use super::super::pairs::PairTable;
use super::super::prepare::{BodyPlan, ColliderTable};
use super::outcome::Method;

/// One active pair's work in this run.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Job {
    /// The pair's slot in the [`PairTable`].
    pub pair: u32,
    /// The colliders' slots in the [`ColliderTable`] (the first is the smaller entity's).
    pub body_a: u32,
    pub body_b: u32,
    pub method: Method,
    /// Priority bucket (0: highest), for choosing the pairs tested under a time budget.
    pub bucket: u8,
    /// The world boxes are apart: certainly not colliding, no test needed.
    pub apart: bool,
    /// The last answer is settled and still holds (answered from memory, no test needed).
    pub cached: bool,
    /// Tested in this run ([`choose_tests`]).
    pub chosen: bool,
    pub p_min: f64,
    /// Runs the pair's last answer was kept without a test (0: tested in the last run;
    /// `u32::MAX`: never tested).
    pub stale: u32,
    pub priority: f32,
    /// A collider swept in this run
    /// ([`ContinuousCollision`](super::super::ContinuousCollision)): a test put off to a later
    /// run would miss what happened during this run's motion, so it is never put off.
    pub swept: bool,
}

impl Job {
    /// A job not planned yet.
    pub fn new(pair: u32, body_a: u32, body_b: u32) -> Self {
        Self {
            pair,
            body_a,
            body_b,
            method: Method::Tracking,
            bucket: 0,
            apart: false,
            cached: false,
            chosen: false,
            p_min: 1.0,
            stale: 0,
            priority: 0.0,
            swept: false,
        }
    }

    /// Needs a test (not apart, not answered from a still valid memory, not bounds-only).
    pub fn testable(&self) -> bool {
        !self.apart && !self.cached && self.method != Method::Bounds
    }

    /// Needs a test, and is tested only if the budget allows (not an exact pair, not swept).
    pub fn optional(&self) -> bool {
        self.testable() && !self.mandatory()
    }

    /// Tested whatever the budget: an exact pair, or a swept one.
    pub fn mandatory(&self) -> bool {
        self.method == Method::Exact || self.swept
    }

    /// Handed over to the Tracking stage (tracked pairs, self-collision).
    pub fn tracked(&self) -> bool {
        !self.apart && matches!(self.method, Method::Tracking | Method::SelfCollision)
    }
}

/// Fills in each job of a run of active pairs: its method (`Tracking` and `SelfCollision`:
/// handed over to the Tracking stage), whether the boxes are apart, whether the last answer
/// still holds, and its priority (`run`: this run's number; `config_run`: the run of the
/// last change of configuration, before which no answer is reused as is).
pub(crate) fn plan_jobs(
    jobs: &mut [Job],
    colliders: &ColliderTable,
    pairs: &PairTable,
    run: u64,
    config_run: u64,
) -> PlanCounts {
    let plans = colliders.plans();
    for job in jobs.iter_mut() {
        let (ea, eb) = (&plans[job.body_a as usize], &plans[job.body_b as usize]);
        if job.body_a == job.body_b {
            job.method = Method::SelfCollision;
            continue;
        }
        (job.method, job.p_min) = pair_method(ea, eb);
        if !ea.aabb.intersects(&eb.aabb) {
            job.apart = true;
            continue;
        }
        job.swept = ea.swept_run == run || eb.swept_run == run;
        if job.method == Method::Tracking {
            continue;
        }
        let memory = pairs.hot(job.pair).memory.as_ref();
        // Settled, asked for the same way, under this configuration, and neither pose nor
        // geometry changed since: the answer still holds.
        job.cached = memory.is_some_and(|m| {
            m.settled
                && (m.method, m.p_min) == (job.method, job.p_min)
                && m.tested_run >= ea.still_since.max(eb.still_since).max(config_run)
        });
        // A cached answer that does not collide needs no priority (no test, no contact).
        if job.cached && !memory.is_some_and(|m| m.collides) {
            continue;
        }
        // A pair whose boxes just met is as uncertain as a new one (its memory says only that
        // the boxes were apart).
        let mut priority = pair_priority(
            memory.filter(|m| !m.boxes_apart).map(|m| m.probability),
            &ea.aabb,
            &eb.aabb,
            eb.motion - ea.motion,
        );
        if job.mandatory() {
            // Exact pairs were asked for, swept ones cannot wait: tested before the others.
            priority *= 4.0;
        }
        // New pairs first, and pairs whose boxes just met (collisions start there); a pair
        // answered from memory waits less each run, so none starves under overload.
        match memory {
            None => priority *= 4.0,
            Some(m) if m.boxes_apart => priority *= 4.0,
            Some(m) => priority *= (1 + m.stale.min(15)) as f32,
        }
        // Both stopped (unchanged since the last run) but the answer is not settled: one test
        // now is answered from memory for as long as they rest.
        let still = ea.still_since < run && eb.still_since < run;
        if still && memory.is_some_and(|m| !m.settled) {
            priority *= 4.0;
        }
        job.priority = priority;
        job.bucket = priority_bucket(priority);
        job.stale = memory.map_or(u32::MAX, |m| m.stale);
    }
    PlanCounts::count(jobs)
}

/// How the pair of two different colliders is answered, and its `p_min`: by the combination
/// of their fidelities (an ADB pair with a deformable collider is answered exactly).
pub(crate) fn pair_method(ea: &BodyPlan, eb: &BodyPlan) -> (Method, f64) {
    match ea.fidelity.combine(eb.fidelity) {
        Fidelity::Tracking { .. } => (Method::Tracking, 1.0),
        Fidelity::Bounds => (Method::Bounds, 1.0),
        Fidelity::Exact => (Method::Exact, 1.0),
        Fidelity::Adb { p_min } if ea.rigid && eb.rigid => (Method::Adb, p_min),
        Fidelity::Adb { .. } => (Method::Exact, 1.0),
    }
}

/// Number of priority buckets ([`priority_bucket`]).
pub(crate) const BUCKETS: usize = 32;

/// The bucket of a priority: 0 for the highest, quarter steps of `log2` (read off the float's
/// exponent and two leading mantissa bits: monotone, no `log2` call).
pub(crate) fn priority_bucket(p: f32) -> u8 {
    // 2^-4 and below share the last bucket, 2^4 and above the first.
    let lowest = 2f32.powi(-4).to_bits() >> 21;
    let step = (p.max(0.0).to_bits() >> 21).saturating_sub(lowest);
    (BUCKETS as u32 - 1).saturating_sub(step) as u8
}

/// What a run of jobs counted while planning.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct PlanCounts {
    /// Optional jobs (tested if the budget allows) per priority bucket.
    pub optional: [u32; BUCKETS],
    /// Jobs that need a test (optional and exact).
    pub testable: u32,
    /// Jobs handed over to the Tracking stage.
    pub tracked: u32,
    /// ADB jobs.
    pub adb: u32,
}

impl PlanCounts {
    pub fn add(mut self, other: &Self) -> Self {
        for (a, b) in self.optional.iter_mut().zip(&other.optional) {
            *a += b;
        }
        self.testable += other.testable;
        self.tracked += other.tracked;
        self.adb += other.adb;
        self
    }

    pub fn count(jobs: &[Job]) -> Self {
        let mut counts = Self::default();
        for j in jobs {
            if j.optional() {
                counts.optional[usize::from(j.bucket)] += 1;
            }
            counts.testable += u32::from(j.testable());
            counts.tracked += u32::from(j.tracked());
            counts.adb += u32::from(j.method == Method::Adb && j.testable());
        }
        counts
    }
}

/// What [`choose_tests`] chose: how many, and the ADB ones' count and summed priority (for
/// their node-pair slices).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Chosen {
    pub count: usize,
    pub adb: u64,
    pub adb_priority: f64,
}

/// Marks the jobs tested in this run: every testable exact or swept job and, of the optional ones,
/// all of them (`fit` is `None`) or `fit = Some((count, per_bucket))` of them: a quarter of
/// `count` to the pairs that waited longest for a test (ties in job order), the rest from
/// the highest priority down (within the last bucket taken, in job order). The quarter for
/// the longest waiting is what keeps a pair of low priority from starving when pairs of high
/// priority fill every run: with `k` tests per run among `n` pairs, none waits much more than
/// `4n/k` runs. `oldest` is scratch.
pub(crate) fn choose_tests(
    jobs: &mut [Job],
    fit: Option<(usize, [u32; BUCKETS])>,
    oldest: &mut Vec<(u32, u32)>,
) -> Chosen {
    let mut chosen = Chosen::default();
    for j in jobs.iter_mut() {
        j.chosen = j.testable() && (j.mandatory() || fit.is_none());
    }
    if let Some((count, mut per_bucket)) = fit {
        // The longest waiting first.
        oldest.clear();
        oldest.extend(
            (0..jobs.len() as u32)
                .filter(|&i| jobs[i as usize].optional() && jobs[i as usize].stale > 0)
                .map(|i| (jobs[i as usize].stale, i)),
        );
        let quarter = (count / 4).min(oldest.len());
        let longest = |x: &(u32, u32), y: &(u32, u32)| y.0.cmp(&x.0).then(x.1.cmp(&y.1));
        if quarter < oldest.len() && quarter > 0 {
            oldest.select_nth_unstable_by(quarter - 1, longest);
        }
        for &(_, i) in &oldest[..quarter] {
            let j = &mut jobs[i as usize];
            j.chosen = true;
            per_bucket[usize::from(j.bucket)] -= 1;
        }
        // Then by priority.
        let (bucket, room) = priority_cut(&per_bucket, count - quarter);
        let mut taken_at_cut = 0;
        for j in jobs.iter_mut().filter(|j| j.optional() && !j.chosen) {
            j.chosen = j.bucket < bucket || (j.bucket == bucket && taken_at_cut < room);
            taken_at_cut += usize::from(j.chosen && j.bucket == bucket);
        }
    }
    for j in jobs.iter().filter(|j| j.chosen) {
        chosen.count += 1;
        if j.method == Method::Adb {
            chosen.adb += 1;
            chosen.adb_priority += f64::from(j.priority);
        }
    }
    chosen
}

/// The priority bucket at which `count` of the jobs counted `per_bucket` are reached (from
/// the most urgent), and how many of that bucket fit.
pub(crate) fn priority_cut(per_bucket: &[u32; BUCKETS], count: usize) -> (u8, usize) {
    let mut before = 0;
    for (b, &n) in per_bucket.iter().enumerate() {
        let n = n as usize;
        if before + n >= count {
            return (b as u8, count - before);
        }
        before += n;
    }
    (BUCKETS as u8, 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn job(method: Method, priority: f32, cached: bool) -> Job {
        Job {
            method,
            bucket: priority_bucket(priority),
            cached,
            priority,
            ..Job::new(0, 0, 1)
        }
    }

    fn chosen(jobs: &[Job]) -> Vec<usize> {
        (0..jobs.len()).filter(|&i| jobs[i].chosen).collect()
    }

    #[test]
    fn buckets_follow_the_priority_in_quarter_octaves() {
        let b = |p: f32| priority_bucket(p);
        assert_eq!(b(16.0), 0);
        assert_eq!(b(1000.0), 0);
        assert_eq!(b(1.0), 15);
        assert_eq!(b(0.0625), 31);
        assert_eq!(b(0.0), 31);
        assert_eq!(b(1.0) - b(2.0), 4);
        let mut last = 0;
        for k in 0..400 {
            let bucket = b(20.0 * 0.98f32.powi(k));
            assert!(bucket >= last, "monotone");
            last = bucket;
        }
    }

    #[test]
    fn exact_jobs_are_always_chosen_then_the_most_urgent_that_fit() {
        let mut jobs = [
            job(Method::Adb, 0.5, false),
            job(Method::Exact, 0.1, false),
            job(Method::Adb, 8.0, false),
            job(Method::Adb, 9.0, true),
            job(Method::Bounds, 9.0, false),
            job(Method::Adb, 2.0, false),
            job(Method::Exact, 0.1, true),
            job(Method::Adb, 2.0, false),
        ];
        let plan = PlanCounts::count(&jobs);
        assert_eq!(plan.testable, 5);
        assert_eq!(plan.optional.iter().sum::<u32>(), 4);
        assert_eq!(plan.adb, 4, "ADB jobs that need a test");
        // Two optional tests fit, none waited: the 8.0 job and the first 2.0 job (job order
        // in a bucket).
        let scratch = &mut Vec::new();
        let c = choose_tests(&mut jobs, Some((2, plan.optional)), scratch);
        assert_eq!(chosen(&jobs), vec![1, 2, 5]);
        assert_eq!((c.count, c.adb, c.adb_priority), (3, 2, 10.0));
        // No cut (work budgets): every testable job.
        assert_eq!(choose_tests(&mut jobs, None, scratch).count, 5);
        assert_eq!(chosen(&jobs), vec![0, 1, 2, 5, 7]);
        // Nothing fits: the exact job still.
        choose_tests(&mut jobs, Some((0, plan.optional)), scratch);
        assert_eq!(chosen(&jobs), vec![1]);
        // A swept ADB job is not optional: chosen too.
        jobs[0].swept = true;
        let plan = PlanCounts::count(&jobs);
        assert_eq!(plan.optional.iter().sum::<u32>(), 3);
        choose_tests(&mut jobs, Some((0, plan.optional)), scratch);
        assert_eq!(chosen(&jobs), vec![0, 1]);
        jobs[0].swept = false;
        // More than there are: all of them.
        choose_tests(&mut jobs, Some((100, plan.optional)), scratch);
        assert_eq!(chosen(&jobs), vec![0, 1, 2, 5, 7]);
    }

    #[test]
    fn a_quarter_of_the_tests_go_to_the_longest_waiting() {
        // Eight urgent pairs, tested every run, and one of low priority that waited long.
        let mut jobs: Vec<Job> = (0..8).map(|_| job(Method::Adb, 8.0, false)).collect();
        jobs.push(Job {
            stale: 30,
            ..job(Method::Adb, 0.1, false)
        });
        jobs.push(Job {
            stale: 3,
            ..job(Method::Adb, 0.1, false)
        });
        let plan = PlanCounts::count(&jobs);
        let scratch = &mut Vec::new();
        // Four tests: one for the longest waiting, three by priority.
        choose_tests(&mut jobs, Some((4, plan.optional)), scratch);
        assert_eq!(chosen(&jobs), vec![0, 1, 2, 8]);
        // Eight tests: two for the longest waiting, six by priority.
        choose_tests(&mut jobs, Some((8, plan.optional)), scratch);
        assert_eq!(chosen(&jobs), vec![0, 1, 2, 3, 4, 5, 8, 9]);
        // Fewer than four: by priority only.
        choose_tests(&mut jobs, Some((3, plan.optional)), scratch);
        assert_eq!(chosen(&jobs), vec![0, 1, 2]);
    }

    #[test]
    fn an_answer_found_before_a_change_of_configuration_is_not_reused() {
        use super::super::super::pairs::Record;
        use super::super::super::prepare::ColliderEntry;
        use super::super::{PairMemory, PairOutcome};
        let mut colliders = ColliderTable::default();
        let (ea, eb) = (
            ColliderEntry::sphere_for_tests(1, 0, 0.0, 1),
            ColliderEntry::sphere_for_tests(2, 0, 1.5, 1),
        );
        let ends = ((ea.entity, 0), (eb.entity, 1));
        assert_eq!((colliders.insert(ea), colliders.insert(eb)), (0, 1));
        let mut pairs = PairTable::default();
        let p = pairs.create(ends.0, ends.1, 1);
        // Tested and settled in run 3; both at rest since run 1.
        let memory = PairMemory::exact_for_tests(true, 3);
        let o = PairOutcome::untested((ends.0.0, ends.1.0), 3);
        let record = Record {
            memory,
            contact: None,
            offset: glam::Vec3::ZERO,
        };
        pairs.answer(p, o, Some(record), 3);
        let cached = |config_run: u64| {
            let mut jobs = [Job::new(p, 0, 1)];
            plan_jobs(&mut jobs, &colliders, &pairs, 9, config_run);
            jobs[0].cached
        };
        assert!(cached(1), "configuration unchanged since before the test");
        assert!(cached(3), "changed in the test's run (before it)");
        // Changed in run 4: in every run after it too, the answer is not reused as it is.
        assert!(!cached(4));
    }
}
