//! The main crate's pile scene (`examples/support/pile.rs`: rigid meshes falling into a box)
//! built twice from one [`PileScene`], once for this crate ([`our_app`]) and once for avian3d
//! ([`avian_app`]), and the per-step collision time of each over the falling phase, their
//! steps interleaved ([`OurRunner`], [`AvianRunner`], [`Comparison`]); the `pile_vs_avian`
//! example prints it.
//!
//! Both sides get the same triangles, box, seeded spawn and initial velocities, rotations
//! locked, 60 Hz steps, two threads, no window. What is timed differs in where the engines put
//! their stages (see [`Comparison`]'s output): ours is [`CollisionDiagnostics::collision_time`]
//! (Prepare to Report, without a budget); avian's is the wall time of its
//! `PhysicsStepSystems::BroadPhase` and `PhysicsStepSystems::NarrowPhase` sets, measured by
//! systems ordered around them. Neither includes the solver or the response.
use std::fmt;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use avian3d::collider_tree::ColliderTreeDiagnostics;
use avian3d::prelude::{
    Collider, ContactGraph, LinearVelocity, LockedAxes, Mass, PhysicsPlugins, PhysicsSchedule,
    PhysicsStepSystems, Position, RigidBody, Sleeping, SleepingDisabled,
};
use bevy::app::{TaskPoolOptions, TaskPoolPlugin};
use bevy::ecs::system::RunSystemOnce;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
#[path = "../../../examples/support/pile/layout.rs"]
mod layout;

use layout::{LEVEL_LAYERS, normalized, pile_layout};
use stochastic_collision::ecs::{ImpulseSettings, Rest, Stage};
use stochastic_collision::prelude::{
    BodyInertia, BodyMass, BodyVelocity, ColliderPose, CollisionConfig, CollisionDiagnostics,
    CollisionPairs, Fidelity, FrameBudget, ImpulseResponsePlugin, MeshCollider, Pose,
    StochasticCollisionPlugin, TriMesh, generate,
};

/// Default number of bodies (the main crate's pile's).
pub const DEFAULT_BODIES: usize = 1000;
/// Default number of steps: the falling phase (two seconds at 60 Hz: the four layers of bodies
/// land between about step 20 and step 60, and settle).
pub const DEFAULT_STEPS: usize = 120;
/// Threads each side works with: our plugin's own pool (`with_threads`), and bevy's task
/// pools (`TaskPoolOptions::with_num_threads`) that avian's parallel loops use.
pub const THREADS: usize = 2;
/// The step, s (the pile's impulse response steps at 60 Hz; avian's fixed clock too).
pub const STEP: f32 = 1.0 / 60.0;

/// One body of the pile: which mesh, where, how it is turned, how fast it starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodySpawn {
    /// Index into [`PileScene::kinds`].
    pub kind: usize,
    /// Its origin.
    pub position: Vec3,
    /// Its (locked) rotation.
    pub rotation: Quat,
    /// Its initial linear velocity.
    pub velocity: Vec3,
}

/// The pile scene of the main crate's `examples/support/pile.rs` (`setup`, `body_kinds`), as
/// plain data both apps are built from.
#[derive(Debug, Clone)]
pub struct PileScene {
    /// Seed of the spawn (and of our plugin).
    pub seed: u64,
    /// The bodies' meshes with their names: icosphere, torus, cube, and Suzanne when the
    /// shared mesh was found.
    pub kinds: Vec<(&'static str, TriMesh)>,
    /// Whether the bodies include Suzanne.
    pub suzanne: Suzanne,
    /// Half the inside of the box: `|x|, |z| < half`, above the floor at `y = 0`.
    pub half: f32,
    /// The floor and the four walls: each mesh and its translation.
    pub walls: Vec<(TriMesh, Vec3)>,
    /// The bodies, in spawn order.
    pub bodies: Vec<BodySpawn>,
    /// Whether bodies may fall asleep (true, as in the main crate's pile: ours with the impulse
    /// response's default sleep settings, avian's with its own); false keeps every body awake
    /// on both sides (ours: `ImpulseSettings::sleep_frames` 0; avian: `SleepingDisabled`).
    pub sleep: bool,
}

/// Whether the pile's bodies include the shared Suzanne mesh (the main crate's pile adds it when
/// the file is present).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Suzanne {
    /// Found at this path: every fourth body is a Suzanne.
    Found(PathBuf),
    /// Not found at this path: three kinds of body.
    Missing(PathBuf),
    /// Not looked for (`PileScene::new`'s `suzanne` false).
    LeftOut,
}

impl fmt::Display for Suzanne {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Suzanne::Found(p) => write!(f, "Suzanne found ({})", p.display()),
            Suzanne::Missing(p) => write!(f, "Suzanne NOT found ({})", p.display()),
            Suzanne::LeftOut => write!(f, "Suzanne left out (--no-suzanne)"),
        }
    }
}

/// Where the shared meshes are: `STOCHASTIC_COLLISION_MESHES`, else `shared/assets/meshes`
/// beside the main crate (as its examples look for them).
pub fn shared_mesh_dir() -> PathBuf {
    std::env::var_os("STOCHASTIC_COLLISION_MESHES").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/assets/meshes"),
        PathBuf::from,
    )
}

impl PileScene {
    /// The scene of `bodies` bodies spawned from `seed`: the main crate's pile layout
    /// (`examples/support/pile/layout.rs`, included by path: the same random draws in the
    /// same order). With `suzanne`, the shared Suzanne
    /// mesh is a fourth kind of body when found (as in the main crate); without, it is not
    /// looked for.
    pub fn new(bodies: usize, seed: u64, suzanne: bool) -> PileScene {
        let mut kinds = vec![
            ("icosphere", generate::icosphere(0.25, 1)),
            ("torus", generate::torus(0.2, 0.08, 16, 8)),
            ("cube", generate::cuboid(Vec3::splat(0.18), 1)),
        ];
        let suzanne = if suzanne {
            let path = shared_mesh_dir().join("suzanne.obj");
            match TriMesh::from_obj(&path) {
                Ok(m) => {
                    kinds.push(("Suzanne", normalized(&m, 0.5)));
                    Suzanne::Found(path)
                }
                Err(_) => Suzanne::Missing(path),
            }
        } else {
            Suzanne::LeftOut
        };
        // The main crate's layout: the same slabs and starts from the same draws.
        let layout = pile_layout(bodies, seed);
        let walls = layout
            .slabs
            .iter()
            .map(|(h, at)| (generate::cuboid(*h, 12), *at))
            .collect();
        let spawns = layout
            .bodies
            .iter()
            .enumerate()
            .map(|(i, b)| BodySpawn {
                kind: i % kinds.len(),
                position: b.position,
                rotation: b.rotation,
                velocity: b.velocity,
            })
            .collect();
        let half = layout.half;
        PileScene {
            seed,
            kinds,
            suzanne,
            half,
            walls,
            bodies: spawns,
            sleep: true,
        }
    }

    /// Whether a body's origin is outside the box (below the floor or beyond a wall, by more
    /// than `margin`).
    pub fn outside(&self, p: Vec3, margin: f32) -> bool {
        p.y < -margin || p.x.abs() > self.half + margin || p.z.abs() > self.half + margin
    }
}

/// Bevy's task pools with [`THREADS`] threads in all (one compute thread, which the thread
/// running a parallel loop joins: two work on it).
fn task_pools() -> TaskPoolPlugin {
    TaskPoolPlugin {
        task_pool_options: TaskPoolOptions::with_num_threads(THREADS),
    }
}

/// This crate's side: the plugin in `PostUpdate` (one collision run per `App::update`, as the
/// main crate's examples run it) without a budget on [`THREADS`] threads, the impulse response
/// at 60 Hz (never sleeping without [`PileScene::sleep`]), bodies of mass 1 whose rotation is locked ([`BodyInertia::locked`]), the box
/// tested exactly and the bodies among themselves with the default fidelity (ADB).
pub fn our_app(scene: &PileScene) -> App {
    let mut app = App::new();
    app.add_plugins((
        task_pools(),
        StochasticCollisionPlugin::in_schedule(PostUpdate)
            .with_config(CollisionConfig {
                budget: FrameBudget::Unlimited,
                seed: scene.seed,
                ..CollisionConfig::default()
            })
            .with_threads(THREADS),
    ));
    app.add_plugins(
        ImpulseResponsePlugin::default().with_settings(ImpulseSettings {
            dt: Some(STEP),
            sleep_frames: if scene.sleep {
                ImpulseSettings::default().sleep_frames
            } else {
                0
            },
            ..Default::default()
        }),
    );
    app.finish();
    app.cleanup();
    let world = app.world_mut();
    for (mesh, at) in &scene.walls {
        world.spawn((
            MeshCollider::new(mesh.clone()),
            ColliderPose::from_translation(*at),
            Fidelity::Exact,
            LEVEL_LAYERS,
        ));
    }
    let colliders: Vec<MeshCollider> = scene
        .kinds
        .iter()
        .map(|(_, m)| MeshCollider::new(m.clone()))
        .collect();
    for b in &scene.bodies {
        world.spawn((
            colliders[b.kind].clone(),
            ColliderPose(Pose::new(b.position, b.rotation)),
            BodyVelocity(b.velocity),
            BodyMass(1.0),
            BodyInertia::locked(),
        ));
    }
    app
}

/// A trimesh collider of avian from the same vertices and triangles.
fn trimesh(mesh: &TriMesh) -> Collider {
    Collider::try_trimesh(mesh.positions().to_vec(), mesh.triangles().to_vec())
        .expect("a trimesh collider from a valid mesh")
}

/// Timestamps of avian's physics step in the current step: its broad and narrow phase sets,
/// and the whole step.
#[derive(Resource, Default, Debug, Clone, Copy)]
pub struct AvianStepClock {
    /// Physics steps run so far.
    pub steps: u64,
    /// When the step began.
    step_start: Option<Instant>,
    /// When the current set began.
    set_start: Option<Instant>,
    /// The broad phase set's wall time in this step.
    pub broad: Duration,
    /// The narrow phase set's wall time in this step.
    pub narrow: Duration,
    /// The whole physics step's wall time (from before `PhysicsStepSystems::First` to after
    /// `PhysicsStepSystems::Last`: the solver and its substeps included).
    pub step: Duration,
    /// Collider tree update time (`ColliderTreeDiagnostics::update`) spent inside the broad
    /// phase set in this step (the rest is spent after the solver).
    pub tree_update_in_broad: Duration,
}

fn clock_step_start(mut clock: ResMut<AvianStepClock>) {
    clock.steps += 1;
    clock.step_start = Some(Instant::now());
}

fn clock_broad_start(mut clock: ResMut<AvianStepClock>) {
    clock.set_start = Some(Instant::now());
}

fn clock_broad_done(mut clock: ResMut<AvianStepClock>, tree: Res<ColliderTreeDiagnostics>) {
    let now = Instant::now();
    clock.broad = clock.set_start.map_or(Duration::ZERO, |s| now - s);
    clock.set_start = Some(now);
    clock.tree_update_in_broad = tree.update;
}

fn clock_narrow_done(mut clock: ResMut<AvianStepClock>) {
    clock.narrow = clock.set_start.map_or(Duration::ZERO, |s| s.elapsed());
    clock.set_start = None;
}

fn clock_step_done(mut clock: ResMut<AvianStepClock>) {
    clock.step = clock.step_start.map_or(Duration::ZERO, |s| s.elapsed());
    clock.step_start = None;
}

/// avian3d's side: `PhysicsPlugins::default()` stepping at 60 Hz, one fixed step per
/// `App::update`, bevy's task pools with [`THREADS`] threads; the box static, the bodies
/// dynamic with `LockedAxes::ROTATION_LOCKED` and mass 1 (`SleepingDisabled` without
/// [`PileScene::sleep`]), every shape a `Collider::trimesh` of the same triangles; systems
/// around the broad and narrow phase sets fill an [`AvianStepClock`].
pub fn avian_app(scene: &PileScene) -> App {
    let mut app = App::new();
    app.add_plugins((
        task_pools(),
        bevy::time::TimePlugin,
        bevy::transform::TransformPlugin,
        PhysicsPlugins::default(),
    ))
    .insert_resource(TimeUpdateStrategy::FixedTimesteps(1))
    .insert_resource(Time::<Fixed>::from_hz(60.0))
    .init_resource::<AvianStepClock>()
    .add_systems(
        PhysicsSchedule,
        (
            clock_step_start.before(PhysicsStepSystems::First),
            clock_broad_start
                .after(PhysicsStepSystems::First)
                .before(PhysicsStepSystems::BroadPhase),
            clock_broad_done
                .after(PhysicsStepSystems::BroadPhase)
                .before(PhysicsStepSystems::NarrowPhase),
            clock_narrow_done
                .after(PhysicsStepSystems::NarrowPhase)
                .before(PhysicsStepSystems::Solver),
            clock_step_done.after(PhysicsStepSystems::Last),
        ),
    );
    app.finish();
    app.cleanup();
    let world = app.world_mut();
    for (mesh, at) in &scene.walls {
        world.spawn((
            RigidBody::Static,
            trimesh(mesh),
            Transform::from_translation(*at),
        ));
    }
    let colliders: Vec<Collider> = scene.kinds.iter().map(|(_, m)| trimesh(m)).collect();
    for b in &scene.bodies {
        let mut body = world.spawn((
            RigidBody::Dynamic,
            colliders[b.kind].clone(),
            Transform::from_translation(b.position).with_rotation(b.rotation),
            LinearVelocity(b.velocity),
            LockedAxes::ROTATION_LOCKED,
            Mass(1.0),
        ));
        if !scene.sleep {
            body.insert(SleepingDisabled);
        }
    }
    app
}

/// p50, p99, mean and max of per-step times, ms.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Stats {
    /// Median.
    pub p50: f64,
    /// 99th percentile (the value at rank `round((n − 1) · 0.99)` of the sorted steps, as the
    /// main crate's `profile` example computes it: the second slowest of 120 steps).
    pub p99: f64,
    /// Mean.
    pub mean: f64,
    /// Slowest step.
    pub max: f64,
}

impl Stats {
    /// The statistics of `ms` (zeros when empty).
    pub fn of(ms: &[f64]) -> Stats {
        if ms.is_empty() {
            return Stats::default();
        }
        let mut v = ms.to_vec();
        v.sort_by(f64::total_cmp);
        let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
        Stats {
            p50: at(0.5),
            p99: at(0.99),
            mean: v.iter().sum::<f64>() / v.len() as f64,
            max: v[v.len() - 1],
        }
    }
}

/// What one side's run saw.
#[derive(Debug, Clone, Default)]
pub struct SideRun {
    /// The measured collision time of each step, ms (ours: Prepare to Report; avian: its broad
    /// and narrow phase sets).
    pub collision_ms: Vec<f64>,
    /// Other per-step times, ms, by name (ours: the stages; avian: each set, its own
    /// diagnostics, the sets with the tree update after the solver ([`WITH_TREE_UPDATE`]),
    /// the whole physics step).
    pub breakdown: Vec<(&'static str, Vec<f64>)>,
    /// Touching pairs after the last step.
    pub touching_pairs: usize,
    /// Bodies outside the box after the last step (more than 0.1 below the floor or beyond a
    /// wall).
    pub escaped: usize,
    /// Bodies asleep after the last step.
    pub asleep: usize,
    /// Wall-clock time of the side's run (building the app and every step), s.
    pub elapsed: f64,
}

impl SideRun {
    /// The per-step times of the breakdown row `name`, if any.
    pub fn row(&self, name: &str) -> Option<&[f64]> {
        self.breakdown
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| v.as_slice())
    }
}

/// Name of avian's breakdown row: its broad and narrow phase sets plus the collider tree
/// update after the solver (the AABBs and BVH of the moved bodies, the counterpart of our
/// Prepare's world boxes).
pub const WITH_TREE_UPDATE: &str = "sets + tree update after solver";

fn ms(d: Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// Our stages in the breakdown (the deformable-only ones, refit, self-collision and
/// tracking, take no time in a pile of rigid bodies).
const OUR_STAGES: [(Stage, &str); 4] = [
    (Stage::Prepare, "prepare"),
    (Stage::BroadPhase, "broad phase"),
    (Stage::NarrowPhase, "narrow phase"),
    (Stage::Report, "report"),
];

/// Our side, stepped one `App::update` at a time.
pub struct OurRunner {
    app: App,
    collision: Vec<f64>,
    stages: Vec<(&'static str, Vec<f64>)>,
    /// Building the app and stepping it so far.
    busy: Duration,
}

impl OurRunner {
    /// Builds our app for `scene` ([`our_app`]).
    pub fn new(scene: &PileScene) -> Self {
        let start = Instant::now();
        let app = our_app(scene);
        OurRunner {
            app,
            collision: Vec::new(),
            stages: OUR_STAGES
                .iter()
                .map(|(_, name)| (*name, Vec::new()))
                .collect(),
            busy: start.elapsed(),
        }
    }

    /// Runs one step and records its times.
    pub fn step(&mut self) {
        let start = Instant::now();
        self.app.update();
        self.busy += start.elapsed();
        let d = self.app.world().resource::<CollisionDiagnostics>();
        self.collision.push(ms(d.collision_time));
        for ((stage, _), (_, v)) in OUR_STAGES.iter().zip(&mut self.stages) {
            v.push(ms(d.stage(*stage).last.unwrap_or_default()));
        }
    }

    /// The times recorded and the state after the last step.
    pub fn finish(mut self, scene: &PileScene) -> SideRun {
        let world = self.app.world_mut();
        let touching_pairs = world
            .run_system_once(|pairs: CollisionPairs| pairs.iter().filter(|p| p.touching()).count())
            .expect("the collision pairs");
        let escaped = world
            .query_filtered::<&ColliderPose, With<BodyVelocity>>()
            .iter(world)
            .filter(|p| scene.outside(p.0.translation, 0.1))
            .count();
        let asleep = world
            .query::<&Rest>()
            .iter(world)
            .filter(|r| r.is_asleep())
            .count();
        SideRun {
            collision_ms: self.collision,
            breakdown: self.stages,
            touching_pairs,
            escaped,
            asleep,
            elapsed: self.busy.as_secs_f64(),
        }
    }
}

/// Names of avian's breakdown rows, in [`AvianRunner`]'s order.
const AVIAN_ROWS: [&str; 5] = [
    "broad phase set",
    "narrow phase set",
    "its CollisionDiagnostics",
    WITH_TREE_UPDATE,
    "whole physics step",
];

/// avian's side, stepped one physics step at a time.
pub struct AvianRunner {
    app: App,
    collision: Vec<f64>,
    rows: Vec<Vec<f64>>,
    /// Building the app and stepping it so far.
    busy: Duration,
}

impl AvianRunner {
    /// Builds avian's app for `scene` ([`avian_app`]).
    pub fn new(scene: &PileScene) -> Self {
        let start = Instant::now();
        let app = avian_app(scene);
        AvianRunner {
            app,
            collision: Vec::new(),
            rows: vec![Vec::new(); AVIAN_ROWS.len()],
            busy: start.elapsed(),
        }
    }

    /// Runs one physics step and records its times.
    pub fn step(&mut self) {
        let start = Instant::now();
        let done = self.collision.len() as u64;
        // One fixed step per update, except the first update, which starts the clocks.
        for _ in 0..3 {
            self.app.update();
            if self.app.world().resource::<AvianStepClock>().steps > done {
                break;
            }
        }
        self.busy += start.elapsed();
        let world = self.app.world();
        let clock = *world.resource::<AvianStepClock>();
        assert_eq!(clock.steps, done + 1, "one physics step per update");
        let diag = world.resource::<avian3d::collision::CollisionDiagnostics>();
        let tree = world.resource::<ColliderTreeDiagnostics>();
        let sets = clock.broad + clock.narrow;
        let tree_after = tree.update.saturating_sub(clock.tree_update_in_broad);
        self.collision.push(ms(sets));
        for (row, d) in self.rows.iter_mut().zip([
            clock.broad,
            clock.narrow,
            diag.broad_phase + diag.narrow_phase,
            sets + tree_after,
            clock.step,
        ]) {
            row.push(ms(d));
        }
    }

    /// The times recorded and the state after the last step.
    pub fn finish(mut self, scene: &PileScene) -> SideRun {
        let world = self.app.world_mut();
        let graph = world.resource::<ContactGraph>();
        let touching_pairs =
            graph.iter_active_touching().count() + graph.iter_sleeping_touching().count();
        let escaped = world
            .query::<(&Position, &RigidBody)>()
            .iter(world)
            .filter(|(p, b)| b.is_dynamic() && scene.outside(p.0, 0.1))
            .count();
        let asleep = world
            .query_filtered::<&RigidBody, With<Sleeping>>()
            .iter(world)
            .filter(|b| b.is_dynamic())
            .count();
        SideRun {
            collision_ms: self.collision,
            breakdown: AVIAN_ROWS.into_iter().zip(self.rows).collect(),
            touching_pairs,
            escaped,
            asleep,
            elapsed: self.busy.as_secs_f64(),
        }
    }
}

/// Both sides on one scene; its `Display` is the summary the example prints.
#[derive(Debug, Clone)]
pub struct Comparison {
    /// Bodies in the scene.
    pub bodies: usize,
    /// Steps measured.
    pub steps: usize,
    /// Seed of the spawn.
    pub seed: u64,
    /// Whether the bodies include Suzanne.
    pub suzanne: Suzanne,
    /// Whether bodies could fall asleep ([`PileScene::sleep`]).
    pub sleep: bool,
    /// The kinds of body, by name.
    pub kinds: Vec<&'static str>,
    /// Triangles of each kind of body and of the floor.
    pub triangles: (Vec<usize>, usize),
    /// This crate's run.
    pub ours: SideRun,
    /// avian's run.
    pub avian: SideRun,
}

impl Comparison {
    /// Runs both sides on `scene` for `steps` steps, interleaved (a step of ours, then a step
    /// of avian's: load from other processes on the machine falls on both alike); `progress`
    /// is told of each step done.
    pub fn run(scene: &PileScene, steps: usize, mut progress: impl FnMut(usize)) -> Self {
        let mut ours = OurRunner::new(scene);
        let mut avian = AvianRunner::new(scene);
        for step in 0..steps {
            ours.step();
            avian.step();
            progress(step + 1);
        }
        let (ours, avian) = (ours.finish(scene), avian.finish(scene));
        Comparison {
            bodies: scene.bodies.len(),
            steps,
            seed: scene.seed,
            suzanne: scene.suzanne.clone(),
            sleep: scene.sleep,
            kinds: scene.kinds.iter().map(|(n, _)| *n).collect(),
            triangles: (
                scene
                    .kinds
                    .iter()
                    .map(|(_, m)| m.triangles().len())
                    .collect(),
                scene.walls[0].0.triangles().len(),
            ),
            ours,
            avian,
        }
    }

    /// Ours over avian's (broad + narrow phase sets): the ratios of the p50s and of the p99s.
    pub fn ratios(&self) -> (f64, f64) {
        let (o, a) = (
            Stats::of(&self.ours.collision_ms),
            Stats::of(&self.avian.collision_ms),
        );
        (o.p50 / a.p50, o.p99 / a.p99)
    }
}

fn row(f: &mut fmt::Formatter<'_>, name: &str, v: &[f64], pairs: Option<usize>) -> fmt::Result {
    let s = Stats::of(v);
    write!(
        f,
        "  {name:<40}{:>8.2}{:>8.2}{:>8.2}{:>8.2}",
        s.p50, s.p99, s.mean, s.max
    )?;
    match pairs {
        Some(p) => writeln!(f, "{p:>10}"),
        None => writeln!(f),
    }
}

impl fmt::Display for Comparison {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kinds: Vec<String> = self
            .kinds
            .iter()
            .zip(&self.triangles.0)
            .map(|(n, t)| format!("{n} {t}"))
            .collect();
        writeln!(
            f,
            "== pile vs avian3d 0.8: {} bodies, seed {}, steps 1..{} (the falling phase), {THREADS} threads each, headless{}",
            self.bodies,
            self.seed,
            self.steps,
            if self.sleep {
                ""
            } else {
                ", sleeping off on both sides"
            }
        )?;
        writeln!(
            f,
            "  bodies (triangles): {}; {}; floor and walls {} triangles each",
            kinds.join(", "),
            self.suzanne,
            self.triangles.1
        )?;
        writeln!(
            f,
            "  {:<40}{:>8}{:>8}{:>8}{:>8}{:>10}",
            "per step, ms", "p50", "p99", "mean", "max", "touching"
        )?;
        row(
            f,
            "ours: Prepare..Report",
            &self.ours.collision_ms,
            Some(self.ours.touching_pairs),
        )?;
        for (name, v) in &self.ours.breakdown {
            row(f, &format!("  {name}"), v, None)?;
        }
        row(
            f,
            "avian: broad + narrow phase sets",
            &self.avian.collision_ms,
            Some(self.avian.touching_pairs),
        )?;
        for (name, v) in &self.avian.breakdown {
            row(f, &format!("  {name}"), v, None)?;
        }
        let (r50, r99) = self.ratios();
        write!(
            f,
            "  ours/avian: p50 {r50:.2}x, p99 {r99:.2}x (target p99 <= 0.25x: {})",
            if r99 <= 0.25 { "met" } else { "NOT met" },
        )?;
        if let Some(w) = self.avian.row(WITH_TREE_UPDATE) {
            let (o, w) = (Stats::of(&self.ours.collision_ms), Stats::of(w));
            write!(
                f,
                "; against avian's {WITH_TREE_UPDATE}: p50 {:.2}x, p99 {:.2}x",
                o.p50 / w.p50,
                o.p99 / w.p99
            )?;
        }
        writeln!(f)?;
        writeln!(
            f,
            "  after step {}: ours {} escaped the box, {} asleep; avian {} escaped, {} sleeping; run time (build + steps) ours {:.1} s, avian {:.1} s",
            self.steps,
            self.ours.escaped,
            self.ours.asleep,
            self.avian.escaped,
            self.avian.asleep,
            self.ours.elapsed,
            self.avian.elapsed
        )
    }
}

/// What each side's time covers (printed once above the comparisons).
pub const MEASURES: &str = "\
measured per step, wall clock, the two apps' steps interleaved (the two compared rows include
neither the solver nor the response):
  ours: Prepare..Report = CollisionDiagnostics::collision_time: pose sync and world boxes, broad
    phase, narrow phase (ADB between bodies, exact against the box), events and contact queue;
    FrameBudget::Unlimited; below it the stages' own times (without the gaps between them)
  avian: broad + narrow phase sets = wall time of PhysicsStepSystems::BroadPhase (AABBs of
    colliders moved outside the solver, BVH pair search, start of the tree optimisation, which
    runs on a task beside the narrow phase) and PhysicsStepSystems::NarrowPhase (parry
    trimesh-trimesh contact manifolds, contact status changes); below it each set, avian's own
    CollisionDiagnostics (broad_phase + narrow_phase: its pair search and contact update
    functions), the sets plus ColliderTreeDiagnostics::update spent after the solver (AABBs
    and BVH refit of the moved bodies: the counterpart of our world boxes), and the whole
    physics step (solver with its 6 substeps included)
  p99 = value at rank round((n - 1) * 0.99) of the sorted steps (the second slowest of 120)
  touching = touching pairs after the last step (ours: CollisionPairs; avian: ContactGraph)";
