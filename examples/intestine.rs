//! Intestine: a deforming intestine (the shared `small_intestine_100k` when present, else a
//! generated coiled tube) with a peristaltic wave, self-collision and the built-in penalty
//! response. Headless; prints a summary.
//!
//! ```text
//! cargo run --release --example intestine -- [FRAMES]
//! ```
mod support;

use std::time::Instant;

use stochastic_collision::ecs::Stage;
use stochastic_collision::prelude::*;
use support::{Options, Scene, intestine};

fn main() {
    let frames = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(30);
    let (mesh, name) = intestine::intestine_mesh();
    println!(
        "intestine: {name}, {} triangles, {frames} frames",
        mesh.triangle_count()
    );
    let options = Options {
        budget_us: Scene::Intestine.default_budget_us(),
        ..Options::default()
    };
    println!(
        "  collision budget {} ms per frame",
        options.budget_us / 1000
    );
    let mut app = Scene::Intestine.build(&options);
    let start = Instant::now();
    for _ in 0..frames {
        app.update();
    }
    let d = app.world().resource::<CollisionDiagnostics>();
    let mean = |s: Stage| {
        let r = d.stage(s);
        r.total.as_secs_f64() * 1e3 / r.runs.max(1) as f64
    };
    println!(
        "  {:.2} s; mean per frame: refit {:.2} ms, self-collision {:.2} ms, response {:.2} ms",
        start.elapsed().as_secs_f64(),
        mean(Stage::Refit),
        mean(Stage::SelfCollision),
        mean(Stage::Response)
    );
    let queue = app.world().resource::<ContactQueue>();
    println!(
        "  {} self-contacts handled by the penalty response ({} still queued)",
        queue.consumed_total,
        queue.len()
    );
}
