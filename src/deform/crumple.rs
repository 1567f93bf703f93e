//! The crumple: a sheet folded like paper, two seeded folds at a time.

use std::f32::consts::PI;

use glam::{Quat, Vec3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::{Animation, axes_by_extent, episode_at, episode_count};
use crate::mesh::TriMesh;

/// One fold of a [`Crumple`] episode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrumpleFold {
    /// A point of the fold line (in the sheet's plane at rest).
    pub point: Vec3,
    /// The fold line's direction (a unit vector in the sheet's plane).
    pub direction: Vec3,
    /// Vertices whose rest position lies on this side of the line (positive dot product
    /// with their offset from `point`) turn about it.
    pub side: Vec3,
    /// Largest angle of the episode, radians (about π: a half turn lays the flap flat on
    /// the sheet; past it, the flap cuts through).
    pub max_angle: f32,
}

/// A seeded crumpling of a mesh's rest positions (see [the module docs](super)): episodes
/// of two folds each, whose angles grow from zero to about a half turn and return.
///
/// # Example
/// ```
/// use stochastic_collision::deform::{Animation, Crumple};
/// use stochastic_collision::mesh::generate;
/// let cloth = generate::cloth_grid(1.0, 1.0, 20, 20);
/// let crumple = Crumple::new(&cloth, 80, 3);
/// let mut p = Vec::new();
/// crumple.positions(0, &mut p);
/// assert_eq!(p, cloth.positions()); // Episodes start flat.
/// crumple.positions(20, &mut p);
/// // Half-way through the first episode, the flaps stand out of the sheet's plane.
/// assert!(p.iter().map(|q| q.y.abs()).fold(0.0, f32::max) > 0.1);
/// ```
#[derive(Debug, Clone)]
pub struct Crumple {
    rest: Vec<Vec3>,
    frames: usize,
    episodes: Vec<[CrumpleFold; 2]>,
}

impl Crumple {
    /// The crumpling of `mesh` over `frames` frames: `max(1, frames / 40)` episodes. The sheet's
    /// plane is that of its box's two largest extents.
    pub fn new(mesh: &TriMesh, frames: usize, seed: u64) -> Self {
        let frames = frames.max(1);
        let bbox = mesh.aabb();
        let (order, ext) = axes_by_extent(mesh);
        let (u, w) = (Vec3::AXES[order[0]], Vec3::AXES[order[1]]);
        let (eu, ew) = (ext[order[0]], ext[order[1]]);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0xC12C);
        let count = episode_count(frames);
        let episodes = (0..count)
            .map(|_| {
                [(); 2].map(|_| {
                    let point = bbox.center()
                        + u * (eu * rng.random_range(-0.25f32..0.25))
                        + w * (ew * rng.random_range(-0.25f32..0.25));
                    let phi = rng.random_range(0.0..PI);
                    let direction = u * phi.cos() + w * phi.sin();
                    let across = u * -phi.sin() + w * phi.cos();
                    let side = if rng.random::<bool>() {
                        across
                    } else {
                        -across
                    };
                    let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
                    CrumpleFold {
                        point,
                        direction,
                        side,
                        max_angle: sign * PI * rng.random_range(0.85f32..1.05),
                    }
                })
            })
            .collect();
        Crumple {
            rest: mesh.positions().to_vec(),
            frames,
            episodes,
        }
    }

    /// The episodes.
    pub fn episodes(&self) -> &[[CrumpleFold; 2]] {
        &self.episodes
    }

    /// The folds of `frame`'s episode and the fraction of their largest angles at that frame.
    pub fn turn(&self, frame: usize) -> (&[CrumpleFold; 2], f32) {
        let (e, envelope) = episode_at(self.frames, self.episodes.len(), frame);
        (&self.episodes[e], envelope)
    }
}

impl Animation for Crumple {
    fn frames(&self) -> usize {
        self.frames
    }

    fn positions(&self, frame: usize, out: &mut Vec<Vec3>) {
        let (folds, k) = self.turn(frame.min(self.frames - 1));
        let turns = folds.map(|f| Quat::from_axis_angle(f.direction, k * f.max_angle));
        out.clear();
        out.extend(self.rest.iter().map(|&rest| {
            let mut p = rest;
            if k != 0.0 {
                for (f, q) in folds.iter().zip(&turns) {
                    if (rest - f.point).dot(f.side) > 0.0 {
                        p = f.point + *q * (p - f.point);
                    }
                }
            }
            p
        }));
    }
}
