//! Pile: hundreds to thousands of rigid meshes (generated, and the shared Suzanne when
//! present) falling into a box, with the built-in impulse response. Headless; prints a summary.
//!
//! ```text
//! cargo run --release --example pile -- [BODIES] [FRAMES] [BUDGET_US (0: none)]
//! ```
mod support;

use std::time::Instant;

use bevy_ecs::prelude::*;
use stochastic_collision::prelude::*;
use support::{Options, Scene, pile};

fn main() {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<usize>());
    let bodies = args.next().and_then(Result::ok).unwrap_or(500);
    let frames = args.next().and_then(Result::ok).unwrap_or(240);
    let budget_us = args.next().and_then(Result::ok).unwrap_or(2000) as u64;
    let options = Options {
        entities: bodies,
        budget_us,
        fidelity: std::env::var_os("PILE_EXACT").map(|_| Fidelity::Exact),
        ..Options::default()
    };
    let mut app = Scene::Pile.build(&options);
    let start = Instant::now();
    let mut worst = 0f64;
    for _ in 0..frames {
        app.update();
        let d = app.world().resource::<CollisionDiagnostics>();
        worst = worst.max(d.collision_time.as_secs_f64() * 1e3);
    }
    let elapsed = start.elapsed().as_secs_f64();
    let world = app.world_mut();
    let moving = pile::moving(world, 0.5);
    let asleep = world
        .query::<&stochastic_collision::ecs::Rest>()
        .iter(world)
        .filter(|r| r.is_asleep())
        .count();
    let mut q = world.query_filtered::<&ColliderPose, With<BodyVelocity>>();
    let (inside, below) = q.iter(world).fold((0, 0), |(i, b), p| {
        let y = p.0.translation.y;
        (
            i + usize::from((-0.1..3.5).contains(&y)),
            b + usize::from(y < -0.5),
        )
    });
    let d = world.resource::<CollisionDiagnostics>();
    let c = d.counters;
    println!(
        "pile: {bodies} bodies, {frames} frames in {elapsed:.2} s ({:.2} ms/frame, worst collision stage {worst:.2} ms, budget {} us)",
        elapsed * 1e3 / frames as f64,
        options.budget_us
    );
    println!(
        "  {inside} bodies in the box, {below} below the floor, {moving} still moving faster than 0.5 m/s, {asleep} asleep"
    );
    println!(
        "  {} contacts started, {} ended; {} ADB pairs ({} cut by the budget, {} answered from the last frame)",
        c.started, c.ended, c.adb_pairs, c.budget_exhausted_pairs, c.coherence_pairs
    );
}
