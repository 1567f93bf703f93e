//! The main demo's pile keeps its bodies: rigid meshes falling into a box with the built-in
//! impulse response stay in it, the open ones (the shared Suzanne, whose eyes are holes) too.
//! An open body's contact with the floor once took the body's own face normal turned towards
//! the floor's far-away centre, and a quarter of the demo's bodies were pushed through the
//! walls and the floor.
#[path = "../examples/support/mod.rs"]
mod support;

mod common;

use support::pile::{Args, run};

#[test]
fn the_pile_keeps_its_bodies_in_the_box() {
    // Suzanne is the pile's open body; without the shared meshes there is none to check.
    if common::shared_mesh("suzanne.obj").is_none() {
        return;
    }
    let dir = std::env::temp_dir().join(format!("pile_in_box_{}", std::process::id()));
    let svg = dir.join("pile.svg");
    let args = ["200", "240", "0", "--svg", svg.to_str().unwrap()];
    let args = Args::parse(args.iter().map(|s| s.to_string())).unwrap();
    let (_, report) = run(&args);
    assert_eq!(report.escaped, 0, "{report}");
    assert_eq!(report.inside, 200, "{report}");
    let _ = std::fs::remove_dir_all(dir);
}
