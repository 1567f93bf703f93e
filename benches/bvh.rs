//! BVH build (triangles/s) and refit (the per-frame cost of a deforming mesh).
use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use stochastic_collision::bvh::CollisionMesh;

mod support;

fn bench(c: &mut Criterion) {
    for (name, mesh) in support::bench_meshes() {
        let mut group = c.benchmark_group(format!("bvh/{name}"));
        group
            .sample_size(10)
            .measurement_time(Duration::from_secs(2))
            .warm_up_time(Duration::from_millis(300));
        group.throughput(Throughput::Elements(mesh.triangle_count() as u64));
        group.bench_function("build", |b| {
            b.iter(|| CollisionMesh::new(black_box(mesh.clone())))
        });
        let mut cm = CollisionMesh::new(mesh.clone());
        let size = cm.bvh().root_aabb().extents().length();
        let waves: Vec<Vec<Vec3>> = (0..4)
            .map(|k| {
                mesh.positions()
                    .iter()
                    .map(|p| *p + Vec3::Y * (0.01 * size * (p.x * 7.0 / size + k as f32).sin()))
                    .collect()
            })
            .collect();
        let mut k = 0;
        group.bench_function("set_positions_and_refit", |b| {
            b.iter(|| {
                k = (k + 1) % waves.len();
                cm.set_positions(black_box(&waves[k])).unwrap();
            })
        });
        group.finish();
    }
}

criterion_group!(bvh, bench);
criterion_main!(bvh);
