//! Pile: rigid meshes (generated, and shared ones when present) falling into a box, with the
//! built-in impulse response; the `pile` example's command line and run ([`Args`], [`run`]),
//! and its picture of the final scene ([`picture`]).
pub mod layout;
pub mod picture;

use std::fmt;
use std::path::PathBuf;
use std::time::Instant;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use stochastic_collision::ecs::{ImpulseSettings, Rest};
use stochastic_collision::prelude::*;

use super::{Options, Scene, normalized, shared_mesh};
use layout::pile_layout;

/// Default number of bodies.
pub const DEFAULT_BODIES: usize = 1000;

/// The bodies' meshes with their names: a few generated shapes, plus the shared Suzanne when
/// present.
pub fn body_kinds() -> Vec<(&'static str, MeshCollider)> {
    let mut meshes = vec![
        ("icosphere", generate::icosphere(0.25, 1)),
        ("torus", generate::torus(0.2, 0.08, 16, 8)),
        ("cube", generate::cuboid(Vec3::splat(0.18), 1)),
    ];
    if let Some(m) = shared_mesh("suzanne.obj") {
        meshes.push(("Suzanne", normalized(&m, 0.5)));
    }
    meshes
        .into_iter()
        .map(|(name, m)| (name, MeshCollider::new(m)))
        .collect()
}

/// The inside of the pile's box: `|x|, |z| < half`, above the floor at `y = 0`.
#[derive(Resource, Clone, Copy)]
pub struct PileBox {
    pub half: f32,
}

impl PileBox {
    /// Whether a body's origin is outside the box (below the floor or beyond a wall, by
    /// more than `margin`).
    pub fn outside(&self, p: Vec3, margin: f32) -> bool {
        p.y < -margin || p.x.abs() > self.half + margin || p.z.abs() > self.half + margin
    }
}

/// The meshes the bodies share, by name (the picture colours the bodies by kind).
#[derive(Resource, Clone)]
pub struct BodyKinds(pub Vec<(&'static str, MeshCollider)>);

pub fn setup(app: &mut App, options: &Options) {
    // The scene the measurements were made on steps at 60 Hz (the examples run without
    // bevy_time: one collision run per app update).
    app.add_plugins(
        ImpulseResponsePlugin::default().with_settings(ImpulseSettings {
            dt: Some(1.0 / 60.0),
            ..Default::default()
        }),
    );
    let layout = pile_layout(options.count(DEFAULT_BODIES), options.seed);
    let world = app.world_mut();
    world.insert_resource(PileBox { half: layout.half });
    // Subdivided, so that its tree has small leaves (a few huge triangles make every exact
    // test against it slow). The box is static level geometry: tested exactly (cheap, and
    // nothing may fall through it), on a layer of its own that does not collide with itself
    // (the walls stand on the floor and meet at the corners: nothing would act on those
    // contacts, and avian never pairs two static bodies); the bodies among themselves use the
    // default fidelity.
    for (h, at) in &layout.slabs {
        world.spawn((
            MeshCollider::new(generate::cuboid(*h, 12)),
            ColliderPose::from_translation(*at),
            Fidelity::Exact,
            layout::LEVEL_LAYERS,
        ));
    }
    let kinds = body_kinds();
    let colliders: Vec<MeshCollider> = kinds.iter().map(|(_, c)| c.clone()).collect();
    world.insert_resource(BodyKinds(kinds));
    for (i, body) in layout.bodies.iter().enumerate() {
        world.spawn((
            colliders[i % colliders.len()].clone(),
            ColliderPose(Pose::new(body.position, body.rotation)),
            BodyVelocity(body.velocity),
            BodyMass(1.0),
        ));
    }
}

/// Bodies with a velocity still above `speed` (how settled the pile is).
pub fn moving(world: &mut World, speed: f32) -> usize {
    let mut q = world.query::<&BodyVelocity>();
    q.iter(world).filter(|v| v.0.length() > speed).count()
}

/// Usage of the `pile` example.
pub const USAGE: &str = "usage: pile [BODIES (default 500)] [FRAMES (default 240)] \
                         [BUDGET_US (default 2000; 0: none)] [--svg PATH (default target/pile.svg)]";

/// The `pile` example's command line.
#[derive(Debug, Clone, PartialEq)]
pub struct Args {
    pub bodies: usize,
    pub frames: usize,
    /// Collision budget per frame, µs (0: none).
    pub budget_us: u64,
    /// Where the picture of the final scene goes.
    pub svg: PathBuf,
    /// Fidelity of the bodies (default: the plugin's).
    pub fidelity: Option<Fidelity>,
    /// `-h` / `--help`: print the usage only.
    pub help: bool,
}

impl Default for Args {
    fn default() -> Self {
        Self {
            bodies: 500,
            frames: 240,
            budget_us: 2000,
            svg: PathBuf::from("target/pile.svg"),
            fidelity: None,
            help: false,
        }
    }
}

impl Args {
    /// Parses the arguments (without the program name): up to three numbers (bodies, frames,
    /// budget) and `--svg PATH`, in any order.
    pub fn parse<I: IntoIterator<Item = String>>(args: I) -> Result<Args, String> {
        let mut parsed = Args::default();
        let mut it = args.into_iter();
        let mut position = 0;
        while let Some(arg) = it.next() {
            match arg.as_str() {
                "--svg" => {
                    let path = it.next().ok_or("--svg needs a value (a file path)")?;
                    if path.is_empty() || path.starts_with("--") {
                        return Err(format!("--svg needs a file path, not `{path}`"));
                    }
                    parsed.svg = PathBuf::from(path);
                }
                "-h" | "--help" => parsed.help = true,
                flag if flag.starts_with('-') => return Err(format!("unknown flag {flag}")),
                value => {
                    let name = ["BODIES", "FRAMES", "BUDGET_US"]
                        .get(position)
                        .ok_or(format!(
                            "unexpected argument `{value}` (three numbers at most)"
                        ))?;
                    let n = value
                        .parse::<u64>()
                        .map_err(|e| format!("{name}: invalid number `{value}` ({e})"))?;
                    match position {
                        0 if n == 0 => return Err("BODIES: at least 1".to_owned()),
                        0 => parsed.bodies = n as usize,
                        1 => parsed.frames = n as usize,
                        _ => parsed.budget_us = n,
                    }
                    position += 1;
                }
            }
        }
        Ok(parsed)
    }
}

/// What a run of the `pile` example found; its `Display` is the printed summary.
#[derive(Debug, Clone)]
pub struct Report {
    pub bodies: usize,
    pub frames: usize,
    pub budget_us: u64,
    /// Wall-clock time of the frames, s.
    pub elapsed: f64,
    /// Slowest collision stage run, ms.
    pub worst_ms: f64,
    pub inside: usize,
    /// Bodies outside the box: below its floor or beyond a wall.
    pub escaped: usize,
    pub moving: usize,
    pub asleep: usize,
    pub started: u64,
    pub ended: u64,
    pub adb_pairs: u64,
    pub budget_exhausted_pairs: u64,
    pub coherence_pairs: u64,
    /// The picture of the final scene, or why it was not written.
    pub picture: Result<picture::Picture, String>,
}

/// Builds the pile, runs its frames and draws the final scene; returns the app (in its final
/// state) and the report.
pub fn run(args: &Args) -> (App, Report) {
    let options = Options {
        entities: args.bodies,
        budget_us: args.budget_us,
        fidelity: args.fidelity,
        ..Options::default()
    };
    let mut app = Scene::Pile.build(&options);
    let start = Instant::now();
    let mut worst = 0f64;
    for _ in 0..args.frames {
        app.update();
        let d = app.world().resource::<CollisionDiagnostics>();
        worst = worst.max(d.collision_time.as_secs_f64() * 1e3);
    }
    let elapsed = start.elapsed().as_secs_f64();
    let world = app.world_mut();
    let moving = moving(world, 0.5);
    let asleep = world
        .query::<&Rest>()
        .iter(world)
        .filter(|r| r.is_asleep())
        .count();
    let mut q = world.query_filtered::<&ColliderPose, With<BodyVelocity>>();
    let walls = *world.resource::<PileBox>();
    let (inside, escaped) = q.iter(world).fold((0, 0), |(i, e), p| {
        let t = p.0.translation;
        let out = walls.outside(t, 0.1);
        (i + usize::from(!out && t.y < 3.5), e + usize::from(out))
    });
    let c = world.resource::<CollisionDiagnostics>().counters;
    let picture = picture::side_view(world, &args.svg);
    let report = Report {
        bodies: args.bodies,
        frames: args.frames,
        budget_us: args.budget_us,
        elapsed,
        worst_ms: worst,
        inside,
        escaped,
        moving,
        asleep,
        started: c.started,
        ended: c.ended,
        adb_pairs: c.adb_pairs,
        budget_exhausted_pairs: c.budget_exhausted_pairs,
        coherence_pairs: c.coherence_pairs,
        picture,
    };
    (app, report)
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "pile: {} bodies, {} frames in {:.2} s ({:.2} ms/frame, worst collision stage {:.2} ms, budget {} us)",
            self.bodies,
            self.frames,
            self.elapsed,
            self.elapsed * 1e3 / self.frames.max(1) as f64,
            self.worst_ms,
            self.budget_us
        )?;
        writeln!(
            f,
            "  {} bodies in the box, {} escaped it (below the floor or beyond a wall), {} still moving faster than 0.5 m/s, {} asleep",
            self.inside, self.escaped, self.moving, self.asleep
        )?;
        writeln!(
            f,
            "  {} contacts started, {} ended; {} ADB pairs ({} cut by the budget, {} answered from the last frame)",
            self.started,
            self.ended,
            self.adb_pairs,
            self.budget_exhausted_pairs,
            self.coherence_pairs
        )?;
        match &self.picture {
            Ok(p) => writeln!(
                f,
                "  picture of the final scene (side view): {} ({} bodies, {} contact points of {} touching pairs)",
                p.path.display(),
                p.bodies,
                p.contacts,
                p.touching_pairs
            ),
            Err(e) => writeln!(f, "  no picture: {e}"),
        }
    }
}
