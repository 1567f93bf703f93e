use glam::Vec3;

use crate::geometry::Aabb;

/// One node of a [`Bvh`]: 32 bytes, two per cache line.
///
/// An inner node has `count == 0` and its two children at `first` and `first + 1` (siblings are
/// adjacent, and every child comes after its parent, so a reverse sweep refits bottom-up).
/// A leaf has `count > 0` triangles: `Bvh::leaf_triangles` entries `first .. first + count`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[repr(C)]
pub struct BvhNode {
    /// Lowest corner of the node's box.
    pub min: Vec3,
    /// Inner node: index of the left child (the right one follows). Leaf: first triangle slot.
    pub first: u32,
    /// Highest corner of the node's box.
    pub max: Vec3,
    /// Number of triangles in a leaf; 0 for an inner node.
    pub count: u32,
}

const _: () = assert!(std::mem::size_of::<BvhNode>() == 32);

impl BvhNode {
    /// Whether this node is a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// The node's box.
    #[inline]
    pub fn aabb(&self) -> Aabb {
        Aabb::new(self.min, self.max)
    }

    /// Index of the left child (inner nodes only; the right child is `left() + 1`).
    #[inline]
    pub fn left(&self) -> u32 {
        self.first
    }
}

/// A binary AABB tree over the triangles of one mesh, in a flat node array.
///
/// Node 0 is the root. Leaves refer to ranges of [`Bvh::leaf_triangles`], a permutation of the
/// mesh's triangle indices. Built by [`Bvh::build`] (binned SAH); after the mesh's vertices move,
/// [`CollisionMesh::set_positions`](super::CollisionMesh::set_positions) refits it in `O(n)`.
///
/// # Example
/// ```
/// use stochastic_collision::{bvh::Bvh, mesh::generate};
/// let sphere = generate::icosphere(1.0, 3);
/// let bvh = Bvh::build(&sphere);
/// assert_eq!(bvh.leaf_triangles().len(), sphere.triangle_count());
/// assert!(bvh.root_aabb().contains_point(glam::Vec3::ZERO));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Bvh {
    pub(crate) nodes: Vec<BvhNode>,
    pub(crate) leaf_triangles: Vec<u32>,
    pub(crate) depth: u32,
}

impl Bvh {
    /// All nodes; node 0 is the root.
    #[inline]
    pub fn nodes(&self) -> &[BvhNode] {
        &self.nodes
    }

    /// The triangle indices referred to by leaves (a permutation of `0..triangle_count`).
    #[inline]
    pub fn leaf_triangles(&self) -> &[u32] {
        &self.leaf_triangles
    }

    /// The triangles of leaf `node`.
    #[inline]
    pub fn triangles_of(&self, node: &BvhNode) -> &[u32] {
        &self.leaf_triangles[node.first as usize..(node.first + node.count) as usize]
    }

    /// The root's box: the bounds of every triangle.
    #[inline]
    pub fn root_aabb(&self) -> Aabb {
        self.nodes[0].aabb()
    }

    /// Number of levels (1 for a single leaf).
    #[inline]
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Bytes held by the tree.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.capacity() * std::mem::size_of::<BvhNode>()
            + self.leaf_triangles.capacity() * std::mem::size_of::<u32>()
    }
}
