//! Cloth: sheets draped over a ball, folding onto themselves on the floor: deformable meshes
//! refitted every frame, self-collision, and the built-in penalty response. Headless; prints
//! a summary.
//!
//! ```text
//! cargo run --release --example cloth -- [SHEETS] [FRAMES]
//! ```
mod support;

use std::time::Instant;

use stochastic_collision::ecs::Stage;
use stochastic_collision::prelude::*;
use support::{Options, Scene};

fn main() {
    let mut args = std::env::args().skip(1).map(|a| a.parse::<usize>().ok());
    let sheets = args.next().flatten().unwrap_or(2);
    let frames = args.next().flatten().unwrap_or(120);
    let options = Options {
        entities: sheets,
        ..Options::default()
    };
    let mut app = Scene::Cloth.build(&options);
    let start = Instant::now();
    let mut self_contacts = 0usize;
    for _ in 0..frames {
        app.update();
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
}
