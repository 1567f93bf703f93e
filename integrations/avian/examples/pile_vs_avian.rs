//! The main crate's pile (rigid meshes falling into a box) run by this crate without a budget
//! and by avian3d 0.8, side by side on the same scene: the same triangles (trimesh colliders
//! everywhere), box, seeded spawn and initial velocities, rotations locked, 60 Hz, 2 threads,
//! headless. Prints p50, p99, mean and max of each side's per-step collision time over the
//! falling phase (see `stochastic_collision_avian::pile`).
//!
//! `cargo run --release --example pile_vs_avian -- [--bodies N[,N...]] [--steps N] [--seed S]
//! [--no-suzanne] [--no-sleep] [--out PATH]` (from `integrations/avian`; add `--ignore-rust-version` on rustc older than
//! bevy's 1.97.1). `docs/plugin/avian_pile.sh` runs it at 1,000 and 4,000 bodies. Suzanne is
//! read from `STOCHASTIC_COLLISION_MESHES` or `shared/assets/meshes` beside the main crate;
//! `--no-suzanne` leaves it out (three kinds of body). `--no-sleep` keeps every body awake on
//! both sides (the main crate's pile lets them sleep).
use std::fmt::Write as _;
use std::io::Write as _;

use stochastic_collision_avian::pile::{
    Comparison, DEFAULT_BODIES, DEFAULT_STEPS, MEASURES, PileScene,
};

const USAGE: &str = "usage: pile_vs_avian [--bodies N[,N...] (default 1000)] [--steps N (default 120)] \
                     [--seed S (default 1)] [--no-suzanne] [--no-sleep] [--out PATH]";

struct Args {
    bodies: Vec<usize>,
    steps: usize,
    seed: u64,
    suzanne: bool,
    sleep: bool,
    out: Option<String>,
}

fn parse() -> Result<Args, String> {
    let mut args = Args {
        bodies: vec![DEFAULT_BODIES],
        steps: DEFAULT_STEPS,
        seed: 1,
        suzanne: true,
        sleep: true,
        out: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        if flag == "-h" || flag == "--help" {
            return Err(String::new());
        }
        if flag == "--no-suzanne" || flag == "--no-sleep" {
            if flag == "--no-suzanne" {
                args.suzanne = false;
            } else {
                args.sleep = false;
            }
            continue;
        }
        let value = it.next().ok_or(format!("{flag} needs a value"))?;
        let number = |v: &str| {
            v.trim()
                .parse::<u64>()
                .map_err(|e| format!("{flag}: invalid number `{v}` ({e})"))
        };
        match flag.as_str() {
            "--bodies" => {
                args.bodies = value
                    .split(',')
                    .map(|v| number(v).map(|n| n as usize))
                    .collect::<Result<_, _>>()?;
                if args.bodies.contains(&0) {
                    return Err("--bodies: at least 1".to_owned());
                }
            }
            "--steps" => args.steps = number(&value)?.max(1) as usize,
            "--seed" => args.seed = number(&value)?,
            "--out" => args.out = Some(value),
            _ => return Err(format!("unknown flag {flag}")),
        }
    }
    Ok(args)
}

/// The machine's load average (1, 5 and 15 minutes), where there is one (Linux): other
/// processes on the machine slow both sides.
fn load_average() -> Option<String> {
    let text = std::fs::read_to_string("/proc/loadavg").ok()?;
    Some(
        text.split_whitespace()
            .take(3)
            .collect::<Vec<_>>()
            .join(" "),
    )
}

fn main() {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            if !e.is_empty() {
                eprintln!("{e}");
            }
            eprintln!("{USAGE}");
            std::process::exit(if e.is_empty() { 0 } else { 2 });
        }
    };
    let mut summary = String::new();
    let header = format!(
        "pile_vs_avian --bodies {} --steps {} --seed {}{}{}{}\n{MEASURES}\n",
        args.bodies
            .iter()
            .map(ToString::to_string)
            .collect::<Vec<_>>()
            .join(","),
        args.steps,
        args.seed,
        if args.suzanne { "" } else { " --no-suzanne" },
        if args.sleep { "" } else { " --no-sleep" },
        if cfg!(debug_assertions) {
            " (DEBUG BUILD: times are not representative)"
        } else {
            ""
        },
    );
    print!("{header}");
    summary.push_str(&header);
    if let Some(load) = load_average() {
        let line = format!("load average at the start (1, 5, 15 min): {load}\n");
        print!("{line}");
        summary.push_str(&line);
    }
    for &n in &args.bodies {
        let mut scene = PileScene::new(n, args.seed, args.suzanne);
        scene.sleep = args.sleep;
        let every = (args.steps / 4).max(1);
        let comparison = Comparison::run(&scene, args.steps, |step| {
            if step % every == 0 || step == args.steps {
                eprintln!("{n} bodies: step {step}/{}", args.steps);
            }
        });
        let mut text = comparison.to_string();
        if let Some(load) = load_average() {
            let _ = writeln!(text, "  load average at the end: {load}");
        }
        print!("{text}");
        let _ = std::io::stdout().flush();
        let _ = write!(summary, "{text}");
    }
    if let Some(path) = &args.out {
        if let Some(dir) = std::path::Path::new(path).parent() {
            let _ = std::fs::create_dir_all(dir);
        }
        match std::fs::write(path, &summary) {
            Ok(()) => eprintln!("summary written to {path}"),
            Err(e) => {
                eprintln!("cannot write {path}: {e}");
                std::process::exit(1);
            }
        }
    }
}
