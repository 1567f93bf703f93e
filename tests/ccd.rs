//! Continuous collision: the first time of impact of two moving meshes against a brute-force
//! reference (the discrete exact query on many sub-steps, the first hit refined by bisection),
//! on tunnelling shots through thin walls, rotating bars, random rigid motions and a cloth
//! falling through a ball; and hard cases (touching at the start, reaching contact exactly at
//! the end, no motion, bad input).
use glam::{Quat, Vec3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::bvh::{CollisionMesh, QueryWorkspace, closest_points, intersects};
use stochastic_collision::ccd::{
    CcdError, CcdOptions, CcdWorkspace, RigidMotion, deforming_time_of_impact, time_of_impact,
};
use stochastic_collision::geometry::Pose;
use stochastic_collision::mesh::generate;

/// The first time the meshes intersect (the discrete exact query) on `steps` sub-steps, refined
/// by bisection to 1e-7 between the last sub-step apart and the first one touching.
fn reference_time(
    a: &CollisionMesh,
    ma: &RigidMotion,
    b: &CollisionMesh,
    mb: &RigidMotion,
    steps: usize,
) -> Option<f32> {
    let mut ws = QueryWorkspace::new();
    let mut hit = |t: f32| intersects(a, &ma.at(t), b, &mb.at(t), &mut ws);
    let first = (0..=steps).find(|&k| hit(k as f32 / steps as f32))?;
    if first == 0 {
        return Some(0.0);
    }
    let (mut lo, mut hi) = (
        (first - 1) as f32 / steps as f32,
        first as f32 / steps as f32,
    );
    while hi - lo > 1e-7 {
        let mid = 0.5 * (lo + hi);
        if hit(mid) { hi = mid } else { lo = mid }
    }
    Some(hi)
}

/// Distance between the meshes at time `t`.
fn distance_at(
    a: &CollisionMesh,
    ma: &RigidMotion,
    b: &CollisionMesh,
    mb: &RigidMotion,
    t: f32,
) -> f32 {
    let mut ws = QueryWorkspace::new();
    closest_points(a, &ma.at(t), b, &mb.at(t), f32::INFINITY, &mut ws).map_or(0.0, |d| d.distance)
}

/// Whether a time of impact `t` is on time against an exact or reference time: never later
/// (beyond rounding), and at most 1e-4 of the step earlier (the precision the query promises).
fn on_time(t: f64, reference: f64) -> bool {
    t <= reference + 1e-6 && t >= reference - 1e-4
}

fn toi(
    a: &CollisionMesh,
    ma: &RigidMotion,
    b: &CollisionMesh,
    mb: &RigidMotion,
) -> Option<stochastic_collision::ccd::TimeOfImpact> {
    time_of_impact(
        a,
        ma,
        b,
        mb,
        &CcdOptions::default(),
        &mut CcdWorkspace::new(),
    )
    .unwrap()
}

/// A random vector in the cube `[-s, s)³`.
fn v3(rng: &mut Xoshiro256PlusPlus, s: f32) -> Vec3 {
    Vec3::new(
        rng.random_range(-s..s),
        rng.random_range(-s..s),
        rng.random_range(-s..s),
    )
}

/// Checks case `k`'s time of impact against the reference on 1,000 sub-steps: never later,
/// at most 1e-4 of the step before, no contact missed, none where they never come close. The reference's time (`None`: it sees no contact), and whether
/// the query found one.
fn agrees_with_the_reference(
    k: usize,
    (a, ma): (&CollisionMesh, &RigidMotion),
    (b, mb): (&CollisionMesh, &RigidMotion),
) -> (Option<f32>, bool) {
    let found = toi(a, ma, b, mb);
    match (reference_time(a, ma, b, mb, 1000), found) {
        (Some(reference), Some(hit)) => {
            assert!(
                on_time(hit.time.into(), reference.into()),
                "case {k}: {} against the reference's {reference}",
                hit.time
            );
            (Some(reference), true)
        }
        (Some(reference), None) => panic!("case {k}: missed the contact at {reference}"),
        // The sub-steps can miss a graze: then the meshes must come within tolerance.
        (None, Some(hit)) => {
            assert!(
                distance_at(a, ma, b, mb, hit.time) < 1e-3,
                "case {k}: false contact {hit:?}"
            );
            (None, true)
        }
        (None, None) => (None, false),
    }
}

#[test]
fn a_fast_ball_never_passes_through_a_thin_wall() {
    let ball = CollisionMesh::new(generate::icosphere(0.5, 2));
    // A tenth of the ball's diameter thick.
    let wall = CollisionMesh::new(generate::cuboid(Vec3::new(0.05, 3.0, 3.0), 2));
    let still = RigidMotion::still(Pose::IDENTITY);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
    let mut ws = QueryWorkspace::new();
    for _ in 0..20 {
        // From well left of the wall to well right of it in one step: both ends are apart.
        let y = rng.random_range(-1.5..1.5f32);
        let z = rng.random_range(-1.5..1.5f32);
        let shot = RigidMotion::new(
            Pose::from_translation(Vec3::new(-4.0, y, z)),
            Pose::new(
                Vec3::new(5.0, y + rng.random_range(-0.5..0.5), z),
                Quat::from_rotation_z(rng.random_range(-1.0..1.0)),
            ),
        );
        assert!(!intersects(
            &ball,
            &shot.start,
            &wall,
            &Pose::IDENTITY,
            &mut ws
        ));
        assert!(!intersects(
            &ball,
            &shot.end,
            &wall,
            &Pose::IDENTITY,
            &mut ws
        ));
        let hit = toi(&ball, &shot, &wall, &still).expect("the shot crosses the wall");
        let reference = reference_time(&ball, &shot, &wall, &still, 2000).unwrap();
        assert!(
            hit.time <= reference + 1e-6,
            "{} after {reference}",
            hit.time
        );
        assert!(
            hit.time >= reference - 1e-4,
            "{} long before {reference}",
            hit.time
        );
        assert!(
            hit.normal.x < -0.5,
            "normal {:?} from the wall towards the ball",
            hit.normal
        );
        assert!(
            (hit.point.x + 0.05).abs() < 0.02,
            "{:?} on the wall's face",
            hit.point
        );
    }
}

/// The same shots through a thin wall with the whole scene scaled down a thousand times and
/// up a hundred times: the time of impact stays within 1e-4 of the step of the reference at
/// every scale (a tolerance fixed in world units would make the small scene's answers
/// coarser: 1e-5 units is about 1.7e-3 of the small shot's step), and so the three scales
/// agree.
#[test]
fn times_of_impact_keep_their_precision_when_the_scene_is_scaled() {
    let (ball, wall) = (
        generate::icosphere(0.5, 2),
        generate::cuboid(Vec3::new(0.05, 3.0, 3.0), 2),
    );
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(41);
    let shots: Vec<(Vec3, Vec3, f32)> = (0..6)
        .map(|_| {
            let (y, z) = (
                rng.random_range(-1.0..1.0f32),
                rng.random_range(-1.0..1.0f32),
            );
            let start = Vec3::new(-4.0, y, z);
            let end = Vec3::new(2.0, y + rng.random_range(-0.5..0.5), z);
            (start, end, rng.random_range(-1.0..1.0))
        })
        .collect();
    let mut times = Vec::new();
    for scale in [1.0f32, 1e-3, 100.0] {
        let sized = |m: &stochastic_collision::mesh::TriMesh| {
            CollisionMesh::new(m.scaled(Vec3::splat(scale)).unwrap())
        };
        let (ball, wall) = (sized(&ball), sized(&wall));
        let still = RigidMotion::still(Pose::IDENTITY);
        let at_scale: Vec<f32> = shots
            .iter()
            .map(|&(start, end, turn)| {
                let shot = RigidMotion::new(
                    Pose::from_translation(start * scale),
                    Pose::new(end * scale, Quat::from_rotation_z(turn)),
                );
                let hit = toi(&ball, &shot, &wall, &still).expect("the shot crosses the wall");
                let reference = reference_time(&ball, &shot, &wall, &still, 1000).unwrap();
                assert!(
                    on_time(hit.time.into(), reference.into()),
                    "scale {scale}: {} against the reference's {reference}",
                    hit.time
                );
                hit.time
            })
            .collect();
        times.push(at_scale);
    }
    for (k, t) in times[0].iter().enumerate() {
        for other in &times[1..] {
            assert!(
                (other[k] - t).abs() <= 2e-4,
                "shot {k}: {t} and {}",
                other[k]
            );
        }
    }
}

#[test]
fn a_rotating_bar_sweeping_through_a_box_is_caught() {
    // A bar 4 long turning 90° about z within the step; a small box on its path, at 45°,
    // touched by neither end pose.
    let bar = CollisionMesh::new(generate::cuboid(Vec3::new(2.0, 0.05, 0.05), 1));
    let target = CollisionMesh::new(generate::cuboid(Vec3::splat(0.1), 1));
    let at = Vec3::new(1.2, 1.2, 0.0);
    let turn = RigidMotion::new(
        Pose::IDENTITY,
        Pose::new(Vec3::ZERO, Quat::from_rotation_z(1.5)),
    );
    let still = RigidMotion::still(Pose::from_translation(at));
    let mut ws = QueryWorkspace::new();
    assert!(!intersects(
        &bar,
        &turn.start,
        &target,
        &still.start,
        &mut ws
    ));
    assert!(!intersects(&bar, &turn.end, &target, &still.start, &mut ws));
    let hit = toi(&bar, &turn, &target, &still).expect("the bar hits the box");
    let reference = reference_time(&bar, &turn, &target, &still, 2000).unwrap();
    assert!(
        on_time(hit.time.into(), reference.into()),
        "{} vs {reference}",
        hit.time
    );
    // The box's corner facing the bar is hit first, a little before 45°.
    assert!(reference < 0.5);
}

#[test]
fn random_rigid_motions_agree_with_the_reference() {
    let meshes = [
        CollisionMesh::new(generate::icosphere(0.6, 1)),
        CollisionMesh::new(generate::cuboid(Vec3::new(0.8, 0.3, 0.2), 1)),
        CollisionMesh::new(generate::icosphere(0.3, 2)),
    ];
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(17);
    let (mut hits, mut misses, mut during) = (0, 0, 0);
    for k in 0..240 {
        let (a, b) = (&meshes[k % 3], &meshes[(k / 3) % 3]);
        let rot = |rng: &mut Xoshiro256PlusPlus| {
            Quat::from_axis_angle(
                v3(rng, 1.0).normalize_or(Vec3::X),
                rng.random_range(0.0..1.2),
            )
        };
        let ma = RigidMotion::new(
            Pose::new(v3(&mut rng, 2.0), rot(&mut rng)),
            Pose::new(v3(&mut rng, 2.0), rot(&mut rng)),
        );
        let mb = RigidMotion::new(
            Pose::new(v3(&mut rng, 1.0), rot(&mut rng)),
            Pose::new(v3(&mut rng, 1.0), rot(&mut rng)),
        );
        match agrees_with_the_reference(k, (a, &ma), (b, &mb)) {
            (Some(reference), _) => {
                hits += 1;
                during += (reference > 0.0) as usize;
            }
            (None, false) => misses += 1,
            (None, true) => {}
        }
    }
    // Contacts that start during the step, not only poses that overlap at its start.
    assert!(
        hits > 40 && during > 20 && misses > 40,
        "{hits} hits ({during} during the step), {misses} misses"
    );
}

#[test]
fn translations_agree_with_the_reference() {
    // Meshes that do not turn: the search bounds their nodes by slabs too (still in the
    // frame of the first mesh, or translating in it), on curved and flat, fine and coarse
    // surfaces; and one that turns against one that does not.
    let meshes = [
        CollisionMesh::new(generate::icosphere(0.6, 3)),
        CollisionMesh::new(generate::torus(0.5, 0.2, 32, 12)),
        CollisionMesh::new(generate::cuboid(Vec3::new(0.8, 0.3, 0.2), 4)),
        CollisionMesh::new(generate::cloth_grid(1.2, 1.0, 12, 10)),
    ];
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(29);
    let (mut hits, mut during) = (0, 0);
    for k in 0..160 {
        let (a, b) = (&meshes[k % 4], &meshes[(k / 4) % 4]);
        let rot = |rng: &mut Xoshiro256PlusPlus| {
            Quat::from_axis_angle(
                v3(rng, 1.0).normalize_or(Vec3::X),
                rng.random_range(0.0..3.0),
            )
        };
        let (ra, rb) = (rot(&mut rng), rot(&mut rng));
        // B comes from afar towards A (moving too, a little, in every other case).
        let ma = if k % 2 == 0 {
            RigidMotion::still(Pose::new(v3(&mut rng, 0.1), ra))
        } else {
            RigidMotion::new(
                Pose::new(v3(&mut rng, 0.3), ra),
                Pose::new(v3(&mut rng, 0.3), ra),
            )
        };
        let turned = k % 8 == 7;
        let end_b = if turned {
            rb * Quat::from_rotation_y(0.4)
        } else {
            rb
        };
        let mb = RigidMotion::new(
            Pose::new(v3(&mut rng, 0.4) + Vec3::new(2.5, 0.0, 0.0), rb),
            Pose::new(v3(&mut rng, 0.6), end_b),
        );
        if let (Some(reference), _) = agrees_with_the_reference(k, (a, &ma), (b, &mb)) {
            hits += 1;
            during += (reference > 0.0) as usize;
        }
    }
    assert!(
        hits > 80 && during > 80,
        "{hits} hits ({during} during the step)"
    );
}

#[test]
fn fast_turns_agree_with_the_reference() {
    // Flat and curved meshes turning by up to 3 rad in the step (long runs of pieces, whose
    // bounds must hold the arcs; a door hinged far from its centre), against a still or a
    // translating partner (whose slabs bound its nodes). Half the scenes lie far from the
    // origin.
    let meshes = [
        // A door: a plate hinged at its mesh's origin, far from its own centre.
        CollisionMesh::new(
            generate::cuboid(Vec3::new(0.9, 0.02, 0.3), 6)
                .translated(Vec3::new(1.2, 0.0, 0.0))
                .expect("finite"),
        ),
        CollisionMesh::new(generate::cloth_grid(1.4, 0.6, 14, 6)),
        CollisionMesh::new(generate::icosphere(0.4, 3)),
        CollisionMesh::new(generate::torus(0.5, 0.15, 32, 12)),
    ];
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(41);
    let (mut hits, mut during) = (0, 0);
    for k in 0..120 {
        let (a, b) = (&meshes[k % 4], &meshes[(k / 4) % 4]);
        let axis = v3(&mut rng, 1.0).normalize_or(Vec3::Y);
        let r0 = Quat::from_axis_angle(v3(&mut rng, 1.0).normalize_or(Vec3::X), 1.0);
        let spin = Quat::from_axis_angle(axis, rng.random_range(1.0..3.0));
        let far = if k % 4 < 2 {
            Vec3::ZERO
        } else {
            Vec3::new(7.0, -4.0, 5.0)
        };
        let ma = RigidMotion::new(
            Pose::new(far + v3(&mut rng, 0.2), r0),
            Pose::new(far + v3(&mut rng, 0.2), spin * r0),
        );
        let rb = Quat::from_axis_angle(v3(&mut rng, 1.0).normalize_or(Vec3::Z), 2.0);
        let at = far + v3(&mut rng, 0.5) + Vec3::new(0.9, 0.0, 0.0);
        let mb = if k % 2 == 0 {
            RigidMotion::still(Pose::new(at, rb))
        } else {
            RigidMotion::new(Pose::new(at, rb), Pose::new(at - Vec3::X * 0.5, rb))
        };
        if let (Some(reference), _) = agrees_with_the_reference(k, (a, &ma), (b, &mb)) {
            hits += 1;
            during += (reference > 0.0) as usize;
        }
    }
    assert!(
        hits > 40 && during > 25,
        "{hits} hits ({during} during the step)"
    );
}

#[test]
fn hard_cases_at_the_ends_of_the_step_and_without_motion() {
    let cube = CollisionMesh::new(generate::cuboid(Vec3::splat(0.5), 0));
    // Face to face, touching at the start and not moving: time 0.
    let a = RigidMotion::still(Pose::IDENTITY);
    let touching = RigidMotion::still(Pose::from_translation(Vec3::X));
    assert_eq!(toi(&cube, &a, &cube, &touching).unwrap().time, 0.0);
    // Apart and not moving: none.
    let apart = RigidMotion::still(Pose::from_translation(Vec3::X * 1.001));
    assert!(toi(&cube, &a, &cube, &apart).is_none());
    // Reaching the face exactly at the end of the step: found, at the end.
    let arriving = RigidMotion::new(
        Pose::from_translation(Vec3::X * 2.0),
        Pose::from_translation(Vec3::X),
    );
    let hit = toi(&cube, &a, &cube, &arriving).unwrap();
    assert!(hit.time > 1.0 - 1e-4 && hit.time <= 1.0, "{}", hit.time);
    assert!(hit.normal.x < -0.99, "{:?}", hit.normal);
    // Sliding along each other's faces, in contact all the way: time 0.
    let sliding = RigidMotion::new(
        Pose::from_translation(Vec3::X),
        Pose::from_translation(Vec3::new(1.0, 0.7, 0.0)),
    );
    assert_eq!(toi(&cube, &a, &cube, &sliding).unwrap().time, 0.0);
}

#[test]
fn a_cloth_falling_through_a_ball_in_one_step_is_caught() {
    let ball = CollisionMesh::new(generate::icosphere(0.5, 2));
    let cloth_at = |y: f32| {
        let mut m = generate::cloth_grid(3.0, 3.0, 12, 12);
        let moved: Vec<Vec3> = m.positions().iter().map(|p| *p + Vec3::Y * y).collect();
        m.set_positions(&moved).unwrap();
        m
    };
    let start = CollisionMesh::new(cloth_at(1.0));
    let mut end = start.clone();
    end.set_positions(cloth_at(-1.0).positions()).unwrap();
    let ball_end = ball.clone();
    let hit = deforming_time_of_impact(
        (&start, &end),
        (&ball, &ball_end),
        &CcdOptions::default(),
        &mut CcdWorkspace::new(),
    )
    .unwrap()
    .expect("the cloth hits the ball");
    // Reference: the cloth's positions interpolated, the discrete query on sub-steps.
    let mut ws = QueryWorkspace::new();
    let mut sheet = start.clone();
    let lerp = |t: f32| -> Vec<Vec3> {
        start
            .mesh()
            .positions()
            .iter()
            .zip(end.mesh().positions())
            .map(|(p, q)| p.lerp(*q, t))
            .collect()
    };
    let steps = 2000;
    let first = (0..=steps)
        .find(|&k| {
            sheet.set_positions(&lerp(k as f32 / steps as f32)).unwrap();
            intersects(&sheet, &Pose::IDENTITY, &ball, &Pose::IDENTITY, &mut ws)
        })
        .unwrap();
    let reference = first as f32 / steps as f32;
    assert!(
        hit.time <= reference + 1e-6,
        "{} after {reference}",
        hit.time
    );
    assert!(
        hit.time >= reference - 1.0 / steps as f32 - 1e-4,
        "{} before {reference}",
        hit.time
    );
    // The sheet comes from above: the normal points up, from the ball towards the cloth.
    assert!(hit.normal.y > 0.5, "{:?}", hit.normal);
}

/// A flat sheet falling onto a ball, its vertices on straight lines, at three scales (1,
/// 1/1000 and 100): it first touches the ball's highest vertex when its plane comes down to
/// it, a time known exactly, and the query finds that time within 1e-4 of the step at every
/// scale (with a tolerance fixed in world units the small scene's answer would come about
/// 5e-3 of the step early).
#[test]
fn a_falling_sheet_meets_the_ball_on_time_at_every_scale() {
    for scale in [1.0f32, 1e-3, 100.0] {
        let ball = generate::icosphere(0.5, 2)
            .scaled(Vec3::splat(scale))
            .unwrap();
        let top = ball
            .positions()
            .iter()
            .map(|p| p.y)
            .fold(f32::MIN, f32::max);
        let sheet_at = |y: f32| {
            let mut m = generate::cloth_grid(3.0, 3.0, 12, 12)
                .scaled(Vec3::splat(scale))
                .unwrap();
            let moved: Vec<Vec3> = m.positions().iter().map(|p| *p + Vec3::Y * y).collect();
            m.set_positions(&moved).unwrap();
            m
        };
        let (high, low) = (scale, -scale);
        let start = CollisionMesh::new(sheet_at(high));
        let mut end = start.clone();
        end.set_positions(sheet_at(low).positions()).unwrap();
        let ball = CollisionMesh::new(ball);
        let hit = deforming_time_of_impact(
            (&start, &end),
            (&ball, &ball.clone()),
            &CcdOptions::default(),
            &mut CcdWorkspace::new(),
        )
        .unwrap()
        .expect("the sheet meets the ball");
        // The plane y = high + (low - high) t reaches the top vertex at this time.
        let exact = f64::from(high - top) / f64::from(high - low);
        assert!(
            on_time(hit.time.into(), exact),
            "scale {scale}: {} against {exact}",
            hit.time
        );
    }
}

/// A ball a micrometre across shot at a wall ten kilometres wide and 0.2 µm thick, near the
/// origin and farther out: the first touch (the ball's extreme vertex reaching the wall's
/// face, from the poses as they are stored, in f32) is found within 1e-4 of the step. A
/// tolerance of 1e-5 world units alone, ten times the ball, reported contact at once.
#[test]
fn a_micrometre_ball_meets_a_huge_wall_on_time() {
    let ball = CollisionMesh::new(generate::icosphere(1e-6, 2));
    let wall = CollisionMesh::new(generate::cuboid(Vec3::new(1e-7, 1e4, 1e4), 2));
    let xs = |m: &CollisionMesh| -> Vec<f64> {
        m.mesh()
            .positions()
            .iter()
            .map(|p| f64::from(p.x))
            .collect()
    };
    // The ball's extreme vertex towards the wall, and the wall's face towards the ball.
    let reach = xs(&ball).into_iter().fold(f64::MIN, f64::max);
    let face = xs(&wall).into_iter().fold(f64::MAX, f64::min);
    for (x, y) in [(0.0f32, 0.0f32), (1.0, 3.0), (30.0, 500.0)] {
        let still = RigidMotion::still(Pose::from_translation(Vec3::new(x, 0.0, 0.0)));
        let shot = RigidMotion::new(
            Pose::from_translation(Vec3::new(x - 4e-6, y, 1.0)),
            Pose::from_translation(Vec3::new(x + 4e-6, y, 1.0)),
        );
        let hit = toi(&ball, &shot, &wall, &still).expect("the ball meets the wall");
        // Where the centre is when the extreme vertex reaches the face, along the stored
        // (rounded) translations.
        let (from, to) = (
            f64::from(shot.start.translation.x),
            f64::from(shot.end.translation.x),
        );
        let exact = (f64::from(x) + face - reach - from) / (to - from);
        assert!(
            on_time(hit.time.into(), exact),
            "at x = {x}: {} against {exact}",
            hit.time
        );
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let ball = CollisionMesh::new(generate::icosphere(0.5, 1));
    let bad = RigidMotion::new(
        Pose::IDENTITY,
        Pose::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)),
    );
    let still = RigidMotion::still(Pose::IDENTITY);
    let err = time_of_impact(
        &ball,
        &bad,
        &ball,
        &still,
        &CcdOptions::default(),
        &mut CcdWorkspace::new(),
    );
    assert!(
        matches!(
            err,
            Err(CcdError::InvalidPose {
                which: "first",
                end: "end",
                ..
            })
        ),
        "{err:?}"
    );
    let other = CollisionMesh::new(generate::icosphere(0.5, 2));
    let err = deforming_time_of_impact(
        (&ball, &other),
        (&ball, &ball),
        &CcdOptions::default(),
        &mut CcdWorkspace::new(),
    );
    assert!(
        matches!(err, Err(CcdError::MismatchedStates { which: "first", .. })),
        "{err:?}"
    );
}
