//! Nearness of two triangles of one mesh along its surface: sharing a vertex, or within a
//! number of vertex rings. Self-collision passes exclude such pairs (they touch or nearly touch
//! by construction).
use smallvec::SmallVec;

use super::Topology;

/// Two triangles of one mesh that share a vertex.
#[inline]
pub fn adjacent(a: [u32; 3], b: [u32; 3]) -> bool {
    a.iter().any(|v| b.contains(v))
}

/// A list of vertex indices, in place up to 64.
pub(crate) type VertexList = SmallVec<[u32; 64]>;

/// The vertices within a number of edge steps of some seed vertices, by a breadth-first walk
/// over [`Topology::vertex_neighbours`] whose buffers are reused from call to call (a vertex is
/// marked seen by stamping it with the walk's number: no search of the list found so far).
#[derive(Debug, Default, Clone)]
pub(crate) struct RingWalk {
    frontier: VertexList,
    next: VertexList,
    /// Per vertex, the number of the last walk that reached it.
    stamps: Vec<u32>,
    walk: u32,
}

impl RingWalk {
    /// Writes to `out` the distinct vertices at most `rings` edge steps from one of `seeds`:
    /// the seeds first (once each), then ring by ring (not sorted).
    pub fn collect(
        &mut self,
        topology: &Topology,
        seeds: &[u32],
        rings: u32,
        out: &mut VertexList,
    ) {
        out.clear();
        self.frontier.clear();
        if self.stamps.len() < topology.vertex_count() {
            self.stamps.resize(topology.vertex_count(), 0);
        }
        self.walk = self.walk.wrapping_add(1);
        if self.walk == 0 {
            self.stamps.fill(0);
            self.walk = 1;
        }
        let (stamps, walk) = (&mut self.stamps, self.walk);
        let mut first_visit = |v: u32| {
            let stamp = &mut stamps[v as usize];
            let new = *stamp != walk;
            *stamp = walk;
            new
        };
        for &v in seeds {
            if first_visit(v) {
                out.push(v);
                self.frontier.push(v);
            }
        }
        for _ in 0..rings {
            self.next.clear();
            for &u in &self.frontier {
                for &w in topology.vertex_neighbours(u) {
                    if first_visit(w) {
                        out.push(w);
                        self.next.push(w);
                    }
                }
            }
            if self.next.is_empty() {
                break;
            }
            std::mem::swap(&mut self.frontier, &mut self.next);
        }
    }
}

/// Whether triangles `a` and `b` of a mesh with `topology` are within `rings` edge steps of
/// each other: with 0 they share a vertex; with 1 they share a vertex or an edge joins a
/// vertex of one to a vertex of the other; and so on. Self-collision excludes such pairs.
pub fn triangles_within_rings(topology: &Topology, a: [u32; 3], b: [u32; 3], rings: u32) -> bool {
    if adjacent(a, b) {
        return true;
    }
    match rings {
        0 => false,
        1 => a
            .iter()
            .any(|&v| topology.vertex_neighbours(v).iter().any(|w| b.contains(w))),
        2 => {
            // Within two steps: some vertex of `a` and some vertex of `b` are neighbours or
            // share a neighbour (a merge of two ascending lists).
            a.iter().any(|&v| {
                let nv = topology.vertex_neighbours(v);
                b.iter().any(|&u| {
                    let nu = topology.vertex_neighbours(u);
                    if nv.binary_search(&u).is_ok() {
                        return true;
                    }
                    let (mut i, mut j) = (0, 0);
                    while i < nv.len() && j < nu.len() {
                        match nv[i].cmp(&nu[j]) {
                            std::cmp::Ordering::Less => i += 1,
                            std::cmp::Ordering::Greater => j += 1,
                            std::cmp::Ordering::Equal => return true,
                        }
                    }
                    false
                })
            })
        }
        _ => {
            // Some vertex of `b` within `rings` steps of `a`'s corners.
            let mut near = VertexList::new();
            RingWalk::default().collect(topology, &a, rings, &mut near);
            b.iter().any(|v| near.contains(v))
        }
    }
}

/// The pairs of triangles of one mesh that a self-collision pass leaves out: those within
/// `rings` vertex rings of each other ([`triangles_within_rings`]), decided by one merge of two
/// short sorted lists computed once per triangle.
///
/// Two triangles are within `r` rings when some vertex of one is at most `r` edges from some
/// vertex of the other. That holds exactly when the vertices within `⌈r/2⌉` edges of one
/// triangle and those within `⌊r/2⌋` edges of the other share a vertex; both sets are stored per
/// triangle as sorted lists (about 12 entries for two rings on a regular mesh: one 64-byte
/// line per triangle and list, longer lists in a shared array). Build it once per mesh; it holds for any positions of that mesh.
///
/// Rings are counted on the [welded](super::TriMesh::welded) mesh: a mesh whose seams or poles
/// repeat a vertex (the same position under two indices) does not report the triangles along
/// them as touching each other.
///
/// # Example
/// ```
/// use stochastic_collision::mesh::{SelfExclusion, Topology, generate, triangles_within_rings};
/// let sheet = generate::cloth_grid(1.0, 1.0, 6, 6);
/// let exclusion = SelfExclusion::new(&sheet, 2);
/// let topology = Topology::new(&sheet);
/// let tris = sheet.triangles();
/// for a in 0..tris.len() as u32 {
///     for b in 0..tris.len() as u32 {
///         assert_eq!(
///             exclusion.excludes(a, b),
///             triangles_within_rings(&topology, tris[a as usize], tris[b as usize], 2)
///         );
///     }
/// }
/// ```
#[derive(Debug, Clone)]
pub struct SelfExclusion {
    rings: u32,
    vertices: usize,
    /// Per triangle, the sorted vertices within `⌈rings/2⌉` edges of a corner.
    outer: Neighbourhoods,
    /// The same within `⌊rings/2⌋` edges, kept only when that differs (odd `rings`).
    inner: Option<Neighbourhoods>,
}

impl SelfExclusion {
    /// The exclusion of pairs within `rings` rings on `mesh` (0: pairs sharing a vertex).
    ///
    /// Rings are counted on the [welded](super::TriMesh::welded) mesh: vertices at one position
    /// (an unwelded seam or pole) are one vertex, so triangles on either side of a seam are
    /// neighbours, never a self-contact. On a mesh without such vertices this is
    /// [`triangles_within_rings`] on its own [`Topology`].
    pub fn new(mesh: &super::TriMesh, rings: u32) -> Self {
        let welded = mesh.welded();
        Self::build(&welded, &Topology::new(&welded), rings)
    }

    /// The same, reusing the mesh's [`Topology`] when it is already at hand (it is used only
    /// when welding changes nothing; otherwise the welded mesh's topology is built).
    pub fn from_topology(mesh: &super::TriMesh, topology: &Topology, rings: u32) -> Self {
        match mesh.welded() {
            std::borrow::Cow::Borrowed(mesh) => Self::build(mesh, topology, rings),
            std::borrow::Cow::Owned(welded) => Self::build(&welded, &Topology::new(&welded), rings),
        }
    }

    /// The exclusion on `mesh` as it is (no welding), with its `topology`.
    fn build(mesh: &super::TriMesh, topology: &Topology, rings: u32) -> Self {
        SelfExclusion {
            rings,
            vertices: mesh.vertex_count(),
            outer: Neighbourhoods::new(mesh, topology, rings.div_ceil(2)),
            inner: (rings % 2 == 1).then(|| Neighbourhoods::new(mesh, topology, rings / 2)),
        }
    }

    /// How many rings are excluded.
    pub fn rings(&self) -> u32 {
        self.rings
    }

    /// Vertex and triangle counts of the mesh it was built for.
    pub fn mesh_size(&self) -> (usize, usize) {
        (self.vertices, self.outer.short.len())
    }

    /// Triangle `t`'s two sorted vertex lists: `excludes(a, b)` is whether the first of `a`
    /// meets the second of `b`.
    pub(crate) fn lists(&self, t: u32) -> (&[u32], &[u32]) {
        (
            self.outer.get(t),
            self.inner.as_ref().unwrap_or(&self.outer).get(t),
        )
    }

    /// Asks for triangle `t`'s lists to be brought into the cache, for a
    /// [`SelfExclusion::lists`] or [`SelfExclusion::excludes`] on it soon after (a hint: no
    /// effect on any answer).
    #[inline]
    pub(crate) fn prefetch_lists(&self, t: u32) {
        if (t as usize) < self.outer.short.len() {
            self.outer.prefetch(t);
            if let Some(inner) = &self.inner {
                inner.prefetch(t);
            }
        }
    }

    /// Whether triangles `a` and `b` (indices into the mesh it was built for) are within the
    /// excluded rings: the same answer as [`triangles_within_rings`] on their corners in the
    /// welded mesh.
    ///
    /// # Panics
    /// If `a` or `b` is not a triangle of that mesh.
    #[inline]
    pub fn excludes(&self, a: u32, b: u32) -> bool {
        let list_b = self.inner.as_ref().unwrap_or(&self.outer).get(b);
        sorted_lists_meet(self.outer.get(a), list_b)
    }
}

/// Entries a triangle's list holds in place (one cache line with its length).
const SHORT: usize = 15;

/// A triangle's sorted list when it is short enough, in one cache line.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
struct ShortList {
    /// Entries in `items`, or `u32::MAX` when the list is in the long lists.
    len: u32,
    items: [u32; SHORT],
}

/// Per triangle, a sorted list of vertices: in place when short, else in a CSR array.
#[derive(Debug, Clone)]
struct Neighbourhoods {
    short: Vec<ShortList>,
    /// CSR offsets (`triangle count + 1`) into `long`; only long lists have entries.
    long_offsets: Vec<u32>,
    long: Vec<u32>,
}

impl Neighbourhoods {
    /// Per triangle of `mesh`, the sorted vertices at most `k` edges from one of its corners
    /// (the corners included).
    fn new(mesh: &super::TriMesh, topology: &Topology, k: u32) -> Self {
        let mut out = Neighbourhoods {
            short: Vec::with_capacity(mesh.triangle_count()),
            long_offsets: Vec::with_capacity(mesh.triangle_count() + 1),
            long: Vec::new(),
        };
        out.long_offsets.push(0);
        let mut seen = VertexList::new();
        let mut walk = RingWalk::default();
        for corners in mesh.triangles() {
            walk.collect(topology, corners, k, &mut seen);
            seen.sort_unstable();
            let mut list = ShortList {
                len: u32::MAX,
                items: [0; SHORT],
            };
            if seen.len() <= SHORT {
                list.len = seen.len() as u32;
                list.items[..seen.len()].copy_from_slice(&seen);
            } else {
                out.long.extend_from_slice(&seen);
            }
            out.short.push(list);
            out.long_offsets.push(out.long.len() as u32);
        }
        out
    }

    /// Asks for triangle `t`'s list to be brought into the cache when it is held in place (a
    /// long list's entries, in the shared array, are not asked for: only its length).
    #[inline]
    fn prefetch(&self, t: u32) {
        let list = &self.short[t as usize];
        crate::prefetch::prefetch(std::ptr::from_ref(list).cast());
    }

    #[inline]
    fn get(&self, t: u32) -> &[u32] {
        let list = &self.short[t as usize];
        if list.len != u32::MAX {
            &list.items[..list.len as usize]
        } else {
            let (s, e) = (
                self.long_offsets[t as usize] as usize,
                self.long_offsets[t as usize + 1] as usize,
            );
            &self.long[s..e]
        }
    }
}

/// Whether two ascending lists share an entry (a merge without unpredictable branches).
#[inline]
fn sorted_lists_meet(a: &[u32], b: &[u32]) -> bool {
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        let (x, y) = (a[i], b[j]);
        if x == y {
            return true;
        }
        i += (x < y) as usize;
        j += (y < x) as usize;
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    /// Edge steps from the nearest of `seeds` to every vertex (`u32::MAX`: unreachable), by a
    /// plain breadth-first labelling of the whole mesh: the reference for the ring tests.
    fn edge_steps(topo: &Topology, seeds: &[u32]) -> Vec<u32> {
        let mut dist = vec![u32::MAX; topo.vertex_count()];
        let mut queue = std::collections::VecDeque::new();
        for &v in seeds {
            if dist[v as usize] == u32::MAX {
                dist[v as usize] = 0;
                queue.push_back(v);
            }
        }
        while let Some(v) = queue.pop_front() {
            for &w in topo.vertex_neighbours(v) {
                if dist[w as usize] == u32::MAX {
                    dist[w as usize] = dist[v as usize] + 1;
                    queue.push_back(w);
                }
            }
        }
        dist
    }

    /// One walk reused over many seeds, ring counts and two meshes of different sizes finds
    /// what a fresh breadth-first labelling finds (stamps of earlier walks never leak).
    #[test]
    fn a_reused_walk_finds_each_ring_anew() {
        let meshes = [
            generate::torus(1.0, 0.3, 24, 12),
            generate::cloth_grid(1.0, 1.0, 5, 5),
        ];
        let mut walk = RingWalk::default();
        let mut out = VertexList::new();
        for step in 0..400usize {
            let mesh = &meshes[step % 2];
            let topo = Topology::new(mesh);
            let seed = (step * 7919 % mesh.vertex_count()) as u32;
            let seeds = [seed, (seed + 1) % mesh.vertex_count() as u32, seed];
            let rings = (step % 4) as u32;
            walk.collect(&topo, &seeds, rings, &mut out);
            let dist = edge_steps(&topo, &seeds);
            let mut expected: Vec<u32> = (0..mesh.vertex_count() as u32)
                .filter(|&v| dist[v as usize] <= rings)
                .collect();
            let mut found = out.to_vec();
            found.sort_unstable();
            expected.sort_unstable();
            // Every vertex within the rings, once.
            assert_eq!(found, expected, "step {step}");
            // Seeds first, then ring by ring.
            assert!(
                out.windows(2)
                    .all(|w| dist[w[0] as usize] <= dist[w[1] as usize])
            );
        }
    }

    /// A mesh whose every triangle has its own copies of its corners (a seam along every
    /// edge) excludes the same pairs as the mesh it was cut from.
    #[test]
    fn seams_of_repeated_vertices_are_not_gaps_in_the_rings() {
        let mesh = generate::torus(1.0, 0.3, 16, 8);
        let soup = crate::mesh::triangle_soup(&mesh);
        let soup_topology = Topology::new(&soup);
        for rings in 0..4 {
            let (whole, cut) = (
                SelfExclusion::new(&mesh, rings),
                SelfExclusion::from_topology(&soup, &soup_topology, rings),
            );
            let mut excluded = 0;
            for a in 0..mesh.triangle_count() as u32 {
                for b in 0..mesh.triangle_count() as u32 {
                    assert_eq!(whole.excludes(a, b), cut.excludes(a, b), "{a} {b} {rings}");
                    excluded += usize::from(cut.excludes(a, b) && a != b);
                }
            }
            // Unwelded, only a triangle with itself would share a vertex.
            assert!(
                excluded >= mesh.triangle_count() * 12,
                "{excluded} at {rings}"
            );
        }
    }

    #[test]
    fn ring_fast_paths_agree_with_the_search() {
        let mesh = generate::torus(1.0, 0.3, 24, 12);
        let topo = Topology::new(&mesh);
        let tris = mesh.triangles();
        // Reference: edge steps from `a`'s corners to every vertex, then the nearest corner
        // of `b`.
        let slow = |a: [u32; 3], b: [u32; 3], rings: u32| {
            let dist = edge_steps(&topo, &a);
            b.iter().map(|&v| dist[v as usize]).min().unwrap() <= rings
        };
        for i in (0..tris.len()).step_by(37) {
            for j in 0..tris.len() {
                for rings in 0..4 {
                    assert_eq!(
                        triangles_within_rings(&topo, tris[i], tris[j], rings),
                        slow(tris[i], tris[j], rings),
                        "{i} {j} {rings}"
                    );
                }
            }
        }
    }
}
