//! The surface samples of an [`InteriorMap`](super::InteriorMap): vertices spread over the
//! mesh's surface, finer samples of each part of it, and per direction the vertices a mesh
//! leads with when it moves that way (where a collision begins and goes deepest).
use glam::Vec3;

use crate::bvh::{CollisionMesh, component_labels};

/// Samples looked up between two checks of whether the certificate is found (a multiple of 4,
/// at most 8: a chunk's 2-bit classes fill 16 bits).
pub const CERTIFY_CHUNK: usize = 8;

/// The component rank of samples whose component is not among the 63 largest: such samples
/// never certify (components are tracked in a `u64`).
pub(super) const NO_COMPONENT: u8 = 63;

/// Finer samples per coarse chunk, looked up only where the coarse samples came into or near
/// the other mesh ([`InteriorMap::look_up`](super::InteriorMap::look_up)): deep overlaps whose
/// coarse samples straddle the other surface without one inside it get a denser look there.
pub(super) const REFINEMENT: usize = 64;

/// Vertices from which the support samples' six cube faces are found on threads of their own.
const PARALLEL_SUPPORT_VERTICES: usize = 4096;

/// Direction bins along each side of a cube face for the support samples: `6 · n²` bins of
/// about `90° / n` each; 8 gives 384 bins of about 11°. Protruding parts (horns, arms, spikes)
/// that few evenly spread samples reach lead in some direction, so they get samples of their
/// own.
pub(super) const SUPPORT_BINS: u32 = 8;

/// Points on a mesh's surface (with their connected components), in chunks of
/// [`CERTIFY_CHUNK`] (padded by repeating the last sample): the coarse samples, then per coarse
/// chunk the finer samples of the same part of the surface, then one support chunk per
/// direction bin (a chunk of leading vertices, then one of trailing vertices).
#[derive(Debug, Clone, Default)]
pub(super) struct SurfaceSamples {
    /// The samples, a chunk at a time.
    pub chunks: Vec<ChunkSamples>,
    /// Per sample, the vertex it is.
    pub vertex: Vec<u32>,
    /// Per chunk of [`CERTIFY_CHUNK`] samples, a sphere around them (centre, radius).
    pub chunk_spheres: Vec<(Vec3, f32)>,
    /// Per chunk, bit `c` set for each component rank `c` of its samples.
    pub chunk_components: Vec<u64>,
    /// The coarse samples' chunks (the first ones); the refinement of coarse chunk `c` is the
    /// [`REFINEMENT`] samples after them at `coarse_chunks + c · REFINEMENT / CERTIFY_CHUNK`.
    pub coarse_chunks: usize,
    /// The chunk of direction bin 0's leading samples (its trailing ones follow, then the next
    /// bin's), if any.
    support_first: Option<usize>,
    /// The centre of the mesh's box: support directions are taken from it.
    pub centre: Vec3,
}

/// One chunk of samples: coordinates in structure-of-arrays form, for a vectorised transform,
/// and component ranks, together in two cache lines (a chunk looked up is read whole).
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(64))]
pub(super) struct ChunkSamples {
    pub x: [f32; CERTIFY_CHUNK],
    pub y: [f32; CERTIFY_CHUNK],
    pub z: [f32; CERTIFY_CHUNK],
    /// Per sample, the size rank of its connected component (below [`NO_COMPONENT`]), or
    /// [`NO_COMPONENT`].
    pub component: [u8; CERTIFY_CHUNK],
}

impl SurfaceSamples {
    /// Sample `j`'s point.
    #[inline]
    pub fn point(&self, j: usize) -> Vec3 {
        let c = &self.chunks[j / CERTIFY_CHUNK];
        let k = j % CERTIFY_CHUNK;
        Vec3::new(c.x[k], c.y[k], c.z[k])
    }

    /// Up to `count` coarse vertices spread over the surface of `mesh` (every connected
    /// component, in proportion to its triangles): one per equal share of the BVH's leaf
    /// order, so spatially coherent chunks; [`REFINEMENT`] finer ones per coarse chunk; and
    /// the support chunks of [`SUPPORT_BINS`].
    pub fn build(mesh: &CollisionMesh, count: usize) -> Self {
        let triangles = mesh.mesh().triangles();
        let positions = mesh.mesh().positions();
        let mut samples = SurfaceSamples {
            centre: mesh.mesh().aabb().center(),
            ..Self::default()
        };
        if triangles.is_empty() || count == 0 || !samples.centre.is_finite() {
            return samples;
        }
        let rank = component_ranks(mesh);
        let order = mesh.bvh().leaf_triangles();
        let count = count.min(order.len());
        let mut push = |vertex: u32| {
            let j = samples.vertex.len();
            if j.is_multiple_of(CERTIFY_CHUNK) {
                samples.chunks.push(ChunkSamples::default());
            }
            let (c, k) = (
                samples.chunks.last_mut().expect("pushed"),
                j % CERTIFY_CHUNK,
            );
            let p = positions[vertex as usize];
            (c.x[k], c.y[k], c.z[k]) = (p.x, p.y, p.z);
            c.component[k] = rank[vertex as usize];
            samples.vertex.push(vertex);
        };
        let vertex_at = |position: usize| triangles[order[position] as usize][0];
        // The coarse samples: one per equal share of the leaf order, padded to whole chunks.
        let coarse = count.next_multiple_of(CERTIFY_CHUNK);
        for j in 0..coarse {
            push(vertex_at(
                (j.min(count - 1) * order.len() + order.len() / 2) / count,
            ));
        }
        // The refinement of each coarse chunk: REFINEMENT samples spread over the share of the
        // leaf order its samples stand for.
        let share = |c: usize| (c * CERTIFY_CHUNK).min(count) * order.len() / count;
        for c in 0..coarse / CERTIFY_CHUNK {
            let (from, to) = (share(c), share(c + 1).max(share(c) + 1).min(order.len()));
            for j in 0..REFINEMENT {
                push(vertex_at(
                    from + (j * (to - from) + (to - from) / 2) / REFINEMENT,
                ));
            }
        }
        samples.coarse_chunks = coarse / CERTIFY_CHUNK;
        // The support chunks, of the vertices triangles use (finite ones: a mesh's are).
        let mut used = vec![false; positions.len()];
        for tri in triangles {
            for &v in tri {
                used[v as usize] = true;
            }
        }
        let used: Vec<u32> = (0..positions.len() as u32)
            .filter(|&v| used[v as usize] && positions[v as usize].is_finite())
            .collect();
        let centre = samples.centre;
        let support_first = (!used.is_empty()).then(|| {
            let first = (coarse + coarse / CERTIFY_CHUNK * REFINEMENT) / CERTIFY_CHUNK;
            for [leading, trailing] in support_chunks(positions, &used, &rank, centre) {
                leading.into_iter().chain(trailing).for_each(&mut push);
            }
            first
        });
        samples.support_first = support_first;
        samples.chunk_spheres = (0..samples.vertex.len())
            .step_by(CERTIFY_CHUNK)
            .map(|start| samples.sphere(start))
            .collect();
        samples.chunk_components = samples
            .chunks
            .iter()
            .map(|chunk| chunk.component.iter().fold(0, |bits, &c| bits | 1 << c))
            .collect();
        samples
    }

    /// A sphere around the chunk of samples from `start`, grown a little: it must hold them
    /// whatever the rounding.
    fn sphere(&self, start: usize) -> (Vec3, f32) {
        let points: Vec<Vec3> = (start..start + CERTIFY_CHUNK)
            .map(|j| self.point(j))
            .collect();
        let (lo, hi) = points.iter().fold((points[0], points[0]), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
        let centre = (lo + hi) * 0.5;
        let radius = points
            .iter()
            .map(|p| p.distance(centre))
            .fold(0.0, f32::max);
        (
            centre,
            radius * (1.0 + 1e-4) + 1e-6 * centre.abs().max_element(),
        )
    }

    /// The support chunks for `direction` (in the mesh's frame; need not be unit): the
    /// chunk of vertices that lead when the mesh moves that way, and the next chunk, of the
    /// vertices that trail, of the same components. `None` for a mesh without them or a
    /// direction that is zero or not finite.
    pub fn support_chunk(&self, direction: Vec3) -> Option<usize> {
        let first = self.support_first?;
        let (face, u, v) = cube_face(direction)?;
        let n = SUPPORT_BINS as f32;
        let bin = |t: f32| (((t + 1.0) * 0.5 * n) as u32).min(SUPPORT_BINS - 1);
        let (iu, iv) = (bin(u), bin(v));
        Some(first + 2 * ((face * SUPPORT_BINS + iv) * SUPPORT_BINS + iu) as usize)
    }
}

/// Per vertex, the size rank of its connected component (0 the largest by triangles; the ones
/// beyond the 63 largest share [`NO_COMPONENT`], which never certifies).
fn component_ranks(mesh: &CollisionMesh) -> Vec<u8> {
    let labels = component_labels(mesh.mesh());
    let mut sizes = std::collections::HashMap::<u32, usize>::new();
    for tri in mesh.mesh().triangles() {
        *sizes.entry(labels[tri[0] as usize]).or_default() += 1;
    }
    let mut ranked: Vec<(usize, u32)> = sizes.iter().map(|(&label, &n)| (n, label)).collect();
    ranked.sort_by_key(|&(n, label)| (std::cmp::Reverse(n), label));
    let rank: std::collections::HashMap<u32, u8> = ranked
        .iter()
        .enumerate()
        .map(|(i, &(_, label))| (label, i.min(usize::from(NO_COMPONENT)) as u8))
        .collect();
    labels
        .iter()
        .map(|label| rank.get(label).copied().unwrap_or(NO_COMPONENT))
        .collect()
}

/// The cube face a direction points through (0..6: +x, −x, +y, −y, +z, −z) and its two
/// coordinates on that face, in `[−1, 1]`; `None` for a zero or non-finite direction.
fn cube_face(d: Vec3) -> Option<(u32, f32, f32)> {
    let a = d.abs();
    if !d.is_finite() || a.max_element() <= 0.0 {
        return None;
    }
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let face = 2 * axis as u32 + u32::from(d[axis] < 0.0);
    let major = a[axis];
    Some((face, d[u] / major, d[v] / major))
}

/// The direction through point `(u, v)` of cube face `face` ([`cube_face`]'s inverse).
fn face_direction(face: u32, u: f32, v: f32) -> Vec3 {
    let axis = (face / 2) as usize;
    let mut d = Vec3::ZERO;
    d[axis] = if face.is_multiple_of(2) { 1.0 } else { -1.0 };
    d[(axis + 1) % 3] = u;
    d[(axis + 2) % 3] = v;
    d
}

/// Per direction bin (faces, then rows, then columns, as
/// [`SurfaceSamples::support_chunk`] numbers them), two chunks of vertices: the leading ones,
/// farthest along the bin (the support vertices of its four corner directions, distinct,
/// then the farthest along its centre direction), and for each of them the trailing one, the
/// vertex of its component farthest back along the bin's centre direction. A collision of the
/// mesh moving that way begins at its leading vertices and goes deepest there; the trailing
/// ones are the outside samples of the same surface that complete a certificate.
fn support_chunks(
    positions: &[Vec3],
    used: &[u32],
    rank: &[u8],
    centre: Vec3,
) -> Vec<[[u32; CERTIFY_CHUNK]; 2]> {
    let n = SUPPORT_BINS;
    let coordinate = |i: u32| -1.0 + 2.0 * i as f32 / n as f32;
    let relative: Vec<Vec3> = used
        .iter()
        .map(|&v| positions[v as usize] - centre)
        .collect();
    let farthest = |d: Vec3| {
        let mut best = (f32::NEG_INFINITY, used[0]);
        for (p, &v) in relative.iter().zip(used) {
            let h = p.dot(d);
            if h > best.0 {
                best = (h, v);
            }
        }
        best.1
    };
    // The bins of one cube face.
    let face_chunks = |face: u32| {
        // The support vertex of every corner direction of the face's bins.
        let corners: Vec<u32> = (0..(n + 1) * (n + 1))
            .map(|k| {
                farthest(face_direction(
                    face,
                    coordinate(k % (n + 1)),
                    coordinate(k / (n + 1)),
                ))
            })
            .collect();
        let mut chunks = Vec::with_capacity((n * n) as usize);
        for iv in 0..n {
            for iu in 0..n {
                let at = |du: u32, dv: u32| corners[((iv + dv) * (n + 1) + iu + du) as usize];
                let d = face_direction(
                    face,
                    coordinate(iu) + 1.0 / n as f32,
                    coordinate(iv) + 1.0 / n as f32,
                );
                let mut leading: Vec<u32> = Vec::with_capacity(CERTIFY_CHUNK);
                for v in [at(0, 0), at(1, 0), at(0, 1), at(1, 1)] {
                    if !leading.contains(&v) && leading.len() < CERTIFY_CHUNK {
                        leading.push(v);
                    }
                }
                // The rest: the farthest along the centre direction, and per
                // component the farthest back.
                let mut ahead: Vec<(f32, u32)> = Vec::with_capacity(CERTIFY_CHUNK + 1);
                let mut back = [(f32::INFINITY, u32::MAX); 64];
                for (p, &v) in relative.iter().zip(used) {
                    let h = p.dot(d);
                    let c = usize::from(rank[v as usize]);
                    if h < back[c].0 {
                        back[c] = (h, v);
                    }
                    if ahead.len() < CERTIFY_CHUNK || h > ahead[ahead.len() - 1].0 {
                        let at = ahead.partition_point(|&(g, _)| g >= h);
                        ahead.insert(at, (h, v));
                        ahead.truncate(CERTIFY_CHUNK);
                    }
                }
                for &(_, v) in &ahead {
                    if leading.len() < CERTIFY_CHUNK && !leading.contains(&v) {
                        leading.push(v);
                    }
                }
                while leading.len() < CERTIFY_CHUNK {
                    leading.push(leading[0]);
                }
                let leading: [u32; CERTIFY_CHUNK] = leading.try_into().expect("a whole chunk");
                let trailing = leading.map(|v| back[usize::from(rank[v as usize])].1);
                chunks.push([leading, trailing]);
            }
        }
        chunks
    };
    // Six faces in parallel where the mesh is large enough for threads to pay.
    let faces: Vec<Vec<[[u32; CERTIFY_CHUNK]; 2]>> = if used.len() < PARALLEL_SUPPORT_VERTICES {
        (0..6).map(face_chunks).collect()
    } else {
        std::thread::scope(|s| {
            let handles: Vec<_> = (0..6u32)
                .map(|face| s.spawn(move || face_chunks(face)))
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("support samples of a cube face"))
                .collect()
        })
    };
    faces.into_iter().flatten().collect()
}
