//! Seeded shape generators: meshes no test or constant was chosen on, for held-out
//! evaluation (re-exported by [`generate`](super)).

use std::f32::consts::TAU;

use glam::Vec3;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::super::TriMesh;
use super::{icosphere, tube};

/// Sinusoids in each lateral direction of a [`random_tube`]'s centre line.
const WAVES: usize = 3;

/// A capped tube of `radius` and `radial_segments` × `length_segments` like
/// [`tube`](super::tube), whose centre line runs along Y from `-length/2` to
/// `length/2` and wanders sideways along a seeded sum of sinusoids (up to 3 waves over the
/// length in each direction). The bend is bounded so that the centre line's curvature stays
/// below `1 / (2·radius)` and its sideways offset within `length / 8`: the tube does not
/// touch itself at rest. The cross-sections are perpendicular to the centre line
/// (parallel-transported frames). Same topology and counts as the straight capped tube;
/// outward normals.
///
/// # Example
/// ```
/// use stochastic_collision::mesh::generate;
/// let a = generate::random_tube(0.1, 2.0, 16, 64, 3);
/// assert!(a.is_closed());
/// assert_eq!(a.triangle_count(), generate::tube(0.1, 2.0, 16, 64, true).triangle_count());
/// assert_ne!(a.positions(), generate::random_tube(0.1, 2.0, 16, 64, 4).positions());
/// ```
///
/// # Panics
/// If a size is NaN or infinite.
pub fn random_tube(
    radius: f32,
    length: f32,
    radial_segments: u32,
    length_segments: u32,
    seed: u64,
) -> TriMesh {
    let straight = tube(radius, length, radial_segments, length_segments, true);
    let (r, len) = (radius.abs(), length.abs().max(f32::MIN_POSITIVE));
    let (rs, ls) = (radial_segments.max(3), length_segments.max(1));
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x70BE);
    // Per lateral direction: (amplitude, angular frequency over y, phase).
    let mut waves = [[(0.0f32, 0.0f32, 0.0f32); WAVES]; 2];
    for side in &mut waves {
        for wave in side.iter_mut() {
            let cycles = rng.random_range(0.5f32..3.0);
            *wave = (
                rng.random_range(0.2f32..1.0),
                TAU * cycles / len,
                rng.random_range(0.0..TAU),
            );
        }
    }
    // Scale the amplitudes so that |c''| ≤ 1/(2r) and |offset| ≤ len/8 in each direction
    // (the curvature of a graph is at most its second derivative).
    let curvature_cap = if r > 0.0 { 0.5 / r } else { f32::INFINITY };
    for side in &mut waves {
        let bend: f32 = side.iter().map(|(a, w, _)| a * w * w).sum();
        let reach: f32 = side.iter().map(|(a, _, _)| *a).sum();
        let scale = (curvature_cap / bend.max(f32::MIN_POSITIVE))
            .min(len / 8.0 / reach.max(f32::MIN_POSITIVE))
            / std::f32::consts::SQRT_2;
        for wave in side.iter_mut() {
            wave.0 *= scale;
        }
    }
    let offset = |y: f32| {
        let f = |side: &[(f32, f32, f32); WAVES]| {
            side.iter()
                .map(|(a, w, p)| a * (w * y + p).sin())
                .sum::<f32>()
        };
        Vec3::new(f(&waves[0]), y, f(&waves[1]))
    };
    let rings: Vec<f32> = (0..=ls)
        .map(|k| len * (k as f32 / ls as f32 - 0.5))
        .collect();
    let centres: Vec<Vec3> = rings.iter().map(|&y| offset(y)).collect();
    let tangent = |k: usize| {
        let (a, b) = (
            centres[k.saturating_sub(1)],
            centres[(k + 1).min(ls as usize)],
        );
        (b - a).normalize_or(Vec3::Y)
    };
    let mut positions = Vec::with_capacity(straight.vertex_count());
    // The straight tube's frame is (x, y, z) with the section spanned by x and z; transport
    // x along the centre line so that the sections turn with it.
    let mut normal = Vec3::X;
    for (k, &c) in centres.iter().enumerate() {
        let t = tangent(k);
        normal = (normal - normal.dot(t) * t).normalize_or(t.any_orthonormal_vector());
        let binormal = normal.cross(t);
        for j in 0..rs {
            let (sin, cos) = (TAU * j as f32 / rs as f32).sin_cos();
            positions.push(c + r * (cos * normal + sin * binormal));
        }
    }
    positions.push(centres[0]);
    positions.push(centres[ls as usize]);
    match TriMesh::new(positions, straight.triangles().to_vec()) {
        Ok(mesh) => mesh,
        Err(e) => panic!("generate::random_tube: {e} (sizes must be finite)"),
    }
}

/// An [`icosphere`](super::icosphere) of `radius` and `subdivisions` whose every
/// vertex is moved along its direction from the centre by a seeded uniform factor in
/// `[1 − noise, 1 + noise]` (`noise` clamped to `[0, 0.9]`): a noisy, and with a large
/// `noise` spiky, closed star-shaped surface that does not touch itself at rest.
///
/// # Example
/// ```
/// use stochastic_collision::mesh::generate;
/// let s = generate::noisy_sphere(1.0, 3, 0.3, 7);
/// assert!(s.is_closed());
/// assert!(s.positions().iter().all(|p| (0.7 - 1e-5..=1.3 + 1e-5).contains(&p.length())));
/// ```
///
/// # Panics
/// If `radius` is NaN or infinite.
pub fn noisy_sphere(radius: f32, subdivisions: u32, noise: f32, seed: u64) -> TriMesh {
    let sphere = icosphere(radius, subdivisions);
    let noise = if noise.is_nan() {
        0.0
    } else {
        noise.clamp(0.0, 0.9)
    };
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x5B1C);
    let positions = sphere
        .positions()
        .iter()
        .map(|&p| p * (1.0 + noise * rng.random_range(-1.0f32..=1.0)))
        .collect();
    match TriMesh::new(positions, sphere.triangles().to_vec()) {
        Ok(mesh) => mesh,
        Err(e) => panic!("generate::noisy_sphere: {e} (sizes must be finite)"),
    }
}
