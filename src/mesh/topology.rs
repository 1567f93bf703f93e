//! Mesh adjacency in flat (CSR) arrays: vertex → triangles / neighbours / edges,
//! triangle → edges / neighbours, edge → triangles.

use smallvec::SmallVec;

use super::TriMesh;

/// An undirected edge and the triangles that use it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Edge {
    /// The two vertex indices, smaller first.
    pub vertices: [u32; 2],
    /// Triangles using this edge, ascending, each once: 1 on a boundary, 2 on a manifold
    /// interior edge, more if non-manifold.
    pub triangles: SmallVec<[u32; 2]>,
}

impl Edge {
    /// Whether exactly one triangle uses this edge.
    #[inline]
    pub fn is_boundary(&self) -> bool {
        self.triangles.len() == 1
    }

    /// Whether more than two triangles use this edge.
    #[inline]
    pub fn is_non_manifold(&self) -> bool {
        self.triangles.len() > 2
    }
}

/// Mesh adjacency, by vertex index (no welding of vertices that share a position), for local
/// searches over a mesh's surface.
///
/// Edges are numbered in ascending order of their vertex pair. Every list is a slice into a
/// flat array. Degenerate triangles are handled: a triangle with a repeated index (`[3, 3, 5]`)
/// makes no edge between a vertex and itself, appears once in each of its distinct vertices'
/// lists and once in each of its edges' lists. Duplicate triangles are distinct triangles, so
/// their shared edges are non-manifold. Unreferenced vertices have empty lists.
///
/// Built in `O(n log n)` for `n` triangles.
///
/// # Example
/// ```
/// use stochastic_collision::mesh::{Topology, generate};
/// let cube = generate::cuboid(glam::Vec3::ONE, 0);
/// let topo = Topology::new(&cube);
/// assert!(topo.is_closed());
/// assert_eq!(topo.edges().len(), 18);
/// for t in 0..cube.triangle_count() as u32 {
///     assert_eq!(topo.triangle_neighbours(t).len(), 3);
/// }
/// ```
#[derive(Debug, Clone)]
pub struct Topology {
    edges: Vec<Edge>,
    /// Per triangle, the edge of corners `(i, i + 1)`, or [`Topology::NO_EDGE`].
    triangle_edges: Vec<[u32; 3]>,
    /// CSR offsets (`vertex_count + 1`) into `vertex_triangles`.
    vertex_triangle_offsets: Vec<u32>,
    vertex_triangles: Vec<u32>,
    /// CSR offsets (`vertex_count + 1`) into `vertex_edges` and `vertex_neighbours`.
    vertex_edge_offsets: Vec<u32>,
    vertex_edges: Vec<u32>,
    vertex_neighbours: Vec<u32>,
    /// CSR offsets (`triangle_count + 1`) into `triangle_neighbours`.
    triangle_neighbour_offsets: Vec<u32>,
    triangle_neighbours: Vec<u32>,
    boundary_edges: usize,
    non_manifold_edges: usize,
}

impl Topology {
    /// Stands in [`Topology::triangle_edges`] for a degenerate side whose two corners are the
    /// same vertex.
    pub const NO_EDGE: u32 = u32::MAX;

    /// Builds the adjacency of `mesh`.
    pub fn new(mesh: &TriMesh) -> Self {
        let triangles = mesh.triangles();
        let vertex_count = mesh.vertex_count();

        // Edge keys: (smaller vertex, larger vertex, triangle, side), sorted.
        let mut keys: Vec<(u64, u32, u8)> = Vec::with_capacity(triangles.len() * 3);
        for (t, tri) in triangles.iter().enumerate() {
            for side in 0..3 {
                let (a, b) = (tri[side], tri[(side + 1) % 3]);
                if a != b {
                    let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
                    keys.push((key, t as u32, side as u8));
                }
            }
        }
        keys.sort_unstable();

        let mut edges: Vec<Edge> = Vec::new();
        let mut triangle_edges = vec![[Self::NO_EDGE; 3]; triangles.len()];
        let mut previous_key = None;
        for &(key, t, side) in &keys {
            if previous_key != Some(key) {
                previous_key = Some(key);
                edges.push(Edge {
                    vertices: [(key >> 32) as u32, key as u32],
                    triangles: SmallVec::new(),
                });
            }
            let id = (edges.len() - 1) as u32;
            let edge = edges.last_mut().expect("an edge was just pushed");
            // Sorted by triangle within a key: a triangle using the edge twice is listed once.
            if edge.triangles.last() != Some(&t) {
                edge.triangles.push(t);
            }
            triangle_edges[t as usize][side as usize] = id;
        }
        drop(keys);

        // Vertex → triangles, each distinct vertex of a triangle once.
        let mut counts = vec![0u32; vertex_count + 1];
        for tri in triangles {
            for (i, &v) in tri.iter().enumerate() {
                if !tri[..i].contains(&v) {
                    counts[v as usize + 1] += 1;
                }
            }
        }
        let vertex_triangle_offsets = prefix_sum(counts);
        let mut cursor = vertex_triangle_offsets.clone();
        let mut vertex_triangles =
            vec![0u32; *vertex_triangle_offsets.last().unwrap_or(&0) as usize];
        for (t, tri) in triangles.iter().enumerate() {
            for (i, &v) in tri.iter().enumerate() {
                if !tri[..i].contains(&v) {
                    let slot = &mut cursor[v as usize];
                    vertex_triangles[*slot as usize] = t as u32;
                    *slot += 1;
                }
            }
        }

        // Vertex → edges and neighbours. Filling in edge order yields, for vertex v, first the
        // edges (u, v) with u < v by ascending u, then (v, w) by ascending w: neighbours come
        // out sorted and distinct.
        let mut counts = vec![0u32; vertex_count + 1];
        for e in &edges {
            counts[e.vertices[0] as usize + 1] += 1;
            counts[e.vertices[1] as usize + 1] += 1;
        }
        let vertex_edge_offsets = prefix_sum(counts);
        let mut cursor = vertex_edge_offsets.clone();
        let total = *vertex_edge_offsets.last().unwrap_or(&0) as usize;
        let mut vertex_edges = vec![0u32; total];
        let mut vertex_neighbours = vec![0u32; total];
        for (id, e) in edges.iter().enumerate() {
            let [a, b] = e.vertices;
            for (v, other) in [(a, b), (b, a)] {
                let slot = &mut cursor[v as usize];
                vertex_edges[*slot as usize] = id as u32;
                vertex_neighbours[*slot as usize] = other;
                *slot += 1;
            }
        }

        // Triangle → triangles sharing an edge, ascending and distinct.
        let mut triangle_neighbour_offsets = Vec::with_capacity(triangles.len() + 1);
        let mut triangle_neighbours = Vec::with_capacity(triangles.len() * 3);
        triangle_neighbour_offsets.push(0u32);
        let mut scratch: SmallVec<[u32; 8]> = SmallVec::new();
        for (t, sides) in triangle_edges.iter().enumerate() {
            scratch.clear();
            for &e in sides {
                if e != Self::NO_EDGE {
                    scratch.extend(
                        edges[e as usize]
                            .triangles
                            .iter()
                            .copied()
                            .filter(|&o| o != t as u32),
                    );
                }
            }
            scratch.sort_unstable();
            scratch.dedup();
            triangle_neighbours.extend_from_slice(&scratch);
            triangle_neighbour_offsets.push(triangle_neighbours.len() as u32);
        }

        let boundary_edges = edges.iter().filter(|e| e.is_boundary()).count();
        let non_manifold_edges = edges.iter().filter(|e| e.is_non_manifold()).count();
        Self {
            edges,
            triangle_edges,
            vertex_triangle_offsets,
            vertex_triangles,
            vertex_edge_offsets,
            vertex_edges,
            vertex_neighbours,
            triangle_neighbour_offsets,
            triangle_neighbours,
            boundary_edges,
            non_manifold_edges,
        }
    }

    /// All edges, in ascending order of [`Edge::vertices`]; an edge's id is its index here.
    #[inline]
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// Edge `e`.
    ///
    /// # Panics
    /// If `e` is not an edge id (`e >= self.edges().len()`).
    #[inline]
    pub fn edge(&self, e: u32) -> &Edge {
        &self.edges[e as usize]
    }

    /// Number of vertices (of the mesh this was built from, unreferenced ones included).
    #[inline]
    pub fn vertex_count(&self) -> usize {
        self.vertex_triangle_offsets.len() - 1
    }

    /// Number of triangles.
    #[inline]
    pub fn triangle_count(&self) -> usize {
        self.triangle_edges.len()
    }

    /// Triangles that use vertex `v`, ascending, each once.
    ///
    /// # Panics
    /// If `v` is not a vertex index.
    #[inline]
    pub fn vertex_triangles(&self, v: u32) -> &[u32] {
        csr(&self.vertex_triangle_offsets, &self.vertex_triangles, v)
    }

    /// Vertices that share an edge with `v`, ascending, each once, never `v` itself.
    ///
    /// # Panics
    /// If `v` is not a vertex index.
    #[inline]
    pub fn vertex_neighbours(&self, v: u32) -> &[u32] {
        csr(&self.vertex_edge_offsets, &self.vertex_neighbours, v)
    }

    /// Ids of the edges at vertex `v`, ascending; `vertex_edges(v)[i]` is the edge to
    /// `vertex_neighbours(v)[i]`.
    ///
    /// # Panics
    /// If `v` is not a vertex index.
    #[inline]
    pub fn vertex_edges(&self, v: u32) -> &[u32] {
        csr(&self.vertex_edge_offsets, &self.vertex_edges, v)
    }

    /// Ids of the edges of triangle `t`: side `i` joins corners `i` and `(i + 1) % 3`. A side
    /// whose two corners are the same vertex has no edge: [`Topology::NO_EDGE`].
    ///
    /// # Panics
    /// If `t` is not a triangle index.
    #[inline]
    pub fn triangle_edges(&self, t: u32) -> [u32; 3] {
        self.triangle_edges[t as usize]
    }

    /// Triangles other than `t` that share an edge with it, ascending, each once.
    ///
    /// # Panics
    /// If `t` is not a triangle index.
    #[inline]
    pub fn triangle_neighbours(&self, t: u32) -> &[u32] {
        csr(
            &self.triangle_neighbour_offsets,
            &self.triangle_neighbours,
            t,
        )
    }

    /// The edge joining vertices `v0` and `v1` (in either order), if any. `None` when
    /// `v0 == v1` or either is not a vertex index.
    pub fn edge_between(&self, v0: u32, v1: u32) -> Option<u32> {
        if v0 == v1 || v0 as usize >= self.vertex_count() || v1 as usize >= self.vertex_count() {
            return None;
        }
        let i = self.vertex_neighbours(v0).binary_search(&v1).ok()?;
        Some(self.vertex_edges(v0)[i])
    }

    /// Ids of the boundary edges (used by exactly one triangle), ascending.
    pub fn boundary_edges(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.edges.len() as u32).filter(|&e| self.edges[e as usize].is_boundary())
    }

    /// Ids of the non-manifold edges (used by more than two triangles), ascending.
    pub fn non_manifold_edges(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.edges.len() as u32).filter(|&e| self.edges[e as usize].is_non_manifold())
    }

    /// Number of boundary edges.
    #[inline]
    pub fn boundary_edge_count(&self) -> usize {
        self.boundary_edges
    }

    /// Number of non-manifold edges.
    #[inline]
    pub fn non_manifold_edge_count(&self) -> usize {
        self.non_manifold_edges
    }

    /// Whether vertex `v` lies on a boundary edge.
    ///
    /// # Panics
    /// If `v` is not a vertex index.
    pub fn is_boundary_vertex(&self, v: u32) -> bool {
        self.vertex_edges(v)
            .iter()
            .any(|&e| self.edges[e as usize].is_boundary())
    }

    /// Whether the mesh is closed: it has edges, and every edge has exactly two triangles (no
    /// boundary and no non-manifold edge).
    #[inline]
    pub fn is_closed(&self) -> bool {
        !self.edges.is_empty() && self.boundary_edges == 0 && self.non_manifold_edges == 0
    }

    /// Euler characteristic `V − E + F`, counting only referenced vertices (those with at
    /// least one triangle): 2 for a closed sphere-like surface, 0 for a torus or an open tube,
    /// 1 for a disc.
    pub fn euler_characteristic(&self) -> i64 {
        let vertices = self
            .vertex_triangle_offsets
            .windows(2)
            .filter(|w| w[1] > w[0])
            .count();
        vertices as i64 - self.edges.len() as i64 + self.triangle_count() as i64
    }
}

/// Exclusive prefix sum in place over `counts[1..]` (with `counts[0] == 0`).
fn prefix_sum(mut counts: Vec<u32>) -> Vec<u32> {
    for i in 1..counts.len() {
        counts[i] += counts[i - 1];
    }
    counts
}

#[inline]
fn csr<'a>(offsets: &[u32], values: &'a [u32], i: u32) -> &'a [u32] {
    let i = i as usize;
    &values[offsets[i] as usize..offsets[i + 1] as usize]
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn mesh(n: usize, triangles: Vec<[u32; 3]>) -> TriMesh {
        let positions = (0..n)
            .map(|i| Vec3::new(i as f32, (i * i) as f32, 0.0))
            .collect();
        TriMesh::new(positions, triangles).unwrap()
    }

    #[test]
    fn tetrahedron() {
        let m = mesh(5, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]);
        let t = Topology::new(&m);
        assert!(t.is_closed());
        assert_eq!(t.edges().len(), 6);
        assert_eq!(t.vertex_neighbours(0), &[1, 2, 3]);
        assert_eq!(t.vertex_triangles(4), &[] as &[u32]);
        assert_eq!(t.triangle_neighbours(0), &[1, 2, 3]);
        assert_eq!(t.euler_characteristic(), 2);
        let e = t.edge_between(3, 1).unwrap();
        assert_eq!(t.edge(e).vertices, [1, 3]);
        assert_eq!(t.edge(e).triangles.as_slice(), &[1, 2]);
        assert_eq!(t.edge_between(0, 4), None);
        assert_eq!(t.edge_between(0, 99), None);
    }

    #[test]
    fn degenerate_and_duplicate() {
        let m = mesh(4, vec![[3, 3, 1], [0, 1, 2], [0, 1, 2]]);
        let t = Topology::new(&m);
        assert_eq!(t.triangle_edges(0)[0], Topology::NO_EDGE);
        assert_eq!(t.vertex_triangles(3), &[0]);
        assert_eq!(t.vertex_neighbours(3), &[1]);
        assert_eq!(
            t.edge(t.edge_between(1, 3).unwrap()).triangles.as_slice(),
            &[0]
        );
        assert_eq!(t.non_manifold_edge_count(), 0);
        assert_eq!(t.boundary_edge_count(), 1);
        assert!(!t.is_closed());
    }
}
