//! Contacts for a deformable mesh's vertices that lie inside a closed collider: a sheet that
//! sank into a floor or a ball has triangles wholly inside it, which no surface crossing
//! reports, and the response must still push them out.

use std::cell::RefCell;

use glam::Vec3;

use super::super::contact::ContactPoint;
use crate::bvh::{CollisionMesh, TrianglePair, closest_surface_point, contains_point};
use crate::geometry::Pose;

thread_local! {
    /// The inside vertices of the pair being answered (no allocation per call once grown).
    static INSIDE: RefCell<Vec<(u32, Vec3, u32)>> = const { RefCell::new(Vec::new()) };
}

/// The vertices of `soft` (at `pose_soft`) inside the closed mesh `solid` (at `pose_solid`),
/// at most `max` of them evenly spread over the inside ones (every k-th, starting at
/// `rotation` modulo k, so that successive runs given successive rotations reach them all),
/// each as a contact: at the
/// vertex, its depth the distance to `solid`'s surface, its normal pushing the vertex
/// towards the closest surface point (with `soft_first`, `soft` is the pair's first entity:
/// the normal points from the vertex's surface point into the solid; otherwise out of it),
/// its triangle pair one of the vertex's triangles and the closest triangle of `solid`.
/// Vertices on the surface (within a millionth of `solid`'s size) get none. Nothing when
/// `solid` is not closed (an open mesh has no inside).
pub(crate) fn contained_vertex_contacts(
    (soft, pose_soft): (&CollisionMesh, &Pose),
    (solid, pose_solid): (&CollisionMesh, &Pose),
    soft_first: bool,
    (max, rotation): (usize, u64),
    out: &mut impl Extend<ContactPoint>,
) {
    if !solid.is_closed() || max == 0 {
        return;
    }
    let to_solid = pose_solid.inverse_mul(pose_soft);
    let root = solid.bvh().root_aabb();
    let on_surface = 1e-6 * root.extents().length();
    let positions = soft.mesh().positions();
    INSIDE.with_borrow_mut(|inside| {
        // (vertex, where it is in `solid`'s frame, a triangle at it), reused from call to call.
        inside.clear();
        inside.extend(positions.iter().enumerate().filter_map(|(v, &p)| {
            let local = to_solid.transform_point(p);
            let in_box = local.cmpge(root.min).all() && local.cmple(root.max).all();
            (in_box && contains_point(solid, local)).then_some((v as u32, local, u32::MAX))
        }));
        if inside.is_empty() {
            return;
        }
        let stride = inside.len().div_ceil(max);
        let first = (rotation % stride as u64) as usize;
        let mut k = 0;
        inside.retain(|_| {
            k += 1;
            k > first && (k - 1 - first).is_multiple_of(stride)
        });
        // A triangle at each chosen vertex (the response spreads a contact over its
        // triangle's corners by the contact point's barycentric weights: at a corner, all to
        // that corner).
        for (t, corners) in soft.mesh().triangles().iter().enumerate() {
            for v in corners {
                if let Ok(k) = inside.binary_search_by_key(v, |c| c.0)
                    && inside[k].2 == u32::MAX
                {
                    inside[k].2 = t as u32;
                }
            }
        }
        out.extend(inside.iter().filter_map(|&(v, local, t)| {
            // An unreferenced vertex has no triangle to move.
            if t == u32::MAX {
                return None;
            }
            let surface = closest_surface_point(solid, local)?;
            // On the surface (to rounding): the crossing triangles' contacts hold it, and
            // the direction to the surface is noise.
            if surface.distance <= on_surface {
                return None;
            }
            let vertex = pose_soft.transform_point(positions[v as usize]);
            let exit = pose_solid.transform_point(surface.point);
            // Into the solid, from where the vertex leaves it; on the surface, no contact.
            let inward = (vertex - exit).try_normalize()?;
            let (normal, triangles) = if soft_first {
                (
                    inward,
                    TrianglePair {
                        a: t,
                        b: surface.triangle,
                    },
                )
            } else {
                (
                    -inward,
                    TrianglePair {
                        a: surface.triangle,
                        b: t,
                    },
                )
            };
            Some(ContactPoint {
                point: vertex,
                normal,
                depth: surface.distance,
                triangles: Some(triangles),
                time_of_impact: None,
            })
        }));
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    /// A sheet sunk into a box: every vertex inside gets a contact pushing it up to the top
    /// face, as deep as it sank; vertices outside get none.
    #[test]
    fn a_sheet_inside_a_box_is_pushed_out_through_the_nearest_face() {
        let floor = CollisionMesh::new(generate::cuboid(Vec3::new(3.0, 0.25, 3.0), 2));
        let sheet = CollisionMesh::new(generate::cloth_grid(2.0, 2.0, 4, 4));
        // The floor's top at y = 0; the sheet 0.05 below it, half of it beyond the box's side.
        let floor_pose = Pose::from_translation(Vec3::new(0.0, -0.25, 0.0));
        let sheet_pose = Pose::from_translation(Vec3::new(2.5, -0.05, 0.0));
        for soft_first in [true, false] {
            let mut out = Vec::new();
            contained_vertex_contacts(
                (&sheet, &sheet_pose),
                (&floor, &floor_pose),
                soft_first,
                (1000, 0),
                &mut out,
            );
            let inside = sheet
                .mesh()
                .positions()
                .iter()
                .filter(|p| sheet_pose.transform_point(**p).x < 3.0)
                .count();
            assert_eq!(out.len(), inside);
            let up = if soft_first { -Vec3::Y } else { Vec3::Y };
            for c in &out {
                assert!((c.depth - 0.05).abs() < 1e-5, "{c:?}");
                assert!((c.normal - up).length() < 1e-5, "{c:?}");
                let t = c.triangles.unwrap();
                let soft_triangle = if soft_first { t.a } else { t.b };
                let corners = sheet.mesh().triangle(soft_triangle as usize);
                assert!(
                    corners
                        .iter()
                        .any(|&p| sheet_pose.transform_point(p) == c.point)
                );
            }
            // At most 4 a run; successive rotations reach every inside vertex.
            let mut reached = std::collections::HashSet::new();
            for rotation in 0..8 {
                let mut few = Vec::new();
                contained_vertex_contacts(
                    (&sheet, &sheet_pose),
                    (&floor, &floor_pose),
                    soft_first,
                    (4, rotation),
                    &mut few,
                );
                assert!(!few.is_empty() && few.len() <= 4);
                reached.extend(few.iter().map(|c| c.point.to_array().map(f32::to_bits)));
            }
            assert_eq!(reached.len(), inside);
        }
        // An open solid has no inside.
        let mut none = Vec::new();
        contained_vertex_contacts(
            (&sheet, &sheet_pose),
            (&sheet, &Pose::IDENTITY),
            true,
            (1000, 0),
            &mut none,
        );
        assert!(none.is_empty());
    }
}
