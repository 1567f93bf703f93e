//! Fits the swept answer model (`ccd::SweptAnswerModel::FITTED`): the confidence of a
//! continuous ADB answer its budget cut short.
//!
//! Training set: random rigid motions over one step (`support/swept_cases.rs`, as in
//! `continuous_adb_reliability`) of pairs of training meshes named below (`training_meshes`:
//! the shared bunny, armadillo and dragon_50k, the dragon also at a third of the size and the
//! bunny at an eighth, and generated shapes none of which the reliability report or the tunnel
//! uses: a plank, a capped tube, an open sheet, a coarse spiky ball and a small one, a large
//! thin slab and a large sheet), each mesh against each and, half as many again, a small mesh
//! flying past a large one, on the seeds `TRAINING_SEEDS`, each answered by the
//! exact continuous query and by the estimating query under node budgets of 3, 10, 30, 100
//! and 300; every answer cut short with node pairs left (and no contact found) is a sample. The
//! report `continuous_adb_reliability` evaluates the model on other meshes and seeds.
//!
//! Prints the weights (paste them into `src/ccd/swept_answer_model.rs`) and, on the training
//! set, the Brier score and errors of the combined estimates and of the fitted model.
//!
//! ```text
//! cargo run --release --example fit_swept_answer_model -- [--cases N]
//! ```
#[allow(dead_code)]
#[path = "support/mesh_pairs.rs"]
mod mesh_pairs;
mod support;
// Only its `cases_between` is used here.
#[allow(dead_code)]
#[path = "support/swept_cases.rs"]
mod swept_cases;

use glam::Vec3;
use stochastic_collision::adb::{AdbTree, Budget};
use stochastic_collision::bvh::CollisionMesh;
use stochastic_collision::ccd::{
    CcdWorkspace, ContinuousAdbQuery, SWEPT_FEATURES, SweptAnswerModel, SweptConfidence,
    adb_time_of_impact,
};
use stochastic_collision::mesh::{TriMesh, generate};
use support::shared_mesh;
use swept_cases::cases_between;

/// Seeds of the training motions (the reliability report uses others).
const TRAINING_SEEDS: [u64; 2] = [0x5EE7_0001, 0x5EE7_0002];

/// Node budgets the samples come from (those the reliability report evaluates).
const BUDGETS: [u64; 5] = [3, 10, 30, 100, 300];

/// Ridge penalty of the fit.
const RIDGE: f64 = 1e-2;

/// `mesh` centred, its box diagonal `size`.
fn centred(mesh: &TriMesh, size: f32) -> TriMesh {
    mesh.translated(-mesh.aabb().center())
        .and_then(|m| mesh_pairs::sized(&m, size))
        .expect("moving and scaling keep a valid mesh")
}

/// A training mesh and its part in the small-against-large cases.
struct Training {
    name: &'static str,
    tree: AdbTree,
    small: bool,
    large: bool,
}

/// The training meshes: most about 1.5 across, three small (0.2–0.5) and two large (7 across)
/// for the cases of small bodies flying past large ones (a tenth to a fortieth of their size,
/// as a shot against a wall).
fn training_meshes() -> Vec<Training> {
    let spiky = |size: f32, seed: u64| {
        let ball = mesh_pairs::spiky_sphere(0.4, 2, 0.6, 3, seed);
        centred(&ball, size)
    };
    let mut out = vec![
        ("plank", generate::cuboid(Vec3::new(0.6, 0.06, 0.25), 6), ""),
        ("capped tube", generate::tube(0.15, 1.2, 20, 30, true), ""),
        ("sheet", generate::cloth_grid(1.2, 1.0, 24, 20), ""),
        ("coarse spiky ball", spiky(1.5, 0x5EE7), ""),
        ("pebble", spiky(0.2, 0x5EE8), "small"),
        (
            "slab",
            generate::cuboid(Vec3::new(0.02, 2.0, 3.0), 8),
            "large",
        ),
        (
            "wide sheet",
            generate::cloth_grid(5.0, 5.0, 40, 40),
            "large",
        ),
    ];
    for (name, file, size, part) in [
        ("bunny", "bunny.obj", 1.5, ""),
        ("armadillo", "armadillo.obj", 1.5, ""),
        ("dragon", "dragon_50k.obj", 1.5, ""),
        ("dragon/3", "dragon_50k.obj", 0.5, "small"),
        ("bunny/8", "bunny.obj", 0.2, "small"),
    ] {
        match shared_mesh(file) {
            Some(m) => out.push((name, centred(&m, size), part)),
            None => eprintln!("note: {file} is missing; training without it"),
        }
    }
    out.into_iter()
        .map(|(name, m, part)| Training {
            name,
            tree: AdbTree::new(CollisionMesh::new(m)),
            small: part == "small",
            large: part == "large",
        })
        .collect()
}

/// Brier score, missed and false contacts of confidences against the truth ("collision" from
/// ½).
fn score(answers: &[(f64, bool)]) -> (f64, usize, usize) {
    let brier = answers
        .iter()
        .map(|&(p, y)| (p - f64::from(u8::from(y))).powi(2))
        .sum::<f64>()
        / answers.len().max(1) as f64;
    let missed = answers.iter().filter(|&&(p, y)| y && p < 0.5).count();
    let false_contacts = answers.iter().filter(|&&(p, y)| !y && p >= 0.5).count();
    (brier, missed, false_contacts)
}

fn main() {
    let mut n = 480;
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        match (flag.as_str(), it.next().map(|v| v.parse::<usize>())) {
            ("--cases", Some(Ok(v))) => n = v,
            _ => {
                eprintln!("usage: fit_swept_answer_model [--cases N]");
                std::process::exit(2);
            }
        }
    }
    let meshes = training_meshes();
    let names: Vec<&str> = meshes.iter().map(|m| m.name).collect();
    let pick = |f: fn(&Training) -> bool| -> Vec<usize> {
        (0..meshes.len()).filter(|&i| f(&meshes[i])).collect()
    };
    let (all, small, large) = (pick(|_| true), pick(|m| m.small), pick(|m| m.large));
    let mut ws = CcdWorkspace::new();
    // Per sample: features, the combined estimate, the budget's index, whether it touches.
    let mut samples: Vec<([f64; SWEPT_FEATURES], f64, usize, bool)> = Vec::new();
    let mut touching = 0;
    for seed in TRAINING_SEEDS {
        // Every mesh against every other, then half as many small bodies past large ones.
        let mut cases = cases_between(n, &all, &all, seed);
        cases.extend(cases_between(n / 2, &small, &large, seed ^ 0x5A11));
        for (k, c) in cases.iter().enumerate() {
            if k % 40 == 0 {
                eprint!("\rseed {seed:#x}: case {k}/{}", cases.len());
            }
            let (a, b) = (&meshes[c.a].tree, &meshes[c.b].tree);
            let touches = c.reference(a, b, &mut ws).is_some();
            touching += usize::from(touches);
            for (i, &budget) in BUDGETS.iter().enumerate() {
                let query = ContinuousAdbQuery {
                    confidence: SweptConfidence::Combined,
                    ..ContinuousAdbQuery::with_budget(Budget::NodePairs(budget))
                };
                let out = adb_time_of_impact(a, &c.motion_a, b, &c.motion_b, &query, &mut ws)
                    .expect("finite motions");
                if let Some(f) = out.frontier {
                    samples.push((SweptAnswerModel::features(&f), f.raw_confidence, i, touches));
                }
            }
        }
    }
    eprintln!("\r{} samples                    ", samples.len());
    let fit_set: Vec<([f64; SWEPT_FEATURES], bool)> =
        samples.iter().map(|&(x, _, _, y)| (x, y)).collect();
    let Some(model) = SweptAnswerModel::fit(&fit_set, RIDGE) else {
        eprintln!("fit_swept_answer_model: the fit failed");
        std::process::exit(1);
    };
    println!(
        "swept answer model: {} training cases ({} touch during the step; {} per seed of each mesh against each, {} of a small one past a large one) on seeds {}, meshes: {}",
        (n + n / 2) * TRAINING_SEEDS.len(),
        touching,
        n,
        n / 2,
        TRAINING_SEEDS.map(|s| format!("{s:#x}")).join(", "),
        names.join(", ")
    );
    println!(
        "{} samples (answers cut short with node pairs left, budgets {:?}), {} of them touch; ridge {RIDGE}",
        samples.len(),
        BUDGETS,
        samples.iter().filter(|s| s.3).count()
    );
    println!(
        "training set: budget | samples | combined estimates: Brier, missed, false | model: Brier, missed, false"
    );
    for (i, budget) in BUDGETS.iter().enumerate() {
        let of: Vec<_> = samples.iter().filter(|s| s.2 == i).collect();
        let combined: Vec<(f64, bool)> = of.iter().map(|s| (s.1, s.3)).collect();
        let fitted: Vec<(f64, bool)> = of
            .iter()
            .map(|s| (model.confidence_of(&s.0), s.3))
            .collect();
        let (cb, cm, cf) = score(&combined);
        let (mb, mm, mf) = score(&fitted);
        println!(
            "{budget:>6} | {:>7} | {cb:.3}, {cm:>4}, {cf:>4} | {mb:.3}, {mm:>4}, {mf:>4}",
            of.len()
        );
    }
    println!("weights (src/ccd/swept_answer_model.rs, SweptAnswerModel::FITTED):");
    println!("        weights: [");
    for w in model.weights {
        println!("            {w:?},");
    }
    println!("        ],");
}
