//! Needle: needles shot down through a cloth, each crossing it within one frame, both tracked
//! (`Fidelity::Tracking`). Between two frames a needle passes from above the cloth to below
//! it, so the discrete tracker sees it only when a frame ends with it through the cloth; with
//! `ContinuousCollision` on the needles the tracked pairs are checked over the frame's motion.
//! Both runs are checked against the exact continuous query over each frame. Headless; prints
//! a summary and writes a side view (SVG) of the needles that cross the cloth.
//!
//! ```text
//! cargo run --release --example needle -- [--needles N] [--frames N] [--seed S] [--svg PATH]
//! ```
mod support;

use support::needle::{Args, USAGE, run};

fn main() {
    let args = match Args::parse(std::env::args().skip(1)) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("needle: {e}\n{USAGE}");
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
