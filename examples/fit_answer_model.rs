//! Fits the ADB answer model (`adb::AnswerModel`): the confidence of answers the traversal did
//! not settle, from features that mean the same for any pair of trees. Training: the pairs and
//! seeds named below (`training_pairs`, `TRAINING_SEEDS`), every pose answered under a range of
//! node budgets and checked by the exact query. Held out: the accuracy report's pairs of
//! different meshes and CAD-like parts (`support/mesh_pairs.rs`) and same-mesh pairs of shared
//! meshes not in the training set, on other seeds, under a 20 µs time budget. Prints the fitted weights (the
//! `AnswerModel::FITTED` constant) and, on the held-out answers, the Brier score and error of
//! the frontier's raw confidence, of the confidence the query reports, and of the fitted model.
//!
//! ```text
//! cargo run --release --example fit_answer_model -- [--poses N] [--quick]
//! ```
use std::path::PathBuf;
use std::time::Duration;

use glam::Vec3;
use stochastic_collision::adb::{
    ANSWER_FEATURES, AdbQuery, AdbTree, AdbWorkspace, AnswerModel, Budget, adb_intersects,
};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, intersects, root_boxes_overlap};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::{TriMesh, generate};
use stochastic_collision::poses::near_contact_poses;

#[path = "support/mesh_pairs.rs"]
mod mesh_pairs;
#[path = "support/progress.rs"]
mod progress;

/// Seeds of the training poses (the report evaluates on 0xACC0 and 7).
const TRAINING_SEEDS: [u64; 2] = [0x7A1_0001, 0x7A1_0002];
/// Seeds of the held-out poses.
const HELD_OUT_SEEDS: [u64; 2] = [0xACC0, 7];
/// Node budgets of the training queries: from a handful of pairs to most of a shallow query.
const TRAINING_BUDGETS: [u64; 7] = [8, 16, 32, 64, 128, 256, 512];
/// Offsets from first contact of the training and held-out poses (fractions of the size).
const SPREADS: [f32; 2] = [0.02, 0.15];
/// The ridge penalty of the fit.
const RIDGE: f64 = 1e-2;

/// Where the shared meshes are.
fn shared_dir() -> PathBuf {
    std::env::var_os("STOCHASTIC_COLLISION_MESHES")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/meshes")
        })
}

use mesh_pairs::size;

/// `mesh` scaled so that its box diagonal is `target` ([`mesh_pairs::sized`]; the scales here
/// are all finite).
fn sized(mesh: &TriMesh, target: f32) -> TriMesh {
    mesh_pairs::sized(mesh, target).expect("a finite scale")
}

/// The training pairs: the meshes the ADB defaults were developed on (the shared bunny,
/// armadillo and dragon_50k) and generated shapes (a ball, a torus, a thin plate, an open
/// cloth, an open tube), each pair at a size ratio of 1, 2, 5 or 20, same-mesh and cross-mesh.
/// None of them is in the held-out set.
fn training_pairs() -> Vec<(String, TriMesh, TriMesh)> {
    let load = |name: &str| TriMesh::from_obj(shared_dir().join(format!("{name}.obj")));
    let (Ok(bunny), Ok(armadillo), Ok(dragon)) =
        (load("bunny"), load("armadillo"), load("dragon_50k"))
    else {
        eprintln!("note: the shared meshes are missing; training on generated shapes only");
        return generated_pairs();
    };
    let ball = generate::icosphere(1.0, 4);
    let torus = generate::torus(1.0, 0.3, 96, 32);
    let mut out = generated_pairs();
    let s = size(&bunny);
    for (name, a, b) in [
        ("bunny vs bunny", bunny.clone(), bunny.clone()),
        (
            "armadillo vs armadillo",
            armadillo.clone(),
            armadillo.clone(),
        ),
        ("bunny vs dragon", sized(&bunny, s), sized(&dragon, s)),
        (
            "armadillo/5 vs dragon",
            sized(&armadillo, s / 5.0),
            sized(&dragon, s),
        ),
        (
            "ball/20 vs armadillo",
            sized(&ball, s / 20.0),
            sized(&armadillo, s),
        ),
        ("torus vs bunny", sized(&torus, s), sized(&bunny, s)),
        (
            "dragon/5 vs torus",
            sized(&dragon, s / 5.0),
            sized(&torus, s),
        ),
        (
            "bunny/20 vs dragon",
            sized(&bunny, s / 20.0),
            sized(&dragon, s),
        ),
    ] {
        out.push((name.to_string(), a, b));
    }
    out
}

/// The generated training pairs: a ball, a torus, a thin plate, an open cloth and an open
/// tube of thousands of triangles, and small ones of hundreds.
fn generated_pairs() -> Vec<(String, TriMesh, TriMesh)> {
    let ball = generate::icosphere(1.0, 4);
    let torus = generate::torus(1.0, 0.3, 96, 32);
    let plate = generate::cuboid(Vec3::new(1.0, 0.02, 1.0), 8);
    let cloth = generate::cloth_grid(2.0, 2.0, 48, 48);
    let tube = generate::tube(0.3, 2.0, 48, 24, false);
    // Small meshes too (hundreds of triangles), where the same work covers most of a tree.
    let small_ball = generate::icosphere(1.0, 2);
    let small_torus = generate::torus(1.0, 0.4, 24, 10);
    let small_cloth = generate::cloth_grid(2.0, 2.0, 12, 12);
    let s = size(&ball);
    vec![
        (
            "small ball vs small ball".into(),
            small_ball.clone(),
            small_ball.clone(),
        ),
        (
            "small torus vs small torus".into(),
            small_torus.clone(),
            small_torus.clone(),
        ),
        (
            "small ball vs small cloth".into(),
            sized(&small_ball, s / 2.0),
            sized(&small_cloth, s),
        ),
        (
            "small torus/5 vs torus".into(),
            sized(&small_torus, s / 5.0),
            sized(&torus, s),
        ),
        ("ball vs ball".into(), ball.clone(), ball.clone()),
        ("torus vs torus".into(), torus.clone(), torus.clone()),
        (
            "ball/5 vs plate".into(),
            sized(&ball, s / 5.0),
            sized(&plate, s),
        ),
        ("torus vs cloth".into(), sized(&torus, s), sized(&cloth, s)),
        (
            "ball/20 vs tube".into(),
            sized(&ball, s / 20.0),
            sized(&tube, s),
        ),
        (
            "tube/5 vs torus".into(),
            sized(&tube, s / 5.0),
            sized(&torus, s),
        ),
    ]
}

/// The held-out pairs: the report's pairs of different meshes, its generated CAD-like parts
/// against themselves, and shared meshes the training never saw against themselves.
fn held_out_pairs() -> Vec<(String, TriMesh, TriMesh)> {
    let mut out: Vec<_> = mesh_pairs::held_out_pairs(&shared_dir())
        .into_iter()
        .map(|p| (p.name, p.first, p.second))
        .collect();
    for (name, part) in mesh_pairs::cad_parts() {
        out.push((format!("{name} vs {name}"), part.clone(), part));
    }
    for name in ["spot", "teapot", "large_intestine_20k", "suzanne"] {
        match TriMesh::from_obj(shared_dir().join(format!("{name}.obj"))) {
            Ok(m) => out.push((format!("{name} vs {name}"), m.clone(), m)),
            Err(e) => eprintln!("note: skipping {name}: {e}"),
        }
    }
    out
}

/// One unsettled answer: its features, the confidence the query reported, and the truth.
struct Sample {
    x: [f64; ANSWER_FEATURES],
    reported: f64,
    truth: bool,
}

/// Answers `poses` poses per seed and spread of every pair under every budget; returns the
/// unsettled answers and how many answers there were in all.
fn collect(
    label: &str,
    pairs: &[(String, TriMesh, TriMesh)],
    seeds: &[u64],
    budgets: &[Budget],
    poses: usize,
) -> (Vec<Sample>, usize) {
    let (mut samples, mut answers) = (Vec::new(), 0);
    let (mut ws, mut exact_ws) = (AdbWorkspace::new(), QueryWorkspace::new());
    for (k, (name, a, b)) in pairs.iter().enumerate() {
        eprint!(
            "\r  {label}: {:<40} {}",
            name,
            progress::bar(k, pairs.len())
        );
        let ta = AdbTree::new(CollisionMesh::new(a.clone()));
        let tb = AdbTree::new(CollisionMesh::new(b.clone()));
        let (ca, cb) = (ta.collision_mesh(), tb.collision_mesh());
        let size_ratio = f64::from(size(a) / size(b));
        let tree_nodes = (ta.nodes().len() + tb.nodes().len()) as u64;
        for &seed in seeds {
            for spread in SPREADS {
                for p in near_contact_poses(ca, cb, poses, spread, seed) {
                    if !root_boxes_overlap(ca, &Pose::IDENTITY, cb, &p.pose) {
                        continue;
                    }
                    let truth = intersects(ca, &Pose::IDENTITY, cb, &p.pose, &mut exact_ws);
                    for &budget in budgets {
                        let query = AdbQuery::with_budget(budget);
                        let out =
                            adb_intersects(&ta, &Pose::IDENTITY, &tb, &p.pose, &query, &mut ws);
                        answers += 1;
                        // Answers the evidence decided keep the evidence's confidence: the
                        // model is not asked for them.
                        let Some(f) = out.frontier.filter(|_| out.pairs_found < query.k_min) else {
                            continue;
                        };
                        samples.push(Sample {
                            x: AnswerModel::features(
                                &f,
                                out.node_pairs_visited,
                                size_ratio,
                                tree_nodes,
                            ),
                            reported: out.probability,
                            truth,
                        });
                    }
                }
            }
        }
    }
    eprintln!(
        "\r  {label}: done {}",
        progress::bar(pairs.len(), pairs.len())
    );
    (samples, answers)
}

/// Brier score and error (%) of `confidence` over `samples`, and over `answers` in all (the
/// settled answers, exact hits, certificates and emptied queues, are counted as right and score
/// 0; only an approximate certificate among them could be wrong).
fn score(samples: &[Sample], answers: usize, confidence: impl Fn(&Sample) -> f64) -> (f64, f64) {
    let (mut brier, mut wrong) = (0.0, 0usize);
    for s in samples {
        let c = confidence(s);
        brier += (c - f64::from(u8::from(s.truth))).powi(2);
        wrong += usize::from((c >= 0.5) != s.truth);
    }
    let n = answers.max(1) as f64;
    (brier / n, 100.0 * wrong as f64 / n)
}

fn main() {
    let mut poses = 60usize;
    let mut quick = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--poses" => {
                poses = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .filter(|&n| n > 0)
                    .unwrap_or_else(|| {
                        eprintln!("error: --poses needs a positive number");
                        std::process::exit(2)
                    })
            }
            "--quick" => quick = true,
            other => {
                eprintln!("error: unknown argument `{other}` (known: --poses N, --quick)");
                std::process::exit(2);
            }
        }
    }
    let mut training = training_pairs();
    let mut held_out = held_out_pairs();
    if quick {
        training.truncate(3);
        held_out.truncate(2);
        poses = poses.min(20);
    }
    let budgets: Vec<Budget> = TRAINING_BUDGETS.map(Budget::NodePairs).to_vec();
    let (train, train_answers) = collect("training", &training, &TRAINING_SEEDS, &budgets, poses);
    let Some(model) = AnswerModel::fit(
        &train.iter().map(|s| (s.x, s.truth)).collect::<Vec<_>>(),
        RIDGE,
    ) else {
        eprintln!("error: nothing to fit ({} unsettled answers)", train.len());
        std::process::exit(1);
    };
    println!(
        "training: {} pairs, {} answers, {} unsettled",
        training.len(),
        train_answers,
        train.len()
    );
    println!(
        "fitted weights (AnswerModel::FITTED):\n    weights: {:?},",
        model.weights
    );
    let raw = |s: &Sample| 1.0 / (1.0 + (-s.x[1]).exp());
    let (b0, e0) = score(&train, train_answers, raw);
    let (b1, e1) = score(&train, train_answers, |s| s.reported);
    let (b2, e2) = score(&train, train_answers, |s| model.confidence_of(&s.x));
    println!(
        "training: raw Brier {b0:.4} error {e0:.2} %; reported {b1:.4} / {e1:.2} %; model {b2:.4} / {e2:.2} %"
    );
    let held_budget = [Budget::Time(Duration::from_micros(20))];
    println!("held out (20 µs budget, seeds {HELD_OUT_SEEDS:?}), per pair:");
    for pair in &held_out {
        let (set, answers) = collect(
            "held out",
            std::slice::from_ref(pair),
            &HELD_OUT_SEEDS,
            &held_budget,
            poses,
        );
        let (b0, e0) = score(&set, answers, raw);
        let (b1, e1) = score(&set, answers, |s| s.reported);
        let (b2, e2) = score(&set, answers, |s| model.confidence_of(&s.x));
        println!(
            "  {}: {answers} answers, {} unsettled; raw Brier {b0:.4} error {e0:.2} %; reported {b1:.4} / {e1:.2} %; model {b2:.4} / {e2:.2} %",
            pair.0,
            set.len()
        );
    }
}
