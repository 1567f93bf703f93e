//! An animation confined to one part of a mesh: the rest stays where it is.

use glam::Vec3;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::Animation;
use crate::mesh::TriMesh;

/// Another animation applied within a ball around a seeded vertex only: a vertex within half
/// the radius follows the inner animation fully, one beyond the radius stays at rest, and in
/// between it is blended smoothly (`smoothstep`) from one to the other, so the surface stays
/// whole. For scenes where most of a large surface rests while one part of it deforms (a tool
/// working on one loop of an intestine) and the work per frame should follow that part.
///
/// # Example
/// ```
/// use stochastic_collision::deform::{Animation, Local, Whirl};
/// use stochastic_collision::mesh::generate;
/// let cloth = generate::cloth_grid(1.0, 1.0, 30, 30);
/// let local = Local::new(&cloth, Whirl::new(&cloth, 40, 1), 0.2, 3);
/// let mut p = Vec::new();
/// local.positions(20, &mut p);
/// let moved = p.iter().zip(cloth.positions()).filter(|(a, b)| a != b).count();
/// assert!(moved > 0 && moved < cloth.vertex_count() / 2);
/// ```
#[derive(Debug, Clone)]
pub struct Local<A> {
    inner: A,
    rest: Vec<Vec3>,
    /// Per vertex, how much of the inner animation's displacement it takes (0 to 1).
    weights: Vec<f32>,
    centre: Vec3,
    radius: f32,
}

impl<A: Animation> Local<A> {
    /// `inner` (an animation of `mesh`) confined to a ball of `radius_fraction` of the mesh
    /// box's diagonal around a vertex drawn with `seed`.
    pub fn new(mesh: &TriMesh, inner: A, radius_fraction: f32, seed: u64) -> Self {
        let rest = mesh.positions().to_vec();
        let radius = (radius_fraction * mesh.aabb().extents().length()).max(f32::MIN_POSITIVE);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x10CA1);
        let centre = if rest.is_empty() {
            Vec3::ZERO
        } else {
            rest[rng.random_range(0..rest.len())]
        };
        let weights = rest
            .iter()
            .map(|p| {
                // 1 within radius / 2, 0 beyond the radius, smooth in between.
                let x = ((radius - p.distance(centre)) / (0.5 * radius)).clamp(0.0, 1.0);
                x * x * (3.0 - 2.0 * x)
            })
            .collect();
        Local {
            inner,
            rest,
            weights,
            centre,
            radius,
        }
    }

    /// The ball's centre (a vertex's rest position) and radius.
    pub fn ball(&self) -> (Vec3, f32) {
        (self.centre, self.radius)
    }
}

impl<A: Animation> Animation for Local<A> {
    fn frames(&self) -> usize {
        self.inner.frames()
    }

    fn positions(&self, frame: usize, out: &mut Vec<Vec3>) {
        self.inner.positions(frame, out);
        for ((p, rest), w) in out.iter_mut().zip(&self.rest).zip(&self.weights) {
            if *w < 1.0 {
                *p = if *w == 0.0 {
                    *rest
                } else {
                    *rest + (*p - *rest) * *w
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::deform::Whirl;
    use crate::mesh::generate;

    /// Outside the ball nothing moves, inside half its radius the inner animation is followed
    /// exactly, and no vertex moves farther than under the inner animation.
    #[test]
    fn only_the_ball_moves() {
        let tube = generate::tube(0.1, 2.0, 24, 120, true);
        let whirl = Whirl::new(&tube, 80, 4);
        let local = Local::new(&tube, whirl.clone(), 0.15, 9);
        let (centre, radius) = local.ball();
        let (mut p, mut q) = (Vec::new(), Vec::new());
        let mut moved_any = false;
        for frame in [0, 10, 20, 30, 50, 79] {
            local.positions(frame, &mut p);
            whirl.positions(frame, &mut q);
            assert_eq!(p.len(), tube.vertex_count());
            for ((now, full), rest) in p.iter().zip(&q).zip(tube.positions()) {
                let d = rest.distance(centre);
                if d >= radius {
                    assert_eq!(now, rest);
                } else if d <= 0.5 * radius {
                    assert_eq!(now, full);
                }
                assert!(now.distance(*rest) <= full.distance(*rest) + 1e-6);
                moved_any |= now != rest;
            }
        }
        assert!(moved_any);
        let still = tube
            .positions()
            .iter()
            .filter(|r| r.distance(centre) >= radius)
            .count();
        assert!(still > tube.vertex_count() / 2, "most of the tube rests");
    }
}
