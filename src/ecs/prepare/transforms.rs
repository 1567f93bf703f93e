//! Poses from bevy_transform: each collider's [`ColliderPose`] and [`ColliderScale`] from its
//! `Transform` composed with its ancestors' (the pose of this run, without waiting for
//! transform propagation), and bodies moved by the built-in responses through their
//! `Transform`.
use bevy_ecs::prelude::*;
use bevy_transform::components::{GlobalTransform, Transform};
use glam::Vec3;

use super::super::components::{ColliderPose, ColliderScale};
use crate::geometry::Pose;

/// What the walk up a hierarchy reads of an ancestor.
type Ancestor = (
    Option<&'static Transform>,
    Option<&'static GlobalTransform>,
    Option<&'static ChildOf>,
);

/// The world transform of an entity with `local` under `parent`: the ancestors' `Transform`s
/// composed up to the root (an ancestor without `Transform` contributes its
/// `GlobalTransform` and ends the walk), as transform propagation would compute it.
fn world_transform(
    local: &Transform,
    parent: Option<&ChildOf>,
    ancestors: &Query<Ancestor>,
) -> GlobalTransform {
    let mut world = GlobalTransform::from(*local);
    let mut next = parent.map(ChildOf::parent);
    while let Some(p) = next {
        match ancestors.get(p) {
            Ok((Some(t), _, up)) => {
                world = GlobalTransform::from(*t) * world;
                next = up.map(ChildOf::parent);
            }
            Ok((None, Some(g), _)) => {
                world = *g * world;
                next = None;
            }
            _ => next = None,
        }
    }
    world
}

/// A scale factor decomposed from a composed transform, rounded to 16 bits of mantissa
/// (relative steps of 1.5e-5): the rounding noise of the decomposition must not make a new
/// scaled tree every run.
fn snapped(scale: Vec3) -> Vec3 {
    let snap = |f: f32| f32::from_bits((f.to_bits() + (1 << 6)) & !((1 << 7) - 1));
    Vec3::new(snap(scale.x), snap(scale.y), snap(scale.z))
}

fn write(pose: &mut Mut<ColliderPose>, scale: &mut Mut<ColliderScale>, p: Pose, s: Vec3) {
    pose.set_if_neq(ColliderPose(p));
    scale.set_if_neq(ColliderScale(s));
}

/// Colliders at the root of their hierarchy whose `Transform` changed, or that are new.
type Roots = (
    Without<ChildOf>,
    Or<(Changed<Transform>, Added<ColliderPose>)>,
);

/// Colliders with a `GlobalTransform` but no `Transform`, whose `GlobalTransform` changed.
type GlobalsOnly = (Without<Transform>, Changed<GlobalTransform>);

/// Sets [`ColliderPose`] and [`ColliderScale`] from the entity's `Transform` and its
/// ancestors' (children are composed every run: an ancestor may have moved), or from its
/// `GlobalTransform` when it has no `Transform`. Runs first in the Prepare stage.
pub fn sync_transforms(
    mut roots: Query<(&Transform, &mut ColliderPose, &mut ColliderScale), Roots>,
    mut children: Query<(&Transform, &ChildOf, &mut ColliderPose, &mut ColliderScale)>,
    ancestors: Query<Ancestor>,
    mut globals: Query<(&GlobalTransform, &mut ColliderPose, &mut ColliderScale), GlobalsOnly>,
) {
    for (t, mut pose, mut scale) in &mut roots {
        write(
            &mut pose,
            &mut scale,
            Pose::new(t.translation, t.rotation),
            t.scale,
        );
    }
    for (t, parent, mut pose, mut scale) in &mut children {
        let (s, r, tr) =
            world_transform(t, Some(parent), &ancestors).to_scale_rotation_translation();
        write(&mut pose, &mut scale, Pose::new(tr, r), snapped(s));
    }
    for (g, mut pose, mut scale) in &mut globals {
        let (s, r, t) = g.to_scale_rotation_translation();
        write(&mut pose, &mut scale, Pose::new(t, r), snapped(s));
    }
}

/// What a built-in response moves a body through: its `Transform` (and parent), if any.
pub(crate) type Placement = (Option<&'static mut Transform>, Option<&'static ChildOf>);

/// The parents' world transforms, to move a child body in its parent's frame.
pub(crate) type Parents<'w, 's> = Query<'w, 's, &'static GlobalTransform>;

/// Moves a body by `delta` (world space): its pose, and its `Transform` when it has one (in
/// its parent's frame for a child), so that the game sees the move and the next run's poses
/// (read from `Transform`) keep it.
pub(crate) fn shift(
    pose: &mut ColliderPose,
    (transform, parent): &mut (Option<Mut<Transform>>, Option<&ChildOf>),
    parents: &Parents,
    delta: Vec3,
) {
    pose.0.translation += delta;
    if let Some(t) = transform {
        let local = match parent.and_then(|p| parents.get(p.parent()).ok()) {
            Some(g) => g.affine().inverse().transform_vector3(delta),
            None => delta,
        };
        t.translation += local;
    }
}

/// Puts a body at `world` (a pose, world space): its pose, and its `Transform` when it has one
/// (in its parent's frame for a child, whose parent is taken to be without shear), keeping
/// the `Transform`'s scale.
pub(crate) fn place(
    pose: &mut ColliderPose,
    (transform, parent): &mut (Option<Mut<Transform>>, Option<&ChildOf>),
    parents: &Parents,
    world: Pose,
) {
    pose.0 = world;
    if let Some(t) = transform {
        match parent.and_then(|p| parents.get(p.parent()).ok()) {
            Some(g) => {
                let (_, parent_rotation, _) = g.to_scale_rotation_translation();
                t.translation = g.affine().inverse().transform_point3(world.translation);
                t.rotation = (parent_rotation.inverse() * world.rotation).normalize();
            }
            None => {
                t.translation = world.translation;
                t.rotation = world.rotation;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decomposition_noise_is_snapped_but_real_scales_are_kept() {
        assert_eq!(snapped(Vec3::splat(0.99999994)), Vec3::ONE);
        assert_eq!(snapped(Vec3::splat(1.0000001)), Vec3::ONE);
        assert_eq!(snapped(Vec3::new(2.0, 0.5, 1.5)), Vec3::new(2.0, 0.5, 1.5));
        let s = snapped(Vec3::splat(1.001));
        assert!((s.x - 1.001).abs() < 2e-5);
        assert_eq!(snapped(Vec3::splat(-2.0)), Vec3::splat(-2.0));
    }
}
