//! The ADB-tree: a [`CollisionMesh`]'s BVH augmented per node with the count of well-filled
//! cells, the node's depth and the shape data the probability model needs.
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;

use super::calibration::{Calibration, ConfidenceCalibration};
use super::cells::{CellGrid, CellScratch, count_well_filled};
use super::interior::InteriorMap;
use super::options::AdbBuildOptions;
use crate::bvh::CollisionMesh;
use crate::bvh::box_test::{FirstBox, RelativeFrame, SecondBox};
use crate::geometry::Aabb;

/// Progress of a build, reported to the callback of [`AdbTree::build_with_progress`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AdbBuildProgress {
    /// Nodes whose cells are counted.
    pub nodes_done: usize,
    /// Nodes in the tree.
    pub nodes_total: usize,
}

/// What the ADB traversal knows of one BVH node (same index as the node).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdbNode {
    /// Number of well-filled ("possible collision") cells of the node's grid: cells where the
    /// area of all triangles in or crossing the node, clipped to the cell, reaches MaxArea.
    pub well_filled: u16,
    /// Depth of the node (the root is 0).
    pub depth: u16,
    /// Side lengths of the node's box, largest first.
    pub sides: [f32; 3],
    /// How flat the node's surface is: |Σ area·normal| / Σ area over the node's triangles, in
    /// `[0, 1]` (1 for a planar patch, near 0 for a closed or strongly curved one).
    pub planarity: f32,
    /// Area-weighted mean normal of the node's triangles (zero when they cancel out).
    pub normal: Vec3,
    /// The slab `{p : slab[0] ≤ normal·p ≤ slab[1]}` that holds every triangle of the node
    /// (infinite when the normal is zero, or when the tree was built without slabs:
    /// [`AdbBuildOptions::normal_slabs`]): with the box, a tighter bounding volume, thin for
    /// nearly flat patches, so near misses between flat patches are culled exactly.
    pub slab: [f32; 2],
}

impl AdbNode {
    /// The slab as `(normal, lo, hi)`, the form the box tests take.
    #[inline]
    fn slab_plane(&self) -> (Vec3, f32, f32) {
        (self.normal, self.slab[0], self.slab[1])
    }
}

/// An ADB-tree (Klein & Zachmann 2003): a [`CollisionMesh`] whose BVH nodes also carry a tiny
/// description of the triangle distribution inside them ([`AdbNode`]), so that the
/// probability that two nodes contain intersecting triangles can be estimated without
/// touching a triangle. Built once per mesh (in parallel); share it (e.g. in an `Arc`) among
/// all rigid instances of that mesh.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::adb::AdbTree;
/// let tree = AdbTree::new(CollisionMesh::new(generate::icosphere(1.0, 3)));
/// assert_eq!(tree.nodes().len(), tree.collision_mesh().bvh().nodes().len());
/// assert!(tree.nodes()[0].well_filled > 0);
/// ```
#[derive(Debug, Clone)]
pub struct AdbTree {
    mesh: CollisionMesh,
    nodes: Vec<AdbNode>,
    max_depth: u32,
    resolution: u32,
    /// Set by the build's fit ([`AdbBuildOptions::fit`]).
    pub(super) calibration: Option<Calibration>,
    /// Set by the build ([`AdbBuildOptions::interior_resolution`]).
    pub(super) interior: Option<InteriorMap>,
    /// Set by the build's confidence fit ([`AdbBuildOptions::confidence_fit`]).
    pub(super) confidence_calibration: Option<ConfidenceCalibration>,
    options: AdbBuildOptions,
}

impl AdbTree {
    /// The tree's per-node data (cell counts, depths, shapes, slabs), without an interior map
    /// or fits: what [`AdbTree::build_with_progress`] starts from.
    pub(super) fn with_nodes(
        mesh: CollisionMesh,
        options: AdbBuildOptions,
        progress: &(dyn Fn(AdbBuildProgress) + Sync),
    ) -> Self {
        let resolution = options.resolution.clamp(1, 8);
        let bvh = mesh.bvh();
        let n = bvh.nodes().len();
        let (depths, max_depth) = node_depths(bvh.nodes());
        let (normals, areas) = normal_sums(&mesh);
        let counts = count_cells(
            &mesh,
            resolution,
            options.fill_fraction,
            options.threads,
            progress,
        );
        let mut nodes: Vec<AdbNode> = (0..n)
            .map(|i| {
                let node = &bvh.nodes()[i];
                let mut sides = (node.max - node.min).to_array();
                sides.sort_by(|a, b| b.total_cmp(a));
                let normal_sum = normals[i];
                let len = normal_sum.length();
                AdbNode {
                    well_filled: counts[i],
                    depth: depths[i],
                    sides,
                    planarity: if areas[i] > 0.0 {
                        (len / areas[i]).clamp(0.0, 1.0)
                    } else {
                        0.0
                    },
                    normal: if len > 0.0 {
                        normal_sum / len
                    } else {
                        Vec3::ZERO
                    },
                    slab: [f32::NEG_INFINITY, f32::INFINITY],
                }
            })
            .collect();
        if options.normal_slabs {
            node_slabs(&mesh, &mut nodes);
        }
        Self {
            mesh,
            nodes,
            max_depth,
            resolution,
            calibration: None,
            interior: None,
            confidence_calibration: None,
            options,
        }
    }

    /// The options it was built with.
    #[inline]
    pub fn options(&self) -> &AdbBuildOptions {
        &self.options
    }

    /// The calibration fitted on this mesh at build time, if any.
    #[inline]
    pub fn calibration(&self) -> Option<&Calibration> {
        self.calibration.as_ref()
    }

    /// The map of the mesh's inside and outside, with its surface samples (`None` when built
    /// with `interior_resolution` 0).
    #[inline]
    pub fn interior(&self) -> Option<&InteriorMap> {
        self.interior.as_ref()
    }

    /// The calibration of the confidence of answers a failed interpenetration certificate left
    /// unsettled, fitted at build time (with a fit and an interior map), if any.
    #[inline]
    pub fn confidence_calibration(&self) -> Option<&ConfidenceCalibration> {
        self.confidence_calibration.as_ref()
    }

    /// The mesh and its BVH.
    #[inline]
    pub fn collision_mesh(&self) -> &CollisionMesh {
        &self.mesh
    }

    /// Per-node data, indexed like [`crate::bvh::Bvh::nodes`].
    #[inline]
    pub fn nodes(&self) -> &[AdbNode] {
        &self.nodes
    }

    /// Depth of the deepest node (the root is 0).
    #[inline]
    pub fn max_depth(&self) -> u32 {
        self.max_depth
    }

    /// Cells per axis of every node's grid.
    #[inline]
    pub fn resolution(&self) -> u32 {
        self.resolution
    }

    /// Cells per node (`resolution³`).
    #[inline]
    pub fn cells_per_node(&self) -> u32 {
        self.resolution.pow(3)
    }

    /// Bytes held beyond the [`CollisionMesh`].
    pub fn extra_memory_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<AdbNode>()
            + self.interior.as_ref().map_or(0, InteriorMap::memory_bytes)
    }
}

/// Depth of every node and the maximum depth (children always follow their parent).
fn node_depths(nodes: &[crate::bvh::BvhNode]) -> (Vec<u16>, u32) {
    let mut depth = vec![0u16; nodes.len()];
    for (i, node) in nodes.iter().enumerate() {
        if !node.is_leaf() {
            let l = node.left() as usize;
            depth[l] = depth[i].saturating_add(1);
            depth[l + 1] = depth[i].saturating_add(1);
        }
    }
    let max = depth.iter().copied().max().unwrap_or(0);
    (depth, u32::from(max))
}

/// Per node: Σ area-weighted normals (twice the vector area) and Σ areas of its subtree.
fn normal_sums(mesh: &CollisionMesh) -> (Vec<Vec3>, Vec<f32>) {
    let bvh = mesh.bvh();
    let nodes = bvh.nodes();
    let mut normals = vec![Vec3::ZERO; nodes.len()];
    let mut areas = vec![0.0f32; nodes.len()];
    for i in (0..nodes.len()).rev() {
        let node = &nodes[i];
        if node.is_leaf() {
            for &t in bvh.triangles_of(node) {
                let [a, b, c] = mesh.mesh().triangle(t as usize);
                let n = (b - a).cross(c - a) * 0.5;
                normals[i] += n;
                areas[i] += n.length();
            }
        } else {
            let l = node.left() as usize;
            normals[i] = normals[l] + normals[l + 1];
            areas[i] = areas[l] + areas[l + 1];
        }
    }
    (normals, areas)
}

/// The slab of every node along its mean normal: the extent of its vertices' projections,
/// computed in `f64` and rounded outwards. Each subtree covers a contiguous range of the
/// tree's leaf triangles.
fn node_slabs(mesh: &CollisionMesh, nodes: &mut [AdbNode]) {
    let bvh = mesh.bvh();
    let tree = bvh.nodes();
    let mut ranges = vec![(0u32, 0u32); tree.len()];
    for i in (0..tree.len()).rev() {
        let n = &tree[i];
        ranges[i] = if n.is_leaf() {
            (n.first, n.first + n.count)
        } else {
            let l = n.left() as usize;
            (ranges[l].0, ranges[l + 1].1)
        };
    }
    for (i, node) in nodes.iter_mut().enumerate() {
        if node.normal == Vec3::ZERO {
            continue;
        }
        let n = node.normal.as_dvec3();
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let (start, end) = ranges[i];
        for &t in &bvh.leaf_triangles()[start as usize..end as usize] {
            for p in mesh.mesh().triangle(t as usize) {
                let d = n.dot(p.as_dvec3());
                lo = lo.min(d);
                hi = hi.max(d);
            }
        }
        // Round outwards so the f32 slab still holds every vertex.
        node.slab = [(lo as f32).next_down(), (hi as f32).next_up()];
    }
}

/// Whether nodes `ia` of `a` and `ib` of `b` may overlap: their boxes (six face axes) and each
/// one's slab against the other's box. Conservative: never false for touching triangles.
#[inline]
pub(crate) fn nodes_overlap(
    a: &AdbTree,
    b: &AdbTree,
    frame: &RelativeFrame,
    ia: u32,
    ib: u32,
) -> bool {
    overlap_distance(a, b, frame, ia, ib).is_some()
}

/// [`nodes_overlap`], and if they may overlap, the distance between the two boxes' centres
/// (what the probability model needs), from the same transforms.
#[inline]
pub(crate) fn overlap_distance(
    a: &AdbTree,
    b: &AdbTree,
    frame: &RelativeFrame,
    ia: u32,
    ib: u32,
) -> Option<f32> {
    let (first, second) = (prepare_first(a, frame, ia), prepare_second(b, frame, ib));
    frame
        .overlap_prepared(&first, &second)
        .map(|o| o.center_distance)
}

/// Node `ia` of the first tree with its slab, prepared for box and slab tests
/// against several nodes of the second (`RelativeFrame::overlap_prepared`).
#[inline]
pub(crate) fn prepare_first(a: &AdbTree, frame: &RelativeFrame, ia: u32) -> FirstBox {
    let box_ = &a.collision_mesh().bvh().nodes()[ia as usize];
    frame.prepare_first(box_, a.nodes()[ia as usize].slab_plane())
}

/// Node `ib` of the second tree with its slab, prepared for box and slab tests
/// against several nodes of the first (`RelativeFrame::overlap_prepared`).
#[inline]
pub(crate) fn prepare_second(b: &AdbTree, frame: &RelativeFrame, ib: u32) -> SecondBox {
    let box_ = &b.collision_mesh().bvh().nodes()[ib as usize];
    frame.prepare_second(box_, b.nodes()[ib as usize].slab_plane())
}

/// Well-filled cell count of every node, over all triangles in or crossing its box.
/// Nodes are handed out in small chunks to the worker threads (the root and upper nodes see
/// many triangles, leaves few); each node's count is independent, so the result does not
/// depend on the thread count.
fn count_cells(
    mesh: &CollisionMesh,
    resolution: u32,
    fill_fraction: f32,
    threads: usize,
    progress: &(dyn Fn(AdbBuildProgress) + Sync),
) -> Vec<u16> {
    let n = mesh.bvh().nodes().len();
    let threads = if threads == 0 {
        std::thread::available_parallelism().map_or(1, |c| c.get())
    } else {
        threads
    }
    .clamp(1, 64);
    const CHUNK: usize = 16;
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let work = || {
        let mut out: Vec<(usize, u16)> = Vec::new();
        let mut scratch = CellScratch::default();
        let mut candidates: Vec<u32> = Vec::new();
        let mut stack: Vec<u32> = Vec::new();
        loop {
            let start = next.fetch_add(CHUNK, Ordering::Relaxed);
            if start >= n {
                break;
            }
            let end = (start + CHUNK).min(n);
            for i in start..end {
                let bounds = mesh.bvh().nodes()[i].aabb();
                triangles_touching(mesh, &bounds, &mut stack, &mut candidates);
                let grid =
                    CellGrid::new(bounds, resolution).with_fill_fraction(f64::from(fill_fraction));
                let tris = candidates.iter().map(|&t| mesh.mesh().triangle(t as usize));
                let count = count_well_filled(&grid, tris, &mut scratch);
                out.push((i, count.min(u32::from(u16::MAX)) as u16));
            }
            let finished = done.fetch_add(end - start, Ordering::Relaxed) + (end - start);
            progress(AdbBuildProgress {
                nodes_done: finished,
                nodes_total: n,
            });
        }
        out
    };
    let parts: Vec<Vec<(usize, u16)>> = if threads == 1 || n < 256 {
        vec![work()]
    } else {
        std::thread::scope(|s| {
            let handles: Vec<_> = (1..threads).map(|_| s.spawn(work)).collect();
            let mut parts = vec![work()];
            parts.extend(
                handles
                    .into_iter()
                    .map(|h| h.join().expect("ADB build thread panicked")),
            );
            parts
        })
    };
    let mut counts = vec![0u16; n];
    for (i, c) in parts.into_iter().flatten() {
        counts[i] = c;
    }
    counts
}

/// Indices of the triangles whose boxes touch `bounds` (the candidates for P(node); clipping
/// then gives zero area to those that only graze it).
fn triangles_touching(
    mesh: &CollisionMesh,
    bounds: &Aabb,
    stack: &mut Vec<u32>,
    out: &mut Vec<u32>,
) {
    let bvh = mesh.bvh();
    out.clear();
    stack.clear();
    stack.push(0);
    while let Some(i) = stack.pop() {
        let node = &bvh.nodes()[i as usize];
        if !node.aabb().intersects(bounds) {
            continue;
        }
        if node.is_leaf() {
            for &t in bvh.triangles_of(node) {
                if Aabb::from_points(mesh.mesh().triangle(t as usize)).intersects(bounds) {
                    out.push(t);
                }
            }
        } else {
            stack.push(node.left());
            stack.push(node.left() + 1);
        }
    }
}
