//! What stochastic tracking costs and misses, against the exact self-collision pass.
//!
//! ```text
//! cargo run --release --example tracking_quality -- [--mesh PATH|generated:NAME]
//!     [--motion whirl|crumple|local] [--frames 120] [--seed S] [--pairs-per-frame N] [--budget-us US] [--json out.json] [--out-dir DIR] \
//!     [--sweep a,b,c | --no-sweep] [--sampling hierarchy|uniform|velocity] [--search two-step|full]
//!     [--patch-size N] [--overlaps-per-pair K|none] [--multiresolution on|off]
//! ```
//!
//! The main run uses the tracker's defaults: at least `--pairs-per-frame` (64) new pairs per
//! frame, more where the candidates are many (one per `--overlaps-per-pair` overlapping patch
//! pairs, `TrackerConfig::overlaps_per_pair`; `none`: exactly `--pairs-per-frame`). The sweep
//! (`--sweep`, by default 16, 32, 64, 128, 256 and `--pairs-per-frame`) runs fixed numbers of
//! new pairs per frame: what recall each number buys.
//!
//! `--multiresolution off` searches every new pair over triangles from where it was drawn
//! instead of first over vertices (`TrackerConfig::multiresolution`), for comparisons.
//!
//! `--budget-us US` gives the tracker a time budget per step (`TrackerConfig::time_budget`):
//! it adapts its new pairs per frame, starting from `--pairs-per-frame`, to what the budget
//! allows (no sweep then unless `--sweep` is given).
//!
//! The mesh (default: a generated capped tube, like a stretch of gut; any OBJ with `--mesh`,
//! or a generated one: `generated:tube` (the default), `generated:random-tube` (a tube along
//! a random centre line, seeded by `--seed`), `generated:noisy-sphere` (a spiky sphere, seeded),
//! `generated:cloth` (a 7200-triangle sheet)) is animated by a seeded [`Whirl`] (its halves
//! wind around an axis in opposite senses until they cut through each other, then unwind, in
//! episodes) or with `--motion crumple` a [`Crumple`] (folded like paper, two folds at a
//! time), or with `--motion local` the whirl within a ball around one seeded vertex
//! ([`Local`], of radius `LOCAL_RADIUS` of the box's diagonal), the rest at rest. Each run is labelled training or held out (`TRAINING_MESHES`, `TRAINING_SEEDS`:
//! what the tracker's constants were chosen on). Every frame, the exact pass
//! ([`self_contacts_excluding`], after a refit) finds every pair of triangles closer than the
//! thickness (a tenth of the mean edge length) that are not adjacent in the tracker's sense
//! (within its exclusion rings, 2 by default: `SelfExclusion`); a *contact region* is a connected set of
//! them (triangles linked by a contact pair or a shared vertex), followed from frame to frame
//! while it keeps a vertex in common with its previous shape or a contact point within two
//! tolerances of one of its previous points (regions move); regions that merge are followed
//! on together (hitting the merged region detects each). The tracker runs on the same
//! positions; a contact it reports *hits* a region when it lies within thickness + tolerance
//! (one mean edge length) of one of the region's exact contact points, and is *false* when it
//! hits none.
//!
//! JSON fields: `split` (`training` or `held_out`), `motion`, `recall` (regions hit within 3 frames of their first appearance; regions that
//! appear in the last 3 frames and are not hit yet are left out), `false_contact_rate` (contacts
//! farther than thickness + tolerance from every exact contact point),
//! `strict_false_contact_rate` (contacts whose triangle pair the exact pass does not report: its
//! triangles are farther apart than the thickness, no tolerance), `depth_error_mean`/`_p95`
//! (over the other contacts whose triangles are apart: |reported depth − (thickness − exact
//! distance)| over the thickness), `normal_error_deg_mean`/`_p95` (the angle from the exact
//! closest points' direction; contacts on crossing triangles have no exact depth or direction
//! and are left out of both),
//! `pair_coverage` (the exact contact triangle pairs, over all frames, with a reported contact
//! whose triangles each share a vertex with the pair's),
//! `regions`, `latency_frames_p95` (over the hit regions), `tracker_us_per_frame` (surface
//! update + step), `exact_us_per_frame` (refit + exact pass), both in thread CPU time (the
//! machine may be shared), `time_ratio`, `pairs_per_frame` (the configured one, the start under
//! a budget, the least with `overlaps_per_pair`), `mean_pairs_per_frame` (what the steps drew),
//! `overlaps_per_pair` (of the main run; `null` when its pairs per frame were fixed), `budget_us`, `breakdown_us`
//! (mean wall-clock µs per frame of the surface update and of each stage of the step:
//! candidates, sampling, local search, pruning, propagation; `StepTimes`),
//! `evaluations_per_frame` (triangle distances the local search and propagation measured,
//! `StepStats::evaluations`), `coarse_per_frame` (what the multiresolution coarse level did
//! with the new pairs, `StepStats::coarse`: started, refined, far, sliding, duplicate),
//! and the same for each `sweep` entry. Writes `frames.csv`, `sweep.csv`,
//! `recall_vs_pairs.svg` and `time_vs_pairs.svg` to `--out-dir` (default
//! `target/tracking_quality`). With `TRACKING_QUALITY_DEBUG=1`, each missed region is listed
//! (first frame, frames alive, largest number of exact pairs).

#[path = "support/progress.rs"]
mod progress;

use std::collections::{HashMap, HashSet};
use std::fmt::Write as _;
use std::path::PathBuf;

use glam::Vec3;
use plotters::prelude::*;
use stochastic_collision::bvh::{
    CollisionMesh, QueryWorkspace, SelfContact, self_contacts_excluding,
};
use stochastic_collision::deform::{Animation, Crumple, Local, Whirl};
use stochastic_collision::geometry::closest_points_triangle_triangle;
use stochastic_collision::mesh::{SelfExclusion, Topology, TriMesh, generate};
use stochastic_collision::tracking::{
    DEFAULT_PATCH_SIZE, Sampling, SearchMode, TRAINING_MESHES, TRAINING_SEEDS, TrackedSurface,
    Tracker, TrackerConfig,
};

/// CPU time of the calling thread, µs: what the work cost, whatever else runs on the machine
/// (falls back to wall-clock time where the platform has no thread clock).
fn cpu_us() -> f64 {
    #[cfg(unix)]
    {
        let mut ts = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: `ts` is a valid, writable timespec; the clock id is a constant.
        if unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) } == 0 {
            return ts.tv_sec as f64 * 1e6 + ts.tv_nsec as f64 * 1e-3;
        }
    }
    static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
    START
        .get_or_init(std::time::Instant::now)
        .elapsed()
        .as_secs_f64()
        * 1e6
}

/// Frames within which a new region must be hit.
const LATENCY_LIMIT: usize = 3;

/// Which animation moves the mesh.
#[derive(Clone, Copy, PartialEq)]
enum Motion {
    Whirl,
    Crumple,
    /// The whirl within a ball around one vertex ([`Local`]); the rest of the mesh rests.
    Local,
}

impl Motion {
    fn name(self) -> &'static str {
        match self {
            Motion::Whirl => "whirl",
            Motion::Crumple => "crumple",
            Motion::Local => "local",
        }
    }
}

/// `--motion local`: the ball's radius, as a fraction of the mesh box's diagonal.
const LOCAL_RADIUS: f32 = 0.15;

struct Settings {
    mesh: Option<PathBuf>,
    motion: Motion,
    frames: usize,
    seed: u64,
    pairs: usize,
    json: Option<PathBuf>,
    out_dir: PathBuf,
    sweep: Option<Vec<usize>>,
    sampling: Sampling,
    search: SearchMode,
    /// The tracker's time budget per step, µs (`TrackerConfig::time_budget`).
    budget_us: Option<u64>,
    /// Largest triangles per patch of the incomplete hierarchy.
    patch_size: u32,
    /// `TrackerConfig::overlaps_per_pair` of the main run.
    overlaps_per_pair: Option<u32>,
    /// `TrackerConfig::multiresolution`.
    multiresolution: bool,
}

fn parse_args() -> Result<Settings, String> {
    let mut s = Settings {
        mesh: None,
        motion: Motion::Whirl,
        frames: 120,
        seed: 1,
        pairs: 64,
        json: None,
        out_dir: PathBuf::from("target/tracking_quality"),
        sweep: Some(Vec::new()),
        sampling: Sampling::default(),
        search: SearchMode::default(),
        budget_us: None,
        patch_size: DEFAULT_PATCH_SIZE,
        overlaps_per_pair: TrackerConfig::default().overlaps_per_pair,
        multiresolution: TrackerConfig::default().multiresolution,
    };
    let mut explicit_sweep = false;
    let mut it = std::env::args_os().skip(1);
    let text = |v: Option<std::ffi::OsString>, flag: &str| -> Result<String, String> {
        v.and_then(|v| v.into_string().ok())
            .ok_or(format!("{flag} needs a value"))
    };
    let number = |v: Option<std::ffi::OsString>, flag: &str| -> Result<u64, String> {
        text(v, flag)?
            .parse()
            .map_err(|_| format!("{flag} needs a non-negative integer"))
    };
    while let Some(flag) = it.next() {
        match flag.to_str().unwrap_or("") {
            "--mesh" => s.mesh = Some(PathBuf::from(it.next().ok_or("--mesh needs a path")?)),
            "--motion" => {
                s.motion = match text(it.next(), "--motion")?.as_str() {
                    "whirl" => Motion::Whirl,
                    "crumple" => Motion::Crumple,
                    "local" => Motion::Local,
                    o => return Err(format!("unknown motion `{o}` (whirl|crumple|local)")),
                }
            }
            "--frames" => s.frames = number(it.next(), "--frames")?.max(1) as usize,
            "--seed" => s.seed = number(it.next(), "--seed")?,
            "--pairs-per-frame" => s.pairs = number(it.next(), "--pairs-per-frame")? as usize,
            "--json" => s.json = Some(PathBuf::from(it.next().ok_or("--json needs a path")?)),
            "--out-dir" => {
                s.out_dir = PathBuf::from(it.next().ok_or("--out-dir needs a directory")?)
            }
            "--no-sweep" => s.sweep = None,
            "--patch-size" => s.patch_size = number(it.next(), "--patch-size")?.max(1) as u32,
            "--overlaps-per-pair" => {
                s.overlaps_per_pair = match text(it.next(), "--overlaps-per-pair")?.as_str() {
                    "none" => None,
                    k => Some(k.parse().ok().filter(|&k: &u32| k > 0).ok_or(
                        "--overlaps-per-pair needs a positive integer or `none`".to_owned(),
                    )?),
                }
            }
            "--budget-us" => {
                let us = number(it.next(), "--budget-us")?;
                if us == 0 {
                    return Err("--budget-us needs a positive number of microseconds".into());
                }
                s.budget_us = Some(us);
            }
            "--sweep" => {
                explicit_sweep = true;
                let list = text(it.next(), "--sweep")?;
                let values: Result<Vec<usize>, _> = list.split(',').map(str::parse).collect();
                s.sweep = Some(values.map_err(|_| "--sweep needs numbers like 8,16,32")?);
            }
            "--sampling" => {
                s.sampling = match text(it.next(), "--sampling")?.as_str() {
                    "hierarchy" => Sampling::Hierarchy,
                    "uniform" => Sampling::Uniform,
                    "velocity" => Sampling::Velocity,
                    o => {
                        return Err(format!(
                            "unknown sampling `{o}` (hierarchy|uniform|velocity)"
                        ));
                    }
                }
            }
            "--multiresolution" => {
                s.multiresolution = match text(it.next(), "--multiresolution")?.as_str() {
                    "on" => true,
                    "off" => false,
                    o => return Err(format!("unknown --multiresolution `{o}` (on|off)")),
                }
            }
            "--search" => {
                s.search = match text(it.next(), "--search")?.as_str() {
                    "two-step" => SearchMode::TwoStep,
                    "full" => SearchMode::Full,
                    o => return Err(format!("unknown search `{o}` (two-step|full)")),
                }
            }
            other => {
                return Err(format!(
                    "unknown argument `{other}` (known: --mesh, --motion, --frames, --seed, --pairs-per-frame, --budget-us, --patch-size, --overlaps-per-pair, --json, --out-dir, --sweep, --no-sweep, --sampling, --search, --multiresolution)"
                ));
            }
        }
    }
    // Under a time budget the tracker picks its own pairs per frame: no sweep unless asked.
    if s.budget_us.is_some() && !explicit_sweep {
        s.sweep = None;
    }
    if let Some(sw) = &mut s.sweep {
        if sw.is_empty() {
            let n = s.pairs.max(1);
            *sw = vec![n / 4, n / 2, n, 2 * n, 4 * n];
        }
        sw.retain(|&v| v > 0);
        sw.sort_unstable();
        sw.dedup();
    }
    Ok(s)
}

/// One exact contact region in one frame.
struct Region {
    /// The tracks it continues, ascending: a new region starts a track; a region that moved
    /// continues its own; regions that merged continue all of theirs (hitting the merged
    /// region detects each of them).
    tracks: Vec<usize>,
}

/// The exact answer of one frame.
struct ExactFrame {
    us: f64,
    pairs: usize,
    regions: Vec<Region>,
    /// Contact points (midpoints of the closest points) and the region of each.
    points: Vec<(Vec3, usize)>,
    /// The triangle pairs of those points.
    triangle_pairs: Vec<(u32, u32)>,
}

struct Truth {
    frames: Vec<ExactFrame>,
    /// Per track: first frame.
    first_seen: Vec<usize>,
}

fn show_progress(label: &str, done: usize, total: usize) {
    // Redraw about every 2 %.
    let step = (total / 50).max(1);
    if !done.is_multiple_of(step) && done < total {
        return;
    }
    eprint!("\r  {label:<24} {}", progress::bar(done, total));
    if done >= total {
        eprintln!();
    }
}

struct UnionFind(Vec<u32>);
impl UnionFind {
    fn find(&mut self, mut x: u32) -> u32 {
        while self.0[x as usize] != x {
            let p = self.0[x as usize];
            self.0[x as usize] = self.0[p as usize];
            x = p;
        }
        x
    }
    fn union(&mut self, a: u32, b: u32) {
        let (a, b) = (self.find(a), self.find(b));
        if a != b {
            self.0[a.max(b) as usize] = a.min(b);
        }
    }
}

fn exact_truth(
    mesh: &TriMesh,
    whirl: &dyn Animation,
    thickness: f32,
    exclusion_rings: u32,
    continuity: f32,
) -> Truth {
    let topology = Topology::new(mesh);
    let exclusion = SelfExclusion::from_topology(mesh, &topology, exclusion_rings);
    let mut cm = CollisionMesh::new(mesh.clone());
    let mut ws = QueryWorkspace::new();
    let mut pairs: Vec<SelfContact> = Vec::new();
    let mut positions = Vec::new();
    let mut frames = Vec::new();
    let mut first_seen = Vec::new();
    // Vertex → the previous frame's region that used it.
    let mut prev_mark: HashMap<u32, usize> = HashMap::new();
    let mut prev_regions: Vec<Region> = Vec::new();
    // The previous frame's contact points, with their regions.
    let mut prev_points: Vec<(Vec3, usize)> = Vec::new();
    let mut near = Vec::new();
    let tris = mesh.triangles();
    for f in 0..whirl.frames() {
        whirl.positions(f, &mut positions);
        let t0 = cpu_us();
        cm.set_positions(&positions)
            .expect("the animation keeps positions finite");
        pairs.clear();
        // The same adjacency as the tracker's (pairs within `exclusion_rings` rings).
        self_contacts_excluding(&cm, thickness, &exclusion, &mut ws, &mut pairs)
            .expect("the exclusion is built for this mesh");
        let us = cpu_us() - t0;
        // Regions: triangles linked by a contact pair or a shared vertex.
        let mut ids: HashMap<u32, u32> = HashMap::new();
        let mut uf = UnionFind(Vec::new());
        let mut id_of = |t: u32, uf: &mut UnionFind| -> u32 {
            *ids.entry(t).or_insert_with(|| {
                uf.0.push(uf.0.len() as u32);
                uf.0.len() as u32 - 1
            })
        };
        let mut vertex_owner: HashMap<u32, u32> = HashMap::new();
        for c in &pairs {
            let (a, b) = (id_of(c.pair.a, &mut uf), id_of(c.pair.b, &mut uf));
            uf.union(a, b);
            for (t, id) in [(c.pair.a, a), (c.pair.b, b)] {
                for v in tris[t as usize] {
                    let o = *vertex_owner.entry(v).or_insert(id);
                    uf.union(o, id);
                }
            }
        }
        let pair_points: Vec<(Vec3, u32)> = pairs
            .iter()
            .map(|c| {
                let a = cm.mesh().triangle(c.pair.a as usize).map(|p| p.as_dvec3());
                let b = cm.mesh().triangle(c.pair.b as usize).map(|p| p.as_dvec3());
                let cp = closest_points_triangle_triangle(&a, &b);
                let root = uf.find(ids[&c.pair.a]);
                (((cp.point_a + cp.point_b) * 0.5).as_vec3(), root)
            })
            .collect();
        // Components → regions, each continuing the tracks of the previous regions it
        // touches: through a shared vertex, or a contact point within `continuity` of one of
        // their points (a region that moved).
        let mut inherited: HashMap<u32, Vec<usize>> = HashMap::new();
        let prev_grid = PointGrid::new(&prev_points, continuity);
        for &(p, root) in &pair_points {
            prev_grid.regions_near(p, &prev_points, &mut near);
            for &r in &near {
                inherited
                    .entry(root)
                    .or_default()
                    .extend_from_slice(&prev_regions[r].tracks);
            }
        }
        let mut sorted: Vec<(u32, u32)> = ids.iter().map(|(&t, &i)| (t, i)).collect();
        sorted.sort_unstable();
        for &(t, i) in &sorted {
            let root = uf.find(i);
            for v in tris[t as usize] {
                if let Some(&r) = prev_mark.get(&v) {
                    inherited
                        .entry(root)
                        .or_default()
                        .extend_from_slice(&prev_regions[r].tracks);
                }
            }
        }
        let mut regions: Vec<Region> = Vec::new();
        let mut region_of_root: HashMap<u32, usize> = HashMap::new();
        let mut mark = HashMap::new();
        for &(t, i) in &sorted {
            let root = uf.find(i);
            let r = *region_of_root.entry(root).or_insert_with(|| {
                let mut tracks = inherited.remove(&root).unwrap_or_default();
                tracks.sort_unstable();
                tracks.dedup();
                if tracks.is_empty() {
                    first_seen.push(f);
                    tracks.push(first_seen.len() - 1);
                }
                regions.push(Region { tracks });
                regions.len() - 1
            });
            for v in tris[t as usize] {
                mark.insert(v, r);
            }
        }
        let points: Vec<(Vec3, usize)> = pair_points
            .iter()
            .map(|&(p, root)| (p, region_of_root[&root]))
            .collect();
        prev_mark = mark;
        prev_points = points.clone();
        prev_regions = regions
            .iter()
            .map(|r| Region {
                tracks: r.tracks.clone(),
            })
            .collect();
        frames.push(ExactFrame {
            us,
            pairs: pairs.len(),
            regions,
            points,
            triangle_pairs: pairs.iter().map(|c| (c.pair.a, c.pair.b)).collect(),
        });
        show_progress("exact self pass", f + 1, whirl.frames());
    }
    Truth { frames, first_seen }
}

/// A uniform grid over the exact contact points of one frame.
/// Points of one grid cell grouped by label: (label, the points' indices).
type CellGroups = Vec<(usize, Vec<u32>)>;

struct PointGrid {
    cell: f32,
    /// Per cell: its points grouped by label.
    cells: HashMap<(i32, i32, i32), CellGroups>,
}

impl PointGrid {
    fn new(points: &[(Vec3, usize)], cell: f32) -> Self {
        let mut cells: HashMap<(i32, i32, i32), CellGroups> = HashMap::new();
        for (i, &(p, label)) in points.iter().enumerate() {
            let groups = cells.entry(Self::key(p, cell)).or_default();
            match groups.iter_mut().find(|(l, _)| *l == label) {
                Some((_, members)) => members.push(i as u32),
                None => groups.push((label, vec![i as u32])),
            }
        }
        PointGrid { cell, cells }
    }
    fn key(p: Vec3, cell: f32) -> (i32, i32, i32) {
        let q = (p / cell).floor();
        (q.x as i32, q.y as i32, q.z as i32)
    }
    /// Labels (regions, or tracks) of the points within `cell` of `p`. A label found once is
    /// not looked for again (dense contact patches hold many points of one label per cell).
    fn regions_near(&self, p: Vec3, points: &[(Vec3, usize)], out: &mut Vec<usize>) {
        out.clear();
        let (x, y, z) = Self::key(p, self.cell);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(groups) = self.cells.get(&(x + dx, y + dy, z + dz)) else {
                        continue;
                    };
                    for (label, members) in groups {
                        if out.contains(label) {
                            continue;
                        }
                        if members
                            .iter()
                            .any(|&i| (points[i as usize].0 - p).length() <= self.cell)
                        {
                            out.push(*label);
                        }
                    }
                }
            }
        }
    }
}

#[derive(Default, Clone)]
struct RunResult {
    pairs_per_frame: usize,
    /// New pairs per frame the steps drew, on average (under a time budget, adapted).
    mean_pairs: f64,
    /// The tracker's time budget per step, µs, if any.
    budget_us: Option<u64>,
    recall: f64,
    false_contact_rate: f64,
    regions: usize,
    latency_p95: f64,
    tracker_us: f64,
    exact_us: f64,
    /// Exact contact triangle pairs, over all frames, with a reported contact whose two
    /// triangles each share a vertex with (or are) the pair's, in either order: how much of
    /// each region the tracker covers, not only whether it found the region.
    pair_coverage: f64,
    /// Reported contacts whose triangle pair is not among the exact pass's pairs (no
    /// tolerance: the two triangles are farther apart than the thickness).
    strict_false_rate: f64,
    /// Contacts reported over all frames.
    contacts: usize,
    /// Over reported contacts whose triangles the exact pass finds apart (not crossing):
    /// |reported depth − (thickness − exact distance)| over the thickness, mean and p95.
    depth_error: (f64, f64),
    /// How many contacts, over all frames, the depth and normal errors are taken over.
    apart_contacts: usize,
    /// Over the same contacts: the angle between the reported normal and the exact closest
    /// points' direction (from `triangle_a` to `triangle_b`), degrees, mean and p95.
    normal_error_deg: (f64, f64),
    /// Per frame: (contacts, false contacts, active pairs, µs, regions hit).
    per_frame: Vec<(usize, usize, usize, f64, usize)>,
    /// Mean wall-clock µs per frame of each stage: the surface update
    /// (`TrackedSurface::update_time`), then the step's `StepTimes` (candidates, sampling,
    /// local search, pruning, propagation).
    breakdown_us: [f64; 6],
    /// Mean per frame of the multiresolution coarse level's counts: new pairs started at
    /// the vertex level, refined and searched, left far, sliding, duplicate
    /// (`StepStats::coarse`).
    coarse: [f64; 5],
    /// Mean triangle distances evaluated per frame by the search and propagation
    /// (`StepStats::evaluations`).
    evaluations: f64,
}

/// Names of [`RunResult::coarse`]'s entries.
const COARSE: [&str; 5] = ["started", "refined", "far", "sliding", "duplicate"];

/// Names of [`RunResult::breakdown_us`]'s entries.
const STAGES: [&str; 6] = [
    "update",
    "candidates",
    "sampling",
    "local_search",
    "pruning",
    "propagation",
];

fn run_tracker(
    mesh: &TriMesh,
    mut surface: TrackedSurface,
    whirl: &dyn Animation,
    truth: &Truth,
    config: TrackerConfig,
    tolerance: f32,
) -> RunResult {
    let mut tracker = Tracker::new(config.clone());
    let radius = config.thickness + tolerance;
    let mut positions = Vec::new();
    let mut first_hit: Vec<Option<usize>> = vec![None; truth.first_seen.len()];
    let (mut reported, mut false_contacts) = (0usize, 0usize);
    let mut total_us = 0.0;
    let mut per_frame = Vec::new();
    let mut near = Vec::new();
    let topology = Topology::new(mesh);
    let (mut exact_pairs, mut covered_pairs) = (0usize, 0usize);
    let mut covered: HashSet<(u32, u32)> = HashSet::new();
    let mut pairs_drawn = 0usize;
    let mut strict_false = 0usize;
    let (mut depth_errors, mut normal_errors) = (Vec::new(), Vec::new());
    let mut exact_set: HashSet<(u32, u32)> = HashSet::new();
    let mut breakdown = [0.0f64; 6];
    let mut coarse = [0.0f64; 5];
    let mut evaluations = 0.0;
    for (f, exact) in truth.frames.iter().enumerate() {
        whirl.positions(f, &mut positions);
        let t0 = cpu_us();
        surface
            .set_positions(&positions)
            .expect("the animation keeps positions finite");
        tracker.step_self(&surface);
        let us = cpu_us() - t0;
        total_us += us;
        pairs_drawn += tracker.stats().pairs_per_frame;
        let times = tracker.stats().times;
        let c = tracker.stats().coarse;
        for (sum, n) in coarse
            .iter_mut()
            .zip([c.started, c.refined, c.far, c.sliding, c.duplicate])
        {
            *sum += n as f64;
        }
        evaluations += tracker.stats().evaluations as f64;
        for (sum, d) in breakdown.iter_mut().zip([
            surface.update_time(),
            times.candidates,
            times.sampling,
            times.local_search,
            times.pruning,
            times.propagation,
        ]) {
            *sum += d.as_secs_f64() * 1e6;
        }
        let grid = PointGrid::new(&exact.points, radius);
        let mut false_here = 0;
        let mut hit_here = Vec::new();
        for c in tracker.contacts() {
            grid.regions_near((c.point_a + c.point_b) * 0.5, &exact.points, &mut near);
            if near.is_empty() {
                false_here += 1;
            }
            for &r in &near {
                for &track in &exact.regions[r].tracks {
                    if first_hit[track].is_none() {
                        first_hit[track] = Some(f);
                    }
                    if !hit_here.contains(&track) {
                        hit_here.push(track);
                    }
                }
            }
        }
        reported += tracker.contacts().len();
        false_contacts += false_here;
        // Untimed: each contact against the exact pass's answer for its triangle pair.
        exact_set.clear();
        exact_set.extend(
            exact
                .triangle_pairs
                .iter()
                .map(|&(a, b)| (a.min(b), a.max(b))),
        );
        for c in tracker.contacts() {
            let (a, b) = (c.triangle_a, c.triangle_b);
            if !exact_set.contains(&(a.min(b), a.max(b))) {
                strict_false += 1;
                continue;
            }
            let tri =
                |t: u32| mesh.triangles()[t as usize].map(|v| positions[v as usize].as_dvec3());
            let cp = closest_points_triangle_triangle(&tri(a), &tri(b));
            if cp.distance > 0.0 {
                let h = config.thickness as f64;
                depth_errors.push((c.depth as f64 - (h - cp.distance)).abs() / h);
                let exact_normal = (cp.point_b - cp.point_a) / cp.distance;
                let cos = c.normal.as_dvec3().normalize_or_zero().dot(exact_normal);
                normal_errors.push(cos.clamp(-1.0, 1.0).acos().to_degrees());
            }
        }
        // Untimed: the triangle pairs near a reported contact, then the exact pairs among them.
        covered.clear();
        for c in tracker.contacts() {
            for x in one_ring(mesh, &topology, c.triangle_a) {
                for y in one_ring(mesh, &topology, c.triangle_b) {
                    covered.insert((x.min(y), x.max(y)));
                }
            }
        }
        exact_pairs += exact.triangle_pairs.len();
        covered_pairs += exact
            .triangle_pairs
            .iter()
            .filter(|&&(a, b)| covered.contains(&(a.min(b), a.max(b))))
            .count();
        per_frame.push((
            tracker.contacts().len(),
            false_here,
            tracker.pairs().len(),
            us,
            hit_here.len(),
        ));
    }
    let frames = truth.frames.len();
    let (mut counted, mut detected) = (0usize, 0usize);
    let mut latencies = Vec::new();
    let debug = std::env::var_os("TRACKING_QUALITY_DEBUG").is_some();
    for (track, &t0) in truth.first_seen.iter().enumerate() {
        if debug && first_hit[track].is_none_or(|h| h - t0 > LATENCY_LIMIT) {
            let (frames_alive, max_points) = truth.frames.iter().fold((0, 0), |(n, m), fr| {
                let pts = fr
                    .points
                    .iter()
                    .filter(|(_, r)| fr.regions[*r].tracks.contains(&track))
                    .count();
                (n + usize::from(pts > 0), m.max(pts))
            });
            let fr = &truth.frames[t0];
            let rings: Vec<u32> = fr
                .points
                .iter()
                .zip(&fr.triangle_pairs)
                .filter(|((_, r), _)| fr.regions[*r].tracks.contains(&track))
                .map(|(_, &(x, y))| ring_distance(mesh, &topology, x, y, 40))
                .collect();
            eprintln!(
                "missed track {track}: t0 {t0}, hit {:?}, alive {frames_alive} frames, up to {max_points} pairs, rings at t0 {}..{}",
                first_hit[track],
                rings.iter().min().unwrap_or(&0),
                rings.iter().max().unwrap_or(&0)
            );
        }
        let hit = first_hit[track];
        let in_time = hit.is_some_and(|h| h - t0 <= LATENCY_LIMIT);
        if let Some(h) = hit {
            latencies.push((h - t0) as f64);
        }
        if in_time || t0 + LATENCY_LIMIT < frames {
            counted += 1;
            detected += usize::from(in_time);
        }
    }
    let latency_p95 = p95(&mut latencies);
    let mean_p95 = |v: &mut Vec<f64>| {
        let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
        (mean, p95(v))
    };
    RunResult {
        pairs_per_frame: config.pairs_per_frame,
        mean_pairs: pairs_drawn as f64 / frames.max(1) as f64,
        budget_us: config.time_budget.map(|b| b.as_micros() as u64),
        recall: if counted == 0 {
            1.0
        } else {
            detected as f64 / counted as f64
        },
        false_contact_rate: if reported == 0 {
            0.0
        } else {
            false_contacts as f64 / reported as f64
        },
        strict_false_rate: if reported == 0 {
            0.0
        } else {
            strict_false as f64 / reported as f64
        },
        contacts: reported,
        apart_contacts: depth_errors.len(),
        depth_error: mean_p95(&mut depth_errors),
        normal_error_deg: mean_p95(&mut normal_errors),
        regions: counted,
        latency_p95,
        tracker_us: total_us / frames as f64,
        exact_us: truth.frames.iter().map(|f| f.us).sum::<f64>() / frames as f64,
        pair_coverage: if exact_pairs == 0 {
            1.0
        } else {
            covered_pairs as f64 / exact_pairs as f64
        },
        per_frame,
        breakdown_us: breakdown.map(|t| t / frames.max(1) as f64),
        coarse: coarse.map(|n| n / frames.max(1) as f64),
        evaluations: evaluations / frames.max(1) as f64,
    }
}

/// The 95th percentile of `v` (sorted in place; 0 when empty).
fn p95(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        0.0
    } else {
        v[((v.len() as f64 * 0.95).ceil() as usize).clamp(1, v.len()) - 1]
    }
}

/// Triangle `t` and every triangle sharing a vertex with it.
fn one_ring<'a>(
    mesh: &'a TriMesh,
    topology: &'a Topology,
    t: u32,
) -> impl Iterator<Item = u32> + 'a {
    let mut seen: Vec<u32> = mesh.triangles()[t as usize]
        .iter()
        .flat_map(|&v| topology.vertex_triangles(v).iter().copied())
        .collect();
    seen.sort_unstable();
    seen.dedup();
    seen.into_iter()
}

/// Vertex rings between two triangles (0: they share a vertex), up to `limit`.
fn ring_distance(mesh: &TriMesh, topology: &Topology, a: u32, b: u32, limit: u32) -> u32 {
    let target = mesh.triangles()[b as usize];
    let mut seen: std::collections::HashSet<u32> =
        mesh.triangles()[a as usize].into_iter().collect();
    let mut front: Vec<u32> = seen.iter().copied().collect();
    for r in 0..limit {
        if front.iter().any(|v| target.contains(v)) {
            return r;
        }
        let mut next = Vec::new();
        for &v in &front {
            for &w in topology.vertex_neighbours(v) {
                if seen.insert(w) {
                    next.push(w);
                }
            }
        }
        front = next;
    }
    limit
}

fn json_run(r: &RunResult) -> String {
    format!(
        "\"pairs_per_frame\": {}, \"mean_pairs_per_frame\": {:.1}, \"budget_us\": {}, \"recall\": {:.4}, \"false_contact_rate\": {:.4}, \"strict_false_contact_rate\": {:.4}, \"contacts\": {}, \"apart_contacts\": {}, \"depth_error_mean\": {:.3e}, \"depth_error_p95\": {:.3e}, \"normal_error_deg_mean\": {:.3e}, \"normal_error_deg_p95\": {:.3e}, \"pair_coverage\": {:.4}, \"regions\": {}, \"latency_frames_p95\": {:.1}, \"tracker_us_per_frame\": {:.1}, \"exact_us_per_frame\": {:.1}, \"time_ratio\": {:.4}, \"breakdown_us\": {{{}}}, \"evaluations_per_frame\": {:.1}, \"coarse_per_frame\": {{{}}}",
        r.pairs_per_frame,
        r.mean_pairs,
        r.budget_us.map_or("null".to_owned(), |b| b.to_string()),
        r.recall,
        r.false_contact_rate,
        r.strict_false_rate,
        r.contacts,
        r.apart_contacts,
        r.depth_error.0,
        r.depth_error.1,
        r.normal_error_deg.0,
        r.normal_error_deg.1,
        r.pair_coverage,
        r.regions,
        r.latency_p95,
        r.tracker_us,
        r.exact_us,
        r.tracker_us / r.exact_us.max(1e-9),
        breakdown(r, |name, us| format!("\"{name}\": {us:.1}")),
        r.evaluations,
        coarse_counts(r, |name, n| format!("\"{name}\": {n:.1}"))
    )
}

/// `r`'s mean coarse-level counts per frame, each written by `item`, separated by commas.
fn coarse_counts(r: &RunResult, item: impl Fn(&str, f64) -> String) -> String {
    named(&COARSE, r.coarse, item)
}

/// `r`'s per-frame breakdown, each stage written by `item`, separated by commas.
fn breakdown(r: &RunResult, item: impl Fn(&str, f64) -> String) -> String {
    named(&STAGES, r.breakdown_us, item)
}

/// Each of `values` with its name, written by `item`, separated by commas.
fn named<const N: usize>(
    names: &[&str; N],
    values: [f64; N],
    item: impl Fn(&str, f64) -> String,
) -> String {
    names
        .iter()
        .zip(values)
        .map(|(name, v)| item(name, v))
        .collect::<Vec<_>>()
        .join(", ")
}

/// A labelled curve of a plot.
type Series<'a> = (&'a str, Vec<(f64, f64)>, RGBColor);

fn plot(
    path: &std::path::Path,
    title: &str,
    y_desc: &str,
    series: &[Series],
) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::new(path, (800, 500)).into_drawing_area();
    root.fill(&WHITE)?;
    let xmax = series
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.0))
        .fold(1.0, f64::max);
    let xmin = series
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.0))
        .fold(xmax, f64::min);
    let ymax = series
        .iter()
        .flat_map(|s| s.1.iter().map(|p| p.1))
        .fold(1e-9, f64::max);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d((xmin / 1.5..xmax * 1.5).log_scale(), 0.0f64..ymax * 1.15)?;
    chart
        .configure_mesh()
        .x_desc("new pairs per frame (log)")
        .x_labels(12)
        .x_label_formatter(&|x| format!("{x:.0}"))
        .y_desc(y_desc)
        .draw()?;
    for (label, pts, color) in series {
        let color = *color;
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
            .label(*label)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 16, y)], color.stroke_width(2))
            });
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}

/// Generated meshes `--mesh generated:NAME` names: a seeded shape (the run's seed) that no
/// constant was chosen on, unless it is the training tube.
const GENERATED: [&str; 4] = ["tube", "random-tube", "noisy-sphere", "cloth"];

/// The mesh of `--mesh` (an OBJ path or `generated:NAME`; default the generated tube) and
/// its name.
fn load_mesh(path: Option<&std::path::Path>, seed: u64) -> Result<(String, TriMesh), String> {
    let Some(path) = path else {
        return load_mesh(Some(std::path::Path::new("generated:tube")), seed);
    };
    let text = path.to_string_lossy();
    let Some(kind) = text.strip_prefix("generated:") else {
        return TriMesh::from_obj(path)
            .map(|m| (path.display().to_string(), m))
            .map_err(|e| e.to_string());
    };
    let mesh = match kind {
        "tube" => generate::tube(0.08, 2.0, 24, 160, true),
        "random-tube" => generate::random_tube(0.06, 2.0, 24, 240, seed),
        "noisy-sphere" => generate::noisy_sphere(1.0, 4, 0.25, seed),
        "cloth" => generate::cloth_grid(1.0, 1.0, 60, 60),
        other => {
            return Err(format!(
                "unknown generated mesh `{other}` (known: {})",
                GENERATED.join(", ")
            ));
        }
    };
    Ok((format!("generated:{kind}"), mesh))
}

/// Whether a run is on the tracker's training data ([`TRAINING_MESHES`], [`TRAINING_SEEDS`]).
fn is_training(name: &str, seed: u64) -> bool {
    let stem = std::path::Path::new(name.trim_start_matches("generated:"))
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    TRAINING_SEEDS.contains(&seed) && TRAINING_MESHES.iter().any(|m| *m == stem || *m == name)
}

fn main() {
    let settings = match parse_args() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("tracking_quality: {e}");
            std::process::exit(2);
        }
    };
    let (name, mesh) = match load_mesh(settings.mesh.as_deref(), settings.seed) {
        Ok(named) => named,
        Err(e) => {
            eprintln!("tracking_quality: {e}");
            std::process::exit(2);
        }
    };
    let (whirl, episodes): (Box<dyn Animation>, usize) = match settings.motion {
        Motion::Whirl => {
            let w = Whirl::new(&mesh, settings.frames, settings.seed);
            let n = w.episodes().len();
            (Box::new(w), n)
        }
        Motion::Crumple => {
            let c = Crumple::new(&mesh, settings.frames, settings.seed);
            let n = c.episodes().len();
            (Box::new(c), n)
        }
        Motion::Local => {
            let w = Whirl::new(&mesh, settings.frames, settings.seed);
            let n = w.episodes().len();
            let l = Local::new(&mesh, w, LOCAL_RADIUS, settings.seed);
            (Box::new(l), n)
        }
    };
    let whirl = whirl.as_ref();
    let training = is_training(&name, settings.seed);
    let probe = TrackedSurface::with_patch_size(mesh.clone(), settings.patch_size);
    let mut config = TrackerConfig::for_surface(&probe);
    config.seed = settings.seed;
    config.time_budget = settings.budget_us.map(std::time::Duration::from_micros);
    config.sampling = settings.sampling;
    config.search = settings.search;
    config.multiresolution = settings.multiresolution;
    let tolerance = probe.mean_edge_length();
    println!(
        "tracking_quality: {name} ({}): {} triangles, {} boundary edges, {} non-manifold; {} frames, {} {} episode(s); thickness {:.4}, tolerance {:.4}",
        if training { "training" } else { "held out" },
        mesh.triangle_count(),
        Topology::new(&mesh).boundary_edge_count(),
        Topology::new(&mesh).non_manifold_edge_count(),
        settings.frames,
        episodes,
        settings.motion.name(),
        config.thickness,
        tolerance
    );
    let truth = exact_truth(
        &mesh,
        whirl,
        config.thickness,
        config.exclusion_rings,
        config.thickness + 2.0 * tolerance,
    );
    // The sweep: fixed numbers of new pairs per frame.
    let mut counts: Vec<usize> = settings.sweep.clone().unwrap_or_default();
    if settings.sweep.is_some() && !counts.contains(&settings.pairs) {
        counts.push(settings.pairs);
        counts.sort_unstable();
    }
    let mut results = Vec::new();
    for (i, &n) in counts.iter().enumerate() {
        let cfg = TrackerConfig {
            pairs_per_frame: n,
            overlaps_per_pair: None,
            ..config.clone()
        };
        results.push(run_tracker(
            &mesh,
            probe.clone(),
            whirl,
            &truth,
            cfg,
            tolerance,
        ));
        show_progress("tracker sweep", i + 1, counts.len());
    }
    // The main run: the defaults (or the settings given), the sweep's row when it is the same.
    let main_config = TrackerConfig {
        pairs_per_frame: settings.pairs,
        overlaps_per_pair: settings.overlaps_per_pair,
        ..config.clone()
    };
    let same_as_sweep = results
        .iter()
        .find(|r| r.pairs_per_frame == settings.pairs && main_config.overlaps_per_pair.is_none());
    let main_run = match same_as_sweep {
        Some(r) => r.clone(),
        None => {
            let r = run_tracker(&mesh, probe.clone(), whirl, &truth, main_config, tolerance);
            show_progress("tracker, main run", 1, 1);
            r
        }
    };
    let adaptive = settings.overlaps_per_pair.is_some() && settings.budget_us.is_none();

    println!(
        "{:>8} {:>8} {:>8} {:>8} {:>9} {:>9} {:>9} {:>9} {:>8} {:>9} {:>12} {:>12} {:>7}",
        "pairs/f",
        "recall",
        "false",
        "strict",
        "apart",
        "depth95",
        "normal95",
        "coverage",
        "regions",
        "lat.p95",
        "tracker µs",
        "exact µs",
        "ratio"
    );
    let rows = results.iter().map(|r| (r.pairs_per_frame.to_string(), r));
    let main_label = if adaptive {
        format!("≥{}", main_run.pairs_per_frame)
    } else {
        main_run.pairs_per_frame.to_string()
    };
    let main_row = same_as_sweep
        .is_none()
        .then_some((main_label.clone(), &main_run));
    for (label, r) in rows.chain(main_row) {
        println!(
            "{:>8} {:>8.3} {:>8.3} {:>8.3} {:>9} {:>9.1e} {:>8.1e}° {:>9.3} {:>8} {:>9.1} {:>12.0} {:>12.0} {:>7.3}",
            label,
            r.recall,
            r.false_contact_rate,
            r.strict_false_rate,
            format!("{}/{}", r.apart_contacts, r.contacts),
            r.depth_error.1,
            r.normal_error_deg.1,
            r.pair_coverage,
            r.regions,
            r.latency_p95,
            r.tracker_us,
            r.exact_us,
            r.tracker_us / r.exact_us.max(1e-9)
        );
    }
    println!(
        "per-frame breakdown at {} pairs/f (wall-clock µs, mean): {}",
        main_label,
        breakdown(&main_run, |name, us| format!("{name} {us:.0}"))
    );
    println!(
        "per frame (mean): {:.0} triangle distances searched; coarse level (--multiresolution {}): {}",
        main_run.evaluations,
        if settings.multiresolution {
            "on"
        } else {
            "off"
        },
        coarse_counts(&main_run, |name, n| format!("{name} {n:.1}"))
    );
    if adaptive {
        println!(
            "main run (the defaults): {:.1} new pairs per frame on average (at least {}, one per {} overlapping patch pairs where the surface moved)",
            main_run.mean_pairs,
            main_run.pairs_per_frame,
            settings.overlaps_per_pair.unwrap_or(0)
        );
    }
    if let Some(us) = settings.budget_us {
        println!(
            "time budget {us} µs per tracker step: {:.1} new pairs per frame on average (adapted from {})",
            main_run.mean_pairs, main_run.pairs_per_frame
        );
    }

    if let Err(e) = std::fs::create_dir_all(&settings.out_dir) {
        eprintln!(
            "tracking_quality: cannot create {}: {e}",
            settings.out_dir.display()
        );
        std::process::exit(1);
    }
    let mut csv = String::from(
        "frame,exact_pairs,exact_regions,tracker_contacts,false_contacts,active_pairs,regions_hit,tracker_us,exact_us\n",
    );
    for (f, (exact, row)) in truth.frames.iter().zip(&main_run.per_frame).enumerate() {
        let _ = writeln!(
            csv,
            "{f},{},{},{},{},{},{},{:.1},{:.1}",
            exact.pairs,
            exact.regions.len(),
            row.0,
            row.1,
            row.2,
            row.4,
            row.3,
            exact.us
        );
    }
    let mut sweep_csv = String::from(
        "pairs_per_frame,recall,false_contact_rate,strict_false_contact_rate,depth_error_p95,normal_error_deg_p95,pair_coverage,regions,latency_frames_p95,tracker_us_per_frame,exact_us_per_frame\n",
    );
    for r in &results {
        let _ = writeln!(
            sweep_csv,
            "{},{:.4},{:.4},{:.4},{:.3e},{:.3e},{:.4},{},{:.1},{:.1},{:.1}",
            r.pairs_per_frame,
            r.recall,
            r.false_contact_rate,
            r.strict_false_rate,
            r.depth_error.1,
            r.normal_error_deg.1,
            r.pair_coverage,
            r.regions,
            r.latency_p95,
            r.tracker_us,
            r.exact_us
        );
    }
    let write = |file: &str, text: &str| {
        let path = settings.out_dir.join(file);
        if let Err(e) = std::fs::write(&path, text) {
            eprintln!("tracking_quality: cannot write {}: {e}", path.display());
            std::process::exit(1);
        }
    };
    write("frames.csv", &csv);
    write("sweep.csv", &sweep_csv);
    let curve = |y: fn(&RunResult) -> f64| -> Vec<(f64, f64)> {
        results
            .iter()
            .map(|r| (r.pairs_per_frame as f64, y(r)))
            .collect()
    };
    let recall = curve(|r| r.recall);
    let false_rate = curve(|r| r.false_contact_rate);
    let tracker_t = curve(|r| r.tracker_us / 1000.0);
    let exact_t = curve(|r| r.exact_us / 1000.0);
    let budget_t = curve(|r| 0.2 * r.exact_us / 1000.0);
    let recall_target = curve(|_| 0.95);
    let title = format!(
        "{}: {} triangles",
        name.rsplit('/').next().unwrap_or(&name),
        mesh.triangle_count()
    );
    let plots = [
        plot(
            &settings.out_dir.join("recall_vs_pairs.svg"),
            &format!("Recall within 3 frames — {title}"),
            "fraction",
            &[
                ("recall", recall, RGBColor(31, 119, 180)),
                ("false contact rate", false_rate, RGBColor(214, 39, 40)),
                ("target recall 0.95", recall_target, RGBColor(150, 150, 150)),
            ],
        ),
        plot(
            &settings.out_dir.join("time_vs_pairs.svg"),
            &format!("Time per frame — {title}"),
            "ms per frame (thread CPU time)",
            &[
                ("tracker", tracker_t, RGBColor(31, 119, 180)),
                ("exact self pass", exact_t, RGBColor(44, 160, 44)),
                ("target: 0.2 × exact", budget_t, RGBColor(150, 150, 150)),
            ],
        ),
    ];
    for p in plots {
        if let Err(e) = p {
            eprintln!("tracking_quality: plot failed: {e}");
            std::process::exit(1);
        }
    }
    let sweep_json: Vec<String> = results
        .iter()
        .map(|r| format!("{{{}}}", json_run(r)))
        .collect();
    let json = format!(
        "{{\"mesh\": \"{}\", \"split\": \"{}\", \"motion\": \"{}\", \"triangles\": {}, \"frames\": {}, \"seed\": {}, \"thickness\": {}, \"tolerance\": {}, \"overlaps_per_pair\": {}, {}, \"sweep\": [{}]}}\n",
        name.replace('\\', "\\\\").replace('"', "\\\""),
        if training { "training" } else { "held_out" },
        settings.motion.name(),
        mesh.triangle_count(),
        settings.frames,
        settings.seed,
        config.thickness,
        tolerance,
        settings
            .overlaps_per_pair
            .filter(|_| adaptive)
            .map_or("null".to_owned(), |k| k.to_string()),
        json_run(&main_run),
        sweep_json.join(", ")
    );
    if let Some(path) = &settings.json
        && let Err(e) = std::fs::write(path, &json)
    {
        eprintln!("tracking_quality: cannot write {}: {e}", path.display());
        std::process::exit(1);
    }
    println!(
        "wrote {}/{{frames.csv, sweep.csv, recall_vs_pairs.svg, time_vs_pairs.svg}}",
        settings.out_dir.display()
    );
}
