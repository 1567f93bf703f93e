//! Markers and per-entity outputs: the entities it touches, sensors, observed entities.

use bevy_ecs::prelude::*;
use bevy_reflect::prelude::*;

/// The entities this entity currently collides with (sorted), kept up to date by the Report
/// stage. Inserted automatically with [`MeshCollider`](crate::ecs::MeshCollider) and [`Deformable`](crate::ecs::Deformable); a mesh's own
/// self-collision is not listed.
#[derive(Component, Reflect, Clone, Debug, Default, PartialEq, Eq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct TouchingEntities(pub(crate) Vec<Entity>);

impl TouchingEntities {
    /// The colliding entities, sorted.
    #[inline]
    pub fn entities(&self) -> &[Entity] {
        &self.0
    }

    /// Whether this entity collides with `other`.
    #[inline]
    pub fn contains(&self, other: Entity) -> bool {
        self.0.binary_search(&other).is_ok()
    }

    /// Number of colliding entities.
    #[inline]
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether the entity collides with nothing.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Applies `flips` (other entity, touching now), sorted by entity, the last of an
    /// entity's flips winning, in one merge with the sorted list (`scratch`: reused memory).
    /// A level touched by thousands of bodies takes a run's hundreds of flips at the cost of
    /// one pass over its list, not one shift of it per flip.
    pub(crate) fn apply(&mut self, flips: &[(Entity, bool)], scratch: &mut Vec<Entity>) {
        scratch.clear();
        scratch.reserve(self.0.len() + flips.len());
        let mut kept = self.0.iter().copied().peekable();
        let mut k = 0;
        while k < flips.len() {
            // The last flip of this entity decides.
            let other = flips[k].0;
            while k + 1 < flips.len() && flips[k + 1].0 == other {
                k += 1;
            }
            let touching = flips[k].1;
            k += 1;
            while let Some(e) = kept.next_if(|e| *e < other) {
                scratch.push(e);
            }
            kept.next_if_eq(&other);
            if touching {
                scratch.push(other);
            }
        }
        scratch.extend(kept);
        // Copied back rather than swapped: each list keeps its own memory, so a run
        // allocates nothing once the lists have grown.
        self.0.clear();
        self.0.extend_from_slice(scratch);
    }
}

/// Marks a collider as a sensor (a trigger volume): its pairs are detected and reported as
/// usual (events, [`TouchingEntities`], contacts through
/// [`CollisionPairs`](crate::ecs::CollisionPairs) and [`Contact`](crate::ecs::Contact) messages), but its
/// contacts never reach the [`ContactQueue`](crate::ecs::ContactQueue): no response pushes
/// anything out of it or away from it. Named so that it does not clash with avian's and
/// bevy_rapier's `Sensor`.
///
/// Contact is contact of surfaces: with [`Fidelity::Exact`](crate::ecs::Fidelity::Exact) a body wholly inside a closed
/// sensor mesh does not touch it (ADB's interpenetration certificate does count it).
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component, Clone, Debug, Default)]
pub struct CollisionSensor;

/// Opt in to per-entity observer events ([`CollisionStarted`](crate::ecs::CollisionStarted) and
/// [`CollisionEnded`](crate::ecs::CollisionEnded) triggered on this entity, observed with
/// `On<CollisionStarted>`). The marker is read when events are emitted, so adding it to an
/// entity that already exists works.
#[derive(Component, Reflect, Clone, Copy, Debug, Default)]
#[reflect(Component, Clone, Debug, Default)]
pub struct ObserveCollisions;

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    /// One merge of a run's flips leaves the list that flipping one at a time would: sorted,
    /// each entity once, the last flip of an entity deciding (an end and a start of one pair
    /// in a run leave it touching), on random lists and flips.
    #[test]
    fn a_run_of_flips_applied_at_once_equals_them_one_by_one() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = |n: u64| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state % n
        };
        let entity = |i: u64| Entity::from_raw_u32(i as u32 + 1).unwrap();
        let mut scratch = Vec::new();
        for _ in 0..500 {
            let mut reference = BTreeSet::new();
            for _ in 0..next(40) {
                reference.insert(entity(next(60)));
            }
            let mut touching = TouchingEntities(reference.iter().copied().collect());
            let mut flips: Vec<(Entity, bool)> = (0..next(30))
                .map(|_| (entity(next(60)), next(2) == 1))
                .collect();
            for &(e, on) in &flips {
                if on {
                    reference.insert(e);
                } else {
                    reference.remove(&e);
                }
            }
            // Sorted by entity, keeping each entity's flips in order, as the Report does.
            flips.sort_by_key(|f| f.0);
            touching.apply(&flips, &mut scratch);
            let expected: Vec<Entity> = reference.into_iter().collect();
            assert_eq!(touching.entities(), &expected[..]);
        }
    }
}
