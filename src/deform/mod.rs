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
//! [`Crumple`] folds a sheet (or any mesh, about lines across its two largest extents) like
//! paper: in each episode two seeded fold lines, the part beyond each turned about it by an
//! angle that grows to about a half turn (some past it, cutting through the sheet) and
//! returns, so flaps come down onto the sheet and onto each other in layers.
//!
//! [`Local`] confines another animation to a ball around one vertex: the rest of the mesh
//! stays where it is, as in a scene where one part of a large surface is worked on.
//!
//! They implement [`Animation`]: a number of frames and the positions at each.
//!
//! Next: [`crate::tracking`], which these deformations exercise (`examples/tracking_quality.rs`).

mod crumple;
mod local;
mod whirl;

pub use crumple::{Crumple, CrumpleFold};
pub use local::Local;
pub use whirl::{Whirl, WhirlEpisode};

use glam::Vec3;

/// A seeded animation of a mesh's vertices over a number of frames.
pub trait Animation {
    /// Number of frames.
    fn frames(&self) -> usize;

    /// Vertex positions at `frame` (0-based; frames past the end repeat the last frame's
    /// shape), written to `out`.
    fn positions(&self, frame: usize, out: &mut Vec<Vec3>);
}

/// Frames per episode (at least) of the animations here.
const EPISODE_FRAMES: usize = 40;

/// The number of episodes of an animation over `frames` frames.
fn episode_count(frames: usize) -> usize {
    (frames / EPISODE_FRAMES).max(1)
}

/// The axes of `mesh`'s box from its longest extent to its shortest (ties by axis), and the
/// extents.
fn axes_by_extent(mesh: &crate::mesh::TriMesh) -> ([usize; 3], Vec3) {
    let ext = mesh.aabb().extents();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| ext[j].total_cmp(&ext[i]).then(i.cmp(&j)));
    (order, ext)
}

/// The episode of `frame` among `episodes` spread over `frames` frames, and the envelope
/// `sin²(π·τ)` at the fraction `τ` of the episode done: 0 at its start, 1 half-way.
fn episode_at(frames: usize, episodes: usize, frame: usize) -> (usize, f32) {
    let per = frames as f32 / episodes as f32;
    let e = ((frame as f32 / per) as usize).min(episodes - 1);
    let tau = (frame as f32 - e as f32 * per) / per;
    (e, (std::f32::consts::PI * tau).sin().powi(2))
}
