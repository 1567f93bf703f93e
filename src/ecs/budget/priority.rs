//! Sharing the frame budget among pairs: priorities, node-pair slices, per-pair seeds.
use bevy_ecs::entity::Entity;
use glam::{Vec3, Vec3A};

use crate::geometry::Aabb;

/// Priority of a pair for the budget (higher: a bigger slice, tested earlier): pairs whose last
/// answer was uncertain, whose boxes overlap deeply and that move fast need the work most.
///
/// `last_probability` is the pair's confidence in the previous run (`None`: a new pair, as
/// uncertain as can be); `motion` the relative translation since the previous run.
#[inline]
pub fn pair_priority(last_probability: Option<f64>, a: &Aabb, b: &Aabb, motion: Vec3) -> f32 {
    // In SIMD lanes (this runs for every candidate pair of every run).
    let (amin, amax) = (Vec3A::from(a.min), Vec3A::from(a.max));
    let (bmin, bmax) = (Vec3A::from(b.min), Vec3A::from(b.max));
    let p = last_probability.unwrap_or(0.5) as f32;
    let uncertainty = 1.0 - (2.0 * p - 1.0).abs();
    let overlap = (amax.min(bmax) - amin.max(bmin)).max(Vec3A::ZERO);
    let size = (amax - amin).min(bmax - bmin).max(Vec3A::splat(1e-6));
    let closeness = (overlap / size).min(Vec3A::ONE).min_element();
    let speed = if motion == Vec3::ZERO {
        0.0
    } else {
        (motion.length() / size.max_element()).min(4.0)
    };
    (0.25 + uncertainty) * (0.25 + closeness) * (1.0 + speed)
}

/// Node-pair slices: every pair gets `min`, the rest of `total` goes out in proportion to the
/// priorities, each slice at most `max`.
pub fn slices(priorities: &[f32], total: u64, min: u64, max: u64) -> Vec<u64> {
    let share = SliceShare::new(priorities.iter().copied(), total, min, max);
    priorities.iter().map(|&p| share.slice(p)).collect()
}

/// The rule of [`slices`], for slices handed out one at a time.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SliceShare {
    min: u64,
    max: u64,
    /// Node pairs left after every pair's minimum, per unit of priority.
    per_priority: f64,
}

impl SliceShare {
    /// The share of `total` among pairs of the given priorities.
    pub fn new(priorities: impl Iterator<Item = f32>, total: u64, min: u64, max: u64) -> Self {
        let (n, sum) = priorities.fold((0u64, 0.0f64), |(n, s), p| (n + 1, s + f64::from(p)));
        Self::from_sum(n, sum, total, min, max)
    }

    /// The share of `total` among `n` pairs whose priorities sum to `sum`.
    pub fn from_sum(n: u64, sum: f64, total: u64, min: u64, max: u64) -> Self {
        let rest = total.saturating_sub(n * min) as f64;
        Self {
            min,
            max: max.max(min),
            per_priority: if sum > 0.0 { rest / sum } else { 0.0 },
        }
    }

    /// The slice of a pair of priority `p`.
    pub fn slice(&self, p: f32) -> u64 {
        (self.min + (self.per_priority * f64::from(p)) as u64).clamp(self.min, self.max)
    }
}

/// The seed of a pair's randomness in one run: the same for any thread count or order.
pub fn pair_seed(seed: u64, frame: u64, a: Entity, b: Entity) -> u64 {
    let mut h = seed ^ 0x9e37_79b9_7f4a_7c15;
    for v in [frame, a.to_bits(), b.to_bits()] {
        h = splitmix(h ^ v);
    }
    h
}

fn splitmix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slices_respect_min_max_and_total() {
        let s = slices(&[1.0, 3.0], 108, 4, 1000);
        assert_eq!(s, vec![4 + 25, 4 + 75]);
        let s = slices(&[1.0, 1.0], 4, 8, 1000);
        assert_eq!(s, vec![8, 8]);
        let s = slices(&[1.0], 1_000_000, 8, 100);
        assert_eq!(s, vec![100]);
    }

    #[test]
    fn uncertain_close_fast_pairs_come_first() {
        let a = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let deep = Aabb::new(Vec3::splat(0.2), Vec3::splat(1.2));
        let graze = Aabb::new(Vec3::splat(0.95), Vec3::splat(1.95));
        let p = |last, b: &Aabb, m| pair_priority(last, &a, b, m);
        assert!(p(None, &deep, Vec3::ZERO) > p(None, &graze, Vec3::ZERO));
        assert!(p(Some(0.5), &deep, Vec3::ZERO) > p(Some(1.0), &deep, Vec3::ZERO));
        assert!(p(None, &deep, Vec3::X) > p(None, &deep, Vec3::ZERO));
    }
}
