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
            self.refit_node(i, mesh);
        }
    }

    /// Recomputes the boxes of the subtree below node `root` only (the rest of the tree is
    /// left as it is: for callers that know no vertex under it moved), with `stack` as
    /// scratch. The same boxes as [`Bvh::refit`] gives them when the positions below `root`
    /// are the only ones that changed.
    pub(crate) fn refit_subtree(&mut self, mesh: &TriMesh, root: u32, stack: &mut Vec<u32>) {
        stack.clear();
        stack.push(root);
        let mut i = 0;
        while i < stack.len() {
            let node = self.nodes[stack[i] as usize];
            if !node.is_leaf() {
                stack.push(node.first);
                stack.push(node.first + 1);
            }
            i += 1;
        }
        // Breadth-first order puts every child after its parent.
        for &n in stack.iter().rev() {
            self.refit_node(n as usize, mesh);
        }
    }

    /// Recomputes inner nodes `nodes` from their children, in the order given (children
    /// before parents: descending indices).
    pub(crate) fn refit_inner(&mut self, nodes: &[u32]) {
        for &n in nodes {
            let node = self.nodes[n as usize];
            debug_assert!(!node.is_leaf());
            let l = &self.nodes[node.first as usize];
            let r = &self.nodes[node.first as usize + 1];
            let (min, max) = (l.min.min(r.min), l.max.max(r.max));
            self.nodes[n as usize].min = min;
            self.nodes[n as usize].max = max;
        }
    }

    /// Node `i`'s box from its triangles (a leaf) or its children's boxes.
    #[inline]
    fn refit_node(&mut self, i: usize, mesh: &TriMesh) {
        let node = self.nodes[i];
        let b = if node.is_leaf() {
            let mut b = Aabb::EMPTY;
            for &t in &self.leaf_triangles[node.first as usize..(node.first + node.count) as usize]
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
