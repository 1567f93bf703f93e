//! Drawing new random triangle pairs: uniform over area, velocity-weighted, or inside the
//! overlapping patch pairs of the incomplete hierarchy (Kimmerle et al.).

use rand::RngExt;
use rand::rngs::Xoshiro256PlusPlus;

use super::boxes::{Box64, box_axis_gap, box_gap, triangle_box};
use super::candidates::KeptCandidates;
use super::config::Sampling;
use super::patch_tree::{box_transform, random_leaf_pair};
use super::surface::{ExcludedPairs, Placed, TrackedSurface};
use crate::bvh::within_thickness;
use crate::geometry::{PoseF64, closest_points_triangle_triangle};
use crate::mesh::{LocalExclusion, RingWalk, VertexList, adjacent};

/// Scratch memory of the samplers, reused across frames.
#[derive(Debug, Default, Clone)]
pub(crate) struct SamplerScratch {
    stack: Vec<(u32, u32)>,
    overlaps: Vec<(u32, u32)>,
    /// Patch pairs holding a known contact, sorted (a few dozen, looked up for each of up to
    /// tens of thousands of overlapping pairs).
    covered: Vec<(u32, u32)>,
    known_triangles: rustc_hash::FxHashSet<u32>,
    near_known: Vec<u32>,
    /// Crease probe candidates: (sharpness key, edge, collapsed rather than folded).
    sharp: Vec<(f32, u32, bool)>,
    walk: RingWalk,
    ring: VertexList,
    local: Vec<u32>,
    boxes: Vec<([glam::DVec3; 3], Box64)>,
    /// The exclusion among a crease probe's triangles, as bit masks.
    local_exclusion: LocalExclusion,
    /// A crease probe's triangles in the order of their boxes along x, and its pairs found.
    order: Vec<u32>,
    hits: Vec<(u32, u32)>,
    cdf_a: Vec<f64>,
    cdf_b: Vec<f64>,
    /// Self-collision: the candidates kept between steps.
    pub kept: KeptCandidates,
    /// The kept sharp edges of this step (see [`KeptCandidates::refresh`]).
    kept_sharp: Vec<(f32, u32, bool)>,
    /// Overlapping patch pairs found this frame.
    pub overlap_count: usize,
    /// Of them, those in a part of the surface that moved since the last frame (self-collision:
    /// in the kept lists made again); between two meshes, all.
    pub moved_overlap_count: usize,
    /// New pairs this frame's [`draw`] was to draw: the request's count, or more with
    /// [`DrawRequest::overlaps_per_pair`].
    pub count: usize,
    /// Where this frame's crease probes lie among the pairs drawn (they start within the
    /// thickness: the coarse level has nothing to do for them).
    pub crease_starts: std::ops::Range<usize>,
    /// Time spent this frame finding candidates (patch overlaps, covered patch pairs, sharp
    /// edges); the rest of [`draw`] is sampling.
    pub candidates_time: std::time::Duration,
}

/// Fraction of hierarchy-driven samples drawn uniformly instead (contacts between adjacent
/// patches, which the hierarchy skips in self-collision).
const UNIFORM_SHARE: f64 = 0.25;

/// One sample in this many is spent on a crease probe (self-collision). Chosen on the
/// training meshes and seeds (`TRAINING_MESHES`, `TRAINING_SEEDS`): a third found as many
/// regions as a quarter or more on each, and kept more of the exact pairs covered than a half.
const CREASE_SHARE: usize = 3;

/// Crease probes go to random edges among this many times as many of the sharpest.
const PROBE_POOL: usize = 4;

/// Candidate patch pairs tried per sample: a random descent below a pair can dead-end (its
/// subtrees are apart at a finer level), and then another pair is drawn.
const DESCENT_TRIES: usize = 8;

/// What one frame's [`draw`] is asked for.
#[derive(Clone, Copy)]
pub(crate) struct DrawRequest<'a> {
    /// Where new pairs come from.
    pub sampling: Sampling,
    /// How many new pairs to draw (0: none).
    pub count: usize,
    /// Hierarchy sampling: draw at least one pair per this many overlapping patch pairs, up
    /// to `count_cap` (see [`TrackerConfig::overlaps_per_pair`](super::TrackerConfig::overlaps_per_pair)).
    pub overlaps_per_pair: Option<u32>,
    /// The most pairs `overlaps_per_pair` may ask for.
    pub count_cap: usize,
    /// One mesh against itself.
    pub self_mode: bool,
    /// Self-collision leaves out these pairs (within the exclusion rings).
    pub excluded_pairs: Option<ExcludedPairs<'a>>,
    /// Contact distance.
    pub thickness: f32,
    /// Boxes within this of each other may hold a pair worth tracking.
    pub margin: f32,
    /// Two meshes: the second's pose in the first's frame at the previous step, if any (for
    /// velocity sampling, which weighs the relative rigid motion too).
    pub previous_pose: Option<PoseF64>,
    /// Hierarchy sampling in self-collision: the candidates (overlapping patch pairs, sharp
    /// edges) are kept between steps and brought up to date where the surface moved most
    /// within this time ([`KeptCandidates`]; [`Duration::MAX`](std::time::Duration::MAX):
    /// every list whose blocks moved). Between two meshes they are found anew.
    pub candidate_allowance: std::time::Duration,
}

/// Draws `request.count` new triangle pairs of `a` and `b` into `out`; `known` are the
/// triangle pairs of the current contacts (their patch pairs are left to them).
pub(crate) fn draw(
    request: &DrawRequest,
    a: &Placed,
    b: &Placed,
    known: impl Iterator<Item = (u32, u32)>,
    rng: &mut Xoshiro256PlusPlus,
    scratch: &mut SamplerScratch,
    out: &mut Vec<(u32, u32)>,
) {
    let DrawRequest {
        sampling,
        count: n,
        self_mode,
        excluded_pairs,
        margin,
        ..
    } = *request;
    scratch.overlap_count = 0;
    scratch.moved_overlap_count = 0;
    scratch.count = n;
    scratch.candidates_time = std::time::Duration::ZERO;
    scratch.kept.refreshed = 0;
    scratch.crease_starts = 0..0;
    if n == 0 {
        return;
    }
    match sampling {
        Sampling::Uniform => uniform(n, a, b, self_mode, rng, out),
        Sampling::Velocity => {
            // Two meshes: each side's motion as the other side sees it (its deformation and
            // the relative rigid motion since the last step); one mesh: its deformation.
            let motion = match (b.pose, request.previous_pose) {
                (Some(now), Some(before)) if !self_mode => Some((now, before)),
                _ => None,
            };
            velocity_cdf(
                a.surface,
                motion.map(|(now, before)| (now.inverse(), before.inverse())),
                &mut scratch.cdf_a,
            );
            if !self_mode {
                velocity_cdf(b.surface, motion, &mut scratch.cdf_b);
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
            let started = std::time::Instant::now();
            scratch.overlaps.clear();
            // Self-collision: candidates kept between steps.
            let kept = self_mode;
            if kept {
                scratch.kept.refresh(
                    a.surface,
                    margin,
                    request.candidate_allowance,
                    &mut scratch.overlaps,
                    &mut scratch.kept_sharp,
                );
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
            // More pairs where many patch pairs are close: in self-collision those where the
            // surface moved (the lists made again), where new contacts can appear.
            scratch.moved_overlap_count = if kept {
                scratch.kept.refreshed_overlaps
            } else {
                scratch.overlap_count
            };
            let n = match request.overlaps_per_pair {
                Some(k) => n.max(
                    scratch
                        .moved_overlap_count
                        .div_ceil(k.max(1) as usize)
                        .min(request.count_cap),
                ),
                None => n,
            };
            scratch.count = n;
            // Patch pairs that already hold a contact are followed by its pair and by
            // propagation: new samples go where no contact is known yet.
            scratch.covered.clear();
            scratch.known_triangles.clear();
            let (of_a, of_b) = (&a.surface.patches.patch_of, &b.surface.patches.patch_of);
            for (ta, tb) in known {
                scratch.known_triangles.insert(ta);
                scratch.known_triangles.insert(tb);
                let (x, y) = (of_a[ta as usize], of_b[tb as usize]);
                scratch.covered.push(if self_mode {
                    (x.min(y), x.max(y))
                } else {
                    (x, y)
                });
            }
            scratch.covered.sort_unstable();
            scratch.covered.dedup();
            // Kept candidates are many (tens of thousands on a coiled 100k-triangle tube):
            // their covered pairs are passed over when drawn rather than filtered out here.
            if !scratch.covered.is_empty() && !kept {
                let covered = &scratch.covered;
                scratch
                    .overlaps
                    .retain(|p| covered.binary_search(p).is_err());
            }
            let uniform_n = if self_mode {
                (n as f64 * UNIFORM_SHARE).round() as usize
            } else {
                0
            };
            scratch.candidates_time = started.elapsed();
            uniform(uniform_n, a, b, self_mode, rng, out);
            if scratch.overlaps.is_empty() {
                // No two non-adjacent patches (or, for two meshes, no two patches at all)
                // come within the margin: contacts elsewhere are impossible.
                return;
            }
            let mut budget = n - uniform_n;
            if self_mode {
                let first = out.len();
                budget -=
                    crease_probes(n / CREASE_SHARE, a, request, rng, scratch, out).min(budget);
                scratch.crease_starts = first..out.len();
            }
            let xf = b.pose.as_ref().map(box_transform);
            let (bvh_a, bvh_b) = (&a.surface.patches.bvh, &b.surface.patches.bvh);
            for _ in 0..budget {
                for _ in 0..DESCENT_TRIES {
                    let (pa, pb) = scratch.overlaps[rng.random_range(0..scratch.overlaps.len())];
                    if kept && scratch.covered.binary_search(&(pa, pb)).is_ok() {
                        continue;
                    }
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
                    let exclusion = excluded_pairs.filter(|_| self_mode);
                    if let Some(pair) = best_in_leaves(ts_a, ts_b, a, b, exclusion, rng) {
                        out.push(pair);
                        break;
                    }
                }
            }
        }
    }
}

/// The closest pair of triangles of two leaves (not excluded in self-collision), if any: a
/// start on the right side of a fold, where a random pick would often start on the same side
/// and slide. Ties keep the first in a random order.
fn best_in_leaves(
    ts_a: &[u32],
    ts_b: &[u32],
    a: &Placed,
    b: &Placed,
    exclusion: Option<ExcludedPairs>,
    rng: &mut Xoshiro256PlusPlus,
) -> Option<(u32, u32)> {
    let (oa, ob) = (
        rng.random_range(0..ts_a.len()),
        rng.random_range(0..ts_b.len()),
    );
    let mut best: Option<(f64, u32, u32)> = None;
    for i in 0..ts_a.len() {
        let ta = ts_a[(oa + i) % ts_a.len()];
        let tri_a = a.triangle(ta);
        let box_a = triangle_box(&tri_a);
        for j in 0..ts_b.len() {
            let tb = ts_b[(ob + j) % ts_b.len()];
            if exclusion.is_some_and(|e| e.excludes(ta, tb)) {
                continue;
            }
            let tri_b = b.triangle(tb);
            let gap = box_gap(&box_a, &triangle_box(&tri_b));
            if best.is_some_and(|(d, _, _)| gap >= d) {
                continue;
            }
            let d = closest_points_triangle_triangle(&tri_a, &tri_b).distance;
            if best.is_none_or(|(e, _, _)| d < e) {
                best = Some((d, ta, tb));
            }
        }
    }
    best.map(|(_, ta, tb)| (ta, tb))
}

/// Crease probes (self-collision): around `count` edges drawn among the sharpest folded ones
/// (dihedral fold past 90°) or most collapsed ones (shorter than 30 % of their rest length)
/// that are not next to a known contact, every pair of triangles within two vertex rings
/// of the edge that are closer than the thickness (and not excluded) becomes a start,
/// whatever their orientation: the two sides of a fold face each other, but the outer layers
/// of a pleat (a sheet folded down and up again) lie parallel, and a squeezed sheet meets
/// itself at any angle. A surface folding onto itself first touches just beyond the excluded
/// zone, next to a sharp edge, where random starts mostly slide along the sheet. Returns the
/// number of probes made.
fn crease_probes(
    count: usize,
    a: &Placed,
    request: &DrawRequest,
    rng: &mut Xoshiro256PlusPlus,
    scratch: &mut SamplerScratch,
    out: &mut Vec<(u32, u32)>,
) -> usize {
    let thickness = request.thickness;
    let Some(excluded) = request.excluded_pairs else {
        return 0;
    };
    let scan_started = std::time::Instant::now();
    let topo = a.topology();
    // Vertices within a ring of a known contact: creases there are being followed.
    scratch.near_known.clear();
    for &t in &scratch.known_triangles {
        for v in a.corners(t) {
            scratch.near_known.push(v);
            scratch
                .near_known
                .extend_from_slice(topo.vertex_neighbours(v));
        }
    }
    scratch.near_known.sort_unstable();
    scratch.near_known.dedup();
    // The kept sharp edges (see `KeptCandidates::refresh`), those next to a known contact
    // left out.
    let near_known = &scratch.near_known;
    let free = |v: u32| near_known.binary_search(&v).is_err();
    scratch.sharp.clear();
    scratch.sharp.extend(
        scratch
            .kept_sharp
            .iter()
            .filter(|&&(_, edge, _)| topo.edge(edge).vertices.into_iter().all(free)),
    );
    // `count` edges drawn at random among the `PROBE_POOL · count` sharpest.
    let sharpest =
        |x: &(f32, u32, bool), y: &(f32, u32, bool)| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1));
    let pool = count.saturating_mul(PROBE_POOL);
    if scratch.sharp.len() > pool {
        scratch.sharp.select_nth_unstable_by(pool, sharpest);
        scratch.sharp.truncate(pool);
    }
    scratch.sharp.sort_unstable_by(sharpest);
    for i in 0..count.min(scratch.sharp.len()) {
        let j = rng.random_range(i..scratch.sharp.len());
        scratch.sharp.swap(i, j);
    }
    scratch.sharp.truncate(count);
    scratch.candidates_time += scan_started.elapsed();
    let h = thickness.max(0.0) as f64;
    let probes = scratch.sharp.len();
    for i in 0..probes {
        let (_, edge, _) = scratch.sharp[i];
        let [v0, v1] = topo.edge(edge).vertices;
        // Triangles within two rings of the edge.
        scratch.walk.collect(topo, &[v0, v1], 2, &mut scratch.ring);
        scratch.local.clear();
        for &v in &scratch.ring {
            scratch.local.extend_from_slice(topo.vertex_triangles(v));
        }
        scratch.local.sort_unstable();
        scratch.local.dedup();
        scratch.boxes.clear();
        scratch.boxes.extend(scratch.local.iter().map(|&t| {
            let x = a.triangle(t);
            (x, triangle_box(&x))
        }));
        // Most of these pairs are within the excluded rings: one bit test each when the
        // neighbourhood's vertices fit the masks.
        let built = match excluded {
            ExcludedPairs::Cached { exclusion, .. } => {
                scratch.local_exclusion.build(exclusion, &scratch.local)
            }
            ExcludedPairs::Walk { .. } => false,
        };
        let masks = built.then_some(&scratch.local_exclusion);
        // Sweep along x: pairs whose boxes are more than `h` apart along it are never looked
        // at. Their hits are written in the order of a scan of every pair.
        let boxes = &scratch.boxes;
        scratch.order.clear();
        scratch.order.extend(0..boxes.len() as u32);
        scratch
            .order
            .sort_unstable_by(|&i, &j| boxes[i as usize].1.0.x.total_cmp(&boxes[j as usize].1.0.x));
        scratch.hits.clear();
        for (n, &i) in scratch.order.iter().enumerate() {
            let reach = boxes[i as usize].1.1.x + h;
            for &j in &scratch.order[n + 1..] {
                if boxes[j as usize].1.0.x > reach {
                    break;
                }
                let (k, l) = (i.min(j) as usize, i.max(j) as usize);
                let excludes = match masks {
                    Some(m) => m.excludes(k, l),
                    None => excluded.excludes(scratch.local[k], scratch.local[l]),
                };
                let ((x, box_x), (y, box_y)) = (&boxes[k], &boxes[l]);
                if excludes || box_axis_gap(box_x, box_y) > h {
                    continue;
                }
                if within_thickness(x, y, h).is_some() {
                    scratch.hits.push((k as u32, l as u32));
                }
            }
        }
        scratch.hits.sort_unstable();
        out.extend(
            scratch
                .hits
                .iter()
                .map(|&(k, l)| (scratch.local[k as usize], scratch.local[l as usize])),
        );
    }
    probes
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

/// Cumulative weights `area · (ε + displacement)`: fast-moving triangles are drawn more. The
/// displacement of a vertex is its motion since the surface's previous positions, in its own
/// frame, or with `seen_from = (now, before)` in another frame that it was placed in by
/// `before` at its previous positions and is placed in by `now` (rigid motion included).
pub(crate) fn velocity_cdf(
    surface: &TrackedSurface,
    seen_from: Option<(PoseF64, PoseF64)>,
    cdf: &mut Vec<f64>,
) {
    cdf.clear();
    let mesh = surface.mesh();
    let floor = 1e-3 * surface.mean_edge_length() as f64;
    let moved = |v: u32| match &seen_from {
        None => surface.displacement(v) as f64,
        Some((now, before)) => {
            let here = now.transform_point(mesh.positions()[v as usize]);
            let there = before.transform_point(surface.previous_position(v));
            (here - there).length()
        }
    };
    let mut total = 0.0;
    for (t, tri) in mesh.triangles().iter().enumerate() {
        let [p, q, r] = mesh.triangle(t).map(|x| x.as_dvec3());
        let area = 0.5 * (q - p).cross(r - p).length();
        let speed = tri.iter().map(|&v| moved(v)).fold(0.0, f64::max);
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

#[cfg(test)]
mod tests {
    use super::super::patch_tree::COLLAPSED_FRACTION;
    use super::super::sharp_edges::sharp_edges;
    use super::*;
    use crate::deform::Whirl;
    use crate::mesh::{TriMesh, generate};
    use crate::tracking::DEFAULT_PATCH_SIZE;
    use glam::Vec3;

    /// The reference: every topology edge between two triangles, its fold from the current
    /// normals and its collapse from the rest mesh's edge length.
    fn every_sharp_edge(
        surface: &TrackedSurface,
        rest: &TriMesh,
        near_known: &[u32],
    ) -> Vec<(f32, u32, bool)> {
        let (now, before) = (surface.mesh().positions(), rest.positions());
        let mut out = Vec::new();
        for (e, edge) in surface.topology().edges().iter().enumerate() {
            let [t0, t1, ..] = edge.triangles[..] else {
                continue;
            };
            let [v0, v1] = edge.vertices.map(|v| v as usize);
            let (n0, n1) = (surface.normals[t0 as usize], surface.normals[t1 as usize]);
            let fold = if n0 != Vec3::ZERO && n1 != Vec3::ZERO {
                n0.dot(n1)
            } else {
                1.0
            };
            let rest_length = (before[v0] - before[v1]).length();
            let collapse = if rest_length > 0.0 {
                (now[v0] - now[v1]).length() / rest_length / COLLAPSED_FRACTION - 1.0
            } else {
                1.0
            };
            let sharpness = fold.min(collapse);
            if sharpness < 0.0
                && !near_known.contains(&(v0 as u32))
                && !near_known.contains(&(v1 as u32))
            {
                out.push((sharpness, e as u32, collapse < fold));
            }
        }
        out
    }

    fn sorted(mut v: Vec<(f32, u32, bool)>) -> Vec<(u32, bool, u32)> {
        let mut out: Vec<_> = v.drain(..).map(|(c, e, k)| (e, k, c.to_bits())).collect();
        out.sort_unstable();
        out
    }

    /// `cloth`'s positions folded flat onto itself at x = 0.1, the folded part 0.01 above.
    fn folded_flat(cloth: &TriMesh) -> Vec<Vec3> {
        let fold = |p: &Vec3| {
            if p.x > 0.1 {
                Vec3::new(0.2 - p.x, 0.01, p.z)
            } else {
                *p
            }
        };
        cloth.positions().iter().map(fold).collect()
    }

    /// Scanning only the patches that may crease finds every folded and collapsed edge that
    /// a scan of every edge finds, with the same sharpness: on a whirled tube (frames that
    /// cut through themselves), a cloth folded flat onto itself, a cloth squeezed in a band
    /// (collapsed edges, no fold), and a whirled sphere in patches of up to 400 triangles
    /// (normal cones wider than a half turn), with and without known-contact vertices left
    /// out.
    #[test]
    fn the_patch_restricted_scan_finds_every_sharp_edge() {
        let tube = generate::tube(0.08, 2.0, 24, 160, true);
        let cloth = generate::cloth_grid(1.0, 1.0, 40, 40);
        let mut cases: Vec<(TriMesh, Vec<Vec3>)> = Vec::new();
        let whirl = Whirl::new(&tube, 60, 2);
        for f in [0, 10, 20, 30, 45] {
            let mut p = Vec::new();
            whirl.positions(f, &mut p);
            cases.push((tube.clone(), p));
        }
        cases.push((cloth.clone(), folded_flat(&cloth)));
        let squeezed = cloth
            .positions()
            .iter()
            .map(|p| {
                let x = if p.x.abs() < 0.1 {
                    0.1 * p.x
                } else {
                    p.x - 0.09 * p.x.signum()
                };
                Vec3::new(x, p.y, p.z)
            })
            .collect();
        cases.push((cloth.clone(), squeezed));
        cases.push((cloth.clone(), cloth.positions().to_vec()));
        // Patches wider than a half turn (most of a sphere each), whirled.
        let ball = generate::icosphere(1.0, 3);
        let whirl = Whirl::new(&ball, 40, 5);
        let mut balls = Vec::new();
        for f in [8, 14, 20] {
            let mut p = Vec::new();
            whirl.positions(f, &mut p);
            balls.push((ball.clone(), p));
        }
        let mut found_any = [false; 2];
        for (k, (mesh, positions)) in cases.into_iter().chain(balls).enumerate() {
            let patch_size = if k >= 8 { 400 } else { DEFAULT_PATCH_SIZE };
            let mut surface = TrackedSurface::with_patch_size(mesh.clone(), patch_size);
            surface.set_positions(&positions).unwrap();
            let mut restricted = Vec::new();
            for near_known in [vec![], (0..200).collect::<Vec<u32>>()] {
                let every = every_sharp_edge(&surface, &mesh, &near_known);
                sharp_edges(&surface, &near_known, &mut restricted);
                for &(_, _, collapsed) in &every {
                    found_any[collapsed as usize] = true;
                }
                assert_eq!(sorted(restricted.clone()), sorted(every), "case {k}");
            }
            let tree = &surface.patches;
            let scanned = (0..tree.patches.len() as u32)
                .filter(|&p| tree.may_crease(p))
                .count();
            if k == 5 {
                assert!(
                    scanned < tree.patches.len() / 2,
                    "the folded cloth's flat parts are skipped"
                );
            }
            if k == 7 {
                assert!(
                    every_sharp_edge(&surface, &mesh, &[]).is_empty() && scanned == 0,
                    "a flat sheet is not scanned"
                );
            }
        }
        assert!(
            found_any[0] && found_any[1],
            "folds and collapses were both seen"
        );
    }

    /// Velocity weights of a rigid mesh: nothing moves in its own frame, so the weights are its
    /// areas; seen from a frame in which it turns about one end, its far end weighs more
    /// than its hub, in proportion to how far each moved.
    #[test]
    fn velocity_weights_see_rigid_motion_in_the_other_frame() {
        use glam::{DQuat, DVec3};
        let rod = generate::tube(0.05, 1.0, 8, 20, false);
        let mut surface = TrackedSurface::new(rod.clone());
        surface.set_positions(rod.positions()).unwrap();
        let (mut own, mut seen) = (Vec::new(), Vec::new());
        velocity_cdf(&surface, None, &mut own);
        // Turning about the rod's lower end (y = -0.5) by 0.2 rad between the two steps.
        let hinge = DVec3::new(0.0, -0.5, 0.0);
        let turn = |angle: f64| {
            let rotation = DQuat::from_rotation_z(angle);
            PoseF64 {
                rotation,
                translation: hinge - rotation * hinge,
            }
        };
        velocity_cdf(&surface, Some((turn(0.2), turn(0.0))), &mut seen);
        let weight = |cdf: &[f64], t: usize| cdf[t] - if t == 0 { 0.0 } else { cdf[t - 1] };
        let halves = |cdf: &[f64]| {
            let mut sums = [0.0f64; 2];
            for t in 0..rod.triangle_count() {
                let c = rod.triangle(t).iter().map(|p| p.y).sum::<f32>() / 3.0;
                sums[usize::from(c > 0.0)] += weight(cdf, t);
            }
            sums
        };
        let (own, seen) = (halves(&own), halves(&seen));
        assert!(
            (own[0] / own[1] - 1.0).abs() < 0.01,
            "own frame: by area, {own:?}"
        );
        assert!(seen[1] > 2.0 * seen[0], "the far half moved more: {seen:?}");
    }

    /// Each crease probe reports exactly the pairs of triangles within two rings of its edge
    /// that a scan of every such pair finds (not excluded, at most the thickness apart by the
    /// exact distance), in that scan's order: on a cloth folded flat onto itself and on frames
    /// of a whirled tube, with the surface's cached exclusion (two rings) and with a ring walk
    /// (three rings).
    #[test]
    fn crease_probes_report_what_a_scan_of_every_pair_finds() {
        use rand::SeedableRng;
        let cloth = generate::cloth_grid(1.0, 1.0, 40, 40);
        let folded = folded_flat(&cloth);
        let tube = generate::tube(0.08, 2.0, 24, 160, true);
        let whirl = Whirl::new(&tube, 60, 2);
        let mut cases = vec![(cloth, folded, 0.02f32)];
        for f in [20, 30, 45] {
            let mut p = Vec::new();
            whirl.positions(f, &mut p);
            cases.push((tube.clone(), p, 0.02));
        }
        let mut total = 0;
        for (k, (mesh, positions, thickness)) in cases.into_iter().enumerate() {
            let mut surface = TrackedSurface::new(mesh);
            surface.set_positions(&positions).unwrap();
            for rings in [2, 3, 4] {
                let excluded = surface.excluded_pairs(rings);
                assert_eq!(
                    matches!(excluded, ExcludedPairs::Cached { .. }),
                    rings != 4,
                    "the exclusion built with the surface, the first other ring count's and a \
                     walk of the topology are all tried"
                );
                let request = DrawRequest {
                    sampling: Sampling::Hierarchy,
                    count: 0,
                    overlaps_per_pair: None,
                    count_cap: 0,
                    self_mode: true,
                    excluded_pairs: Some(excluded),
                    thickness,
                    margin: thickness,
                    previous_pose: None,
                    candidate_allowance: std::time::Duration::MAX,
                };
                let placed = Placed {
                    surface: &surface,
                    pose: None,
                };
                let mut scratch = SamplerScratch::default();
                scratch.kept.refresh(
                    &surface,
                    thickness,
                    std::time::Duration::MAX,
                    &mut scratch.overlaps,
                    &mut scratch.kept_sharp,
                );
                let mut rng = Xoshiro256PlusPlus::seed_from_u64(k as u64);
                let mut found = Vec::new();
                let probes =
                    crease_probes(12, &placed, &request, &mut rng, &mut scratch, &mut found);
                assert!(probes > 0, "case {k}: sharp edges to probe");
                // The reference: the same edges, every pair of the triangles within two rings.
                let topo = surface.topology();
                let mut expected = Vec::new();
                for &(_, edge, _) in &scratch.sharp[..probes] {
                    let mut near: Vec<u32> = topo.edge(edge).vertices.to_vec();
                    for _ in 0..2 {
                        let next: Vec<u32> = near
                            .iter()
                            .flat_map(|&v| topo.vertex_neighbours(v).iter().copied())
                            .collect();
                        near.extend(next);
                        near.sort_unstable();
                        near.dedup();
                    }
                    let mut local: Vec<u32> = near
                        .iter()
                        .flat_map(|&v| topo.vertex_triangles(v).iter().copied())
                        .collect();
                    local.sort_unstable();
                    local.dedup();
                    for (i, &t) in local.iter().enumerate() {
                        for &u in &local[i + 1..] {
                            let d = closest_points_triangle_triangle(
                                &placed.triangle(t),
                                &placed.triangle(u),
                            )
                            .distance;
                            if !excluded.excludes(t, u) && d <= f64::from(thickness) {
                                expected.push((t, u));
                            }
                        }
                    }
                }
                assert_eq!(found, expected, "case {k}, {rings} rings");
                total += found.len();
            }
        }
        assert!(total > 50, "{total} pairs found: the probes meet folds");
    }
}
