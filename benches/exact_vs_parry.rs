//! Exact mesh–mesh `intersects` on near-contact poses, side by side with parry3d's
//! `intersection_test` on the same meshes and poses, and BVH build against parry's TriMesh build.
//! The table also times the crate's best exact query (`adb::exact_intersects` on ADB-trees) and
//! counts, pose by pose, where either of ours answers differently from parry3d.
//!
//! `cargo bench --bench exact_vs_parry` runs the criterion groups, then prints a table of
//! per-query medians and the ratio ours / parry (`docs/performance.md` quotes it).
use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group};
use parry3d::math::Pose as ParryPose;
use parry3d::query::intersection_test;
use parry3d::shape::TriMesh as ParryMesh;
use stochastic_collision::adb::{AdbTree, AdbWorkspace, exact_intersects};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, intersects};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::TriMesh;

mod support;

const POSES: usize = 48;

struct Case {
    name: String,
    triangles: usize,
    ours: CollisionMesh,
    /// The same mesh's ADB-tree, for the best exact query.
    adb: AdbTree,
    parry: ParryMesh,
    poses: Vec<Pose>,
}

fn parry_mesh(mesh: &TriMesh) -> ParryMesh {
    ParryMesh::new(mesh.positions().to_vec(), mesh.triangles().to_vec()).expect("valid mesh")
}

fn parry_pose(p: &Pose) -> ParryPose {
    ParryPose::from_parts(p.translation, p.rotation)
}

fn cases() -> Vec<Case> {
    support::bench_meshes()
        .into_iter()
        .map(|(name, mesh)| {
            let ours = CollisionMesh::new(mesh.clone());
            let poses = support::bench_poses(&ours, POSES)
                .into_iter()
                .map(|p| p.pose)
                .collect();
            Case {
                name,
                triangles: mesh.triangle_count(),
                parry: parry_mesh(&mesh),
                adb: AdbTree::new(ours.clone()),
                ours,
                poses,
            }
        })
        .collect()
}

fn bench_queries(c: &mut Criterion, cases: &[Case]) {
    for case in cases {
        let mut group = c.benchmark_group(format!("intersects/{}", case.name));
        group
            .sample_size(20)
            .measurement_time(Duration::from_secs(2))
            .warm_up_time(Duration::from_millis(500));
        let mut ws = QueryWorkspace::new();
        group.bench_function("ours", |bench| {
            bench.iter(|| {
                case.poses
                    .iter()
                    .filter(|p| intersects(&case.ours, &Pose::IDENTITY, &case.ours, p, &mut ws))
                    .count()
            })
        });
        group.bench_function("parry", |bench| {
            bench.iter(|| {
                case.poses
                    .iter()
                    .filter(|p| {
                        intersection_test(
                            &ParryPose::IDENTITY,
                            &case.parry,
                            &parry_pose(p),
                            &case.parry,
                        )
                        .expect("supported")
                        .intersecting
                    })
                    .count()
            })
        });
        group.finish();
    }
}

fn bench_build(c: &mut Criterion, cases: &[Case]) {
    for case in cases {
        let mut group = c.benchmark_group(format!("build/{}", case.name));
        group
            .sample_size(10)
            .measurement_time(Duration::from_secs(2))
            .warm_up_time(Duration::from_millis(300));
        group.throughput(criterion::Throughput::Elements(case.triangles as u64));
        let mesh = case.ours.mesh();
        group.bench_function("ours", |bench| {
            bench.iter(|| CollisionMesh::new(black_box(mesh.clone())))
        });
        group.bench_function("parry", |bench| bench.iter(|| parry_mesh(black_box(mesh))));
        group.finish();
    }
}

/// Median of per-pose medians (each pose timed `REPEATS` times): robust to noise on a shared machine.
fn median_query_ns(poses: &[Pose], mut query: impl FnMut(&Pose) -> bool) -> (f64, usize) {
    const REPEATS: usize = 15;
    let mut per_pose = Vec::with_capacity(poses.len());
    let mut hits = 0;
    for p in poses {
        let mut times = [0f64; REPEATS];
        for t in &mut times {
            let start = Instant::now();
            let hit = black_box(query(black_box(p)));
            *t = start.elapsed().as_nanos() as f64;
            hits += usize::from(hit);
        }
        times.sort_by(f64::total_cmp);
        per_pose.push(times[REPEATS / 2]);
    }
    per_pose.sort_by(f64::total_cmp);
    (per_pose[per_pose.len() / 2], hits / REPEATS)
}

fn median_build_ns(mut build: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..7)
        .map(|_| {
            let start = Instant::now();
            build();
            start.elapsed().as_nanos() as f64
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[3]
}

fn print_table(cases: &[Case]) {
    println!(
        "\n## exact intersects vs parry3d {POSES} near-contact poses per mesh (offsets within ±2% of size)\n"
    );
    println!(
        "| mesh | triangles | colliding | ours median µs | best exact median µs | parry median µs | ratio | best exact ratio | poses unlike parry | best exact unlike ours | ours build ms | parry build ms | build ratio |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for case in cases {
        let mut ws = QueryWorkspace::new();
        let mut adb_ws = AdbWorkspace::new();
        let parry_answer = |p: &Pose| {
            intersection_test(
                &ParryPose::IDENTITY,
                &case.parry,
                &parry_pose(p),
                &case.parry,
            )
            .expect("supported")
            .intersecting
        };
        let (ours, hits_ours) = median_query_ns(&case.poses, |p| {
            intersects(&case.ours, &Pose::IDENTITY, &case.ours, p, &mut ws)
        });
        let (best, _) = median_query_ns(&case.poses, |p| {
            exact_intersects(&case.adb, &Pose::IDENTITY, &case.adb, p, &mut adb_ws)
        });
        let (parry, hits_parry) = median_query_ns(&case.poses, parry_answer);
        // Pose by pose: where the exact query answers unlike parry3d, and where the best exact
        // query answers unlike the exact query (never, if it is exact).
        let (mut unlike_parry, mut unlike_exact) = (0, 0);
        for p in &case.poses {
            let exact = intersects(&case.ours, &Pose::IDENTITY, &case.ours, p, &mut ws);
            unlike_parry += usize::from(exact != parry_answer(p));
            unlike_exact += usize::from(
                exact_intersects(&case.adb, &Pose::IDENTITY, &case.adb, p, &mut adb_ws) != exact,
            );
        }
        let mesh = case.ours.mesh();
        let build_ours = median_build_ns(|| drop(black_box(CollisionMesh::new(mesh.clone()))));
        let build_parry = median_build_ns(|| drop(black_box(parry_mesh(mesh))));
        let colliding = if hits_ours == hits_parry {
            format!("{hits_ours}/{}", case.poses.len())
        } else {
            format!("{hits_ours} (parry {hits_parry})/{}", case.poses.len())
        };
        println!(
            "| {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.2}× | {:.2}× | {unlike_parry} | {unlike_exact} | {:.1} | {:.1} | {:.2}× |",
            case.name,
            case.triangles,
            colliding,
            ours / 1e3,
            best / 1e3,
            parry / 1e3,
            ours / parry,
            best / parry,
            build_ours / 1e6,
            build_parry / 1e6,
            build_ours / build_parry
        );
    }
}

fn benches(c: &mut Criterion) {
    let cases = cases();
    bench_queries(c, &cases);
    bench_build(c, &cases);
    print_table(&cases);
}

criterion_group!(exact_vs_parry, benches);

fn main() {
    exact_vs_parry();
    Criterion::default().configure_from_args().final_summary();
}
