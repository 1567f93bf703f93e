use glam::{DQuat, DVec3, Mat3, Quat, Vec3, Vec4};

use super::Aabb;

/// A rigid transform: a rotation followed by a translation (`p ↦ rotation * p + translation`).
///
/// Queries take one pose per mesh; internally they work in the first mesh's frame through
/// [`Pose::inverse_mul`], and transform points in `f64` so that exact predicates see the
/// transformed geometry with no `f32` rounding.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Rotation (unit quaternion).
    pub rotation: Quat,
    /// Translation.
    pub translation: Vec3,
}

impl Default for Pose {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Pose {
    /// No rotation, no translation.
    pub const IDENTITY: Pose = Pose {
        rotation: Quat::IDENTITY,
        translation: Vec3::ZERO,
    };

    /// A pose from its parts. The rotation is normalised, scaled first so that neither a huge
    /// nor a tiny quaternion over- or underflows `f32` on the way; one that cannot be (zero,
    /// NaN or infinite parts) gives a pose that is not [finite](Pose::is_finite).
    #[inline]
    pub fn new(translation: Vec3, rotation: Quat) -> Self {
        let v = Vec4::from(rotation);
        let largest = v.abs().max_element();
        let rotation = if largest.is_finite() && largest > 0.0 {
            Quat::from_vec4(v / largest).normalize()
        } else {
            rotation.normalize()
        };
        Self {
            rotation,
            translation,
        }
    }

    /// A pure translation.
    #[inline]
    pub fn from_translation(translation: Vec3) -> Self {
        Self {
            rotation: Quat::IDENTITY,
            translation,
        }
    }

    /// Whether the translation is finite and the rotation can be normalised (finite and not
    /// zero; queries normalise it in `f64`). Queries given a pose that is not (NaN or infinite
    /// parts, a zero rotation) place that mesh nowhere: no collision, no distance, probability
    /// 0, rather than an answer computed from NaN. Check this before querying to report such a
    /// pose as an error.
    ///
    /// # Example
    /// ```
    /// use stochastic_collision::prelude::*;
    /// assert!(Pose::from_translation(Vec3::X).is_finite());
    /// assert!(!Pose::new(Vec3::ZERO, Quat::from_xyzw(0.0, 0.0, 0.0, 0.0)).is_finite());
    /// assert!(!Pose::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)).is_finite());
    /// ```
    #[inline]
    pub fn is_finite(&self) -> bool {
        let len2 = self.rotation.as_dquat().length_squared();
        self.translation.is_finite() && len2.is_finite() && len2 > 0.0
    }

    /// Applies the pose to a point.
    #[inline]
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.rotation * p + self.translation
    }

    /// Applies the rotation only (to a direction or normal).
    #[inline]
    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation * v
    }

    /// The box of `local`'s eight corners under this pose: the smallest world box that holds
    /// `local` rotated and moved.
    #[inline]
    pub fn transform_aabb(&self, local: &Aabb) -> Aabb {
        let m = Mat3::from_quat(self.rotation);
        let abs = Mat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
        let center = self.translation + m * local.center();
        let half = abs * local.half_extents();
        Aabb::new(center - half, center + half)
    }

    /// The inverse transform.
    #[inline]
    pub fn inverse(&self) -> Pose {
        let r = self.rotation.inverse();
        Pose {
            rotation: r,
            translation: -(r * self.translation),
        }
    }

    /// `self * other`: apply `other`, then `self`.
    #[inline]
    pub fn mul(&self, other: &Pose) -> Pose {
        Pose {
            rotation: (self.rotation * other.rotation).normalize(),
            translation: self.transform_point(other.translation),
        }
    }

    /// `self⁻¹ * other`: the pose of `other`'s frame seen from `self`'s frame.
    ///
    /// When the `f32` computation overflows (poses near the limits of the `f32` range, or a
    /// rotation whose squared length overflows) it is redone in `f64` and rounded once, so the
    /// result is not [finite](Pose::is_finite) only when a pose is not, or when the two frames
    /// are farther apart than the `f32` range.
    #[inline]
    pub fn inverse_mul(&self, other: &Pose) -> Pose {
        let rel = self.inverse().mul(other);
        if rel.is_finite() || !(self.is_finite() && other.is_finite()) {
            return rel;
        }
        let (a, b) = (self.to_f64(), other.to_f64());
        let r = a.rotation.inverse();
        Pose {
            rotation: (r * b.rotation).normalize().as_quat(),
            translation: (r * (b.translation - a.translation)).as_vec3(),
        }
    }

    /// This pose in `f64`, for exact work on transformed geometry.
    #[inline]
    pub fn to_f64(&self) -> PoseF64 {
        PoseF64 {
            rotation: self.rotation.as_dquat().normalize(),
            translation: self.translation.as_dvec3(),
        }
    }
}

/// A [`Pose`] in `f64`: transforms `f32` points with no `f32` rounding.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseF64 {
    /// Rotation.
    pub rotation: DQuat,
    /// Translation.
    pub translation: DVec3,
}

impl PoseF64 {
    /// The inverse transform, computed in `f64`.
    #[inline]
    pub fn inverse(&self) -> PoseF64 {
        let r = self.rotation.inverse();
        PoseF64 {
            rotation: r,
            translation: -(r * self.translation),
        }
    }

    /// Applies the pose to a point.
    #[inline]
    pub fn transform_point(&self, p: Vec3) -> DVec3 {
        self.rotation * p.as_dvec3() + self.translation
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_mul_composes_to_the_relative_pose() {
        let a = Pose::new(Vec3::new(1.0, 2.0, 3.0), Quat::from_rotation_y(0.7));
        let b = Pose::new(Vec3::new(-4.0, 0.5, 2.0), Quat::from_rotation_x(-1.2));
        let rel = a.inverse_mul(&b);
        let p = Vec3::new(0.3, -0.2, 0.9);
        let world = b.transform_point(p);
        let via = a.transform_point(rel.transform_point(p));
        assert!((world - via).length() < 1e-5);
        let d = a.to_f64().transform_point(p);
        assert!((d.as_vec3() - a.transform_point(p)).length() < 1e-5);
    }
}
