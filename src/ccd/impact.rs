//! What a continuous query answers: the first contact of two moving meshes and the features
//! that meet.
use glam::Vec3;

use crate::bvh::TrianglePair;

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
