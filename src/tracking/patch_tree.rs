//! The "incomplete" hierarchy of Kimmerle et al.: a BVH cut off at patches of a few dozen
//! triangles, refitted every frame, whose overlapping patch pairs tell the sampler where
//! contacts can be.

use glam::{DMat3, DVec3, Vec3};

use super::boxes::boxes_meet;
use crate::bvh::{Bvh, BvhNode};
use crate::geometry::PoseF64;
use crate::mesh::{Topology, TriMesh};

/// An edge shorter than this fraction of its rest length is collapsed (squeezed along the
/// surface): a crease candidate like an edge folded past 90°.
pub(crate) const COLLAPSED_FRACTION: f32 = 0.3;

const NONE: u32 = u32::MAX;

/// An edge between two triangles, as a fold and collapse scan reads it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CreaseEdge {
    /// Topology edge index.
    pub edge: u32,
    /// Its first two triangles.
    pub triangles: [u32; 2],
    /// Its vertices.
    pub vertices: [u32; 2],
    /// Its rest length.
    pub rest: f32,
    /// `(COLLAPSED_FRACTION · rest)²`, enlarged by 1e-4 (a length below its square root may
    /// be collapsed).
    pub collapse_below_sq: f32,
}

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
    /// The patch's subtree root in [`PatchTree::bvh`].
    pub node: u32,
    /// Triangle indices.
    pub triangles: Vec<u32>,
    /// Distinct vertex indices of those triangles, ascending.
    pub vertices: Vec<u32>,
    /// Patches within two steps of patch adjacency (sharing a vertex with this one or with
    /// one of its neighbours), itself excluded, ascending. Pairs of these are skipped by the
    /// hierarchy sampler: random pairs there mostly slide along the sheet towards each other.
    pub near: Vec<u32>,
    /// Patches sharing a vertex with this one, itself excluded, ascending.
    pub adjacent: Vec<u32>,
    /// Edges between two triangles whose first triangle is in this patch, by first triangle
    /// (from [`PatchTree::assign_edges`]): the edges a fold or crease scan of this patch
    /// looks at.
    pub edges: Vec<CreaseEdge>,
    /// Whether one of [`Patch::edges`] may be collapsed (shorter than the square root of its
    /// [`CreaseEdge::collapse_below_sq`]), from [`PatchTree::update_cones`].
    pub collapsed: bool,
    /// How far its vertices have moved in all: the sum over
    /// [`TrackedSurface::set_positions`](super::TrackedSurface::set_positions) calls of the
    /// farthest move of one of them (at least how far any of them moved between two calls).
    pub travel: f64,
    /// Current box.
    pub min: Vec3,
    /// Current box.
    pub max: Vec3,
    /// Axis of the patch's normal cone (area-weighted mean normal), from
    /// [`PatchTree::update_cones`].
    pub cone_axis: Vec3,
    /// Cosine and sine of the normal cone's half-angle (a half-angle of π, cosine −1, when
    /// the normals cancel out).
    pub cone_cos: f32,
    /// See `cone_cos`.
    pub cone_sin: f32,
}

impl Patch {
    /// Its normal cone from the triangles' unit normals, and its [`Patch::collapsed`] flag
    /// from its edges at `positions`.
    fn update_cone(&mut self, triangle_normals: &[Vec3], positions: &[Vec3]) {
        let patch = self;
        patch.collapsed = patch.edges.iter().any(|c| {
            let [v0, v1] = c.vertices;
            (positions[v0 as usize] - positions[v1 as usize]).length_squared() < c.collapse_below_sq
        });
        let normals = patch
            .triangles
            .iter()
            .map(|&t| triangle_normals[t as usize]);
        let axis = normals.clone().sum::<Vec3>().normalize_or_zero();
        // Cosine of the largest angle between the axis and a triangle's normal.
        let mut cos = 1.0f32;
        if axis == Vec3::ZERO {
            cos = -1.0;
        } else {
            for n in normals {
                if n != Vec3::ZERO {
                    cos = cos.min(axis.dot(n));
                }
            }
        }
        patch.cone_axis = if axis == Vec3::ZERO { Vec3::Y } else { axis };
        patch.cone_cos = cos.clamp(-1.0, 1.0);
        patch.cone_sin = (1.0 - patch.cone_cos * patch.cone_cos).max(0.0).sqrt();
    }
}

/// A BVH cut off at patches of at most `patch_size` triangles (see the module docs).
#[derive(Debug, Clone)]
pub(crate) struct PatchTree {
    nodes: Vec<Node>,
    pub patches: Vec<Patch>,
    /// The patch of each triangle.
    pub patch_of: Vec<u32>,
    /// The full BVH below the cut (refitted with the patches), for random descents inside a
    /// patch pair down to leaves of a few triangles.
    pub bvh: Bvh,
    /// The BVH's nodes above the cut (ancestors of a patch's root), descending: children
    /// before parents.
    bvh_upper: Vec<u32>,
    /// Per patch, whether one of its vertices moved in the last [`PatchTree::add_travel`].
    moved: Vec<bool>,
    /// Scratch of [`PatchTree::refit_moved`].
    stack: Vec<u32>,
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
            patch_of: vec![0; mesh.triangle_count()],
            bvh: Bvh::build(&TriMesh::new(vec![Vec3::ZERO; 3], vec![[0, 1, 2]]).expect("valid")),
            bvh_upper: Vec::new(),
            moved: Vec::new(),
            stack: Vec::new(),
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
                for &t in &triangles {
                    tree.patch_of[t as usize] = tree.patches.len() as u32;
                }
                tree.nodes[new].patch = tree.patches.len() as u32;
                tree.patches.push(Patch {
                    node: old,
                    triangles,
                    vertices,
                    near: Vec::new(),
                    adjacent: Vec::new(),
                    edges: Vec::new(),
                    collapsed: false,
                    travel: 0.0,
                    min: n.min,
                    max: n.max,
                    cone_axis: Vec3::Y,
                    cone_cos: -1.0,
                    cone_sin: 0.0,
                });
            } else {
                tree.bvh_upper.push(old);
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
        for (p, nb) in neighbours.into_iter().enumerate() {
            tree.patches[p].adjacent = nb;
        }
        tree.bvh = bvh;
        tree.bvh_upper.sort_unstable_by(|a, b| b.cmp(a));
        tree.moved = vec![true; tree.patches.len()];
        tree.refit(mesh);
        tree
    }

    /// Recomputes every box from `mesh`'s current positions: the BVH below the cut (`O(n)`),
    /// whose patch roots give the patches' boxes, then the nodes above the cut.
    pub fn refit(&mut self, mesh: &TriMesh) {
        self.bvh.refit(mesh);
        self.refit_above_patches();
    }

    /// [`PatchTree::refit`] where the last [`PatchTree::add_travel`] saw a vertex move: the
    /// BVH below those patches, then everything above the cut (`O(patches)`). The same boxes
    /// as a full refit, since no box below a patch whose vertices all stayed can change.
    pub fn refit_moved(&mut self, mesh: &TriMesh) {
        for (patch, &moved) in self.patches.iter().zip(&self.moved) {
            if moved {
                self.bvh.refit_subtree(mesh, patch.node, &mut self.stack);
            }
        }
        self.bvh.refit_inner(&self.bvh_upper);
        self.refit_above_patches();
    }

    /// Whether more than half of the patches [moved](PatchTree::moved): then one pass over
    /// everything ([`PatchTree::refit`], [`PatchTree::update_cones`]) is quicker than one per
    /// moved patch.
    pub fn mostly_moved(&self) -> bool {
        2 * self.moved.iter().filter(|&&m| m).count() > self.patches.len()
    }

    /// Whether one of patch `p`'s vertices moved in the last [`PatchTree::add_travel`] (every
    /// patch before the first).
    pub fn moved(&self, p: usize) -> bool {
        self.moved[p]
    }

    /// The patches' boxes from their BVH roots, then the nodes above them.
    fn refit_above_patches(&mut self) {
        let bn = self.bvh.nodes();
        for patch in &mut self.patches {
            let n = &bn[patch.node as usize];
            (patch.min, patch.max) = (n.min, n.max);
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

    /// Adds to each patch's [`Patch::travel`] the farthest move of one of its vertices from
    /// `previous` to `current` positions (`O(vertices)`), and notes which patches had a vertex
    /// move at all ([`PatchTree::moved`]).
    pub fn add_travel(&mut self, previous: &[Vec3], current: &[Vec3]) {
        for (patch, moved) in self.patches.iter_mut().zip(&mut self.moved) {
            let mut farthest = 0.0f32;
            *moved = false;
            for &v in &patch.vertices {
                let (a, b) = (previous[v as usize], current[v as usize]);
                farthest = farthest.max(a.distance_squared(b));
                *moved |= a != b;
            }
            patch.travel += (farthest as f64).sqrt();
        }
    }

    /// Gives every edge between two triangles to the patch of its first triangle
    /// ([`Patch::edges`]), with its rest length from `rest_lengths` (per topology edge).
    pub fn assign_edges(&mut self, topology: &Topology, rest_lengths: &[f32]) {
        for patch in &mut self.patches {
            patch.edges.clear();
        }
        for (e, edge) in topology.edges().iter().enumerate() {
            if let [t0, t1, ..] = edge.triangles[..] {
                let p = self.patch_of[t0 as usize] as usize;
                let rest = rest_lengths[e];
                let limit = COLLAPSED_FRACTION * rest;
                self.patches[p].edges.push(CreaseEdge {
                    edge: e as u32,
                    triangles: [t0, t1],
                    vertices: edge.vertices,
                    rest,
                    collapse_below_sq: limit * limit * (1.0 + 1e-4),
                });
            }
        }
        for patch in &mut self.patches {
            patch.edges.sort_unstable_by_key(|c| (c.triangles, c.edge));
        }
    }

    /// Whether patch `p` may hold a folded edge (its two triangles' normals more than 90°
    /// apart) or a collapsed one: the patch is [`Patch::collapsed`], or its normal cone
    /// together with its own or an adjacent patch's is 45° wide or more (two normals in
    /// cones of half-angles θa and θb whose axes are φ apart are at most θa + θb + φ apart,
    /// so a fold across an edge of the patch needs θa + θb + φ ≥ 90°). Conservative by a
    /// small slack; [`PatchTree::update_cones`] must be current.
    pub fn may_crease(&self, p: u32) -> bool {
        const SLACK: f32 = 1e-3;
        let pa = &self.patches[p as usize];
        if pa.collapsed {
            return true;
        }
        let wide = |pb: &Patch| {
            // θa or θb ≥ 45°; else θa + θb < 90° and the test is cos(θa + θb) ≤ 0 or
            // cos φ ≤ sin(θa + θb).
            let half = std::f32::consts::FRAC_1_SQRT_2 + SLACK;
            if pa.cone_cos <= half || pb.cone_cos <= half {
                return true;
            }
            let cos_sum = pa.cone_cos * pb.cone_cos - pa.cone_sin * pb.cone_sin;
            let sin_sum = pa.cone_sin * pb.cone_cos + pa.cone_cos * pb.cone_sin;
            cos_sum <= SLACK || pa.cone_axis.dot(pb.cone_axis) <= sin_sum + SLACK
        };
        wide(pa) || pa.adjacent.iter().any(|&q| wide(&self.patches[q as usize]))
    }

    /// Recomputes every patch's normal cone from the triangles' unit normals, and its
    /// [`Patch::collapsed`] flag from its edges at `positions` (`O(triangles)`).
    pub fn update_cones(&mut self, triangle_normals: &[Vec3], positions: &[Vec3]) {
        for patch in &mut self.patches {
            patch.update_cone(triangle_normals, positions);
        }
    }

    /// [`PatchTree::update_cones`] for the patches that [moved](PatchTree::moved) only (the
    /// others' normals and edges are as they were).
    pub fn update_moved_cones(&mut self, triangle_normals: &[Vec3], positions: &[Vec3]) {
        for (patch, &moved) in self.patches.iter_mut().zip(&self.moved) {
            if moved {
                patch.update_cone(triangle_normals, positions);
            }
        }
    }

    /// Whether the surface of patches `a` and `b` (possibly the same) may fold enough to touch
    /// itself: their normals do not fit in an open hemisphere (the curvature criterion of
    /// Volino and Magnenat-Thalmann for self-collision).
    fn folds(&self, a: u32, b: u32) -> bool {
        let (pa, pb) = (&self.patches[a as usize], &self.patches[b as usize]);
        // The smallest cone holding both has half-angle max(θa, θb, (θa + θb + φ) / 2), φ the
        // angle between the axes; it reaches 90° (normals in no open hemisphere; exactly
        // opposite sheets, a flat fold, are at 90°) when θa or θb does, or when
        // φ ≥ π − θa − θb, that is cos φ ≤ −cos(θa + θb). Without trigonometry:
        const SLACK: f32 = 1e-3;
        if pa.cone_cos <= SLACK || pb.cone_cos <= SLACK {
            return true;
        }
        let cos_sum = pa.cone_cos * pb.cone_cos - pa.cone_sin * pb.cone_sin;
        pa.cone_axis.dot(pb.cone_axis) <= -cos_sum + SLACK
    }

    /// Candidate patch pairs for self-collision whose boxes come within `margin`, each once
    /// (`a <= b`), appended to `out`: patches far apart on the surface (not [`Patch::near`]
    /// each other), and patches that are the same or near each other but fold (their normals
    /// leave a half-space; [`PatchTree::update_cones`] must be current).
    #[cfg(test)]
    pub fn self_overlaps(
        &self,
        margin: f32,
        stack: &mut Vec<(u32, u32)>,
        out: &mut Vec<(u32, u32)>,
    ) {
        stack.clear();
        stack.push((0, 0));
        self.self_overlaps_from(margin, stack, out);
    }

    /// The candidate patch pairs for self-collision whose boxes come within `margin` (as
    /// `self_overlaps` finds them from the root, in the tests) below the node pairs on `stack`
    /// only (a node with itself: the pairs inside its subtree; two nodes: the pairs between
    /// their subtrees), appended to `out`; `stack` is emptied. The node pairs given need not
    /// meet.
    pub fn self_overlaps_from(
        &self,
        margin: f32,
        stack: &mut Vec<(u32, u32)>,
        out: &mut Vec<(u32, u32)>,
    ) {
        let overlap = |a: &Node, b: &Node| boxes_meet(a.min, a.max, b.min, b.max, margin);
        stack.retain(|&(i, j)| i == j || overlap(&self.nodes[i as usize], &self.nodes[j as usize]));
        while let Some((i, j)) = stack.pop() {
            let (ni, nj) = (&self.nodes[i as usize], &self.nodes[j as usize]);
            if i == j {
                if ni.patch != NONE && self.folds(ni.patch, ni.patch) {
                    out.push((ni.patch, ni.patch));
                }
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
                if self.patches[a as usize].near.binary_search(&b).is_err() || self.folds(a, b) {
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

    /// The roots of the subtrees the tree is cut into for [`KeptCandidates`]: the nodes at
    /// depth `depth` (and the patches above it), in breadth-first order.
    ///
    /// [`KeptCandidates`]: super::candidates::KeptCandidates
    pub fn block_roots(&self, depth: u32) -> Vec<u32> {
        let mut level = vec![0u32];
        let mut roots = Vec::new();
        for _ in 0..depth {
            let mut next = Vec::with_capacity(level.len() * 2);
            for &n in &level {
                let node = &self.nodes[n as usize];
                if node.patch != NONE {
                    roots.push(n);
                } else {
                    next.extend([node.left, node.left + 1]);
                }
            }
            level = next;
        }
        roots.extend(level);
        roots.sort_unstable();
        roots
    }

    /// Whether the boxes of nodes `a` and `b` come within `margin`.
    pub fn nodes_meet(&self, a: u32, b: u32, margin: f32) -> bool {
        let (na, nb) = (&self.nodes[a as usize], &self.nodes[b as usize]);
        boxes_meet(na.min, na.max, nb.min, nb.max, margin)
    }

    /// The patches below `node`, appended to `out`.
    pub fn patches_below(&self, node: u32, out: &mut Vec<u32>) {
        let n = &self.nodes[node as usize];
        if n.patch != NONE {
            out.push(n.patch);
        } else {
            self.patches_below(n.left, out);
            self.patches_below(n.left + 1, out);
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
        let xf = box_transform(rel);
        let overlap = |a: &Node, b: &Node| {
            let (lo, hi) = placed_box_of(b.min, b.max, Some(&xf));
            boxes_meet(a.min, a.max, lo, hi, margin)
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

/// The box `[min, max]`, moved by `rel` (bounds of the moved box) when given.
#[inline]
fn placed_box_of(min: Vec3, max: Vec3, rel: Option<&(DMat3, DMat3, DVec3)>) -> (Vec3, Vec3) {
    match rel {
        None => (min, max),
        Some((rot, abs, t)) => {
            let c = (min + max).as_dvec3() * 0.5;
            let h = (max - min).as_dvec3() * 0.5;
            let c = *rot * c + *t;
            let h = *abs * h + DVec3::splat(1e-6 * (c.abs().max_element() + h.max_element()));
            ((c - h).as_vec3(), (c + h).as_vec3())
        }
    }
}

/// The rotation, its absolute value and the translation of `rel`, for [`placed_box`].
pub(crate) fn box_transform(rel: &PoseF64) -> (DMat3, DMat3, DVec3) {
    let rot = DMat3::from_quat(rel.rotation);
    let abs = DMat3::from_cols(rot.x_axis.abs(), rot.y_axis.abs(), rot.z_axis.abs());
    (rot, abs, rel.translation)
}

/// A random walk from BVH nodes `a` (of `ta`) and `b` (of `tb`, placed by `rel`) down to a
/// pair of leaves whose boxes come within `margin`: at each step the larger node is split and
/// one of its children that still meets the other node is chosen at random. `None` when no
/// child meets it (the two subtrees are apart below the patch level). Same node on both sides
/// (self-collision inside one patch): the walk picks one of the child pairs.
pub(crate) fn random_leaf_pair(
    ta: &Bvh,
    tb: &Bvh,
    rel: Option<&(DMat3, DMat3, DVec3)>,
    mut a: u32,
    mut b: u32,
    margin: f32,
    rng: &mut impl rand::RngExt,
) -> Option<(u32, u32)> {
    let (na, nb) = (ta.nodes(), tb.nodes());
    let meets = |x: &BvhNode, y: &BvhNode| {
        let (lo, hi) = placed_box_of(y.min, y.max, rel);
        boxes_meet(x.min, x.max, lo, hi, margin)
    };
    loop {
        let (x, y) = (&na[a as usize], &nb[b as usize]);
        if x.is_leaf() && y.is_leaf() {
            return Some((a, b));
        }
        if rel.is_none() && a == b {
            let l = x.left();
            let mut options = [(l, l), (l + 1, l + 1), (l, l + 1)];
            let n = if meets(&na[l as usize], &na[l as usize + 1]) {
                3
            } else {
                2
            };
            options.swap(0, rng.random_range(0..n));
            (a, b) = options[0];
            continue;
        }
        let split_a = !x.is_leaf()
            && (y.is_leaf() || (x.max - x.min).element_sum() >= (y.max - y.min).element_sum());
        let mut next: [u32; 2] = [0; 2];
        let mut count = 0;
        if split_a {
            for c in [x.left(), x.left() + 1] {
                if meets(&na[c as usize], y) {
                    next[count] = c;
                    count += 1;
                }
            }
        } else {
            for c in [y.left(), y.left() + 1] {
                if meets(x, &nb[c as usize]) {
                    next[count] = c;
                    count += 1;
                }
            }
        }
        if count == 0 {
            return None;
        }
        let pick = next[rng.random_range(0..count)];
        if split_a { a = pick } else { b = pick }
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

    fn normals_of(mesh: &TriMesh) -> Vec<Vec3> {
        (0..mesh.triangle_count())
            .map(|t| {
                let [a, b, c] = mesh.triangle(t);
                (b - a).cross(c - a).normalize_or_zero()
            })
            .collect()
    }

    /// `may_crease` against the angles: two adjacent patches with cones of half-angles θa,
    /// θb whose axes are φ apart may hold two normals more than 90° apart exactly when
    /// θa + θb + φ > 90° (or either cone alone is wider than 45°); checked over a grid of
    /// angles up to a half turn, away from the boundary.
    #[test]
    fn may_crease_follows_the_cone_angles() {
        let sheet = generate::cloth_grid(1.0, 1.0, 2, 1);
        let mut tree = PatchTree::new(&sheet, 2);
        assert_eq!(tree.patches.len(), 2);
        assert!(tree.patches[0].adjacent.contains(&1));
        let steps: Vec<f32> = (0..=18).map(|k| k as f32 * 10f32.to_radians()).collect();
        let mut checked = 0;
        for &ta in &steps {
            for &tb in &steps {
                for &phi in &steps {
                    let set = |p: &mut Patch, theta: f32, axis: Vec3| {
                        p.cone_axis = axis;
                        p.cone_cos = theta.cos();
                        p.cone_sin = theta.sin();
                        p.collapsed = false;
                    };
                    set(&mut tree.patches[0], ta, Vec3::Y);
                    let axis_b = glam::Quat::from_rotation_x(phi) * Vec3::Y;
                    set(&mut tree.patches[1], tb, axis_b);
                    // The widest angle between two normals of the two cones (or of one).
                    let widest = (ta + tb + phi).max(2.0 * ta).max(2.0 * tb);
                    let margin = 2f32.to_radians();
                    if (widest - std::f32::consts::FRAC_PI_2).abs() < margin {
                        continue;
                    }
                    let expected = widest > std::f32::consts::FRAC_PI_2;
                    assert_eq!(tree.may_crease(0), expected, "θa {ta} θb {tb} φ {phi}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 5000);
        tree.patches[0].collapsed = true;
        assert!(tree.may_crease(0));
    }

    #[test]
    fn patches_partition_the_triangles_and_boxes_contain_them() {
        let mesh = generate::torus(1.0, 0.3, 48, 24);
        let mut tree = PatchTree::new(&mesh, 32);
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
        tree.update_cones(&normals_of(&mesh), mesh.positions());
        tree.self_overlaps(0.0, &mut stack, &mut out);
        for &(a, b) in &out {
            let (pa, pb) = (&tree.patches[a as usize], &tree.patches[b as usize]);
            assert!(pa.min.cmple(pb.max).all() && pb.min.cmple(pa.max).all());
            assert!(pa.near.binary_search(&b).is_err() || tree.folds(a, b));
        }
        // A flat sheet never folds; one folded in half does, where it folds.
        let sheet = generate::cloth_grid(1.0, 1.0, 16, 16);
        let mut tree = PatchTree::new(&sheet, 16);
        tree.update_cones(&normals_of(&sheet), sheet.positions());
        assert!(tree.patches.iter().all(|p| p.cone_cos > 1.0 - 1e-6));
        out.clear();
        tree.self_overlaps(0.0, &mut stack, &mut out);
        assert!(
            out.is_empty(),
            "a flat sheet has no candidate pairs: {out:?}"
        );
        let folded: Vec<Vec3> = sheet
            .positions()
            .iter()
            .map(|p| {
                if p.x > 0.0 {
                    Vec3::new(-p.x, 0.01, p.z)
                } else {
                    *p
                }
            })
            .collect();
        let moved = TriMesh::new(folded, sheet.triangles().to_vec()).unwrap();
        tree.refit(&moved);
        tree.update_cones(&normals_of(&moved), moved.positions());
        out.clear();
        tree.self_overlaps(0.02, &mut stack, &mut out);
        // The folded half lies over the flat one (far pairs), and the patches at the crease
        // fold (near pairs or a patch with itself).
        let near = |&(a, b): &(u32, u32)| {
            a == b || tree.patches[a as usize].near.binary_search(&b).is_ok()
        };
        assert!(out.iter().any(near), "{out:?}");
        assert!(out.iter().any(|p| !near(p)), "{out:?}");
    }
}
