//! The components of a simple rigid body moved by the
//! [`ImpulseResponsePlugin`](super::ImpulseResponsePlugin): velocities, mass, inertia, sleep.
use bevy_ecs::prelude::*;
use bevy_reflect::prelude::*;
use glam::{Mat3, Vec3};

use crate::mesh::MassProperties;

/// Linear velocity of a simple rigid body (units per second), of its centre of mass. Adding
/// it makes the entity a body: it also gets a [`BodyAngularVelocity`], a [`BodyInertia`]
/// (from its collider's mesh) and a sleep state ([`Rest`]).
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
#[require(Rest, BodyAngularVelocity, BodyInertia)]
pub struct BodyVelocity(pub Vec3);

/// Angular velocity of a simple rigid body, world space: the axis of rotation scaled by the
/// speed in radians per second, about the body's centre of mass.
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct BodyAngularVelocity(pub Vec3);

/// Sleep state of a body with [`BodyVelocity`]: a body that stays slower than
/// [`ImpulseSettings::sleep_speed`](super::ImpulseSettings::sleep_speed) and turns slower than
/// [`ImpulseSettings::sleep_spin`](super::ImpulseSettings::sleep_spin) for
/// [`ImpulseSettings::sleep_frames`](super::ImpulseSettings::sleep_frames) runs falls asleep:
/// it stops moving (so its pairs are not worked on: their answers stand) until an awake body
/// hits it faster than [`ImpulseSettings::wake_speed`](super::ImpulseSettings::wake_speed).
#[derive(Component, Reflect, Debug, Clone, Copy, Default, PartialEq, Eq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct Rest {
    pub(super) still_frames: u32,
    pub(super) asleep: bool,
}

impl Rest {
    /// Whether the body sleeps.
    pub fn is_asleep(&self) -> bool {
        self.asleep
    }

    /// Wakes the body up.
    pub fn wake(&mut self) {
        *self = Rest::default();
    }
}

/// Mass of a body with [`BodyVelocity`] (default 1).
#[derive(Component, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct BodyMass(pub f32);

impl Default for BodyMass {
    fn default() -> Self {
        Self(1.0)
    }
}

/// Where a [`BodyInertia`] comes from.
#[derive(Reflect, Debug, Clone, Copy, Default, PartialEq, Eq)]
#[reflect(Clone, Debug, Default, PartialEq)]
pub enum InertiaSource {
    /// Computed by the impulse response from the entity's collider mesh at its scale
    /// ([`TriMesh::mass_properties`](crate::mesh::TriMesh::mass_properties): a uniform
    /// solid for a closed mesh, a shell otherwise), again whenever the mesh or the scale
    /// changes.
    #[default]
    FromMesh,
    /// Given by the user; never recomputed.
    Given,
    /// The body does not turn (infinite inertia); its centre of mass is its origin.
    Locked,
}

/// How a body with [`BodyVelocity`] turns: its centre of mass and inertia. The default is
/// computed from the collider's mesh; [`BodyInertia::locked`] keeps the body from turning.
#[derive(Component, Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct BodyInertia {
    /// Where the values come from.
    pub source: InertiaSource,
    /// Centre of mass in the body's frame (the mesh's coordinates times its scale).
    pub center: Vec3,
    /// Inverse inertia tensor about the centre of mass, in the body's frame, for unit mass
    /// (divided by [`BodyMass`] when used). Zero: the body does not turn.
    pub inverse_inertia: Mat3,
    /// Largest distance of the body's surface from its centre of mass.
    pub radius: f32,
    /// Whether the values have been set (from the mesh, for [`InertiaSource::FromMesh`]).
    pub ready: bool,
}

impl Default for BodyInertia {
    /// From the collider's mesh, computed when the impulse response first sees the body.
    fn default() -> Self {
        Self {
            source: InertiaSource::FromMesh,
            center: Vec3::ZERO,
            inverse_inertia: Mat3::ZERO,
            radius: 0.0,
            ready: false,
        }
    }
}

impl BodyInertia {
    /// A body that does not turn; its centre of mass is its origin.
    pub fn locked() -> Self {
        Self {
            source: InertiaSource::Locked,
            ready: true,
            ..Self::default()
        }
    }

    /// Given mass properties (for example of another mesh than the collider, or a scaled
    /// one): [`InertiaSource::Given`].
    pub fn from_properties(properties: &MassProperties) -> Self {
        Self {
            source: InertiaSource::Given,
            ..Self::computed(properties)
        }
    }

    /// The values of `properties`, keeping [`InertiaSource::FromMesh`].
    pub(super) fn computed(properties: &MassProperties) -> Self {
        Self {
            source: InertiaSource::FromMesh,
            center: properties.center,
            inverse_inertia: properties.inverse_inertia(),
            radius: properties.radius,
            ready: true,
        }
    }

    /// The inverse inertia tensor in world space for a body of `inverse_mass`, rotated by
    /// `rotation`.
    pub fn world_inverse(&self, rotation: glam::Quat, inverse_mass: f32) -> Mat3 {
        let r = Mat3::from_quat(rotation);
        r * self.inverse_inertia * r.transpose() * inverse_mass
    }
}
