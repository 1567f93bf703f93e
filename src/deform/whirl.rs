//! The whirl: two halves of a mesh winding around an axis in opposite senses.

use std::f32::consts::PI;

use glam::{Quat, Vec3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::{Animation, axes_by_extent, episode_at, episode_count};
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

impl Whirl {
    /// The animation of `mesh` over `frames` frames: `max(1, frames / 40)` episodes.
    pub fn new(mesh: &TriMesh, frames: usize, seed: u64) -> Self {
        let frames = frames.max(1);
        let bbox = mesh.aabb();
        let (order, ext) = axes_by_extent(mesh);
        let unit = |i: usize| Vec3::AXES[i];
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0xD1CE);
        let count = episode_count(frames);
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
        let (e, envelope) = episode_at(self.frames, self.episodes.len(), frame);
        let ep = &self.episodes[e];
        (ep, ep.max_turn * envelope)
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

impl Animation for Whirl {
    fn frames(&self) -> usize {
        Whirl::frames(self)
    }

    fn positions(&self, frame: usize, out: &mut Vec<Vec3>) {
        Whirl::positions(self, frame, out)
    }
}
