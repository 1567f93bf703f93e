//! Optional features: the stage timings in bevy_diagnostic's store (`diagnostic`).
#![cfg(feature = "diagnostic")]
mod plugin_support;

use bevy_app::prelude::*;
use plugin_support::*;
use stochastic_collision::prelude::*;

#[test]
fn stage_timings_reach_the_diagnostics_store() {
    use bevy_diagnostic::{DiagnosticsPlugin, DiagnosticsStore};
    use stochastic_collision::ecs::diagnostics_store::{COLLISION_PATH, STAGE_PATHS};
    let mut app = app();
    app.add_plugins(DiagnosticsPlugin);
    let ball = ball(1.0);
    spawn(&mut app, (ball.clone(), at(0.0, 0.0, 0.0)));
    spawn(&mut app, (ball, at(1.5, 0.0, 0.0)));
    for _ in 0..3 {
        app.update();
    }
    let store = app.world().resource::<DiagnosticsStore>();
    assert!(store.get(&COLLISION_PATH).unwrap().measurement().is_some());
    assert!(
        store.get(&STAGE_PATHS[3]).unwrap().measurement().is_some(),
        "narrow phase"
    );
    assert!(
        store.get(&STAGE_PATHS[1]).unwrap().measurement().is_none(),
        "no refit ran"
    );
}
