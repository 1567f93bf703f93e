//! Benchmark deformations that bring distant parts of any mesh into contact and apart again.
//!
//! [`Whirl`] turns every vertex about an axis through the mesh's centre by an angle
//! proportional to its signed distance from that centre along the mesh's longest extent: the
//! two halves wind around the axis in opposite senses, and once the angle at the ends passes a
//! quarter turn they cut through each other. The animation runs in episodes: in each, a
//! seeded choice of axes, centre offset and largest angle; the angle grows from zero and
//! returns to zero, so contact regions appear, move and vanish on every input, closed or open,
//! flat (a cloth), tubular or convoluted.
//!
//! Next: [`crate::tracking`], which these deformations exercise (`examples/tracking_quality.rs`).

use std::f32::consts::PI;

use glam::{Quat, Vec3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use crate::mesh::TriMesh;

/// One episode of a [`Whirl`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WhirlEpisode {
    /// Axis along which the angle varies (a unit vector).
    pub along: Vec3,
    /// Axis of rotation (a unit vector, perpendicular to `along`).
    pub axis: Vec3,
    /// Centre of the whirl.
    pub centre: Vec3,
    /// Half the extent of the mesh along `along` (the angle is `k · s` with
    /// `s = offset / half_extent`).
    pub half_extent: f32,
    /// Largest `k` of the episode, radians.
    pub max_turn: f32,
}

/// A seeded whirl animation of a mesh's rest positions (see the module docs).
///
/// # Example
/// ```
/// use stochastic_collision::deform::Whirl;
/// use stochastic_collision::mesh::generate;
/// let cloth = generate::cloth_grid(1.0, 1.0, 20, 20);
/// let whirl = Whirl::new(&cloth, 60, 7);
/// let mut p = Vec::new();
/// whirl.positions(0, &mut p);
/// assert_eq!(p, cloth.positions()); // Episodes start at rest.
/// whirl.positions(15, &mut p);
/// assert_ne!(p, cloth.positions());
/// ```
#[derive(Debug, Clone)]
pub struct Whirl {
    rest: Vec<Vec3>,
    frames: usize,
    episodes: Vec<WhirlEpisode>,
}

/// Frames per episode (at least).
const EPISODE_FRAMES: usize = 40;

impl Whirl {
    /// The animation of `mesh` over `frames` frames: `max(1, frames / 40)` episodes.
    pub fn new(mesh: &TriMesh, frames: usize, seed: u64) -> Self {
        let frames = frames.max(1);
        let bbox = mesh.aabb();
        let ext = bbox.extents();
        let mut order = [0usize, 1, 2];
        order.sort_by(|&i, &j| ext[j].total_cmp(&ext[i]).then(i.cmp(&j)));
        let unit = |i: usize| Vec3::AXES[i];
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0xD1CE);
        let count = (frames / EPISODE_FRAMES).max(1);
        let episodes = (0..count)
            .map(|e| {
                // Alternate between the longest and the second-longest extent; the rotation
                // axis is the other of the two, so a flat sheet winds out of its plane.
                let (u, a) = if e % 2 == 0 {
                    (order[0], order[1])
                } else {
                    (order[1], order[0])
                };
                let half = (0.5 * ext[u]).max(f32::MIN_POSITIVE);
                let shift = rng.random_range(-0.15f32..0.15) * ext[u];
                let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
                WhirlEpisode {
                    along: unit(u),
                    axis: unit(a) * sign,
                    centre: bbox.center() + unit(u) * shift,
                    half_extent: half,
                    max_turn: PI * rng.random_range(0.75f32..1.6),
                }
            })
            .collect();
        Whirl {
            rest: mesh.positions().to_vec(),
            frames,
            episodes,
        }
    }

    /// The episodes.
    pub fn episodes(&self) -> &[WhirlEpisode] {
        &self.episodes
    }

    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// The episode of `frame` and the turn `k` at that frame.
    pub fn turn(&self, frame: usize) -> (&WhirlEpisode, f32) {
        let n = self.episodes.len();
        let per = self.frames as f32 / n as f32;
        let e = ((frame as f32 / per) as usize).min(n - 1);
        let tau = (frame as f32 - e as f32 * per) / per;
        let ep = &self.episodes[e];
        (ep, ep.max_turn * (PI * tau).sin().powi(2))
    }

    /// Vertex positions at `frame` (0-based; frames past the end repeat the last episode's
    /// shape), written to `out`.
    pub fn positions(&self, frame: usize, out: &mut Vec<Vec3>) {
        let (ep, k) = self.turn(frame.min(self.frames - 1));
        out.clear();
        out.extend(self.rest.iter().map(|&p| {
            let d = p - ep.centre;
            let s = d.dot(ep.along) / ep.half_extent;
            if k == 0.0 {
                p
            } else {
                ep.centre + Quat::from_axis_angle(ep.axis, k * s) * d
            }
        }));
    }
}
