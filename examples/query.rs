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
//! Modes: `exact` (BVH + exact triangle tests). `--solid` also counts a mesh inside a closed
//! other mesh as colliding. Bad input (missing or malformed file, NaN, short rows, unknown mode
//! or flag) exits with code 2 and one line on stderr naming the file and line.
use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use stochastic_collision::bvh::{CollisionMesh, ExactOptions, QueryWorkspace, intersects_with};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::TriMesh;
use stochastic_collision::poses::read_poses_csv;

const USAGE: &str =
    "usage: query --a A.obj --b B.obj --poses poses.csv --mode exact [--solid] [--out results.csv]";

/// The query modes; each parses its own flags.
enum Mode {
    Exact(ExactOptions),
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

fn parse_args(mut it: impl Iterator<Item = String>) -> Result<Args, String> {
    let (mut a, mut b, mut poses, mut out, mut mode) = (None, None, None, None, None);
    let mut solid = false;
    while let Some(flag) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .ok_or_else(|| format!("{name} needs a value; {USAGE}"))
        };
        match flag.as_str() {
            "--a" => a = Some(PathBuf::from(value("--a")?)),
            "--b" => b = Some(PathBuf::from(value("--b")?)),
            "--poses" => poses = Some(PathBuf::from(value("--poses")?)),
            "--out" => out = Some(PathBuf::from(value("--out")?)),
            "--mode" => mode = Some(value("--mode")?),
            "--solid" => solid = true,
            "-h" | "--help" => return Err(USAGE.to_string()),
            other => return Err(format!("unknown argument `{other}`; {USAGE}")),
        }
    }
    let missing = |name: &str| format!("missing {name}; {USAGE}");
    let mode = match mode.as_deref() {
        Some("exact") => Mode::Exact(ExactOptions { solid }),
        Some(other) => return Err(format!("unknown mode `{other}` (known: exact)")),
        None => return Err(missing("--mode")),
    };
    Ok(Args {
        a: a.ok_or_else(|| missing("--a"))?,
        b: b.ok_or_else(|| missing("--b"))?,
        poses: poses.ok_or_else(|| missing("--poses"))?,
        out,
        mode,
    })
}

fn run(args: Args) -> Result<(), String> {
    let load = |path: &PathBuf| TriMesh::from_obj(path).map_err(|e| e.to_string());
    let a = CollisionMesh::new(load(&args.a)?);
    let b = CollisionMesh::new(load(&args.b)?);
    let poses = read_poses_csv(&args.poses).map_err(|e| e.to_string())?;
    let mut ws = QueryWorkspace::new();
    let rows: Vec<Row> = poses
        .iter()
        .map(|pose_b| match &args.mode {
            Mode::Exact(options) => {
                let start = Instant::now();
                let outcome = intersects_with(&a, &Pose::IDENTITY, &b, pose_b, options, &mut ws);
                let time_ns = start.elapsed().as_nanos();
                Row {
                    collides: outcome.collides,
                    probability: if outcome.collides { 1.0 } else { 0.0 },
                    time_ns,
                    nodes_visited: outcome.node_pairs_visited,
                }
            }
        })
        .collect();
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
    match &args.out {
        Some(path) => {
            let mut file = std::fs::File::create(path)
                .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
            write(&mut std::io::BufWriter::new(&mut file))
                .map_err(|e| format!("cannot write {}: {e}", path.display()))
        }
        None => {
            write(&mut std::io::stdout().lock()).map_err(|e| format!("cannot write to stdout: {e}"))
        }
    }
}

fn main() -> ExitCode {
    match parse_args(std::env::args().skip(1)).and_then(run) {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
    }
}
