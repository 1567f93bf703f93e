//! Cannonball: randomized shots against a castle wall. The same shots are simulated twice:
//! with time-critical ADB queries at a low confidence (`p_min = 0.5`, within a 2 ms frame
//! budget) and with exact queries. Prints which paths the approximate run found plausible
//! (hit or miss, where, when) against the exact run, and the collision time each needed.
//!
//! The shots stop where they hit through a response the scene writes itself (see
//! `support/cannonball.rs`, `embed`): the way a game adds its own reaction to contacts.
//!
//! ```text
//! cargo run --release --example cannonball -- [SHOTS] [P_MIN] [NODE_PAIRS_PER_FRAME] [COLLIDE_AT] [on|off] [SPEED]
//! ```
//!
//! `COLLIDE_AT` (default 0.2): the confidence from which an ADB answer its traversal did not
//! settle counts as a hit (`CollisionConfig::adb_collide_at`): a missed hit loses the shot,
//! a false one stops it a frame early. The last argument turns the interpenetration
//! certificate on (`CollisionConfig::adb_interior`; off by default in this scene). `SPEED`
//! (default 1) multiplies the shots' speed; with another speed the exact run is repeated with
//! continuous collision (`ContinuousCollision::WhenFast` on the shots), and the summary says
//! how many shots the discrete runs let pass through the castle unseen. The `tunnel` example
//! measures this against a sub-stepped reference.
mod support;

use std::time::Duration;

use bevy_app::App;
use stochastic_collision::ecs::Stage;
use stochastic_collision::prelude::*;
use support::{Options, cannonball};

struct Run {
    hits: Vec<Option<u64>>,
    narrow: Duration,
    collision: Duration,
}

fn simulate(options: &Options, fidelity: Fidelity, collide_at: f64, frames: usize) -> Run {
    let mut app = App::new();
    app.add_plugins(options.plugin());
    cannonball::setup(&mut app, options, Some(fidelity));
    app.world_mut()
        .resource_mut::<CollisionConfig>()
        .adb_collide_at = collide_at;
    let mut collision = Duration::ZERO;
    for _ in 0..frames {
        app.update();
        collision += app
            .world()
            .resource::<CollisionDiagnostics>()
            .collision_time;
    }
    let narrow = app
        .world()
        .resource::<CollisionDiagnostics>()
        .stage(Stage::NarrowPhase)
        .total;
    Run {
        hits: cannonball::hits(app.world_mut()),
        narrow,
        collision,
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let shots = args.next().and_then(|a| a.parse().ok()).unwrap_or(300);
    let p_min = args.next().and_then(|a| a.parse().ok()).unwrap_or(0.5);
    let node_budget = args.next().and_then(|a| a.parse().ok()).unwrap_or(1000);
    let collide_at = args
        .next()
        .and_then(|a| a.parse().ok())
        .unwrap_or(cannonball::COLLIDE_AT);
    let adb_interior = args.next().map(|a| a == "on");
    let speed = args.next().and_then(|a| a.parse().ok()).unwrap_or(1.0);
    let frames = 150;
    // ADB gets a small work budget per frame: what a game would give a background effect.
    let options = Options {
        entities: shots,
        node_budget: Some(node_budget),
        adb_interior,
        speed,
        ..Options::default()
    };
    let adb = simulate(&options, Fidelity::Adb { p_min }, collide_at, frames);
    let exact = simulate(
        &Options {
            budget_us: 0,
            node_budget: None,
            ..options.clone()
        },
        Fidelity::Exact,
        collide_at,
        frames,
    );
    // Faster shots: the exact run again with continuous collision, which no shot passes
    // through unseen.
    let continuous = (speed != 1.0).then(|| {
        simulate(
            &Options {
                budget_us: 0,
                node_budget: None,
                continuous: true,
                ..options.clone()
            },
            Fidelity::Exact,
            collide_at,
            frames,
        )
    });
    let both = |f: fn(&Option<u64>, &Option<u64>) -> bool| {
        adb.hits
            .iter()
            .zip(&exact.hits)
            .filter(|(a, e)| f(a, e))
            .count()
    };
    let hits_exact = exact.hits.iter().flatten().count();
    let hits_adb = adb.hits.iter().flatten().count();
    let same = both(|a, e| a.is_some() == e.is_some());
    let same_frame = both(|a, e| a.is_some() && a == e);
    let late: Vec<i64> = adb
        .hits
        .iter()
        .zip(&exact.hits)
        .filter_map(|(a, e)| Some(a.as_ref()? - e.as_ref()?).map(|d| d as i64))
        .collect();
    let mean_delay = late.iter().sum::<i64>() as f64 / late.len().max(1) as f64;
    let at_speed = if speed == 1.0 {
        String::new()
    } else {
        format!(" at {speed}x speed")
    };
    println!(
        "cannonball: {shots} shots{at_speed}, {frames} frames, ADB p_min = {p_min} within {node_budget} node pairs per frame, hit from confidence {collide_at}, vs exact"
    );
    println!("  exact: {hits_exact} shots hit the castle; ADB: {hits_adb}");
    if let Some(c) = &continuous {
        println!(
            "  exact with continuous collision: {} shots hit the castle ({} passed through it unseen by the discrete exact run)",
            c.hits.iter().flatten().count(),
            c.hits
                .iter()
                .zip(&exact.hits)
                .filter(|(c, e)| c.is_some() && e.is_none())
                .count()
        );
    }
    println!(
        "  same hit/miss verdict for {same} of {shots} shots ({:.1} %); same first-contact frame for {same_frame} of the {} hits found by both; mean delay {mean_delay:.2} frames",
        100.0 * same as f64 / shots as f64,
        late.len()
    );
    println!(
        "  narrow phase: ADB {:.1} ms, exact {:.1} ms in all ({:.1}x); collision stages: ADB {:.1} ms, exact {:.1} ms",
        adb.narrow.as_secs_f64() * 1e3,
        exact.narrow.as_secs_f64() * 1e3,
        exact.narrow.as_secs_f64() / adb.narrow.as_secs_f64().max(1e-9),
        adb.collision.as_secs_f64() * 1e3,
        exact.collision.as_secs_f64() * 1e3
    );
}
