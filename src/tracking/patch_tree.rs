//! The "incomplete" hierarchy of Kimmerle et al.: a BVH cut off at patches of a few dozen
//! triangles, refitted every frame, whose overlapping patch pairs tell the sampler where
//! contacts can be.

use glam::{DMat3, DVec3, Vec3};

use crate::bvh::Bvh;
use crate::geometry::PoseF64;
use crate::mesh::TriMesh;

const NONE: u32 = u32::MAX;

/// A node of the cut tree: inner (two children) or a patch.
#[derive(Debug, Clone, Copy)]
struct Node {
    min: Vec3,
    max: Vec3,
    /// Inner: left child (right is `left + 1`); patch node: [`NONE`].
    left: u32,
    /// Patch node: the patch id; inner: [`NONE`].
    patch: u32,
}

/// A patch: a set of triangles contiguous in the mesh's BVH, with its vertices.
#[derive(Debug, Clone)]
pub(crate) struct Patch {
    /// Triangle indices.
    pub triangles: Vec<u32>,
    /// Distinct vertex indices of those triangles, ascending.
    pub vertices: Vec<u32>,
    /// Patches within two steps of patch adjacency (sharing a vertex with this one or with
    /// one of its neighbours), itself excluded, ascending. Pairs of these are skipped by the
    /// hierarchy sampler: random pairs there mostly slide along the sheet towards each other.
    pub near: Vec<u32>,
    /// Current box.
    pub min: Vec3,
    /// Current box.
    pub max: Vec3,
}

/// A BVH cut off at patches of at most `patch_size` triangles (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct PatchTree {
    nodes: Vec<Node>,
    pub patches: Vec<Patch>,
}

impl PatchTree {
    /// Builds the tree over `mesh` (a binned-SAH BVH, cut at subtrees of at most `patch_size`
    /// triangles).
    pub fn new(mesh: &TriMesh, patch_size: u32) -> Self {
        let bvh = Bvh::build(mesh);
        let bn = bvh.nodes();
        // Triangles under each BVH node (children come after parents: reverse sweep).
        let mut count = vec![0u32; bn.len()];
        for i in (0..bn.len()).rev() {
            count[i] = if bn[i].is_leaf() {
                bn[i].count
            } else {
                count[bn[i].left() as usize] + count[bn[i].left() as usize + 1]
            };
        }
        let mut tree = PatchTree {
            nodes: Vec::new(),
            patches: Vec::new(),
        };
        // Breadth-first copy so that siblings are adjacent and children follow parents.
        tree.nodes.push(Node {
            min: Vec3::ZERO,
            max: Vec3::ZERO,
            left: NONE,
            patch: NONE,
        });
        let mut queue = std::collections::VecDeque::from([(0usize, 0u32)]);
        while let Some((new, old)) = queue.pop_front() {
            let n = &bn[old as usize];
            if n.is_leaf() || count[old as usize] <= patch_size.max(1) {
                let mut triangles = Vec::new();
                collect(&bvh, old, &mut triangles);
                let mut vertices: Vec<u32> = triangles
                    .iter()
                    .flat_map(|&t| mesh.triangles()[t as usize])
                    .collect();
                vertices.sort_unstable();
                vertices.dedup();
                tree.nodes[new].patch = tree.patches.len() as u32;
                tree.patches.push(Patch {
                    triangles,
                    vertices,
                    near: Vec::new(),
                    min: n.min,
                    max: n.max,
                });
            } else {
                let left = tree.nodes.len() as u32;
                tree.nodes[new].left = left;
                for c in 0..2 {
                    tree.nodes.push(Node {
                        min: Vec3::ZERO,
                        max: Vec3::ZERO,
                        left: NONE,
                        patch: NONE,
                    });
                    queue.push_back((left as usize + c, n.left() + c as u32));
                }
            }
        }
        // Patch adjacency through shared vertices.
        let mut owners: Vec<Vec<u32>> = vec![Vec::new(); mesh.vertex_count()];
        for (p, patch) in tree.patches.iter().enumerate() {
            for &v in &patch.vertices {
                owners[v as usize].push(p as u32);
            }
        }
        let neighbours: Vec<Vec<u32>> = (0..tree.patches.len())
            .map(|p| {
                let mut nb: Vec<u32> = tree.patches[p]
                    .vertices
                    .iter()
                    .flat_map(|&v| owners[v as usize].iter().copied())
                    .filter(|&q| q != p as u32)
                    .collect();
                nb.sort_unstable();
                nb.dedup();
                nb
            })
            .collect();
        for (p, nb) in neighbours.iter().enumerate() {
            let mut near: Vec<u32> = nb
                .iter()
                .flat_map(|&q| std::iter::once(q).chain(neighbours[q as usize].iter().copied()))
                .filter(|&q| q != p as u32)
                .collect();
            near.sort_unstable();
            near.dedup();
            tree.patches[p].near = near;
        }
        tree.refit(mesh.positions());
        tree
    }

    /// Recomputes every box from `positions`: patches from their vertices, then the inner
    /// nodes bottom-up. `O(vertices)`.
    pub fn refit(&mut self, positions: &[Vec3]) {
        for patch in &mut self.patches {
            let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            for &v in &patch.vertices {
                let p = positions[v as usize];
                lo = lo.min(p);
                hi = hi.max(p);
            }
            (patch.min, patch.max) = (lo, hi);
        }
        for i in (0..self.nodes.len()).rev() {
            let n = self.nodes[i];
            let (lo, hi) = if n.patch != NONE {
                let p = &self.patches[n.patch as usize];
                (p.min, p.max)
            } else {
                let (l, r) = (
                    &self.nodes[n.left as usize],
                    &self.nodes[n.left as usize + 1],
                );
                (l.min.min(r.min), l.max.max(r.max))
            };
            self.nodes[i].min = lo;
            self.nodes[i].max = hi;
        }
    }

    /// Pairs of patches, not [`Patch::near`] each other, whose boxes come within `margin`, each once
    /// (`a < b`), appended to `out`.
    pub fn self_overlaps(
        &self,
        margin: f32,
        stack: &mut Vec<(u32, u32)>,
        out: &mut Vec<(u32, u32)>,
    ) {
        let overlap = |a: &Node, b: &Node| {
            (a.min - margin).cmple(b.max).all() && b.min.cmple(a.max + margin).all()
        };
        stack.clear();
        stack.push((0, 0));
        while let Some((i, j)) = stack.pop() {
            let (ni, nj) = (&self.nodes[i as usize], &self.nodes[j as usize]);
            if i == j {
                if ni.patch == NONE {
                    let l = ni.left;
                    stack.push((l, l));
                    stack.push((l + 1, l + 1));
                    if overlap(&self.nodes[l as usize], &self.nodes[l as usize + 1]) {
                        stack.push((l, l + 1));
                    }
                }
                continue;
            }
            if ni.patch != NONE && nj.patch != NONE {
                let (a, b) = (ni.patch.min(nj.patch), ni.patch.max(nj.patch));
                if self.patches[a as usize].near.binary_search(&b).is_err() {
                    out.push((a, b));
                }
                continue;
            }
            let split_i = ni.patch == NONE
                && (nj.patch != NONE
                    || (ni.max - ni.min).element_sum() >= (nj.max - nj.min).element_sum());
            let (keep, split) = if split_i { (j, ni) } else { (i, nj) };
            for c in [split.left, split.left + 1] {
                if overlap(&self.nodes[c as usize], &self.nodes[keep as usize]) {
                    stack.push(if split_i { (c, keep) } else { (keep, c) });
                }
            }
        }
    }

    /// Pairs of patches (`self`'s, `other`'s) whose boxes come within `margin`, with `other`
    /// placed by `rel` in `self`'s frame (its boxes are the transformed boxes' bounds).
    pub fn pair_overlaps(
        &self,
        other: &PatchTree,
        rel: &PoseF64,
        margin: f32,
        stack: &mut Vec<(u32, u32)>,
        out: &mut Vec<(u32, u32)>,
    ) {
        let rot = DMat3::from_quat(rel.rotation);
        let abs = DMat3::from_cols(rot.x_axis.abs(), rot.y_axis.abs(), rot.z_axis.abs());
        let moved = |n: &Node| -> (Vec3, Vec3) {
            let c = (n.min + n.max).as_dvec3() * 0.5;
            let h = (n.max - n.min).as_dvec3() * 0.5;
            let c = rot * c + rel.translation;
            let h = abs * h + DVec3::splat(1e-6 * (c.abs().max_element() + h.max_element()));
            ((c - h).as_vec3(), (c + h).as_vec3())
        };
        let overlap = |a: &Node, b: &Node| {
            let (lo, hi) = moved(b);
            (a.min - margin).cmple(hi).all() && lo.cmple(a.max + margin).all()
        };
        stack.clear();
        if overlap(&self.nodes[0], &other.nodes[0]) {
            stack.push((0, 0));
        }
        while let Some((i, j)) = stack.pop() {
            let (ni, nj) = (&self.nodes[i as usize], &other.nodes[j as usize]);
            if ni.patch != NONE && nj.patch != NONE {
                out.push((ni.patch, nj.patch));
                continue;
            }
            let split_i = ni.patch == NONE
                && (nj.patch != NONE
                    || (ni.max - ni.min).element_sum() >= (nj.max - nj.min).element_sum());
            if split_i {
                for c in [ni.left, ni.left + 1] {
                    if overlap(&self.nodes[c as usize], nj) {
                        stack.push((c, j));
                    }
                }
            } else {
                for c in [nj.left, nj.left + 1] {
                    if overlap(ni, &other.nodes[c as usize]) {
                        stack.push((i, c));
                    }
                }
            }
        }
    }
}

fn collect(bvh: &Bvh, node: u32, out: &mut Vec<u32>) {
    let n = &bvh.nodes()[node as usize];
    if n.is_leaf() {
        out.extend_from_slice(bvh.triangles_of(n));
    } else {
        collect(bvh, n.left(), out);
        collect(bvh, n.left() + 1, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn patches_partition_the_triangles_and_boxes_contain_them() {
        let mesh = generate::torus(1.0, 0.3, 48, 24);
        let tree = PatchTree::new(&mesh, 32);
        let mut seen = vec![0u32; mesh.triangle_count()];
        for p in &tree.patches {
            assert!(p.triangles.len() <= 32 && !p.triangles.is_empty());
            for &t in &p.triangles {
                seen[t as usize] += 1;
                for q in mesh.triangle(t as usize) {
                    assert!(q.cmpge(p.min).all() && q.cmple(p.max).all());
                }
            }
        }
        assert!(seen.iter().all(|&c| c == 1));
        // A closed torus: no two non-adjacent patches of the rest shape overlap much, but
        // far-apart patches never appear as overlapping without their boxes touching.
        let (mut stack, mut out) = (Vec::new(), Vec::new());
        tree.self_overlaps(0.0, &mut stack, &mut out);
        for &(a, b) in &out {
            let (pa, pb) = (&tree.patches[a as usize], &tree.patches[b as usize]);
            assert!(pa.min.cmple(pb.max).all() && pb.min.cmple(pa.max).all());
            assert!(pa.near.binary_search(&b).is_err());
        }
    }
}
