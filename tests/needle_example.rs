//! The `needle` example through the code its `main` runs (`examples/support/needle.rs`):
//! needles falling through a tracked cloth within a frame pass unseen by discrete tracking
//! more often than not; with `ContinuousCollision` every needle the exact continuous reference
//! sees crossing is detected, in its frame (or a frame early, within the tracker's thickness),
//! never later, and none is invented. Bad arguments are errors.
#[path = "../examples/support/mod.rs"]
mod support;

use support::needle::{Args, run};

#[test]
fn continuous_tracking_catches_every_needle_discrete_tracking_lets_through() {
    let dir = std::env::temp_dir().join(format!("sc_needle_{}", std::process::id()));
    let args = Args {
        needles: 40,
        seed: 5,
        svg: dir.join("needle.svg"),
        ..Args::default()
    };
    let r = run(&args);
    assert!(r.crossing >= 20, "enough needles cross: {r}");
    assert!(
        r.discrete.detected < r.crossing * 3 / 4,
        "discrete tracking misses many: {r}"
    );
    // Detected in its frame, or a frame early (within the tracker's thickness), never later.
    assert_eq!(
        r.continuous.detected + r.continuous.early_run,
        r.crossing,
        "{r}"
    );
    assert_eq!(r.continuous.late_run, 0, "{r}");
    assert_eq!(r.continuous.false_hits + r.discrete.false_hits, 0, "{r}");
    assert_eq!(r.continuous.late, 0, "{r}");
    let svg = std::fs::read_to_string(r.picture.as_ref().expect("picture written")).unwrap();
    assert_eq!(svg.matches("stroke-width=\"2\"").count(), r.crossing + 1);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn bad_arguments_are_errors() {
    let parse = |a: &[&str]| Args::parse(a.iter().map(|s| s.to_string()));
    assert!(parse(&["--needles", "0"]).is_err());
    assert!(parse(&["--frames", "many"]).is_err());
    assert!(parse(&["--seed"]).is_err());
    assert!(parse(&["--bogus", "1"]).is_err());
    let a = parse(&["--needles", "7", "--seed", "3"]).unwrap();
    assert_eq!((a.needles, a.seed), (7, 3));
}
