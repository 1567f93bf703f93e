//! Continuous tests of pairs with a swept collider
//! ([`ContinuousCollision`](super::super::ContinuousCollision)): the exact continuous query over
//! both colliders' motions in the run, for a pair the discrete test found apart (a collider
//! may have passed through the other) or that did not touch before (its started event gets
//! the time of impact).
use super::super::contact::ContactPoint;
use super::super::prepare::ColliderEntry;
use crate::ccd::{CcdOptions, CcdWorkspace, time_of_impact};

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
    Some(ContactPoint {
        point: hit.point,
        // The query's normal points from the second mesh towards the first.
        normal: -hit.normal,
        depth: 0.0,
        triangles: Some(hit.triangles),
        time_of_impact: Some(hit.time),
    })
}
