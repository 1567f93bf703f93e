//! The tracker: persistent feature pairs, updated every frame.

use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};
use std::time::{Duration, Instant};

use glam::DVec3;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use smallvec::SmallVec;

use super::coarse::{CoarseCounts, CoarseSearch, CoarseStart};
use super::config::TrackerConfig;
use super::contact::Contact;
use super::feature::Feature;
use super::local_search::{Located, SearchCounters, Searcher};
use super::pruning::{PruneCounts, PruneScratch, PruneSettings, prune};
use super::sampling::{DrawRequest, SamplerScratch, draw};
use super::surface::{Placed, TrackedSurface};
use super::sweep::{Sweep, SweepScratch, SweptSide};
use super::timing::{Lap, StepTimes};
use crate::ccd::RigidMotion;
use crate::geometry::{ClosestPoints, Pose, PoseF64};

/// Sliding self pairs within this many mean edge lengths keep descending and are kept (see
/// `Searcher::slide_limit`).
const SLIDE_LIMIT_EDGES: f64 = 1.0;

/// Past a step's deadline, one in this many of its searches still runs (see
/// [`Tracker::step_self_until`]).
const LATE_SHARE: usize = 8;

/// Under a time budget: the share of the budget a step aims at (the rest absorbs the
/// variation from frame to frame), the largest change of the pairs per frame after one step
/// (a step that hits its deadline halves them), and the fewest pairs per frame. Controller
/// settings, not fitted to any mesh.
const ADAPT_TARGET: f64 = 0.8;
const ADAPT_MIN_FACTOR: f64 = 0.5;
const ADAPT_MAX_FACTOR: f64 = 1.5;
const MIN_ADAPTIVE_PAIRS: usize = 8;

/// Under a time budget, the pair work (sampling, searching, pruning, propagation) always gets
/// at least this share of the budget after the candidates are found, even when finding them
/// took the whole budget: a budget smaller than a mesh's fixed cost is overrun, not turned
/// into a tracker that searches nothing. A controller setting, not fitted to any mesh.
const PAIR_FLOOR: f64 = 0.25;

/// Under a time budget, in self-collision: the share of the budget after which the step stops
/// bringing its kept candidates up to date (see [`DrawRequest::candidate_allowance`]). A
/// controller setting, not fitted to any mesh.
const CANDIDATE_SHARE: f64 = 0.2;

/// A tracked pair of locally closest features, persistent across frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackedPair {
    /// Triangle of the first mesh whose feature is closest.
    pub triangle_a: u32,
    /// Triangle of the second mesh (same mesh in self-collision).
    pub triangle_b: u32,
    /// Closest feature on the first mesh.
    pub feature_a: Feature,
    /// Closest feature on the second mesh.
    pub feature_b: Feature,
    /// Their distance at the last step.
    pub distance: f64,
    /// Closest point on the first mesh (first mesh's frame for a pair of meshes).
    pub point_a: DVec3,
    /// Closest point on the second mesh (same frame).
    pub point_b: DVec3,
    /// A vertex of `feature_a` (for ring distances).
    pub vertex_a: u32,
    /// A vertex of `feature_b`.
    pub vertex_b: u32,
    /// Frames this pair has survived.
    pub age: u32,
    /// Its last local search settled (in contact, or no neighbour pair closer), rather than
    /// running out of steps or time: in self-collision, while no vertex around its two
    /// triangles moves, the next step keeps it as it is without searching
    /// ([`StepStats::still`]).
    pub settled: bool,
}

/// The active pairs of one tracker: inline storage for the common case of a few dozen.
pub type PairList = SmallVec<[TrackedPair; 16]>;

/// What the last [`Tracker`] step did.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct StepStats {
    /// New random pairs the step was to draw (see [`Tracker::pairs_per_frame_now`] and
    /// [`TrackerConfig::overlaps_per_pair`]).
    pub pairs_per_frame: usize,
    /// New random pairs drawn.
    pub sampled: usize,
    /// Overlapping patch pairs of the incomplete hierarchy (hierarchy sampling).
    pub patch_overlaps: usize,
    /// Of them, those where the surfaces moved since the last step: in self-collision those in
    /// the kept lists made again (all on the first step, none on a surface at rest); between two
    /// meshes all of them. [`TrackerConfig::overlaps_per_pair`] counts these.
    pub moved_patch_overlaps: usize,
    /// Local-search steps over all pairs.
    pub iterations: u64,
    /// Feature-pair distance evaluations.
    pub evaluations: u64,
    /// Pairs dropped, by reason.
    pub pruned: PruneCounts,
    /// Active pairs after pruning.
    pub active: usize,
    /// Contacts reported (including propagated ones).
    pub contacts: usize,
    /// Of which found by propagation.
    pub propagated: usize,
    /// Whether the step's deadline passed (see [`Tracker::step_self_until`]): from then on an
    /// eighth of the searches and of the propagation ran, the other pairs were only
    /// re-measured.
    pub cut: bool,
    /// Kept pairs re-measured without a local search because the deadline had passed.
    pub remeasured: usize,
    /// Self-collision: kept pairs taken as they were, without a search, because their search
    /// had settled and no vertex of a triangle around their two triangles moved since the
    /// last step (what the search would find again).
    pub still: usize,
    /// Continuous tracking ([`TrackerConfig::continuous`]): pairs whose neighbourhoods were
    /// checked over the step.
    pub swept: usize,
    /// Continuous tracking: pairs not checked over the step because the deadline had passed
    /// (past it, one in eight still is).
    pub sweep_skipped: usize,
    /// Continuous tracking: triangle pairs decided by the continuous primitives.
    pub sweep_triangle_pairs: usize,
    /// Continuous tracking: contacts added because their triangles touched during the step
    /// (not among the contacts at its end; they carry a
    /// [`Contact::time_of_impact`]).
    pub crossings: usize,
    /// In self-collision with hierarchy sampling: the kept candidate lists (pairs of blocks of
    /// the patch tree, see [`TrackerConfig::time_budget`]) brought up to date in this step:
    /// none on a surface at rest, those of the blocks a motion reached (under a time budget,
    /// the most out of date of them that its share allowed). 0 between two meshes (their
    /// candidates are found anew) or when none were drawn.
    pub candidate_lists_refreshed: usize,
    /// The kept candidate lists there are (0 between two meshes).
    pub candidate_lists: usize,
    /// What the coarse level did with the new pairs
    /// ([`TrackerConfig::multiresolution`]; all zero without it).
    pub coarse: CoarseCounts,
    /// Where the step's time went.
    pub times: StepTimes,
}

/// Stochastic closest-feature tracking (Raghupathi et al., Guy and Debunne, Kimmerle et al.)
/// between two meshes or of one mesh against itself.
///
/// Each [`Tracker::step_self`] / [`Tracker::step_pair`] on the current vertex positions:
/// draws [`TrackerConfig::pairs_per_frame`] new random pairs, moves every pair (new and kept)
/// to locally closest features, prunes far, duplicate and redundant pairs, and reports the
/// pairs closer than the thickness as [`Contact`]s, extended by collision propagation. Pairs
/// persist to the next step (temporal coherence). Randomness comes from the configured seed
/// and the frame number only, so a run is reproducible whatever thread runs it.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::tracking::{TrackedSurface, Tracker, TrackerConfig};
///
/// // A cloth folded over itself: the half beyond x = 0 is turned over and pushed through.
/// let flat = generate::cloth_grid(1.0, 1.0, 20, 20);
/// let mut cloth = TrackedSurface::new(flat.clone());
/// let folded: Vec<Vec3> = flat
///     .positions()
///     .iter()
///     .map(|p| if p.x > 0.1 { Vec3::new(0.2 - p.x, 0.05 - 0.2 * (p.x - 0.1), p.z) } else { *p })
///     .collect();
/// cloth.set_positions(&folded).unwrap();
/// let mut tracker = Tracker::new(TrackerConfig::for_surface(&cloth));
/// for _ in 0..5 {
///     tracker.step_self(&cloth);
/// }
/// assert!(!tracker.contacts().is_empty());
/// ```
#[derive(Debug, Clone)]
pub struct Tracker {
    config: TrackerConfig,
    /// New pairs per frame under a time budget (adapted after every step).
    adaptive_pairs: usize,
    pairs: PairList,
    contacts: Vec<Contact>,
    frame: u64,
    stats: StepStats,
    scratch: Scratch,
    /// Two meshes: the second's pose in the first's frame at the last step (velocity sampling
    /// weighs the relative motion since then).
    last_relative_pose: Option<PoseF64>,
    /// The surfaces' [`TrackedSurface::generation`] at the last step (whether they deformed
    /// since).
    last_generations: Option<[u64; 2]>,
    /// Under a time budget: what the work after the local search (pruning, propagation, the
    /// continuous check) took at the last step; the search stops that much before the
    /// deadline, so that the step ends by it.
    tail: std::time::Duration,
    /// Self-collision: the surface of the last step ([`TrackedSurface::topology_id`]), with
    /// the configuration its pairs were searched under unchanged since.
    last_self_surface: Option<u64>,
}

/// Where the surfaces were at the start of a step (for the continuous check).
#[derive(Clone, Copy)]
struct StepStart {
    /// Whether each surface deformed since the last step (its vertices start at its previous
    /// positions).
    deformed: [bool; 2],
    /// Two meshes: the second's pose in the first's frame at the start, if known.
    pose_b: Option<PoseF64>,
    /// Self-collision: what moved since the last step is known ([`Stillness`]).
    still: Stillness,
}

/// What a self-collision step knows about the motion since the last step.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Stillness {
    /// Nothing (two meshes, a first step, another surface, a skipped update, a new
    /// configuration): every kept pair is searched.
    Unknown,
    /// The surface was not updated since: nothing moved.
    Nothing,
    /// One update since: the surface's moved vertices say where.
    LastUpdate,
}

#[derive(Debug, Default, Clone)]
struct Scratch {
    starts: Vec<(u32, u32)>,
    /// The vertex pairs of kept pairs and of this step's refined coarse starts.
    coarse_seen: HashSet<(u32, u32)>,
    pairs: Vec<TrackedPair>,
    sampler: SamplerScratch,
    prune: PruneScratch,
    visited: HashSet<(u32, u32)>,
    queue: Vec<(u32, u32)>,
    sweep: SweepScratch,
    contact_keys: HashMap<(u32, u32), usize>,
}

impl Tracker {
    /// A tracker with no pairs yet.
    pub fn new(config: TrackerConfig) -> Self {
        Tracker {
            adaptive_pairs: config.pairs_per_frame.max(1),
            config,
            pairs: PairList::new(),
            contacts: Vec::new(),
            frame: 0,
            stats: StepStats::default(),
            scratch: Scratch::default(),
            last_relative_pose: None,
            last_generations: None,
            tail: std::time::Duration::ZERO,
            last_self_surface: None,
        }
    }

    /// The configuration.
    pub fn config(&self) -> &TrackerConfig {
        &self.config
    }

    /// Changes the configuration; kept pairs stay (and, under a time budget, the pairs per
    /// frame learnt so far).
    pub fn set_config(&mut self, config: TrackerConfig) {
        if config.time_budget.is_none() || self.config.time_budget.is_none() {
            self.adaptive_pairs = config.pairs_per_frame.max(1);
        }
        if config != self.config {
            self.last_self_surface = None;
        }
        self.config = config;
    }

    /// New random pairs the next step draws: [`TrackerConfig::pairs_per_frame`] (at least:
    /// with [`TrackerConfig::overlaps_per_pair`] a step draws more where the candidates are
    /// many, [`StepStats::pairs_per_frame`]), or under [`TrackerConfig::time_budget`] what
    /// the budget was found to allow.
    pub fn pairs_per_frame_now(&self) -> usize {
        if self.config.time_budget.is_some() {
            self.adaptive_pairs
        } else {
            self.config.pairs_per_frame
        }
    }

    /// The active pairs after the last step, closest first.
    pub fn pairs(&self) -> &[TrackedPair] {
        &self.pairs
    }

    /// The contacts of the last step: tracked pairs closer than the thickness first (closest
    /// first), then propagated ones, then (with [`TrackerConfig::continuous`]) the triangle
    /// pairs that touched during the step, earliest first.
    pub fn contacts(&self) -> &[Contact] {
        &self.contacts
    }

    /// What the last step did.
    pub fn stats(&self) -> &StepStats {
        &self.stats
    }

    /// Steps taken so far.
    pub fn frame(&self) -> u64 {
        self.frame
    }

    /// Forgets every pair (for example after the mesh was replaced).
    pub fn clear(&mut self) {
        self.pairs.clear();
        self.contacts.clear();
        self.last_relative_pose = None;
        self.last_generations = None;
        self.last_self_surface = None;
        self.scratch.sampler.kept = Default::default();
    }

    /// Whether each surface deformed since the last step.
    fn deformed(&self, a: &TrackedSurface, b: &TrackedSurface) -> [bool; 2] {
        let now = [a.generation(), b.generation()];
        match self.last_generations {
            Some(last) => [now[0] != last[0], now[1] != last[1]],
            // First step: the last deformation is the best guess of the motion.
            None => now.map(|g| g > 0),
        }
    }

    /// One frame of self-collision tracking of `surface` at its current positions. Contacts
    /// are in the mesh's own frame; triangles sharing a vertex are never paired.
    pub fn step_self(&mut self, surface: &TrackedSurface) -> &[Contact] {
        self.step_self_until(surface, None)
    }

    /// [`step_self`](Self::step_self) inside a time budget: once `deadline` has passed, the
    /// step does an eighth of its work: new random pairs drawn only every eighth step and an
    /// eighth of them searched, each kept pair searched every eighth step and otherwise only
    /// re-measured on its current features (one evaluation), an eighth of the collision
    /// propagation ([`StepStats::cut`], [`StepStats::remeasured`]). Accuracy degrades (pairs
    /// converge more slowly, new contacts are found later), frame time less; a tracker
    /// that is always late still finds and follows its contacts. With a deadline the result
    /// depends on timing; `None` (no deadline) is [`step_self`](Self::step_self), reproducible.
    pub fn step_self_until(
        &mut self,
        surface: &TrackedSurface,
        deadline: Option<Instant>,
    ) -> &[Contact] {
        let placed = Placed {
            surface,
            pose: None,
        };
        let still = match (self.last_self_surface, self.last_generations) {
            (Some(id), Some([g, _])) if id == surface.topology_id() => {
                if g == surface.generation() {
                    Stillness::Nothing
                } else if g + 1 == surface.generation() {
                    Stillness::LastUpdate
                } else {
                    Stillness::Unknown
                }
            }
            _ => Stillness::Unknown,
        };
        let start = StepStart {
            deformed: self.deformed(surface, surface),
            pose_b: None,
            still,
        };
        self.step(placed, placed, true, surface.size(), deadline, start);
        self.last_relative_pose = None;
        self.last_generations = Some([surface.generation(); 2]);
        self.last_self_surface = Some(surface.topology_id());
        &self.contacts
    }

    /// One frame of tracking between `a` at `pose_a` and `b` at `pose_b`. Contacts are in the
    /// world frame; the normal points from `a` towards `b`.
    pub fn step_pair(
        &mut self,
        a: &TrackedSurface,
        pose_a: &Pose,
        b: &TrackedSurface,
        pose_b: &Pose,
    ) -> &[Contact] {
        self.step_pair_until(a, pose_a, b, pose_b, None)
    }

    /// [`step_pair`](Self::step_pair) inside a time budget (see
    /// [`step_self_until`](Self::step_self_until)). With
    /// [`TrackerConfig::continuous`], the step's motion is from the poses of the last step
    /// (none on the first: only deformation is swept then).
    pub fn step_pair_until(
        &mut self,
        a: &TrackedSurface,
        pose_a: &Pose,
        b: &TrackedSurface,
        pose_b: &Pose,
        deadline: Option<Instant>,
    ) -> &[Contact] {
        let start = self.last_relative_pose;
        self.pair_step(a, pose_a, b, pose_b, start, deadline)
    }

    /// [`step_pair_until`](Self::step_pair_until) for meshes that moved over the step as
    /// `motion_a` and `motion_b` say (from their poses at the start of the step to those at
    /// its end): with [`TrackerConfig::continuous`] that motion is swept (each vertex on a
    /// straight line in `a`'s frame), whatever the poses at the last step were; the
    /// contacts are at the end poses. Use it when the tracker did not see the start poses
    /// (a new pair, a skipped step).
    ///
    /// # Example
    /// ```
    /// use stochastic_collision::ccd::RigidMotion;
    /// use stochastic_collision::prelude::*;
    /// use stochastic_collision::tracking::{TrackedSurface, Tracker, TrackerConfig};
    ///
    /// // A sheet that passes through another in one step: at the step's end they are apart.
    /// let sheet = TrackedSurface::new(generate::cloth_grid(1.0, 1.0, 10, 10));
    /// let config = TrackerConfig { continuous: true, ..TrackerConfig::for_surface(&sheet) };
    /// let mut tracker = Tracker::new(config);
    /// let still = RigidMotion::still(Pose::IDENTITY);
    /// let through = RigidMotion::new(
    ///     Pose::from_translation(Vec3::new(0.05, 0.2, 0.03)),
    ///     Pose::from_translation(Vec3::new(0.05, -0.2, 0.03)),
    /// );
    /// let contacts = tracker.step_pair_moving_until(&sheet, &still, &sheet, &through, None);
    /// let hit = contacts.iter().find_map(|c| c.time_of_impact).expect("caught");
    /// assert!((hit - 0.5).abs() < 1e-3);
    /// ```
    pub fn step_pair_moving_until(
        &mut self,
        a: &TrackedSurface,
        motion_a: &RigidMotion,
        b: &TrackedSurface,
        motion_b: &RigidMotion,
        deadline: Option<Instant>,
    ) -> &[Contact] {
        let start = motion_a.start.inverse_mul(&motion_b.start).to_f64();
        self.pair_step(a, &motion_a.end, b, &motion_b.end, Some(start), deadline)
    }

    fn pair_step(
        &mut self,
        a: &TrackedSurface,
        pose_a: &Pose,
        b: &TrackedSurface,
        pose_b: &Pose,
        start_pose: Option<PoseF64>,
        deadline: Option<Instant>,
    ) -> &[Contact] {
        let rel = pose_a.inverse_mul(pose_b).to_f64();
        let pa = Placed {
            surface: a,
            pose: None,
        };
        let pb = Placed {
            surface: b,
            pose: Some(rel),
        };
        let start = StepStart {
            deformed: self.deformed(a, b),
            pose_b: start_pose,
            still: Stillness::Unknown,
        };
        self.last_self_surface = None;
        self.step(pa, pb, false, a.size().max(b.size()), deadline, start);
        self.last_relative_pose = Some(rel);
        self.last_generations = Some([a.generation(), b.generation()]);
        if *pose_a != Pose::IDENTITY {
            for c in &mut self.contacts {
                c.point_a = pose_a.transform_point(c.point_a);
                c.point_b = pose_a.transform_point(c.point_b);
                c.normal = pose_a.transform_vector(c.normal);
            }
        }
        &self.contacts
    }

    /// One step; under a time budget, within it (its end is a deadline too) and followed by
    /// the adaptation of the pairs per frame to what the step took.
    fn step(
        &mut self,
        a: Placed,
        b: Placed,
        self_mode: bool,
        size: f32,
        deadline: Option<Instant>,
        begin: StepStart,
    ) {
        let Some(budget) = self.config.time_budget else {
            let n = self.config.pairs_per_frame;
            self.step_with(a, b, self_mode, size, deadline, n, begin);
            return;
        };
        let start = Instant::now();
        let own = start + budget;
        let deadline = Some(deadline.map_or(own, |d| d.min(own)));
        self.step_with(a, b, self_mode, size, deadline, self.adaptive_pairs, begin);
        // The candidates cost what the mesh and its folds cost, whatever the pairs: the pairs
        // per frame are scaled towards what fills the rest of the target (at least the floor).
        let took = start.elapsed().as_secs_f64();
        let fixed = self.stats.times.candidates.as_secs_f64();
        let budget_s = budget.as_secs_f64();
        let target = (ADAPT_TARGET * budget_s - fixed).max(PAIR_FLOOR * budget_s);
        let factor = if self.stats.cut {
            ADAPT_MIN_FACTOR
        } else {
            (target / (took - fixed).max(1e-9)).clamp(ADAPT_MIN_FACTOR, ADAPT_MAX_FACTOR)
        };
        let next = (self.adaptive_pairs as f64 * factor).round() as usize;
        self.adaptive_pairs = next.clamp(
            MIN_ADAPTIVE_PAIRS,
            self.config.max_active_pairs.max(MIN_ADAPTIVE_PAIRS),
        );
    }

    #[allow(clippy::too_many_arguments)]
    fn step_with(
        &mut self,
        a: Placed,
        b: Placed,
        self_mode: bool,
        size: f32,
        deadline: Option<Instant>,
        pairs_per_frame: usize,
        begin: StepStart,
    ) {
        let deadline = std::cell::Cell::new(deadline);
        let passed = || deadline.get().is_some_and(|d| Instant::now() >= d);
        // Under a time budget the search leaves time for what follows it (see `Tracker::tail`).
        let reserve = if self.config.time_budget.is_some() {
            self.tail
        } else {
            std::time::Duration::ZERO
        };
        let search_passed = || {
            deadline
                .get()
                .is_some_and(|d| Instant::now() + reserve >= d)
        };
        let mut lap = Lap::start();
        let cfg = &self.config;
        let mean_edge = a
            .surface
            .mean_edge_length()
            .max(b.surface.mean_edge_length()) as f64;
        let mut stats = StepStats::default();
        let searcher = Searcher {
            a,
            b,
            self_mode,
            excluded_pairs: self_mode.then(|| a.surface.excluded_pairs(cfg.exclusion_rings)),
            mode: cfg.search,
            max_iterations: cfg.max_iterations,
            epsilon: 1e-9 * size as f64,
            thickness: cfg.thickness.max(0.0) as f64,
            slide_limit: SLIDE_LIMIT_EDGES * mean_edge,
        };
        let s = &mut self.scratch;
        let frame = self.frame;
        self.frame += 1;

        // 1. New random pairs (seeded by the configuration and the frame only).
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(mix(cfg.seed, frame));
        s.starts.clear();
        let far_eps = cfg.far_epsilon.max(0.0) * size;
        // Continuous: patches that come within the step's motion of each other may have met.
        let reach = if cfg.continuous {
            motion_bound(&a, &b, self_mode, &begin)
        } else {
            0.0
        };
        let margin = cfg.thickness.max(0.0) + far_eps + reach;
        // Past the deadline an eighth of the work still gets done (new pairs every eighth step
        // and an eighth of them searched, each kept pair searched every eighth step): a
        // tracker that starts late, or stays over its budget, still finds and follows its
        // contacts, only more slowly.
        stats.cut = passed();
        // Drawing has a cost of its own (hierarchy sampling looks for the overlapping patches
        // of the whole surface): late, it draws every eighth step only.
        let draw_now = !stats.cut || frame.is_multiple_of(LATE_SHARE as u64);
        let request = DrawRequest {
            sampling: cfg.sampling,
            count: if draw_now { pairs_per_frame } else { 0 },
            // Without a time budget the pairs per frame grow with the candidates.
            overlaps_per_pair: cfg.overlaps_per_pair.filter(|_| cfg.time_budget.is_none()),
            count_cap: cfg.max_active_pairs,
            self_mode,
            excluded_pairs: searcher.excluded_pairs,
            thickness: cfg.thickness,
            margin,
            previous_pose: self.last_relative_pose,
            // In self-collision the candidates are kept between steps: every list whose
            // blocks moved is made again (exact, reproducible), or under a time budget the
            // most out of date ones within a share of it.
            candidate_allowance: cfg
                .time_budget
                .map_or(Duration::MAX, |b| b.mul_f64(CANDIDATE_SHARE)),
        };
        draw(
            &request,
            &a,
            &b,
            self.contacts.iter().map(|c| (c.triangle_a, c.triangle_b)),
            &mut rng,
            &mut s.sampler,
            &mut s.starts,
        );
        stats.sampled = s.starts.len();
        let pairs_per_frame = if draw_now {
            s.sampler.count
        } else {
            pairs_per_frame
        };
        stats.pairs_per_frame = pairs_per_frame;
        let late_fresh = pairs_per_frame.div_ceil(LATE_SHARE);
        stats.patch_overlaps = s.sampler.overlap_count;
        stats.moved_patch_overlaps = s.sampler.moved_overlap_count;
        if self_mode {
            stats.candidate_lists_refreshed = s.sampler.kept.refreshed;
            stats.candidate_lists = s.sampler.kept.pair_count();
        }
        let drawing = lap.lap();
        stats.times.candidates = s.sampler.candidates_time.min(drawing);
        stats.times.sampling = drawing - stats.times.candidates;
        // Under the tracker's own budget, the pair work keeps its floor (see `PAIR_FLOOR`).
        if let (Some(budget), Some(d)) = (cfg.time_budget, deadline.get()) {
            deadline.set(Some(d.max(Instant::now() + budget.mul_f64(PAIR_FLOOR))));
        }

        // 2. Local search from every kept and new pair.
        let mut counters = SearchCounters::default();
        s.pairs.clear();
        let kept = self
            .pairs
            .iter()
            .map(|p| (p.triangle_a, p.triangle_b, p.age + 1, Some(p)));
        let fresh = s.starts.iter().map(|&(x, y)| (x, y, 0, None));
        let mut fresh_late = 0;
        let still = |t: u32| match begin.still {
            Stillness::Unknown => false,
            Stillness::Nothing => true,
            Stillness::LastUpdate => a.surface.still_around(t),
        };
        // Multiresolution: new pairs (not the crease probes) start at the vertex level.
        let kept_count = self.pairs.len();
        let crease = s.sampler.crease_starts.clone();
        let mut coarse = cfg.multiresolution.then(|| CoarseSearch {
            a,
            b,
            excluded_pairs: searcher.excluded_pairs,
            far_factor: cfg.far_factor as f64,
            far_epsilon: far_eps as f64,
            thickness: searcher.thickness,
            closest: self
                .pairs
                .iter()
                .map(|p| p.distance.max(0.0))
                .fold(f64::INFINITY, f64::min),
            slide_limit: searcher.slide_limit,
        });
        s.coarse_seen.clear();
        let mut seen_filled = false;
        for (k, (mut ta, mut tb, age, before)) in kept.chain(fresh).enumerate() {
            // A settled pair nothing moved around finds itself again: kept as it is.
            if let Some(p) = before.filter(|p| p.settled && still(ta) && still(tb)) {
                stats.still += 1;
                s.pairs.push(TrackedPair { age, ..*p });
                continue;
            }
            if searcher.excluded(ta, tb) {
                continue;
            }
            stats.cut = stats.cut || search_passed();
            let search = !stats.cut
                || if age == 0 {
                    fresh_late += 1;
                    fresh_late <= late_fresh
                } else {
                    (k as u64 + frame).is_multiple_of(LATE_SHARE as u64)
                };
            if !search && age == 0 {
                continue;
            }
            if let Some(coarse) = coarse.as_mut().filter(|_| age == 0) {
                let drawn = k - kept_count;
                if !crease.contains(&drawn) {
                    if !seen_filled {
                        // The kept pairs' vertex pairs: a start coming to rest on one of
                        // them would find that pair again.
                        seen_filled = true;
                        for p in s.pairs.iter() {
                            for v in a.corners(p.triangle_a) {
                                for w in b.corners(p.triangle_b) {
                                    s.coarse_seen.insert(key(self_mode, v, w));
                                }
                            }
                        }
                    }
                    match coarse.start(ta, tb, &mut stats.coarse) {
                        (CoarseStart::Refine(x, y), (v, w)) => {
                            if !s.coarse_seen.insert(key(self_mode, v, w)) {
                                stats.coarse.duplicate += 1;
                                continue;
                            }
                            stats.coarse.refined += 1;
                            (ta, tb) = (x, y);
                        }
                        _ => continue,
                    }
                }
            }
            let start = searcher.locate(ta, tb, &mut counters);
            let (l, sliding, settled) = if search {
                searcher.descend(start, &mut counters)
            } else {
                // Out of time: re-measured where it is (one evaluation), searched later.
                stats.remeasured += 1;
                (start, false, false)
            };
            if sliding || searcher.sliding(&l) {
                stats.pruned.sliding += 1;
                continue;
            }
            s.pairs.push(TrackedPair {
                settled,
                ..tracked(&a, &b, &l, age, self_mode)
            });
        }
        stats.iterations = counters.iterations;
        stats.evaluations = counters.evaluations;
        stats.times.local_search = lap.lap();

        // 3. Prune.
        let settings = PruneSettings {
            self_mode,
            far_factor: cfg.far_factor,
            far_epsilon: far_eps as f64,
            thickness: cfg.thickness,
            redundancy_rings: cfg.redundancy_rings,
            max_pairs: cfg.max_active_pairs,
        };
        prune(
            &mut s.pairs,
            a.topology(),
            b.topology(),
            &settings,
            &mut s.prune,
            &mut stats.pruned,
        );
        self.pairs.clear();
        self.pairs.extend(s.pairs.iter().copied());
        stats.active = self.pairs.len();
        stats.times.pruning = lap.lap();

        // 4. Contacts, then collision propagation around them.
        self.contacts.clear();
        s.visited.clear();
        s.queue.clear();
        let thickness = cfg.thickness.max(0.0) as f64;
        for p in &self.pairs {
            if p.distance <= thickness {
                let l = Located {
                    ta: p.triangle_a,
                    tb: p.triangle_b,
                    cp: ClosestPoints {
                        distance: p.distance,
                        point_a: p.point_a,
                        point_b: p.point_b,
                    },
                    fa: p.feature_a,
                    fb: p.feature_b,
                };
                self.contacts
                    .push(Contact::new(&a, &b, &l, cfg.thickness, false));
                let key = key(self_mode, p.triangle_a, p.triangle_b);
                if s.visited.insert(key) {
                    s.queue.push((p.triangle_a, p.triangle_b));
                }
            }
        }
        let mut added = 0;
        while let Some((ta, tb)) = s.queue.pop() {
            // Late, an eighth of the propagation (each step of it is one evaluation): past the
            // deadline itself, not the search's earlier stop (see `Tracker::tail`).
            let late = passed();
            stats.cut = stats.cut || late;
            let limit = if late {
                cfg.propagation_limit.div_ceil(LATE_SHARE)
            } else {
                cfg.propagation_limit
            };
            if added >= limit {
                break;
            }
            let na = a
                .topology()
                .triangle_neighbours(ta)
                .iter()
                .map(|&x| (x, tb));
            let nb = b
                .topology()
                .triangle_neighbours(tb)
                .iter()
                .map(|&y| (ta, y));
            for (x, y) in na.chain(nb) {
                if added >= limit {
                    break;
                }
                if searcher.excluded(x, y) || !s.visited.insert(key(self_mode, x, y)) {
                    continue;
                }
                let l = searcher.locate(x, y, &mut counters);
                if l.cp.distance <= thickness && !searcher.sliding(&l) {
                    self.contacts
                        .push(Contact::new(&a, &b, &l, cfg.thickness, true));
                    s.queue.push((x, y));
                    added += 1;
                }
            }
        }
        stats.evaluations = counters.evaluations;
        stats.contacts = self.contacts.len();
        stats.propagated = added;
        stats.times.propagation = lap.lap();

        // 5. Continuous: the neighbourhoods of the pairs checked over the step, closest first.
        if cfg.continuous {
            let sweep = Sweep {
                a: SweptSide {
                    surface: a.surface,
                    deformed: begin.deformed[0],
                    start_pose: None,
                    end_pose: None,
                },
                b: SweptSide {
                    surface: b.surface,
                    deformed: begin.deformed[1],
                    start_pose: begin.pose_b.or(b.pose),
                    end_pose: b.pose,
                },
                self_mode,
                excluded: |x, y| searcher.excluded(x, y),
                size: size as f64,
            };
            let mut cut = passed();
            let counts = sweep.run(
                self.pairs.iter().map(|p| (p.triangle_a, p.triangle_b)),
                |k| {
                    cut = cut || passed();
                    !cut || (k as u64 + frame).is_multiple_of(LATE_SHARE as u64)
                },
                cfg.propagation_limit,
                &mut s.sweep,
            );
            stats.cut = stats.cut || cut;
            stats.swept = counts.swept;
            stats.sweep_skipped = counts.skipped;
            stats.sweep_triangle_pairs = counts.triangle_pairs;
            s.contact_keys.clear();
            s.contact_keys.extend(
                self.contacts
                    .iter()
                    .enumerate()
                    .map(|(i, c)| (key(self_mode, c.triangle_a, c.triangle_b), i)),
            );
            // Earliest first: a contact at the step's end whose triangles touched during it
            // gets the time they first touched.
            for c in &s.sweep.crossings {
                match s.contact_keys.entry(key(self_mode, c.ta, c.tb)) {
                    std::collections::hash_map::Entry::Occupied(i) => {
                        let contact = &mut self.contacts[*i.get()];
                        contact.time_of_impact.get_or_insert(c.time as f32);
                    }
                    std::collections::hash_map::Entry::Vacant(slot) => {
                        slot.insert(self.contacts.len());
                        self.contacts
                            .push(sweep.contact(c, cfg.thickness.max(0.0) as f64));
                        stats.crossings += 1;
                    }
                }
            }
            stats.contacts = self.contacts.len();
            stats.times.continuous = lap.lap();
        }
        self.tail = stats.times.pruning + stats.times.propagation + stats.times.continuous;
        self.stats = stats;
    }
}

/// A bound on how far any point of one surface moved towards the other over the step (in the
/// first mesh's frame): the surfaces' largest vertex displacements if they deformed, and for
/// two meshes the relative rigid motion's largest displacement over the second's box (the
/// displacement of a rigid motion is affine in the point: its largest length over a box is at
/// a corner), with what the rotation does to the deformation.
fn motion_bound(a: &Placed, b: &Placed, self_mode: bool, begin: &StepStart) -> f32 {
    let deformation = |p: &Placed, deformed: bool| {
        if deformed {
            p.surface.max_displacement() as f64
        } else {
            0.0
        }
    };
    let (da, db) = (
        deformation(a, begin.deformed[0]),
        deformation(b, begin.deformed[1]),
    );
    if self_mode {
        return (2.0 * da) as f32;
    }
    let rigid = match (begin.pose_b, b.pose) {
        (Some(start), Some(end)) => {
            let bx = b.surface.mesh().aabb();
            let mut most = 0.0f64;
            for i in 0..8 {
                let corner = glam::Vec3::new(
                    if i & 1 == 0 { bx.min.x } else { bx.max.x },
                    if i & 2 == 0 { bx.min.y } else { bx.max.y },
                    if i & 4 == 0 { bx.min.z } else { bx.max.z },
                );
                most = most.max(
                    end.transform_point(corner)
                        .distance(start.transform_point(corner)),
                );
            }
            // The deformation, seen through the start and the end rotation.
            most + 2.0 * db
        }
        _ => 0.0,
    };
    (da + db + rigid) as f32
}

fn key(self_mode: bool, x: u32, y: u32) -> (u32, u32) {
    if self_mode {
        (x.min(y), x.max(y))
    } else {
        (x, y)
    }
}

/// A pair record from a search result; in self-collision, sides ordered so that `(x, y)` and
/// `(y, x)` are the same record.
fn tracked(a: &Placed, b: &Placed, l: &Located, age: u32, self_mode: bool) -> TrackedPair {
    let va =
        l.fa.vertices(a.topology(), a.surface.mesh().triangles())
            .first();
    let vb =
        l.fb.vertices(b.topology(), b.surface.mesh().triangles())
            .first();
    let p = TrackedPair {
        triangle_a: l.ta,
        triangle_b: l.tb,
        feature_a: l.fa,
        feature_b: l.fb,
        distance: l.cp.distance,
        point_a: l.cp.point_a,
        point_b: l.cp.point_b,
        vertex_a: va,
        vertex_b: vb,
        age,
        settled: false,
    };
    if self_mode && (l.fb, l.tb) < (l.fa, l.ta) {
        TrackedPair {
            triangle_a: p.triangle_b,
            triangle_b: p.triangle_a,
            feature_a: p.feature_b,
            feature_b: p.feature_a,
            point_a: p.point_b,
            point_b: p.point_a,
            vertex_a: p.vertex_b,
            vertex_b: p.vertex_a,
            ..p
        }
    } else {
        p
    }
}

/// SplitMix64 of the seed and the frame: independent streams per frame.
fn mix(seed: u64, frame: u64) -> u64 {
    let mut z = seed ^ frame.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}
