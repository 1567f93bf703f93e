//! Tracking stage: pairs with [`Fidelity::Tracking`] and self-collision of deformable meshes.
//!
//! Both produce contacts with points, normals and depths from intersecting triangle pairs. The
//! working path here is the exact BVH query (`intersecting_pairs` for tracked pairs,
//! `self_intersections` for [`SelfCollision`] meshes), run in parallel per pair or per mesh;
//! the stochastic closest-feature tracker plugs in here, and keeps its per-partner feature
//! pairs in each entity's [`FeaturePairs`].
//!
//! [`Fidelity::Tracking`]: super::Fidelity::Tracking
//! [`SelfCollision`]: super::SelfCollision
use std::time::Instant;

use bevy_ecs::prelude::*;
use smallvec::SmallVec;

use super::broad_phase::CandidatePair;
use super::components::{Deformable, Fidelity, SelfCollision};
use super::contact::triangle_pair_contact;
use super::diagnostics::{CollisionDiagnostics, Stage};
use super::narrow_phase::{Method, PairOutcome, PairOutcomes, spread, with_workspaces};
use super::plugin::CollisionConfig;
use super::pool::CollisionTaskPool;
use super::prepare::ColliderFrame;
use crate::bvh::{TrianglePair, intersecting_pairs, self_intersections};

/// The feature pairs an entity is tracking against each partner (itself for self-collision),
/// as of the last run: kept across runs, dropped with the entity. Inserted by the Tracking
/// stage on the first (smaller) entity of each tracked pair.
#[derive(Component, Debug, Clone, Default, PartialEq)]
pub struct FeaturePairs {
    /// Per partner entity, the triangle pairs (this entity's, the partner's) in contact.
    pub partners: SmallVec<[(Entity, SmallVec<[TrianglePair; 4]>); 2]>,
}

impl FeaturePairs {
    /// The pairs tracked against `partner`.
    pub fn with(&self, partner: Entity) -> &[TrianglePair] {
        self.partners
            .iter()
            .find(|(e, _)| *e == partner)
            .map_or(&[], |(_, p)| p.as_slice())
    }
}

/// Drops the feature pairs of partners that are no longer tracked (apart, despawned, or
/// changed fidelity), so each entity's lists hold only live pairs.
pub fn prune_feature_pairs(
    frame: Res<ColliderFrame>,
    outcomes: Res<PairOutcomes>,
    mut q: Query<(Entity, &mut FeaturePairs)>,
) {
    let mut live: Vec<(Entity, Entity)> = outcomes
        .tracked
        .iter()
        .map(|p| {
            (
                frame.entries[p.a as usize].entity,
                frame.entries[p.b as usize].entity,
            )
        })
        .collect();
    live.sort_unstable();
    for (owner, mut f) in &mut q {
        if f.partners
            .iter()
            .any(|(p, _)| live.binary_search(&(owner, *p)).is_err())
        {
            f.partners
                .retain(|(p, _)| live.binary_search(&(owner, *p)).is_ok());
        }
    }
}

/// Run condition: some deformable mesh has the [`SelfCollision`] marker.
pub fn needs_self_pass(q: Query<(), (With<SelfCollision>, With<Deformable>)>) -> bool {
    !q.is_empty()
}

/// Run condition: the narrow phase handed over some tracked pair.
pub fn needs_tracking(outcomes: Res<PairOutcomes>) -> bool {
    !outcomes.tracked.is_empty()
}

/// Self-collision of every [`SelfCollision`] deformable mesh, in parallel per mesh.
pub fn self_collision(
    frame: Res<ColliderFrame>,
    config: Res<CollisionConfig>,
    pool: Res<CollisionTaskPool>,
    mut outcomes: ResMut<PairOutcomes>,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    let start = Instant::now();
    let meshes: Vec<u32> = (0..frame.entries.len() as u32)
        .filter(|&i| frame.entries[i as usize].self_collision)
        .collect();
    let max = config.max_self_contacts;
    let results = pool.map_chunks(&meshes, 1, |chunk| {
        let e = &frame.entries[chunk[0] as usize];
        let mesh = e.geometry.mesh();
        with_workspaces(|ws, _, pairs| {
            pairs.clear();
            self_intersections(mesh, ws, pairs);
            let contacts: SmallVec<_> = spread(pairs, max)
                .map(|t| triangle_pair_contact(mesh, &e.pose, mesh, &e.pose, t))
                .collect();
            let ends = (e.entity, e.entity);
            PairOutcome::exact(
                ends,
                Method::SelfCollision,
                ws.node_pairs_visited(),
                1.0,
                contacts,
            )
        })
    });
    diag.counters.node_pairs += results.iter().map(|o| o.node_pairs).sum::<u64>();
    outcomes.outcomes.extend(results);
    diag.record(Stage::SelfCollision, start.elapsed(), meshes.len() as u64);
}

/// Tracked pairs: contacts from the intersecting triangle pairs, at most `pairs_per_frame`
/// per pair, in parallel per pair; the pairs are kept in the first entity's [`FeaturePairs`].
pub fn track_pairs(
    frame: Res<ColliderFrame>,
    pool: Res<CollisionTaskPool>,
    mut outcomes: ResMut<PairOutcomes>,
    mut features: Query<&mut FeaturePairs>,
    mut commands: Commands,
    mut diag: ResMut<CollisionDiagnostics>,
) {
    let start = Instant::now();
    let tracked: Vec<CandidatePair> = outcomes.tracked.clone();
    let results = pool.map_chunks(&tracked, pool.chunk_size(tracked.len(), 1), |chunk| {
        chunk
            .iter()
            .map(|pair| {
                let (ea, eb) = (
                    &frame.entries[pair.a as usize],
                    &frame.entries[pair.b as usize],
                );
                let budget = match ea.fidelity.combine(eb.fidelity) {
                    Fidelity::Tracking { pairs_per_frame } => pairs_per_frame.max(1) as usize,
                    _ => 1,
                };
                let (ma, mb) = (ea.geometry.mesh(), eb.geometry.mesh());
                with_workspaces(|ws, _, pairs| {
                    pairs.clear();
                    intersecting_pairs(ma, &ea.pose, mb, &eb.pose, ws, pairs);
                    let kept: SmallVec<[TrianglePair; 4]> = spread(pairs, budget).collect();
                    let contacts = kept
                        .iter()
                        .map(|&t| triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t))
                        .collect();
                    let ends = (ea.entity, eb.entity);
                    let nodes = ws.node_pairs_visited();
                    let outcome = PairOutcome::exact(ends, Method::Tracking, nodes, 1.0, contacts);
                    (outcome, kept)
                })
            })
            .collect::<Vec<_>>()
    });
    for (outcome, kept) in results.into_iter().flatten() {
        diag.counters.node_pairs += outcome.node_pairs;
        match features.get_mut(outcome.a) {
            Ok(mut f) => {
                let f = &mut *f;
                f.partners.retain(|(e, _)| *e != outcome.b);
                if !kept.is_empty() {
                    f.partners.push((outcome.b, kept));
                }
            }
            Err(_) if !kept.is_empty() => {
                let mut f = FeaturePairs::default();
                f.partners.push((outcome.b, kept));
                commands.entity(outcome.a).try_insert(f);
            }
            Err(_) => {}
        }
        outcomes.outcomes.push(outcome);
    }
    diag.record(Stage::Tracking, start.elapsed(), tracked.len() as u64);
}
