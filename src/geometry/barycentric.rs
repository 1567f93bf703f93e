//! Barycentric weights of a point on a triangle, and a correction at that point spread to the
//! triangle's corners so that the point moves by exactly the correction.
use glam::{DVec3, Vec3};

use super::closest_points::closest_point_on_triangle;

/// Barycentric weights `(w0, w1, w2)` (non-negative, summing to 1) of the point of `tri`
/// closest to `p`.
///
/// A degenerate triangle (collinear or coincident corners) is handled as its longest edge:
/// the weights are the closest point's position along it (all three `1/3` when the corners
/// coincide). Never NaN for finite input.
///
/// # Example
/// ```
/// use stochastic_collision::geometry::barycentric_weights;
/// use glam::DVec3;
/// let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
/// let w = barycentric_weights(DVec3::new(0.25, 0.25, 3.0), &tri);
/// assert!((w[0] - 0.5).abs() < 1e-12 && (w[1] - 0.25).abs() < 1e-12);
/// ```
pub fn barycentric_weights(p: DVec3, tri: &[DVec3; 3]) -> [f64; 3] {
    let q = closest_point_on_triangle(p, tri);
    let (e0, e1, d) = (tri[1] - tri[0], tri[2] - tri[0], q - tri[0]);
    let (d00, d01, d11) = (e0.dot(e0), e0.dot(e1), e1.dot(e1));
    let denom = d00 * d11 - d01 * d01;
    // Relative to the edges' lengths: a sliver's denominator is all rounding.
    if denom > 1e-12 * d00 * d11 && denom.is_finite() {
        let (d20, d21) = (d.dot(e0), d.dot(e1));
        let w1 = (d11 * d20 - d01 * d21) / denom;
        let w2 = (d00 * d21 - d01 * d20) / denom;
        return normalised([1.0 - w1 - w2, w1, w2]);
    }
    // Degenerate: the longest edge carries the point.
    let edges = [(0, 1), (1, 2), (2, 0)];
    let (i, j) = edges
        .into_iter()
        .max_by(|a, b| {
            let la = (tri[a.1] - tri[a.0]).length_squared();
            let lb = (tri[b.1] - tri[b.0]).length_squared();
            la.total_cmp(&lb)
        })
        .unwrap_or((0, 1));
    let edge = tri[j] - tri[i];
    let len2 = edge.length_squared();
    let usable = len2 > 0.0 && len2.is_finite();
    if !usable {
        return [1.0 / 3.0; 3];
    }
    let t = ((q - tri[i]).dot(edge) / len2).clamp(0.0, 1.0);
    let mut w = [0.0; 3];
    w[i] = 1.0 - t;
    w[j] = t;
    w
}

/// Weights clamped to `[0, 1]` and scaled to sum to 1 (rounding leaves them slightly off).
fn normalised(w: [f64; 3]) -> [f64; 3] {
    let w = w.map(|x| x.clamp(0.0, 1.0));
    let sum = w[0] + w[1] + w[2];
    if sum > 0.0 {
        w.map(|x| x / sum)
    } else {
        [1.0 / 3.0; 3]
    }
}

/// Corner displacements that move the point with barycentric `weights` by exactly `delta`,
/// with the least total squared displacement: corner `i` moves by `wᵢ·delta / Σ wⱼ²`
/// (Raghupathi et al.'s spreading of a correction at the closest points, for three corners).
/// A corner with weight 0 does not move.
///
/// # Example
/// ```
/// use stochastic_collision::geometry::spread_to_corners;
/// use glam::Vec3;
/// let w = [0.5, 0.25, 0.25];
/// let d = spread_to_corners(w, Vec3::Y);
/// let moved = d[0] * 0.5 + d[1] * 0.25 + d[2] * 0.25;
/// assert!((moved - Vec3::Y).length() < 1e-6);
/// ```
pub fn spread_to_corners(weights: [f64; 3], delta: Vec3) -> [Vec3; 3] {
    let norm2 = weights.iter().map(|w| w * w).sum::<f64>();
    let usable = norm2 > 0.0;
    if !usable {
        return [Vec3::ZERO; 3];
    }
    weights.map(|w| delta * (w / norm2) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(tri: &[DVec3; 3], w: [f64; 3]) -> DVec3 {
        tri[0] * w[0] + tri[1] * w[1] + tri[2] * w[2]
    }

    #[test]
    fn weights_reproduce_the_closest_point_and_sum_to_one() {
        let tri = [
            DVec3::new(0.3, -1.0, 2.0),
            DVec3::new(2.0, 0.5, 1.0),
            DVec3::new(-0.5, 1.5, 0.0),
        ];
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 6.0 - 3.0
        };
        for _ in 0..1000 {
            let p = DVec3::new(next(), next(), next());
            let w = barycentric_weights(p, &tri);
            assert!(w.iter().all(|&x| (0.0..=1.0).contains(&x)), "{w:?}");
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            let q = closest_point_on_triangle(p, &tri);
            assert!((point(&tri, w) - q).length() < 1e-9, "{p:?}");
        }
    }

    #[test]
    fn degenerate_triangles_weigh_their_longest_edge() {
        // Collinear: the point's place along the segment from corner 0 to corner 2.
        let line = [
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(4.0, 0.0, 0.0),
        ];
        let w = barycentric_weights(DVec3::new(3.0, 1.0, 0.0), &line);
        assert!((point(&line, w) - DVec3::new(3.0, 0.0, 0.0)).length() < 1e-12);
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        let dot = [DVec3::ONE; 3];
        assert_eq!(barycentric_weights(DVec3::ZERO, &dot), [1.0 / 3.0; 3]);
    }

    #[test]
    fn spreading_moves_the_point_by_the_correction_and_nothing_else_more() {
        for w in [
            [1.0, 0.0, 0.0],
            [0.5, 0.5, 0.0],
            [0.2, 0.3, 0.5],
            [1.0 / 3.0; 3],
        ] {
            let delta = Vec3::new(0.1, -0.3, 0.2);
            let d = spread_to_corners(w, delta);
            let moved = d[0] * w[0] as f32 + d[1] * w[1] as f32 + d[2] * w[2] as f32;
            assert!((moved - delta).length() < 1e-6, "{w:?}");
            // The least-squares spreading never moves a corner further than a uniform push
            // would need to (|delta| / max weight ≤ 3 |delta|).
            for (k, dk) in d.iter().enumerate() {
                assert!(dk.length() <= delta.length() * 3.0 + 1e-6);
                if w[k] == 0.0 {
                    assert_eq!(*dk, Vec3::ZERO);
                }
            }
        }
        assert_eq!(spread_to_corners([0.0; 3], Vec3::X), [Vec3::ZERO; 3]);
    }
}
