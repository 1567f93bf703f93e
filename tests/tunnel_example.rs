//! The `tunnel` example through the code its `main` runs (`examples/support/tunnel.rs`): shots
//! at 10× the cannonball's speed against a wall a tenth of the ball's diameter thick tunnel
//! through it under the discrete exact test; with `ContinuousCollision` every shot the
//! sub-stepped reference sees touching the wall is detected, in the reference's frame, never
//! later, and none is invented (also with the wall a `Deformable`, swept with the deforming
//! query); with ADB pairs and the conservative time-critical continuous
//! query the same holds at the plugin's default budget and at a tight work budget, and with the
//! estimating one at the default budget. Bad arguments are errors.
#[path = "../examples/support/mod.rs"]
mod support;

use support::tunnel::{Args, run};

#[test]
fn continuous_collision_catches_every_shot_the_discrete_test_lets_through() {
    let dir = std::env::temp_dir().join(format!("sc_tunnel_{}", std::process::id()));
    let args = Args {
        shots: 80,
        seed: 4,
        svg: dir.join("tunnel.svg"),
        ..Args::default()
    };
    let r = run(&args);
    assert!(
        r.crossing >= 10,
        "enough shots touch the wall: {}",
        r.crossing
    );
    assert!(
        r.discrete.detected < r.crossing / 2,
        "the discrete test misses most: {} of {}",
        r.discrete.detected,
        r.crossing
    );
    assert_eq!(r.continuous.detected, r.crossing, "{r}");
    assert_eq!(r.continuous.same_run, r.crossing, "{r}");
    assert_eq!(r.continuous.false_hits, 0, "{r}");
    assert_eq!(r.discrete.false_hits, 0, "{r}");
    assert_eq!(r.late, 0, "{r}");
    // The wall made a deformable: the deforming continuous query catches the same shots.
    assert_eq!(r.deformable.detected, r.crossing, "{r}");
    assert_eq!(r.deformable.same_run, r.crossing, "{r}");
    assert_eq!(r.deformable.false_hits, 0, "{r}");
    assert!(
        r.worst_time_error <= 2.0 / support::tunnel::REFERENCE_SUBSTEPS as f32,
        "{r}"
    );
    // The ADB runs: the conservative ones (default time budget, then a tight work budget)
    // and the estimating one at the default time budget (each swept pair gets at least an
    // eighth of the largest slice, past the deadline too: enough to settle a ball against a
    // wall) detect every shot, in its frame, never late; the estimating one under the tight
    // work budget is only reported.
    assert_eq!(r.adb.len(), 4, "{r}");
    for run in &r.adb[..3] {
        assert_eq!(run.verdicts.detected, r.crossing, "{}: {r}", run.name);
        assert_eq!(run.verdicts.same_run, r.crossing, "{}: {r}", run.name);
        assert_eq!(run.late, 0, "{}: {r}", run.name);
    }
    let svg = std::fs::read_to_string(r.picture.as_ref().expect("picture written")).unwrap();
    assert_eq!(svg.matches("<circle").count(), 2 * r.crossing);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn bad_arguments_are_errors() {
    let parse = |a: &[&str]| Args::parse(a.iter().map(|s| s.to_string()));
    assert!(parse(&["--speed", "0"]).is_err());
    assert!(parse(&["--speed", "fast"]).is_err());
    assert!(parse(&["--shots"]).is_err());
    assert!(parse(&["--bogus", "1"]).is_err());
    assert!(parse(&["--adb-budget", "-3"]).is_err());
    assert_eq!(parse(&["--adb-budget", "40"]).unwrap().adb_budget, 40);
    let a = parse(&["--speed", "3", "--shots", "12", "--seed", "9"]).unwrap();
    assert_eq!((a.speed, a.shots, a.seed), (3.0, 12, 9));
}
