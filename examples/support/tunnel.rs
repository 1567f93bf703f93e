//! Tunnel: cannonball shots at a multiple of their speed against a wall a tenth of the ball's
//! diameter thick, with the discrete exact test and with continuous collision
//! (`ContinuousCollision`): exact (the wall rigid, and a `Deformable`, whose swept pairs get
//! the deforming query), and ADB pairs with the time-critical continuous query (conservative
//! and estimating, within a work budget and at the plugin's default time budget),
//! each against a reference that sub-steps every frame with the exact query. The
//! `tunnel` example's run ([`run`]) and its side view ([`picture`]).
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Instant;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use stochastic_collision::prelude::*;

use super::Options;
use super::cannonball::random_shot;

/// The time step of the shots' flight (60 Hz, one collision run per frame).
pub const DT: f32 = 1.0 / 60.0;
const GRAVITY: f32 = -9.81;
/// The ball's radius (its diameter 0.3).
pub const RADIUS: f32 = 0.15;
/// Half the wall's thickness: the wall is a tenth of the ball's diameter thick.
pub const WALL_HALF: f32 = 0.1 * RADIUS;
/// The wall's half height and half width (it stands on y = 0, centred on z = 0).
const WALL_SIZE: Vec3 = Vec3::new(WALL_HALF, 3.0, 8.0);
/// Sub-steps per frame of the reference (each a straight segment of the frame's motion).
pub const REFERENCE_SUBSTEPS: usize = 1024;

/// The command line of the `tunnel` example.
#[derive(Debug, Clone, PartialEq)]
pub struct Args {
    pub shots: usize,
    /// The shots' speed as a multiple of the cannonball example's.
    pub speed: f32,
    pub frames: usize,
    pub seed: u64,
    pub svg: PathBuf,
    /// ADB node pairs per run of the budgeted ADB runs.
    pub adb_budget: u64,
    pub help: bool,
}

impl Default for Args {
    fn default() -> Self {
        Self {
            shots: 300,
            speed: 10.0,
            frames: 30,
            seed: 1,
            svg: PathBuf::from("target/tunnel.svg"),
            adb_budget: 100,
            help: false,
        }
    }
}

/// Usage of the `tunnel` example.
pub const USAGE: &str = "usage: tunnel [--shots N (300)] [--speed K (10: times the cannonball's)] \
                         [--frames N (30)] [--seed S (1)] [--svg PATH (target/tunnel.svg)] \
                         [--adb-budget N (100 ADB node pairs per run)]";

impl Args {
    /// Parses `--shots`, `--speed`, `--frames`, `--seed`, `--svg`, `--adb-budget`, `-h`.
    pub fn parse<I: IntoIterator<Item = String>>(args: I) -> Result<Args, String> {
        let mut parsed = Args::default();
        let mut it = args.into_iter();
        while let Some(flag) = it.next() {
            if flag == "-h" || flag == "--help" {
                parsed.help = true;
                continue;
            }
            let value = it.next().ok_or(format!("{flag} needs a value"))?;
            let number = |what: &str| -> Result<f64, String> {
                value
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite() && *v > 0.0)
                    .ok_or(format!("{flag}: `{value}` is not a positive {what}"))
            };
            match flag.as_str() {
                "--shots" => parsed.shots = number("count")? as usize,
                "--speed" => parsed.speed = number("number")? as f32,
                "--frames" => parsed.frames = number("count")? as usize,
                "--seed" => {
                    parsed.seed = value
                        .parse()
                        .map_err(|_| format!("--seed: `{value}` is not a seed"))?
                }
                "--svg" => parsed.svg = PathBuf::from(value),
                "--adb-budget" => parsed.adb_budget = number("count")? as u64,
                other => return Err(format!("unknown flag {other}")),
            }
        }
        if parsed.shots == 0 || parsed.frames == 0 {
            return Err("--shots and --frames must be at least 1".to_owned());
        }
        Ok(parsed)
    }
}

/// A shot: its start, its velocity, and where and when it first touched the wall.
#[derive(Component, Debug, Clone, Copy)]
pub struct Shot {
    pub index: usize,
    pub start: Vec3,
    pub velocity: Vec3,
    /// Run of its first contact, and the time of impact in that run's step, if reported.
    pub hit: Option<(u64, Option<f32>)>,
    /// Where it stopped (at its first contact) or the end of its flight.
    pub stop: Vec3,
}

/// The shots' starts and velocities: the cannonball example's distribution times `speed`.
pub fn shots(args: &Args) -> Vec<(Vec3, Vec3)> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(args.seed);
    (0..args.shots)
        .map(|_| {
            let (start, v) = random_shot(&mut rng);
            (start, v * args.speed)
        })
        .collect()
}

fn ball_mesh() -> TriMesh {
    generate::icosphere(RADIUS, 2)
}

fn wall_mesh() -> TriMesh {
    generate::cuboid(WALL_SIZE, 8)
}

fn wall_pose() -> Pose {
    Pose::from_translation(Vec3::new(0.0, WALL_SIZE.y, 0.0))
}

/// Moves the flying shots one frame (before the collision stages).
fn fly(mut q: Query<(&mut Shot, &mut ColliderPose)>) {
    for (mut shot, mut pose) in &mut q {
        if shot.hit.is_some() {
            continue;
        }
        shot.velocity.y += GRAVITY * DT;
        pose.0.translation += shot.velocity * DT;
        shot.stop = pose.0.translation;
    }
}

/// A shot that touches the wall stops there; its first contact is recorded.
fn stop_at_wall(mut queue: ResMut<ContactQueue>, mut shots: Query<(&mut Shot, &ColliderPose)>) {
    queue.consume(|c| {
        for e in [c.a, c.b] {
            if let Ok((mut shot, pose)) = shots.get_mut(e) {
                if shot.hit.is_none() {
                    shot.hit = Some((c.frame, c.time_of_impact));
                    shot.stop = match c.time_of_impact {
                        // Where it was when it touched.
                        Some(t) => pose.0.translation - shot.velocity * DT * (1.0 - t),
                        None => pose.0.translation,
                    };
                }
                return true;
            }
        }
        false
    });
}

/// One run of the scene: every shot's first contact (run, time of impact), where it stopped,
/// and the collision stages' time.
#[derive(Debug, Clone)]
pub struct Flight {
    pub shots: Vec<Shot>,
    pub collision_ms: f64,
    pub swept_pairs: u64,
    pub caught_by_sweep: u64,
}

/// How a flight tests the balls against the wall.
#[derive(Debug, Clone, Copy)]
pub struct Setup {
    pub continuous: Option<ContinuousCollision>,
    /// Exact, or ADB (`p_min` 0.99).
    pub adb: bool,
    /// The plugin's budget: ADB node pairs per run, else a time per run in µs (0: unlimited).
    pub node_budget: Option<u64>,
    pub budget_us: u64,
    /// `CollisionConfig::continuous_adb_conservative`.
    pub conservative: bool,
    /// The wall a `Deformable` (still): swept pairs get the deforming query, both meshes'
    /// vertices on straight lines in world coordinates.
    pub deformable_wall: bool,
}

impl Setup {
    /// The wall tested exactly, no budget.
    pub fn exact(continuous: Option<ContinuousCollision>) -> Self {
        Self {
            continuous,
            adb: false,
            node_budget: None,
            budget_us: 0,
            conservative: true,
            deformable_wall: false,
        }
    }
}

/// Flies the shots with the plugin, the wall tested as `setup` says, the balls swept or not.
pub fn fly_shots(args: &Args, setup: Setup) -> Flight {
    let fidelity = if setup.adb {
        Fidelity::Adb { p_min: 0.99 }
    } else {
        Fidelity::Exact
    };
    let options = Options {
        budget_us: setup.budget_us,
        node_budget: setup.node_budget,
        seed: args.seed,
        fidelity: Some(fidelity),
        ..Options::default()
    };
    let config = CollisionConfig {
        continuous_adb_conservative: setup.conservative,
        ..options.config()
    };
    let mut app = App::new();
    app.add_plugins(options.plugin().with_config(config))
        .add_systems(PostUpdate, fly.before(CollisionSystems::Prepare))
        .add_systems(PostUpdate, stop_at_wall.in_set(CollisionSystems::Response));
    let world = app.world_mut();
    world.resource_mut::<ContactQueue>().enable();
    if setup.deformable_wall {
        world.spawn((Deformable::new(wall_mesh()), ColliderPose(wall_pose())));
    } else {
        world.spawn((
            MeshCollider::new(wall_mesh()),
            ColliderPose(wall_pose()),
            fidelity,
        ));
    }
    let ball = MeshCollider::new(ball_mesh());
    for (index, (start, velocity)) in shots(args).into_iter().enumerate() {
        let mut e = world.spawn((
            ball.clone(),
            ColliderPose::from_translation(start),
            Shot {
                index,
                start,
                velocity,
                hit: None,
                stop: start,
            },
            // Shots do not collide with each other.
            ContactLayers::new(0b10, 0b01),
        ));
        if let Some(c) = setup.continuous {
            e.insert(c);
        }
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
    let world = app.world_mut();
    let counters = world.resource::<CollisionDiagnostics>().counters;
    let mut shots: Vec<Shot> = world.query::<&Shot>().iter(world).copied().collect();
    shots.sort_by_key(|s| s.index);
    Flight {
        shots,
        collision_ms: collision * 1e3,
        swept_pairs: counters.swept_pairs,
        caught_by_sweep: counters.caught_by_sweep,
    }
}

/// The reference: every shot flown frame by frame as the scene flies it, each frame's straight
/// motion sub-stepped [`REFERENCE_SUBSTEPS`] times with the exact query; the run in which
/// the ball first touches the wall, and when in that frame. Runs are numbered as the plugin
/// numbers them ([`CollisionDiagnostics::frame`]): run `k` sees the pose after `k` frames of
/// flight, so frame `k`'s motion (from `k - 1` frames to `k`) is run `k`'s. `None`: it never
/// touches.
pub fn reference(args: &Args) -> Vec<Option<(u64, f32)>> {
    let ball = CollisionMesh::new(ball_mesh());
    let wall = CollisionMesh::new(wall_mesh());
    let wall_pose = wall_pose();
    let mut ws = QueryWorkspace::default();
    shots(args)
        .into_iter()
        .map(|(start, v0)| {
            let (mut p, mut v) = (start, v0);
            for run in 1..=args.frames as u64 {
                v.y += GRAVITY * DT;
                let next = p + v * DT;
                // Far from the wall: the frame's segment cannot reach it.
                let reach = RADIUS + WALL_HALF + 0.01;
                if p.x.min(next.x) > reach || p.x.max(next.x) < -reach {
                    p = next;
                    continue;
                }
                for k in 0..=REFERENCE_SUBSTEPS {
                    let t = k as f32 / REFERENCE_SUBSTEPS as f32;
                    let pose = Pose::from_translation(p.lerp(next, t));
                    let hit = intersects_with(
                        &ball,
                        &pose,
                        &wall,
                        &wall_pose,
                        &ExactOptions::default(),
                        &mut ws,
                    );
                    if hit.collides {
                        return Some((run, t));
                    }
                }
                p = next;
            }
            None
        })
        .collect()
}

/// What the `tunnel` example found; its `Display` is the printed summary.
#[derive(Debug, Clone)]
pub struct Report {
    pub args: Args,
    /// Shots that touch the wall (reference).
    pub crossing: usize,
    pub discrete: Verdicts,
    pub continuous: Verdicts,
    pub discrete_ms: f64,
    pub continuous_ms: f64,
    pub swept_pairs: u64,
    pub caught_by_sweep: u64,
    /// The continuous exact run with the wall a `Deformable`.
    pub deformable: Verdicts,
    pub deformable_ms: f64,
    pub deformable_swept_pairs: u64,
    pub reference_s: f64,
    /// Largest difference between the continuous run's time of impact and the reference's,
    /// in frames, over the shots both found in the same run.
    pub worst_time_error: f32,
    /// Of those, how many report a time of impact later than the reference's first sub-step
    /// in contact (the continuous query must never be late).
    pub late: usize,
    /// The runs with ADB pairs swept by the time-critical continuous query.
    pub adb: Vec<AdbRun>,
    pub picture: Result<PathBuf, String>,
}

/// A flight with ADB pairs and `ContinuousCollision::Always`.
#[derive(Debug, Clone)]
pub struct AdbRun {
    pub name: String,
    pub verdicts: Verdicts,
    pub ms: f64,
    pub swept_pairs: u64,
    /// Contacts reported in the reference's run later in it than the reference's time of
    /// impact (the conservative query must never be late).
    pub late: usize,
}

/// How one run's contacts compare with the reference.
#[derive(Debug, Clone, Copy, Default)]
pub struct Verdicts {
    /// Reference contacts the run reported (in any run).
    pub detected: usize,
    /// Of those, in the same run as the reference.
    pub same_run: usize,
    /// Reported contacts the reference does not have.
    pub false_hits: usize,
}

fn verdicts(flight: &Flight, reference: &[Option<(u64, f32)>]) -> Verdicts {
    let mut v = Verdicts::default();
    for (shot, r) in flight.shots.iter().zip(reference) {
        match (shot.hit, r) {
            (Some((run, _)), Some((ref_run, _))) => {
                v.detected += 1;
                v.same_run += usize::from(run == *ref_run);
            }
            (Some(_), None) => v.false_hits += 1,
            _ => {}
        }
    }
    v
}

/// Runs the reference, the discrete and the continuous flights, draws the picture.
pub fn run(args: &Args) -> Report {
    let t = Instant::now();
    let reference = reference(args);
    let reference_s = t.elapsed().as_secs_f64();
    let discrete = fly_shots(args, Setup::exact(None));
    let continuous = fly_shots(args, Setup::exact(Some(ContinuousCollision::Always)));
    let deformable = fly_shots(
        args,
        Setup {
            deformable_wall: true,
            ..Setup::exact(Some(ContinuousCollision::Always))
        },
    );
    let adb = |name: String, node_budget: Option<u64>, conservative: bool| {
        let setup = Setup {
            continuous: Some(ContinuousCollision::Always),
            adb: true,
            node_budget,
            budget_us: 2000,
            conservative,
            deformable_wall: false,
        };
        let flight = fly_shots(args, setup);
        let late = flight
            .shots
            .iter()
            .zip(&reference)
            .filter(|(s, r)| match (s.hit, r) {
                (Some((run, toi)), Some((ref_run, ref_t))) => {
                    run == *ref_run && toi.unwrap_or(1.0) > *ref_t + 1e-6
                }
                _ => false,
            })
            .count();
        AdbRun {
            name,
            verdicts: verdicts(&flight, &reference),
            ms: flight.collision_ms,
            swept_pairs: flight.swept_pairs,
            late,
        }
    };
    let n = args.adb_budget;
    let adb = vec![
        adb(
            "continuous (ADB, conservative, the default 2000 µs budget)".to_owned(),
            None,
            true,
        ),
        adb(
            format!("continuous (ADB, conservative, {n} node pairs per run)"),
            Some(n),
            true,
        ),
        adb(
            "continuous (ADB, estimating, the default 2000 µs budget)".to_owned(),
            None,
            false,
        ),
        adb(
            format!("continuous (ADB, estimating, {n} node pairs per run)"),
            Some(n),
            false,
        ),
    ];
    // Continuous time of impact less the reference's, for shots found in the same run.
    let offsets: Vec<f32> = continuous
        .shots
        .iter()
        .zip(&reference)
        .filter_map(|(s, r)| {
            let ((run, toi), (ref_run, ref_t)) = (s.hit?, (*r)?);
            (run == ref_run).then(|| toi.unwrap_or(1.0) - ref_t)
        })
        .collect();
    let worst_time_error = offsets.iter().map(|d| d.abs()).fold(0.0f32, f32::max);
    let late = offsets.iter().filter(|d| **d > 1e-6).count();
    let picture = picture(&args.svg, &discrete, &continuous, &reference);
    Report {
        args: args.clone(),
        crossing: reference.iter().flatten().count(),
        discrete: verdicts(&discrete, &reference),
        continuous: verdicts(&continuous, &reference),
        discrete_ms: discrete.collision_ms,
        continuous_ms: continuous.collision_ms,
        swept_pairs: continuous.swept_pairs,
        caught_by_sweep: continuous.caught_by_sweep,
        deformable: verdicts(&deformable, &reference),
        deformable_ms: deformable.collision_ms,
        deformable_swept_pairs: deformable.swept_pairs,
        reference_s,
        worst_time_error,
        late,
        adb,
        picture,
    }
}

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = &self.args;
        writeln!(
            f,
            "tunnel: {} shots at {}x the cannonball's speed ({:.1}-{:.1} units per frame) against a wall {:.3} thick (a tenth of the ball's diameter), {} frames, seed {}",
            a.shots,
            a.speed,
            14.0 * a.speed * DT,
            22.0 * a.speed * DT,
            2.0 * WALL_HALF,
            a.frames,
            a.seed
        )?;
        writeln!(
            f,
            "  reference ({REFERENCE_SUBSTEPS} exact sub-steps per frame, {:.1} s): {} shots touch the wall",
            self.reference_s, self.crossing
        )?;
        for (name, v, ms) in [
            ("discrete exact", self.discrete, self.discrete_ms),
            ("continuous (exact)", self.continuous, self.continuous_ms),
        ] {
            writeln!(
                f,
                "  {name}: detected {} of {} ({} in the reference's frame), {} tunnelled, {} false; collision stages {ms:.1} ms in all",
                v.detected,
                self.crossing,
                v.same_run,
                self.crossing - v.detected,
                v.false_hits
            )?;
        }
        writeln!(
            f,
            "  continuous: {} pairs swept, {} contacts the discrete test missed; time of impact within {:.4} of the frame of the reference's (resolution {:.4}), later than it for {}",
            self.swept_pairs,
            self.caught_by_sweep,
            self.worst_time_error,
            1.0 / REFERENCE_SUBSTEPS as f32,
            self.late
        )?;
        let v = self.deformable;
        writeln!(
            f,
            "  continuous (exact, the wall a Deformable: both meshes' vertices on straight lines in world coordinates): detected {} of {} ({} in the reference's frame), {} tunnelled, {} false; {} pairs swept; collision stages {:.1} ms in all",
            v.detected,
            self.crossing,
            v.same_run,
            self.crossing - v.detected,
            v.false_hits,
            self.deformable_swept_pairs,
            self.deformable_ms
        )?;
        for r in &self.adb {
            writeln!(
                f,
                "  {}: detected {} of {} ({} in the reference's frame), {} tunnelled, {} false, {} later than the reference; {} pairs swept; collision stages {:.1} ms in all",
                r.name,
                r.verdicts.detected,
                self.crossing,
                r.verdicts.same_run,
                self.crossing - r.verdicts.detected,
                r.verdicts.false_hits,
                r.late,
                r.swept_pairs,
                r.ms
            )?;
        }
        match &self.picture {
            Ok(p) => writeln!(f, "  side view: {}", p.display()),
            Err(e) => writeln!(f, "  no picture: {e}"),
        }
    }
}

/// A side view (x, y) of the wall and every shot that touches it (reference): where the
/// discrete run stopped it (red: passed through) and where the continuous run did (green).
fn picture(
    path: &Path,
    discrete: &Flight,
    continuous: &Flight,
    reference: &[Option<(u64, f32)>],
) -> Result<PathBuf, String> {
    let (w, h) = (800.0f32, 400.0f32);
    let stops = discrete
        .shots
        .iter()
        .chain(&continuous.shots)
        .map(|s| s.stop);
    let far = stops.fold(Vec3::new(1.0, 2.0 * WALL_SIZE.y, 0.0), Vec3::max);
    let (x0, x1, y0, y1) = (-22.0f32, far.x + 2.0, -1.0f32, far.y + 2.0);
    let sx = |x: f32| (x - x0) / (x1 - x0) * w;
    let sy = |y: f32| h - (y - y0) / (y1 - y0) * h;
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">\n\
         <rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n\
         <rect x=\"{:.1}\" y=\"{:.1}\" width=\"2\" height=\"{:.1}\" fill=\"#444\"/>\n",
        sx(0.0) - 1.0,
        sy(2.0 * WALL_SIZE.y),
        sy(0.0) - sy(2.0 * WALL_SIZE.y)
    );
    for ((d, c), r) in discrete.shots.iter().zip(&continuous.shots).zip(reference) {
        if r.is_none() {
            continue;
        }
        for (shot, colour) in [(d, "#d62728"), (c, "#2ca02c")] {
            svg += &format!(
                "<line x1=\"{:.1}\" y1=\"{:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"{colour}\" stroke-opacity=\"0.35\"/>\n\
                 <circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"2\" fill=\"{colour}\"/>\n",
                sx(shot.start.x),
                sy(shot.start.y),
                sx(shot.stop.x),
                sy(shot.stop.y),
                sx(shot.stop.x),
                sy(shot.stop.y)
            );
        }
    }
    svg += "<text x=\"10\" y=\"20\" font-family=\"sans-serif\" font-size=\"13\">shots that touch the wall: where the discrete test stopped them (red) and continuous collision did (green)</text>\n</svg>\n";
    super::write_svg(path, &svg)
}
