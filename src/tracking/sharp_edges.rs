//! The sharp edges of a tracked surface: folded past 90° or collapsed, where the crease
//! probes look for contacts (read by the sampling and kept per part of the patch tree by the
//! kept candidates).
use glam::Vec3;

use super::patch_tree::COLLAPSED_FRACTION;
use super::surface::TrackedSurface;

/// The folded edges (dihedral fold past 90°: the normals' cosine below 0) and collapsed
/// ones (shorter than [`COLLAPSED_FRACTION`] of their rest length) of `surface` with no
/// vertex in `near_known` (sorted), as (sharpness below 0: the normals' cosine, or the
/// remaining fraction of the rest length mapped to [-1, 0); edge; collapsed rather than
/// folded), written to `out` in no particular order. Only the edges of patches that
/// [may crease](super::patch_tree::PatchTree::may_crease) are looked at: the same set as a
/// scan of every edge, at a cost that follows the folded part of the surface. The tests'
/// reference for the kept sharp edges (the tracker keeps them per part of the patch tree).
#[cfg(test)]
pub(crate) fn sharp_edges(
    surface: &TrackedSurface,
    near_known: &[u32],
    out: &mut Vec<(f32, u32, bool)>,
) {
    out.clear();
    let all = 0..surface.patches.patches.len() as u32;
    sharp_edges_of(surface, all, near_known, out);
}

/// [`sharp_edges`] of the patches `patches` only, appended to `out`.
pub(crate) fn sharp_edges_of(
    surface: &TrackedSurface,
    patches: impl IntoIterator<Item = u32>,
    near_known: &[u32],
    out: &mut Vec<(f32, u32, bool)>,
) {
    let normals = &surface.normals;
    let positions = surface.mesh().positions();
    let tree = &surface.patches;
    for p in patches {
        if !tree.may_crease(p) {
            continue;
        }
        let patch = &tree.patches[p as usize];
        for c in &patch.edges {
            let [t0, t1] = c.triangles;
            let [v0, v1] = c.vertices;
            let (n0, n1) = (normals[t0 as usize], normals[t1 as usize]);
            // A zero normal (degenerate triangle) folds nothing.
            let fold = if n0 != Vec3::ZERO && n1 != Vec3::ZERO {
                n0.dot(n1)
            } else {
                1.0
            };
            let d = positions[v0 as usize] - positions[v1 as usize];
            let maybe_collapsed = d.length_squared() < c.collapse_below_sq;
            if fold >= 0.0 && !maybe_collapsed {
                continue;
            }
            let collapse = if maybe_collapsed && c.rest > 0.0 {
                d.length() / c.rest / COLLAPSED_FRACTION - 1.0
            } else {
                1.0
            };
            let sharpness = fold.min(collapse);
            if sharpness < 0.0
                && near_known.binary_search(&v0).is_err()
                && near_known.binary_search(&v1).is_err()
            {
                out.push((sharpness, c.edge, collapse < fold));
            }
        }
    }
}
