//! Random rigid motions of pairs of meshes over one step, for the continuous ADB query's
//! reliability report and the fit of its answer model: one mesh flying across the other's
//! neighbourhood (a third without turning, the rest turning up to a radian), the other moving
//! a little and turning.
use glam::Quat;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::adb::AdbTree;
use stochastic_collision::ccd::{
    CcdOptions, CcdWorkspace, RigidMotion, TimeOfImpact, time_of_impact,
};
use stochastic_collision::geometry::Pose;
use stochastic_collision::poses::random_direction;

/// One case: which two meshes and their motions over the step.
pub struct Case {
    pub a: usize,
    pub b: usize,
    pub motion_a: RigidMotion,
    pub motion_b: RigidMotion,
}

impl Case {
    /// The exact continuous query's answer for this case's motions of `a` and `b` (the
    /// reference).
    pub fn reference(
        &self,
        a: &AdbTree,
        b: &AdbTree,
        ws: &mut CcdWorkspace,
    ) -> Option<TimeOfImpact> {
        time_of_impact(
            a.collision_mesh(),
            &self.motion_a,
            b.collision_mesh(),
            &self.motion_b,
            &CcdOptions::default(),
            ws,
        )
        .expect("finite motions")
    }
}

/// `n` cases over `meshes` meshes (centred), from `seed`: each mesh against each.
pub fn cases(n: usize, meshes: usize, seed: u64) -> Vec<Case> {
    let all: Vec<usize> = (0..meshes).collect();
    cases_between(n, &all, &all, seed)
}

/// `n` cases of a mesh of `movers` flying across the neighbourhood of one of `others`, from
/// `seed` (with every mesh in both, the same cases as [`cases`]).
pub fn cases_between(n: usize, movers: &[usize], others: &[usize], seed: u64) -> Vec<Case> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0xC0A7);
    // A point within `s` of the origin along each axis; a turn of up to `max` radians.
    let v3 = |rng: &mut Xoshiro256PlusPlus, s: f32| {
        random_direction(rng) * rng.random_range(0.0..s * 3f32.sqrt())
    };
    let rot = |rng: &mut Xoshiro256PlusPlus, max: f32| {
        Quat::from_axis_angle(random_direction(rng), rng.random_range(0.0..max))
    };
    (0..n)
        .map(|k| {
            let a = movers[rng.random_range(0..movers.len())];
            let b = others[rng.random_range(0..others.len())];
            // A third of the flights do not turn; the rest turn up to a radian over the step.
            let turn = if k % 3 == 0 { 0.0 } else { 1.0 };
            let start = rot(&mut rng, 3.0);
            let motion_a = RigidMotion::new(
                Pose::new(v3(&mut rng, 2.0), start),
                Pose::new(v3(&mut rng, 2.0), start * rot(&mut rng, turn + 1e-3)),
            );
            let still = rot(&mut rng, 3.0);
            let motion_b = RigidMotion::new(
                Pose::new(v3(&mut rng, 0.3), still),
                Pose::new(v3(&mut rng, 0.3), still * rot(&mut rng, 0.3)),
            );
            Case {
                a,
                b,
                motion_a,
                motion_b,
            }
        })
        .collect()
}
