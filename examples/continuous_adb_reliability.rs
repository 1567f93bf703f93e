//! How far the time-critical continuous ADB query's confidence can be trusted on swept pairs.
//!
//! Random rigid motions of pairs of meshes over one step (one mesh flying across the other's
//! neighbourhood, turning or not; the other moving a little and turning), each answered by the
//! exact continuous query (`ccd::time_of_impact`, the reference) and by `adb_time_of_impact`
//! under node budgets of 3, 10, 30, 100 and 300 node pairs: the estimating query (probability of
//! a contact during the step from the swept answer model, "collision" from ½; beside it the
//! node pairs' estimates combined as the discrete query does, its confidence before the model)
//! and the conservative one. Meshes: generated
//! shapes (a ball, a thin wall, a torus, a seeded random tube and spiky sphere) and, when the
//! shared meshes are present, Spot and Suzanne, none of them a training mesh of the ADB
//! defaults or of the swept answer model (`fit_swept_answer_model`); motions from `--seed`. Prints, per budget, how many answers the budget cut short,
//! the estimating query's errors (missed and false contacts), its Brier score over all answers
//! and over the cut ones, the observed frequency of contact per bin of reported probability,
//! and the conservative query's misses (always 0) and false contacts; writes the reliability
//! curves (cut answers) as SVG.
//!
//! ```text
//! cargo run --release --example continuous_adb_reliability -- [--seed S] [--cases N] [--svg PATH]
//! ```
// Only its `sized` is used here.
#[allow(dead_code)]
#[path = "support/mesh_pairs.rs"]
mod mesh_pairs;
#[path = "support/reliability.rs"]
mod reliability;
mod support;
#[path = "support/swept_cases.rs"]
mod swept_cases;

use std::fmt::Write as _;
use std::path::PathBuf;

use glam::Vec3;
use plotters::prelude::*;
use stochastic_collision::adb::{AdbTree, Budget};
use stochastic_collision::bvh::CollisionMesh;
use stochastic_collision::ccd::{
    CcdWorkspace, ContinuousAdbQuery, SweptConfidence, adb_time_of_impact,
};
use stochastic_collision::mesh::{TriMesh, generate};
use support::shared_mesh;
use swept_cases::cases;

/// Node budgets compared.
const BUDGETS: [u64; 5] = [3, 10, 30, 100, 300];

struct Args {
    seed: u64,
    cases: usize,
    svg: PathBuf,
}

fn parse() -> Result<Args, String> {
    let mut args = Args {
        seed: 1,
        cases: 240,
        svg: PathBuf::from("target/continuous_adb_reliability.svg"),
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--seed" => args.seed = value()?.parse().map_err(|e| format!("--seed: {e}"))?,
            "--cases" => args.cases = value()?.parse().map_err(|e| format!("--cases: {e}"))?,
            "--svg" => args.svg = PathBuf::from(value()?),
            other => return Err(format!("unknown argument {other}")),
        }
    }
    Ok(args)
}

/// `mesh` centred, its box diagonal `size`.
fn centred(mesh: &TriMesh, size: f32) -> TriMesh {
    mesh.translated(-mesh.aabb().center())
        .and_then(|m| mesh_pairs::sized(&m, size))
        .expect("moving and scaling keep a valid mesh")
}

fn meshes(seed: u64) -> Vec<(&'static str, AdbTree)> {
    let mut out = vec![
        ("ball", generate::icosphere(0.4, 3)),
        ("thin wall", generate::cuboid(Vec3::new(0.04, 1.0, 1.0), 8)),
        ("torus", generate::torus(0.6, 0.15, 32, 12)),
        (
            "random tube",
            generate::random_tube(0.12, 1.6, 16, 48, seed),
        ),
        ("spiky sphere", generate::noisy_sphere(0.45, 3, 0.25, seed)),
    ];
    for (name, file) in [("spot", "spot.obj"), ("suzanne", "suzanne.obj")] {
        if let Some(m) = shared_mesh(file) {
            out.push((name, centred(&m, 1.5)));
        }
    }
    out.into_iter()
        .map(|(n, m)| (n, AdbTree::new(CollisionMesh::new(m))))
        .collect()
}

/// What one budget's answers came to.
#[derive(Default)]
struct Tally {
    cut: usize,
    missed: usize,
    false_contacts: usize,
    brier: f64,
    brier_cut: f64,
    /// Per bin of reported probability (cut answers).
    bins: reliability::Bins,
    conservative_missed: usize,
    conservative_false: usize,
    /// The same answers with the node pairs' estimates combined as the discrete query does
    /// (`SweptConfidence::Combined`, the confidence before the swept answer model).
    combined_missed: usize,
    combined_false: usize,
    combined_brier_cut: f64,
}

fn main() {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!(
                "continuous_adb_reliability: {e}\nusage: continuous_adb_reliability [--seed S] [--cases N] [--svg PATH]"
            );
            std::process::exit(2);
        }
    };
    let meshes = meshes(args.seed);
    let names: Vec<&str> = meshes.iter().map(|(n, _)| *n).collect();
    let cases = cases(args.cases, meshes.len(), args.seed);
    let mut ws = CcdWorkspace::new();
    let mut tallies: Vec<Tally> = BUDGETS.iter().map(|_| Tally::default()).collect();
    let mut contacts = 0;
    for (k, c) in cases.iter().enumerate() {
        if k % 40 == 0 {
            eprint!("\rcase {k}/{}", cases.len());
        }
        let (a, b) = (&meshes[c.a].1, &meshes[c.b].1);
        let reference = c.reference(a, b, &mut ws);
        let touches = reference.is_some();
        contacts += usize::from(touches);
        for (t, &budget) in tallies.iter_mut().zip(&BUDGETS) {
            let query = ContinuousAdbQuery::with_budget(Budget::NodePairs(budget));
            debug_assert!(matches!(query.confidence, SweptConfidence::Model(_)));
            let out = adb_time_of_impact(a, &c.motion_a, b, &c.motion_b, &query, &mut ws)
                .expect("finite motions");
            let truth = f64::from(u8::from(touches));
            let square = (out.probability - truth).powi(2);
            t.brier += square;
            t.missed += usize::from(touches && !out.collides);
            t.false_contacts += usize::from(!touches && out.collides);
            // The combined estimates instead, where the model decided.
            let (combined, combined_collides) = match out.frontier {
                Some(f) => (f.raw_confidence, f.raw_confidence >= 0.5),
                None => (out.probability, out.collides),
            };
            t.combined_missed += usize::from(touches && !combined_collides);
            t.combined_false += usize::from(!touches && combined_collides);
            if !out.settled {
                t.cut += 1;
                t.brier_cut += square;
                t.combined_brier_cut += (combined - truth).powi(2);
                reliability::add(&mut t.bins, out.probability, touches);
            }
            let query = ContinuousAdbQuery::conservative(Budget::NodePairs(budget));
            let out = adb_time_of_impact(a, &c.motion_a, b, &c.motion_b, &query, &mut ws)
                .expect("finite motions");
            t.conservative_missed += usize::from(touches && !out.collides);
            t.conservative_false += usize::from(!touches && out.collides);
        }
    }
    eprintln!("\r{} cases          ", cases.len());
    print!("{}", report(&args, &names, cases.len(), contacts, &tallies));
    match plot(&args.svg, &tallies) {
        Ok(()) => println!("wrote {}", args.svg.display()),
        Err(e) => {
            eprintln!("cannot write {}: {e}", args.svg.display());
            std::process::exit(1);
        }
    }
}

fn report(args: &Args, names: &[&str], n: usize, contacts: usize, tallies: &[Tally]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "continuous ADB on swept pairs: {n} random motions (seed {}), {contacts} touch during the step (exact continuous query); meshes: {}",
        args.seed,
        names.join(", ")
    );
    let _ = writeln!(
        s,
        "node budget | cut short | estimating (swept answer model): missed, false, error | Brier (all, cut) | combined estimates: missed, false, Brier (cut) | conservative: missed, false"
    );
    for (t, budget) in tallies.iter().zip(BUDGETS) {
        let _ = writeln!(
            s,
            "{budget:>11} | {:>9} | {:>7}, {:>5}, {:>5.1} % | {:.3}, {:.3} | {:>7}, {:>5}, {:.3} | {:>7}, {:>5}",
            t.cut,
            t.missed,
            t.false_contacts,
            100.0 * (t.missed + t.false_contacts) as f64 / n.max(1) as f64,
            t.brier / n.max(1) as f64,
            t.brier_cut / t.cut.max(1) as f64,
            t.combined_missed,
            t.combined_false,
            t.combined_brier_cut / t.cut.max(1) as f64,
            t.conservative_missed,
            t.conservative_false,
        );
    }
    let _ = writeln!(
        s,
        "reliability of the cut answers: reported probability bin -> observed frequency of contact (answers)"
    );
    for (t, budget) in tallies.iter().zip(BUDGETS) {
        let _ = writeln!(s, "  {budget} node pairs: {}", reliability::line(&t.bins));
    }
    s
}

/// Observed frequency of contact against the reported probability (cut answers), one curve per
/// budget, each point at its bin's mean reported probability.
fn plot(path: &std::path::Path, tallies: &[Tally]) -> Result<(), Box<dyn std::error::Error>> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let root = SVGBackend::new(path, (700, 620)).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            "Continuous ADB: reliability of answers cut by the budget",
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.0f64..1.0, 0.0f64..1.0)?;
    chart
        .configure_mesh()
        .x_desc("reported probability of a contact during the step")
        .y_desc("observed frequency of contact")
        .draw()?;
    chart
        .draw_series(LineSeries::new(
            vec![(0.0, 0.0), (1.0, 1.0)],
            BLACK.mix(0.4),
        ))?
        .label("perfectly calibrated")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], BLACK.mix(0.4)));
    for (i, (t, budget)) in tallies.iter().zip(BUDGETS).enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let pts = reliability::points(&t.bins);
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))?
            .label(format!("{budget} node pairs ({} cut)", t.cut))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], color));
        chart.draw_series(pts.iter().map(|&p| Circle::new(p, 3, color.filled())))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK.mix(0.3))
        .draw()?;
    root.present()?;
    Ok(())
}
