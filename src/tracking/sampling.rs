//! Drawing new random triangle pairs: uniform over area, velocity-weighted, or inside the
//! overlapping patch pairs of the incomplete hierarchy (Kimmerle et al.).

use rand::RngExt;
use rand::rngs::Xoshiro256PlusPlus;

use super::config::Sampling;
use super::local_search::adjacent;
use super::patch_tree::{box_transform, random_leaf_pair};
use super::surface::{Placed, TrackedSurface};

/// Scratch memory of the samplers, reused across frames.
#[derive(Debug, Default, Clone)]
pub(crate) struct SamplerScratch {
    stack: Vec<(u32, u32)>,
    overlaps: Vec<(u32, u32)>,
    covered: std::collections::HashSet<(u32, u32)>,
    cdf_a: Vec<f64>,
    cdf_b: Vec<f64>,
    /// Overlapping patch pairs found this frame.
    pub overlap_count: usize,
}

/// Fraction of hierarchy-driven samples drawn uniformly instead (contacts between adjacent
/// patches, which the hierarchy skips in self-collision).
const UNIFORM_SHARE: f64 = 0.25;

/// Candidate patch pairs tried per sample: a random descent below a pair can dead-end (its
/// subtrees are apart at a finer level), and then another pair is drawn.
const DESCENT_TRIES: usize = 8;

#[allow(clippy::too_many_arguments)]
pub(crate) fn draw(
    sampling: Sampling,
    n: usize,
    a: &Placed,
    b: &Placed,
    self_mode: bool,
    margin: f32,
    known: impl Iterator<Item = (u32, u32)>,
    rng: &mut Xoshiro256PlusPlus,
    scratch: &mut SamplerScratch,
    out: &mut Vec<(u32, u32)>,
) {
    scratch.overlap_count = 0;
    if n == 0 {
        return;
    }
    match sampling {
        Sampling::Uniform => uniform(n, a, b, self_mode, rng, out),
        Sampling::Velocity => {
            velocity_cdf(a.surface, &mut scratch.cdf_a);
            if !self_mode {
                velocity_cdf(b.surface, &mut scratch.cdf_b);
            }
            let cdf_b = if self_mode {
                &scratch.cdf_a
            } else {
                &scratch.cdf_b
            };
            for _ in 0..n {
                for _ in 0..4 {
                    let ta = pick(&scratch.cdf_a, rng.random::<f64>());
                    let tb = pick(cdf_b, rng.random::<f64>());
                    if !self_mode || (ta != tb && !adjacent(a.corners(ta), b.corners(tb))) {
                        out.push((ta, tb));
                        break;
                    }
                }
            }
        }
        Sampling::Hierarchy => {
            scratch.overlaps.clear();
            if self_mode {
                a.surface.patches.self_overlaps(margin, &mut scratch.stack, &mut scratch.overlaps);
            } else if let Some(rel) = &b.pose {
                a.surface.patches.pair_overlaps(
                    &b.surface.patches,
                    rel,
                    margin,
                    &mut scratch.stack,
                    &mut scratch.overlaps,
                );
            }
            scratch.overlap_count = scratch.overlaps.len();
            // Patch pairs that already hold a tracked pair or a contact are followed by it (and
            // by propagation): new samples go where nothing is known yet.
            scratch.covered.clear();
            let (of_a, of_b) = (&a.surface.patches.patch_of, &b.surface.patches.patch_of);
            for (ta, tb) in known {
                let (x, y) = (of_a[ta as usize], of_b[tb as usize]);
                scratch
                    .covered
                    .insert(if self_mode { (x.min(y), x.max(y)) } else { (x, y) });
            }
            if !scratch.covered.is_empty() {
                let covered = &scratch.covered;
                scratch.overlaps.retain(|p| !covered.contains(p));
            }
            let uniform_n = if self_mode {
                (n as f64 * UNIFORM_SHARE).round() as usize
            } else {
                0
            };
            uniform(uniform_n, a, b, self_mode, rng, out);
            if scratch.overlaps.is_empty() {
                // No two non-adjacent patches (or, for two meshes, no two patches at all)
                // come within the margin: contacts elsewhere are impossible.
                return;
            }
            let xf = b.pose.as_ref().map(box_transform);
            let (bvh_a, bvh_b) = (&a.surface.patches.bvh, &b.surface.patches.bvh);
            for _ in 0..n - uniform_n {
                for _ in 0..DESCENT_TRIES {
                    let (pa, pb) = scratch.overlaps[rng.random_range(0..scratch.overlaps.len())];
                    let na = a.surface.patches.patches[pa as usize].node;
                    let nb = b.surface.patches.patches[pb as usize].node;
                    let Some((la, lb)) =
                        random_leaf_pair(bvh_a, bvh_b, xf.as_ref(), na, nb, margin, rng)
                    else {
                        continue;
                    };
                    let (ts_a, ts_b) = (
                        bvh_a.triangles_of(&bvh_a.nodes()[la as usize]),
                        bvh_b.triangles_of(&bvh_b.nodes()[lb as usize]),
                    );
                    if let Some(pair) = pick_in_leaves(ts_a, ts_b, a, b, self_mode, rng) {
                        out.push(pair);
                        break;
                    }
                }
            }
        }
    }
}

/// A random pair of triangles from two leaves (not adjacent in self-collision), if any.
fn pick_in_leaves(
    ts_a: &[u32],
    ts_b: &[u32],
    a: &Placed,
    b: &Placed,
    self_mode: bool,
    rng: &mut Xoshiro256PlusPlus,
) -> Option<(u32, u32)> {
    let (oa, ob) = (rng.random_range(0..ts_a.len()), rng.random_range(0..ts_b.len()));
    for i in 0..ts_a.len() {
        for j in 0..ts_b.len() {
            let (ta, tb) = (ts_a[(oa + i) % ts_a.len()], ts_b[(ob + j) % ts_b.len()]);
            if !self_mode || (ta != tb && !adjacent(a.corners(ta), b.corners(tb))) {
                return Some((ta, tb));
            }
        }
    }
    None
}

fn uniform(
    n: usize,
    a: &Placed,
    b: &Placed,
    self_mode: bool,
    rng: &mut Xoshiro256PlusPlus,
    out: &mut Vec<(u32, u32)>,
) {
    for _ in 0..n {
        for _ in 0..4 {
            let ta = a.surface.triangle_at_area(rng.random::<f64>());
            let tb = b.surface.triangle_at_area(rng.random::<f64>());
            if !self_mode || (ta != tb && !adjacent(a.corners(ta), b.corners(tb))) {
                out.push((ta, tb));
                break;
            }
        }
    }
}

/// Cumulative weights `area · (ε + displacement)`: fast-moving triangles are drawn more.
fn velocity_cdf(surface: &TrackedSurface, cdf: &mut Vec<f64>) {
    cdf.clear();
    let mesh = surface.mesh();
    let floor = 1e-3 * surface.mean_edge_length() as f64;
    let mut total = 0.0;
    for (t, tri) in mesh.triangles().iter().enumerate() {
        let [p, q, r] = mesh.triangle(t).map(|x| x.as_dvec3());
        let area = 0.5 * (q - p).cross(r - p).length();
        let speed = tri
            .iter()
            .map(|&v| surface.displacement(v) as f64)
            .fold(0.0, f64::max);
        total += area * (floor + speed);
        cdf.push(total);
    }
}

fn pick(cdf: &[f64], u: f64) -> u32 {
    let total = cdf.last().copied().unwrap_or(0.0);
    if total.is_nan() || total <= 0.0 {
        return ((u * cdf.len() as f64) as usize).min(cdf.len().saturating_sub(1)) as u32;
    }
    cdf.partition_point(|&c| c <= u * total).min(cdf.len() - 1) as u32
}
