//! Stochastic closest-feature tracking against exact answers: pairs of meshes, self-collision,
//! plateaus, zero-length edges, adjacency exclusion, boundaries, non-manifold edges,
//! determinism.

mod common;

use glam::{DVec3, Quat, Vec3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, closest_points, intersects};
use stochastic_collision::deform::Whirl;
use stochastic_collision::geometry::{Pose, closest_points_triangle_triangle};
use stochastic_collision::mesh::{Topology, TriMesh, generate};
use stochastic_collision::tracking::{
    Contact, Feature, Sampling, SearchMode, TrackedSurface, Tracker, TrackerConfig,
    triangles_within_rings,
};

fn tri(mesh: &TriMesh, t: u32, pose: &Pose) -> [DVec3; 3] {
    mesh.triangle(t as usize)
        .map(|p| pose.transform_point(p).as_dvec3())
}

/// Every contact is real: its two triangles are within the thickness (recomputed exactly),
/// its numbers are finite, its normal is a unit vector.
fn check_contacts(contacts: &[Contact], a: &TriMesh, pa: &Pose, b: &TriMesh, pb: &Pose, h: f32) {
    for c in contacts {
        let d =
            closest_points_triangle_triangle(&tri(a, c.triangle_a, pa), &tri(b, c.triangle_b, pb));
        assert!(
            d.distance <= h as f64 * (1.0 + 1e-5) + 1e-9,
            "{c:?}: exact {}",
            d.distance
        );
        assert!(
            (d.distance - c.distance as f64).abs() <= 1e-4 * (1.0 + d.distance),
            "{c:?}"
        );
        assert!(c.point_a.is_finite() && c.point_b.is_finite() && c.depth.is_finite());
        assert!((c.normal.length() - 1.0).abs() < 1e-3, "{c:?}");
        assert!(c.depth >= 0.0);
    }
}

#[test]
fn pair_of_meshes_contacts_match_the_exact_query() {
    let ball = generate::icosphere(1.0, 3);
    let cm = CollisionMesh::new(ball.clone());
    let surface = TrackedSurface::new(ball.clone());
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
    let mut ws = QueryWorkspace::new();
    let (mut hits, mut misses) = (0, 0);
    for case in 0..24 {
        let dir = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        )
        .normalize_or(Vec3::X);
        let gap: f32 = rng.random_range(1.9..2.1);
        let pa = Pose::IDENTITY;
        let pb = Pose::new(dir * gap, Quat::from_rotation_y(rng.random_range(0.0..6.0)));
        let exact = intersects(&cm, &pa, &cm, &pb, &mut ws);
        let config = TrackerConfig {
            seed: case,
            ..TrackerConfig::default()
        };
        let mut tracker = Tracker::new(config);
        let mut found = false;
        for _ in 0..5 {
            let contacts = tracker.step_pair(&surface, &pa, &surface, &pb);
            check_contacts(contacts, &ball, &pa, &ball, &pb, 0.0);
            found |= !contacts.is_empty();
        }
        assert_eq!(found, exact, "case {case}: tracker {found}, exact {exact}");
        if exact {
            hits += 1
        } else {
            misses += 1
        }
        // Convex meshes: the locally closest pair is the globally closest one.
        if !exact {
            let d = closest_points(&cm, &pa, &cm, &pb, f32::INFINITY, &mut ws)
                .unwrap()
                .distance;
            let best = tracker.pairs().first().expect("a pair survives").distance;
            assert!(
                (best - d as f64).abs() <= 1e-3 * (1.0 + d as f64),
                "case {case}: {best} vs {d}"
            );
        }
    }
    assert!(
        hits > 3 && misses > 3,
        "both outcomes exercised: {hits} hits, {misses} misses"
    );
}

#[test]
fn both_search_variants_end_at_local_minima() {
    let ball = generate::icosphere(1.0, 2);
    let surface = TrackedSurface::new(ball.clone());
    let pa = Pose::IDENTITY;
    let pb = Pose::new(Vec3::new(2.3, 0.4, -0.2), Quat::from_rotation_z(0.3));
    let cm = CollisionMesh::new(ball.clone());
    let d = closest_points(
        &cm,
        &pa,
        &cm,
        &pb,
        f32::INFINITY,
        &mut QueryWorkspace::new(),
    )
    .unwrap()
    .distance as f64;
    for search in [SearchMode::Full, SearchMode::TwoStep] {
        for sampling in [Sampling::Uniform, Sampling::Velocity, Sampling::Hierarchy] {
            let config = TrackerConfig {
                search,
                sampling,
                pairs_per_frame: 8,
                ..TrackerConfig::default()
            };
            let mut tracker = Tracker::new(config);
            for _ in 0..4 {
                tracker.step_pair(&surface, &pa, &surface, &pb);
            }
            if sampling == Sampling::Hierarchy {
                // No patches within the margin: no contact possible, nothing drawn.
                assert!(tracker.pairs().is_empty() && tracker.stats().sampled == 0);
                continue;
            }
            let best = tracker.pairs().first().expect("pairs survive").distance;
            assert!(
                (best - d).abs() < 1e-3,
                "{search:?}/{sampling:?}: {best} vs {d}"
            );
            assert!(tracker.contacts().is_empty());
        }
    }
}

/// A cloth whose part beyond `x = fold_at` is turned over the other part: at height `lift`
/// (negative: below) at the fold, rising with the distance from the fold so that it cuts
/// through the flat part a quarter of the way out.
fn folded_cloth(n: u32, fold_at: f32, lift: f32) -> (TriMesh, Vec<Vec3>) {
    let flat = generate::cloth_grid(1.0, 1.0, n, n);
    let folded = flat
        .positions()
        .iter()
        .map(|p| {
            if p.x > fold_at {
                Vec3::new(
                    2.0 * fold_at - p.x,
                    lift * (1.0 - 4.0 * (p.x - fold_at)),
                    p.z,
                )
            } else {
                *p
            }
        })
        .collect();
    (flat, folded)
}

/// The folded cloth of 24 × 24 cells as a tracked surface, and its folded positions.
fn folded_surface() -> (TrackedSurface, Vec<Vec3>) {
    let (flat, folded) = folded_cloth(24, 0.1, -0.02);
    let mut surface = TrackedSurface::new(flat);
    surface.set_positions(&folded).unwrap();
    (surface, folded)
}

#[test]
fn self_collision_of_a_folded_cloth_reports_only_real_contacts() {
    let (surface, _) = folded_surface();
    let config = TrackerConfig::for_surface(&surface);
    let h = config.thickness;
    let mut tracker = Tracker::new(config);
    let mut seen = 0;
    let moved = surface.mesh().clone();
    for _ in 0..6 {
        let contacts = tracker.step_self(&surface);
        check_contacts(
            contacts,
            &moved,
            &Pose::IDENTITY,
            &moved,
            &Pose::IDENTITY,
            h,
        );
        seen += contacts.len();
        let topo = surface.topology();
        for c in contacts {
            let (a, b) = (
                moved.triangles()[c.triangle_a as usize],
                moved.triangles()[c.triangle_b as usize],
            );
            assert!(
                !triangles_within_rings(topo, a, b, 1),
                "adjacent pair reported: {c:?}"
            );
        }
    }
    assert!(seen > 0, "the fold's crossing was not found");
    assert!(
        tracker.contacts().iter().any(|c| c.propagated),
        "propagation extends contacts"
    );
}

#[test]
fn a_passed_deadline_cuts_the_search_but_keeps_the_pairs_and_their_contacts_real() {
    let (mut surface, folded) = folded_surface();
    let config = TrackerConfig::for_surface(&surface);
    let (h, n) = (config.thickness, config.pairs_per_frame);
    let mut tracker = Tracker::new(config.clone());
    let mut twin = Tracker::new(config.clone());
    // No deadline is the plain step, bit for bit.
    for _ in 0..4 {
        let a = tracker.step_self_until(&surface, None).to_vec();
        assert_eq!(a, twin.step_self(&surface));
        assert!(!tracker.stats().cut);
    }
    let kept = tracker.pairs().len();
    assert!(kept >= 8, "{kept} pairs");
    // The cloth moves on; the deadline has passed before the step begins.
    let moved: Vec<Vec3> = folded
        .iter()
        .map(|p| *p + Vec3::new(0.0, 0.001, 0.0))
        .collect();
    surface.set_positions(&moved).unwrap();
    let past = std::time::Instant::now();
    let contacts = tracker.step_self_until(&surface, Some(past)).to_vec();
    let stats = *tracker.stats();
    assert!(stats.cut);
    assert!(
        stats.sampled <= n.div_ceil(8),
        "{} new pairs",
        stats.sampled
    );
    assert!(
        stats.propagated <= config.propagation_limit.div_ceil(8),
        "{} propagated past the deadline",
        stats.propagated
    );
    assert!(
        stats.remeasured >= kept * 3 / 4,
        "{} of {kept} kept pairs re-measured",
        stats.remeasured
    );
    assert!(tracker.pairs().iter().all(|p| p.distance.is_finite()));
    // Its contacts are measured at the new positions: real, within the thickness.
    let mesh = surface.mesh().clone();
    check_contacts(&contacts, &mesh, &Pose::IDENTITY, &mesh, &Pose::IDENTITY, h);
    assert!(!contacts.is_empty(), "the fold's contacts are kept");
    // With time again, the step searches and draws as before.
    tracker.step_self_until(&surface, None);
    assert!(!tracker.stats().cut && tracker.stats().sampled > stats.sampled);
    // A tracker that is late from its first step on still finds the fold, more slowly.
    let mut starved = Tracker::new(config.clone());
    let found = (0..64).any(|_| {
        !starved
            .step_self_until(&surface, Some(std::time::Instant::now()))
            .is_empty()
    });
    assert!(
        found,
        "a tracker always over its budget never found the fold"
    );
}

#[test]
fn flat_and_curved_sheets_alone_have_no_self_contacts() {
    // Adjacency exclusion: with a thickness of half an edge, neighbours would all "touch".
    for mesh in [
        generate::cloth_grid(1.0, 1.0, 20, 20),
        generate::icosphere(1.0, 3),
        generate::tube(0.3, 1.0, 16, 12, false),
    ] {
        let surface = TrackedSurface::new(mesh.clone());
        let config = TrackerConfig {
            thickness: 0.5 * surface.mean_edge_length(),
            pairs_per_frame: 128,
            ..TrackerConfig::default()
        };
        let mut tracker = Tracker::new(config);
        for _ in 0..5 {
            assert!(tracker.step_self(&surface).is_empty());
        }
        let topo = surface.topology();
        for p in tracker.pairs() {
            let (a, b) = (
                mesh.triangles()[p.triangle_a as usize],
                mesh.triangles()[p.triangle_b as usize],
            );
            assert!(!triangles_within_rings(topo, a, b, 1));
        }
    }
}

#[test]
fn coplanar_plateaus_and_coincident_sheets_terminate_with_finite_distances() {
    // Two parallel 20×20 grids a gap apart: every facing pair is equally close (a plateau);
    // then coincident (gap 0), where every pair touches.
    let sheet = generate::cloth_grid(1.0, 1.0, 20, 20);
    let surface = TrackedSurface::new(sheet.clone());
    for gap in [0.05f32, 0.0, 1e-7] {
        for search in [SearchMode::Full, SearchMode::TwoStep] {
            let config = TrackerConfig {
                search,
                thickness: 0.01,
                max_iterations: 1000,
                ..TrackerConfig::default()
            };
            let mut tracker = Tracker::new(config.clone());
            let pb = Pose::from_translation(Vec3::Y * gap);
            for _ in 0..3 {
                tracker.step_pair(&surface, &Pose::IDENTITY, &surface, &pb);
                let stats = tracker.stats();
                // Strict decrease: no cycling, so far fewer steps than the cap allows.
                let searched = (stats.active + stats.sampled).max(1) as u64;
                assert!(
                    stats.iterations <= searched * 60,
                    "{search:?} gap {gap}: {stats:?}"
                );
                for p in tracker.pairs() {
                    assert!(p.distance.is_finite() && p.distance >= 0.0);
                    assert!(
                        (p.distance - gap as f64).abs() < 1e-5,
                        "{search:?} gap {gap}: {p:?}"
                    );
                }
                check_contacts(
                    tracker.contacts(),
                    &sheet,
                    &Pose::IDENTITY,
                    &sheet,
                    &pb,
                    config.thickness,
                );
            }
            assert_eq!(tracker.contacts().is_empty(), gap > config.thickness);
        }
    }
}

#[test]
fn zero_length_edges_and_huge_or_tiny_scales_stay_finite() {
    // A grid whose middle column is collapsed onto its neighbour: zero-length edges and
    // zero-area triangles, then folded through itself; at scales 1e-4 and 1e4.
    for scale in [1.0f32, 1e-4, 1e4] {
        let (flat, folded) = folded_cloth(16, 0.05, -0.03);
        let collapse = |p: Vec3| {
            let x = if (p.x - 0.0625).abs() < 1e-4 {
                0.0
            } else {
                p.x
            };
            Vec3::new(x, p.y, p.z) * scale
        };
        let rest: Vec<Vec3> = flat.positions().iter().map(|&p| collapse(p)).collect();
        let mesh = TriMesh::new(rest, flat.triangles().to_vec()).unwrap();
        let mut surface = TrackedSurface::new(mesh);
        let moved: Vec<Vec3> = folded.iter().map(|&p| collapse(p)).collect();
        surface.set_positions(&moved).unwrap();
        let config = TrackerConfig::for_surface(&surface);
        let h = config.thickness;
        let mut tracker = Tracker::new(config);
        let current = surface.mesh().clone();
        let mut any = false;
        for _ in 0..5 {
            let contacts = tracker.step_self(&surface);
            any |= !contacts.is_empty();
            check_contacts(
                contacts,
                &current,
                &Pose::IDENTITY,
                &current,
                &Pose::IDENTITY,
                h,
            );
            for p in tracker.pairs() {
                assert!(p.distance.is_finite() && p.point_a.is_finite() && p.point_b.is_finite());
            }
        }
        assert!(any, "scale {scale}: no contact found in the fold");
    }
}

fn run_whirl(mesh: &TriMesh, frames: usize, seed: u64) -> Vec<Vec<Contact>> {
    let whirl = Whirl::new(mesh, frames, seed);
    let mut surface = TrackedSurface::new(mesh.clone());
    let mut tracker = Tracker::new(TrackerConfig {
        seed,
        ..TrackerConfig::for_surface(&surface)
    });
    let mut p = Vec::new();
    (0..frames)
        .map(|f| {
            whirl.positions(f, &mut p);
            surface.set_positions(&p).unwrap();
            tracker.step_self(&surface).to_vec()
        })
        .collect()
}

#[test]
fn seeded_runs_are_identical_whatever_thread_runs_them() {
    let mesh = generate::tube(0.1, 1.5, 16, 60, true);
    let here = run_whirl(&mesh, 30, 9);
    let threads: Vec<_> = (0..2)
        .map(|_| {
            let m = mesh.clone();
            std::thread::spawn(move || run_whirl(&m, 30, 9))
        })
        .collect();
    for t in threads {
        assert_eq!(t.join().unwrap(), here);
    }
    assert!(
        here.iter().any(|c| !c.is_empty()),
        "the whirl makes contacts"
    );
    assert_ne!(
        run_whirl(&mesh, 30, 10),
        here,
        "another seed draws other pairs"
    );
}

#[test]
fn boundaries_and_non_manifold_edges_are_handled() {
    // An open tube (two boundary loops) and a "book": two sheets sharing one row of vertices
    // (non-manifold edges), both whirled through themselves.
    let tube = generate::tube(0.1, 1.5, 16, 60, false);
    let page = generate::cloth_grid(1.0, 1.0, 16, 16);
    let n = page.vertex_count() as u32;
    let mut positions = page.positions().to_vec();
    let mut triangles = page.triangles().to_vec();
    // Two more sheets turned up and down about the x = -0.5 edge, sharing its vertices: the
    // edges along it have three triangles.
    for sign in [1.0f32, -1.0] {
        let mut map = Vec::with_capacity(n as usize);
        for (i, p) in page.positions().iter().enumerate() {
            if (p.x + 0.5).abs() < 1e-6 {
                map.push(i as u32);
            } else {
                map.push(positions.len() as u32);
                positions.push(Vec3::new(-0.5 + 0.02 * sign, sign * (p.x + 0.5), p.z));
            }
        }
        triangles.extend(page.triangles().iter().map(|t| t.map(|v| map[v as usize])));
    }
    let book = TriMesh::new(positions, triangles).unwrap();
    assert!(Topology::new(&book).non_manifold_edge_count() > 0);
    for mesh in [tube, book] {
        assert!(Topology::new(&mesh).boundary_edge_count() > 0);
        let frames: Vec<usize> = (0..40).collect();
        assert!(
            whirl_and_check(&mesh, &frames, 2) > 0,
            "the whirl makes contacts"
        );
    }
}

/// Tracks `mesh` whirled (40-frame animation) at `frames`, checking every contact against
/// the exact distance; returns how many contacts were reported.
fn whirl_and_check(mesh: &TriMesh, frames: &[usize], seed: u64) -> usize {
    let whirl = Whirl::new(mesh, 40, seed);
    let mut surface = TrackedSurface::new(mesh.clone());
    let config = TrackerConfig::for_surface(&surface);
    let h = config.thickness;
    let mut tracker = Tracker::new(config);
    let mut p = Vec::new();
    let mut total = 0;
    for &f in frames {
        whirl.positions(f, &mut p);
        surface.set_positions(&p).unwrap();
        let contacts = tracker.step_self(&surface).to_vec();
        total += contacts.len();
        let current = surface.mesh().clone();
        let id = Pose::IDENTITY;
        check_contacts(&contacts, &current, &id, &current, &id, h);
    }
    total
}

#[test]
fn shared_meshes_with_boundaries_and_non_manifold_edges_track_cleanly() {
    for file in ["plane_50x50.obj", "dragon_50k.obj"] {
        let Some(path) = common::shared_mesh(file) else {
            continue;
        };
        let mesh = TriMesh::from_obj(&path).unwrap();
        let topo = Topology::new(&mesh);
        assert!(topo.boundary_edge_count() > 0 || topo.non_manifold_edge_count() > 0);
        whirl_and_check(&mesh, &[0, 8, 12, 16, 20], 4);
    }
}

#[test]
fn close_pairs_of_the_colon_at_rest_lie_within_the_two_excluded_rings() {
    // Why self-collision excludes two rings by default: the shared open colon, undeformed, has
    // triangle pairs closer than the default thickness that share no vertex, and all of them
    // are within two rings of each other: tessellation, not folds.
    let Some(path) = common::shared_mesh("large-intestine-sf+-hf-.obj") else {
        return;
    };
    let mesh = TriMesh::from_obj(&path).unwrap();
    let thickness = TrackerConfig::for_surface(&TrackedSurface::new(mesh.clone())).thickness;
    let cm = CollisionMesh::new(mesh.clone());
    let mut close = Vec::new();
    stochastic_collision::bvh::self_contacts(
        &cm,
        thickness,
        &mut QueryWorkspace::new(),
        &mut close,
    );
    let topo = Topology::new(&mesh);
    let tris = mesh.triangles();
    let beyond = |rings| {
        close
            .iter()
            .filter(|c| {
                !triangles_within_rings(
                    &topo,
                    tris[c.pair.a as usize],
                    tris[c.pair.b as usize],
                    rings,
                )
            })
            .count()
    };
    assert!(
        beyond(0) > 0,
        "pairs one or two rings apart closer than the thickness"
    );
    assert_eq!(beyond(2), 0);
}

#[test]
fn a_time_budget_adapts_the_pairs_per_frame_to_what_it_allows() {
    use std::time::Duration;
    let mesh = generate::tube(0.08, 2.0, 16, 80, true);
    let mut surface = TrackedSurface::new(mesh.clone());
    let whirl = Whirl::new(&mesh, 40, 2);
    let base = TrackerConfig::for_surface(&surface);
    let mut positions = Vec::new();
    // A budget no step can miss: the pairs grow by half each step up to the cap of kept pairs.
    let mut generous = Tracker::new(TrackerConfig {
        time_budget: Some(Duration::from_secs(30)),
        ..base.clone()
    });
    // A budget every step misses: halved each step, down to the floor of 8.
    let mut tiny = Tracker::new(TrackerConfig {
        time_budget: Some(Duration::from_nanos(1)),
        ..base.clone()
    });
    let mut fixed = Tracker::new(base.clone());
    let mut drawn = Vec::new();
    for f in 0..12 {
        whirl.positions(f, &mut positions);
        surface.set_positions(&positions).unwrap();
        drawn.push(generous.pairs_per_frame_now());
        generous.step_self(&surface);
        assert_eq!(generous.stats().pairs_per_frame, drawn[f]);
        assert!(!generous.stats().cut);
        tiny.step_self(&surface);
        assert!(tiny.stats().cut, "every step of the tiny budget is cut");
        fixed.step_self(&surface);
        assert_eq!(fixed.stats().pairs_per_frame, base.pairs_per_frame);
    }
    assert_eq!(
        drawn[0], base.pairs_per_frame,
        "it starts from pairs_per_frame"
    );
    assert!(drawn.windows(2).all(|w| w[1] >= w[0]), "{drawn:?}");
    assert_eq!(
        generous.pairs_per_frame_now(),
        base.max_active_pairs,
        "{drawn:?}"
    );
    assert_eq!(tiny.pairs_per_frame_now(), 8);
    // Contacts stay real under either budget.
    let pose = Pose::IDENTITY;
    let h = base.thickness;
    let current = TriMesh::new(positions.clone(), mesh.triangles().to_vec()).unwrap();
    check_contacts(generous.contacts(), &current, &pose, &current, &pose, h);
    check_contacts(tiny.contacts(), &current, &pose, &current, &pose, h);
}

/// At the default settings the new pairs per frame grow with the candidates where the surface
/// moved: one per `overlaps_per_pair` overlapping patch pairs in the parts that moved, at least
/// `pairs_per_frame`, at most `max_active_pairs`; a surface at rest keeps `pairs_per_frame`;
/// without `overlaps_per_pair` a step draws exactly `pairs_per_frame`. The contacts stay real
/// either way.
#[test]
fn the_default_pairs_per_frame_grow_with_the_overlapping_patch_pairs() {
    let mesh = generate::tube(0.08, 2.0, 16, 80, true);
    let mut surface = TrackedSurface::new(mesh.clone());
    let whirl = Whirl::new(&mesh, 40, 2);
    let base = TrackerConfig::for_surface(&surface);
    assert!(base.overlaps_per_pair.is_some(), "on by default");
    // The tube has 116–236 overlapping patch pairs over these frames.
    let dense = TrackerConfig {
        overlaps_per_pair: Some(2),
        ..base.clone()
    };
    let capped = TrackerConfig {
        overlaps_per_pair: Some(1),
        max_active_pairs: 100,
        ..base.clone()
    };
    let fixed = TrackerConfig {
        overlaps_per_pair: None,
        ..base.clone()
    };
    let mut trackers: Vec<_> = [&base, &dense, &capped, &fixed]
        .into_iter()
        .map(|c| Tracker::new(c.clone()))
        .collect();
    let mut positions = Vec::new();
    let (mut grew, mut floor, mut cap) = (0, 0, 0);
    // 24 frames of motion, then 3 at rest.
    for f in 0..27 {
        whirl.positions(f.min(23), &mut positions);
        surface.set_positions(&positions).unwrap();
        for t in trackers.iter_mut() {
            t.step_self(&surface);
            let (stats, cfg) = (t.stats(), t.config());
            assert!(stats.moved_patch_overlaps <= stats.patch_overlaps);
            if f == 0 {
                assert_eq!(stats.moved_patch_overlaps, stats.patch_overlaps, "all new");
            }
            if f >= 24 {
                assert_eq!(stats.moved_patch_overlaps, 0, "at rest");
            }
            let expected = match cfg.overlaps_per_pair {
                Some(k) => cfg.pairs_per_frame.max(
                    stats
                        .moved_patch_overlaps
                        .div_ceil(k as usize)
                        .min(cfg.max_active_pairs),
                ),
                None => cfg.pairs_per_frame,
            };
            assert_eq!(stats.pairs_per_frame, expected, "frame {f}: {stats:?}");
            assert!(
                stats.sampled <= stats.pairs_per_frame,
                "frame {f}: {stats:?}"
            );
            if cfg.overlaps_per_pair == Some(2) {
                grew += usize::from(stats.pairs_per_frame > cfg.pairs_per_frame);
                floor += usize::from(stats.pairs_per_frame == cfg.pairs_per_frame);
            }
            if cfg.max_active_pairs == 100 {
                cap += usize::from(stats.pairs_per_frame == 100);
                if f >= 24 {
                    assert_eq!(stats.pairs_per_frame, cfg.pairs_per_frame, "at rest");
                }
            }
        }
    }
    assert!(grew > 0, "the coiling tube's candidates raise the pairs");
    assert!(
        floor > 0,
        "the straight tube's few candidates keep the floor"
    );
    assert!(cap > 0, "max_active_pairs bounds the pairs");
    let pose = Pose::IDENTITY;
    let current = TriMesh::new(positions.clone(), mesh.triangles().to_vec()).unwrap();
    for t in &trackers {
        check_contacts(
            t.contacts(),
            &current,
            &pose,
            &current,
            &pose,
            base.thickness,
        );
    }
}

/// The neighbours a local search tries for triangle `t` whose closest feature is `f`: around a
/// closest corner or edge every triangle at those corners, from a face its edge neighbours.
fn search_neighbours(topology: &Topology, t: u32, f: Feature) -> Vec<u32> {
    match f {
        Feature::Vertex(v) => topology.vertex_triangles(v).to_vec(),
        Feature::Edge(e) => topology
            .edge(e)
            .vertices
            .iter()
            .flat_map(|&v| topology.vertex_triangles(v).iter().copied())
            .collect(),
        Feature::Triangle(_) => topology.triangle_neighbours(t).to_vec(),
    }
}

/// Every pair of `tracker` is up to date on `mesh` at `positions` (its distance is its
/// triangles' distance now) and, where its search settled apart, no pair the search would try
/// next (not within the two excluded rings) is closer.
fn assert_pairs_are_what_a_search_leaves(
    tracker: &Tracker,
    mesh: &TriMesh,
    positions: &[Vec3],
    what: &str,
) {
    let topology = Topology::new(mesh);
    let current = TriMesh::new(positions.to_vec(), mesh.triangles().to_vec()).unwrap();
    let triangle = |t: u32| tri(&current, t, &Pose::IDENTITY);
    let corners = |t: u32| mesh.triangles()[t as usize];
    let epsilon = 1e-9 * mesh.aabb().extents().length() as f64;
    for p in tracker.pairs() {
        let (ta, tb) = (p.triangle_a, p.triangle_b);
        let d = closest_points_triangle_triangle(&triangle(ta), &triangle(tb)).distance;
        assert!(
            (d - p.distance).abs() <= 1e-9 * (1.0 + d),
            "{what}: pair ({ta}, {tb})'s distance is out of date: {} against {d}",
            p.distance
        );
        if !p.settled || p.distance <= tracker.config().thickness as f64 {
            continue;
        }
        let neighbours = search_neighbours(&topology, ta, p.feature_a)
            .into_iter()
            .map(|x| (x, tb))
            .chain(
                search_neighbours(&topology, tb, p.feature_b)
                    .into_iter()
                    .map(|y| (ta, y)),
            );
        for (x, y) in neighbours {
            if x == y || triangles_within_rings(&topology, corners(x), corners(y), 2) {
                continue;
            }
            let e = closest_points_triangle_triangle(&triangle(x), &triangle(y)).distance;
            assert!(
                e >= p.distance - epsilon,
                "{what}: settled pair ({ta}, {tb}) at {} has a closer neighbour ({x}, {y}) at {e}",
                p.distance
            );
        }
    }
}

/// In self-collision a kept pair whose search settled and around which nothing moved is kept
/// as it is, without a search: on a folded cloth whose far edge flaps under the fold's tip,
/// the pairs where the fold cuts through the sheet are kept so, and every kept pair is still
/// what a search would leave. A step with nothing moved keeps every settled pair.
#[test]
fn settled_pairs_where_nothing_moved_are_kept_without_a_search() {
    let (mesh, folded) = folded_cloth(24, 0.1, -0.02);
    let mut surface = TrackedSurface::new(mesh.clone());
    // The flat part's far end (under the folded part's tip, 0.008–0.012 below it) flaps.
    let flap = |f: usize| -> Vec<Vec3> {
        mesh.positions()
            .iter()
            .zip(&folded)
            .map(|(rest, p)| {
                if rest.x < -0.25 {
                    *p + Vec3::Y * (0.004 * (f as f32 * 0.7).sin())
                } else {
                    *p
                }
            })
            .collect()
    };
    let config = TrackerConfig {
        seed: 3,
        ..TrackerConfig::for_surface(&surface)
    };
    let mut tracker = Tracker::new(config.clone());
    let (mut still, mut searched) = (0, 0);
    for f in 0..40 {
        let positions = flap(f);
        surface.set_positions(&positions).unwrap();
        tracker.step_self(&surface);
        let stats = tracker.stats();
        still += stats.still;
        searched += stats.active.saturating_sub(stats.still);
        if f == 0 {
            assert_eq!(stats.still, 0, "nothing is known before the first step");
        }
        assert_pairs_are_what_a_search_leaves(&tracker, &mesh, &positions, &format!("frame {f}"));
        let current = TriMesh::new(positions.clone(), mesh.triangles().to_vec()).unwrap();
        let pose = Pose::IDENTITY;
        check_contacts(
            tracker.contacts(),
            &current,
            &pose,
            &current,
            &pose,
            config.thickness,
        );
    }
    assert!(
        still > 0,
        "the pairs where the fold cuts the sheet are kept as they are"
    );
    assert!(
        searched > 0,
        "pairs near the flapping end, and new ones, are searched"
    );
    // Nothing moved: every settled pair is kept as it is.
    let settled = tracker.pairs().iter().filter(|p| p.settled).count();
    tracker.step_self(&surface);
    assert_eq!(tracker.stats().still, settled);
    // Two updates since the last step: what moved in the first is not known, all are searched.
    surface.set_positions(&flap(7)).unwrap();
    surface.set_positions(&flap(7)).unwrap();
    tracker.step_self(&surface);
    assert_eq!(
        tracker.stats().still,
        0,
        "an update the tracker did not see"
    );
}

/// A settled pair apart is searched again when a vertex of a triangle its search tries moves,
/// though its own triangles stay: a cloth folded flat over itself at a gap of 2.5 thicknesses
/// settles into pairs apart; one vertex next to such a pair moved halfway to its partner makes
/// the search move on, and every pair is again what a search would leave.
#[test]
fn a_settled_pair_is_searched_again_when_a_neighbour_moves() {
    let flat = generate::cloth_grid(1.0, 1.0, 24, 24);
    let mut surface = TrackedSurface::new(flat.clone());
    let config = TrackerConfig {
        seed: 5,
        ..TrackerConfig::for_surface(&surface)
    };
    let gap = 2.5 * config.thickness;
    let mut positions: Vec<Vec3> = flat
        .positions()
        .iter()
        .map(|p| {
            if p.x > 0.1 {
                Vec3::new(0.2 - p.x, gap, p.z)
            } else {
                *p
            }
        })
        .collect();
    surface.set_positions(&positions).unwrap();
    let mut tracker = Tracker::new(config.clone());
    for _ in 0..6 {
        tracker.step_self(&surface);
    }
    assert!(tracker.contacts().is_empty(), "the sheets are apart");
    assert_pairs_are_what_a_search_leaves(&tracker, &flat, &positions, "at rest");
    let settled = tracker.pairs().iter().filter(|p| p.settled).count();
    tracker.step_self(&surface);
    assert!(settled > 0, "{:?}", tracker.stats());
    assert_eq!(
        tracker.stats().still,
        settled,
        "nothing moved: every settled pair kept"
    );
    let settled = tracker.pairs().iter().filter(|p| p.settled).count();
    let topology = Topology::new(&flat);
    let p = *tracker
        .pairs()
        .iter()
        .find(|p| p.settled)
        .expect("a settled pair apart");
    let own = |v: &u32| {
        flat.triangles()[p.triangle_a as usize].contains(v)
            || flat.triangles()[p.triangle_b as usize].contains(v)
    };
    let v = search_neighbours(&topology, p.triangle_a, p.feature_a)
        .iter()
        .flat_map(|&x| flat.triangles()[x as usize])
        .find(|v| !own(v))
        .expect("a neighbour vertex");
    positions[v as usize] = p.point_a.lerp(p.point_b, 0.5).as_vec3();
    surface.set_positions(&positions).unwrap();
    tracker.step_self(&surface);
    assert!(
        tracker.stats().still < settled,
        "the moved vertex's neighbours are searched"
    );
    assert_pairs_are_what_a_search_leaves(&tracker, &flat, &positions, "a neighbour moved");
}

/// In self-collision the candidates are kept between steps and follow the motion, at the
/// default settings (every list whose blocks moved is made again) and under a time budget
/// alike: the first step makes every list, a step on a surface at rest refreshes none, a
/// corner's motion a few (those of the blocks it reached), a fold more, and the fold's
/// contacts are found (and real). Between two meshes nothing is kept.
#[test]
fn self_collision_candidate_work_follows_the_motion() {
    use std::time::Duration;
    let flat = generate::cloth_grid(1.0, 1.0, 48, 48);
    for budget in [None, Some(Duration::from_secs(30))] {
        let mut cloth = TrackedSurface::with_patch_size(flat.clone(), 4);
        let base = TrackerConfig::for_surface(&cloth);
        let mut tracker = Tracker::new(TrackerConfig {
            time_budget: budget,
            ..base.clone()
        });
        tracker.step_self(&cloth);
        let lists = tracker.stats().candidate_lists;
        assert!(lists >= 100, "{lists}");
        assert_eq!(tracker.stats().candidate_lists_refreshed, lists);
        tracker.step_self(&cloth);
        assert_eq!(
            tracker.stats().candidate_lists_refreshed,
            0,
            "nothing moved ({budget:?})"
        );
        let mut moved = flat.positions().to_vec();
        moved[0].y += 0.01;
        cloth.set_positions(&moved).unwrap();
        tracker.step_self(&cloth);
        let corner = tracker.stats().candidate_lists_refreshed;
        assert!(corner >= 1 && corner < lists / 4, "{corner} of {lists}");
        // The right half folded over the left, a little above it: contacts between the layers.
        let folded: Vec<Vec3> = flat
            .positions()
            .iter()
            .map(|p| {
                if p.x > 0.1 {
                    Vec3::new(0.2 - p.x, 0.5 * base.thickness, p.z)
                } else {
                    *p
                }
            })
            .collect();
        cloth.set_positions(&folded).unwrap();
        tracker.step_self(&cloth);
        assert!(tracker.stats().candidate_lists_refreshed > corner);
        for _ in 0..4 {
            tracker.step_self(&cloth);
        }
        assert_eq!(tracker.stats().candidate_lists_refreshed, 0);
        let fold = TriMesh::new(folded, flat.triangles().to_vec()).unwrap();
        assert!(!tracker.contacts().is_empty());
        let pose = Pose::IDENTITY;
        check_contacts(
            tracker.contacts(),
            &fold,
            &pose,
            &fold,
            &pose,
            base.thickness,
        );
        let mut pair = Tracker::new(base);
        let other = TrackedSurface::new(flat.clone());
        pair.step_pair(&cloth, &pose, &other, &Pose::from_translation(Vec3::Y));
        assert_eq!(pair.stats().candidate_lists, 0);
        assert_eq!(pair.stats().candidate_lists_refreshed, 0);
    }
}

/// Velocity sampling between two meshes weighs their relative rigid motion: a rod turning
/// about a hinge above a plate sweeps its tip through the plate; the tracker finds real
/// contacts on the way, the same ones on a second run with the same seed.
#[test]
fn velocity_sampling_follows_a_turning_rigid_body_into_contact() {
    let plate = generate::cloth_grid(2.0, 2.0, 24, 24);
    let rod = generate::tube(0.05, 1.0, 8, 24, true);
    let run = || {
        let (sa, sb) = (
            TrackedSurface::new(plate.clone()),
            TrackedSurface::new(rod.clone()),
        );
        let config = TrackerConfig {
            sampling: Sampling::Velocity,
            thickness: 0.02,
            pairs_per_frame: 32,
            ..TrackerConfig::default()
        };
        let mut tracker = Tracker::new(config);
        let mut found = Vec::new();
        for f in 0..30 {
            // The rod hangs from (0, 0.9, 0) and swings from horizontal down through the plate.
            let angle = f as f32 / 29.0 * std::f32::consts::FRAC_PI_2;
            let rotation = glam::Quat::from_rotation_z(-std::f32::consts::FRAC_PI_2 + angle);
            let hinge = Vec3::new(0.0, 0.9, 0.0);
            let pose_b = Pose::new(hinge - rotation * Vec3::new(0.0, 0.5, 0.0), rotation);
            let contacts = tracker
                .step_pair(&sa, &Pose::IDENTITY, &sb, &pose_b)
                .to_vec();
            check_contacts(&contacts, &plate, &Pose::IDENTITY, &rod, &pose_b, 0.02);
            found.push(contacts.len());
        }
        found
    };
    let first = run();
    assert!(
        first.iter().any(|&n| n > 0),
        "the swinging rod's tip reaches the plate: {first:?}"
    );
    assert_eq!(first, run());
}

/// Guy and Debunne's multiresolution starts (`TrackerConfig::multiresolution`): on a tube
/// whirled through itself, the new pairs first moved over vertices find contacts in the
/// frames where searching every new pair over triangles does, with fewer triangle distances;
/// starts are left at the vertex level (far or sliding), and every contact is real.
#[test]
fn multiresolution_starts_find_the_contacts_with_fewer_triangle_distances() {
    let mesh = generate::tube(0.1, 1.5, 16, 60, true);
    let whirl = Whirl::new(&mesh, 40, 7);
    let run = |multiresolution: bool| {
        let mut surface = TrackedSurface::new(mesh.clone());
        let config = TrackerConfig {
            multiresolution,
            seed: 7,
            ..TrackerConfig::for_surface(&surface)
        };
        let h = config.thickness;
        let mut tracker = Tracker::new(config);
        let mut p = Vec::new();
        let (mut frames_in_contact, mut evaluations, mut left_coarse) = (Vec::new(), 0, 0);
        for f in 0..40 {
            whirl.positions(f, &mut p);
            surface.set_positions(&p).unwrap();
            let contacts = tracker.step_self(&surface).to_vec();
            let current = surface.mesh().clone();
            check_contacts(
                &contacts,
                &current,
                &Pose::IDENTITY,
                &current,
                &Pose::IDENTITY,
                h,
            );
            if !contacts.is_empty() {
                frames_in_contact.push(f);
            }
            let stats = tracker.stats();
            evaluations += stats.evaluations;
            left_coarse += stats.coarse.far + stats.coarse.sliding + stats.coarse.duplicate;
            let c = stats.coarse;
            assert_eq!(
                c.started,
                c.refined + c.far + c.sliding + c.duplicate,
                "frame {f}: {c:?}"
            );
        }
        (frames_in_contact, evaluations, left_coarse)
    };
    let (with, with_evaluations, left) = run(true);
    let (without, without_evaluations, none_left) = run(false);
    assert_eq!(none_left, 0);
    assert!(left > 0);
    assert!(!without.is_empty());
    let missed: Vec<_> = without.iter().filter(|f| !with.contains(f)).collect();
    assert!(
        missed.len() <= without.len() / 10,
        "frames in contact without multiresolution {without:?}, with {with:?}"
    );
    assert!(
        (with_evaluations as f64) < 0.7 * without_evaluations as f64,
        "{with_evaluations} triangle distances with multiresolution, {without_evaluations} without"
    );
}
