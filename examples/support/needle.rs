//! Needle: needles shot down through a deformable cloth, each crossing it within one frame, both
//! tracked (`Fidelity::Tracking`), with and without `ContinuousCollision` on the needles. A
//! needle is a thin capped tube 0.3 long; per frame it falls 0.35-0.9, so at most poses it is
//! above the cloth and at the next below, and the discrete tracker sees it only when a frame
//! happens to end with it through the cloth. Both runs are checked against the exact
//! continuous query over each frame's motion. The `needle` example's run ([`run`]) and its side
//! view ([`picture`]).
use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Instant;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::ccd::{CcdOptions, CcdWorkspace, RigidMotion, time_of_impact};
use stochastic_collision::prelude::*;

use super::Options;

/// Half the cloth's side: it spans x, z in [-0.5, 0.5] at y = 0.
const CLOTH_HALF: f32 = 0.5;
const NEEDLE_LENGTH: f32 = 0.3;
const NEEDLE_RADIUS: f32 = 0.01;
const TRACKED: Fidelity = Fidelity::Tracking {
    pairs_per_frame: 32,
};

/// The command line of the `needle` example.
#[derive(Debug, Clone, PartialEq)]
pub struct Args {
    pub needles: usize,
    pub frames: usize,
    pub seed: u64,
    pub svg: PathBuf,
    pub help: bool,
}

impl Default for Args {
    fn default() -> Self {
        Self {
            needles: 100,
            frames: 12,
            seed: 1,
            svg: PathBuf::from("target/needle.svg"),
            help: false,
        }
    }
}

/// Usage of the `needle` example.
pub const USAGE: &str = "usage: needle [--needles N (100)] [--frames N (12)] [--seed S (1)] \
                         [--svg PATH (target/needle.svg)]";

impl Args {
    /// Parses `--needles`, `--frames`, `--seed`, `--svg`, `-h`.
    pub fn parse<I: IntoIterator<Item = String>>(args: I) -> Result<Args, String> {
        let mut parsed = Args::default();
        let mut it = args.into_iter();
        while let Some(flag) = it.next() {
            if flag == "-h" || flag == "--help" {
                parsed.help = true;
                continue;
            }
            let value = it.next().ok_or(format!("{flag} needs a value"))?;
            let count = || -> Result<usize, String> {
                value
                    .parse::<usize>()
                    .ok()
                    .filter(|v| *v > 0)
                    .ok_or(format!("{flag}: `{value}` is not a positive count"))
            };
            match flag.as_str() {
                "--needles" => parsed.needles = count()?,
                "--frames" => parsed.frames = count()?,
                "--seed" => {
                    parsed.seed = value
                        .parse()
                        .map_err(|_| format!("--seed: `{value}` is not a seed"))?
                }
                "--svg" => parsed.svg = PathBuf::from(value),
                other => return Err(format!("unknown flag {other}")),
            }
        }
        Ok(parsed)
    }
}

/// A needle: where it starts, how it is tilted, how far it falls per frame.
#[derive(Component, Debug, Clone, Copy)]
pub struct Needle {
    pub index: usize,
    pub start: Vec3,
    pub tilt: Quat,
    pub fall: f32,
}

impl Needle {
    /// Its pose after `moves` frames of fall.
    pub fn pose(&self, moves: usize) -> Pose {
        Pose::new(self.start - Vec3::Y * self.fall * moves as f32, self.tilt)
    }
}

/// The needles: above the cloth (some beside it), tilted up to 0.5 rad, falling 0.35-0.9 per
/// frame.
pub fn needles(args: &Args) -> Vec<Needle> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(args.seed);
    (0..args.needles)
        .map(|index| {
            let start = Vec3::new(
                rng.random_range(-0.6..0.6),
                rng.random_range(0.8..2.5),
                rng.random_range(-0.6..0.6),
            );
            let axis = Vec3::new(
                rng.random_range(-1.0..1.0),
                0.0,
                rng.random_range(-1.0..1.0),
            );
            let tilt =
                Quat::from_axis_angle(axis.normalize_or(Vec3::X), rng.random_range(0.0..0.5));
            Needle {
                index,
                start,
                tilt,
                fall: rng.random_range(0.35..0.9),
            }
        })
        .collect()
}

fn needle_mesh() -> TriMesh {
    generate::tube(NEEDLE_RADIUS, NEEDLE_LENGTH, 8, 6, true)
}

fn cloth_mesh() -> TriMesh {
    generate::cloth_grid(2.0 * CLOTH_HALF, 2.0 * CLOTH_HALF, 24, 24)
}

/// Frames flown: the plugin's run `k` sees each needle after `k` frames of fall.
#[derive(Resource, Default)]
struct Frame(usize);

fn fall(mut frame: ResMut<Frame>, mut q: Query<(&Needle, &mut ColliderPose)>) {
    frame.0 += 1;
    for (needle, mut pose) in &mut q {
        pose.0 = needle.pose(frame.0);
    }
}

/// Each needle's first contact with the cloth: the run, and the time of impact.
#[derive(Resource, Default)]
struct FirstContacts(HashMap<Entity, (u64, Option<f32>)>);

fn record(
    mut first: ResMut<FirstContacts>,
    mut reader: MessageReader<CollisionStarted>,
    diagnostics: Res<CollisionDiagnostics>,
) {
    for s in reader.read() {
        for e in [s.entity, s.other] {
            first
                .0
                .entry(e)
                .or_insert((diagnostics.frame, s.time_of_impact));
        }
    }
}

/// One flight of the needles: each needle's first contact, and the collision stages' time.
#[derive(Debug, Clone)]
pub struct Flight {
    pub contacts: Vec<Option<(u64, Option<f32>)>>,
    pub collision_ms: f64,
}

/// Flies the needles through the cloth with the plugin, both tracked, the needles swept or not.
pub fn fly(args: &Args, continuous: bool) -> Flight {
    let options = Options {
        budget_us: 0,
        seed: args.seed,
        ..Options::default()
    };
    let mut app = App::new();
    app.add_plugins(options.plugin())
        .init_resource::<Frame>()
        .init_resource::<FirstContacts>()
        .add_systems(PostUpdate, fall.before(CollisionSystems::Prepare))
        .add_systems(PostUpdate, record.after(CollisionSystems::Report));
    let world = app.world_mut();
    world.spawn((
        Deformable::new(cloth_mesh()),
        ColliderPose(Pose::IDENTITY),
        TRACKED,
    ));
    let mesh = MeshCollider::new(needle_mesh());
    let mut entities = Vec::new();
    for needle in needles(args) {
        let mut e = world.spawn((
            mesh.clone(),
            ColliderPose(needle.pose(0)),
            needle,
            TRACKED,
            // Needles do not collide with each other.
            ContactLayers::new(0b10, 0b01),
        ));
        if continuous {
            e.insert(ContinuousCollision::Always);
        }
        entities.push(e.id());
    }
    let mut collision = 0.0;
    for _ in 0..args.frames {
        app.update();
        collision += app
            .world()
            .resource::<CollisionDiagnostics>()
            .collision_time
            .as_secs_f64();
    }
    let first = &app.world().resource::<FirstContacts>().0;
    Flight {
        contacts: entities.iter().map(|e| first.get(e).copied()).collect(),
        collision_ms: collision * 1e3,
    }
}

/// The reference: for each needle, the first run in which it touches the cloth. Run 1 only
/// places it (the plugin has no motion for a collider it has just met): a contact there is one
/// at its pose after the first frame (the exact discrete query; time 1). From run 2 on, the
/// exact continuous query over the run's frame of motion (from its pose after `k - 1` frames
/// to its pose after `k`), and when in that frame.
pub fn reference(args: &Args) -> Vec<Option<(u64, f32)>> {
    let cloth = CollisionMesh::new(cloth_mesh());
    let needle = CollisionMesh::new(needle_mesh());
    let still = RigidMotion::still(Pose::IDENTITY);
    let (mut ws, mut exact) = (CcdWorkspace::new(), QueryWorkspace::new());
    needles(args)
        .iter()
        .map(|n| {
            if intersects(&cloth, &Pose::IDENTITY, &needle, &n.pose(1), &mut exact) {
                return Some((1, 1.0));
            }
            (2..=args.frames).find_map(|k| {
                let motion = RigidMotion::new(n.pose(k - 1), n.pose(k));
                let options = CcdOptions::default();
                let hit = time_of_impact(&cloth, &still, &needle, &motion, &options, &mut ws)
                    .expect("finite poses")?;
                Some((k as u64, hit.time))
            })
        })
        .collect()
}

/// How a flight's contacts compare with the reference.
#[derive(Debug, Clone, Copy, Default)]
pub struct Verdicts {
    /// Reference crossings the flight reported, in the same run.
    pub detected: usize,
    /// Reported in an earlier run than the reference's (tracking reports contacts within its
    /// thickness, so a needle a hair above the cloth at the end of a frame counts).
    pub early_run: usize,
    /// Reported in a later run than the reference's.
    pub late_run: usize,
    /// Reported for needles the reference never sees touching.
    pub false_hits: usize,
    /// Detected with a time of impact more than 1e-3 of a frame after the reference's.
    pub late: usize,
    /// Largest difference from the reference's time of impact (frames), where both have one.
    pub worst_time_error: f32,
}

fn verdicts(flight: &Flight, reference: &[Option<(u64, f32)>]) -> Verdicts {
    let mut v = Verdicts::default();
    for (c, r) in flight.contacts.iter().zip(reference) {
        match (c, r) {
            (Some((run, toi)), Some((ref_run, ref_t))) if run == ref_run => {
                v.detected += 1;
                if let Some(t) = toi {
                    v.late += usize::from(*t > ref_t + 1e-3);
                    v.worst_time_error = v.worst_time_error.max((t - ref_t).abs());
                }
            }
            (Some((run, _)), Some((ref_run, _))) if run < ref_run => v.early_run += 1,
            (Some(_), Some(_)) => v.late_run += 1,
            (Some(_), None) => v.false_hits += 1,
            _ => {}
        }
    }
    v
}

/// What the `needle` example found; its `Display` is the printed summary.
#[derive(Debug, Clone)]
pub struct Report {
    pub args: Args,
    /// Needles that cross the cloth (reference).
    pub crossing: usize,
    pub discrete: Verdicts,
    pub continuous: Verdicts,
    pub discrete_ms: f64,
    pub continuous_ms: f64,
    pub reference_s: f64,
    pub picture: Result<PathBuf, String>,
}

/// Runs the reference and both flights, draws the picture.
pub fn run(args: &Args) -> Report {
    let t = Instant::now();
    let reference = reference(args);
    let reference_s = t.elapsed().as_secs_f64();
    let discrete = fly(args, false);
    let continuous = fly(args, true);
    let picture = picture(&args.svg, args, &discrete, &continuous, &reference);
    Report {
        args: args.clone(),
        crossing: reference.iter().flatten().count(),
        discrete: verdicts(&discrete, &reference),
        continuous: verdicts(&continuous, &reference),
        discrete_ms: discrete.collision_ms,
        continuous_ms: continuous.collision_ms,
        reference_s,
        picture,
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = &self.args;
        writeln!(
            f,
            "needle: {} needles ({NEEDLE_LENGTH} long) falling 0.35-0.9 per frame through a tracked cloth, {} frames, seed {}",
            a.needles, a.frames, a.seed
        )?;
        writeln!(
            f,
            "  reference (exact continuous query over each frame, {:.1} s): {} needles cross the cloth",
            self.reference_s, self.crossing
        )?;
        for (name, v, ms) in [
            ("discrete tracking", self.discrete, self.discrete_ms),
            ("continuous tracking", self.continuous, self.continuous_ms),
        ] {
            writeln!(
                f,
                "  {name}: detected {} of {} in the reference's frame ({} passed through unseen), {} a frame early (within the tracker's thickness), {} in a later frame, {} false, {} later than the reference in its frame (worst time error {:.4} of a frame); collision stages {ms:.1} ms in all",
                v.detected,
                self.crossing,
                self.crossing - v.detected - v.early_run - v.late_run,
                v.early_run,
                v.late_run,
                v.false_hits,
                v.late,
                v.worst_time_error
            )?;
        }
        match &self.picture {
            Ok(p) => writeln!(f, "  side view: {}", p.display()),
            Err(e) => writeln!(f, "  no picture: {e}"),
        }
    }
}

/// A side view (x, y) of the cloth and of every needle that crosses it (reference), at its
/// last pose above the cloth: red when the discrete run missed it, green when the continuous
/// run found it (a ring around it when both did).
fn picture(
    path: &Path,
    args: &Args,
    discrete: &Flight,
    continuous: &Flight,
    reference: &[Option<(u64, f32)>],
) -> Result<PathBuf, String> {
    let (w, h) = (600.0f32, 400.0f32);
    let (x0, x1, y0, y1) = (-0.8f32, 0.8f32, -0.9f32, 1.0f32);
    let sx = |x: f32| (x - x0) / (x1 - x0) * w;
    let sy = |y: f32| h - (y - y0) / (y1 - y0) * h;
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n\
         <line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"#444\" stroke-width=\"2\"/>\n",
        sx(-CLOTH_HALF),
        sy(0.0),
        sx(CLOTH_HALF),
        sy(0.0)
    );
    let all = needles(args);
    for (k, r) in reference.iter().enumerate() {
        let Some((run, _)) = r else { continue };
        // The needle's axis at its pose before the crossing frame.
        let pose = all[k].pose(*run as usize - 1);
        let half = pose.rotation * Vec3::Y * (0.5 * NEEDLE_LENGTH);
        let (p, q) = (pose.translation - half, pose.translation + half);
        let found = |f: &Flight| f.contacts[k].is_some_and(|(r, _)| r == *run);
        let colour = if found(continuous) {
            "#2ca02c"
        } else {
            "#d62728"
        };
        svg += &format!(
            "<line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"{colour}\" stroke-width=\"2\"/>\n",
            sx(p.x),
            sy(p.y),
            sx(q.x),
            sy(q.y)
        );
        if found(discrete) {
            svg += &format!(
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"5\" fill=\"none\" stroke=\"#1f77b4\"/>\n",
                sx(p.x),
                sy(p.y)
            );
        }
    }
    svg += "<text x=\"10\" y=\"20\" font-family=\"sans-serif\" font-size=\"13\">needles that cross the cloth, before the frame: found with continuous tracking (green) or not (red); ringed: found by discrete tracking</text>\n</svg>\n";
    super::write_svg(path, &svg)
}
