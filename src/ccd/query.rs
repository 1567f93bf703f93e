//! The continuous query between two meshes: the first time of impact over a step.
use glam::{DVec3, Vec3};

use super::primitive::{
    CcdScratch, PrimitiveTolerances, Trajectory, edge_edge_time, vertex_face_time,
};
use super::swept::{DeformingPiece, RigidPiece, SweptMesh, chord_deviation, mesh_radius};
use crate::bvh::{CollisionMesh, ExactOptions, QueryWorkspace, TrianglePair, intersects_with};
use crate::geometry::{Pose, closest_points_segment_segment, closest_points_triangle_triangle};

/// How a rigid mesh moves over the step: from `start` to `end`, its translation linearly and
/// its rotation at a constant rate about one axis (spherical interpolation, the shorter way).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidMotion {
    /// The pose at the start of the step.
    pub start: Pose,
    /// The pose at the end of the step.
    pub end: Pose,
}

impl RigidMotion {
    /// A motion from `start` to `end`.
    pub fn new(start: Pose, end: Pose) -> Self {
        Self { start, end }
    }

    /// A mesh that stays at `pose`.
    pub fn still(pose: Pose) -> Self {
        Self {
            start: pose,
            end: pose,
        }
    }

    /// The pose at time `t ∈ [0, 1]` of the step.
    pub fn at(&self, t: f32) -> Pose {
        Pose::new(
            self.start.translation.lerp(self.end.translation, t),
            self.start.rotation.slerp(self.end.rotation, t),
        )
    }

    /// The angle the mesh turns through over the step (radians, in `[0, π]`).
    pub fn angle(&self) -> f64 {
        let (a, b) = (self.start.rotation.as_dquat(), self.end.rotation.as_dquat());
        let d = a.normalize().dot(b.normalize()).abs().min(1.0);
        2.0 * d.acos()
    }
}

/// Tolerances of the continuous query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CcdOptions {
    /// Features closer than this (world units, in each coordinate) count as touching: the
    /// query reports contact when the meshes come this close, and never later than they
    /// touch. Default `1e-5`.
    pub distance_tolerance: f32,
    /// The time resolution of the answer where features move fast (a fraction of the step).
    /// Default `1e-5`.
    pub time_tolerance: f32,
    /// A rotating mesh's step is cut into pieces over which its vertices stray at most
    /// `distance_tolerance / 2` from straight paths; at most this many (beyond, each piece's
    /// tolerance grows by what its vertices stray: still conservative, less precise).
    /// Default 4096.
    pub max_pieces: u32,
}

impl Default for CcdOptions {
    fn default() -> Self {
        Self {
            distance_tolerance: 1e-5,
            time_tolerance: 1e-5,
            max_pieces: 4096,
        }
    }
}

/// Which features meet at the time of impact.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImpactFeatures {
    /// A vertex of the first mesh reaches a face of the second.
    VertexFace {
        /// The first mesh's vertex.
        vertex: u32,
    },
    /// A vertex of the second mesh reaches a face of the first.
    FaceVertex {
        /// The second mesh's vertex.
        vertex: u32,
    },
    /// The surfaces already cross at the start of the step (time 0): the witness triangles
    /// intersect.
    Overlapping,
    /// An edge of each mesh (their vertex indices).
    EdgeEdge {
        /// The first mesh's edge.
        a: [u32; 2],
        /// The second mesh's edge.
        b: [u32; 2],
    },
}

/// The first contact of two moving meshes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimeOfImpact {
    /// When, as a fraction of the step in `[0, 1]`: never after the meshes first touch, and
    /// no earlier than the last moment they were more than the distance tolerance apart (up
    /// to the time tolerance).
    pub time: f32,
    /// Where, in world coordinates.
    pub point: Vec3,
    /// The contact normal, a unit vector pointing from the second mesh towards the first.
    pub normal: Vec3,
    /// The triangles that meet.
    pub triangles: TrianglePair,
    /// The features that meet.
    pub features: ImpactFeatures,
}

/// A continuous query's input that cannot be answered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CcdError {
    /// A pose has a NaN or infinite part, or a zero rotation.
    #[error("{which} mesh's {end} pose is not finite: {pose:?}")]
    InvalidPose {
        /// "first" or "second".
        which: &'static str,
        /// "start" or "end".
        end: &'static str,
        /// The pose.
        pose: Pose,
    },
    /// The two states of a deforming mesh are not the same mesh.
    #[error(
        "{which} deforming mesh: its start and end differ in topology or tree ({start_triangles} \
         and {end_triangles} triangles, {start_nodes} and {end_nodes} nodes)"
    )]
    MismatchedStates {
        /// "first" or "second".
        which: &'static str,
        /// Triangles at the start.
        start_triangles: usize,
        /// Triangles at the end.
        end_triangles: usize,
        /// Tree nodes at the start.
        start_nodes: usize,
        /// Tree nodes at the end.
        end_nodes: usize,
    },
}

/// Reusable scratch memory of the continuous queries.
#[derive(Debug, Default, Clone)]
pub struct CcdWorkspace {
    stack: Vec<(u32, u32)>,
    exact: QueryWorkspace,
    scratch: CcdScratch,
    /// Triangle pairs tested by the last query.
    pub triangle_pairs: u64,
}

impl CcdWorkspace {
    /// An empty workspace.
    pub fn new() -> Self {
        Self::default()
    }
}

/// The first time of impact of two rigid meshes moving over a step, or `None` if they do not
/// touch during it (see [`TimeOfImpact::time`] for what is promised). Meshes that touch at the
/// start have time 0. Surfaces are what collide, as in the discrete [`intersects`]: a mesh
/// wholly inside another at the start does not touch it.
///
/// Every vertex–face and edge–edge pair whose swept boxes meet is solved by an inclusion-based
/// root finder (see [`vertex_face_time`]); a rotating mesh's step is cut into pieces short
/// enough that its vertices' paths are straight within the tolerance.
///
/// [`intersects`]: crate::bvh::intersects
///
/// # Example
/// A ball that passes through a thin wall within one step, which no discrete test sees:
/// ```
/// use stochastic_collision::ccd::{CcdOptions, CcdWorkspace, RigidMotion, time_of_impact};
/// use stochastic_collision::prelude::*;
///
/// let ball = CollisionMesh::new(generate::icosphere(0.5, 2));
/// let wall = CollisionMesh::new(generate::cuboid(Vec3::new(0.05, 2.0, 2.0), 1));
/// let shot = RigidMotion::new(
///     Pose::from_translation(Vec3::new(-3.0, 0.0, 0.0)),
///     Pose::from_translation(Vec3::new(3.0, 0.0, 0.0)),
/// );
/// let still = RigidMotion::still(Pose::IDENTITY);
/// let mut ws = CcdWorkspace::new();
/// let hit = time_of_impact(&ball, &shot, &wall, &still, &CcdOptions::default(), &mut ws)
///     .unwrap()
///     .expect("the ball hits the wall");
/// // The ball's surface (radius 0.5) meets the wall's face (x = -0.05) after 2.45 of 6 units.
/// assert!((hit.time - 2.45 / 6.0).abs() < 1e-3);
/// assert!(hit.normal.x < -0.9); // from the wall towards the ball
/// ```
pub fn time_of_impact(
    a: &CollisionMesh,
    motion_a: &RigidMotion,
    b: &CollisionMesh,
    motion_b: &RigidMotion,
    options: &CcdOptions,
    ws: &mut CcdWorkspace,
) -> Result<Option<TimeOfImpact>, CcdError> {
    for (which, m) in [("first", motion_a), ("second", motion_b)] {
        for (end, pose) in [("start", m.start), ("end", m.end)] {
            if !pose.is_finite() {
                return Err(CcdError::InvalidPose { which, end, pose });
            }
        }
    }
    ws.triangle_pairs = 0;
    if let Some(hit) = overlap_at_start(a, &motion_a.start, b, &motion_b.start, ws) {
        return Ok(Some(hit));
    }
    let delta = options.distance_tolerance.max(0.0) as f64;
    let pieces_for = |mesh: &CollisionMesh, m: &RigidMotion| {
        let angle = m.angle();
        if angle == 0.0 {
            return 1u32;
        }
        // Pieces short enough that the sagitta stays within delta / 4 per mesh.
        let radius = mesh_radius(mesh).max(1e-30);
        let allowed = 2.0 * (1.0 - (0.25 * delta / radius).min(1.0)).acos();
        (angle / allowed.max(1e-12))
            .ceil()
            .min(options.max_pieces as f64) as u32
    };
    // Pieces over which the meshes move about twice a leaf's size: each piece's swept boxes
    // stay tight, and pieces are searched in time order, so the search ends at the first
    // piece with a contact.
    let travel = |mesh: &CollisionMesh, m: &RigidMotion| {
        (m.end.translation - m.start.translation).length() as f64 + mesh_radius(mesh) * m.angle()
    };
    let leaf = leaf_size(a).min(leaf_size(b)).max(1e-30);
    let by_travel = ((travel(a, motion_a) + travel(b, motion_b)) / (2.0 * leaf))
        .ceil()
        .min(options.max_pieces as f64) as u32;
    let pieces = pieces_for(a, motion_a)
        .max(pieces_for(b, motion_b))
        .max(by_travel)
        .clamp(1, options.max_pieces.max(1));
    let stray = chord_deviation(mesh_radius(a), motion_a.angle() / pieces as f64)
        + chord_deviation(mesh_radius(b), motion_b.angle() / pieces as f64);
    let tol = PrimitiveTolerances {
        distance: delta + stray,
        time: (options.time_tolerance.max(0.0) as f64 * pieces as f64).min(1.0),
        ..Default::default()
    };
    for k in 0..pieces {
        let (s0, s1) = (k as f32 / pieces as f32, (k + 1) as f32 / pieces as f32);
        let pa = RigidPiece::new(a, motion_a.at(s0), motion_a.at(s1));
        let pb = RigidPiece::new(b, motion_b.at(s0), motion_b.at(s1));
        if let Some(hit) = first_impact(&pa, &pb, &tol, ws) {
            return Ok(Some(TimeOfImpact {
                time: ((k as f64 + hit.time as f64) / pieces as f64) as f32,
                ..hit
            }));
        }
    }
    Ok(None)
}

/// A typical leaf box's size: the root box's diagonal over the square root of the number of
/// leaves (leaves tile a surface).
fn leaf_size(mesh: &CollisionMesh) -> f64 {
    let leaves = mesh.bvh().nodes().len().div_ceil(2).max(1) as f64;
    let root = mesh.bvh().root_aabb();
    (root.max - root.min).as_dvec3().length() / leaves.sqrt()
}

/// The first time of impact of two deforming meshes whose vertices move linearly from their
/// positions in `start` to those in `end` (world coordinates; each pair of states is one mesh
/// before and after [`CollisionMesh::set_positions`], so that their trees have one
/// structure), or `None`. What is promised is as for [`time_of_impact`].
pub fn deforming_time_of_impact(
    a: (&CollisionMesh, &CollisionMesh),
    b: (&CollisionMesh, &CollisionMesh),
    options: &CcdOptions,
    ws: &mut CcdWorkspace,
) -> Result<Option<TimeOfImpact>, CcdError> {
    for (which, (start, end)) in [("first", a), ("second", b)] {
        let same = start.mesh().triangles() == end.mesh().triangles()
            && start.bvh().nodes().len() == end.bvh().nodes().len()
            && start.bvh().leaf_triangles() == end.bvh().leaf_triangles();
        if !same {
            return Err(CcdError::MismatchedStates {
                which,
                start_triangles: start.mesh().triangle_count(),
                end_triangles: end.mesh().triangle_count(),
                start_nodes: start.bvh().nodes().len(),
                end_nodes: end.bvh().nodes().len(),
            });
        }
    }
    ws.triangle_pairs = 0;
    if let Some(hit) = overlap_at_start(a.0, &Pose::IDENTITY, b.0, &Pose::IDENTITY, ws) {
        return Ok(Some(hit));
    }
    let tol = PrimitiveTolerances {
        distance: options.distance_tolerance.max(0.0) as f64,
        time: options.time_tolerance.max(0.0) as f64,
        ..Default::default()
    };
    let pa = DeformingPiece {
        start: a.0,
        end: a.1,
    };
    let pb = DeformingPiece {
        start: b.0,
        end: b.1,
    };
    Ok(first_impact(&pa, &pb, &tol, ws))
}

/// A contact at time 0 if the surfaces already cross at the start (feature pairs that cross
/// do not *come* into contact, so the root finder alone would not see them): at the witness
/// triangles, with the second triangle's normal turned towards the first.
fn overlap_at_start(
    a: &CollisionMesh,
    pose_a: &Pose,
    b: &CollisionMesh,
    pose_b: &Pose,
    ws: &mut CcdWorkspace,
) -> Option<TimeOfImpact> {
    let out = intersects_with(
        a,
        pose_a,
        b,
        pose_b,
        &ExactOptions::default(),
        &mut ws.exact,
    );
    let pair = out.witness?;
    let (pa, pb) = (pose_a.to_f64(), pose_b.to_f64());
    let ta = a
        .mesh()
        .triangle(pair.a as usize)
        .map(|p| pa.transform_point(p));
    let tb = b
        .mesh()
        .triangle(pair.b as usize)
        .map(|p| pb.transform_point(p));
    let meet = closest_points_triangle_triangle(&ta, &tb);
    let n = (tb[1] - tb[0]).cross(tb[2] - tb[0]).normalize_or(DVec3::X);
    let towards = (ta[0] + ta[1] + ta[2] - tb[0] - tb[1] - tb[2]).dot(n);
    let n = if towards < 0.0 { -n } else { n };
    Some(TimeOfImpact {
        time: 0.0,
        point: (0.5 * (meet.point_a + meet.point_b)).as_vec3(),
        normal: n.as_vec3(),
        triangles: pair,
        features: ImpactFeatures::Overlapping,
    })
}

/// The earliest contact over one piece (time as a fraction of the piece).
fn first_impact(
    a: &impl SweptMesh,
    b: &impl SweptMesh,
    tol: &PrimitiveTolerances,
    ws: &mut CcdWorkspace,
) -> Option<TimeOfImpact> {
    let margin = tol.distance as f32 * 1.01;
    let mut best: Option<(f64, Candidate)> = None;
    ws.stack.clear();
    ws.stack.push((0, 0));
    while let Some((i, j)) = ws.stack.pop() {
        let (bi, bj) = (a.node_box(i as usize), b.node_box(j as usize));
        if !bi.inflated(margin).intersects(&bj) {
            continue;
        }
        let (ni, nj) = (&a.bvh().nodes()[i as usize], &b.bvh().nodes()[j as usize]);
        match (ni.is_leaf(), nj.is_leaf()) {
            (true, true) => {
                for &ta in a.bvh().triangles_of(ni) {
                    for &tb in b.bvh().triangles_of(nj) {
                        ws.triangle_pairs += 1;
                        let limit = best.as_ref().map_or(1.0 + 1e-12, |(t, _)| *t);
                        if let Some(found) =
                            triangle_pair(a, ta, b, tb, tol, limit, &mut ws.scratch)
                            && best.as_ref().is_none_or(|(t, _)| found.0 < *t)
                        {
                            best = Some(found);
                        }
                    }
                }
            }
            // Descend the larger box (or the only inner node).
            (false, true) => push_children(&mut ws.stack, ni.left(), j, true),
            (true, false) => push_children(&mut ws.stack, i, nj.left(), false),
            (false, false) => {
                if bi.surface_area() >= bj.surface_area() {
                    push_children(&mut ws.stack, ni.left(), j, true);
                } else {
                    push_children(&mut ws.stack, i, nj.left(), false);
                }
            }
        }
    }
    best.map(|(t, c)| c.impact(a, b, t))
}

fn push_children(stack: &mut Vec<(u32, u32)>, i: u32, j: u32, first: bool) {
    if first {
        stack.extend([(i, j), (i + 1, j)]);
    } else {
        stack.extend([(i, j), (i, j + 1)]);
    }
}

/// Which features a root was found for (vertex indices of the meshes).
#[derive(Debug, Clone, Copy)]
enum Meeting {
    VertexFace(u32),
    FaceVertex(u32),
    EdgeEdge([u32; 2], [u32; 2]),
}

impl Meeting {
    fn features(self) -> ImpactFeatures {
        match self {
            Meeting::VertexFace(vertex) => ImpactFeatures::VertexFace { vertex },
            Meeting::FaceVertex(vertex) => ImpactFeatures::FaceVertex { vertex },
            Meeting::EdgeEdge(a, b) => ImpactFeatures::EdgeEdge { a, b },
        }
    }
}

/// The features found to meet first, before their contact is worked out.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    triangles: TrianglePair,
    features: Meeting,
}

/// The earliest contact of triangle `ta` of `a` and `tb` of `b` before `limit`: the six
/// vertex–face and nine edge–edge tests, each bounded by the earliest found so far.
fn triangle_pair(
    a: &impl SweptMesh,
    ta: u32,
    b: &impl SweptMesh,
    tb: u32,
    tol: &PrimitiveTolerances,
    mut limit: f64,
    scratch: &mut CcdScratch,
) -> Option<(f64, Candidate)> {
    let (fa, fb) = (a.triangles()[ta as usize], b.triangles()[tb as usize]);
    let (va, vb) = (fa.map(|v| a.vertex(v)), fb.map(|v| b.vertex(v)));
    let edge = |k: usize| [k, (k + 1) % 3];
    let meetings = (0..3)
        .flat_map(|k| [Meeting::VertexFace(k as u32), Meeting::FaceVertex(k as u32)])
        .chain((0..9).map(|k| {
            let (i, j) = (edge(k / 3), edge(k % 3));
            Meeting::EdgeEdge(i.map(|x| x as u32), j.map(|x| x as u32))
        }));
    let mut best = None;
    // Meetings are built with corner numbers (0..3) and reported with vertex indices.
    for m in meetings {
        let (t, features) = match m {
            Meeting::VertexFace(k) => (
                vertex_face_time(&va[k as usize], &vb, tol, limit, scratch),
                Meeting::VertexFace(fa[k as usize]),
            ),
            Meeting::FaceVertex(k) => (
                vertex_face_time(&vb[k as usize], &va, tol, limit, scratch),
                Meeting::FaceVertex(fb[k as usize]),
            ),
            Meeting::EdgeEdge(i, j) => (
                edge_edge_time(
                    &i.map(|k| va[k as usize]),
                    &j.map(|k| vb[k as usize]),
                    tol,
                    limit,
                    scratch,
                ),
                Meeting::EdgeEdge(i.map(|k| fa[k as usize]), j.map(|k| fb[k as usize])),
            ),
        };
        if let Some(t) = t {
            // The solvers only return times before the limit.
            limit = t;
            let triangles = TrianglePair { a: ta, b: tb };
            best = Some((
                t,
                Candidate {
                    triangles,
                    features,
                },
            ));
        }
    }
    best
}

impl Candidate {
    /// The contact point and normal at time `t` of the piece.
    fn impact(&self, a: &impl SweptMesh, b: &impl SweptMesh, t: f64) -> TimeOfImpact {
        let (point, normal) = match self.features {
            Meeting::VertexFace(vertex) => {
                let p = a.vertex(vertex);
                let face = b.triangles()[self.triangles.b as usize].map(|v| b.vertex(v));
                // The face's normal, towards the side the vertex comes from.
                let n = face_normal_towards(&face, &p, t);
                (p.at(t), n)
            }
            Meeting::FaceVertex(vertex) => {
                let p = b.vertex(vertex);
                let face = a.triangles()[self.triangles.a as usize].map(|v| a.vertex(v));
                (p.at(t), -face_normal_towards(&face, &p, t))
            }
            Meeting::EdgeEdge(ea, eb) => {
                let (pa, pb) = (ea.map(|v| a.vertex(v)), eb.map(|v| b.vertex(v)));
                edge_contact(&pa, &pb, t)
            }
        };
        TimeOfImpact {
            time: t as f32,
            point: point.as_vec3(),
            normal: normal.as_vec3().normalize_or(Vec3::X),
            triangles: self.triangles,
            features: self.features.features(),
        }
    }
}

/// The unit normal of `face` at time `t`, oriented towards the side `p` comes from (where `p`
/// was at the start, or against `p`'s motion relative to the face when it starts on it).
fn face_normal_towards(face: &[Trajectory; 3], p: &Trajectory, t: f64) -> DVec3 {
    let [x, y, z] = face.map(|v| v.at(t));
    let n = (y - x).cross(z - x).normalize_or_zero();
    let side = n.dot(p.start - face[0].start);
    let relative_motion = (p.end - p.start) - (face[0].end - face[0].start);
    let toward = if side.abs() > 1e-12 {
        side
    } else {
        -n.dot(relative_motion)
    };
    if toward < 0.0 { -n } else { n }
}

/// The contact point (midway between the edges' closest points) and the normal (from `q`
/// towards `p`) of two edges at time `t`.
fn edge_contact(p: &[Trajectory; 2], q: &[Trajectory; 2], t: f64) -> (DVec3, DVec3) {
    let now = closest_points_segment_segment(p[0].at(t), p[1].at(t), q[0].at(t), q[1].at(t));
    let before = closest_points_segment_segment(p[0].start, p[1].start, q[0].start, q[1].start);
    let n = (p[1].at(t) - p[0].at(t))
        .cross(q[1].at(t) - q[0].at(t))
        .normalize_or_zero();
    let apart = before.point_a - before.point_b;
    let relative_motion = (p[0].end - p[0].start) - (q[0].end - q[0].start);
    let n = if n == DVec3::ZERO {
        // Parallel edges: the direction between them, or against their motion.
        if apart.length_squared() > 1e-24 {
            apart.normalize()
        } else {
            -relative_motion.normalize_or(DVec3::X)
        }
    } else if n.dot(apart) < 0.0 || (n.dot(apart) == 0.0 && n.dot(relative_motion) > 0.0) {
        -n
    } else {
        n
    };
    (0.5 * (now.point_a + now.point_b), n)
}
