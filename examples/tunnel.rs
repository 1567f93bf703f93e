//! Tunnel: cannonball shots at ten times their speed (by default) against a wall a tenth of
//! the ball's diameter thick. Between two frames a shot moves 2-4 units, so the discrete test
//! sees it on one side of the wall and then on the other, never touching: it tunnels. With
//! `ContinuousCollision` each shot's pair is tested over the frame's motion and the contact
//! is found, with its time of impact. Both runs are checked against a reference that
//! sub-steps every frame 1024 times with the exact query. Headless; prints a summary and
//! writes a side view (SVG) of where each run stopped the shots.
//!
//! ```text
//! cargo run --release --example tunnel -- [--shots N] [--speed K] [--frames N] [--seed S] [--svg PATH]
//! ```
mod support;

use support::tunnel::{Args, USAGE, run};

fn main() {
    let args = match Args::parse(std::env::args().skip(1)) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("tunnel: {e}\n{USAGE}");
            std::process::exit(2);
        }
    };
    if args.help {
        println!("{USAGE}");
        return;
    }
    let report = run(&args);
    print!("{report}");
    if report.picture.is_err() {
        std::process::exit(1);
    }
}
