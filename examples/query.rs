//! Batch collision queries over poses: the crate's command-line contract.
//!
//! ```text
//! cargo run --release --example query -- --a A.obj --b B.obj --poses poses.csv \
//!     --mode exact [--solid] [--out results.csv]
//! ```
//!
//! `poses.csv` has the header `tx,ty,tz,qx,qy,qz,qw` and one pose of B in A's frame per line
//! (A stays at identity). The output CSV (to `--out`, else stdout) has the header
//! `index,collides,probability,time_ns,nodes_visited`: `collides` is 0/1, `probability` is the
//! confidence (1 or 0 in exact mode), `time_ns` times the query alone (trees are built before),
//! `nodes_visited` counts the node pairs whose boxes were tested.
//!
//! Modes:
//! - `exact` (BVH + exact triangle tests). `--solid` also counts a mesh inside a closed other
//!   mesh as colliding.
//! - `adb` (ADB-tree, time-critical): `[--p-min 0.99] [--k-min 10] [--collide-at 0.5]
//!   [--budget-us T | --budget-nodes N] [--leaves exact|estimated]
//!   [--decision evidence|confidence] [--order straddle|depth-first|evidence-first|best-first]
//!   [--estimator calibrated|paper|planarity] [--resolution 4]`; `probability` is the ADB
//!   confidence, `nodes_visited` the node pairs visited. `--leaves estimated` never tests a
//!   triangle (default: leaf pairs are tested exactly); `--decision evidence` stops as soon as
//!   the evidence found reaches `p_min`
//!   (`Decision::Evidence`; default `confidence`: waits for `k_min` pieces of evidence);
//!   `--order best-first` expands the most probable pair of the whole queue next (the papers'
//!   order), `evidence-first` the pairs that count as evidence best first, then the others depth
//!   first (`Order::EvidenceFirst`), `depth-first` the most promising child of the pair just
//!   expanded next (`Order::DepthFirst`); default `straddle`: depth first by how squarely the
//!   boxes straddle each other's surface, with exact leaves estimating only the pairs its
//!   evidence checks and its confidence need (`Order::Straddle`).
//!   `--collide-at C`: the confidence from which an answer the traversal did not settle says
//!   "collision" (`AdbQuery::collide_at`).
//!   `--estimator paper` is the papers' method as published: their decision rule (so no
//!   `--decision`), best-first order and estimated leaves unless `--order` or `--leaves` say
//!   otherwise.
//!
//! Bad input (missing or malformed file, NaN, short rows, unknown mode or flag, bad flag value,
//! a flag given twice) exits with code 2 and one line on stderr naming the file and line.
//! `--help` prints the usage to stdout. Building the trees of a large mesh (from 20 000
//! triangles) shows its progress on stderr; when `--a` and `--b` are the same file, it is
//! loaded and built once.
#[path = "support/cli.rs"]
mod cli;
#[path = "support/progress.rs"]
mod progress;

use std::ffi::OsString;
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, Instant};

use stochastic_collision::adb::{
    AdbBuildOptions, AdbQuery, AdbTree, AdbWorkspace, Budget, CalibratedEstimator, Decision, Order,
    PaperEstimator, PlanarityEstimator, adb_intersects,
};
use stochastic_collision::bvh::{CollisionMesh, ExactOptions, QueryWorkspace, intersects_with};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::TriMesh;
use stochastic_collision::poses::read_poses_csv;

use cli::{DECISIONS, ORDERS, parse_choice};

const USAGE: &str = "usage: query --a A.obj --b B.obj --poses poses.csv --mode exact|adb [--solid] \
[--p-min P] [--k-min K] [--collide-at C] [--budget-us T | --budget-nodes N] \
[--leaves exact|estimated] \
[--decision evidence|confidence] [--order straddle|depth-first|evidence-first|best-first] \
[--estimator calibrated|paper|planarity] [--resolution R] [--out results.csv]";

/// What `--help` prints after the usage.
const HELP: &str = "\
Collides mesh B, at each pose of poses.csv (header tx,ty,tz,qx,qy,qz,qw: B in A's frame), with
mesh A (at identity) and writes the CSV index,collides,probability,time_ns,nodes_visited to
--out, else to stdout.
  --mode exact      BVH and exact triangle tests (--solid: a mesh inside a closed other one
                    collides too)
  --mode adb        ADB-tree: --p-min (0.99) and --k-min (10) set the decision, --collide-at
                    (0.5) the confidence from which an unsettled answer is a collision,
                    --budget-us or --budget-nodes a budget per query, --leaves, --decision,
                    --order and --estimator the traversal, --resolution (4) the cells per axis
Bad input exits with code 2 and one line on stderr.";

/// Meshes from this many triangles show the progress of their build on stderr (smaller ones
/// build in well under a second).
const PROGRESS_MIN_TRIANGLES: usize = 20_000;

/// The query modes; each parses its own flags.
enum Mode {
    Exact(ExactOptions),
    Adb { query: AdbQuery, resolution: u32 },
}

/// What the command line asks for.
enum Command {
    Run(Box<Args>),
    Help,
}

struct Args {
    a: PathBuf,
    b: PathBuf,
    poses: PathBuf,
    out: Option<PathBuf>,
    mode: Mode,
}

/// One result row.
struct Row {
    collides: bool,
    probability: f64,
    time_ns: u128,
    nodes_visited: u64,
}

fn parse_args(mut it: impl Iterator<Item = OsString>) -> Result<Command, String> {
    let (mut a, mut b, mut poses, mut out, mut mode) = (None, None, None, None, None);
    let mut solid = false;
    let mut adb = AdbQuery::default();
    let mut resolution = AdbBuildOptions::default().resolution;
    let mut adb_flags: Vec<&'static str> = Vec::new();
    let mut budget_flags = 0;
    // Set after all flags are read, so that they win over `--estimator paper` in any order.
    let mut leaves: Option<bool> = None;
    let mut decision: Option<Decision> = None;
    let mut order: Option<Order> = None;
    // Every flag at most once (an unknown flag is refused the first time).
    let mut seen: Vec<String> = Vec::new();
    while let Some(flag) = it.next() {
        let flag = flag
            .into_string()
            .map_err(|f| format!("unknown argument `{}`; {USAGE}", f.to_string_lossy()))?;
        if seen.contains(&flag) {
            return Err(format!("{flag} given twice; give each flag at most once"));
        }
        seen.push(flag.clone());
        // Paths may be any OS string; other values must be text.
        let mut next = |name: &str| {
            it.next()
                .ok_or_else(|| format!("{name} needs a value; {USAGE}"))
        };
        let mut value = |name: &str| next(name).and_then(|v| text(v, name));
        match flag.as_str() {
            "--a" => a = Some(PathBuf::from(next("--a")?)),
            "--b" => b = Some(PathBuf::from(next("--b")?)),
            "--poses" => poses = Some(PathBuf::from(next("--poses")?)),
            "--out" => out = Some(PathBuf::from(next("--out")?)),
            "--mode" => mode = Some(value("--mode")?),
            "--solid" => solid = true,
            "--p-min" => {
                adb.p_min = parse_number(&value("--p-min")?, "--p-min", |p: f64| {
                    (0.0..=1.0).contains(&p)
                })?;
                adb_flags.push("--p-min");
            }
            "--collide-at" => {
                adb.collide_at =
                    parse_number(&value("--collide-at")?, "--collide-at", |c: f64| {
                        (0.0..=1.0).contains(&c)
                    })?;
                adb_flags.push("--collide-at");
            }
            "--k-min" => {
                adb.k_min = parse_number(&value("--k-min")?, "--k-min", |k: u32| k >= 1)?;
                adb_flags.push("--k-min");
            }
            "--budget-us" => {
                let text = value("--budget-us")?;
                adb.budget = Budget::Time(parse_budget_us(&text)?);
                budget_flags += 1;
                adb_flags.push("--budget-us");
            }
            "--budget-nodes" => {
                adb.budget = Budget::NodePairs(parse_number(
                    &value("--budget-nodes")?,
                    "--budget-nodes",
                    |n: u64| n >= 1,
                )?);
                budget_flags += 1;
                adb_flags.push("--budget-nodes");
            }
            "--leaves" => {
                leaves = Some(parse_choice(
                    &value("--leaves")?,
                    "--leaves",
                    &[("exact", true), ("estimated", false)],
                )?);
                adb_flags.push("--leaves");
            }
            "--decision" => {
                decision = Some(parse_choice(
                    &value("--decision")?,
                    "--decision",
                    DECISIONS,
                )?);
                adb_flags.push("--decision");
            }
            "--order" => {
                order = Some(parse_choice(&value("--order")?, "--order", ORDERS)?);
                adb_flags.push("--order");
            }
            "--estimator" => {
                adb.estimator = match value("--estimator")?.as_str() {
                    // The papers' method as published, decision rule, order and estimated
                    // leaves included (exact leaves, evidence first only if asked for).
                    "paper" => {
                        adb.decision = Decision::Paper;
                        adb.order = Order::BestFirst;
                        adb.exact_leaves = false;
                        Arc::new(PaperEstimator::default())
                    }
                    "planarity" => Arc::new(PlanarityEstimator::default()),
                    "calibrated" => Arc::new(CalibratedEstimator::default()),
                    other => {
                        return Err(format!(
                            "unknown estimator `{other}` (known: calibrated, paper, planarity)"
                        ));
                    }
                };
                adb_flags.push("--estimator");
            }
            "--resolution" => {
                resolution = parse_number(&value("--resolution")?, "--resolution", |r: u32| {
                    (1..=8).contains(&r)
                })?;
                adb_flags.push("--resolution");
            }
            "-h" | "--help" => return Ok(Command::Help),
            other => return Err(format!("unknown argument `{other}`; {USAGE}")),
        }
    }
    if budget_flags > 1 {
        return Err("give at most one of --budget-us and --budget-nodes".to_string());
    }
    if let Some(decision) = decision {
        if adb.decision == Decision::Paper {
            return Err(
                "--decision does not apply to --estimator paper (the papers' own rule)".into(),
            );
        }
        adb.decision = decision;
    }
    if let Some(exact) = leaves {
        adb.exact_leaves = exact;
    }
    if let Some(order) = order {
        adb.order = order;
    }
    let missing = |name: &str| format!("missing {name}; {USAGE}");
    let mode = match mode.as_deref() {
        Some("exact") => {
            if let Some(flag) = adb_flags.first() {
                return Err(format!("{flag} applies to --mode adb only"));
            }
            Mode::Exact(ExactOptions { solid })
        }
        Some("adb") => {
            if solid {
                return Err("--solid applies to --mode exact only".to_string());
            }
            Mode::Adb {
                query: adb,
                resolution,
            }
        }
        Some(other) => return Err(format!("unknown mode `{other}` (known: exact, adb)")),
        None => return Err(missing("--mode")),
    };
    Ok(Command::Run(Box::new(Args {
        a: a.ok_or_else(|| missing("--a"))?,
        b: b.ok_or_else(|| missing("--b"))?,
        poses: poses.ok_or_else(|| missing("--poses"))?,
        out,
        mode,
    })))
}

/// The time budget of `--budget-us`: finite, at least 1 ns (a value that would round to no
/// time at all is refused like 0) and within what a `Duration` holds.
fn parse_budget_us(text: &str) -> Result<Duration, String> {
    let invalid = || {
        format!("--budget-us: invalid value `{text}` (a number of microseconds, at least 0.001)")
    };
    let us: f64 = parse_number(text, "--budget-us", |t: f64| t >= 0.001 && t.is_finite())
        .map_err(|_| invalid())?;
    match Duration::try_from_secs_f64(us * 1e-6) {
        Ok(budget) if budget.is_zero() => Err(invalid()),
        Ok(budget) => Ok(budget),
        Err(_) => Err(format!(
            "--budget-us: invalid value `{text}` (too large for a duration)"
        )),
    }
}

/// A flag's value as text.
fn text(value: OsString, flag: &str) -> Result<String, String> {
    value
        .into_string()
        .map_err(|v| format!("{flag}: invalid value `{}`", v.to_string_lossy()))
}

/// Parses a flag's value and checks its range.
fn parse_number<T: std::str::FromStr + Copy>(
    text: &str,
    flag: &str,
    valid: impl Fn(T) -> bool,
) -> Result<T, String> {
    match text.parse::<T>() {
        Ok(v) if valid(v) => Ok(v),
        _ => Err(format!("{flag}: invalid value `{text}`")),
    }
}

/// Whether `a` and `b` name the same file (the same path, or the same file once resolved).
fn same_file(a: &Path, b: &Path) -> bool {
    a == b
        || matches!(
            (std::fs::canonicalize(a), std::fs::canonicalize(b)),
            (Ok(x), Ok(y)) if x == y
        )
}

/// How a path is named in progress lines: its file name.
fn display_name(path: &Path) -> String {
    path.file_name().map_or_else(
        || path.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

/// One build step of a large mesh shown on stderr (never stdout: the CSV may go there): a bar
/// redrawn in place when stderr is a terminal and the step reports progress, else the label
/// and then the time taken. [`Progress::finish`] always ends the line.
struct Progress {
    label: String,
    start: Instant,
    bar: bool,
    /// The largest count drawn so far (updates come from several build threads).
    shown: Mutex<usize>,
}

impl Progress {
    fn start(label: String, with_bar: bool) -> Self {
        let bar = with_bar && std::io::stderr().is_terminal();
        if bar {
            eprint!("\r  {label} {}", progress::bar(0, 1));
        } else {
            eprint!("  {label} ...");
        }
        Self {
            label,
            start: Instant::now(),
            bar,
            shown: Mutex::new(0),
        }
    }

    /// Redraws the bar about every 2 %; the last state is drawn by [`Progress::finish`].
    fn update(&self, done: usize, total: usize) {
        if !self.bar || done >= total {
            return;
        }
        let mut shown = self.shown.lock().unwrap_or_else(PoisonError::into_inner);
        if done < *shown + (total / 50).max(1) {
            return;
        }
        *shown = done;
        eprint!("\r  {} {}", self.label, progress::bar(done, total));
    }

    fn finish(self) {
        let seconds = self.start.elapsed().as_secs_f64();
        if self.bar {
            eprintln!("\r  {} {} {seconds:.2} s", self.label, progress::bar(1, 1));
        } else {
            eprintln!(" done in {seconds:.2} s");
        }
    }
}

/// The collision mesh (BVH) of `mesh`, loaded from `path`; shown on stderr if large.
fn collision_mesh(path: &Path, mesh: TriMesh) -> CollisionMesh {
    let triangles = mesh.triangle_count();
    if triangles < PROGRESS_MIN_TRIANGLES {
        return CollisionMesh::new(mesh);
    }
    let progress = Progress::start(
        format!("{}: BVH of {triangles} triangles", display_name(path)),
        false,
    );
    let cm = CollisionMesh::new(mesh);
    progress.finish();
    cm
}

/// The ADB-tree of `mesh`, loaded from `path`; the progress of its build (BVH included) shown
/// on stderr if large.
fn adb_tree(path: &Path, mesh: TriMesh, options: AdbBuildOptions) -> AdbTree {
    let triangles = mesh.triangle_count();
    if triangles < PROGRESS_MIN_TRIANGLES {
        return AdbTree::build_with(CollisionMesh::new(mesh), options);
    }
    let progress = Progress::start(
        format!("{}: ADB tree of {triangles} triangles", display_name(path)),
        true,
    );
    let tree = AdbTree::build_with_progress(CollisionMesh::new(mesh), options, &|p| {
        progress.update(p.nodes_done, p.nodes_total);
    });
    progress.finish();
    tree
}

fn run(args: Args) -> Result<(), String> {
    let load = |path: &PathBuf| TriMesh::from_obj(path).map_err(|e| e.to_string());
    // The same file for A and B is loaded and built once, and shared.
    let mesh_a = load(&args.a)?;
    let mesh_b = if same_file(&args.a, &args.b) {
        None
    } else {
        Some(load(&args.b)?)
    };
    let poses = read_poses_csv(&args.poses).map_err(|e| e.to_string())?;
    // Created before the (possibly long) build, so that an unwritable path fails at once.
    let cannot_write =
        |path: &PathBuf, e: std::io::Error| format!("cannot write {}: {e}", path.display());
    let out = match &args.out {
        Some(path) => Some((
            path,
            std::fs::File::create(path).map_err(|e| cannot_write(path, e))?,
        )),
        None => None,
    };
    let rows: Vec<Row> = match &args.mode {
        Mode::Exact(options) => {
            let a = collision_mesh(&args.a, mesh_a);
            let b_own = mesh_b.map(|mesh| collision_mesh(&args.b, mesh));
            let b = b_own.as_ref().unwrap_or(&a);
            let mut ws = QueryWorkspace::new();
            poses
                .iter()
                .map(|pose_b| {
                    let start = Instant::now();
                    let outcome = intersects_with(&a, &Pose::IDENTITY, b, pose_b, options, &mut ws);
                    let time_ns = start.elapsed().as_nanos();
                    Row {
                        collides: outcome.collides,
                        probability: if outcome.collides { 1.0 } else { 0.0 },
                        time_ns,
                        nodes_visited: outcome.node_pairs_visited,
                    }
                })
                .collect()
        }
        Mode::Adb { query, resolution } => {
            let options = AdbBuildOptions {
                resolution: *resolution,
                ..Default::default()
            };
            let a = adb_tree(&args.a, mesh_a, options);
            let b_own = mesh_b.map(|mesh| adb_tree(&args.b, mesh, options));
            let b = b_own.as_ref().unwrap_or(&a);
            let mut ws = AdbWorkspace::new();
            poses
                .iter()
                .map(|pose_b| {
                    let start = Instant::now();
                    let outcome = adb_intersects(&a, &Pose::IDENTITY, b, pose_b, query, &mut ws);
                    let time_ns = start.elapsed().as_nanos();
                    Row {
                        collides: outcome.collides,
                        probability: outcome.probability,
                        time_ns,
                        nodes_visited: outcome.node_pairs_visited,
                    }
                })
                .collect()
        }
    };
    let write = |out: &mut dyn Write| -> std::io::Result<()> {
        writeln!(out, "index,collides,probability,time_ns,nodes_visited")?;
        for (i, r) in rows.iter().enumerate() {
            writeln!(
                out,
                "{i},{},{},{},{}",
                u8::from(r.collides),
                r.probability,
                r.time_ns,
                r.nodes_visited
            )?;
        }
        out.flush()
    };
    match out {
        Some((path, mut file)) => {
            write(&mut std::io::BufWriter::new(&mut file)).map_err(|e| cannot_write(path, e))
        }
        None => {
            write(&mut std::io::stdout().lock()).map_err(|e| format!("cannot write to stdout: {e}"))
        }
    }
}

fn main() -> ExitCode {
    let result = parse_args(std::env::args_os().skip(1)).and_then(|command| match command {
        Command::Run(args) => run(*args),
        Command::Help => writeln!(std::io::stdout().lock(), "{USAGE}\n\n{HELP}")
            .map_err(|e| format!("cannot write to stdout: {e}")),
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
}
