//! World boxes of meshes under rigid poses.
use glam::{Mat3, Vec3};

use crate::bvh::Bvh;
use crate::geometry::{Aabb, Pose};

/// The world box of a mesh under a rigid pose: the union of the world boxes of its tree's
/// nodes a few levels down (up to [`TIGHT_LEVELS`] levels: 8 small boxes). A rotated box's
/// world box grows by up to √3 per axis; smaller boxes grow less, so the union is much
/// tighter than the root's (fewer broad-phase pairs that do not touch) for a few box
/// transforms per moving body.
pub(crate) fn tight_world_aabb(bvh: &Bvh, pose: &Pose) -> Aabb {
    let nodes = bvh.nodes();
    let rotation = BoxRotation::new(pose);
    let mut out = Aabb::EMPTY;
    let mut stack = [(0u32, 0u32); 2 * TIGHT_LEVELS as usize + 2];
    let mut len = 1;
    while len > 0 {
        len -= 1;
        let (i, level) = stack[len];
        let node = &nodes[i as usize];
        if node.is_leaf() || level == TIGHT_LEVELS {
            out = out.union(&rotation.world_box(&node.aabb(), pose.translation));
        } else {
            stack[len] = (node.left(), level + 1);
            stack[len + 1] = (node.left() + 1, level + 1);
            len += 2;
        }
    }
    out
}

/// Levels of the tree below the root whose boxes make an entity's world box.
const TIGHT_LEVELS: u32 = 3;

/// The world box of a local box under a rigid pose.
pub(crate) fn world_aabb(local: &Aabb, pose: &Pose) -> Aabb {
    BoxRotation::new(pose).world_box(local, pose.translation)
}

/// A pose's rotation as a matrix and its absolute value, for the world boxes of local boxes.
struct BoxRotation {
    m: Mat3,
    abs: Mat3,
}

impl BoxRotation {
    fn new(pose: &Pose) -> Self {
        let m = Mat3::from_quat(pose.rotation);
        let abs = Mat3::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
        Self { m, abs }
    }

    /// The world box of `local` rotated, then moved by `translation`.
    fn world_box(&self, local: &Aabb, translation: Vec3) -> Aabb {
        let center = translation + self.m * local.center();
        let half = self.abs * local.half_extents();
        Aabb::new(center - half, center + half)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::CollisionMesh;
    use crate::mesh::generate;
    use glam::Quat;

    #[test]
    fn the_tight_box_holds_every_vertex_inside_the_root_box() {
        let meshes = [
            generate::icosphere(1.0, 3),
            generate::cuboid(Vec3::new(2.0, 0.1, 0.5), 4),
            generate::torus(1.0, 0.2, 24, 8),
        ];
        for mesh in meshes {
            let cm = CollisionMesh::new(mesh);
            for k in 0..20 {
                let axis = Vec3::new(1.0, k as f32 * 0.37, -0.5 + k as f32 * 0.11).normalize();
                let pose = Pose::new(
                    Vec3::new(k as f32, -3.0, 0.5),
                    Quat::from_axis_angle(axis, k as f32 * 0.7),
                );
                let tight = tight_world_aabb(cm.bvh(), &pose);
                let loose = world_aabb(&cm.bvh().root_aabb(), &pose);
                for &v in cm.mesh().positions() {
                    let w = pose.transform_point(v);
                    assert!(
                        tight.inflated(1e-4).contains_point(w),
                        "{w} outside {tight:?}"
                    );
                }
                assert!(loose.inflated(1e-4).contains_point(tight.min));
                assert!(loose.inflated(1e-4).contains_point(tight.max));
            }
        }
    }
}
