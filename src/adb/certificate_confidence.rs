//! The measured reliability of an approximate interpenetration certificate: the map of an open
//! mesh decides its inside by a vote of three rays, which a hole can fool, so before such a
//! certificate may settle a query its rate of being right is measured on poses of the mesh
//! against itself, checked by the exact query.
use glam::Vec3;
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};

use super::interior::{InteriorMap, PairLookup};
use crate::bvh::{CollisionMesh, QueryWorkspace, intersects};
use crate::geometry::Pose;
use crate::poses::random_rotation;

/// Seed of the poses a tree's build measures on: training poses, a seed of their own (the
/// `accuracy_vs_time` report evaluates on other seeds).
pub(super) const TRAINING_SEED: u64 = 0x0CE7_7A11;

/// One-sided level of the lower confidence bound the measurement reports.
const LOWER_BOUND_LEVEL: f64 = 0.95;

/// What [`InteriorMap::measure_certificate`] found: how often an approximate certificate was
/// right.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CertificateReliability {
    /// Poses tried.
    pub poses: usize,
    /// Poses the certificate claimed a collision on.
    pub certified: usize,
    /// Of those, the poses the exact query says collide.
    pub correct: usize,
    /// The lower one-sided 95 % Clopper–Pearson bound on the rate of being right (0 when
    /// nothing was certified): the confidence a certificate of this map is given.
    pub confidence: f64,
}

impl InteriorMap {
    /// For a map that is not exact, measures how often its certificate is right on `poses`
    /// seeded poses of `mesh` (the mesh it was built from) against itself, checked by the
    /// exact query, and makes the lower 95 % bound on that rate the map's
    /// [`certificate_confidence`](InteriorMap::certificate_confidence). An exact map is left
    /// as it is (its certificate is never wrong). Returns what was measured (`None` for an
    /// exact map).
    pub fn measure_certificate(
        &mut self,
        mesh: &CollisionMesh,
        poses: usize,
        seed: u64,
    ) -> Option<CertificateReliability> {
        if self.exact {
            return None;
        }
        let found = measure(self, mesh, poses, seed);
        self.certificate_confidence = found.confidence;
        Some(found)
    }
}

/// Measures how often `map`'s certificate (both ways, the mesh against itself) is right on
/// `poses` seeded random poses (random rotation, translation uniform over the mesh's box, so
/// the boxes overlap), each certified pose checked by the exact query.
fn measure(
    map: &InteriorMap,
    mesh: &CollisionMesh,
    poses: usize,
    seed: u64,
) -> CertificateReliability {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut ws = QueryWorkspace::new();
    let aabb = mesh.bvh().root_aabb();
    let extent = aabb.max - aabb.min;
    let (mut certified, mut correct) = (0, 0);
    for _ in 0..poses {
        let rotation = random_rotation(&mut rng);
        let shift = Vec3::new(
            rng.random_range(-1.0f32..=1.0),
            rng.random_range(-1.0f32..=1.0),
            rng.random_range(-1.0f32..=1.0),
        ) * extent;
        // Rotate about the box centre, then shift.
        let centre = aabb.center();
        let pose = Pose::new(centre + shift - rotation * centre, rotation);
        if let PairLookup::Crossing(_) = InteriorMap::look_up_pair(map, map, &pose) {
            certified += 1;
            correct += usize::from(intersects(mesh, &Pose::IDENTITY, mesh, &pose, &mut ws));
        }
    }
    CertificateReliability {
        poses,
        certified,
        correct,
        confidence: lower_bound(correct, certified, 1.0 - LOWER_BOUND_LEVEL),
    }
}

/// The lower one-sided Clopper–Pearson bound at error `alpha` on a rate seen `successes`
/// times in `trials`: the `p` whose chance of `successes` or more is `alpha` (by bisection
/// of the binomial tail).
fn lower_bound(successes: usize, trials: usize, alpha: f64) -> f64 {
    if trials == 0 || successes == 0 {
        return 0.0;
    }
    if successes == trials {
        return alpha.powf(1.0 / trials as f64);
    }
    let upper_tail = |p: f64| -> f64 {
        // P(X ≥ successes) for X ~ Binomial(trials, p), summed in log space.
        let (n, ln_p, ln_q) = (trials as f64, p.ln(), (1.0 - p).ln());
        let mut ln_choose = 0.0f64;
        let mut total = 0.0;
        for k in 0..=trials {
            if k > 0 {
                ln_choose += ((n - k as f64 + 1.0) / k as f64).ln();
            }
            if k >= successes {
                total += (ln_choose + k as f64 * ln_p + (n - k as f64) * ln_q).exp();
            }
        }
        total
    };
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if upper_tail(mid) < alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bound against its closed form where every trial succeeded (0.05^(1/n)) and against
    /// the beta quantile otherwise (95 of 100: qbeta(0.05, 95, 6) = 0.8977).
    #[test]
    fn the_lower_bound_matches_the_beta_quantile() {
        assert!((lower_bound(100, 100, 0.05) - 0.05f64.powf(0.01)).abs() < 1e-12);
        assert!((lower_bound(95, 100, 0.05) - 0.8977).abs() < 1e-3);
        assert_eq!(lower_bound(0, 10, 0.05), 0.0);
        assert_eq!(lower_bound(0, 0, 0.05), 0.0);
        assert!(lower_bound(5, 10, 0.05) < 0.5);
    }
}
