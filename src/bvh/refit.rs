//! Bottom-up refit after the mesh's vertices moved (same topology).
use super::tree::Bvh;
use crate::geometry::Aabb;
use crate::mesh::TriMesh;

impl Bvh {
    /// Recomputes every box from `mesh`'s current positions in one reverse sweep over the
    /// nodes: `O(n)`, no allocation, same tree shape. `mesh` must be the mesh the tree was built
    /// on (same triangles); [`CollisionMesh`](super::CollisionMesh) guarantees that.
    pub(crate) fn refit(&mut self, mesh: &TriMesh) {
        debug_assert_eq!(self.leaf_triangles.len(), mesh.triangle_count());
        // Children always come after their parent, so a reverse sweep sees them first.
        for i in (0..self.nodes.len()).rev() {
            let node = self.nodes[i];
            let b = if node.is_leaf() {
                let mut b = Aabb::EMPTY;
                for &t in
                    &self.leaf_triangles[node.first as usize..(node.first + node.count) as usize]
                {
                    for p in mesh.triangle(t as usize) {
                        b.grow(p);
                    }
                }
                b
            } else {
                let l = &self.nodes[node.first as usize];
                let r = &self.nodes[node.first as usize + 1];
                Aabb::new(l.min.min(r.min), l.max.max(r.max))
            };
            self.nodes[i].min = b.min;
            self.nodes[i].max = b.max;
        }
    }
}
