//! Answers from memory. A pair worked on but not tested in a run keeps its last answer, one
//! run older ([`PairTable::keep`](super::super::pairs::PairTable)); only an exact pair that a
//! deadline left untested gets an answer computed from its memory, as level geometry must
//! hold whatever the load: exact where its remembered triangle pair still crosses or its root
//! boxes are apart, else [`Method::Coherence`].
use glam::Vec3;
use smallvec::{SmallVec, smallvec};

use super::super::contact::{ContactPoint, bounds_contact, triangle_pair_contact};
use super::super::pairs::{PairSlot, Record};
use super::super::prepare::ColliderEntry;
use super::outcome::{Method, PairOutcome};
use super::plan::Job;
use crate::bvh::{root_boxes_overlap, triangle_pair_intersects};

/// What a pair's last test found (what planning reads of it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PairMemory {
    pub probability: f64,
    pub collides: bool,
    /// The answer holds for as long as neither collider changes: a test of two rigid
    /// colliders that settled (not cut by its budget).
    pub settled: bool,
    /// Runs answered from memory since the test.
    pub stale: u32,
    /// The run whose poses the answer was computed at.
    pub tested_run: u64,
    /// How it was asked for: the pair's method and `p_min` then (another fidelity asks anew).
    pub method: Method,
    pub p_min: f64,
    /// The world boxes were apart (no test ran): when they meet, the pair is as new.
    pub boxes_apart: bool,
}

impl Record {
    /// What a test in `run` leaves.
    pub fn of_test(
        job: &Job,
        o: &PairOutcome,
        (ea, eb): (&ColliderEntry, &ColliderEntry),
        run: u64,
    ) -> Self {
        Self {
            memory: PairMemory {
                probability: o.probability,
                collides: o.collides,
                settled: !o.budget_exhausted && ea.is_rigid() && eb.is_rigid(),
                stale: 0,
                tested_run: run,
                method: job.method,
                p_min: job.p_min,
                boxes_apart: job.apart,
            },
            contact: o.contacts.first().copied(),
            offset: eb.pose.translation - ea.pose.translation,
        }
    }
}

#[cfg(test)]
impl PairMemory {
    /// What a settled exact test in `run` leaves.
    pub(crate) fn exact_for_tests(collides: bool, run: u64) -> Self {
        Self {
            probability: if collides { 1.0 } else { 0.0 },
            collides,
            settled: true,
            stale: 0,
            tested_run: run,
            method: Method::Exact,
            p_min: 1.0,
            boxes_apart: false,
        }
    }
}

/// The confidence of an answer `memory` of a pair whose colliders were `offset` apart at the
/// test, now: the tested one, drawn towards ½ as the colliders moved relative to each other
/// since (by `e^(−drift / scale)`, the scale half the smaller collider's box size: a pair that
/// moved by that much is answered at about `½ + (p − ½)/e`).
pub(crate) fn decayed_probability(
    memory: &PairMemory,
    offset: Vec3,
    (ea, eb): (&ColliderEntry, &ColliderEntry),
) -> f64 {
    let drift = (eb.pose.translation - ea.pose.translation - offset).length();
    let size = |e: &ColliderEntry| e.aabb.extents().max_element();
    let scale = (0.5 * size(ea).min(size(eb))).max(1e-6);
    0.5 + (memory.probability - 0.5) * f64::from((-drift / scale).exp())
}

/// The answer of an exact pair that a deadline left untested in `run`, from its memory.
///
/// Exact where a cheap test decides it at the current poses ([`Method::Exact`], a fresh
/// memory): a pair that collided and whose remembered triangle pair still crosses collides,
/// its contact measured on that pair; one whose oriented root boxes are apart does not.
/// Otherwise [`Method::Coherence`]: a pair that collided keeps colliding with a decayed
/// probability, its contact re-measured on its triangle pair (a box contact stays, without
/// its depth); one that did not, or was never tested, collides with probability ½ and a box
/// contact of half the depth (level geometry must not be passed through). A memory older than
/// either collider's geometry counts as none; a Coherence answer leaves the memory one run
/// staler.
pub(crate) fn exact_from_memory(
    job: &Job,
    memory: Option<&PairMemory>,
    slot: &PairSlot,
    (ea, eb): (&ColliderEntry, &ColliderEntry),
    run: u64,
) -> (PairOutcome, Option<Record>) {
    let ends = (ea.entity, eb.entity);
    let mut out = PairOutcome {
        method: Method::Coherence,
        probability: 0.5,
        computed_run: memory.map_or(run, |m| m.tested_run),
        ..PairOutcome::exact(
            ends,
            Method::Coherence,
            0,
            job.priority,
            SmallVec::new(),
            run,
        )
    };
    let (ma, mb) = (ea.geometry.mesh(), eb.geometry.mesh());
    // What was found on other geometry (a swapped mesh) says nothing about this one.
    let geometry_since = ea.geometry_since.max(eb.geometry_since);
    let memory = memory.filter(|m| m.tested_run >= geometry_since);
    let (na, nb) = (ma.mesh().triangle_count(), mb.mesh().triangle_count());
    let remembered = slot
        .contact
        .and_then(|c| c.triangles)
        .filter(|t| (t.a as usize) < na && (t.b as usize) < nb);
    let tested = |o: PairOutcome| {
        let r = Record::of_test(job, &o, (ea, eb), run);
        (o, Some(r))
    };
    match memory {
        Some(m)
            if m.collides
                && remembered
                    .is_some_and(|t| triangle_pair_intersects(ma, &ea.pose, mb, &eb.pose, t)) =>
        {
            let t = remembered.expect("checked above");
            let contact = triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t);
            return tested(PairOutcome::exact(
                ends,
                Method::Exact,
                1,
                job.priority,
                smallvec![contact],
                run,
            ));
        }
        _ if !root_boxes_overlap(ma, &ea.pose, mb, &eb.pose) => {
            return tested(PairOutcome::exact(
                ends,
                Method::Exact,
                1,
                job.priority,
                SmallVec::new(),
                run,
            ));
        }
        Some(m) if m.collides => {
            out.collides = true;
            out.probability = decayed_probability(m, slot.offset, (ea, eb));
            out.contacts.extend(slot.contact.map(|c| match remembered {
                Some(t) => triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, t),
                None => ContactPoint {
                    depth: 0.0,
                    triangles: None,
                    ..c
                },
            }));
        }
        _ => {
            out.collides = true;
            let mut c = bounds_contact(ea, eb);
            c.depth *= 0.5;
            out.contacts = smallvec![c];
        }
    }
    let record = memory.map(|m| Record {
        memory: PairMemory {
            stale: m.stale + 1,
            ..*m
        },
        contact: slot.contact,
        offset: slot.offset,
    });
    (out, record)
}

#[cfg(test)]
mod tests {
    use bevy_ecs::entity::Entity;

    use super::*;
    use crate::bvh::TrianglePair;

    fn entry(index: u32, subdivisions: u32, x: f32, geometry_since: u64) -> ColliderEntry {
        ColliderEntry::sphere_for_tests(index, subdivisions, x, geometry_since)
    }

    /// A memory of a test in run 3 that found triangles 4000 and 5000 in contact.
    fn remembered() -> (PairMemory, PairSlot) {
        let memory = PairMemory::exact_for_tests(true, 3);
        let (a, b) = (
            Entity::from_raw_u32(1).unwrap(),
            Entity::from_raw_u32(2).unwrap(),
        );
        let slot = PairSlot {
            a,
            b,
            outcome: PairOutcome::untested((a, b), 3),
            contact: Some(ContactPoint {
                point: Vec3::new(0.95, 0.0, 0.0),
                normal: Vec3::X,
                depth: 0.1,
                triangles: Some(TrianglePair { a: 4000, b: 5000 }),
                time_of_impact: None,
            }),
            offset: Vec3::new(1.9, 0.0, 0.0),
            since: 3,
        };
        (memory, slot)
    }

    #[test]
    fn a_memory_of_swapped_geometry_is_not_read() {
        // Both meshes swapped in run 5 for icospheres of 20 triangles: the memory is older
        // than the geometry, so the answer comes from the root boxes (they overlap).
        let (memory, slot) = remembered();
        let (ea, eb) = (entry(1, 0, 0.0, 5), entry(2, 0, 1.5, 5));
        let job = Job::new(0, 0, 1);
        let (o, _) = exact_from_memory(&job, Some(&memory), &slot, (&ea, &eb), 6);
        assert!(o.collides);
        assert_eq!(o.probability, 0.5, "as if never tested");
        assert!(o.contacts.iter().all(|c| c.triangles.is_none()));
    }

    #[test]
    fn a_remembered_triangle_the_mesh_no_longer_has_is_not_read() {
        // The geometry's identity did not change, but it has fewer triangles than the
        // memory names (a mesh rewritten in place): the contact stays, without triangles.
        let (memory, slot) = remembered();
        // (Icosahedra 1.6 apart: their root boxes, 0.85 from the centre, overlap.)
        let (ea, eb) = (entry(1, 0, 0.0, 0), entry(2, 0, 1.6, 0));
        let job = Job::new(0, 0, 1);
        let (o, _) = exact_from_memory(&job, Some(&memory), &slot, (&ea, &eb), 6);
        assert!(o.collides);
        assert_eq!(o.contacts.len(), 1);
        assert_eq!(o.contacts[0].triangles, None);
        assert_eq!(o.contacts[0].point, Vec3::new(0.95, 0.0, 0.0));
        // Triangles it has are read again at the current poses.
        let (ea, eb) = (entry(1, 4, 0.0, 0), entry(2, 4, 1.9, 0));
        let (o, _) = exact_from_memory(&job, Some(&memory), &slot, (&ea, &eb), 6);
        assert_eq!(
            o.contacts[0].triangles,
            Some(TrianglePair { a: 4000, b: 5000 })
        );
    }

    /// A memory of an exact test in run 3 that found the spheres at `x = 0` and `x = 1.9`
    /// colliding at their first crossing triangle pair.
    fn crossing_memory(ea: &ColliderEntry, eb: &ColliderEntry) -> (PairMemory, PairSlot) {
        let (ma, mb) = (ea.geometry.mesh(), eb.geometry.mesh());
        let mut found = Vec::new();
        let ws = &mut crate::bvh::QueryWorkspace::new();
        crate::bvh::intersecting_pairs(ma, &ea.pose, mb, &eb.pose, ws, &mut found);
        let (memory, mut slot) = remembered();
        slot.contact = Some(triangle_pair_contact(ma, &ea.pose, mb, &eb.pose, found[0]));
        (memory, slot)
    }

    #[test]
    fn a_remembered_triangle_pair_that_still_crosses_is_an_exact_answer() {
        let (ea, eb) = (entry(1, 2, 0.0, 0), entry(2, 2, 1.9, 0));
        let (memory, slot) = crossing_memory(&ea, &eb);
        let job = Job::new(0, 0, 1);
        let (o, r) = exact_from_memory(&job, Some(&memory), &slot, (&ea, &eb), 6);
        assert_eq!(
            (o.method, o.collides, o.probability),
            (Method::Exact, true, 1.0)
        );
        assert_eq!(o.computed_run, 6, "computed at this run's poses");
        assert_eq!(o.contacts[0].triangles, slot.contact.unwrap().triangles);
        let r = r.expect("a fresh memory");
        assert_eq!((r.memory.tested_run, r.memory.stale), (6, 0));
        assert!(r.memory.settled && r.memory.collides);
    }

    #[test]
    fn a_remembered_pair_that_no_longer_crosses_keeps_colliding_from_memory() {
        // Remembered at 1.9 apart, now 1.95: the spheres still overlap, but the triangle pair
        // crossed near the rim of the lens and no longer does (checked), so the answer is
        // not exact: it keeps colliding, with a decayed probability.
        let (ea, eb) = (entry(1, 2, 0.0, 0), entry(2, 2, 1.9, 0));
        let (memory, slot) = crossing_memory(&ea, &eb);
        let t = slot.contact.unwrap().triangles.unwrap();
        let moved = (1..40)
            .map(|k| entry(2, 2, 1.9 - 0.05 * k as f32, 0))
            .find(|e| {
                let (ma, mb) = (ea.geometry.mesh(), e.geometry.mesh());
                !triangle_pair_intersects(ma, &ea.pose, mb, &e.pose, t)
            })
            .expect("moving closer, the pair stops crossing");
        let job = Job::new(0, 0, 1);
        let (o, r) = exact_from_memory(&job, Some(&memory), &slot, (&ea, &moved), 6);
        assert_eq!((o.method, o.collides), (Method::Coherence, true));
        assert!(o.probability > 0.5 && o.probability < 1.0);
        assert_eq!(o.computed_run, 3);
        assert_eq!(r.expect("kept").memory.stale, 1);
    }

    #[test]
    fn root_boxes_apart_are_an_exact_answer_whatever_the_memory_says() {
        // Remembered colliding, now 3 apart (unit spheres): apart, exactly.
        let (ea, eb) = (entry(1, 2, 0.0, 0), entry(2, 2, 1.9, 0));
        let (memory, slot) = crossing_memory(&ea, &eb);
        let far = entry(2, 2, 3.0, 0);
        let job = Job::new(0, 0, 1);
        for m in [Some(&memory), None] {
            let (o, r) = exact_from_memory(&job, m, &slot, (&ea, &far), 6);
            assert_eq!(
                (o.method, o.collides, o.probability),
                (Method::Exact, false, 0.0)
            );
            assert!(o.contacts.is_empty());
            assert_eq!(r.expect("a fresh memory").memory.tested_run, 6);
        }
    }
}
