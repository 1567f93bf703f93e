//! The drawing systems: world and fat boxes, contacts and normals, feature pairs.
use bevy_color::Color;
use bevy_ecs::prelude::*;
use bevy_gizmos::gizmos::Gizmos;
use glam::Vec3;

use super::super::broad_phase::BroadPhaseState;
use super::super::pairs::CollisionPairs;
use super::super::prepare::{ColliderEntry, ColliderTable};
use super::super::tracking::FeaturePairs;
use super::config::CollisionGizmos;
use crate::bvh::TrianglePair;
use crate::geometry::{Aabb, closest_points_triangle_triangle};

/// The collision gizmos, as the drawing systems take them.
type CollisionDraw<'w, 's> = Gizmos<'w, 's, CollisionGizmos>;

/// The 12 edges of a box.
fn box_edges(b: &Aabb) -> [(Vec3, Vec3); 12] {
    let corner = |i: usize| {
        Vec3::new(
            if i & 1 == 0 { b.min.x } else { b.max.x },
            if i & 2 == 0 { b.min.y } else { b.max.y },
            if i & 4 == 0 { b.min.z } else { b.max.z },
        )
    };
    // Corners i and i | bit, for each corner without that bit.
    let mut edges = [(Vec3::ZERO, Vec3::ZERO); 12];
    let mut k = 0;
    for bit in [1, 2, 4] {
        for i in (0..8).filter(|i| i & bit == 0) {
            edges[k] = (corner(i), corner(i | bit));
            k += 1;
        }
    }
    edges
}

/// Draws a box's 12 edges (nothing for an empty or non-finite box).
fn draw_box(gizmos: &mut CollisionDraw, b: &Aabb, color: Color) {
    if b.is_empty() || !b.min.is_finite() || !b.max.is_finite() {
        return;
    }
    for (p, q) in box_edges(b) {
        gizmos.line(p, q, color);
    }
}

/// Draws a cross of half-size `size` along the axes at `p` (nothing for size 0 or a
/// non-finite point).
fn draw_cross(gizmos: &mut CollisionDraw, p: Vec3, size: f32, color: Color) {
    if size.is_nan() || size <= 0.0 || !p.is_finite() {
        return;
    }
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        gizmos.line(p - axis * size, p + axis * size, color);
    }
}

/// Draws the world box of every collider ([`CollisionGizmos::world_boxes`]) and its
/// broad-phase fat box ([`CollisionGizmos::fat_boxes`]).
pub fn draw_collider_boxes(
    mut gizmos: CollisionDraw,
    colliders: Res<ColliderTable>,
    broad_phase: Res<BroadPhaseState>,
) {
    let settings = gizmos.config_ext.clone();
    if !gizmos.config.enabled {
        return;
    }
    for entry in colliders.iter() {
        if settings.world_boxes {
            draw_box(&mut gizmos, &entry.aabb, settings.box_color);
        }
        if settings.fat_boxes
            && let Some(fat) = broad_phase.fat_box(&colliders, entry.entity)
        {
            draw_box(&mut gizmos, &fat, settings.fat_box_color);
        }
    }
}

/// Draws the contacts of every pair (a cross, [`CollisionGizmos::contact_size`]) and their
/// normals ([`CollisionGizmos::normals`]), in the colour of the pair's answer
/// ([`CollisionGizmos::confidence_color`] of its method and current probability).
pub fn draw_contacts(mut gizmos: CollisionDraw, pairs: CollisionPairs) {
    let settings = gizmos.config_ext.clone();
    if !gizmos.config.enabled {
        return;
    }
    for pair in pairs.iter() {
        let contacts = pair.contacts();
        if contacts.is_empty() {
            continue;
        }
        let color = settings.confidence_color(pair.method(), pair.probability());
        for c in contacts {
            draw_cross(&mut gizmos, c.point, settings.contact_size, color);
            let end = c.point + c.normal * settings.normal_length.of(c.depth);
            if settings.normals && end.is_finite() && end != c.point {
                gizmos.line(c.point, end, color);
            }
        }
    }
}

/// Triangle `t` of a collider in world space, if its mesh has it.
fn world_triangle(entry: &ColliderEntry, t: u32) -> Option<[Vec3; 3]> {
    let mesh = entry.geometry.mesh().mesh();
    ((t as usize) < mesh.triangle_count()).then(|| {
        mesh.triangle(t as usize)
            .map(|p| entry.pose.transform_point(p))
    })
}

/// Draws one feature pair: both triangles' outlines and the segment between their closest
/// points, or a cross where they meet. Triangles the meshes no longer have are skipped.
fn draw_feature_pair(
    gizmos: &mut CollisionDraw,
    (a, b): (&ColliderEntry, &ColliderEntry),
    pair: TrianglePair,
    settings: &CollisionGizmos,
) {
    let (Some(ta), Some(tb)) = (world_triangle(a, pair.a), world_triangle(b, pair.b)) else {
        return;
    };
    let color = settings.feature_pair_color;
    for t in [&ta, &tb] {
        for i in 0..3 {
            gizmos.line(t[i], t[(i + 1) % 3], color);
        }
    }
    let closest =
        closest_points_triangle_triangle(&ta.map(Vec3::as_dvec3), &tb.map(Vec3::as_dvec3));
    let (pa, pb) = (closest.point_a.as_vec3(), closest.point_b.as_vec3());
    if closest.distance > 0.0 && closest.distance.is_finite() {
        gizmos.line(pa, pb, color);
    } else {
        draw_cross(gizmos, pa, settings.contact_size, color);
    }
}

/// Draws the feature pairs of tracked pairs and self-colliding meshes
/// ([`CollisionGizmos::feature_pairs`]), each pair once (by the smaller entity), both ends
/// at their colliders' poses.
pub fn draw_feature_pairs(
    mut gizmos: CollisionDraw,
    colliders: Res<ColliderTable>,
    features: Query<(Entity, &FeaturePairs)>,
) {
    let settings = gizmos.config_ext.clone();
    if !gizmos.config.enabled || !settings.feature_pairs {
        return;
    }
    for (entity, pairs) in &features {
        let Some(a) = colliders.get(entity) else {
            continue;
        };
        for (partner, list) in &pairs.partners {
            let Some(b) = colliders.get(*partner).filter(|_| entity <= *partner) else {
                continue;
            };
            for &pair in list {
                draw_feature_pair(&mut gizmos, (a, b), pair, &settings);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_has_twelve_distinct_axis_aligned_edges_of_its_extents() {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 2.5));
        let edges = box_edges(&b);
        let mut lengths: Vec<f32> = edges.iter().map(|(p, q)| (*q - *p).length()).collect();
        lengths.sort_by(f32::total_cmp);
        assert_eq!(lengths, [[0.5; 4], [2.0; 4], [3.0; 4]].concat());
        for (i, e) in edges.iter().enumerate() {
            assert!(b.contains_point(e.0) && b.contains_point(e.1));
            assert_eq!(
                ((e.1 - e.0).abs().cmpgt(Vec3::ZERO)).bitmask().count_ones(),
                1
            );
            assert!(!edges[..i].contains(e), "edge {i} twice");
        }
    }
}
