use glam::{DVec3, Vec3, Vec3A};

use crate::geometry::PoseF64;

/// A pair of triangle indices: `a` in the first mesh, `b` in the second (for a self query,
/// both in the same mesh with `a < b`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct TrianglePair {
    /// Triangle of the first mesh.
    pub a: u32,
    /// Triangle of the second mesh.
    pub b: u32,
}

/// Reusable scratch memory for the exact queries: the traversal stacks and a cache of the
/// second mesh's vertices transformed into the first mesh's frame.
///
/// Keep one per thread and pass it to every query: after the first queries have grown it,
/// queries allocate nothing. It also reports what the last query did
/// ([`QueryWorkspace::node_pairs_visited`]).
#[derive(Debug, Default, Clone)]
pub struct QueryWorkspace {
    pub(crate) stack: Vec<(u32, u32)>,
    pub(crate) distance_stack: Vec<(u32, u32, f32)>,
    /// Per triangle in the tree's leaf order, its box (`min`, `max`) and its corners, filled
    /// by the self queries.
    pub(crate) triangle_boxes: Vec<[Vec3A; 2]>,
    pub(crate) leaf_corners: Vec<[u32; 3]>,
    /// The same corners of the welded mesh, when welding joins some (adjacency only).
    pub(crate) leaf_welded: Vec<[u32; 3]>,
    pub(crate) cache: TransformCache,
    pub(crate) node_pairs_visited: u64,
}

impl QueryWorkspace {
    /// An empty workspace.
    pub fn new() -> Self {
        Self::default()
    }

    /// Node pairs whose boxes the last query tested.
    #[inline]
    pub fn node_pairs_visited(&self) -> u64 {
        self.node_pairs_visited
    }

    /// Starts a query whose second mesh has `vertex_count` vertices (for callers outside the
    /// BVH queries that test triangles of a transformed mesh, such as the ADB exact leaves).
    #[inline]
    pub(crate) fn cache_begin(&mut self, vertex_count: usize) {
        self.cache.begin(vertex_count);
    }

    /// Triangle `tri` of `positions` under `pose`, vertices transformed once per query.
    #[inline]
    pub(crate) fn cached_triangle(
        &mut self,
        tri: [u32; 3],
        positions: &[Vec3],
        pose: &PoseF64,
    ) -> [DVec3; 3] {
        self.cache.triangle(tri, positions, pose)
    }

    /// Heap bytes the workspace holds on to (it grows to the largest query seen, then stays).
    pub fn retained_bytes(&self) -> usize {
        use std::mem::size_of;
        self.stack.capacity() * size_of::<(u32, u32)>()
            + self.distance_stack.capacity() * size_of::<(u32, u32, f32)>()
            + self.triangle_boxes.capacity() * size_of::<[Vec3A; 2]>()
            + self.leaf_corners.capacity() * size_of::<[u32; 3]>()
            + self.leaf_welded.capacity() * size_of::<[u32; 3]>()
            + self.cache.points.capacity() * size_of::<DVec3>()
            + self.cache.stamps.capacity() * size_of::<u32>()
    }
}

/// Lazily transformed vertices, valid for the current query only (generation stamps, so a new
/// query costs nothing to start).
#[derive(Debug, Default, Clone)]
pub(crate) struct TransformCache {
    points: Vec<DVec3>,
    stamps: Vec<u32>,
    stamp: u32,
}

impl TransformCache {
    /// Starts a query over a mesh of `vertex_count` vertices.
    pub(crate) fn begin(&mut self, vertex_count: usize) {
        if self.stamps.len() < vertex_count {
            self.points.resize(vertex_count, DVec3::ZERO);
            self.stamps.resize(vertex_count, 0);
        }
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.stamps.fill(0);
            self.stamp = 1;
        }
    }

    /// Vertex `i` of `positions` under `pose`, computed once per query.
    #[inline]
    pub(crate) fn get(&mut self, i: u32, positions: &[Vec3], pose: &PoseF64) -> DVec3 {
        let i = i as usize;
        if self.stamps[i] != self.stamp {
            self.stamps[i] = self.stamp;
            self.points[i] = pose.transform_point(positions[i]);
        }
        self.points[i]
    }

    /// Triangle `tri` (vertex indices) under `pose`.
    #[inline]
    pub(crate) fn triangle(
        &mut self,
        tri: [u32; 3],
        positions: &[Vec3],
        pose: &PoseF64,
    ) -> [DVec3; 3] {
        [
            self.get(tri[0], positions, pose),
            self.get(tri[1], positions, pose),
            self.get(tri[2], positions, pose),
        ]
    }
}

/// Triangle `tri` of `positions` in `f64` (exact conversion).
#[inline]
pub(crate) fn triangle_f64(tri: [u32; 3], positions: &[Vec3]) -> [DVec3; 3] {
    [
        positions[tri[0] as usize].as_dvec3(),
        positions[tri[1] as usize].as_dvec3(),
        positions[tri[2] as usize].as_dvec3(),
    ]
}
