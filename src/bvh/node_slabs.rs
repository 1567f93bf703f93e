//! Per-node slabs of a [`Bvh`]: for each node, a unit normal (the area-weighted mean of its
//! triangles' normals) and the interval its triangles' vertices span along it. Where a node's
//! surface is nearly flat (the patches where two surfaces first come close) the slab is far
//! thinner than the node's box, so box and slab together bound the node's triangles more
//! tightly than the box alone. The continuous query uses them ([`crate::ccd`]).
use glam::DVec3;

use super::tree::Bvh;
use crate::mesh::TriMesh;

/// The slab `{p : lo ≤ normal · p ≤ hi}` (unit `normal`, the mesh's frame) that holds every
/// vertex of a node's triangles; [`NodeSlab::UNBOUNDED`] where the node's normals spread too
/// widely for a slab to be thinner than its box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeSlab {
    /// Unit normal (zero: unbounded).
    pub normal: DVec3,
    /// Lowest `normal · p` of the node's vertices (rounded down).
    pub lo: f64,
    /// Highest `normal · p` of the node's vertices (rounded up).
    pub hi: f64,
}

impl NodeSlab {
    /// No bound: the whole space.
    pub const UNBOUNDED: NodeSlab = NodeSlab {
        normal: DVec3::ZERO,
        lo: f64::NEG_INFINITY,
        hi: f64::INFINITY,
    };

    /// Whether the slab bounds anything (a unit normal).
    pub fn is_bounded(&self) -> bool {
        self.normal != DVec3::ZERO
    }
}

/// A node gets a slab only where its mean normal is at least this long relative to its summed
/// triangle areas: its normals lie within a cone of about 60° around the mean. Wider, the slab
/// is about as thick as the box and only costs its test.
const MIN_ALIGNMENT: f64 = 0.5;

/// The slab of every node of `bvh` (index-aligned with [`Bvh::nodes`]), built over `mesh`'s
/// current positions. `O(n log n)`: each triangle is projected once per level above it.
pub(crate) fn node_slabs(bvh: &Bvh, mesh: &TriMesh) -> Vec<NodeSlab> {
    let nodes = bvh.nodes();
    let (positions, triangles) = (mesh.positions(), mesh.triangles());
    let order = bvh.leaf_triangles();
    let area_vector = |t: u32| {
        let [a, b, c] = triangles[t as usize].map(|v| positions[v as usize].as_dvec3());
        (b - a).cross(c - a)
    };
    // Bottom-up (every child comes after its parent): each node's range of `order` (a subtree's
    // triangles are contiguous there; `None` if not, then no slab) and its summed area vectors
    // and areas.
    let mut range: Vec<Option<(u32, u32)>> = vec![None; nodes.len()];
    let mut sums = vec![(DVec3::ZERO, 0.0f64); nodes.len()];
    for i in (0..nodes.len()).rev() {
        let node = &nodes[i];
        if node.is_leaf() {
            range[i] = Some((node.first, node.first + node.count));
            sums[i] = bvh
                .triangles_of(node)
                .iter()
                .map(|&t| area_vector(t))
                .fold((DVec3::ZERO, 0.0), |(v, a), n| (v + n, a + n.length()));
        } else {
            let l = node.left() as usize;
            range[i] = match (range[l], range[l + 1]) {
                (Some(x), Some(y)) if x.1 == y.0 => Some((x.0, y.1)),
                (Some(x), Some(y)) if y.1 == x.0 => Some((y.0, x.1)),
                _ => None,
            };
            sums[i] = (sums[l].0 + sums[l + 1].0, sums[l].1 + sums[l + 1].1);
        }
    }
    (0..nodes.len())
        .map(|i| {
            let (vector, area) = sums[i];
            let length = vector.length();
            let Some((first, end)) = range[i] else {
                return NodeSlab::UNBOUNDED;
            };
            // (A NaN length fails the first test.)
            let aligned = length > MIN_ALIGNMENT * area;
            if !aligned || !length.is_finite() {
                return NodeSlab::UNBOUNDED;
            }
            let normal = vector / length;
            let (mut lo, mut hi, mut far) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
            for &t in &order[first as usize..end as usize] {
                for v in triangles[t as usize] {
                    let p = positions[v as usize].as_dvec3();
                    let d = normal.dot(p);
                    lo = lo.min(d);
                    hi = hi.max(d);
                    far = far.max(p.abs().max_element());
                }
            }
            // Each dot product is within a few ulps of `|p|`: padded by far more.
            let pad = 1e-12 * (1.0 + far);
            NodeSlab {
                normal,
                lo: lo - pad,
                hi: hi + pad,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    #[test]
    fn every_slab_holds_its_nodes_vertices_and_flat_nodes_are_thin() {
        for mesh in [
            generate::icosphere(1.0, 4),
            generate::torus(1.0, 0.3, 48, 16),
            generate::cloth_grid(2.0, 1.0, 20, 10),
        ] {
            let bvh = Bvh::build(&mesh);
            let slabs = node_slabs(&bvh, &mesh);
            assert_eq!(slabs.len(), bvh.nodes().len());
            let mut bounded_leaves = 0;
            for (i, node) in bvh.nodes().iter().enumerate() {
                let s = slabs[i];
                if !s.is_bounded() {
                    assert_eq!((s.lo, s.hi), (f64::NEG_INFINITY, f64::INFINITY));
                    continue;
                }
                assert!((s.normal.length() - 1.0).abs() < 1e-12);
                // The node's triangles: those of the leaves below it.
                let mut stack = vec![i];
                while let Some(k) = stack.pop() {
                    let n = &bvh.nodes()[k];
                    if n.is_leaf() {
                        for &t in bvh.triangles_of(n) {
                            for v in mesh.triangles()[t as usize] {
                                let d = s.normal.dot(mesh.positions()[v as usize].as_dvec3());
                                assert!(s.lo <= d && d <= s.hi, "node {i}: {d} not in slab");
                            }
                        }
                    } else {
                        stack.extend([n.left() as usize, n.left() as usize + 1]);
                    }
                }
                if node.is_leaf() {
                    bounded_leaves += 1;
                    // A leaf of a fine mesh is nearly flat: far thinner than its box.
                    let side = node.aabb().extents().max_element() as f64;
                    assert!(
                        s.hi - s.lo < 0.5 * side,
                        "leaf {i}: {} vs {side}",
                        s.hi - s.lo
                    );
                }
            }
            let leaves = bvh.nodes().iter().filter(|n| n.is_leaf()).count();
            assert_eq!(
                bounded_leaves, leaves,
                "every leaf of these meshes has a slab"
            );
            // The whole sphere's normals cancel: its root has none; the flat cloth's has one.
            assert_eq!(slabs[0].is_bounded(), mesh.triangle_count() == 400);
        }
    }
}
