//! Self-intersection of one mesh: the tree descended against itself.
use super::collision_mesh::CollisionMesh;
use super::tree::BvhNode;
use super::workspace::{QueryWorkspace, TrianglePair, triangle_f64};
use crate::geometry::triangles_intersect;

/// All pairs of non-adjacent triangles of `mesh` that intersect or touch, appended to `out`
/// (each pair once, `a < b`); returns how many were appended.
///
/// Triangles sharing a vertex index are adjacent and excluded (they touch by construction).
/// Triangles that merely have corners at the same position (unwelded seams) are not adjacent,
/// so an unwelded mesh reports its seams.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::bvh::self_intersections;
/// let ball = CollisionMesh::new(generate::icosphere(1.0, 2));
/// let mut pairs = Vec::new();
/// assert_eq!(self_intersections(&ball, &mut QueryWorkspace::new(), &mut pairs), 0);
/// ```
pub fn self_intersections(
    mesh: &CollisionMesh,
    ws: &mut QueryWorkspace,
    out: &mut Vec<TrianglePair>,
) -> usize {
    let before = out.len();
    descend_self(mesh, ws, |pair| {
        out.push(pair);
        false
    });
    out.len() - before
}

/// Whether any two non-adjacent triangles of `mesh` intersect or touch (stops at the first).
pub fn self_intersects(mesh: &CollisionMesh, ws: &mut QueryWorkspace) -> bool {
    let mut hit = false;
    descend_self(mesh, ws, |_| {
        hit = true;
        true
    });
    hit
}

fn overlap(a: &BvhNode, b: &BvhNode) -> bool {
    a.min.cmple(b.max).all() && b.min.cmple(a.max).all()
}

/// Descends node pairs `(i, j)`; `on_hit` returns `true` to stop.
fn descend_self(
    mesh: &CollisionMesh,
    ws: &mut QueryWorkspace,
    mut on_hit: impl FnMut(TrianglePair) -> bool,
) {
    let bvh = mesh.bvh();
    let nodes = bvh.nodes();
    let (pos, tris) = (mesh.mesh().positions(), mesh.mesh().triangles());
    let mut test = |t: u32, u: u32| -> bool {
        let (ta, tb) = (tris[t as usize], tris[u as usize]);
        if ta.iter().any(|v| tb.contains(v)) {
            return false;
        }
        if triangles_intersect(&triangle_f64(ta, pos), &triangle_f64(tb, pos)) {
            return on_hit(TrianglePair {
                a: t.min(u),
                b: t.max(u),
            });
        }
        false
    };
    ws.stack.clear();
    ws.stack.push((0, 0));
    ws.node_pairs_visited = 1;
    while let Some((i, j)) = ws.stack.pop() {
        let (ni, nj) = (&nodes[i as usize], &nodes[j as usize]);
        if i == j {
            if ni.is_leaf() {
                let ts = bvh.triangles_of(ni);
                for (k, &t) in ts.iter().enumerate() {
                    for &u in &ts[k + 1..] {
                        if test(t, u) {
                            return;
                        }
                    }
                }
            } else {
                let l = ni.left();
                ws.stack.push((l, l));
                ws.stack.push((l + 1, l + 1));
                ws.node_pairs_visited += 1;
                if overlap(&nodes[l as usize], &nodes[l as usize + 1]) {
                    ws.stack.push((l, l + 1));
                }
            }
            continue;
        }
        if ni.is_leaf() && nj.is_leaf() {
            for &t in bvh.triangles_of(ni) {
                for &u in bvh.triangles_of(nj) {
                    if test(t, u) {
                        return;
                    }
                }
            }
            continue;
        }
        let split_i = !ni.is_leaf()
            && (nj.is_leaf() || (ni.max - ni.min).element_sum() >= (nj.max - nj.min).element_sum());
        let (keep, split) = if split_i { (j, ni) } else { (i, nj) };
        let l = split.left();
        for c in [l, l + 1] {
            ws.node_pairs_visited += 1;
            let other = &nodes[keep as usize];
            if overlap(&nodes[c as usize], other) {
                ws.stack.push(if split_i { (c, keep) } else { (keep, c) });
            }
        }
    }
}
