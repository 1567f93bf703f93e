//! Cloth: sheets draped over a ball, folding onto themselves on the floor: deformable meshes
//! refitted every frame, self-collision, and the built-in penalty response. Headless; prints
//! a summary.
//!
//! ```text
//! cargo run --release --example cloth -- [SHEETS] [FRAMES] [DAMPING]
//! ```
//!
//! `DAMPING` is the penalty response's [`PenaltySettings::damping`] (default 1: a contact's
//! approach is cancelled; 0: only its depth is corrected). The summary says how deep any cloth
//! vertex got into the ball and below the floor's top.
//!
//! [`PenaltySettings::damping`]: stochastic_collision::ecs::PenaltySettings::damping
mod support;

use std::time::Instant;

use stochastic_collision::ecs::{PenaltySettings, Stage};
use stochastic_collision::prelude::*;
use support::{Options, Scene, cloth};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize| args.get(i).and_then(|a| a.parse::<usize>().ok());
    let sheets = arg(0).unwrap_or(2);
    let frames = arg(1).unwrap_or(120);
    let damping = args.get(2).and_then(|a| a.parse::<f32>().ok());
    let options = Options {
        entities: sheets,
        ..Options::default()
    };
    let mut app = Scene::Cloth.build(&options);
    if let Some(damping) = damping {
        app.world_mut().resource_mut::<PenaltySettings>().damping = damping;
    }
    let start = Instant::now();
    let mut self_contacts = 0usize;
    // How deep a cloth vertex got into the ball (its inscribed sphere) and below the floor.
    let (mut into_ball, mut below_floor) = (0.0f32, 0.0f32);
    for _ in 0..frames {
        app.update();
        let mut sheets = app.world_mut().query::<(&Deformable, &ColliderPose)>();
        for (sheet, pose) in sheets.iter(app.world()) {
            for p in sheet.positions() {
                let x = pose.0.transform_point(*p);
                into_ball = into_ball.max(cloth::BALL_INSCRIBED - x.length());
                below_floor = below_floor.max(cloth::FLOOR_TOP - x.y);
            }
        }
        let frame = app
            .world()
            .resource::<stochastic_collision::ecs::PairTable>();
        self_contacts += frame
            .outcomes()
            .filter(|o| o.a == o.b)
            .map(|o| o.contacts.len())
            .sum::<usize>();
    }
    let d = app.world().resource::<CollisionDiagnostics>();
    let mean = |s: Stage| {
        let r = d.stage(s);
        r.total.as_secs_f64() * 1e3 / r.runs.max(1) as f64
    };
    println!(
        "cloth: {sheets} sheets of 800 triangles, {frames} frames in {:.2} s",
        start.elapsed().as_secs_f64()
    );
    println!(
        "  mean per frame: refit {:.3} ms, narrow phase {:.3} ms, self-collision {:.3} ms, response {:.3} ms",
        mean(Stage::Refit),
        mean(Stage::NarrowPhase),
        mean(Stage::SelfCollision),
        mean(Stage::Response)
    );
    let consumed = app
        .world()
        .resource::<stochastic_collision::ecs::ContactQueue>()
        .consumed_total;
    println!(
        "  {} contact intervals started, {consumed} contacts ({self_contacts} self-contacts) handled by the penalty response",
        d.counters.started
    );
    println!(
        "  penalty damping {}: deepest cloth vertex {into_ball:.4} into the ball, {below_floor:.4} below the floor's top",
        app.world().resource::<PenaltySettings>().damping
    );
}
