//! A mesh prepared for tracking: topology, area sampling table, velocities, patch tree.

use glam::{DVec3, Vec3};

use super::patch_reach::PatchReach;
use super::patch_tree::PatchTree;
use crate::geometry::PoseF64;
use crate::mesh::{MeshError, SelfExclusion, Topology, TriMesh, triangles_within_rings};

/// Default largest number of triangles in a patch of the incomplete hierarchy.
pub const DEFAULT_PATCH_SIZE: u32 = 64;

/// The ring count whose self-collision exclusion a [`TrackedSurface`] builds with itself:
/// [`TrackerConfig::exclusion_rings`](super::TrackerConfig::exclusion_rings)'s default.
pub const DEFAULT_EXCLUSION_RINGS: u32 = 2;

/// A triangle mesh prepared for stochastic tracking: its [`Topology`] (feature neighbours),
/// a table for sampling points uniformly over its area, the previous frame's positions (for
/// velocity-driven sampling), Kimmerle's incomplete hierarchy (a BVH cut at patches,
/// refitted on every [`TrackedSurface::set_positions`]), and the self-collision exclusion of
/// [`DEFAULT_EXCLUSION_RINGS`] (`O(triangles)`, about 64 bytes a triangle: built here so that
/// a tracker's first step does not stall on it).
///
/// Deform it in place with [`TrackedSurface::set_positions`] (same triangles); the topology
/// never changes.
#[derive(Debug, Clone)]
pub struct TrackedSurface {
    mesh: TriMesh,
    topology: Topology,
    previous: Vec<Vec3>,
    area_cdf: Vec<f64>,
    pub(crate) patches: PatchTree,
    /// Unit normal of each triangle at the current positions (zero when degenerate).
    pub(crate) normals: Vec<Vec3>,
    mean_edge: f32,
    size: f32,
    update_time: std::time::Duration,
    /// Successful [`TrackedSurface::set_positions`] calls so far.
    generation: u64,
    /// The farthest any vertex moved in the last one.
    max_displacement: f32,
    /// Per vertex, one bit: whether the last one moved it.
    moved: Vec<u64>,
    /// The self-collision exclusion of the default ring count
    /// ([`DEFAULT_EXCLUSION_RINGS`], built with the surface: it holds for any positions, and a
    /// tracker's first step does not stall building it), with the patches each patch's
    /// triangles can be excluded with.
    exclusion: (SelfExclusion, PatchReach),
    /// The same for the first other ring count asked for (built on first use by
    /// [`TrackedSurface::excluded_pairs`]).
    other_exclusion: std::sync::OnceLock<(SelfExclusion, PatchReach)>,
    /// The [welded](TriMesh::welded) mesh and its topology, when welding joins some corners
    /// (seams, poles): rings for the exclusion are counted there.
    welded: Option<Box<(TriMesh, Topology)>>,
    /// Names this surface's topology: given on construction, shared by its clones.
    id: u64,
}

/// Which triangle pairs of one surface self-collision leaves out (those within a number of
/// vertex rings, [`triangles_within_rings`]): when the surface's cached [`SelfExclusion`] has
/// that ring count, two lookups of the triangles' patches ([`PatchReach`]) and, for nearby
/// patches, one merge of two precomputed lists; else a walk of the topology.
#[derive(Clone, Copy)]
pub(crate) enum ExcludedPairs<'a> {
    Cached {
        exclusion: &'a SelfExclusion,
        reach: &'a PatchReach,
        patch_of: &'a [u32],
    },
    Walk {
        mesh: &'a TriMesh,
        topology: &'a Topology,
        rings: u32,
    },
}

impl ExcludedPairs<'_> {
    /// Whether triangles `a` and `b` of the surface are the same or within the rings.
    #[inline]
    pub fn excludes(&self, a: u32, b: u32) -> bool {
        match self {
            ExcludedPairs::Cached {
                exclusion,
                reach,
                patch_of,
            } => {
                reach.may_meet(patch_of[a as usize], patch_of[b as usize])
                    && exclusion.excludes(a, b)
            }
            ExcludedPairs::Walk {
                mesh,
                topology,
                rings,
            } => {
                let t = mesh.triangles();
                a == b || triangles_within_rings(topology, t[a as usize], t[b as usize], *rings)
            }
        }
    }
}

impl TrackedSurface {
    /// Prepares `mesh` with patches of at most [`DEFAULT_PATCH_SIZE`] triangles.
    pub fn new(mesh: TriMesh) -> Self {
        Self::with_patch_size(mesh, DEFAULT_PATCH_SIZE)
    }

    /// Prepares `mesh` with patches of at most `patch_size` triangles (at least 1).
    pub fn with_patch_size(mesh: TriMesh, patch_size: u32) -> Self {
        let topology = Topology::new(&mesh);
        let p = mesh.positions();
        let edges = topology.edges();
        let mean_edge = if edges.is_empty() {
            0.0
        } else {
            let sum: f64 = edges
                .iter()
                .map(|e| (p[e.vertices[0] as usize] - p[e.vertices[1] as usize]).length() as f64)
                .sum();
            (sum / edges.len() as f64) as f32
        };
        let size = mesh.aabb().extents().length();
        let rest_edge_lengths: Vec<f32> = edges
            .iter()
            .map(|e| (p[e.vertices[0] as usize] - p[e.vertices[1] as usize]).length())
            .collect();
        let mut area_cdf = Vec::with_capacity(mesh.triangle_count());
        let mut total = 0.0f64;
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.triangle(t).map(|q| q.as_dvec3());
            total += 0.5 * (b - a).cross(c - a).length();
            area_cdf.push(total);
        }
        let mut patches = PatchTree::new(&mesh, patch_size);
        patches.assign_edges(&topology, &rest_edge_lengths);
        let mut normals = Vec::new();
        triangle_normals(&mesh, &mut normals);
        patches.update_cones(&normals, mesh.positions());
        let welded = match mesh.welded() {
            std::borrow::Cow::Borrowed(_) => None,
            std::borrow::Cow::Owned(welded) => {
                let topology = Topology::new(&welded);
                Some(Box::new((welded, topology)))
            }
        };
        let mesh_vertex_words = mesh.vertex_count().div_ceil(64);
        let (m, t) = ring_mesh(&welded, &mesh, &topology);
        let exclusion = exclusion_of(m, t, &patches, DEFAULT_EXCLUSION_RINGS);
        TrackedSurface {
            welded,
            previous: mesh.positions().to_vec(),
            mesh,
            topology,
            area_cdf,
            patches,
            normals,
            mean_edge,
            size,
            update_time: std::time::Duration::ZERO,
            generation: 0,
            max_displacement: 0.0,
            moved: vec![0; mesh_vertex_words],
            exclusion,
            other_exclusion: std::sync::OnceLock::new(),
            id: {
                static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
                NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
            },
        }
    }

    /// Whether no vertex of a triangle sharing a corner with `t` (`t` included) moved in the
    /// last successful [`TrackedSurface::set_positions`]: a local search at `t` sees the same
    /// geometry as before it.
    pub(crate) fn still_around(&self, t: u32) -> bool {
        let triangles = self.mesh.triangles();
        let moved = |v: u32| (self.moved[v as usize / 64] >> (v % 64)) & 1 != 0;
        triangles[t as usize].iter().all(|&c| {
            self.topology
                .vertex_triangles(c)
                .iter()
                .all(|&u| !triangles[u as usize].iter().any(|&v| moved(v)))
        })
    }

    /// Names the surface's topology (triangles, patches and edges): the same for a surface and
    /// its clones, different for surfaces built apart.
    pub(crate) fn topology_id(&self) -> u64 {
        self.id
    }

    /// Moves the vertices (same count, all finite), keeps the old positions as the previous
    /// frame's, and refits the patch tree (boxes and normal cones) where a vertex moved: a
    /// patch whose vertices all stayed keeps its boxes, normals and cone (they cannot have
    /// changed), so what this costs beyond a scan of the positions follows the part of the
    /// surface that moved. On error nothing changes.
    pub fn set_positions(&mut self, positions: &[Vec3]) -> Result<(), MeshError> {
        let started = std::time::Instant::now();
        self.previous.clear();
        self.previous.extend_from_slice(self.mesh.positions());
        if let Err(e) = self.mesh.set_positions(positions) {
            self.previous.clear();
            self.previous.extend_from_slice(self.mesh.positions());
            return Err(e);
        }
        // Only the patches with a vertex that moved are refitted and get new normals and
        // cones: the rest of the surface costs the scan that finds them. When most of it
        // moved, one pass over everything is quicker.
        self.patches
            .add_travel(&self.previous, self.mesh.positions());
        if self.patches.mostly_moved() {
            self.patches.refit(&self.mesh);
            triangle_normals(&self.mesh, &mut self.normals);
            self.patches
                .update_cones(&self.normals, self.mesh.positions());
        } else {
            self.patches.refit_moved(&self.mesh);
            for (p, patch) in self.patches.patches.iter().enumerate() {
                if self.patches.moved(p) {
                    for &t in &patch.triangles {
                        self.normals[t as usize] = triangle_normal(&self.mesh, t as usize);
                    }
                }
            }
            self.patches
                .update_moved_cones(&self.normals, self.mesh.positions());
        }
        self.moved.fill(0);
        let mut farthest = 0.0f32;
        for (i, (p, q)) in self.previous.iter().zip(self.mesh.positions()).enumerate() {
            if p != q {
                self.moved[i / 64] |= 1 << (i % 64);
                farthest = farthest.max(p.distance_squared(*q));
            }
        }
        self.max_displacement = farthest.sqrt();
        self.generation += 1;
        self.update_time = started.elapsed();
        Ok(())
    }

    /// How many times [`TrackedSurface::set_positions`] succeeded: a tracker compares it with
    /// the value at its last step to know whether the surface deformed since (and whether
    /// the previous positions are where the vertices were then).
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// The farthest any vertex moved in the last successful
    /// [`TrackedSurface::set_positions`] (0 before the first).
    pub fn max_displacement(&self) -> f32 {
        self.max_displacement
    }

    /// Wall-clock time of the last successful [`TrackedSurface::set_positions`] (positions,
    /// refit, normals and cones): the first line of a tracking frame's breakdown, before the
    /// step's [`StepTimes`](super::StepTimes).
    pub fn update_time(&self) -> std::time::Duration {
        self.update_time
    }

    /// The mesh at its current positions.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// The mesh's adjacency.
    pub fn topology(&self) -> &Topology {
        &self.topology
    }

    /// The pairs of triangles within `rings` vertex rings of each other on the welded mesh
    /// (self-collision leaves them out; see [`SelfExclusion::new`]). [`DEFAULT_EXCLUSION_RINGS`]
    /// has its [`SelfExclusion`] built with the surface, and the first other ring count asked
    /// for gets one built then (`O(triangles)`, about 64 bytes per triangle) and kept: its test
    /// is one merge of two short lists. Further ring counts walk the topology on every test.
    pub(crate) fn excluded_pairs(&self, rings: u32) -> ExcludedPairs<'_> {
        let (mesh, topology) = ring_mesh(&self.welded, &self.mesh, &self.topology);
        let (cached, reach) = if self.exclusion.0.rings() == rings {
            &self.exclusion
        } else {
            self.other_exclusion
                .get_or_init(|| exclusion_of(mesh, topology, &self.patches, rings))
        };
        if cached.rings() == rings {
            ExcludedPairs::Cached {
                exclusion: cached,
                reach,
                patch_of: &self.patches.patch_of,
            }
        } else {
            ExcludedPairs::Walk {
                mesh,
                topology,
                rings,
            }
        }
    }

    /// Mean edge length of the mesh as built (a natural unit for thickness and tolerances).
    pub fn mean_edge_length(&self) -> f32 {
        self.mean_edge
    }

    /// Diagonal of the mesh's box as built (the "object size" of Guy and Debunne's threshold).
    pub fn size(&self) -> f32 {
        self.size
    }

    /// Number of patches of the incomplete hierarchy.
    pub fn patch_count(&self) -> usize {
        self.patches.patches.len()
    }

    /// How far vertex `v` moved since the previous [`TrackedSurface::set_positions`].
    pub fn displacement(&self, v: u32) -> f32 {
        (self.mesh.positions()[v as usize] - self.previous[v as usize]).length()
    }

    /// Where vertex `v` was before the last [`TrackedSurface::set_positions`].
    pub(crate) fn previous_position(&self, v: u32) -> Vec3 {
        self.previous[v as usize]
    }

    /// The triangle containing the area fraction `u ∈ [0, 1)` (uniform over the rest area).
    pub(crate) fn triangle_at_area(&self, u: f64) -> u32 {
        let total = self.area_cdf.last().copied().unwrap_or(0.0);
        if total <= 0.0 {
            return ((u * self.area_cdf.len() as f64) as usize).min(self.area_cdf.len() - 1) as u32;
        }
        let x = u * total;
        self.area_cdf
            .partition_point(|&c| c <= x)
            .min(self.area_cdf.len() - 1) as u32
    }
}

/// The mesh whose rings self-collision counts: the welded one when welding joined corners.
fn ring_mesh<'a>(
    welded: &'a Option<Box<(TriMesh, Topology)>>,
    mesh: &'a TriMesh,
    topology: &'a Topology,
) -> (&'a TriMesh, &'a Topology) {
    match welded {
        Some(welded) => (&welded.0, &welded.1),
        None => (mesh, topology),
    }
}

/// The exclusion of `rings` rings on `mesh` (the [`ring_mesh`]), with the patches each of
/// `patches`' patches can be excluded with.
fn exclusion_of(
    mesh: &TriMesh,
    topology: &Topology,
    patches: &PatchTree,
    rings: u32,
) -> (SelfExclusion, PatchReach) {
    (
        SelfExclusion::from_topology(mesh, topology, rings),
        PatchReach::new(patches, mesh, topology, rings),
    )
}

/// Unit normals of `mesh`'s triangles (zero for degenerate ones), written to `out`.
fn triangle_normals(mesh: &TriMesh, out: &mut Vec<Vec3>) {
    out.clear();
    out.extend((0..mesh.triangle_count()).map(|t| triangle_normal(mesh, t)));
}

/// Triangle `t`'s unit normal (zero for a degenerate triangle).
#[inline]
fn triangle_normal(mesh: &TriMesh, t: usize) -> Vec3 {
    let [a, b, c] = mesh.triangle(t);
    (b - a).cross(c - a).normalize_or_zero()
}

/// A surface seen from a frame: its own (`pose == None`) or another mesh's.
#[derive(Clone, Copy)]
pub(crate) struct Placed<'a> {
    pub surface: &'a TrackedSurface,
    pub pose: Option<PoseF64>,
}

impl Placed<'_> {
    #[inline]
    pub fn point(&self, v: u32) -> DVec3 {
        let p = self.surface.mesh.positions()[v as usize];
        match &self.pose {
            None => p.as_dvec3(),
            Some(pose) => pose.transform_point(p),
        }
    }

    #[inline]
    pub fn triangle(&self, t: u32) -> [DVec3; 3] {
        self.surface.mesh.triangles()[t as usize].map(|v| self.point(v))
    }

    #[inline]
    pub fn corners(&self, t: u32) -> [u32; 3] {
        self.surface.mesh.triangles()[t as usize]
    }

    #[inline]
    pub fn topology(&self) -> &Topology {
        &self.surface.topology
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::deform::{Animation, Local, Whirl};
    use crate::mesh::generate;

    /// After every update, where only a ball of the tube moved, where all of it moved and
    /// where nothing moved, the surface is what a refit of everything gives: the same BVH
    /// boxes, patch boxes, normals, normal cones, collapse flags and overlapping patch pairs.
    #[test]
    fn the_update_of_the_moved_patches_equals_a_full_one() {
        let tube = generate::tube(0.1, 2.0, 24, 120, true);
        let whirl = Whirl::new(&tube, 80, 3);
        let local = Local::new(&tube, whirl.clone(), 0.12, 5);
        let mut surface = TrackedSurface::with_patch_size(tube.clone(), 32);
        let mut p = Vec::new();
        let mut partial = 0;
        for (k, frame) in [5, 10, 10, 15, 20, 25, 20, 30].into_iter().enumerate() {
            if k < 5 {
                local.positions(frame, &mut p);
            } else {
                whirl.positions(frame, &mut p);
            }
            surface.set_positions(&p).unwrap();
            let moved = (0..surface.patches.patches.len())
                .filter(|&i| surface.patches.moved(i))
                .count();
            if moved > 0 && moved < surface.patches.patches.len() {
                partial += 1;
            }
            let mut full = surface.patches.clone();
            full.refit(&surface.mesh);
            let mut normals = Vec::new();
            triangle_normals(&surface.mesh, &mut normals);
            full.update_cones(&normals, surface.mesh.positions());
            assert_eq!(surface.normals, normals, "update {k}");
            let boxes = |b: &crate::bvh::Bvh| -> Vec<(Vec3, Vec3)> {
                b.nodes().iter().map(|n| (n.min, n.max)).collect()
            };
            assert_eq!(boxes(&surface.patches.bvh), boxes(&full.bvh), "update {k}");
            for (a, b) in surface.patches.patches.iter().zip(&full.patches) {
                assert_eq!((a.min, a.max), (b.min, b.max), "update {k}");
                assert_eq!(
                    (a.cone_axis, a.cone_cos, a.cone_sin, a.collapsed),
                    (b.cone_axis, b.cone_cos, b.cone_sin, b.collapsed),
                    "update {k}"
                );
            }
            let overlaps = |t: &PatchTree| {
                let (mut stack, mut out) = (Vec::new(), Vec::new());
                t.self_overlaps(0.01, &mut stack, &mut out);
                out
            };
            assert_eq!(overlaps(&surface.patches), overlaps(&full), "update {k}");
        }
        assert!(partial >= 3, "{partial} updates moved part of the tube");
    }

    /// The cached exclusion (the first ring count asked for) and the walk (any other) both
    /// answer as `triangles_within_rings`, a triangle with itself included.
    /// The patch filter in front of the cached exclusion changes no answer, on a torus of many
    /// patches (where most patch pairs are far apart) and on the same torus as a triangle soup
    /// (every corner its own vertex: rings are counted on the welded mesh), for the ring
    /// count cached and others; and it does filter: most pairs are decided by it alone.
    #[test]
    fn the_patch_filter_changes_no_exclusion() {
        let torus = generate::torus(1.0, 0.3, 24, 12);
        let soup = TriMesh::new(
            torus
                .triangles()
                .iter()
                .flat_map(|t| t.map(|v| torus.positions()[v as usize]))
                .collect(),
            (0..torus.triangle_count() as u32)
                .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                .collect(),
        )
        .unwrap();
        for mesh in [torus.clone(), soup] {
            let welded = mesh.welded().into_owned();
            let topology = Topology::new(&welded);
            for rings in [2, 1, 3] {
                let surface = TrackedSurface::with_patch_size(mesh.clone(), 8);
                let ExcludedPairs::Cached {
                    exclusion,
                    reach,
                    patch_of,
                } = surface.excluded_pairs(rings)
                else {
                    panic!("the default and the first other ring count asked for are cached");
                };
                let n = mesh.triangle_count() as u32;
                let mut filtered = 0usize;
                for a in 0..n {
                    for b in 0..n {
                        let meet = reach.may_meet(patch_of[a as usize], patch_of[b as usize]);
                        let excluded = surface.excluded_pairs(rings).excludes(a, b);
                        assert_eq!(excluded, exclusion.excludes(a, b), "{rings} rings: {a} {b}");
                        filtered += usize::from(!meet);
                        if a % 7 == 0 && b % 5 == 0 {
                            let corners = |t: u32| welded.triangles()[t as usize];
                            let walk = a == b
                                || triangles_within_rings(&topology, corners(a), corners(b), rings);
                            assert_eq!(excluded, walk, "{rings} rings: {a} {b}");
                        }
                    }
                }
                assert!(filtered > (n * n) as usize / 2, "{rings} rings: {filtered}");
            }
        }
    }

    #[test]
    fn excluded_pairs_match_the_ring_walk() {
        let surface = TrackedSurface::new(generate::torus(1.0, 0.3, 12, 8));
        let (mesh, topology) = (surface.mesh(), surface.topology());
        let n = mesh.triangle_count() as u32;
        // The default ring count's exclusion is built with the surface, the first other one
        // asked for (1) on first use; 3 walks the topology.
        for rings in [2, 1, 3, 2, 1] {
            let excluded = surface.excluded_pairs(rings);
            assert_eq!(matches!(excluded, ExcludedPairs::Cached { .. }), rings != 3);
            for a in 0..n {
                for b in 0..n {
                    let corners = |t: u32| mesh.triangles()[t as usize];
                    let walk =
                        a == b || triangles_within_rings(topology, corners(a), corners(b), rings);
                    assert_eq!(excluded.excludes(a, b), walk, "{rings} rings: {a} {b}");
                }
            }
        }
    }

    /// A surface whose triangles each have their own corners (a seam along every edge)
    /// excludes what the mesh it was cut from excludes, cached and walked.
    #[test]
    fn excluded_pairs_join_seams_of_repeated_vertices() {
        let mesh = generate::torus(1.0, 0.3, 12, 8);
        let (whole, cut) = (
            TrackedSurface::new(mesh.clone()),
            TrackedSurface::new(crate::mesh::triangle_soup(&mesh)),
        );
        let n = mesh.triangle_count() as u32;
        for rings in [2, 1, 3] {
            let (a_pairs, b_pairs) = (whole.excluded_pairs(rings), cut.excluded_pairs(rings));
            for a in 0..n {
                for b in 0..n {
                    assert_eq!(
                        a_pairs.excludes(a, b),
                        b_pairs.excludes(a, b),
                        "{rings}: {a} {b}"
                    );
                }
            }
        }
    }
}
