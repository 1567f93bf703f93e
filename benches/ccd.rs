//! Continuous collision against the discrete exact query and parry3d's linear `cast_shapes`, on
//! the same meshes and motions: the second mesh approaches a near-contact pose from 0.1 of the
//! objects' size away and ends 0.02 deeper than first contact (the discrete query sees only
//! the end pose); a rotating variant also turns it by 0.3 rad over the step (ours only: parry's
//! linear cast does not rotate).
//!
//! `cargo bench --bench ccd` prints, per mesh, the per-query medians, the ratios, how often
//! our time of impact and parry's agree within 1e-3 of the step, and how each compares with a
//! reference (the discrete exact query on 400 sub-steps, refined by bisection to 1e-6): `=`
//! within 1e-4 of it (the tolerance the continuous query promises), `<` earlier, `>` later or
//! missed, `+` a contact the reference does not see;
//! then the same for the turning motions (parry's nonlinear cast on the first
//! `NONLINEAR_POSES` of them only, once each: it takes up to seconds per query; its time is
//! the median of those).
use std::hint::black_box;
use std::time::Instant;

use glam::{Quat, Vec3};
use parry3d::math::Pose as ParryPose;
use parry3d::query::{NonlinearRigidMotion, ShapeCastOptions, cast_shapes, cast_shapes_nonlinear};
use parry3d::shape::TriMesh as ParryMesh;
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, intersects};
use stochastic_collision::ccd::{CcdOptions, CcdWorkspace, RigidMotion, time_of_impact};
use stochastic_collision::geometry::Pose;

mod support;

const POSES: usize = 16;
const REPEATS: usize = 3;
/// parry3d's nonlinear cast takes up to seconds per query on these meshes: it runs on the first
/// few turning approaches only, once each.
const NONLINEAR_POSES: usize = 4;

/// The median over poses of the fastest of `REPEATS` runs of `f` per pose (seconds).
fn median_time(n: usize, f: impl FnMut(usize)) -> f64 {
    median_time_of(n, REPEATS, f)
}

/// The median over poses of the fastest of `repeats` runs of `f` per pose (seconds).
fn median_time_of(n: usize, repeats: usize, mut f: impl FnMut(usize)) -> f64 {
    let mut times: Vec<f64> = (0..n)
        .map(|k| {
            (0..repeats)
                .map(|_| {
                    let start = Instant::now();
                    f(k);
                    start.elapsed().as_secs_f64()
                })
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[n / 2]
}

fn main() {
    println!(
        "{:<22} {:>8} {:>11} {:>11} {:>11} {:>11} {:>9} {:>9} {:>10} {:>12} {:>12} {:>12} {:>9} {:>12} {:>12}",
        "mesh",
        "tris",
        "discrete",
        "ours lin.",
        "ours rot.",
        "parry lin.",
        "lin/disc",
        "lin/parry",
        "agree",
        "ours =/</>/+",
        "parry =/</>/+",
        "parry rot.",
        "rot/parry",
        "ours rot",
        "parry rot"
    );
    for (name, mesh) in support::bench_meshes() {
        let ours = CollisionMesh::new(mesh.clone());
        let parry = ParryMesh::new(mesh.positions().to_vec(), mesh.triangles().to_vec())
            .expect("valid mesh");
        let approaches = support::bench_poses(&ours, POSES);
        let linear: Vec<RigidMotion> = approaches
            .iter()
            .map(|a| {
                let back = a.direction * 0.1 * a.size;
                let deeper = -a.direction * 0.02 * a.size;
                RigidMotion::new(
                    Pose::new(a.pose.translation + back, a.pose.rotation),
                    Pose::new(a.pose.translation + deeper, a.pose.rotation),
                )
            })
            .collect();
        let turning: Vec<RigidMotion> = linear
            .iter()
            .map(|m| {
                let end = Pose::new(
                    m.end.translation,
                    m.end.rotation * Quat::from_rotation_y(0.3),
                );
                RigidMotion::new(m.start, end)
            })
            .collect();
        let still = RigidMotion::still(Pose::IDENTITY);
        let options = CcdOptions::default();
        let (mut ws, mut ccd_ws) = (QueryWorkspace::new(), CcdWorkspace::new());
        let discrete = median_time(POSES, |k| {
            black_box(intersects(
                &ours,
                &Pose::IDENTITY,
                &ours,
                &linear[k].end,
                &mut ws,
            ));
        });
        let mut ours_times = vec![None; POSES];
        let lin = median_time(POSES, |k| {
            let hit = time_of_impact(&ours, &still, &ours, &linear[k], &options, &mut ccd_ws)
                .expect("finite poses");
            ours_times[k] = hit.map(|h| h.time);
        });
        let mut ours_rot_times = vec![None; POSES];
        let rot = median_time(POSES, |k| {
            let hit = time_of_impact(&ours, &still, &ours, &turning[k], &options, &mut ccd_ws)
                .expect("finite poses");
            ours_rot_times[k] = hit.map(|h| h.time);
        });
        // Ours on the approaches parry's nonlinear cast is timed on, for the ratio.
        let rot_few = median_time(NONLINEAR_POSES, |k| {
            black_box(
                time_of_impact(&ours, &still, &ours, &turning[k], &options, &mut ccd_ws)
                    .expect("finite poses"),
            );
        });
        // parry's nonlinear cast of the same turning motion: rotation at a constant rate about
        // the mesh's origin (its local centre), by 0.3 rad about the turned Y axis.
        let mut parry_rot_times = vec![None; NONLINEAR_POSES];
        // One run per pose, on the first few: each takes up to seconds.
        let parry_rot = median_time_of(NONLINEAR_POSES, 1, |k| {
            let m = &turning[k];
            let moving = NonlinearRigidMotion::new(
                ParryPose::from_parts(m.start.translation, m.start.rotation),
                Vec3::ZERO,
                m.end.translation - m.start.translation,
                m.start.rotation * Vec3::Y * 0.3,
            );
            let fixed =
                NonlinearRigidMotion::new(ParryPose::IDENTITY, Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
            let hit = cast_shapes_nonlinear(&fixed, &parry, &moving, &parry, 0.0, 1.0, true)
                .expect("supported shapes");
            parry_rot_times[k] = hit.map(|h| h.time_of_impact);
        });
        let mut parry_times = vec![None; POSES];
        let cast_options = ShapeCastOptions {
            max_time_of_impact: 1.0,
            target_distance: 0.0,
            stop_at_penetration: true,
            compute_impact_geometry_on_penetration: true,
        };
        let par = median_time(POSES, |k| {
            let m = &linear[k];
            let velocity = m.end.translation - m.start.translation;
            let hit = cast_shapes(
                &ParryPose::IDENTITY,
                Vec3::ZERO,
                &parry,
                &ParryPose::from_parts(m.start.translation, m.start.rotation),
                velocity,
                &parry,
                cast_options,
            )
            .expect("supported shapes");
            parry_times[k] = hit.map(|h| h.time_of_impact);
        });
        // The reference: the discrete exact query on 400 sub-steps, the first hit refined by
        // bisection to 1e-6; an answer is right when within 1e-4 of it (or both find none).
        let reference_of = |motions: &[RigidMotion], ws: &mut QueryWorkspace| -> Vec<Option<f32>> {
            motions
                .iter()
                .map(|m| {
                    let mut hit =
                        |t: f32| intersects(&ours, &Pose::IDENTITY, &ours, &m.at(t), &mut *ws);
                    let first = (0..=400).find(|&k| hit(k as f32 / 400.0))?;
                    if first == 0 {
                        return Some(0.0);
                    }
                    let (mut lo, mut hi) = ((first - 1) as f32 / 400.0, first as f32 / 400.0);
                    while hi - lo > 1e-6 {
                        let mid = 0.5 * (lo + hi);
                        if hit(mid) { hi = mid } else { lo = mid }
                    }
                    Some(hi)
                })
                .collect()
        };
        let reference = reference_of(&linear, &mut ws);
        let turning_reference = reference_of(&turning, &mut ws);
        // Against the reference: within 1e-4 (or both none), earlier, later or missed, or a
        // contact where the reference has none.
        let judge = |times: &[Option<f32>], reference: &[Option<f32>]| {
            let mut v = [0usize; 4];
            for (a, r) in times.iter().zip(reference) {
                let class = match (a, r) {
                    (None, None) => 0,
                    (Some(a), Some(r)) if (a - r).abs() <= 1e-4 => 0,
                    (Some(a), Some(r)) if a < r => 1,
                    (_, Some(_)) => 2,
                    (Some(_), None) => 3,
                };
                v[class] += 1;
            }
            format!("{}/{}/{}/{}", v[0], v[1], v[2], v[3])
        };
        let (ours_right, parry_right) = (
            judge(&ours_times, &reference),
            judge(&parry_times, &reference),
        );
        let (ours_rot_right, parry_rot_right) = (
            judge(&ours_rot_times, &turning_reference),
            judge(&parry_rot_times, &turning_reference[..NONLINEAR_POSES]),
        );
        let agree = ours_times
            .iter()
            .zip(&parry_times)
            .filter(|(a, b)| match (a, b) {
                (Some(a), Some(b)) => (a - b).abs() <= 1e-3,
                (None, None) => true,
                _ => false,
            })
            .count();
        let us = |s: f64| format!("{:.1} µs", s * 1e6);
        println!(
            "{:<22} {:>8} {:>11} {:>11} {:>11} {:>11} {:>8.2}x {:>8.2}x {:>7}/{} {:>12} {:>12} {:>12} {:>8.2}x {:>12} {:>12}",
            name,
            mesh.triangle_count(),
            us(discrete),
            us(lin),
            us(rot),
            us(par),
            lin / discrete,
            lin / par,
            agree,
            POSES,
            ours_right,
            parry_right,
            us(parry_rot),
            rot_few / parry_rot,
            ours_rot_right,
            parry_rot_right
        );
    }
}
