//! Stochastic tracking: one frame of self-collision tracking (surface update + step) against
//! the exact self-collision pass (refit + `self_contacts_excluding`, the tracker's thickness and
//! exclusion rings: the same answer the tracker approximates) on the same whirled positions,
//! for a generated tube and the shared cloth and open colon.
use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, self_contacts_excluding};
use stochastic_collision::deform::Whirl;
use stochastic_collision::mesh::{SelfExclusion, TriMesh, generate};
use stochastic_collision::tracking::{TrackedSurface, Tracker, TrackerConfig};

mod support;

fn meshes() -> Vec<(String, TriMesh)> {
    let mut out = vec![("tube".to_string(), generate::tube(0.08, 2.0, 24, 160, true))];
    for file in ["plane_50x50.obj", "large-intestine-sf+-hf-.obj"] {
        if let Some(mesh) = support::shared_mesh(file) {
            out.push((file.trim_end_matches(".obj").to_string(), mesh));
        }
    }
    out
}

fn bench(c: &mut Criterion) {
    for (name, mesh) in meshes() {
        let mut group = c.benchmark_group(format!("tracking/{name}"));
        group
            .sample_size(10)
            .measurement_time(Duration::from_secs(3))
            .warm_up_time(Duration::from_millis(300));
        // Frames of the first episode, where the mesh cuts through itself.
        let whirl = Whirl::new(&mesh, 120, 1);
        let frames: Vec<Vec<glam::Vec3>> = (10..30)
            .map(|f| {
                let mut p = Vec::new();
                whirl.positions(f, &mut p);
                p
            })
            .collect();
        let mut surface = TrackedSurface::new(mesh.clone());
        let config = TrackerConfig::for_surface(&surface);
        let thickness = config.thickness;
        let exclusion = SelfExclusion::new(&mesh, config.exclusion_rings);
        let mut tracker = Tracker::new(config);
        let mut k = 0;
        group.bench_function("tracker_frame", |b| {
            b.iter(|| {
                surface.set_positions(&frames[k % frames.len()]).unwrap();
                k += 1;
                black_box(tracker.step_self(&surface).len())
            })
        });
        let mut cm = CollisionMesh::new(mesh);
        let mut ws = QueryWorkspace::new();
        let mut out = Vec::new();
        let mut k = 0;
        group.bench_function("exact_self_pass", |b| {
            b.iter(|| {
                cm.set_positions(&frames[k % frames.len()]).unwrap();
                k += 1;
                out.clear();
                black_box(
                    self_contacts_excluding(&cm, thickness, &exclusion, &mut ws, &mut out)
                        .expect("the exclusion is built for this mesh"),
                )
            })
        });
        group.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
