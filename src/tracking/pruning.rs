//! Removing unwanted pairs: too far (Guy and Debunne), converged to the same features, or
//! redundant by topological ring distance.

use rustc_hash::{FxHashMap as HashMap, FxHashSet as HashSet};

use smallvec::SmallVec;

use super::TrackedPair;
use crate::mesh::{RingWalk, Topology, VertexList};

/// Why pairs were dropped in one frame.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct PruneCounts {
    /// Farther than `k·d_min + ε` (and than the thickness).
    pub far: usize,
    /// Converged to the same feature pair as a closer pair.
    pub duplicate: usize,
    /// Within the redundancy rings of a closer pair on both sides.
    pub redundant: usize,
    /// Self pairs sliding along the sheet into the adjacency zone.
    pub sliding: usize,
    /// Over the active-pair cap.
    pub over_cap: usize,
}

/// Vertices within a few rings of a vertex, ascending.
type Ring = SmallVec<[u32; 40]>;

/// Scratch memory for redundancy checks.
#[derive(Debug, Default, Clone)]
pub(crate) struct PruneScratch {
    claims: HashMap<u32, SmallVec<[u32; 4]>>,
    /// Per kept pair: the vertices within the rings of its second feature.
    rings: Vec<Ring>,
    walk: RingWalk,
    found: VertexList,
}

/// Vertices within `rings` edge steps of `v`, ascending.
fn ring(topology: &Topology, v: u32, rings: u32, scratch: &mut PruneScratch) -> Ring {
    scratch
        .walk
        .collect(topology, &[v], rings, &mut scratch.found);
    let mut set = Ring::from_slice(&scratch.found);
    set.sort_unstable();
    set
}

/// The thresholds of [`prune`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct PruneSettings {
    /// One mesh against itself: `(x, y)` and `(y, x)` are the same contact.
    pub self_mode: bool,
    /// Guy and Debunne's `k`.
    pub far_factor: f32,
    /// Guy and Debunne's `ε`, absolute.
    pub far_epsilon: f64,
    /// Pairs within it are never far.
    pub thickness: f32,
    /// Pairs within this many rings of a closer pair on both sides are redundant.
    pub redundancy_rings: u32,
    /// Largest number of pairs kept.
    pub max_pairs: usize,
}

/// Prunes `pairs` (already searched) in place; keeps them sorted by distance (ties by
/// features), so the outcome does not depend on the order pairs were found in.
pub(crate) fn prune(
    pairs: &mut Vec<TrackedPair>,
    topo_a: &Topology,
    topo_b: &Topology,
    settings: &PruneSettings,
    scratch: &mut PruneScratch,
    counts: &mut PruneCounts,
) {
    let PruneSettings {
        self_mode,
        far_factor,
        far_epsilon,
        thickness,
        redundancy_rings,
        max_pairs,
    } = *settings;
    pairs.sort_by(|x, y| {
        x.distance
            .total_cmp(&y.distance)
            .then((x.feature_a, x.feature_b).cmp(&(y.feature_a, y.feature_b)))
    });
    // Far pairs (Guy & Debunne).
    if let Some(d_min) = pairs.first().map(|p| p.distance) {
        let limit = (far_factor as f64 * d_min + far_epsilon).max(thickness as f64);
        let before = pairs.len();
        pairs.retain(|p| p.distance <= limit);
        counts.far += before - pairs.len();
    }
    // Same feature pair: keep the first (closest).
    let mut seen = HashSet::with_capacity_and_hasher(pairs.len(), Default::default());
    let before = pairs.len();
    pairs.retain(|p| seen.insert((p.feature_a, p.feature_b)));
    counts.duplicate += before - pairs.len();
    // Redundant within rings on both sides.
    if redundancy_rings > 0 {
        scratch.claims.clear();
        scratch.rings.clear();
        let before = pairs.len();
        let mut kept = Vec::with_capacity(pairs.len());
        for p in pairs.drain(..) {
            let (va, vb) = (p.vertex_a, p.vertex_b);
            // Some kept pair has `v` within its first ring and `other` within its second.
            let covered = |v: u32, other: u32, s: &PruneScratch| {
                s.claims.get(&v).is_some_and(|ids| {
                    ids.iter()
                        .any(|&id| s.rings[id as usize].binary_search(&other).is_ok())
                })
            };
            // In self-collision, (x, y) and (y, x) are the same contact.
            let redundant = covered(va, vb, scratch) || (self_mode && covered(vb, va, scratch));
            if redundant {
                continue;
            }
            let ra = ring(topo_a, va, redundancy_rings, scratch);
            let rb = ring(topo_b, vb, redundancy_rings, scratch);
            let id = scratch.rings.len() as u32;
            for &v in &ra {
                scratch.claims.entry(v).or_default().push(id);
            }
            scratch.rings.push(rb);
            kept.push(p);
        }
        *pairs = kept;
        counts.redundant += before - pairs.len();
    }
    if pairs.len() > max_pairs {
        counts.over_cap += pairs.len() - max_pairs;
        pairs.truncate(max_pairs);
    }
}
