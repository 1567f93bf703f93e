//! Drawing new random triangle pairs: uniform over area, velocity-weighted, or inside the
//! overlapping patch pairs of the incomplete hierarchy (Kimmerle et al.).

use glam::Vec3;
use rand::RngExt;
use rand::rngs::Xoshiro256PlusPlus;

use super::config::Sampling;
use super::local_search::adjacent;
use super::surface::{Placed, TrackedSurface};

/// Scratch memory of the samplers, reused across frames.
#[derive(Debug, Default, Clone)]
pub(crate) struct SamplerScratch {
    stack: Vec<(u32, u32)>,
    overlaps: Vec<(u32, u32)>,
    cdf_a: Vec<f64>,
    cdf_b: Vec<f64>,
    /// Overlapping patch pairs found this frame.
    pub overlap_count: usize,
}

/// Fraction of hierarchy-driven samples drawn uniformly instead (contacts between adjacent
/// patches, which the hierarchy skips in self-collision).
const UNIFORM_SHARE: f64 = 0.25;

/// Tries to find a triangle of a patch whose box meets the region of interest.
const PATCH_TRIES: usize = 8;

#[allow(clippy::too_many_arguments)]
pub(crate) fn draw(
    sampling: Sampling,
    n: usize,
    a: &Placed,
    b: &Placed,
    self_mode: bool,
    margin: f32,
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
                a.surface
                    .patches
                    .self_overlaps(margin, &mut scratch.stack, &mut scratch.overlaps);
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
            for _ in 0..n - uniform_n {
                let (pa, pb) = scratch.overlaps[rng.random_range(0..scratch.overlaps.len())];
                let (patch_a, patch_b) = (
                    &a.surface.patches.patches[pa as usize],
                    &b.surface.patches.patches[pb as usize],
                );
                // The region where the two patches' boxes meet, in `a`'s frame.
                let (lo_b, hi_b) = match &b.pose {
                    None => (patch_b.min, patch_b.max),
                    Some(rel) => {
                        let corners = (0..8).map(|k| {
                            let c = Vec3::new(
                                if k & 1 == 0 {
                                    patch_b.min.x
                                } else {
                                    patch_b.max.x
                                },
                                if k & 2 == 0 {
                                    patch_b.min.y
                                } else {
                                    patch_b.max.y
                                },
                                if k & 4 == 0 {
                                    patch_b.min.z
                                } else {
                                    patch_b.max.z
                                },
                            );
                            rel.transform_point(c).as_vec3()
                        });
                        corners.fold(
                            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                            |(l, h), c| (l.min(c), h.max(c)),
                        )
                    }
                };
                let lo = patch_a.min.max(lo_b) - margin;
                let hi = patch_a.max.min(hi_b) + margin;
                let ta = pick_in_region(a, &patch_a.triangles, lo, hi, rng);
                let tb = pick_in_region(b, &patch_b.triangles, lo, hi, rng);
                if !self_mode || !adjacent(a.corners(ta), b.corners(tb)) {
                    out.push((ta, tb));
                }
            }
        }
    }
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

/// A random triangle of `triangles` whose box (in `a`'s frame) meets `[lo, hi]`, within a
/// few tries (else the last one tried).
fn pick_in_region(
    side: &Placed,
    triangles: &[u32],
    lo: Vec3,
    hi: Vec3,
    rng: &mut Xoshiro256PlusPlus,
) -> u32 {
    let mut t = triangles[0];
    for _ in 0..PATCH_TRIES {
        t = triangles[rng.random_range(0..triangles.len())];
        let tri = side.triangle(t).map(|p| p.as_vec3());
        let (tl, th) = (
            tri[0].min(tri[1]).min(tri[2]),
            tri[0].max(tri[1]).max(tri[2]),
        );
        if tl.cmple(hi).all() && lo.cmple(th).all() {
            break;
        }
    }
    t
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
