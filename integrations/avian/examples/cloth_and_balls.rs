//! avian3d simulates rigid balls; stochastic_collision detects their contacts with a cloth
//! mesh that deforms every step (avian has no deformable colliders: a trimesh collider would
//! be rebuilt every step) and hands them back (see the crate documentation).
//!
//! `cargo run --release --example cloth_and_balls -- [--steps N] [--svg PATH]` (from
//! `integrations/avian`; add `--ignore-rust-version` on rustc older than bevy's 1.97.1).
//! Prints a summary and writes a side view (SVG) of the last step.
use std::fmt::Write as _;

use bevy::prelude::*;
use stochastic_collision::prelude::*;
use stochastic_collision_avian::{RADIUS, Tally, cloth_and_balls_app, positions};

fn main() {
    let mut steps = 240usize;
    let mut svg = "target/cloth_and_balls.svg".to_string();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match (a.as_str(), args.next()) {
            ("--steps", Some(v)) => steps = v.parse().expect("--steps takes a number"),
            ("--svg", Some(v)) => svg = v,
            _ => {
                eprintln!("usage: cloth_and_balls [--steps N] [--svg PATH]");
                std::process::exit(2);
            }
        }
    }
    let mut app = cloth_and_balls_app();
    for step in 0..steps {
        app.update();
        if (step + 1) % 60 == 0 {
            eprintln!("step {}/{steps}", step + 1);
        }
    }
    let (balls, cloth) = positions(&mut app);
    let world = app.world();
    let tally = world.resource::<Tally>();
    let diag = world.resource::<CollisionDiagnostics>();
    let resting = balls.iter().filter(|p| p.y > -0.5 && p.y < 0.5).count();
    let fell = balls.iter().filter(|p| p.y <= -0.5).count();
    let dip = cloth.iter().map(|p| p.y).fold(0.0f32, f32::min);
    println!(
        "cloth_and_balls: {steps} steps; of {} balls {} rest on the cloth, {} fell through \
         (lowest ball centre {:.3}); {} cloth contacts handed to avian, {} contacts started; \
         deepest cloth dimple {:.3}; collision runs: {}",
        balls.len(),
        resting,
        fell,
        tally.lowest_ball,
        tally.contacts,
        tally.started,
        dip,
        diag.frame,
    );
    write_svg(&svg, &balls, &cloth);
    println!("side view: {svg}");
}

/// A side view (x horizontal, y up): the cloth's vertices as dots, the balls as circles.
fn write_svg(path: &str, balls: &[Vec3], cloth: &[Vec3]) {
    let (w, h, scale) = (640.0, 360.0, 150.0);
    let at = |p: Vec3| (w / 2.0 + p.x * scale, h * 0.6 - p.y * scale);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" \
         viewBox=\"0 0 {w} {h}\"><rect width=\"100%\" height=\"100%\" fill=\"white\"/>"
    );
    for p in cloth {
        let (x, y) = at(*p);
        let _ = write!(
            s,
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"1\" fill=\"#4a7\"/>"
        );
    }
    for p in balls {
        let (x, y) = at(*p);
        let r = RADIUS * scale;
        let _ = write!(
            s,
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"{r:.1}\" fill=\"none\" stroke=\"#c33\"/>"
        );
    }
    s.push_str("</svg>\n");
    if let Some(dir) = std::path::Path::new(path).parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    if let Err(e) = std::fs::write(path, s) {
        eprintln!("cannot write {path}: {e}");
    }
}
