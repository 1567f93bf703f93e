//! What accuracy costs in time: Klein & Zachmann's benchmark for ADB-trees against the exact
//! query.
//!
//! Two copies of a mesh at random orientations approach each other along random directions;
//! each pose sits at a random offset from first contact (in units of the mesh's size, the
//! diagonal of its box). Every pose is answered exactly (ground truth, timed), by the exact query
//! preceded by the interpenetration certificate where its map is exact ("certificate + exact":
//! `certified_intersects`, the fastest exact query of the crate), and by ADB-trees over a sweep of `p_min`, `k_min`, time and node budgets,
//! estimators, orders and the certificate on or off ("no-interior"). Only poses whose root boxes
//! overlap count (as in the papers).
//!
//! Timing: each method (the exact query, each configuration) answers all poses in turn before
//! the next method starts, so no query runs on caches another method has just warmed on the
//! same pose; this is done five times (`TIMING_PASSES`), and a query's time (and answer) is that
//! of its median pass.
//!
//! ```text
//! cargo run --release --example accuracy_vs_time -- [--full] [--pairs | --cad] [--paper-trees] [--seed S] [--spread F] [--poses N]
//!     [--out DIR] [--meshes a,b,...] [--resolution R] [--fill F] [--interior-resolution R]
//!     [--interior-samples N]
//! ```
//!
//! `--pairs`: instead of each mesh against itself, held-out pairs of *different* meshes
//! (`support/mesh_pairs.rs`: one 10–30× the other, smooth scans against spiky and thin shapes,
//! CAD-like generated parts; the first of a pair is the smaller, and offsets are in units of its
//! size). `--cad`: generated CAD-like parts (a pipe bundle, a box of thin walls, a slotted plate,
//! layered sheets), each against itself, like the papers' car body, pipes and door lock.
//! `--paper-trees`: trees built as the papers build them (`AdbBuildOptions::paper`: the published
//! MaxArea, boxes without slabs, no fits, no interior map; give it before `--resolution` or
//! `--fill` to change those). `--seed`: the evaluation poses' seed (default 0xACC0). `--spread F`: offsets from first
//! contact within ±F of the size (default 0.15; 0.02 for shallow contacts only).
//!
//! Default: a quick run (generated meshes and the shared bunny, 150 poses each) in seconds.
//! `--full`: every shared mesh, 600 poses each (`docs/adb.md`'s figures: `--full --poses 300`). Writes
//! `results.csv`, `summary.csv`, `outcomes.csv`, `time_vs_distance.csv`, `error_vs_time.svg`,
//! `error_vs_median.svg`, `error_vs_distance.svg`, `time_vs_distance.svg` and `reliability.svg` to
//! `DIR` (default `target/accuracy_vs_time`), and prints a table of the headline configurations, a
//! table of the variants (orders, decisions, the raw estimate without its fitted calibration)
//! against the default, the reliability of the reported probabilities, the ADB targets per mesh
//! (met or not), where the time of the exact and the default queries goes on colliding and
//! non-colliding poses (median time, node pairs, time per node pair: `outcomes.csv`) and by
//! distance from first contact (`time_vs_distance.*`), the oracle bound: what a traversal that went
//! straight down to the nearest intersecting triangle pair would take (`support/oracle_descent.rs`;
//! also in `outcomes.csv`), how many poses each query answers within the targeted fraction of the
//! exact median, and what reaching that fraction with a node budget costs in error.
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use plotters::coord::Shift;
use plotters::prelude::*;
use stochastic_collision::adb::{
    AdbBuildOptions, AdbQuery, AdbTree, AdbWorkspace, AnswerConfidence, AnswerModel, Budget,
    Decision, MAX_SURFACE_SAMPLES, Order, PlanarityEstimator, TRAINING_MESHES, TRAINING_SEEDS,
    adb_intersects, certified_intersects, exact_intersects,
};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, intersects, root_boxes_overlap};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::{TriMesh, generate};
use stochastic_collision::poses::near_contact_poses;

#[path = "support/mesh_pairs.rs"]
mod mesh_pairs;
#[path = "support/oracle_descent.rs"]
mod oracle_descent;
#[path = "support/progress.rs"]
mod progress;
#[path = "support/reliability.rs"]
mod reliability;
use oracle_descent::{LeafDepths, oracle_descent_pairs};

/// Offsets from first contact are drawn uniformly in ±spread × size: by default ±15 % (deep
/// overlaps and poses well short of contact, as in the papers), `--spread` for others (±0.02:
/// the shallow contacts a physics scene mostly sees).
const DEFAULT_SPREAD: f32 = 0.15;
static SPREAD: std::sync::OnceLock<f32> = std::sync::OnceLock::new();

/// The run's spread of offsets from first contact (fraction of the size).
fn spread() -> f32 {
    *SPREAD.get().unwrap_or(&DEFAULT_SPREAD)
}
/// "Near contact": within 5 % of the size of first contact.
const NEAR: f32 = 0.05;
const DISTANCE_BINS: usize = 10;
/// Width of a distance bin (fraction of the size).
fn distance_bin_width() -> f32 {
    2.0 * spread() / DISTANCE_BINS as f32
}

/// The distance bin of an offset from first contact.
fn distance_bin(offset: f32) -> usize {
    (((offset + spread()) / distance_bin_width()) as usize).min(DISTANCE_BINS - 1)
}

/// The centre offset of distance bin `i`.
fn distance_bin_center(i: usize) -> f64 {
    f64::from(-spread() + distance_bin_width() * (i as f32 + 0.5))
}
/// Passes over all poses per method; a query's time is its median over the passes (an odd
/// number, so the median is one pass's time; more passes make the ratios steadier from run to
/// run on a shared machine).
const TIMING_PASSES: usize = 5;

struct Settings {
    full: bool,
    poses: usize,
    out: PathBuf,
    meshes: Option<Vec<String>>,
    build: AdbBuildOptions,
    /// Pairs of different meshes (`mesh_pairs`) instead of each mesh against itself.
    pairs: bool,
    /// Generated CAD-like parts (`mesh_pairs::cad_parts`), each against itself.
    cad: bool,
    /// Seed of the evaluation poses.
    seed: u64,
}

/// The evaluation poses' default seed: the one the ADB defaults were chosen on
/// (`adb::TRAINING_SEEDS`; not the seeds of the build-time fits' training poses). Held-out runs
/// take another (`--seed`).
const EVALUATION_SEED: u64 = TRAINING_SEEDS[0];

fn parse_args() -> Result<Settings, String> {
    let mut s = Settings {
        full: false,
        poses: 0,
        out: PathBuf::from("target/accuracy_vs_time"),
        meshes: None,
        build: AdbBuildOptions::default(),
        pairs: false,
        cad: false,
        seed: EVALUATION_SEED,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        match flag.as_str() {
            "--full" => s.full = true,
            "--pairs" => s.pairs = true,
            "--cad" => s.cad = true,
            "--paper-trees" => s.build = AdbBuildOptions::paper(),
            "--spread" => {
                let v = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .filter(|f: &f32| *f > 0.0 && *f <= 1.0)
                    .ok_or("--spread needs a fraction in (0, 1]")?;
                SPREAD.set(v).map_err(|_| "--spread given twice")?;
            }
            "--seed" => {
                s.seed = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .ok_or("--seed needs a whole number")?
            }
            "--poses" => {
                s.poses = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .filter(|&n: &usize| n > 0)
                    .ok_or("--poses needs a positive number")?
            }
            "--out" => s.out = PathBuf::from(it.next().ok_or("--out needs a directory")?),
            "--meshes" => {
                s.meshes = Some(
                    it.next()
                        .ok_or("--meshes needs a list")?
                        .split(',')
                        .map(str::to_string)
                        .collect(),
                )
            }
            "--resolution" => {
                s.build.resolution = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .filter(|r| (1..=8).contains(r))
                    .ok_or("--resolution needs a number in 1..=8")?
            }
            "--fill" => {
                s.build.fill_fraction = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .filter(|f: &f32| *f > 0.0 && *f <= 1.0)
                    .ok_or("--fill needs a number in (0, 1]")?
            }
            "--interior-resolution" => {
                s.build.interior_resolution = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .filter(|r| (1..=1024).contains(r))
                    .ok_or("--interior-resolution needs a number in 1..=1024")?
            }
            "--interior-samples" => {
                s.build.interior_samples = it
                    .next()
                    .and_then(|v| v.parse().ok())
                    .filter(|n| (1..=MAX_SURFACE_SAMPLES).contains(n))
                    .ok_or(format!(
                        "--interior-samples needs a number in 1..={MAX_SURFACE_SAMPLES}"
                    ))?
            }
            other => {
                return Err(format!(
                    "unknown argument `{other}` (known: --full, --pairs, --cad, --paper-trees, --seed S, --spread F, --poses N, --out DIR, \
                     --meshes a,b, --resolution R, --fill F, --interior-resolution R, \
                     --interior-samples N)"
                ));
            }
        }
    }
    if s.poses == 0 {
        s.poses = if s.full { 600 } else { 150 };
    }
    Ok(s)
}

/// One ADB configuration of the sweep.
struct Config {
    label: String,
    /// Which curve of the error-vs-time plot it belongs to.
    family: &'static str,
    query: AdbQuery,
}

/// The sweep: the papers' method as published, and the calibrated default over `p_min`,
/// `k_min`, pruning and budgets.
fn configs() -> Vec<Config> {
    let mut out = Vec::new();
    let paper = |p_min: f64, k_min: u32| AdbQuery {
        p_min,
        k_min,
        ..AdbQuery::paper()
    };
    let tuned = |p_min: f64, k_min: u32, p_prune: f64, budget: Budget| AdbQuery {
        p_min,
        k_min,
        budget,
        p_prune,
        ..AdbQuery::default()
    };
    for (p, k) in [(0.9, 1), (0.99, 1), (0.99, 5), (0.99, 10), (0.999, 10)] {
        out.push(Config {
            label: format!("paper p{p} k{k}"),
            family: "paper",
            query: paper(p, k),
        });
    }
    for (p, k, prune) in [
        (0.8, 1, 0.0),
        (0.9, 1, 0.0),
        (0.9, 3, 0.0),
        (0.9, 10, 0.0),
        (0.95, 3, 0.0),
        (0.95, 10, 0.0),
        (0.99, 1, 0.0),
        (0.99, 3, 0.0),
        (0.99, 10, 0.0),
        (0.999, 10, 0.0),
        (0.99, 10, 0.01),
        (0.99, 10, 0.05),
    ] {
        let label = if prune > 0.0 {
            format!("calibrated p{p} k{k} prune{prune}")
        } else {
            format!("calibrated p{p} k{k}")
        };
        out.push(Config {
            label,
            family: "calibrated",
            query: tuned(p, k, prune, Budget::Unlimited),
        });
    }
    for us in [5u64, 10, 20, 50, 100] {
        out.push(Config {
            label: format!("calibrated p0.99 k10 {us}us"),
            family: "time budget",
            query: tuned(0.99, 10, 0.0, Budget::Time(Duration::from_micros(us))),
        });
    }
    // Down to a handful of node pairs: where the median reaches the 0.25× target, and what the
    // answers are worth there.
    for n in NODE_BUDGETS {
        out.push(Config {
            label: format!("calibrated p0.99 k10 {n}nodes"),
            family: "node budget",
            query: tuned(0.99, 10, 0.0, Budget::NodePairs(n)),
        });
    }
    // Exact leaves (on by default) undone, the evidence decision (off by default) taken, and
    // both: what each is worth.
    let variant = |decision: Decision, exact_leaves: bool| AdbQuery {
        decision,
        exact_leaves,
        ..tuned(0.99, 10, 0.0, Budget::Unlimited)
    };
    out.push(Config {
        label: "calibrated p0.99 k10 estimated-leaves".into(),
        family: "estimator",
        query: variant(Decision::Confidence, false),
    });
    for (label, order, budget) in [
        (
            "calibrated p0.99 k10 depth-first",
            Order::DepthFirst,
            Budget::Unlimited,
        ),
        (
            "calibrated p0.99 k10 depth-first 20us",
            Order::DepthFirst,
            Budget::Time(Duration::from_micros(20)),
        ),
        (
            "calibrated p0.99 k10 evidence-first",
            Order::EvidenceFirst,
            Budget::Unlimited,
        ),
        (
            "calibrated p0.99 k10 best-first",
            Order::BestFirst,
            Budget::Unlimited,
        ),
    ] {
        out.push(Config {
            label: label.into(),
            family: "estimator",
            query: AdbQuery {
                order,
                ..tuned(0.99, 10, 0.0, budget)
            },
        });
    }
    // The answer model undone (the frontier's raw confidence, the tree's own fit for a mesh
    // against itself), and the tree's own fit where it applies with the model elsewhere.
    for (label, answer_confidence) in [
        (PER_MESH_20_LABEL, AnswerConfidence::PerMesh),
        (
            PER_MESH_ELSE_MODEL_20_LABEL,
            AnswerConfidence::PerMeshElseModel(AnswerModel::FITTED),
        ),
    ] {
        out.push(Config {
            label: label.into(),
            family: "estimator",
            query: AdbQuery {
                answer_confidence,
                ..tuned(0.99, 10, 0.0, Budget::Time(Duration::from_micros(20)))
            },
        });
    }
    // The interpenetration certificate undone: what it is worth, unbudgeted and under a
    // budget.
    for (label, budget) in [
        (NO_INTERIOR_LABEL, Budget::Unlimited),
        (
            "calibrated p0.99 k10 no-interior 20us",
            Budget::Time(Duration::from_micros(20)),
        ),
    ] {
        out.push(Config {
            label: label.into(),
            family: "estimator",
            query: AdbQuery {
                interior_after: None,
                ..tuned(0.99, 10, 0.0, budget)
            },
        });
    }
    out.push(Config {
        label: "calibrated p0.99 k10 evidence".into(),
        family: "estimator",
        query: variant(Decision::Evidence, true),
    });
    out.push(Config {
        label: "calibrated p0.99 k10 evidence estimated-leaves".into(),
        family: "estimator",
        query: variant(Decision::Evidence, false),
    });
    // The fitted calibration undone: the raw estimate, with exact leaves (the default's
    // setting), under budgets and with estimated leaves (where the estimate decides).
    for (suffix, budget, exact_leaves) in [
        ("", Budget::Unlimited, true),
        (" 20us", Budget::Time(Duration::from_micros(20)), true),
        (" 100nodes", Budget::NodePairs(100), true),
        (" estimated-leaves", Budget::Unlimited, false),
    ] {
        out.push(Config {
            label: format!("planarity p0.99 k10{suffix}"),
            family: "estimator",
            query: AdbQuery {
                estimator: Arc::new(PlanarityEstimator::default()),
                budget,
                exact_leaves,
                ..AdbQuery::default()
            },
        });
    }
    out
}

/// The node budgets of the sweep (node pairs), ascending.
const NODE_BUDGETS: [u64; 8] = [10, 20, 30, 40, 60, 100, 300, 1000];

/// `certified_intersects`: the exact query preceded by the interpenetration certificate where
/// its map is exact (not an ADB configuration; always the exact answer).
const CERTIFIED_EXACT_LABEL: &str = "certificate + exact";
/// `exact_intersects`: the best exact query of the crate (always the exact answer).
const BEST_EXACT_LABEL: &str = "best exact";
/// The default without the interpenetration certificate.
const NO_INTERIOR_LABEL: &str = "calibrated p0.99 k10 no-interior";

/// The default configuration, whose error the targets are about.
const DEFAULT_LABEL: &str = "calibrated p0.99 k10";
const PAPER_LABEL: &str = "paper p0.99 k10";
const BUDGET_20_LABEL: &str = "calibrated p0.99 k10 20us";
/// The 20 µs budget without the answer model (the per-mesh confidence fit only).
const PER_MESH_20_LABEL: &str = "calibrated p0.99 k10 20us per-mesh";
/// The 20 µs budget with the per-mesh fit where it applies, the answer model elsewhere.
const PER_MESH_ELSE_MODEL_20_LABEL: &str = "calibrated p0.99 k10 20us per-mesh+model";
const BUDGET_5_LABEL: &str = "calibrated p0.99 k10 5us";
const NODE_BUDGET_100_LABEL: &str = "calibrated p0.99 k10 100nodes";
const ESTIMATED_LEAVES_LABEL: &str = "calibrated p0.99 k10 estimated-leaves";
/// The configurations of the printed table (the exact query besides); the variants table and
/// summary.csv have the others.
const HEADLINE_LABELS: [&str; 4] = [
    PAPER_LABEL,
    DEFAULT_LABEL,
    BUDGET_20_LABEL,
    ESTIMATED_LEAVES_LABEL,
];
/// The ADB targets (`docs/adb.md`): mean error and error
/// near contact (%), the default's median against the exact query's on meshes of at least
/// `TARGET_RATIO_TRIANGLES` triangles (the older, same-mesh targets), and issue 30's: the
/// default unbudgeted query errs nowhere, the best exact query takes at most
/// `TARGET_BEST_EXACT_RATIO` of the plain exact query's median, and a 20 µs budget errs on at
/// most `TARGET_BUDGET_ERROR` % with a Brier score at most `TARGET_BUDGET_BRIER` and a p99 within
/// `TARGET_BUDGET_P99` budgets.
const TARGET_ERROR: f64 = 2.0;
const TARGET_NEAR_ERROR: f64 = 5.0;
const TARGET_RATIO: f64 = 0.25;
const TARGET_RATIO_TRIANGLES: usize = 30_000;
const TARGET_BEST_EXACT_RATIO: f64 = 0.6;
const TARGET_BUDGET_ERROR: f64 = 5.0;
const TARGET_BUDGET_BRIER: f64 = 0.03;
const TARGET_BUDGET_P99: f64 = 1.3;
/// The budget of [`BUDGET_20_LABEL`], in µs.
const BUDGET_20_US: f64 = 20.0;

/// Where the shared meshes are (`STOCHASTIC_COLLISION_MESHES`, else `../shared/assets/meshes`).
fn shared_dir() -> PathBuf {
    std::env::var_os("STOCHASTIC_COLLISION_MESHES")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/meshes")
        })
}

/// The cases of the report: each mesh against itself (no second mesh), or with `--pairs` the
/// held-out pairs of different meshes.
fn cases(settings: &Settings) -> Vec<(String, TriMesh, Option<TriMesh>)> {
    if settings.cad {
        return mesh_pairs::cad_parts()
            .into_iter()
            .map(|(name, mesh)| (name, mesh, None))
            .collect();
    }
    if settings.pairs {
        return mesh_pairs::held_out_pairs(&shared_dir())
            .into_iter()
            .map(|p| (p.name, p.first, Some(p.second)))
            .collect();
    }
    meshes(settings)
        .into_iter()
        .map(|(name, mesh)| (name, mesh, None))
        .collect()
}

fn meshes(settings: &Settings) -> Vec<(String, TriMesh)> {
    let shared_dir = shared_dir();
    // `--full`: the eight meshes the defaults were chosen on (`adb::TRAINING_MESHES`); the
    // quick run, the first three of them.
    let names: &[&str] = if settings.full {
        &TRAINING_MESHES
    } else {
        &TRAINING_MESHES[..3]
    };
    let wanted: Vec<String> = match &settings.meshes {
        Some(list) => list.clone(),
        None => names.iter().map(|s| s.to_string()).collect(),
    };
    let mut out = Vec::new();
    for name in wanted {
        let mesh = match name.as_str() {
            "icosphere_20k" => Ok(generate::icosphere(1.0, 5)),
            "torus_32k" => Ok(generate::torus(1.0, 0.3, 256, 64)),
            other => TriMesh::from_obj(shared_dir.join(format!("{other}.obj"))),
        };
        match mesh {
            Ok(m) => out.push((name, m)),
            Err(e) => eprintln!("note: skipping {name}: {e}"),
        }
    }
    out
}

/// One query's result.
#[derive(Clone, Copy)]
struct Answer {
    collides: bool,
    probability: f64,
    time_ns: f64,
    nodes: u64,
    /// Node pairs counted as evidence (`AdbOutcome::pairs_found`; 0 for the exact queries).
    pairs_found: u32,
    /// The highest pair probability estimated (`AdbOutcome::max_pair_probability`).
    max_pair: f64,
}

struct PoseRecord {
    offset: f32,
    exact: Answer,
    /// `certified_intersects`: the exact query preceded by the interpenetration certificate
    /// where its map is exact; always the exact answer, found sooner where the certificate
    /// settles it.
    certified_exact: Answer,
    /// `exact_intersects`: the best exact query of the crate (the certificate where exact,
    /// then the ADB traversal with `p_min = 1`: slabs, straddle order, exact leaves).
    best_exact: Answer,
    adb: Vec<Answer>,
    /// Node pairs of the oracle descent ([`oracle_descent_pairs`]); `None` if not colliding.
    oracle_pairs: Option<u64>,
}

fn progress_bar(label: &str, done: usize, total: usize) {
    eprint!("\r  {label:<28} {}", progress::bar(done, total));
    if done >= total {
        eprintln!();
    }
}

/// Builds an ADB-tree with a progress bar; prints its size and build time.
fn build_tree(name: &str, mesh: TriMesh, build: AdbBuildOptions) -> AdbTree {
    let cm = CollisionMesh::new(mesh);
    let total_nodes = cm.bvh().nodes().len();
    let start = Instant::now();
    let shown = std::sync::atomic::AtomicUsize::new(0);
    let tree = AdbTree::build_with_progress(cm, build, &|p| {
        // Redraw about every 2 %.
        let step = (p.nodes_total / 50).max(1);
        let last = shown.load(std::sync::atomic::Ordering::Relaxed);
        if p.nodes_done >= last + step || p.nodes_done == p.nodes_total {
            shown.store(p.nodes_done, std::sync::atomic::Ordering::Relaxed);
            progress_bar(&format!("{name}: ADB build"), p.nodes_done, p.nodes_total);
        }
    });
    let build_s = start.elapsed().as_secs_f64();
    let tris = tree.collision_mesh().mesh().triangle_count();
    // How full the cells are: what the papers' rule needs (a node pair whose nodes have no
    // well-filled cell in their overlap has probability 0 and is never expanded by it).
    let nodes = tree.nodes();
    let filled = nodes.iter().filter(|n| n.well_filled > 0).count();
    let mean = nodes.iter().map(|n| f64::from(n.well_filled)).sum::<f64>() / nodes.len() as f64;
    println!(
        "{name}: {:.1} % of the nodes have a well-filled cell, {mean:.1} of {} cells per node on \
         average (fill fraction {}, slabs {})",
        100.0 * filled as f64 / nodes.len() as f64,
        tree.cells_per_node(),
        tree.options().fill_fraction,
        if tree.options().normal_slabs {
            "on"
        } else {
            "off"
        },
    );
    eprintln!(
        "  {name}: {tris} triangles, {total_nodes} nodes, ADB build {:.2} s ({:.0} k triangles/s)",
        build_s,
        tris as f64 / build_s / 1e3
    );
    tree
}

/// Answers every pose of one case: `mesh` against itself, or against `second` (poses of the
/// second in the first's frame, offsets in units of the first's size). Returns the records and
/// the case's triangle count (the larger mesh's).
fn run_mesh(
    name: &str,
    mesh: TriMesh,
    second: Option<TriMesh>,
    poses: usize,
    build: AdbBuildOptions,
    seed: u64,
) -> (Vec<PoseRecord>, usize) {
    let tree = build_tree(name, mesh, build);
    // Against itself the second tree is the same object (what its fitted calibration is for).
    let second_tree = second.map(|m| build_tree(&format!("{name} (second)"), m, build));
    let tree_b = second_tree.as_ref().unwrap_or(&tree);
    let tris = tree
        .collision_mesh()
        .mesh()
        .triangle_count()
        .max(tree_b.collision_mesh().mesh().triangle_count());
    let configs = configs();
    let cm = tree.collision_mesh();
    let cm_b = tree_b.collision_mesh();
    // Evaluation poses: a different seed from the fit's training poses. Only poses whose root
    // boxes overlap count, as in the papers.
    let approach: Vec<_> = near_contact_poses(cm, cm_b, poses, spread(), seed)
        .into_iter()
        .filter(|p| root_boxes_overlap(cm, &Pose::IDENTITY, cm_b, &p.pose))
        .collect();
    let mut exact_ws = QueryWorkspace::new();
    let mut adb_ws = AdbWorkspace::new();
    // runs[method][pose]: one answer per timing pass; method 0 is the exact query, the last
    // two the exact query preceded by the interpenetration certificate and the best exact
    // query (`exact_intersects`).
    let methods = configs.len() + 3;
    let mut runs = vec![vec![Vec::with_capacity(TIMING_PASSES); approach.len()]; methods];
    let steps = TIMING_PASSES * methods;
    for pass in 0..TIMING_PASSES {
        // Each method answers every pose in turn before the next method starts, so no query
        // runs on caches that another method has just warmed on the same pose.
        for (m, method_runs) in runs.iter_mut().enumerate() {
            for (p, pose_runs) in approach.iter().zip(method_runs.iter_mut()) {
                let t = Instant::now();
                let answer = if m == 0 || m >= methods - 2 {
                    let (hit, nodes) = if m == 0 {
                        let hit = intersects(cm, &Pose::IDENTITY, cm_b, &p.pose, &mut exact_ws);
                        (hit, exact_ws.node_pairs_visited())
                    } else if m == methods - 2 {
                        let hit = certified_intersects(
                            &tree,
                            &Pose::IDENTITY,
                            tree_b,
                            &p.pose,
                            &mut exact_ws,
                        );
                        (hit, exact_ws.node_pairs_visited())
                    } else {
                        let hit =
                            exact_intersects(&tree, &Pose::IDENTITY, tree_b, &p.pose, &mut adb_ws);
                        (hit, 0)
                    };
                    Answer {
                        collides: hit,
                        probability: if hit { 1.0 } else { 0.0 },
                        time_ns: t.elapsed().as_nanos() as f64,
                        nodes,
                        pairs_found: 0,
                        max_pair: 0.0,
                    }
                } else {
                    let o = adb_intersects(
                        &tree,
                        &Pose::IDENTITY,
                        tree_b,
                        &p.pose,
                        &configs[m - 1].query,
                        &mut adb_ws,
                    );
                    Answer {
                        collides: o.collides,
                        probability: o.probability,
                        time_ns: t.elapsed().as_nanos() as f64,
                        nodes: o.node_pairs_visited,
                        pairs_found: o.pairs_found,
                        max_pair: o.max_pair_probability,
                    }
                };
                pose_runs.push(answer);
            }
            progress_bar(&format!("{name}: queries"), pass * methods + m + 1, steps);
        }
    }
    // Each query's answer is that of its median-time pass (time budgets make answers vary).
    let median_run = |pose_runs: &mut Vec<Answer>| {
        pose_runs.sort_by(|x, y| x.time_ns.total_cmp(&y.time_ns));
        pose_runs[pose_runs.len() / 2]
    };
    let depths = LeafDepths::new(cm);
    let depths_b = LeafDepths::new(cm_b);
    let mut hits = Vec::new();
    let records = approach
        .iter()
        .enumerate()
        .map(|(i, p)| PoseRecord {
            offset: p.offset / p.size,
            exact: median_run(&mut runs[0][i]),
            certified_exact: median_run(&mut runs[methods - 2][i]),
            best_exact: median_run(&mut runs[methods - 1][i]),
            adb: (1..methods - 2)
                .map(|m| median_run(&mut runs[m][i]))
                .collect(),
            oracle_pairs: oracle_descent_pairs(
                (cm, &depths),
                (cm_b, &depths_b),
                &p.pose,
                &mut exact_ws,
                &mut hits,
            ),
        })
        .collect();
    (records, tris)
}

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// Error statistics of one configuration on one mesh.
struct Stats {
    median_us: f64,
    p99_us: f64,
    error: f64,
    false_pos: f64,
    false_neg: f64,
    near_error: f64,
    brier: f64,
    budget_kept: f64,
}

fn stats(records: &[PoseRecord], pick: impl Fn(&PoseRecord) -> Answer) -> Stats {
    let n = records.len().max(1) as f64;
    let mut times: Vec<f64> = records.iter().map(|r| pick(r).time_ns / 1e3).collect();
    let wrong = |r: &PoseRecord| pick(r).collides != r.exact.collides;
    let near: Vec<&PoseRecord> = records.iter().filter(|r| r.offset.abs() <= NEAR).collect();
    Stats {
        median_us: median(&mut times.clone()),
        p99_us: percentile(&mut times, 0.99),
        error: 100.0 * records.iter().filter(|r| wrong(r)).count() as f64 / n,
        false_pos: 100.0
            * records
                .iter()
                .filter(|r| pick(r).collides && !r.exact.collides)
                .count() as f64
            / n,
        false_neg: 100.0
            * records
                .iter()
                .filter(|r| !pick(r).collides && r.exact.collides)
                .count() as f64
            / n,
        near_error: 100.0 * near.iter().filter(|r| wrong(r)).count() as f64
            / near.len().max(1) as f64,
        brier: records
            .iter()
            .map(|r| (pick(r).probability - f64::from(u8::from(r.exact.collides))).powi(2))
            .sum::<f64>()
            / n,
        budget_kept: 0.0,
    }
}

fn main() {
    let settings = match parse_args() {
        Ok(s) => s,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    if let Err(e) = std::fs::create_dir_all(&settings.out) {
        eprintln!("error: cannot create {}: {e}", settings.out.display());
        std::process::exit(2);
    }
    let configs = configs();
    let mut all: BTreeMap<String, Vec<PoseRecord>> = BTreeMap::new();
    let mut triangles: BTreeMap<String, usize> = BTreeMap::new();
    let mut order = Vec::new();
    for (name, mesh, second) in cases(&settings) {
        // Training: a mesh of `adb::TRAINING_MESHES` against itself, at the training seed and
        // the default spread; everything else is held out.
        let training = second.is_none()
            && !settings.cad
            && TRAINING_MESHES.contains(&name.as_str())
            && TRAINING_SEEDS.contains(&settings.seed)
            && spread() == DEFAULT_SPREAD;
        println!(
            "{name}: {}",
            if training {
                "training (the ADB defaults were chosen on this mesh and these poses)"
            } else {
                "held out (the ADB defaults were not chosen on this mesh, seed or spread)"
            }
        );
        let (records, tris) = run_mesh(
            &name,
            mesh,
            second,
            settings.poses,
            settings.build,
            settings.seed,
        );
        order.push(name.clone());
        triangles.insert(name.clone(), tris);
        all.insert(name, records);
    }
    if all.is_empty() {
        eprintln!("error: no meshes");
        std::process::exit(2);
    }
    if let Err(e) = write_outputs(&settings, &configs, &order, &all)
        .and_then(|()| write_targets(&settings, &configs, &order, &all, &triangles))
    {
        eprintln!("error: cannot write the report: {e}");
        std::process::exit(2);
    }
}

/// The medians (µs) of the two exact baselines on one case: the plain exact query and the best
/// exact query.
#[derive(Clone, Copy)]
struct Medians {
    exact: f64,
    best_exact: f64,
}

/// The columns of a configuration's statistics, in the order of `summary.csv` and the table
/// (median and p99 µs, ratio of the median to the plain and the best exact ones, error, false positives, false
/// negatives and error near contact in %, Brier score), each with its number of decimals,
/// joined by `separator`.
fn stat_columns(s: &Stats, medians: Medians, digits: [usize; 9], separator: &str) -> String {
    let values = [
        s.median_us,
        s.p99_us,
        s.median_us / medians.exact,
        s.median_us / medians.best_exact,
        s.error,
        s.false_pos,
        s.false_neg,
        s.near_error,
        s.brier,
    ];
    let cells: Vec<String> = values
        .iter()
        .zip(digits)
        .map(|(v, d)| format!("{v:.d$}"))
        .collect();
    cells.join(separator)
}

/// A line of `summary.csv` (with the share of budgets kept).
fn summary_row(mesh: &str, label: &str, s: &Stats, medians: Medians) -> String {
    let columns = stat_columns(s, medians, [3, 3, 4, 4, 3, 3, 3, 3, 5], ",");
    format!("{mesh},{label},{columns},{:.1}", s.budget_kept)
}

/// A row of the printed table.
fn table_row(mesh: &str, label: &str, s: &Stats, medians: Medians) -> String {
    let columns = stat_columns(s, medians, [1, 1, 2, 2, 1, 1, 1, 1, 3], " | ");
    format!("| {mesh} | {label} | {columns} |")
}

/// `name` in the output directory, with its header line written.
fn create_csv(
    settings: &Settings,
    name: &str,
    header: &str,
) -> std::io::Result<std::io::BufWriter<std::fs::File>> {
    let mut file = std::io::BufWriter::new(std::fs::File::create(settings.out.join(name))?);
    writeln!(file, "{header}")?;
    Ok(file)
}

fn write_outputs(
    settings: &Settings,
    configs: &[Config],
    order: &[String],
    all: &BTreeMap<String, Vec<PoseRecord>>,
) -> Result<(), Box<dyn std::error::Error>> {
    // Raw results.
    let mut csv = create_csv(
        settings,
        "results.csv",
        "mesh,config,offset,exact,collides,probability,time_ns,nodes_visited",
    )?;
    for name in order {
        for r in &all[name] {
            let e = r.exact;
            writeln!(
                csv,
                "{name},exact,{},{},{},{},{},{}",
                r.offset,
                u8::from(e.collides),
                u8::from(e.collides),
                e.probability,
                e.time_ns,
                e.nodes
            )?;
            for (c, a) in configs.iter().zip(&r.adb) {
                writeln!(
                    csv,
                    "{name},{},{},{},{},{:.6},{},{}",
                    c.label,
                    r.offset,
                    u8::from(e.collides),
                    u8::from(a.collides),
                    a.probability,
                    a.time_ns,
                    a.nodes
                )?;
            }
        }
    }
    csv.flush()?;

    // Summary table.
    let mut summary = create_csv(
        settings,
        "summary.csv",
        "mesh,config,median_us,p99_us,ratio_to_exact,ratio_to_best_exact,error_pct,false_pos_pct,false_neg_pct,near_error_pct,brier,budget_kept_pct",
    )?;
    let mut table = String::new();
    writeln!(
        table,
        "| mesh | config | median µs | p99 µs | × exact | × best exact | error % | FP % | FN % | error % near | Brier |"
    )?;
    writeln!(
        table,
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    for name in order {
        let records = &all[name];
        let medians = Medians {
            exact: stats(records, |r| r.exact).median_us,
            best_exact: stats(records, |r| r.best_exact).median_us,
        };
        let tris_note = format!("{name} ({} poses)", records.len());
        // The exact baselines (the plain exact query, the certificate before it, the best
        // exact query): in the table too, above the ADB configurations.
        for (label, pick) in [
            (
                "exact",
                (|r: &PoseRecord| r.exact) as fn(&PoseRecord) -> Answer,
            ),
            (CERTIFIED_EXACT_LABEL, |r: &PoseRecord| r.certified_exact),
            (BEST_EXACT_LABEL, |r: &PoseRecord| r.best_exact),
        ] {
            let c = Stats {
                budget_kept: 100.0,
                ..stats(records, pick)
            };
            writeln!(summary, "{}", summary_row(name, label, &c, medians))?;
            writeln!(table, "{}", table_row(&tris_note, label, &c, medians))?;
        }
        for (k, c) in configs.iter().enumerate() {
            let mut s = stats(records, |r| r.adb[k]);
            if let Budget::Time(t) = c.query.budget {
                let limit = t.as_nanos() as f64 * 1.5;
                s.budget_kept = 100.0
                    * records.iter().filter(|r| r.adb[k].time_ns <= limit).count() as f64
                    / records.len().max(1) as f64;
            }
            writeln!(summary, "{}", summary_row(name, &c.label, &s, medians))?;
            // The table shows the headline configurations, the variants table the others
            // worth comparing; summary.csv has them all.
            if HEADLINE_LABELS.contains(&c.label.as_str()) {
                writeln!(table, "{}", table_row(&tris_note, &c.label, &s, medians))?;
            }
        }
    }
    summary.flush()?;
    println!("\n{table}");
    println!("{}", variants_table(configs, order, all)?);

    plot_error_vs_time(settings, configs, order, all)?;
    plot_error_vs_median(settings, configs, order, all)?;
    plot_error_vs_distance(settings, configs, order, all)?;
    plot_time_vs_distance(settings, configs, order, all)?;
    plot_reliability(settings, configs, order, all)?;
    Ok(())
}

/// The variants against the default, compactly: one row per variant, one column per mesh,
/// each cell the error (%), the Brier score and the median against the exact query's.
fn variants_table(
    configs: &[Config],
    order: &[String],
    all: &BTreeMap<String, Vec<PoseRecord>>,
) -> Result<String, std::fmt::Error> {
    let mut table = String::new();
    writeln!(
        table,
        "variants (each cell: error % · Brier · median × exact):\n\n| config | {} |",
        order.join(" | ")
    )?;
    writeln!(table, "|---|{}", "---:|".repeat(order.len()))?;
    let exact_medians: Vec<f64> = order
        .iter()
        .map(|name| stats(&all[name], |r| r.exact).median_us)
        .collect();
    let rows = configs.iter().enumerate().filter(|(_, c)| {
        c.label == DEFAULT_LABEL
            || (c.family == "estimator" && !HEADLINE_LABELS.contains(&c.label.as_str()))
            || c.label == NODE_BUDGET_100_LABEL
    });
    for (k, c) in rows {
        write!(table, "| {} |", c.label)?;
        for (name, exact_median) in order.iter().zip(&exact_medians) {
            let s = stats(&all[name], |r| r.adb[k]);
            write!(
                table,
                " {:.1} · {:.3} · {:.2}× |",
                s.error,
                s.brier,
                s.median_us / exact_median
            )?;
        }
        writeln!(table)?;
    }
    Ok(table)
}

/// The best median a traversal that answers "collision" from a triangle test could reach by its
/// order alone: on colliding poses the node pairs of [`oracle_descent_pairs`] (fewer than any
/// such traversal visits) at the exact query's lowest time per node pair, non-colliding poses
/// as fast as the faster of the measured exact and default queries.
struct OracleBound {
    /// Colliding poses.
    colliding: usize,
    /// Median oracle node pairs over them.
    median_pairs: f64,
    /// The time per node pair charged (ns): the lower of the exact query's on colliding and on
    /// non-colliding poses, so the bound is on the oracle's side.
    ns_per_pair: f64,
    /// Median oracle time over the colliding poses (µs): its node pairs at `ns_per_pair`.
    colliding_median_us: f64,
    /// Median over all poses (µs), a non-colliding pose taking the faster of the exact and the
    /// default queries' measured times.
    median_us: f64,
}

/// Total time over total node pairs of some answers (ns; 0 without node pairs).
fn ns_per_node_pair<'a>(answers: impl Iterator<Item = &'a Answer> + Clone) -> f64 {
    let nodes: f64 = answers.clone().map(|a| a.nodes as f64).sum();
    if nodes > 0.0 {
        answers.map(|a| a.time_ns).sum::<f64>() / nodes
    } else {
        0.0
    }
}

/// The oracle bound of one mesh's poses (`default`: the default configuration's index), or
/// `None` without colliding poses.
fn oracle_bound(records: &[PoseRecord], default: usize) -> Option<OracleBound> {
    let exact_rate = |colliding: bool| {
        ns_per_node_pair(
            records
                .iter()
                .filter(move |r| r.exact.collides == colliding)
                .map(|r| &r.exact),
        )
    };
    let ns_per_pair = [exact_rate(true), exact_rate(false)]
        .into_iter()
        .filter(|&r| r > 0.0)
        .fold(f64::INFINITY, f64::min);
    let mut pairs: Vec<f64> = records
        .iter()
        .filter_map(|r| r.oracle_pairs.map(|n| n as f64))
        .collect();
    if pairs.is_empty() || !ns_per_pair.is_finite() {
        return None;
    }
    let mut colliding_us: Vec<f64> = pairs.iter().map(|n| n * ns_per_pair / 1e3).collect();
    let mut all_us: Vec<f64> = records
        .iter()
        .map(|r| oracle_pose_us(r, ns_per_pair, default))
        .collect();
    Some(OracleBound {
        colliding: pairs.len(),
        median_pairs: median(&mut pairs),
        ns_per_pair,
        colliding_median_us: median(&mut colliding_us),
        median_us: median(&mut all_us),
    })
}

/// One pose's time under the oracle bound (µs): a colliding pose's oracle node pairs at
/// `ns_per_pair`, a non-colliding pose the faster of the exact and the default (`default`)
/// queries' measured times.
fn oracle_pose_us(r: &PoseRecord, ns_per_pair: f64, default: usize) -> f64 {
    match r.oracle_pairs {
        Some(n) => n as f64 * ns_per_pair / 1e3,
        None => r.exact.time_ns.min(r.adb[default].time_ns) / 1e3,
    }
}

/// The ADB targets for the default configuration and the 20 µs budget, per mesh, where the
/// time of the exact and the default queries goes on colliding and non-colliding poses, and
/// the oracle bound (both in `outcomes.csv`).
fn write_targets(
    settings: &Settings,
    configs: &[Config],
    order: &[String],
    all: &BTreeMap<String, Vec<PoseRecord>>,
    triangles: &BTreeMap<String, usize>,
) -> Result<(), Box<dyn std::error::Error>> {
    let index = |label: &str| configs.iter().position(|c| c.label == label);
    let (Some(default), Some(budget)) = (index(DEFAULT_LABEL), index(BUDGET_20_LABEL)) else {
        return Ok(());
    };
    let mark = |ok: bool| if ok { "met" } else { "NOT met" };
    let bounds: BTreeMap<&String, OracleBound> = order
        .iter()
        .filter_map(|name| Some((name, oracle_bound(&all[name], default)?)))
        .collect();
    // Each mesh's exact median, which every ratio below is against.
    let exact_medians: BTreeMap<&String, f64> = order
        .iter()
        .map(|name| (name, stats(&all[name], |r| r.exact).median_us))
        .collect();
    println!(
        "targets (p_min 0.99, k_min 10: error ≤ {TARGET_ERROR} %, ≤ {TARGET_NEAR_ERROR} % near \
         contact, median ≤ {TARGET_RATIO}× exact from {TARGET_RATIO_TRIANGLES} triangles; best \
         exact median ≤ {TARGET_BEST_EXACT_RATIO}× exact; 20 µs budget: error ≤ \
         {TARGET_BUDGET_ERROR} %, Brier ≤ {TARGET_BUDGET_BRIER}, p99 ≤ {TARGET_BUDGET_P99}× the \
         budget):"
    );
    for name in order {
        let records = &all[name];
        let tris = triangles[name];
        let exact_median = exact_medians[name];
        let d = stats(records, |r| r.adb[default]);
        let b = stats(records, |r| r.adb[budget]);
        let ratio = d.median_us / exact_median;
        let best_ratio = stats(records, |r| r.best_exact).median_us / exact_median;
        let bound = bounds.get(name).map_or(String::new(), |o| {
            format!(", oracle bound {:.2}×", o.median_us / exact_median)
        }) + &format!("; {:.2}× the best exact median", ratio / best_ratio);
        let ratio_note = if tris >= TARGET_RATIO_TRIANGLES {
            format!("{ratio:.2}× exact ({}{bound})", mark(ratio <= TARGET_RATIO))
        } else {
            format!(
                "{ratio:.2}× exact (not targeted below {TARGET_RATIO_TRIANGLES} triangles{bound})"
            )
        };
        println!(
            "  {name} ({tris} triangles): default error {:.1} % ({}), near {:.1} % ({}), {ratio_note}; \
             best exact {best_ratio:.2}× exact ({}); 20 µs: error {:.1} % ({}), Brier {:.3} ({}), \
             p99 {:.1} µs ({})",
            d.error,
            mark(d.error <= TARGET_ERROR),
            d.near_error,
            mark(d.near_error <= TARGET_NEAR_ERROR),
            mark(best_ratio <= TARGET_BEST_EXACT_RATIO),
            b.error,
            mark(b.error <= TARGET_BUDGET_ERROR),
            b.brier,
            mark(b.brier <= TARGET_BUDGET_BRIER),
            b.p99_us,
            mark(b.p99_us <= TARGET_BUDGET_P99 * BUDGET_20_US),
        );
    }

    // Why the papers' rule answers as it does: on the colliding poses, how many node pairs
    // reached p_min (it needs k_min of them) and how probable the most probable pair was.
    if let Some(paper) = index(PAPER_LABEL) {
        let p_min = configs[paper].query.p_min;
        let k_min = configs[paper].query.k_min;
        println!(
            "{PAPER_LABEL} on colliding poses (it says \"collision\" once {k_min} node pairs reach \
             p ≥ {p_min}): poses with a pair at p_min, median pairs found, median highest pair \
             probability:"
        );
        for name in order {
            let colliding: Vec<Answer> = all[name]
                .iter()
                .filter(|r| r.exact.collides)
                .map(|r| r.adb[paper])
                .collect();
            if colliding.is_empty() {
                continue;
            }
            let at_p_min = colliding.iter().filter(|a| a.max_pair >= p_min).count();
            let mut found: Vec<f64> = colliding.iter().map(|a| f64::from(a.pairs_found)).collect();
            let mut highest: Vec<f64> = colliding.iter().map(|a| a.max_pair).collect();
            println!(
                "  {name}: {} of {} colliding poses have a pair at p_min; {:.0} pairs found, \
                 highest {:.3} (medians); {} answered \"collision\"",
                at_p_min,
                colliding.len(),
                median(&mut found),
                median(&mut highest),
                colliding.iter().filter(|a| a.collides).count(),
            );
        }
    }

    // Where the time goes, by the exact answer.
    let mut csv = create_csv(
        settings,
        "outcomes.csv",
        "mesh,method,outcome,poses,median_us,median_node_pairs,ns_per_node_pair",
    )?;
    println!(
        "by outcome (median time, median node pairs, time per node pair over all poses of the outcome):"
    );
    for name in order {
        let mut line = format!("  {name}:");
        for (method, pick) in [("exact", None), (DEFAULT_LABEL, Some(default))] {
            for (outcome, colliding) in [("colliding", true), ("non-colliding", false)] {
                let answers: Vec<Answer> = all[name]
                    .iter()
                    .filter(|r| r.exact.collides == colliding)
                    .map(|r| pick.map_or(r.exact, |k| r.adb[k]))
                    .collect();
                if answers.is_empty() {
                    continue;
                }
                let mut times: Vec<f64> = answers.iter().map(|a| a.time_ns / 1e3).collect();
                let mut pairs: Vec<f64> = answers.iter().map(|a| a.nodes as f64).collect();
                let per_pair = ns_per_node_pair(answers.iter());
                let (t, n) = (median(&mut times), median(&mut pairs));
                writeln!(
                    csv,
                    "{name},{method},{outcome},{},{t:.3},{n},{per_pair:.1}",
                    answers.len()
                )?;
                let short = if pick.is_none() { "exact" } else { "default" };
                write!(
                    line,
                    " {short} {outcome} {t:.1} µs, {n:.0} pairs, {per_pair:.0} ns/pair;"
                )?;
            }
        }
        println!("{}", line.trim_end_matches(';'));
    }
    println!(
        "oracle bound (colliding poses: a descent straight to the nearest intersecting triangle \
         pair, at the lower of the exact query's times per node pair; non-colliding poses: the \
         faster of the exact and default queries):"
    );
    for name in order {
        let Some(o) = bounds.get(name) else {
            continue;
        };
        writeln!(
            csv,
            "{name},oracle descent,colliding,{},{:.3},{},{:.1}",
            o.colliding, o.colliding_median_us, o.median_pairs, o.ns_per_pair
        )?;
        println!(
            "  {name}: {:.0} node pairs on colliding poses ({:.1} µs at {:.0} ns/pair); \
             median over all poses {:.1} µs = {:.2}× exact",
            o.median_pairs,
            o.colliding_median_us,
            o.ns_per_pair,
            o.median_us,
            o.median_us / exact_medians[name]
        );
    }
    csv.flush()?;
    println!(
        "poses answered within {TARGET_RATIO}× of the exact median (a median of {TARGET_RATIO}× \
         needs half of them; the oracle as in its bound):"
    );
    for name in order {
        let records = &all[name];
        let limit_us = TARGET_RATIO * exact_medians[name];
        let within = |time_us: &dyn Fn(&PoseRecord) -> f64| {
            records.iter().filter(|r| time_us(r) <= limit_us).count()
        };
        let oracle = bounds.get(name).map_or(String::new(), |o| {
            format!(
                ", oracle {}",
                within(&|r| oracle_pose_us(r, o.ns_per_pair, default))
            )
        });
        println!(
            "  {name}: within {limit_us:.2} µs: exact {}, default {}{oracle} of {} (half: {})",
            within(&|r| r.exact.time_ns / 1e3),
            within(&|r| r.adb[default].time_ns / 1e3),
            records.len(),
            records.len().div_ceil(2)
        );
    }
    print_price_of_target_ratio(configs, order, all, triangles, &exact_medians);
    println!(
        "wrote results.csv, summary.csv, outcomes.csv, time_vs_distance.csv, error_vs_time.svg, \
         error_vs_median.svg, error_vs_distance.svg, time_vs_distance.svg, reliability.svg to {}",
        settings.out.display()
    );
    Ok(())
}

/// What answering at the target's median costs: on each mesh the target is about, the largest
/// node budget of the sweep whose median is within [`TARGET_RATIO`]× the exact median, and its
/// error (a budget-cut answer is the traversal's best estimate).
fn print_price_of_target_ratio(
    configs: &[Config],
    order: &[String],
    all: &BTreeMap<String, Vec<PoseRecord>>,
    triangles: &BTreeMap<String, usize>,
    exact_medians: &BTreeMap<&String, f64>,
) {
    // (configuration index, node pairs) of the node-budget sweep, ascending.
    let budgets: Vec<(usize, u64)> = configs
        .iter()
        .enumerate()
        .filter_map(|(k, c)| match c.query.budget {
            Budget::NodePairs(n) if c.family == "node budget" => Some((k, n)),
            _ => None,
        })
        .collect();
    if budgets.is_empty() {
        return;
    }
    println!(
        "the price of a median within {TARGET_RATIO}× exact (the largest node budget that reaches \
         it; answers cut by the budget are the best estimate so far):"
    );
    for name in order
        .iter()
        .filter(|n| triangles[*n] >= TARGET_RATIO_TRIANGLES)
    {
        let records = &all[name];
        let exact_median = exact_medians[name];
        // Ascending budgets: the last that reaches the ratio is the most accurate that does.
        let reaching = budgets
            .iter()
            .rev()
            .map(|&(k, n)| (n, stats(records, |r| r.adb[k])))
            .find(|(_, s)| s.median_us <= TARGET_RATIO * exact_median);
        match reaching {
            Some((n, s)) => println!(
                "  {name}: {} node pairs: median {:.2}× exact, error {:.1} % (false positives \
                 {:.1} %, false negatives {:.1} %), near contact {:.1} %",
                n,
                s.median_us / exact_median,
                s.error,
                s.false_pos,
                s.false_neg,
                s.near_error
            ),
            None => println!("  {name}: no node budget of the sweep reaches it"),
        }
    }
}

/// Error against median time, one curve per mesh: the node budgets ascending, then no budget;
/// the time as a fraction of the mesh's exact median, with the target's ratio and error marked.
fn plot_error_vs_median(
    settings: &Settings,
    configs: &[Config],
    order: &[String],
    all: &BTreeMap<String, Vec<PoseRecord>>,
) -> Result<(), Box<dyn std::error::Error>> {
    let path = settings.out.join("error_vs_median.svg");
    let root = SVGBackend::new(&path, (900, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let swept: Vec<usize> = configs
        .iter()
        .enumerate()
        .filter(|(_, c)| c.family == "node budget")
        .chain(
            configs
                .iter()
                .enumerate()
                .filter(|(_, c)| c.label == DEFAULT_LABEL),
        )
        .map(|(k, _)| k)
        .collect();
    let (mut rmax, mut emax) = (1.0f64, 5.0f64);
    let mut curves = Vec::new();
    for name in order {
        let records = &all[name];
        let exact_median = stats(records, |r| r.exact).median_us;
        let pts: Vec<(f64, f64)> = swept
            .iter()
            .map(|&k| {
                let s = stats(records, |r| r.adb[k]);
                (s.median_us / exact_median, s.error)
            })
            .filter(|(ratio, _)| ratio.is_finite() && *ratio > 0.0)
            .collect();
        for &(r, e) in &pts {
            rmax = rmax.max(r);
            emax = emax.max(e);
        }
        curves.push((name.clone(), pts));
    }
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "Calibrated ADB: error vs median time, node budgets {}-{} then none",
                NODE_BUDGETS[0],
                NODE_BUDGETS[NODE_BUDGETS.len() - 1]
            ),
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0f64..rmax * 1.1, 0.0f64..emax * 1.1)?;
    chart
        .configure_mesh()
        .x_desc("median query time (× the exact query's; dashed: the 0.25× target)")
        .y_desc("error (%; dashed: the 2 % target)")
        .x_label_formatter(&|v| format!("{v:.2}"))
        .light_line_style(TRANSPARENT)
        .draw()?;
    let dashed = BLACK.mix(0.5).stroke_width(1);
    chart.draw_series(DashedLineSeries::new(
        [(TARGET_RATIO, 0.0), (TARGET_RATIO, emax * 1.1)],
        6,
        4,
        dashed,
    ))?;
    chart.draw_series(DashedLineSeries::new(
        [(0.0, TARGET_ERROR), (rmax * 1.1, TARGET_ERROR)],
        6,
        4,
        dashed,
    ))?;
    draw_mesh_curves(&mut chart, curves, SeriesLabelPosition::UpperRight)?;
    root.present()?;
    Ok(())
}

fn palette(i: usize) -> RGBColor {
    const C: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(23, 190, 207),
    ];
    C[i % C.len()]
}

/// Error % against median query time: one curve per mesh over the p_min/k_min and time-budget
/// sweeps, the exact query as a point at 0 % error.
fn plot_error_vs_time(
    settings: &Settings,
    configs: &[Config],
    order: &[String],
    all: &BTreeMap<String, Vec<PoseRecord>>,
) -> Result<(), Box<dyn std::error::Error>> {
    let path = settings.out.join("error_vs_time.svg");
    let root = SVGBackend::new(&path, (900, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut curves = Vec::new();
    let (mut tmin, mut tmax, mut emax) = (f64::INFINITY, 1.0f64, 5.0f64);
    for name in order {
        let records = &all[name];
        let exact = stats(records, |r| r.exact);
        // In sweep order: the time budgets ascending, then no budget.
        let budgets = configs
            .iter()
            .enumerate()
            .filter(|(_, c)| c.family == "time budget");
        let unbudgeted = configs
            .iter()
            .enumerate()
            .filter(|(_, c)| c.label == DEFAULT_LABEL);
        let pts: Vec<(f64, f64)> = budgets
            .chain(unbudgeted)
            .map(|(k, _)| {
                let s = stats(records, |r| r.adb[k]);
                (s.p99_us, s.error)
            })
            .collect();
        for &(t, e) in pts.iter().chain([(exact.p99_us, 0.0)].iter()) {
            tmin = tmin.min(t);
            tmax = tmax.max(t);
            emax = emax.max(e);
        }
        curves.push((name.clone(), pts, exact.p99_us));
    }
    let tmin = if tmin.is_finite() { tmin * 0.8 } else { 0.5 };
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Calibrated ADB: error vs p99 time, time budgets 5-100 µs then none (▲ exact)",
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d((tmin..tmax * 1.3).log_scale(), 0.0f64..emax * 1.1)?;
    chart
        .configure_mesh()
        .x_desc("p99 query time (µs, log): what a frame must reserve per query")
        .y_desc("error (%)")
        .x_label_formatter(&|v| tick_label(*v))
        .light_line_style(TRANSPARENT)
        .draw()?;
    for (i, (name, pts, exact_us)) in curves.into_iter().enumerate() {
        let color = palette(i);
        draw_curve(&mut chart, &pts, name, color, 3)?;
        chart.draw_series(std::iter::once(TriangleMarker::new(
            (exact_us, 0.0),
            6,
            color.filled(),
        )))?;
    }
    finish(&mut chart, &root, SeriesLabelPosition::UpperRight)
}

/// A log axis's tick: whole numbers from 10 up, one decimal below (so no two ticks read alike).
fn tick_label(v: f64) -> String {
    if v >= 10.0 {
        format!("{v:.0}")
    } else {
        format!("{v:.1}")
    }
}

/// Error % against the offset from first contact: the default configuration (left) and the
/// 20 µs budget (right), one curve per mesh.
fn plot_error_vs_distance(
    settings: &Settings,
    configs: &[Config],
    order: &[String],
    all: &BTreeMap<String, Vec<PoseRecord>>,
) -> Result<(), Box<dyn std::error::Error>> {
    let path = settings.out.join("error_vs_distance.svg");
    let panels = two_panels(&path, "ADB error vs distance from first contact")?;
    // Both panels share the error axis, so the two configurations compare at a glance.
    let mut panel_curves = Vec::new();
    let mut emax = 5.0f64;
    for label in [DEFAULT_LABEL, BUDGET_20_LABEL] {
        let k = configs
            .iter()
            .position(|c| c.label == label)
            .expect("config");
        let mut curves = Vec::new();
        for name in order {
            let mut bins = [(0usize, 0usize); DISTANCE_BINS];
            for r in &all[name] {
                let b = distance_bin(r.offset);
                bins[b].0 += 1;
                bins[b].1 += usize::from(r.adb[k].collides != r.exact.collides);
            }
            let pts: Vec<(f64, f64)> = bins
                .iter()
                .enumerate()
                .filter(|(_, b)| b.0 > 0)
                .map(|(i, b)| (distance_bin_center(i), 100.0 * b.1 as f64 / b.0 as f64))
                .collect();
            emax = emax.max(pts.iter().map(|p| p.1).fold(0.0, f64::max));
            curves.push((name.clone(), pts));
        }
        panel_curves.push((label, curves));
    }
    for (area, (label, curves)) in panels.iter().zip(panel_curves) {
        let mut chart = ChartBuilder::on(area)
            .caption(label, ("sans-serif", 16))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(
                f64::from(-spread())..f64::from(spread()),
                0.0f64..emax * 1.1,
            )?;
        chart
            .configure_mesh()
            .x_desc(OFFSET_AXIS)
            .y_desc("error (%)")
            .x_label_formatter(&offset_tick)
            .light_line_style(TRANSPARENT)
            .draw()?;
        draw_mesh_curves(&mut chart, curves, SeriesLabelPosition::UpperLeft)?;
    }
    panels[0].present()?;
    Ok(())
}

/// Median query time against the offset from first contact, for the exact query (left) and
/// the default configuration (right), one curve per mesh on a shared log axis; the same medians,
/// with the median node pairs, in `time_vs_distance.csv`.
fn plot_time_vs_distance(
    settings: &Settings,
    configs: &[Config],
    order: &[String],
    all: &BTreeMap<String, Vec<PoseRecord>>,
) -> Result<(), Box<dyn std::error::Error>> {
    let default = configs
        .iter()
        .position(|c| c.label == DEFAULT_LABEL)
        .expect("config");
    let mut csv = create_csv(
        settings,
        "time_vs_distance.csv",
        "mesh,method,offset_from,offset_to,poses,median_us,median_node_pairs",
    )?;
    let mut panel_curves = Vec::new();
    let (mut tmin, mut tmax) = (f64::INFINITY, 1.0f64);
    for (method, pick) in [("exact", None), (DEFAULT_LABEL, Some(default))] {
        let mut curves = Vec::new();
        for name in order {
            let mut bins: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); DISTANCE_BINS];
            for r in &all[name] {
                let a = pick.map_or(r.exact, |k| r.adb[k]);
                let bin = &mut bins[distance_bin(r.offset)];
                bin.0.push(a.time_ns / 1e3);
                bin.1.push(a.nodes as f64);
            }
            let mut pts = Vec::new();
            for (i, (times, pairs)) in bins.iter_mut().enumerate() {
                if times.is_empty() {
                    continue;
                }
                let (t, n) = (median(times), median(pairs));
                let from = -spread() + distance_bin_width() * i as f32;
                writeln!(
                    csv,
                    "{name},{method},{from:.3},{:.3},{},{t:.3},{n}",
                    from + distance_bin_width(),
                    times.len()
                )?;
                tmin = tmin.min(t);
                tmax = tmax.max(t);
                pts.push((distance_bin_center(i), t));
            }
            curves.push((name.clone(), pts));
        }
        panel_curves.push((method, curves));
    }
    csv.flush()?;
    let tmin = if tmin.is_finite() { tmin * 0.8 } else { 0.1 };
    let path = settings.out.join("time_vs_distance.svg");
    let panels = two_panels(&path, "Median query time vs distance from first contact")?;
    // Both panels share the time axis, so the two queries compare at a glance.
    for (area, (method, curves)) in panels.iter().zip(panel_curves) {
        let caption = if method == "exact" {
            "exact query".to_string()
        } else {
            format!("default ADB query ({method})")
        };
        let mut chart = ChartBuilder::on(area)
            .caption(caption, ("sans-serif", 16))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(
                f64::from(-spread())..f64::from(spread()),
                (tmin..tmax * 1.3).log_scale(),
            )?;
        chart
            .configure_mesh()
            .x_desc(OFFSET_AXIS)
            .y_desc("median query time (µs, log)")
            .x_label_formatter(&offset_tick)
            .y_label_formatter(&|v| tick_label(*v))
            .light_line_style(TRANSPARENT)
            .draw()?;
        draw_mesh_curves(&mut chart, curves, SeriesLabelPosition::UpperRight)?;
    }
    panels[0].present()?;
    Ok(())
}

/// Reliability curve: observed collision frequency against reported probability (10 bins,
/// each point at its mean reported probability, with its number of answers), over all meshes,
/// for the default and the 5 µs and 20 µs budgets.
fn plot_reliability(
    settings: &Settings,
    configs: &[Config],
    order: &[String],
    all: &BTreeMap<String, Vec<PoseRecord>>,
) -> Result<(), Box<dyn std::error::Error>> {
    let path = settings.out.join("reliability.svg");
    let root = SVGBackend::new(&path, (700, 620)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Reliability of the reported probability",
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0f64..1.0, 0.0f64..1.0)?;
    chart
        .configure_mesh()
        .x_desc("reported probability")
        .y_desc("observed collision frequency")
        .light_line_style(TRANSPARENT)
        .draw()?;
    chart
        .draw_series(DashedLineSeries::new(
            vec![(0.0, 0.0), (1.0, 1.0)],
            6,
            4,
            BLACK.mix(0.5).stroke_width(1),
        ))?
        .label("perfectly calibrated")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.mix(0.5)));
    println!("reliability (all meshes): reported probability bin -> observed frequency (queries)");
    // Plotted: the configurations whose probability decides (the papers' rule ignores it, so
    // its line is printed only).
    for (i, label) in [DEFAULT_LABEL, BUDGET_5_LABEL, BUDGET_20_LABEL, PAPER_LABEL]
        .into_iter()
        .enumerate()
    {
        let k = configs
            .iter()
            .position(|c| c.label == label)
            .expect("config");
        let mut bins: reliability::Bins = Default::default();
        let mut brier = (0.0, 0usize);
        for name in order {
            for r in &all[name] {
                let p = r.adb[k].probability;
                reliability::add(&mut bins, p, r.exact.collides);
                brier.0 += (p - f64::from(u8::from(r.exact.collides))).powi(2);
                brier.1 += 1;
            }
        }
        let pts = reliability::points(&bins);
        println!(
            "  {label}: Brier {:.4}; {}",
            brier.0 / brier.1.max(1) as f64,
            reliability::line(&bins)
        );
        if label == PAPER_LABEL {
            continue;
        }
        let name = format!("{label} (Brier {:.3})", brier.0 / brier.1.max(1) as f64);
        draw_curve(&mut chart, &pts, name, palette(i), 4)?;
        // How many answers each point stands for, beside it (inside the frame).
        let counts = bins.iter().filter(|b| b.0 > 0).zip(&pts);
        chart.draw_series(counts.map(|(b, &(x, y))| {
            let x = if x > 0.9 { x - 0.09 } else { x + 0.015 };
            let y = (y + 0.01 - 0.045 * i as f64).clamp(0.02, 0.97);
            Text::new(
                format!("{}", b.0),
                (x, y),
                ("sans-serif", 11).into_font().color(&palette(i)),
            )
        }))?;
    }
    finish(&mut chart, &root, SeriesLabelPosition::UpperLeft)
}

/// A figure of two panels side by side under `title`, written to `path` once presented (any
/// panel presents the whole figure).
fn two_panels<'a>(
    path: &'a std::path::Path,
    title: &str,
) -> Result<Vec<DrawingArea<SVGBackend<'a>, Shift>>, Box<dyn std::error::Error>> {
    let root = SVGBackend::new(path, (1200, 560)).into_drawing_area();
    root.fill(&WHITE)?;
    let root = root.titled(title, ("sans-serif", 20))?;
    Ok(root.split_evenly((1, 2)))
}

/// The x axis of the plots against distance from first contact.
const OFFSET_AXIS: &str = "offset from first contact (fraction of size; < 0 overlapping)";

/// A tick of [`OFFSET_AXIS`]: the middle tick lands a rounding error off 0, so no "-0.00".
fn offset_tick(v: &f64) -> String {
    let v = if v.abs() < 1e-6 { 0.0 } else { *v };
    if spread() < 0.1 {
        format!("{v:.3}")
    } else {
        format!("{v:.2}")
    }
}

/// One curve per mesh (in palette order), then the legend at `position`.
fn draw_mesh_curves<'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, Y>>,
    curves: Vec<(String, Vec<(f64, f64)>)>,
    position: SeriesLabelPosition,
) -> Result<(), Box<dyn std::error::Error>>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    for (i, (name, pts)) in curves.into_iter().enumerate() {
        draw_curve(chart, &pts, name, palette(i), 3)?;
    }
    legend(chart, position)
}

/// One labelled curve with its points marked.
fn draw_curve<'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, Y>>,
    pts: &[(f64, f64)],
    label: String,
    color: RGBColor,
    radius: u32,
) -> Result<(), Box<dyn std::error::Error>>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    chart
        .draw_series(LineSeries::new(pts.to_vec(), color.stroke_width(2)))?
        .label(label)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color.stroke_width(2)));
    chart.draw_series(pts.iter().map(|&p| Circle::new(p, radius, color.filled())))?;
    Ok(())
}

/// The legend box (where the curves leave room), then the file.
fn finish<'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, Y>>,
    root: &DrawingArea<SVGBackend<'a>, Shift>,
    position: SeriesLabelPosition,
) -> Result<(), Box<dyn std::error::Error>>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    legend(chart, position)?;
    root.present()?;
    Ok(())
}

/// The legend box of a chart, at `position`.
fn legend<'a, X, Y>(
    chart: &mut ChartContext<'a, SVGBackend<'a>, Cartesian2d<X, Y>>,
    position: SeriesLabelPosition,
) -> Result<(), Box<dyn std::error::Error>>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}
