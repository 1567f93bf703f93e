//! Pile: hundreds to thousands of rigid meshes (generated, and the shared Suzanne when
//! present) falling into a box, with the built-in impulse response. Headless; prints a summary
//! and writes a picture of the final scene seen from the side (SVG: the bodies' outlines, the
//! box and the contact points).
//!
//! ```text
//! cargo run --release --example pile -- [BODIES] [FRAMES] [BUDGET_US (0: none)] [--svg PATH]
//! ```
//!
//! Defaults: 500 bodies, 240 frames, a 2000 µs budget, the picture in `target/pile.svg`
//! (relative to the current directory). With `PILE_EXACT` set, the bodies are tested exactly.
mod support;

use stochastic_collision::prelude::*;
use support::pile::{self, Args, USAGE};

fn main() {
    let mut args = match Args::parse(std::env::args().skip(1)) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("pile: {e}\n{USAGE}");
            std::process::exit(2);
        }
    };
    if args.help {
        println!("{USAGE}");
        return;
    }
    args.fidelity = std::env::var_os("PILE_EXACT").map(|_| Fidelity::Exact);
    let (_, report) = pile::run(&args);
    print!("{report}");
    if let Err(e) = &report.picture {
        eprintln!("pile: {e}");
        std::process::exit(1);
    }
}
