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
    /// The classification's buffers, reused the same way.
    static CLASSIFY: RefCell<Classify> = RefCell::new(Classify::default());
}

/// Buffers of [`inside_vertices`].
#[derive(Default)]
struct Classify {
    /// Per vertex of the soft mesh: 0 not classified yet, 1 inside, 2 outside.
    state: Vec<u8>,
    /// Per triangle of the soft mesh: whether it meets the solid's surface.
    crossing: Vec<bool>,
    stack: Vec<u32>,
}

/// Appends to `out`, ascending, the referenced vertices of `soft` inside the closed `solid`
/// (`to_solid` places `soft` in `solid`'s frame), each with where it is in `solid`'s frame and
/// one of its triangles. `crossing` are the soft mesh's triangles that meet `solid`'s surface
/// (every one: the pair's intersecting triangle pairs).
///
/// An edge of the soft mesh that meets the solid's surface makes every triangle using it meet
/// the surface; so an edge with a triangle that does not keeps both its ends on the same side.
/// The vertices joined by such edges are classified together: one exact test (ray parity,
/// [`contains_point`]) per piece of the soft mesh that no crossing separates, instead of one
/// per vertex.
fn inside_vertices(
    (soft, to_solid): (&CollisionMesh, &Pose),
    solid: &CollisionMesh,
    crossing: impl Iterator<Item = u32>,
    c: &mut Classify,
    out: &mut Vec<(u32, Vec3, u32)>,
) {
    let topology = soft.topology();
    let positions = soft.mesh().positions();
    let root = solid.bvh().root_aabb();
    c.crossing.clear();
    c.crossing.resize(soft.mesh().triangle_count(), false);
    for t in crossing {
        c.crossing[t as usize] = true;
    }
    c.state.clear();
    c.state.resize(positions.len(), 0);
    for v in 0..positions.len() as u32 {
        if c.state[v as usize] != 0 || topology.vertex_triangles(v).is_empty() {
            continue;
        }
        let local = to_solid.transform_point(positions[v as usize]);
        let in_box = local.cmpge(root.min).all() && local.cmple(root.max).all();
        let mark = if in_box && contains_point(solid, local) {
            1
        } else {
            2
        };
        c.state[v as usize] = mark;
        c.stack.clear();
        c.stack.push(v);
        while let Some(u) = c.stack.pop() {
            for &e in topology.vertex_edges(u) {
                let edge = topology.edge(e);
                if edge.triangles.iter().all(|&t| c.crossing[t as usize]) {
                    continue;
                }
                let w = if edge.vertices[0] == u {
                    edge.vertices[1]
                } else {
                    edge.vertices[0]
                };
                if c.state[w as usize] == 0 {
                    c.state[w as usize] = mark;
                    c.stack.push(w);
                }
            }
        }
    }
    out.extend(
        c.state
            .iter()
            .enumerate()
            .filter(|(_, m)| **m == 1)
            .map(|(v, _)| {
                let local = to_solid.transform_point(positions[v]);
                (v as u32, local, topology.vertex_triangles(v as u32)[0])
            }),
    );
}

/// The vertices of `soft` (at `pose_soft`) inside the closed mesh `solid` (at `pose_solid`),
/// at most `max` of them evenly spread over the inside ones (every k-th, starting at
/// `rotation` modulo k, so that successive runs given successive rotations reach them all),
/// each as a contact: at the
/// vertex, its depth the distance to `solid`'s surface, its normal pushing the vertex
/// towards the closest surface point (with `soft_first`, `soft` is the pair's first entity:
/// the normal points from the vertex's surface point into the solid; otherwise out of it),
/// its triangle pair one of the vertex's triangles and the closest triangle of `solid`.
/// `pairs` are the pair's intersecting triangle pairs, all of them (first entity's triangle,
/// second's): which vertices are inside is decided by one exact test per piece of `soft` they
/// do not cut ([`inside_vertices`]). Vertices on the surface (within a millionth of `solid`'s
/// size) get none. Nothing when `solid` is not closed (an open mesh has no inside).
pub(crate) fn contained_vertex_contacts(
    (soft, pose_soft): (&CollisionMesh, &Pose),
    (solid, pose_solid): (&CollisionMesh, &Pose),
    (soft_first, pairs): (bool, &[TrianglePair]),
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
        let crossing = pairs.iter().map(|p| if soft_first { p.a } else { p.b });
        CLASSIFY.with_borrow_mut(|c| {
            inside_vertices((soft, &to_solid), solid, crossing, c, inside);
        });
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
        out.extend(inside.iter().filter_map(|&(v, local, t)| {
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

    /// The intersecting triangle pairs of `soft` and `solid`, in the pair's order (`soft`
    /// first or second).
    fn crossing_pairs(
        (soft, soft_pose): (&CollisionMesh, &Pose),
        (solid, solid_pose): (&CollisionMesh, &Pose),
        soft_first: bool,
    ) -> Vec<TrianglePair> {
        let mut pairs = Vec::new();
        let ws = &mut crate::bvh::QueryWorkspace::new();
        if soft_first {
            crate::bvh::intersecting_pairs(soft, soft_pose, solid, solid_pose, ws, &mut pairs);
        } else {
            crate::bvh::intersecting_pairs(solid, solid_pose, soft, soft_pose, ws, &mut pairs);
        }
        pairs
    }

    /// Wavy, folded sheets across a ball and a box at many poses: the inside vertices found
    /// with one test per uncut piece are those a direct test of every vertex finds.
    #[test]
    fn inside_vertices_are_those_a_test_of_every_vertex_finds() {
        let solids = [
            CollisionMesh::new(generate::icosphere(0.5, 2)),
            CollisionMesh::new(generate::cuboid(Vec3::new(0.6, 0.2, 0.4), 2)),
        ];
        let mut sheet = generate::cloth_grid(2.0, 2.0, 24, 24);
        let wavy: Vec<Vec3> = sheet
            .positions()
            .iter()
            .map(|p| Vec3::new(p.x, 0.3 * (3.0 * p.x).sin() * (2.0 * p.z).cos(), p.z))
            .collect();
        sheet.set_positions(&wavy).unwrap();
        let sheet = CollisionMesh::new(sheet);
        let mut c = Classify::default();
        let (mut cut, mut checked) = (0, 0);
        for (k, solid) in solids.iter().enumerate() {
            for step in 0..24 {
                let f = step as f32;
                let pose = Pose::new(
                    Vec3::new(0.05 * f - 0.6, 0.03 * f - 0.35, 0.02 * f),
                    glam::Quat::from_euler(glam::EulerRot::XYZ, 0.13 * f, 0.29 * f, 0.07 * f),
                );
                for soft_first in [true, false] {
                    let pairs =
                        crossing_pairs((&sheet, &pose), (solid, &Pose::IDENTITY), soft_first);
                    cut += usize::from(!pairs.is_empty());
                    let crossing = pairs.iter().map(|p| if soft_first { p.a } else { p.b });
                    let mut found = Vec::new();
                    inside_vertices((&sheet, &pose), solid, crossing, &mut c, &mut found);
                    // The same placement as the classification's, so that both test the
                    // same points.
                    let to_solid = Pose::IDENTITY.inverse_mul(&pose);
                    let direct: Vec<u32> = (0..sheet.mesh().vertex_count() as u32)
                        .filter(|&v| {
                            let p = sheet.mesh().positions()[v as usize];
                            contains_point(solid, to_solid.transform_point(p))
                        })
                        .collect();
                    let got: Vec<u32> = found.iter().map(|x| x.0).collect();
                    assert_eq!(got, direct, "solid {k}, step {step}");
                    checked += direct.len();
                    for &(v, _, t) in &found {
                        assert!(sheet.mesh().triangles()[t as usize].contains(&v));
                    }
                }
            }
        }
        assert!(cut > 20 && checked > 100, "{cut} {checked}");
    }

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
            let pairs = crossing_pairs((&sheet, &sheet_pose), (&floor, &floor_pose), soft_first);
            assert!(!pairs.is_empty(), "the sheet crosses the box's side");
            contained_vertex_contacts(
                (&sheet, &sheet_pose),
                (&floor, &floor_pose),
                (soft_first, &pairs),
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
                    (soft_first, &pairs),
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
            (true, &[]),
            (1000, 0),
            &mut none,
        );
        assert!(none.is_empty());
    }
}
