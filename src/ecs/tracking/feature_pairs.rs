//! Each entity's [`FeaturePairs`]: the triangle pairs tracked against each partner, kept
//! in step with the pair table.

use bevy_ecs::entity::EntityHashMap;
use bevy_ecs::prelude::*;
use smallvec::SmallVec;

use super::super::pairs::PairTable;
use crate::bvh::TrianglePair;

/// The feature pairs an entity is tracking against each partner (itself for self-collision),
/// as of the last run: kept across runs, dropped with the entity. Inserted by the Tracking
/// stage on both entities of each tracked pair, every partner listed, each pair as (this
/// entity's triangle, the partner's).
#[derive(Component, bevy_reflect::Reflect, Debug, Clone, Default, PartialEq)]
#[reflect(opaque, Component, Clone, Debug, PartialEq)]
pub struct FeaturePairs {
    /// Per partner entity, the triangle pairs (this entity's, the partner's) in contact.
    pub partners: SmallVec<[(Entity, Vec<TrianglePair>); 2]>,
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

/// Feature pairs of this run for entities that have no [`FeaturePairs`] yet, inserted once
/// each at the end (every partner kept, none overwritten by another's insert).
#[derive(Default)]
pub(super) struct NewFeaturePairs(EntityHashMap<FeaturePairs>);

/// Records `pairs` (`a`'s triangle, `b`'s) as `a`'s feature pairs with `b` and, swapped, as
/// `b`'s with `a`.
pub(super) fn record_pairs(
    features: &mut Query<&mut FeaturePairs>,
    new: &mut NewFeaturePairs,
    (a, b): (Entity, Entity),
    pairs: &[TrianglePair],
) {
    let swapped: Vec<TrianglePair> = pairs
        .iter()
        .map(|t| TrianglePair { a: t.b, b: t.a })
        .collect();
    let sides: [(Entity, Entity, &[TrianglePair]); 2] = [(a, b, pairs), (b, a, &swapped)];
    for &(owner, partner, list) in &sides[..if a == b { 1 } else { 2 }] {
        let set = |f: &mut FeaturePairs| {
            f.partners.retain(|(e, _)| *e != partner);
            if !list.is_empty() {
                f.partners.push((partner, list.to_vec()));
            }
        };
        match features.get_mut(owner) {
            Ok(mut f) => set(&mut f),
            Err(_) if !list.is_empty() => set(new.0.entry(owner).or_default()),
            Err(_) => {}
        }
    }
}

impl NewFeaturePairs {
    pub(super) fn insert(self, commands: &mut Commands) {
        let mut new: Vec<_> = self.0.into_iter().collect();
        new.sort_unstable_by_key(|(e, _)| *e);
        for (e, f) in new {
            commands.entity(e).try_insert(f);
        }
    }
}

/// Drops the feature pairs of partners that are no longer tracked (apart, despawned, or
/// changed fidelity), so each entity's lists hold only live pairs.
pub fn prune_feature_pairs(pairs: Res<PairTable>, mut q: Query<(Entity, &mut FeaturePairs)>) {
    let mut live: Vec<(Entity, Entity)> = pairs
        .tracked
        .iter()
        .flat_map(|&p| {
            let s = pairs.slot(p);
            [(s.a, s.b), (s.b, s.a)]
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
