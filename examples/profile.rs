//! Profiles a headless example world: per-stage timings against the frame budget, events,
//! and how often the budgeted answers agree with the exact query.
//!
//! ```text
//! cargo run --release --example profile -- --scene pile|cannonball|cloth|intestine \
//!     [--frames N] [--entities N] [--threads T] [--budget-us B] [--node-budget N] [--seed S] \
//!     [--adb-decision confidence|evidence] \
//!     [--adb-order straddle|depth-first|evidence-first|best-first] [--adb-interior on|off] \
//!     [--json out.json] [--svg out.svg] [--frames-csv out.csv]
//! ```
//!
//! Without `--budget-us` the scene's own budget applies (2000 µs; 30000 µs for the
//! intestine); `--budget-us 0` means no budget; `--node-budget N` replaces the time budget with a work
//! budget of N ADB node pairs per frame (deterministic: the same run for any thread count,
//! which is how to compare thread counts fairly). `--adb-decision` sets how the ADB queries
//! decide (`CollisionConfig::adb_decision`, default `confidence`), `--adb-order` in which order
//! they expand node pairs (`CollisionConfig::adb_order`, default `straddle`), `--adb-interior`
//! whether they try the interpenetration certificate first (`CollisionConfig::adb_interior`,
//! default `on`).
//!
//! `--frames-csv`: one row per frame (each stage's time in µs, the collision stages' time, the
//! pairs in the table, the pairs worked on in the frame).
//!
//! JSON fields: `scene`, `frames`, `threads`, `budget_us`, `stages` (by name: `mean_us`,
//! `p50_us`, `p99_us` over the frames the stage ran, `runs`), `collision_p99_us` (Prepare to
//! Report), `overrun_frames` (collision time above the budget), `events` (`started`, `ended`,
//! `contacts`), `events_deferred` (contacts left for a later frame by the response budget),
//! `events_lost` (written but never read by a reader that runs every other frame), `memory`
//! (resident MiB after a tenth of the run and at the end, and the growth), `work` (node pairs,
//! ADB pairs, pairs cut by their budget, answered from the last test, tested exactly,
//! `confirmed_pairs`: exact pairs past their deadline answered exactly from memory, cached,
//! tested), `agreement_with_exact` (fraction of sampled pairs whose answer the exact query
//! confirms: each frame 8 random pairs whose world boxes overlap, whether worked on in that
//! frame or not), `agreement_adb` and `agreement_other` (the same for the pairs of ADB fidelity
//! and for the others), `agreement_adb_by_third` (the ADB pairs' agreement in the first,
//! second and last third of the frames: a pile falls first and rests last), `active_pairs`
//! (pairs worked on per frame, mean) and `transitions` (touching states that flipped per
//! frame, mean).
#[path = "support/cli.rs"]
mod cli;
mod support;

use std::fmt::Write as _;
use std::time::Instant;

use cli::{DECISIONS, ORDERS, parse_choice};
use plotters::prelude::*;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::bvh::{QueryWorkspace, intersects};
use stochastic_collision::ecs::{ColliderTable, CollisionCounters, ContactQueue, PairTable, Stage};
use stochastic_collision::prelude::*;
use support::{Options, Scene, tally};

/// Pairs re-tested exactly each frame for the agreement figure.
const SAMPLES_PER_FRAME: usize = 8;
/// Pair slots drawn at most per frame to find them: bounds the work in a frame where few pairs'
/// boxes overlap (that frame then samples fewer).
const SAMPLE_DRAWS_PER_FRAME: usize = 4096;

struct Args {
    scene: Scene,
    frames: usize,
    options: Options,
    json: Option<String>,
    svg: Option<String>,
    frames_csv: Option<String>,
}

fn parse() -> Result<Args, String> {
    let mut args = Args {
        scene: Scene::Pile,
        frames: 0,
        options: Options::default(),
        json: None,
        svg: None,
        frames_csv: None,
    };
    let mut budget = None;
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        let num = |v: String| v.parse::<u64>().map_err(|e| format!("{flag}: {e}"));
        match flag.as_str() {
            "--scene" => {
                let v = value()?;
                args.scene = Scene::parse(&v).ok_or(format!("unknown scene {v}"))?;
            }
            "--frames" => args.frames = num(value()?)? as usize,
            "--entities" => args.options.entities = num(value()?)? as usize,
            "--threads" => args.options.threads = num(value()?)?.max(1) as usize,
            "--budget-us" => budget = Some(num(value()?)?),
            "--node-budget" => args.options.node_budget = Some(num(value()?)?),
            "--seed" => args.options.seed = num(value()?)?,
            "--adb-decision" => {
                args.options.adb_decision = Some(parse_choice(&value()?, &flag, DECISIONS)?)
            }
            "--adb-order" => args.options.adb_order = Some(parse_choice(&value()?, &flag, ORDERS)?),
            "--adb-interior" => {
                args.options.adb_interior = Some(parse_choice(
                    &value()?,
                    &flag,
                    &[("on", true), ("off", false)],
                )?)
            }
            "--json" => args.json = Some(value()?),
            "--svg" => args.svg = Some(value()?),
            "--frames-csv" => args.frames_csv = Some(value()?),
            "-h" | "--help" => return Err(String::new()),
            other => return Err(format!("unknown argument {other}")),
        }
    }
    if args.frames == 0 {
        args.frames = args.scene.default_frames();
    }
    args.options.budget_us = budget.unwrap_or(args.scene.default_budget_us());
    Ok(args)
}

/// One frame's stage times (µs; `None`: not run) and the collision time.
struct FrameRecord {
    stages: Vec<Option<f64>>,
    collision_us: f64,
    /// Pairs in the table and pairs worked on in the frame.
    pairs: usize,
    active: usize,
    /// The diagnostics' counters after the frame (the frame's work is the difference from the
    /// frame before).
    counters: CollisionCounters,
}

fn main() {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!(
                "{e}\nusage: profile --scene pile|cannonball|cloth|intestine [--frames N] [--entities N] \
                 [--threads T] [--budget-us B] [--node-budget N] [--seed S] \
                 [--adb-decision confidence|evidence] \
                 [--adb-order straddle|depth-first|evidence-first|best-first] \
                 [--adb-interior on|off] [--json out.json] [--svg out.svg]"
            );
            std::process::exit(2);
        }
    };
    let build = Instant::now();
    let mut app = args.scene.build(&args.options);
    app.finish();
    app.cleanup();
    let build_time = build.elapsed();
    let mut records = Vec::with_capacity(args.frames);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(args.options.seed ^ 0xa9);
    let mut ws = QueryWorkspace::new();
    let mut agreement = Agreement::default();
    let (mut active_pairs, mut transitions) = (0u64, 0u64);
    let run = Instant::now();
    // Resident memory after a tenth of the run (warm-up: queues, pools and pair tables grown)
    // and at the end: growth means something keeps accumulating.
    let mut rss_warm = None;
    for frame in 0..args.frames {
        if frame == args.frames / 10 {
            rss_warm = resident_bytes();
        }
        if frame + 1 == args.frames {
            app.world_mut().resource_mut::<tally::Tally>().last = true;
        }
        app.update();
        let world = app.world();
        let d = world.resource::<CollisionDiagnostics>();
        records.push(FrameRecord {
            stages: Stage::ALL
                .iter()
                .map(|&s| d.stage(s).last.map(|t| t.as_secs_f64() * 1e6))
                .collect(),
            collision_us: d.collision_time.as_secs_f64() * 1e6,
            pairs: world.resource::<PairTable>().len(),
            active: world.resource::<PairTable>().active_pairs(),
            counters: d.counters,
        });
        // Agreement: a few pairs per frame whose world boxes overlap (every such pair has an
        // answer, worked on in this frame or still holding from an earlier one), re-tested
        // exactly outside the timed stages; ADB pairs counted apart from the others. Drawn by
        // picking pair slots at random and keeping those of two colliders whose boxes overlap
        // (uniform over such pairs): a few hundred reads a frame, where listing every pair
        // would stream the whole table through the caches between two timed frames.
        let colliders = world.resource::<ColliderTable>();
        let table = world.resource::<PairTable>();
        let mut close = Vec::with_capacity(SAMPLES_PER_FRAME);
        for _ in 0..SAMPLE_DRAWS_PER_FRAME {
            if close.len() == SAMPLES_PER_FRAME || table.slot_count() == 0 {
                break;
            }
            let Some(o) = table.outcome_in_slot(rng.random_range(0..table.slot_count())) else {
                continue;
            };
            if let (true, Some(a), Some(b)) = (o.a != o.b, colliders.get(o.a), colliders.get(o.b))
                && a.aabb.intersects(&b.aabb)
            {
                close.push((o, a, b));
            }
        }
        for &(o, a, b) in &close {
            let exact = intersects(
                a.geometry.mesh(),
                &a.pose,
                b.geometry.mesh(),
                &b.pose,
                &mut ws,
            );
            let adb = matches!(a.fidelity.combine(b.fidelity), Fidelity::Adb { .. })
                && a.is_rigid()
                && b.is_rigid();
            agreement.count(adb, exact == o.collides, (frame, args.frames));
        }
        active_pairs += table.active_pairs() as u64;
        transitions += table.transitions() as u64;
    }
    let wall = run.elapsed();
    let memory = (rss_warm, resident_bytes());
    report(
        &args,
        &mut app,
        &records,
        &agreement,
        (active_pairs, transitions),
        (build_time, wall),
        memory,
    );
}

/// Resident set size of this process (Linux `/proc/self/statm`), if known.
/// Sampled pairs re-tested exactly: (sampled, agreed) for ADB pairs and for the others.
#[derive(Default)]
struct Agreement {
    adb: (u64, u64),
    other: (u64, u64),
    /// The ADB pairs' samples by third of the run (a pile falls in the first frames and
    /// rests in the last: what is stale differs).
    adb_by_third: [(u64, u64); 3],
}

impl Agreement {
    /// Counts a sample of frame `frame` of `frames`.
    fn count(&mut self, adb: bool, agreed: bool, (frame, frames): (usize, usize)) {
        let c = if adb { &mut self.adb } else { &mut self.other };
        c.0 += 1;
        c.1 += u64::from(agreed);
        if adb {
            let t = &mut self.adb_by_third[(3 * frame / frames.max(1)).min(2)];
            t.0 += 1;
            t.1 += u64::from(agreed);
        }
    }

    fn share((sampled, agreed): (u64, u64)) -> f64 {
        if sampled == 0 {
            1.0
        } else {
            agreed as f64 / sampled as f64
        }
    }
}

fn resident_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096)
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let i = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[i]
}

fn summary(values: &[f64]) -> (f64, f64, f64) {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let mean = if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    };
    (mean, percentile(&v, 0.5), percentile(&v, 0.99))
}

fn report(
    args: &Args,
    app: &mut bevy_app::App,
    records: &[FrameRecord],
    agreement: &Agreement,
    (active_pairs, transitions): (u64, u64),
    (build_time, wall): (std::time::Duration, std::time::Duration),
    (rss_warm, rss_end): (Option<u64>, Option<u64>),
) {
    let mib = |b: Option<u64>| b.map_or(-1.0, |b| b as f64 / (1024.0 * 1024.0));
    let growth = match (rss_warm, rss_end) {
        (Some(w), Some(e)) => (e as f64 - w as f64) / (1024.0 * 1024.0),
        _ => 0.0,
    };
    let world = app.world_mut();
    let lost = tally::lost(world);
    let d = world.resource::<CollisionDiagnostics>().clone();
    let deferred = world.resource::<ContactQueue>().deferred_total;
    let budget = args.options.budget_us as f64;
    let collision: Vec<f64> = records.iter().map(|r| r.collision_us).collect();
    let (c_mean, c_p50, c_p99) = summary(&collision);
    let overruns = if budget > 0.0 {
        collision.iter().filter(|&&c| c > budget).count()
    } else {
        0
    };
    let sampled = agreement.adb.0 + agreement.other.0;
    let adb_samples = agreement.adb.0;
    let agreement_adb = Agreement::share(agreement.adb);
    let agreement_other = Agreement::share(agreement.other);
    let thirds = agreement.adb_by_third.map(Agreement::share);
    let agreement = Agreement::share((sampled, agreement.adb.1 + agreement.other.1));
    let frames = records.len().max(1) as f64;
    let mut stages = String::new();
    println!(
        "scene {} ({} entities), {} frames, {} threads, budget {} us{}; setup {:.2} s, run {:.2} s",
        args.scene.name(),
        world.resource::<ColliderTable>().len(),
        records.len(),
        args.options.threads,
        args.options.budget_us,
        args.options
            .node_budget
            .map_or(String::new(), |n| format!(" (work budget {n} node pairs)")),
        build_time.as_secs_f64(),
        wall.as_secs_f64()
    );
    println!(
        "{:<16}{:>10}{:>10}{:>10}{:>8}",
        "stage", "mean_us", "p50_us", "p99_us", "runs"
    );
    for (k, s) in Stage::ALL.iter().enumerate() {
        let ran: Vec<f64> = records.iter().filter_map(|r| r.stages[k]).collect();
        let (mean, p50, p99) = summary(&ran);
        if ran.is_empty() {
            println!("{:<16}{:>38}", s.name(), "not run");
        } else {
            println!(
                "{:<16}{mean:>10.1}{p50:>10.1}{p99:>10.1}{:>8}",
                s.name(),
                ran.len()
            );
        }
        let _ = write!(
            stages,
            "{}\n    \"{}\": {{\"mean_us\": {mean:.2}, \"p50_us\": {p50:.2}, \"p99_us\": {p99:.2}, \"runs\": {}}}",
            if k == 0 { "" } else { "," },
            s.name(),
            ran.len()
        );
    }
    let c = d.counters;
    println!(
        "collision (prepare..report): mean {c_mean:.1} us, p50 {c_p50:.1} us, p99 {c_p99:.1} us; {overruns} frames over budget"
    );
    println!(
        "events: {} started, {} ended, {} contacts; {deferred} contacts deferred, {lost} events lost",
        c.started, c.ended, c.contacts
    );
    println!(
        "memory: {:.1} MiB resident after a tenth of the run, {:.1} MiB at the end ({growth:+.1} MiB)",
        mib(rss_warm),
        mib(rss_end)
    );
    println!(
        "work: {} node pairs, {} ADB pairs ({} cut by the budget, {} answered from the last test), {} exact pairs ({} more confirmed from memory), {} cached pairs; agreement with exact {:.4} on {sampled} sampled pairs (ADB pairs {agreement_adb:.4} on {adb_samples}, others {agreement_other:.4}; ADB pairs by third of the run {:.4}, {:.4}, {:.4})",
        c.node_pairs,
        c.adb_pairs,
        c.budget_exhausted_pairs,
        c.coherence_pairs,
        c.exact_pairs,
        c.confirmed_pairs,
        c.cached_pairs,
        agreement,
        thirds[0],
        thirds[1],
        thirds[2]
    );
    if c.tracker_steps_cut > 0 {
        println!(
            "tracking: {} tracker steps cut by the budget (an eighth of their searches, the other pairs re-measured)",
            c.tracker_steps_cut
        );
    }
    let test_ms = c.test_time.as_secs_f64() * 1e3;
    let per_ms = |n: u64| {
        if test_ms > 0.0 {
            n as f64 / test_ms
        } else {
            0.0
        }
    };
    println!(
        "narrow-phase throughput: {} pair tests in {test_ms:.1} ms of testing: {:.0} tests/ms, {:.0} node pairs/ms",
        c.tested_pairs,
        per_ms(c.tested_pairs),
        per_ms(c.node_pairs)
    );
    if let Some(path) = &args.json {
        let json = format!(
            "{{\n  \"scene\": \"{}\",\n  \"frames\": {},\n  \"threads\": {},\n  \"budget_us\": {},\n  \"node_budget\": {},\n  \"entities\": {},\n  \"seed\": {},\n  \"stages\": {{{stages}\n  }},\n  \"collision_mean_us\": {c_mean:.2},\n  \"collision_p50_us\": {c_p50:.2},\n  \"collision_p99_us\": {c_p99:.2},\n  \"overrun_frames\": {overruns},\n  \"events\": {{\"started\": {}, \"ended\": {}, \"contacts\": {}}},\n  \"events_deferred\": {deferred},\n  \"events_lost\": {lost},\n  \"agreement_with_exact\": {agreement:.5},\n  \"agreement_samples\": {sampled},\n  \"agreement_adb\": {agreement_adb:.5},\n  \"agreement_adb_samples\": {adb_samples},\n  \"agreement_other\": {agreement_other:.5},\n  \"agreement_adb_by_third\": [{:.5}, {:.5}, {:.5}],\n  \"active_pairs\": {:.1},\n  \"transitions\": {:.2},\n  \"memory\": {{\"rss_mib_after_warmup\": {:.1}, \"rss_mib_end\": {:.1}, \"rss_growth_mib\": {growth:.1}}},\n  \"work\": {{\"node_pairs\": {}, \"adb_pairs\": {}, \"budget_exhausted_pairs\": {}, \"deadline_pairs\": {}, \"exact_pairs\": {}, \"confirmed_pairs\": {}, \"cached_pairs\": {}, \"tested_pairs\": {}, \"test_ms\": {test_ms:.3}, \"tests_per_ms\": {:.2}, \"node_pairs_per_ms\": {:.2}}}\n}}\n",
            args.scene.name(),
            records.len(),
            args.options.threads,
            args.options.budget_us,
            args.options
                .node_budget
                .map_or("null".to_string(), |n| n.to_string()),
            world.resource::<ColliderTable>().len(),
            args.options.seed,
            c.started,
            c.ended,
            c.contacts,
            thirds[0],
            thirds[1],
            thirds[2],
            active_pairs as f64 / frames,
            transitions as f64 / frames,
            mib(rss_warm),
            mib(rss_end),
            c.node_pairs,
            c.adb_pairs,
            c.budget_exhausted_pairs,
            c.coherence_pairs,
            c.exact_pairs,
            c.confirmed_pairs,
            c.cached_pairs,
            c.tested_pairs,
            per_ms(c.tested_pairs),
            per_ms(c.node_pairs),
        );
        match std::fs::write(path, json) {
            Ok(()) => println!("wrote {path}"),
            Err(e) => eprintln!("cannot write {path}: {e}"),
        }
    }
    if let Some(path) = &args.svg {
        match timeline(path, args, records) {
            Ok(()) => println!("wrote {path}"),
            Err(e) => eprintln!("cannot write {path}: {e}"),
        }
    }
    if let Some(path) = &args.frames_csv {
        match std::fs::write(path, frames_csv(records)) {
            Ok(()) => println!("wrote {path}"),
            Err(e) => eprintln!("cannot write {path}: {e}"),
        }
    }
}

/// One row per frame: each stage's time (µs, empty when it did not run), the collision
/// stages' time, the pairs in the table and the pairs worked on.
fn frames_csv(records: &[FrameRecord]) -> String {
    let mut out = String::from("frame");
    for s in Stage::ALL {
        let _ = write!(out, ",{}_us", s.name());
    }
    out.push_str(
        ",collision_us,pairs,active_pairs,tested_pairs,exact_pairs,confirmed_pairs,node_pairs\n",
    );
    let mut before = CollisionCounters::default();
    for (i, r) in records.iter().enumerate() {
        let _ = write!(out, "{i}");
        for t in &r.stages {
            match t {
                Some(t) => {
                    let _ = write!(out, ",{t:.1}");
                }
                None => out.push(','),
            }
        }
        let c = &r.counters;
        let _ = writeln!(
            out,
            ",{:.1},{},{},{},{},{},{}",
            r.collision_us,
            r.pairs,
            r.active,
            c.tested_pairs - before.tested_pairs,
            c.exact_pairs - before.exact_pairs,
            c.confirmed_pairs - before.confirmed_pairs,
            c.node_pairs - before.node_pairs,
        );
        before = *c;
    }
    out
}

/// Per-frame stage times (and the collision total) against the budget.
fn timeline(
    path: &str,
    args: &Args,
    records: &[FrameRecord],
) -> Result<(), Box<dyn std::error::Error>> {
    let budget = args.options.budget_us as f64;
    let top = records
        .iter()
        .map(|r| r.collision_us)
        .fold(budget, f64::max)
        * 1.1;
    let root = SVGBackend::new(path, (1000, 520)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{}: stage times per frame, {} threads, budget {} us",
                args.scene.name(),
                args.options.threads,
                args.options.budget_us
            ),
            ("sans-serif", 18),
        )
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(60)
        .build_cartesian_2d(0f64..records.len() as f64, 0f64..top.max(1.0))?;
    chart.configure_mesh().x_desc("frame").y_desc("µs").draw()?;
    let colors = [
        BLUE,
        GREEN,
        CYAN,
        MAGENTA,
        RGBColor(200, 120, 0),
        RGBColor(120, 60, 160),
        BLACK,
        RGBColor(120, 120, 120),
    ];
    for (k, s) in Stage::ALL.iter().enumerate() {
        if records.iter().all(|r| r.stages[k].is_none()) {
            continue;
        }
        let color = colors[k % colors.len()];
        chart
            .draw_series(LineSeries::new(
                records
                    .iter()
                    .enumerate()
                    .map(|(f, r)| (f as f64, r.stages[k].unwrap_or(0.0))),
                color,
            ))?
            .label(s.name())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color));
    }
    chart
        .draw_series(LineSeries::new(
            records
                .iter()
                .enumerate()
                .map(|(f, r)| (f as f64, r.collision_us)),
            BLACK.stroke_width(2),
        ))?
        .label("collision (prepare..report)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(2)));
    if budget > 0.0 {
        chart
            .draw_series(LineSeries::new(
                [(0.0, budget), (records.len() as f64, budget)],
                RED.stroke_width(2),
            ))?
            .label("budget")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], RED.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    root.present()?;
    Ok(())
}
