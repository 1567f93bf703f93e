use std::sync::OnceLock;

use glam::Vec3;

use super::build::BvhBuildOptions;
use super::node_slabs::{NodeSlab, node_slabs};
use super::tree::Bvh;
use crate::mesh::{MeshError, Topology, TriMesh};

/// A triangle mesh together with its [`Bvh`], always consistent: what every query takes.
///
/// Share one immutable `CollisionMesh` (e.g. in an `Arc`) among all rigid instances of a mesh;
/// give each deformable instance its own and move its vertices with
/// [`CollisionMesh::set_positions`], which refits the tree in `O(n)` (never a rebuild).
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// let mut cloth = CollisionMesh::new(generate::cloth_grid(1.0, 1.0, 8, 8));
/// let lifted: Vec<Vec3> = cloth.mesh().positions().iter().map(|p| *p + Vec3::Y).collect();
/// cloth.set_positions(&lifted)?;
/// assert!(cloth.bvh().root_aabb().min.y > 0.5);
/// # Ok::<(), MeshError>(())
/// ```
#[derive(Debug)]
pub struct CollisionMesh {
    mesh: TriMesh,
    bvh: Bvh,
    closed: OnceLock<bool>,
    components: OnceLock<Vec<u32>>,
    welded: OnceLock<Option<Vec<[u32; 3]>>>,
    topology: OnceLock<Topology>,
    /// Per-node slabs at the current positions (made again after a move).
    slabs: OnceLock<Vec<NodeSlab>>,
}

impl Clone for CollisionMesh {
    fn clone(&self) -> Self {
        let closed = OnceLock::new();
        if let Some(&c) = self.closed.get() {
            let _ = closed.set(c);
        }
        Self {
            mesh: self.mesh.clone(),
            bvh: self.bvh.clone(),
            closed,
            components: self.components.clone(),
            welded: self.welded.clone(),
            topology: self.topology.clone(),
            slabs: self.slabs.clone(),
        }
    }
}

impl CollisionMesh {
    /// Builds the tree of `mesh` with default options.
    pub fn new(mesh: TriMesh) -> Self {
        Self::with_options(mesh, BvhBuildOptions::default())
    }

    /// Builds the tree of `mesh` with the given options.
    pub fn with_options(mesh: TriMesh, options: BvhBuildOptions) -> Self {
        let bvh = Bvh::build_with(&mesh, options);
        Self {
            mesh,
            bvh,
            closed: OnceLock::new(),
            components: OnceLock::new(),
            welded: OnceLock::new(),
            topology: OnceLock::new(),
            slabs: OnceLock::new(),
        }
    }

    /// The mesh.
    #[inline]
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// The tree.
    #[inline]
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// Moves the vertices (same topology) and refits the tree in `O(n)`.
    ///
    /// # Errors
    /// As [`TriMesh::set_positions`]: wrong count or a non-finite coordinate; nothing changes then.
    pub fn set_positions(&mut self, positions: &[Vec3]) -> Result<(), MeshError> {
        // Topology (closedness, components) does not change with positions: caches stay valid.
        self.mesh.set_positions(positions)?;
        self.bvh.refit(&self.mesh);
        // The slabs do: made again when next asked for.
        self.slabs = OnceLock::new();
        Ok(())
    }

    /// Every node's [`NodeSlab`] (index-aligned with [`Bvh::nodes`]) at the current positions:
    /// made at the first call after the mesh was built or moved, in `O(n log n)` (each
    /// triangle projected once per level above it). The continuous query reads them for a mesh
    /// that does not turn over its step.
    pub fn node_slabs(&self) -> &[NodeSlab] {
        self.slabs.get_or_init(|| node_slabs(&self.bvh, &self.mesh))
    }

    /// Whether the mesh is closed (every edge shared by exactly two triangles), computed once.
    /// Only a closed mesh has an inside for [`ExactOptions::solid`](super::ExactOptions::solid).
    pub fn is_closed(&self) -> bool {
        *self.closed.get_or_init(|| self.mesh.is_closed())
    }

    /// The mesh's [`Topology`] (by vertex index), computed once: it does not change with
    /// positions.
    pub fn topology(&self) -> &Topology {
        self.topology.get_or_init(|| Topology::new(&self.mesh))
    }

    /// The triangles of the [welded](TriMesh::welded) mesh (corners at one position joined
    /// under the lowest index), or `None` when welding changes no corner; computed once, from
    /// the positions at the first call. Self-collision counts triangles with a joined corner in
    /// common as adjacent: an unwelded seam or pole is not a self-contact.
    pub fn welded_triangles(&self) -> Option<&[[u32; 3]]> {
        self.welded
            .get_or_init(|| match self.mesh.welded() {
                std::borrow::Cow::Borrowed(_) => None,
                std::borrow::Cow::Owned(welded) => Some(welded.triangles().to_vec()),
            })
            .as_deref()
    }

    /// One vertex of every connected component (triangles sharing a vertex index are
    /// connected), computed once.
    pub fn component_vertices(&self) -> &[u32] {
        self.components
            .get_or_init(|| component_vertices(&self.mesh))
    }
}

/// One referenced vertex per connected component.
fn component_vertices(mesh: &TriMesh) -> Vec<u32> {
    let labels = component_labels(mesh);
    let mut seen = vec![false; labels.len()];
    let mut out = Vec::new();
    for &[a, _, _] in mesh.triangles() {
        let r = labels[a as usize] as usize;
        if !seen[r] {
            seen[r] = true;
            out.push(a);
        }
    }
    out
}

/// Per vertex, a label (a vertex index) shared by the vertices of one connected component:
/// triangles sharing a vertex index are connected (union–find over triangle corners).
pub(crate) fn component_labels(mesh: &TriMesh) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..mesh.vertex_count() as u32).collect();
    fn find(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            let up = parent[parent[v as usize] as usize];
            parent[v as usize] = up;
            v = up;
        }
        v
    }
    for &[a, b, c] in mesh.triangles() {
        let ra = find(&mut parent, a);
        for v in [b, c] {
            let rv = find(&mut parent, v);
            if rv != ra {
                parent[rv as usize] = ra;
            }
        }
    }
    (0..parent.len() as u32)
        .map(|v| find(&mut parent, v))
        .collect()
}
