//! The exact triangle–triangle test and triangle–triangle closest points, on random pairs
//! (overlapping boxes: about a quarter intersect; and far apart) and on touching and coplanar
//! pairs.
use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::geometry::{closest_points_triangle_triangle, triangles_intersect};

fn random_pairs(n: usize, spread: f64) -> Vec<([DVec3; 3], [DVec3; 3])> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(1);
    let mut p = |c: f64| {
        DVec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ) + c
    };
    (0..n)
        .map(|_| ([p(0.0), p(0.0), p(0.0)], [p(spread), p(spread), p(spread)]))
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("triangles_intersect");
    for (name, spread) in [("random_mixed", 0.0), ("mostly_apart", 2.5)] {
        let pairs = random_pairs(1024, spread);
        let hits = pairs
            .iter()
            .filter(|(a, b)| triangles_intersect(a, b))
            .count();
        eprintln!("{name}: {hits}/1024 intersect");
        group.throughput(criterion::Throughput::Elements(pairs.len() as u64));
        group.bench_function(name, |b| {
            b.iter(|| {
                pairs
                    .iter()
                    .filter(|(x, y)| triangles_intersect(black_box(x), black_box(y)))
                    .count()
            })
        });
    }
    // Coplanar and edge-touching: the slow (exact) paths.
    let a = [DVec3::ZERO, DVec3::X, DVec3::Y];
    let coplanar = [
        DVec3::new(0.5, 0.5, 0.0),
        DVec3::new(1.5, 0.2, 0.0),
        DVec3::new(0.2, 1.5, 0.0),
    ];
    let touching = [
        DVec3::new(0.5, 0.5, 0.0),
        DVec3::new(0.5, 0.5, 1.0),
        DVec3::new(1.5, 1.5, 0.5),
    ];
    group.throughput(criterion::Throughput::Elements(1));
    group.bench_function("coplanar", |b| {
        b.iter(|| triangles_intersect(black_box(&a), black_box(&coplanar)))
    });
    group.bench_function("edge_touching", |b| {
        b.iter(|| triangles_intersect(black_box(&a), black_box(&touching)))
    });
    group.finish();

    let mut group = c.benchmark_group("closest_points_triangle_triangle");
    let pairs = random_pairs(1024, 2.5);
    group.throughput(criterion::Throughput::Elements(pairs.len() as u64));
    group.bench_function("mostly_apart", |b| {
        b.iter(|| {
            pairs
                .iter()
                .map(|(x, y)| closest_points_triangle_triangle(black_box(x), black_box(y)).distance)
                .sum::<f64>()
        })
    });
    group.finish();
}

criterion_group!(primitives, bench);
criterion_main!(primitives);
