//! The continuous query between two meshes: the first time of impact over a step.
use glam::DVec3;

use super::descent::{DescentScratch, first_impact};
use super::impact::{ImpactFeatures, TimeOfImpact};
use super::motion::RigidMotion;
use super::primitive::PrimitiveTolerances;
use super::swept::{BoxFrame, DeformingStep, PoseCache, RigidStep, chord_deviation, mesh_radius};
use crate::bvh::{CollisionMesh, ExactOptions, QueryWorkspace, intersects_with};
use crate::geometry::{Pose, closest_points_triangle_triangle};

/// Tolerances of the continuous query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CcdOptions {
    /// Features closer than this (world units, in each coordinate) count as touching: the
    /// query reports contact when the meshes come this close, and never later than they
    /// touch. Default `1e-5`. For small meshes [`CcdOptions::relative_tolerance`] is the
    /// tighter one.
    pub distance_tolerance: f32,
    /// The same as a fraction of the smaller mesh's size (half its box's diagonal): the query
    /// uses the smaller of the two tolerances, so that scaling a scene down does not make its
    /// times of impact coarser (a contact reported within the tolerance comes early by about
    /// the tolerance over the speed at which the features approach). `0` leaves
    /// `distance_tolerance` alone. Default `1e-6`.
    pub relative_tolerance: f32,
    /// The time resolution of the answer where features move fast (a fraction of the step).
    /// Default `1e-5`.
    pub time_tolerance: f32,
    /// A rotating mesh's step is cut into pieces over which its vertices stray at most half
    /// the distance tolerance (the smaller of the two above) from straight paths; at most
    /// this many (beyond, each piece's tolerance grows by what its vertices stray: still
    /// conservative, less precise). Default 4096.
    pub max_pieces: u32,
}

impl Default for CcdOptions {
    fn default() -> Self {
        Self {
            distance_tolerance: 1e-5,
            relative_tolerance: 1e-6,
            time_tolerance: 1e-5,
            max_pieces: 4096,
        }
    }
}

impl CcdOptions {
    /// The distance tolerance for meshes of sizes `a` and `b` (half their boxes' diagonals):
    /// the smaller of [`CcdOptions::distance_tolerance`] and
    /// [`CcdOptions::relative_tolerance`] times the smaller size.
    pub(crate) fn distance_for(&self, a: f64, b: f64) -> f64 {
        let absolute = f64::from(self.distance_tolerance.max(0.0));
        let relative = f64::from(self.relative_tolerance.max(0.0)) * a.min(b);
        if relative > 0.0 {
            absolute.min(relative)
        } else {
            absolute
        }
    }
}

/// Half the diagonal of `mesh`'s box: its size, for [`CcdOptions::distance_for`].
pub(crate) fn mesh_size(mesh: &CollisionMesh) -> f64 {
    0.5 * f64::from(mesh.bvh().root_aabb().extents().length())
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
    pub(crate) exact: QueryWorkspace,
    pub(crate) descent: DescentScratch,
    /// The two meshes' poses at the step's piece boundaries.
    pub(crate) poses: (PoseCache, PoseCache),
    /// Triangle pairs tested by the last query (those whose boxes meet within the step).
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
/// A rotating mesh's step is cut into pieces short enough that its vertices' paths are straight
/// within the tolerance. Node pairs are searched earliest first by the time their moving boxes
/// can meet, and the search ends when none left can meet before the earliest contact found;
/// every vertex–face and edge–edge pair whose boxes meet before then is solved by an
/// inclusion-based root finder (see [`vertex_face_time`]).
///
/// [`intersects`]: crate::bvh::intersects
/// [`vertex_face_time`]: crate::ccd::vertex_face_time
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
    validate_motions(motion_a, motion_b)?;
    ws.triangle_pairs = 0;
    ws.descent.triangle_pairs = 0;
    if let Some(hit) = overlap_at_start(a, &motion_a.start, b, &motion_b.start, ws) {
        return Ok(Some(hit));
    }
    let step = RigidPair::new((a, motion_a), (b, motion_b), options, &mut ws.poses);
    let hit = first_impact(&step.a, &step.b, &step.tol, step.growth, &mut ws.descent);
    ws.triangle_pairs = ws.descent.triangle_pairs;
    Ok(hit)
}

/// Refuses motions with a pose that is not finite.
pub(crate) fn validate_motions(
    motion_a: &RigidMotion,
    motion_b: &RigidMotion,
) -> Result<(), CcdError> {
    for (which, m) in [("first", motion_a), ("second", motion_b)] {
        for (end, pose) in [("start", m.start), ("end", m.end)] {
            if !pose.is_finite() {
                return Err(CcdError::InvalidPose { which, end, pose });
            }
        }
    }
    Ok(())
}

/// Two rigid meshes over the step as the search reads them: the step cut into pieces over
/// which the vertices' paths are straight within the tolerance, the boxes' frame, and the
/// tolerances of the feature tests.
pub(crate) struct RigidPair<'a> {
    pub a: RigidStep<'a>,
    pub b: RigidStep<'a>,
    pub tol: PrimitiveTolerances,
    /// See [`BoxFrame::max_norm_growth`].
    pub growth: f64,
    pub pieces: u32,
}

impl<'a> RigidPair<'a> {
    pub fn new(
        (a, motion_a): (&'a CollisionMesh, &RigidMotion),
        (b, motion_b): (&'a CollisionMesh, &RigidMotion),
        options: &CcdOptions,
        poses: &'a mut (PoseCache, PoseCache),
    ) -> Self {
        let delta = options.distance_for(mesh_size(a), mesh_size(b));
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
        let pieces = pieces_for(a, motion_a)
            .max(pieces_for(b, motion_b))
            .clamp(1, options.max_pieces.max(1));
        let stray = chord_deviation(mesh_radius(a), motion_a.angle() / pieces as f64)
            + chord_deviation(mesh_radius(b), motion_b.angle() / pieces as f64);
        let tol = PrimitiveTolerances {
            distance: delta + stray,
            time: (options.time_tolerance.max(0.0) as f64 * pieces as f64).min(1.0),
            ..Default::default()
        };
        // The node boxes are taken in the frame of a mesh that does not turn: its own boxes
        // are then the tree's, tight, and only the other mesh's are turned into it.
        let turns = |m: &RigidMotion| m.start.rotation != m.end.rotation;
        let (frame, owner) = match (turns(motion_a), turns(motion_b)) {
            (false, _) => (BoxFrame::Mesh(*motion_a), Some(true)),
            (true, false) => (BoxFrame::Mesh(*motion_b), Some(false)),
            (true, true) => (BoxFrame::World, None),
        };
        poses.0.reset(pieces);
        poses.1.reset(pieces);
        let (poses_a, poses_b): (&'a PoseCache, &'a PoseCache) = (&poses.0, &poses.1);
        Self {
            a: RigidStep::new(a, *motion_a, (pieces, poses_a), frame, owner == Some(true)),
            b: RigidStep::new(b, *motion_b, (pieces, poses_b), frame, owner == Some(false)),
            tol,
            growth: frame.max_norm_growth(),
            pieces,
        }
    }
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
    ws.descent.triangle_pairs = 0;
    if let Some(hit) = overlap_at_start(a.0, &Pose::IDENTITY, b.0, &Pose::IDENTITY, ws) {
        return Ok(Some(hit));
    }
    let tol = PrimitiveTolerances {
        distance: options.distance_for(mesh_size(a.0), mesh_size(b.0)),
        time: options.time_tolerance.max(0.0) as f64,
        ..Default::default()
    };
    let pa = DeformingStep {
        start: a.0,
        end: a.1,
    };
    let pb = DeformingStep {
        start: b.0,
        end: b.1,
    };
    let hit = first_impact(&pa, &pb, &tol, 1.0, &mut ws.descent);
    ws.triangle_pairs = ws.descent.triangle_pairs;
    Ok(hit)
}

/// A contact at time 0 if the surfaces already cross at the start (feature pairs that cross
/// do not *come* into contact, so the root finder alone would not see them): at the witness
/// triangles, with the second triangle's normal turned towards the first.
pub(crate) fn overlap_at_start(
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
