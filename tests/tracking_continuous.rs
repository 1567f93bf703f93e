//! Continuous tracking (`TrackerConfig::continuous`) against exact answers: a sheet passing
//! through a sheet in one step, a fold pushed through its base, a fast needle shot through a
//! cloth (the reference is the exact continuous query `ccd::time_of_impact`); motion that
//! never crosses reports nothing; every crossing is a real one (its triangles touch during the
//! step, checked independently with the continuous primitives); runs are reproducible; a
//! deadline cuts the check.

mod common;

use std::time::Instant;

use common::shapes::sheared_fold;

use glam::{DVec3, Quat, Vec3};
use stochastic_collision::bvh::CollisionMesh;
use stochastic_collision::ccd::{
    CcdOptions, CcdScratch, CcdWorkspace, PrimitiveTolerances, RigidMotion, Trajectory,
    edge_edge_time, time_of_impact, vertex_face_time,
};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::{TriMesh, generate};
use stochastic_collision::tracking::{Contact, TrackedSurface, Tracker, TrackerConfig};

fn config(surface: &TrackedSurface, continuous: bool) -> TrackerConfig {
    TrackerConfig {
        continuous,
        ..TrackerConfig::for_surface(surface)
    }
}

/// The earliest time at which triangles `x` of `a` and `y` of `b` touch while every vertex
/// moves on a straight line from `start` to `end` (positions already placed in one frame).
fn touch_time(
    (start_a, end_a): (&[DVec3], &[DVec3]),
    (start_b, end_b): (&[DVec3], &[DVec3]),
    ta: [u32; 3],
    tb: [u32; 3],
) -> Option<f64> {
    let tol = PrimitiveTolerances {
        distance: 1e-9,
        ..PrimitiveTolerances::default()
    };
    let mut scratch = CcdScratch::default();
    let ja = ta.map(|v| Trajectory::new(start_a[v as usize], end_a[v as usize]));
    let jb = tb.map(|v| Trajectory::new(start_b[v as usize], end_b[v as usize]));
    let mut best: Option<f64> = None;
    let mut keep = |t: Option<f64>| {
        if let Some(t) = t {
            best = Some(best.map_or(t, |b: f64| b.min(t)));
        }
    };
    for i in 0..3 {
        keep(vertex_face_time(&jb[i], &ja, &tol, 1.0, &mut scratch));
        keep(vertex_face_time(&ja[i], &jb, &tol, 1.0, &mut scratch));
        for j in 0..3 {
            let ea = [ja[i], ja[(i + 1) % 3]];
            let eb = [jb[j], jb[(j + 1) % 3]];
            keep(edge_edge_time(&ea, &eb, &tol, 1.0, &mut scratch));
        }
    }
    best
}

fn placed(mesh: &TriMesh, pose: &Pose) -> Vec<DVec3> {
    mesh.positions()
        .iter()
        .map(|&p| pose.transform_point(p).as_dvec3())
        .collect()
}

/// Every contact with a time of impact is a real crossing: its triangles touch during the step
/// at about that time (never before the exact time by more than the tolerance).
fn check_crossings(
    contacts: &[Contact],
    a: (&TriMesh, &[DVec3], &[DVec3]),
    b: (&TriMesh, &[DVec3], &[DVec3]),
) -> usize {
    let mut n = 0;
    for c in contacts {
        let Some(t) = c.time_of_impact else { continue };
        n += 1;
        let exact = touch_time(
            (a.1, a.2),
            (b.1, b.2),
            a.0.triangles()[c.triangle_a as usize],
            b.0.triangles()[c.triangle_b as usize],
        )
        .unwrap_or_else(|| panic!("{c:?}: its triangles never touch during the step"));
        assert!(
            (t as f64 - exact).abs() < 1e-4,
            "{c:?}: time of impact {t}, exact {exact}"
        );
        assert!((0.0..1.0).contains(&t));
        assert!(c.point_a.is_finite() && c.point_b.is_finite() && c.depth.is_finite());
        assert!((c.normal.length() - 1.0).abs() < 1e-3, "{c:?}");
        assert!(c.depth >= 0.0);
    }
    n
}

fn earliest(contacts: &[Contact]) -> Option<f32> {
    contacts
        .iter()
        .filter_map(|c| c.time_of_impact)
        .min_by(f32::total_cmp)
}

/// A sheet tilted a little (so that its triangles cross the other at different times) goes
/// from above a sheet to below it in one step: the discrete tracker sees nothing, the
/// continuous one reports the crossing at the exact query's time of impact.
#[test]
fn a_sheet_passing_through_a_sheet_in_one_step_is_caught() {
    let mesh = generate::cloth_grid(1.0, 1.0, 16, 16);
    let sheet = TrackedSurface::new(mesh.clone());
    let tilt = Quat::from_rotation_x(0.1);
    let above = Pose::new(Vec3::new(0.07, 0.15, 0.02), tilt);
    let below = Pose::new(Vec3::new(0.07, -0.25, 0.02), tilt);
    for continuous in [false, true] {
        let mut tracker = Tracker::new(config(&sheet, continuous));
        for _ in 0..3 {
            let c = tracker.step_pair(&sheet, &Pose::IDENTITY, &sheet, &above);
            assert!(c.is_empty(), "apart above: {c:?}");
        }
        let contacts = tracker
            .step_pair(&sheet, &Pose::IDENTITY, &sheet, &below)
            .to_vec();
        if !continuous {
            assert!(contacts.is_empty(), "the discrete tracker misses it");
            assert_eq!(tracker.stats().swept, 0);
            continue;
        }
        let start = placed(&mesh, &above);
        let end = placed(&mesh, &below);
        let still = placed(&mesh, &Pose::IDENTITY);
        let n = check_crossings(&contacts, (&mesh, &still, &still), (&mesh, &start, &end));
        assert!(
            n > 0 && tracker.stats().crossings > 0,
            "{:?}",
            tracker.stats()
        );
        let cm = CollisionMesh::new(mesh.clone());
        let reference = time_of_impact(
            &cm,
            &RigidMotion::still(Pose::IDENTITY),
            &cm,
            &RigidMotion::new(above, below),
            &CcdOptions::default(),
            &mut CcdWorkspace::default(),
        )
        .unwrap()
        .expect("the exact query sees the crossing");
        let t = earliest(&contacts).unwrap();
        assert!(
            (t - reference.time).abs() < 1e-3,
            "earliest crossing {t}, exact {}",
            reference.time
        );
        // The normal points to where the second sheet came from.
        for c in contacts.iter().filter(|c| c.time_of_impact.is_some()) {
            assert!(c.normal.y > 0.5, "{c:?}");
        }
    }
}

/// A needle (a thin capped tube) shot along its axis through a cloth: it is above the cloth
/// at one step and wholly below at the next. The continuous tracker reports the crossing,
/// its earliest time within 1e-3 of the exact query's; a fresh tracker given the motion
/// explicitly (`step_pair_moving_until`) does the same.
#[test]
fn a_fast_needle_through_a_cloth_is_caught_at_its_time_of_impact() {
    let cloth_mesh = generate::cloth_grid(1.0, 1.0, 24, 24);
    let needle_mesh = generate::tube(0.01, 0.3, 8, 6, true);
    let cloth = TrackedSurface::new(cloth_mesh.clone());
    let needle = TrackedSurface::new(needle_mesh.clone());
    let tilt = Quat::from_rotation_z(0.3);
    let far = Pose::new(Vec3::new(0.013, 1.2, -0.021), tilt);
    let above = Pose::new(Vec3::new(0.013, 0.3, -0.021), tilt);
    let below = Pose::new(Vec3::new(0.013, -0.6, -0.021), tilt);
    let reference = time_of_impact(
        &CollisionMesh::new(cloth_mesh.clone()),
        &RigidMotion::still(Pose::IDENTITY),
        &CollisionMesh::new(needle_mesh.clone()),
        &RigidMotion::new(above, below),
        &CcdOptions::default(),
        &mut CcdWorkspace::default(),
    )
    .unwrap()
    .expect("the needle crosses the cloth");

    let still = placed(&cloth_mesh, &Pose::IDENTITY);
    let (start, end) = (placed(&needle_mesh, &above), placed(&needle_mesh, &below));
    let check = |contacts: &[Contact], what: &str| {
        let n = check_crossings(
            contacts,
            (&cloth_mesh, &still, &still),
            (&needle_mesh, &start, &end),
        );
        assert!(n > 0, "{what}: the crossing is reported");
        let t = earliest(contacts).unwrap();
        assert!(
            (t - reference.time).abs() < 1e-3,
            "{what}: earliest crossing {t}, exact {}",
            reference.time
        );
    };

    let mut discrete = Tracker::new(config(&cloth, false));
    let mut continuous = Tracker::new(config(&cloth, true));
    for pose in [far, above] {
        assert!(
            discrete
                .step_pair(&cloth, &Pose::IDENTITY, &needle, &pose)
                .is_empty()
        );
        assert!(
            continuous
                .step_pair(&cloth, &Pose::IDENTITY, &needle, &pose)
                .is_empty()
        );
    }
    assert!(
        discrete
            .step_pair(&cloth, &Pose::IDENTITY, &needle, &below)
            .is_empty(),
        "the discrete tracker misses it"
    );
    let contacts = continuous
        .step_pair(&cloth, &Pose::IDENTITY, &needle, &below)
        .to_vec();
    check(&contacts, "stepped");

    let mut fresh = Tracker::new(config(&cloth, true));
    let contacts = fresh
        .step_pair_moving_until(
            &cloth,
            &RigidMotion::still(Pose::IDENTITY),
            &needle,
            &RigidMotion::new(above, below),
            None,
        )
        .to_vec();
    check(&contacts, "given the motion");
}

/// A flap folded over its sheet is pushed through the sheet in one step (from above it to
/// below it, the fold line fixed): self-collision tracking sees it only when continuous, at
/// the time the flat part crosses (half the step).
#[test]
fn a_fold_pushed_through_its_sheet_between_two_steps_is_caught() {
    let flat = generate::cloth_grid(1.0, 1.0, 20, 20);
    let (up, down) = (sheared_fold(&flat, 0.04), sheared_fold(&flat, -0.04));
    let mut surface = TrackedSurface::new(flat.clone());
    surface.set_positions(&up).unwrap();
    let mut found = Vec::new();
    for continuous in [false, true] {
        let mut s = surface.clone();
        let mut tracker = Tracker::new(config(&s, continuous));
        for _ in 0..4 {
            s.set_positions(&up).unwrap();
            tracker.step_self(&s);
        }
        assert!(
            tracker.contacts().is_empty(),
            "apart: {:?}",
            tracker.contacts()
        );
        s.set_positions(&down).unwrap();
        let contacts = tracker.step_self(&s).to_vec();
        found.push(contacts);
    }
    assert!(
        found[0].is_empty(),
        "the discrete tracker sees nothing: {:?}",
        found[0]
    );
    let contacts = &found[1];
    let start: Vec<DVec3> = up.iter().map(|p| p.as_dvec3()).collect();
    let end: Vec<DVec3> = down.iter().map(|p| p.as_dvec3()).collect();
    let n = check_crossings(contacts, (&flat, &start, &end), (&flat, &start, &end));
    assert!(n >= 4, "{n} crossings: {contacts:?}");
    let t = earliest(contacts).unwrap();
    assert!(t <= 0.5 + 1e-3, "earliest {t}");
}

/// A sheet sliding sideways over another (never closer than a tenth of an edge more than the
/// thickness) crosses nothing, and a tracked contact that stays is not given a time of impact.
#[test]
fn motion_that_never_crosses_reports_no_crossing() {
    let mesh = generate::cloth_grid(1.0, 1.0, 12, 12);
    let sheet = TrackedSurface::new(mesh.clone());
    let cfg = config(&sheet, true);
    let gap = cfg.thickness * 2.0;
    let mut tracker = Tracker::new(cfg);
    for k in 0..8 {
        let pose = Pose::from_translation(Vec3::new(0.07 * k as f32, gap, 0.01 * k as f32));
        let contacts = tracker.step_pair(&sheet, &Pose::IDENTITY, &sheet, &pose);
        assert!(contacts.is_empty(), "step {k}: {contacts:?}");
        assert_eq!(tracker.stats().crossings, 0);
    }
    assert!(tracker.stats().swept > 0, "the pairs were swept");
    // Resting in contact (within the thickness, not moving): contacts, no times of impact.
    let resting = Pose::from_translation(Vec3::new(0.0, 0.5 * gap / 2.0, 0.0));
    for _ in 0..4 {
        let contacts = tracker.step_pair(&sheet, &Pose::IDENTITY, &sheet, &resting);
        assert!(contacts.iter().all(|c| c.time_of_impact.is_none()));
    }
    assert!(!tracker.contacts().is_empty());
}

/// Two runs of the same continuous scene give the same contacts; a deadline already passed
/// sweeps an eighth of the pairs and says so.
#[test]
fn continuous_tracking_is_reproducible_and_cut_by_a_deadline() {
    let mesh = generate::cloth_grid(1.0, 1.0, 16, 16);
    let sheet = TrackedSurface::new(mesh);
    let poses = [0.2f32, 0.1, -0.15, -0.3]
        .map(|y| Pose::new(Vec3::new(0.03, y, 0.05), Quat::from_rotation_z(0.05)));
    let run = || {
        let mut tracker = Tracker::new(config(&sheet, true));
        let mut all = Vec::new();
        for p in &poses {
            all.push(
                tracker
                    .step_pair(&sheet, &Pose::IDENTITY, &sheet, p)
                    .to_vec(),
            );
        }
        all
    };
    let first = run();
    assert_eq!(first, run());
    assert!(first.iter().flatten().any(|c| c.time_of_impact.is_some()));

    let mut tracker = Tracker::new(config(&sheet, true));
    tracker.step_pair(&sheet, &Pose::IDENTITY, &sheet, &poses[0]);
    tracker.step_pair(&sheet, &Pose::IDENTITY, &sheet, &poses[1]);
    let active = tracker.stats().active;
    tracker.step_pair_until(
        &sheet,
        &Pose::IDENTITY,
        &sheet,
        &poses[2],
        Some(Instant::now()),
    );
    let s = *tracker.stats();
    assert!(s.cut);
    assert_eq!(s.swept + s.sweep_skipped, s.active, "{s:?}");
    assert!(active == 0 || s.sweep_skipped > 0 || s.active <= 1, "{s:?}");
    assert!(s.swept <= s.active.div_ceil(8), "{s:?}");
}
