//! ADB-trees: build throughput (triangles/s, cell counting and calibration fit included) and
//! query time on near-contact poses, next to the exact query on the same poses.
use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use stochastic_collision::adb::{AdbQuery, AdbTree, AdbWorkspace, Budget, adb_intersects};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, intersects};
use stochastic_collision::geometry::Pose;

mod support;

fn bench(c: &mut Criterion) {
    for (name, mesh) in support::bench_meshes() {
        let mut group = c.benchmark_group(format!("adb/{name}"));
        group
            .sample_size(10)
            .measurement_time(Duration::from_secs(3))
            .warm_up_time(Duration::from_millis(300));
        group.throughput(Throughput::Elements(mesh.triangle_count() as u64));
        let cm = CollisionMesh::new(mesh);
        group.bench_function("build", |b| b.iter(|| AdbTree::new(black_box(cm.clone()))));
        let tree = AdbTree::new(cm);
        let poses: Vec<Pose> = support::bench_poses(tree.collision_mesh(), 32)
            .into_iter()
            .map(|p| p.pose)
            .collect();
        group.throughput(Throughput::Elements(poses.len() as u64));
        let mut ws = AdbWorkspace::new();
        for (label, query) in [
            ("calibrated", AdbQuery::default()),
            (
                "calibrated_20us",
                AdbQuery::with_budget(Budget::Time(Duration::from_micros(20))),
            ),
            ("paper", AdbQuery::paper()),
        ] {
            group.bench_function(label, |b| {
                b.iter(|| {
                    poses
                        .iter()
                        .filter(|p| {
                            adb_intersects(&tree, &Pose::IDENTITY, &tree, p, &query, &mut ws)
                                .collides
                        })
                        .count()
                })
            });
        }
        let mut exact_ws = QueryWorkspace::new();
        let m = tree.collision_mesh();
        group.bench_function("exact", |b| {
            b.iter(|| {
                poses
                    .iter()
                    .filter(|p| intersects(m, &Pose::IDENTITY, m, p, &mut exact_ws))
                    .count()
            })
        });
        group.finish();
    }
}

criterion_group!(adb, bench);
criterion_main!(adb);
