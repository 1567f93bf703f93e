//! The broad phase against brute force: the candidate pairs are exactly the pairs of valid
//! colliders whose world boxes overlap and whose layers interact, run after run, while bodies
//! move, appear and disappear (the sweep keeps its order between runs), rest (the last pairs
//! are reused), change layers, on 1 and 2 threads.
mod plugin_support;

use bevy_app::App;
use bevy_ecs::entity::Entity;
use plugin_support::*;
use stochastic_collision::ecs::{CandidatePair, CandidatePairs, ColliderFrame, CollisionLayers};
use stochastic_collision::prelude::*;

/// A small deterministic generator (splitmix64) in `[0, 1)`.
struct Random(u64);

impl Random {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }

    fn pose(&mut self, spread: f32) -> ColliderPose {
        let p = Vec3::new(self.next(), self.next() * 0.3, self.next()) * spread;
        let axis = Vec3::new(self.next() - 0.5, 1.0, self.next() - 0.5).normalize();
        ColliderPose(Pose::new(p, Quat::from_axis_angle(axis, self.next() * 6.0)))
    }
}

/// The pairs brute force finds among the run's colliders.
fn brute_force(app: &App) -> Vec<CandidatePair> {
    let entries = app.world().resource::<ColliderFrame>().entries();
    let mut pairs = Vec::new();
    for i in 0..entries.len() {
        for j in i + 1..entries.len() {
            let (a, b) = (&entries[i], &entries[j]);
            if a.aabb.intersects(&b.aabb) && a.layers.interacts_with(&b.layers) {
                pairs.push(CandidatePair {
                    a: i as u32,
                    b: j as u32,
                });
            }
        }
    }
    pairs
}

#[test]
fn candidate_pairs_are_exactly_the_overlapping_interacting_boxes() {
    for threads in [1, 2] {
        let mut app = app_with(
            CollisionConfig {
                budget: FrameBudget::NodePairs(2000),
                ..Default::default()
            },
            threads,
        );
        let mut random = Random(7);
        let shapes = [
            Collider::new(generate::icosphere(0.5, 1)),
            Collider::new(generate::cuboid(Vec3::new(1.5, 0.1, 0.2), 1)),
            Collider::new(generate::torus(0.6, 0.15, 12, 6)),
        ];
        let layers = [
            CollisionLayers::ALL,
            CollisionLayers::new(0b01, 0b01),
            CollisionLayers::new(0b10, 0b11),
        ];
        let mut bodies: Vec<Entity> = (0..300)
            .map(|k| {
                let pose = random.pose(12.0);
                spawn(&mut app, (shapes[k % 3].clone(), pose, layers[(k / 3) % 3]))
            })
            .collect();
        for run in 0..6 {
            app.update();
            let found = app.world().resource::<CandidatePairs>().pairs().to_vec();
            let expected = brute_force(&app);
            assert!(expected.len() > 100, "run {run}: {} pairs", expected.len());
            assert_eq!(found, expected, "threads {threads}, run {run}");
            // A third move a little, some go away, some arrive.
            for (k, &e) in bodies.iter().enumerate().filter(|(k, _)| k % 3 == run % 3) {
                let step = Vec3::new(random.next() - 0.5, 0.0, random.next() - 0.5) * 0.4;
                let mut pose = app.world_mut().get_mut::<ColliderPose>(e).unwrap();
                pose.0.translation += step * (1 + k % 2) as f32;
            }
            for e in bodies.drain(..10) {
                app.world_mut().despawn(e);
            }
            for k in 0..10 {
                let pose = random.pose(12.0);
                bodies.push(spawn(&mut app, (shapes[k % 3].clone(), pose)));
            }
        }
        // At rest (the last pairs are reused), then a change of layers alone, then one body
        // moving alone: each run still exactly the brute-force pairs.
        for run in 0..4 {
            app.update();
            let found = app.world().resource::<CandidatePairs>().pairs().to_vec();
            assert_eq!(
                found,
                brute_force(&app),
                "threads {threads}, rest run {run}"
            );
            match run {
                1 => {
                    for &e in bodies.iter().step_by(2) {
                        app.world_mut()
                            .entity_mut(e)
                            .insert(CollisionLayers::new(0b100, 0b100));
                    }
                }
                2 => {
                    let mut pose = app.world_mut().get_mut::<ColliderPose>(bodies[0]).unwrap();
                    pose.0.translation += Vec3::new(3.0, 0.0, 0.0);
                }
                _ => {}
            }
        }
    }
}
