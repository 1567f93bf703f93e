//! Continuous tests of pairs with a swept collider
//! ([`ContinuousCollision`](super::super::ContinuousCollision)): the exact continuous query over
//! both colliders' motions in the run (or for ADB pairs the time-critical one within the
//! pair's budget), for a pair the discrete test found apart (a collider may have passed
//! through the other) or that did not touch before (its started event gets the time of
//! impact).
use super::super::contact::ContactPoint;
use super::super::prepare::ColliderEntry;
use crate::adb::Budget;
use crate::ccd::{
    CcdOptions, CcdWorkspace, ContinuousAdbQuery, TimeOfImpact, adb_time_of_impact,
    deforming_time_of_impact, time_of_impact,
};

/// The first contact of two rigid colliders over their motions in `run`, if they meet: at the
/// time of impact, its point, the normal pushing `b` away from `a`, depth 0, the time of
/// impact. A pose the query refuses (it cannot happen: poses are validated in Prepare) gives
/// no contact.
pub(crate) fn swept_contact(
    a: &ColliderEntry,
    b: &ColliderEntry,
    run: u64,
    ws: &mut CcdWorkspace,
) -> Option<ContactPoint> {
    let hit = time_of_impact(
        a.geometry.mesh(),
        &a.motion_in(run),
        b.geometry.mesh(),
        &b.motion_in(run),
        &CcdOptions::default(),
        ws,
    )
    .ok()??;
    Some(impact_contact(&hit))
}

/// [`swept_contact`] where a collider is deformable: both meshes in world coordinates at the
/// start and end of their motions in `run` ([`ColliderEntry::world_states`]), each vertex on a
/// straight line between them.
pub(crate) fn swept_deforming_contact(
    a: &ColliderEntry,
    b: &ColliderEntry,
    run: u64,
    ws: &mut CcdWorkspace,
) -> Option<ContactPoint> {
    let (a0, a1) = a.world_states(run);
    let (b0, b1) = b.world_states(run);
    let hit =
        deforming_time_of_impact((&a0, &a1), (&b0, &b1), &CcdOptions::default(), ws).ok()??;
    Some(impact_contact(&hit))
}

/// The contact at an exact time of impact.
fn impact_contact(hit: &TimeOfImpact) -> ContactPoint {
    ContactPoint {
        point: hit.point,
        // The query's normal points from the second mesh towards the first.
        normal: -hit.normal,
        depth: 0.0,
        triangles: Some(hit.triangles),
        time_of_impact: Some(hit.time),
    }
}

/// What the time-critical continuous test of an ADB pair answered.
pub(crate) struct SweptAdb {
    /// The contact, if the pair is reported touching during the motion.
    pub contact: Option<ContactPoint>,
    /// The confidence of that answer (1 for a contact found exactly).
    pub probability: f64,
    pub node_pairs: u64,
    pub budget_exhausted: bool,
}

/// [`swept_contact`] for two ADB colliders within `budget`: an exact contact when the search
/// finds one, else (budget spent, node pairs left) a contact at the most probable pair left,
/// at the earliest time one can meet, when the query says so.
pub(crate) fn swept_adb_contact(
    a: &ColliderEntry,
    b: &ColliderEntry,
    run: u64,
    (budget, collide_at, conservative): (Budget, f64, bool),
    ws: &mut CcdWorkspace,
) -> Option<SweptAdb> {
    let (ta, tb) = (a.geometry.adb()?, b.geometry.adb()?);
    let query = ContinuousAdbQuery {
        budget,
        collide_at,
        conservative,
        ..ContinuousAdbQuery::default()
    };
    let out = adb_time_of_impact(ta, &a.motion_in(run), tb, &b.motion_in(run), &query, ws).ok()?;
    let contact = match (out.collides, out.impact, out.witness) {
        (false, ..) => None,
        (true, Some(hit), _) if out.time == Some(hit.time) => Some(impact_contact(&hit)),
        (true, impact, witness) => {
            // Unsettled: where the pairs left most probably meet, at the earliest time they can.
            let (point, normal) = match (witness, impact) {
                (Some(w), _) => (w.point, w.normal),
                (None, Some(hit)) => (hit.point, hit.normal),
                (None, None) => return None,
            };
            Some(ContactPoint {
                point,
                normal: -normal,
                depth: 0.0,
                triangles: impact.map(|h| h.triangles),
                time_of_impact: out.time,
            })
        }
    };
    Some(SweptAdb {
        contact,
        probability: out.probability,
        node_pairs: out.node_pairs_visited,
        budget_exhausted: out.budget_exhausted,
    })
}
