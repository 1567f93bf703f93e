//! Parameters of a [`Tracker`](super::Tracker).

/// The meshes the tracker's constants (here and in the sampler, the search and the
/// pruning) were chosen on: `tracking_quality`'s generated capped tube
/// (`generated:tube`) and the shared `plane_50x50`, `large-intestine-sf+-hf-` and
/// `small_intestine_100k`, with [`TRAINING_SEEDS`]. Every other mesh and seed is held out:
/// reports on them measure how the defaults carry over.
pub const TRAINING_MESHES: [&str; 4] = [
    "generated:tube",
    "plane_50x50",
    "large-intestine-sf+-hf-",
    "small_intestine_100k",
];

/// The seeds (of the animation and of the tracker) the constants were chosen on, with
/// [`TRAINING_MESHES`].
pub const TRAINING_SEEDS: [u64; 2] = [1, 2];

/// How new random feature pairs are drawn each frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Sampling {
    /// Both features uniformly over the surfaces' (rest) area.
    Uniform,
    /// Over area weighted by how far the triangles moved since the last frame
    /// (importance-driven: fast-moving parts make new contacts). Between two meshes, each
    /// side's motion is measured in the other's frame, so the relative rigid motion counts
    /// as well as the deformation (a turning body's far end is drawn more than its hub).
    Velocity,
    /// Kimmerle et al.: only inside overlapping patch pairs of the incomplete hierarchy (a
    /// random descent below a candidate pair down to two leaves whose boxes still meet). For
    /// self-collision, a quarter of the samples are uniform (contacts between adjacent
    /// patches) and a third are crease probes around the sharpest folded or collapsed edges.
    #[default]
    Hierarchy,
}

/// The local search that moves a pair to a locally closest pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SearchMode {
    /// Every combination of a neighbour on each side: `O(n·m)` per step.
    Full,
    /// Raghupathi et al.: improve the first feature with the second fixed, then the second
    /// with the new first fixed: `O(n + m)` per step.
    #[default]
    TwoStep,
}

/// Parameters of a [`Tracker`](super::Tracker).
///
/// Distances are in the meshes' units. [`TrackerConfig::for_surface`] picks thickness and
/// thresholds from a mesh's own edge length and size.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackerConfig {
    /// New random pairs per frame (the papers' `n`): the pair work of a frame grows linearly
    /// with it, and so does the chance of finding a new contact region (what else a frame
    /// costs grows with the mesh: see [the module docs](super#what-a-frame-costs)). With
    /// [`TrackerConfig::overlaps_per_pair`] (the default) this is the least a step draws.
    pub pairs_per_frame: usize,
    /// Hierarchy sampling without a time budget: a step draws at least one new pair per this
    /// many overlapping patch pairs where the surfaces moved since the last step
    /// ([`StepStats::moved_patch_overlaps`](super::StepStats::moved_patch_overlaps): the
    /// candidates it samples among, where new contacts can appear), and at least
    /// `pairs_per_frame`, at most `max_active_pairs`. A surface with more places where it
    /// comes close to itself and moves (a larger, more coiled or busier one) gets more
    /// samples, so that each place is drawn about as often as on a small one; a flat, small or
    /// resting surface keeps `pairs_per_frame`. `Some(32)`
    /// by default (chosen on [`TRAINING_MESHES`] and [`TRAINING_SEEDS`]); `None`: exactly
    /// `pairs_per_frame`. Under [`TrackerConfig::time_budget`] the budget decides instead;
    /// `pairs_per_frame` 0 draws none.
    pub overlaps_per_pair: Option<u32>,
    /// Where new pairs come from.
    pub sampling: Sampling,
    /// Local search variant.
    pub search: SearchMode,
    /// Largest number of steps of one pair's local search per frame.
    pub max_iterations: u32,
    /// Contact distance: the sum of the two surfaces' radii `r_a + r_b`. Pairs closer than
    /// this (or intersecting) are contacts. 0 reports intersections only.
    pub thickness: f32,
    /// Guy and Debunne's `k`: pairs farther than `k·d_min + ε` are dropped.
    pub far_factor: f32,
    /// Guy and Debunne's `ε`, as a fraction of the object size (box diagonal).
    pub far_epsilon: f32,
    /// Self-collision ignores pairs of triangles within this many vertex rings of each other
    /// (0: sharing a vertex; 1: also joined by an edge; 2 by default). On irregular meshes,
    /// triangles one ring apart can be closer than a tenth of an edge without any fold.
    pub exclusion_rings: u32,
    /// Two pairs whose features are within this many vertex rings of each other, on both
    /// sides, are redundant: the farther one is dropped. Topological, so that the two walls
    /// of a thin fold stay distinct contacts.
    pub redundancy_rings: u32,
    /// Largest number of pairs kept between frames (the closest are kept).
    pub max_active_pairs: usize,
    /// Largest number of contacts added per frame by collision propagation (searching the
    /// neighbourhood of each contact for further contacts); 0 disables propagation.
    pub propagation_limit: usize,
    /// Seed of the random pair generator (the tracker's stream is also keyed by the frame).
    pub seed: u64,
    /// A time budget per step instead of a fixed number of new pairs: the step's end is a
    /// deadline ([`Tracker::step_self_until`](super::Tracker::step_self_until); the local
    /// search stops early enough to leave what pruning, propagation and the continuous check
    /// took at the last step), and after
    /// every step the new pairs per frame (starting from `pairs_per_frame`) are scaled towards
    /// what fills 80 % of the budget beside the step's fixed cost (finding the candidates,
    /// [`StepTimes::candidates`](super::StepTimes::candidates)), at most ×1.5 or ÷2 per step,
    /// between 8 and `max_active_pairs`
    /// ([`Tracker::pairs_per_frame_now`](super::Tracker::pairs_per_frame_now)). When the fixed
    /// cost alone takes the budget, the pair work still gets a quarter of it after the
    /// candidates (the step then overruns the budget, and an earlier deadline given to
    /// [`Tracker::step_self_until`](super::Tracker::step_self_until), rather than search
    /// nothing). In self-collision with [`Sampling::Hierarchy`], the candidates (overlapping
    /// patch pairs, sharp edges), which are kept between steps, are then brought up to date
    /// within a fifth of the budget: the parts of the patch tree whose vertices moved most
    /// since their lists were made go first, and the first step makes every list. Results
    /// then depend on the machine's speed; `None` (the default): a fixed `pairs_per_frame`,
    /// and every kept list whose part of the tree moved is made again at each step (exactly
    /// the candidates a search of the whole surface finds), reproducible.
    pub time_budget: Option<std::time::Duration>,
    /// Continuous tracking: each step also checks the surfaces over the step, from where
    /// they were at the last step to where they are now (each vertex on a straight line in
    /// the first mesh's frame), so that a sheet, a fold or a thin body that passed into or
    /// through the other surface between two steps is reported, with its time of impact
    /// ([`Contact::time_of_impact`](super::Contact::time_of_impact)). The triangles within a
    /// few vertex rings of every pair kept after the step (more the farther they moved, up to
    /// [`MAX_SWEEP_RINGS`](super::MAX_SWEEP_RINGS)) are swept and decided by the exact
    /// continuous primitives of [`crate::ccd`], then the crossings are followed to their
    /// neighbours like collision propagation (at most `propagation_limit`); new pairs are
    /// drawn from patches that come within the step's motion of each other, not only from
    /// patches that overlap at its end. A crossing no pair comes near is not seen: the check
    /// is as approximate as the tracking. Default `false`: only the step's end is checked.
    pub continuous: bool,
    /// Guy and Debunne's multiresolution: each new pair (besides the crease probes, which
    /// start in contact) is first moved over the meshes' vertices, where a step costs a few
    /// point distances, and is refined to triangles and searched exactly only if the
    /// triangles around the vertex pair it came to rest on can be close enough to be kept;
    /// a far or sliding start costs no triangle distance, and starts that come to rest on the
    /// vertices of a kept pair are dropped before their search ([`StepStats::coarse`](super::StepStats::coarse)).
    /// `true` by default (on the training meshes and seeds it found as many regions as
    /// without, at less time); `false`: every new pair is searched over triangles from where
    /// it was drawn.
    pub multiresolution: bool,
}

impl Default for TrackerConfig {
    fn default() -> Self {
        TrackerConfig {
            pairs_per_frame: 64,
            overlaps_per_pair: Some(32),
            sampling: Sampling::default(),
            search: SearchMode::default(),
            max_iterations: 16,
            thickness: 0.0,
            far_factor: 1.2,
            far_epsilon: 0.01,
            exclusion_rings: super::DEFAULT_EXCLUSION_RINGS,
            redundancy_rings: 2,
            max_active_pairs: 1024,
            propagation_limit: 256,
            seed: 0x5EED,
            time_budget: None,
            continuous: false,
            multiresolution: true,
        }
    }
}

impl TrackerConfig {
    /// Defaults with a thickness of a tenth of `surface`'s mean edge length: thin enough that
    /// triangles two rings apart on a smooth surface are not in contact.
    pub fn for_surface(surface: &super::TrackedSurface) -> Self {
        TrackerConfig {
            thickness: 0.1 * surface.mean_edge_length(),
            ..Self::default()
        }
    }
}
