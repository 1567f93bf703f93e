//! How things move over a step: a rigid mesh (its poses at the start and the end) and a point
//! (its positions, on a straight line). Read by every part of the continuous query.
use glam::DVec3;

use crate::geometry::Pose;

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

/// A point's positions at the start and the end of the step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Trajectory {
    /// Position at the start of the step.
    pub start: DVec3,
    /// Position at the end of the step.
    pub end: DVec3,
}

impl Trajectory {
    /// A point that moves from `start` to `end`.
    #[inline]
    pub fn new(start: DVec3, end: DVec3) -> Self {
        Self { start, end }
    }

    /// A point that does not move.
    #[inline]
    pub fn still(p: DVec3) -> Self {
        Self { start: p, end: p }
    }

    /// The position at time `t` of the step.
    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        self.start + t * (self.end - self.start)
    }
}
