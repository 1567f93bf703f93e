//! The `pile` example's picture of its final scene, through the code its `main` runs
//! (`examples/support/pile.rs`): the command line, the run and the SVG written. The picture
//! holds one outline per body and one dot per contact point of the touching pairs, as the
//! final world's `CollisionPairs` report them; bad arguments and an unwritable path are
//! errors, not panics.
#[path = "../examples/support/mod.rs"]
mod support;

use std::path::PathBuf;

use bevy_ecs::prelude::*;
use bevy_ecs::system::RunSystemOnce;
use plotters::style::RGBColor;
use stochastic_collision::prelude::*;
use support::pile::picture::{CONTACT_COLOR, OUTLINE_COLOR};
use support::pile::{Args, run};

/// A fresh scratch directory for this process and `tag`.
fn scratch(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sc_pile_picture_{}_{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn args(list: &[&str]) -> Result<Args, String> {
    Args::parse(list.iter().map(|s| s.to_string()))
}

/// The SVG elements `<tag ...>` whose attribute `attr` is `color`.
fn count(svg: &str, tag: &str, attr: &str, color: RGBColor) -> usize {
    let value = format!("{attr}=\"#{:02X}{:02X}{:02X}\"", color.0, color.1, color.2);
    svg.split('<')
        .filter(|e| e.starts_with(&format!("{tag} ")))
        .filter(|e| e.contains(&value))
        .count()
}

#[test]
fn pile_picture_has_every_body_and_contact() {
    // In a directory that does not exist yet: the run creates it.
    let path = scratch("full").join("new").join("pile.svg");
    let args = args(&["40", "90", "0", "--svg", path.to_str().unwrap()]).unwrap();
    let (mut app, report) = run(&args);
    let picture = report.picture.clone().expect("the picture is written");

    // What the final scene holds, read independently of the picture code.
    let world = app.world_mut();
    let bodies = world
        .query_filtered::<(), With<BodyVelocity>>()
        .iter(world)
        .count();
    let contacts = world
        .run_system_once(|pairs: CollisionPairs| {
            pairs
                .iter()
                .filter(|p| p.touching())
                .map(|p| p.contacts().len())
                .sum::<usize>()
        })
        .unwrap();
    assert_eq!(bodies, 40);
    // The bodies have landed: each rests on the floor or on another body.
    assert!(contacts >= bodies / 2, "{contacts} contact points");
    assert_eq!((picture.bodies, picture.contacts), (bodies, contacts));
    assert_eq!(picture.box_pieces, 5, "the floor and four walls");

    let svg = std::fs::read_to_string(&path).unwrap();
    assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(200)]);
    assert!(svg.trim_end().ends_with("</svg>"));
    assert_eq!(
        count(&svg, "circle", "fill", CONTACT_COLOR),
        contacts,
        "one dot per contact point"
    );
    assert_eq!(
        count(&svg, "polyline", "stroke", OUTLINE_COLOR),
        bodies,
        "one outline per body"
    );
    let polygons = svg.split('<').filter(|e| e.starts_with("polygon ")).count();
    assert!(
        polygons >= bodies + 2,
        "{polygons} filled shapes: the bodies, the floor and the side walls"
    );

    // The printed summary names the picture and what it shows.
    let summary = report.to_string();
    assert!(summary.contains(&path.display().to_string()), "{summary}");
    assert!(
        summary.contains(&format!("({bodies} bodies, {contacts} contact points")),
        "{summary}"
    );
}

#[test]
fn pile_command_line_and_write_errors() {
    let defaults = args(&[]).unwrap();
    assert_eq!(
        (defaults.bodies, defaults.frames, defaults.budget_us),
        (500, 240, 2000)
    );
    assert_eq!(defaults.svg, PathBuf::from("target/pile.svg"));
    let set = args(&["--svg", "out/p.svg", "12", "5"]).unwrap();
    assert_eq!(
        (set.bodies, set.frames, set.svg),
        (12, 5, PathBuf::from("out/p.svg"))
    );
    for (bad, says) in [
        (&["--svg"][..], "--svg needs a value"),
        (&["--svg", "--help"][..], "--svg needs a file path"),
        (&["many"][..], "BODIES: invalid number `many`"),
        (&["10", "-"][..], "unknown flag -"),
        (&["10", "x"][..], "FRAMES: invalid number `x`"),
        (&["0"][..], "BODIES: at least 1"),
        (&["1", "2", "3", "4"][..], "unexpected argument `4`"),
        (&["--frames", "3"][..], "unknown flag --frames"),
    ] {
        let e = args(bad).unwrap_err();
        assert!(e.contains(says), "{bad:?}: {e}");
    }

    // A path under a file cannot be written: the report says why, naming the path.
    let dir = scratch("unwritable");
    std::fs::write(dir.join("file"), "").unwrap();
    let path = dir.join("file").join("pile.svg");
    let (_, report) = run(&args(&["4", "2", "--svg", path.to_str().unwrap()]).unwrap());
    let e = report.picture.clone().unwrap_err();
    assert!(e.contains(&dir.join("file").display().to_string()), "{e}");
    assert!(report.to_string().contains("no picture: "), "{report}");
}
