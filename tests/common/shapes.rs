//! Generated test shapes shared by several suites.

use glam::Vec3;
use stochastic_collision::mesh::TriMesh;

/// The positions of `flat` (a cloth grid in the y = 0 plane) with its part beyond x = 0.1
/// folded back over the rest at `height` above it, the fold line fixed. Folded back and
/// sheared a little, so that no flap vertex or edge lines up exactly with one of the base (a
/// generic fold, not a degenerate one).
pub fn sheared_fold(flat: &TriMesh, height: f32) -> Vec<Vec3> {
    flat.positions()
        .iter()
        .map(|p| {
            if p.x > 0.1 {
                Vec3::new(0.2137 - p.x, height, p.z + 0.037 * (p.x - 0.1))
            } else {
                *p
            }
        })
        .collect()
}
