//! Per-stage timings and work counters of the collision pipeline: read-only output (the
//! pipeline decides nothing from it; the budget's own measurements are the
//! [`BudgetController`](super::BudgetController)'s).
use std::time::Duration;

use bevy_ecs::prelude::*;
use bevy_reflect::prelude::*;

/// A stage of the pipeline whose time is measured (the Prepare set holds two: `prepare` and
/// `refit`; the Tracking set two: `self_collision` and `tracking`).
#[derive(Reflect, Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[reflect(Clone, Debug, PartialEq, Hash)]
pub enum Stage {
    /// Pose validation and world boxes.
    Prepare,
    /// Refit of deformed meshes (deformables only).
    Refit,
    /// Sweep and prune.
    BroadPhase,
    /// Pair tests.
    NarrowPhase,
    /// Self-collision of deformable meshes (deformables only).
    SelfCollision,
    /// Tracked pairs.
    Tracking,
    /// Events and the contact queue.
    Report,
    /// Responses (measured by the response systems that call [`CollisionDiagnostics::record`]).
    Response,
}

impl Stage {
    /// Every stage, in pipeline order.
    pub const ALL: [Stage; 8] = [
        Stage::Prepare,
        Stage::Refit,
        Stage::BroadPhase,
        Stage::NarrowPhase,
        Stage::SelfCollision,
        Stage::Tracking,
        Stage::Report,
        Stage::Response,
    ];

    /// The stage's name in profiles and diagnostics (`snake_case`).
    pub const fn name(self) -> &'static str {
        match self {
            Stage::Prepare => "prepare",
            Stage::Refit => "refit",
            Stage::BroadPhase => "broad_phase",
            Stage::NarrowPhase => "narrow_phase",
            Stage::SelfCollision => "self_collision",
            Stage::Tracking => "tracking",
            Stage::Report => "report",
            Stage::Response => "response",
        }
    }
}

/// One stage's record.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Clone, Debug, Default, PartialEq)]
pub struct StageRecord {
    /// Time in the current (or last) run; `None` if the stage did not run.
    pub last: Option<Duration>,
    /// Items processed in the last run (entities, pairs, meshes, events…).
    pub items: u64,
    /// Runs in which the stage ran.
    pub runs: u64,
    /// Total time over all runs.
    pub total: Duration,
}

/// Work done, summed over all runs.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq, Eq)]
#[reflect(Clone, Debug, Default, PartialEq)]
pub struct CollisionCounters {
    /// Node pairs visited by all queries.
    pub node_pairs: u64,
    /// Pairs tested with ADB.
    pub adb_pairs: u64,
    /// ADB pairs that ran out of their slice.
    pub budget_exhausted_pairs: u64,
    /// Active pairs not tested under a time budget (not among the most urgent that fit, or
    /// past the deadline), which kept their last answer (an exact pair got one from memory,
    /// [`Method::Coherence`](super::Method::Coherence), unless it was confirmed:
    /// `confirmed_pairs`).
    pub coherence_pairs: u64,
    /// Pairs answered by a test (ADB or exact) in the narrow phase.
    pub tested_pairs: u64,
    /// Wall-clock time of the narrow phase's parallel tests, summed over runs: with
    /// `tested_pairs` and `node_pairs`, the narrow phase's throughput.
    pub test_time: Duration,
    /// Active pairs not tested because neither entity moved since their settled answer, which
    /// stands as it is (pairs not active at all are not counted).
    pub cached_pairs: u64,
    /// Pairs tested exactly.
    pub exact_pairs: u64,
    /// Exact pairs past their deadline answered exactly without a full test: their remembered
    /// crossing triangle pair still crosses, or their oriented root boxes are apart
    /// ([`Method::Coherence`](super::Method::Coherence) describes the rest).
    pub confirmed_pairs: u64,
    /// Pairs tested over a swept collider's motion
    /// ([`ContinuousCollision`](super::ContinuousCollision)).
    pub swept_pairs: u64,
    /// Swept pairs the discrete test found apart that met during the motion: contacts the
    /// discrete test alone would have missed (tunnelling caught).
    pub caught_by_sweep: u64,
    /// `CollisionStarted` messages written.
    pub started: u64,
    /// `CollisionEnded` messages written.
    pub ended: u64,
    /// `Contact` messages written.
    pub contacts: u64,
    /// Runs whose collision stages (Prepare to Report) took longer than a time budget.
    pub overrun_runs: u64,
    /// Tracker steps (of pairs and of self-colliding meshes) cut by the time budget: past
    /// their deadline no new pairs, no local search, no propagation.
    pub tracker_steps_cut: u64,
}

/// Timings and counters of the collision pipeline: per stage, the time of the last run (`None`
/// = not run), runs and totals; the whole collision time (Prepare to Report) of the last run.
/// Times are read on the [`BudgetController`](super::BudgetController)'s clock. Read-only
/// output: nothing in the pipeline reads it back.
#[derive(Resource, Reflect, Debug, Clone, Default)]
#[reflect(Resource, Clone, Debug, Default)]
pub struct CollisionDiagnostics {
    /// Runs of the pipeline so far (the number of the current or last run).
    pub frame: u64,
    /// Prepare to Report in the last run (wall clock, including scheduling gaps).
    pub collision_time: Duration,
    stages: [StageRecord; 8],
    /// Work counters.
    pub counters: CollisionCounters,
}

impl CollisionDiagnostics {
    /// The record of `stage`.
    pub fn stage(&self, stage: Stage) -> &StageRecord {
        &self.stages[stage as usize]
    }

    /// Adds `time` to `stage` in this run (several systems may add to one stage).
    pub fn record(&mut self, stage: Stage, time: Duration, items: u64) {
        let r = &mut self.stages[stage as usize];
        if r.last.is_none() {
            r.runs += 1;
            r.items = 0;
        }
        r.last = Some(r.last.unwrap_or_default() + time);
        r.items += items;
        r.total += time;
    }

    /// Starts the record of run `run`: the stages' last times are reset to "not run".
    pub(crate) fn begin_run(&mut self, run: u64) {
        if self.frame == run {
            return;
        }
        self.frame = run;
        for r in &mut self.stages {
            r.last = None;
        }
    }

    /// Ends the record of a run of the collision stages: their whole time, and whether it
    /// went over a time budget.
    pub(crate) fn end_run(&mut self, collision_time: Duration, overran: bool) {
        self.collision_time = collision_time;
        self.counters.overrun_runs += u64::from(overran);
    }
}

/// Publishing the stage timings to bevy_diagnostic's `DiagnosticsStore` (feature `diagnostic`):
/// paths `stochastic_collision/<stage>` in µs (a stage that did not run adds no measurement) and
/// `stochastic_collision/collision` (Prepare to Report). Add bevy_diagnostic's
/// `DiagnosticsPlugin` to the app to collect them.
///
/// Next: [`CollisionDiagnostics`], the same timings and the work counters as a resource.
#[cfg(feature = "diagnostic")]
pub mod store {
    use bevy_app::App;
    use bevy_diagnostic::{
        Diagnostic, DiagnosticPath, Diagnostics, DiagnosticsStore, RegisterDiagnostic,
    };
    use bevy_ecs::intern::Interned;
    use bevy_ecs::prelude::*;
    use bevy_ecs::schedule::ScheduleLabel;

    use super::{CollisionDiagnostics, Stage};
    use crate::ecs::CollisionSystems;

    /// The path of each stage, in [`Stage::ALL`] order.
    pub const STAGE_PATHS: [DiagnosticPath; 8] = [
        DiagnosticPath::const_new("stochastic_collision/prepare"),
        DiagnosticPath::const_new("stochastic_collision/refit"),
        DiagnosticPath::const_new("stochastic_collision/broad_phase"),
        DiagnosticPath::const_new("stochastic_collision/narrow_phase"),
        DiagnosticPath::const_new("stochastic_collision/self_collision"),
        DiagnosticPath::const_new("stochastic_collision/tracking"),
        DiagnosticPath::const_new("stochastic_collision/report"),
        DiagnosticPath::const_new("stochastic_collision/response"),
    ];

    /// The collision stages in all (Prepare to Report).
    pub const COLLISION_PATH: DiagnosticPath =
        DiagnosticPath::const_new("stochastic_collision/collision");

    pub(crate) fn register(app: &mut App, schedule: Interned<dyn ScheduleLabel>) {
        for path in STAGE_PATHS.iter().chain([&COLLISION_PATH]) {
            app.register_diagnostic(Diagnostic::new(path.clone()).with_suffix("us"));
        }
        app.add_systems(
            schedule,
            publish
                .after(CollisionSystems::Response)
                .run_if(resource_exists::<DiagnosticsStore>),
        );
    }

    fn publish(d: Res<CollisionDiagnostics>, mut out: Diagnostics) {
        for (stage, path) in Stage::ALL.iter().zip(&STAGE_PATHS) {
            if let Some(t) = d.stage(*stage).last {
                out.add_measurement(path, || t.as_secs_f64() * 1e6);
            }
        }
        out.add_measurement(&COLLISION_PATH, || d.collision_time.as_secs_f64() * 1e6);
    }
}
