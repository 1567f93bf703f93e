//! Property tests (proptest, fixed seed, bounded case counts) of the ADB probability model.
//!
//! What the model promises (ALGORITHMS.md §1.5, `adb::probability`):
//!
//! * Eq. 8, `Pr[c ≥ x]` for `s` cells of which `s_A` and `s_B` are well-filled, is the upper
//!   tail of the hypergeometric law. It is in [0, 1], symmetric in `s_A`/`s_B`, non-increasing
//!   in `x`, non-decreasing in `s_A` and in `s_B` (more balls, more shared bins: the law is
//!   stochastically increasing in both), non-increasing in `s` (more bins, fewer collisions),
//!   exactly 1 up to the pigeonhole count `s_A + s_B − s`, 0 beyond `min(s_A, s_B)`.
//! * Eq. 9, `max_x Pr[c ≥ x]·(1 − (1 − LB)^x)` over `1 ≤ x ≤ min(s_A, s_B, x_max)`, is a max of
//!   products of non-negative factors each monotone as above, over a range that only grows with
//!   `s_A`, `s_B` and `x_max`: non-decreasing in `s_A`, `s_B`, `LB` and `x_max`, non-increasing
//!   in `s`; in [0, 1]; never NaN (NaN `LB` counts as 0).
//! * `cell_counts` scales the well-filled counts to the overlap: `s_A` is non-decreasing in the
//!   node's well-filled count, so end to end more well-filled cells never lower the probability.
//! * The lookup table agrees with the direct evaluation within `ProbabilityTable::MAX_ERROR`.
//!
//! The direct evaluation is accurate to about 1e-13, so monotonicity is asserted up to 1e-12.
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use stochastic_collision::adb::probability::{
    CellCounts, cell_counts, collision_probability, node_volume, overlap_volume, prob_at_least,
};
use stochastic_collision::adb::tables::{ProbabilityTable, S_MAX, table};

/// Rounding slack of the direct evaluation.
const EPS: f64 = 1e-12;

fn config(cases: u32) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(0x05EE_DAD8),
        failure_persistence: None,
        ..Config::default()
    }
}

/// `(s, s_a, s_b)` with `s_a, s_b ≤ s`: small (the table's range), or up to thousands.
fn counts() -> impl Strategy<Value = (u32, u32, u32)> {
    prop_oneof![
        3 => 0..=S_MAX,
        1 => 0..=5000u32,
    ]
    .prop_flat_map(|s| (Just(s), 0..=s, 0..=s))
}

fn in_unit(p: f64) -> bool {
    (0.0..=1.0).contains(&p)
}

/// Curvature terms: ordinary, tiny, the ends, and out of range (clamped by the model).
fn lb() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => 0.0..=1.0f64,
        1 => Just(0.0),
        1 => Just(1.0),
        1 => 1e-12..1e-6f64,
        1 => -2.0..3.0f64,
    ]
}

proptest! {
    #![proptest_config(config(300))]

    #[test]
    fn eq8_is_a_probability_symmetric_and_non_increasing_in_x(
        (s, s_a, s_b) in counts(),
        x in 0..40u32,
    ) {
        let p = prob_at_least(s, s_a, s_b, x);
        prop_assert!(in_unit(p), "{p}");
        prop_assert!((p - prob_at_least(s, s_b, s_a, x)).abs() <= EPS);
        prop_assert!(prob_at_least(s, s_a, s_b, x + 1) <= p + EPS);
        // Edge cases: x = 0, beyond min(s_a, s_b), pigeonhole.
        prop_assert_eq!(prob_at_least(s, s_a, s_b, 0), 1.0);
        if x > s_a.min(s_b) {
            prop_assert_eq!(p, 0.0);
        }
        if x >= 1 && x + s <= s_a + s_b {
            prop_assert_eq!(p, 1.0, "pigeonhole: {} forced", s_a + s_b - s);
        }
    }

    #[test]
    fn eq8_is_monotone_in_the_counts(
        (s, s_a, s_b) in counts(),
        x in 1..30u32,
        da in 0..20u32,
        ds in 0..20u32,
    ) {
        let p = prob_at_least(s, s_a, s_b, x);
        // More well-filled cells of A (within s): never lower.
        let more_a = (s_a + da).min(s);
        prop_assert!(prob_at_least(s, more_a, s_b, x) >= p - EPS);
        // More cells in the overlap, same well-filled counts: never higher.
        prop_assert!(prob_at_least(s + ds, s_a, s_b, x) <= p + EPS);
    }

    #[test]
    fn eq9_is_a_probability_and_monotone_where_the_model_says(
        (s, s_a, s_b) in counts(),
        lb in lb(),
        x_max in 0..15u32,
        (da, db, ds) in (0..10u32, 0..10u32, 0..10u32),
        dlb in 0.0..0.5f64,
    ) {
        let c = CellCounts { s, s_a, s_b };
        let p = collision_probability(c, lb, x_max);
        prop_assert!(in_unit(p), "{p}");
        let more = CellCounts { s, s_a: (s_a + da).min(s), s_b: (s_b + db).min(s) };
        prop_assert!(collision_probability(more, lb, x_max) >= p - EPS, "more well-filled");
        let bigger = CellCounts { s: s + ds, s_a, s_b };
        prop_assert!(collision_probability(bigger, lb, x_max) <= p + EPS, "more cells");
        prop_assert!(collision_probability(c, lb + dlb, x_max) >= p - EPS, "larger LB");
        prop_assert!(collision_probability(c, lb, x_max + 1) >= p - EPS, "larger x_max");
        if lb <= 0.0 || x_max == 0 || s_a == 0 || s_b == 0 {
            prop_assert_eq!(p, 0.0);
        }
        prop_assert_eq!(collision_probability(c, f64::NAN, x_max), 0.0);
    }

    #[test]
    fn table_agrees_with_direct_evaluation(
        (s, s_a, s_b) in counts(),
        x in 0..14u32,
        lb in lb(),
        x_max in 0..14u32,
    ) {
        let t = table();
        let (direct, tabled) = (prob_at_least(s, s_a, s_b, x), t.prob_at_least(s, s_a, s_b, x));
        prop_assert!(in_unit(tabled));
        prop_assert!((direct - tabled).abs() <= ProbabilityTable::MAX_ERROR, "{direct} {tabled}");
        prop_assert!(ProbabilityTable::MAX_ERROR <= 1e-6);
        let c = CellCounts { s, s_a, s_b };
        let (direct, tabled) = (collision_probability(c, lb, x_max), t.collision_probability(c, lb, x_max));
        prop_assert!(in_unit(tabled));
        prop_assert!((direct - tabled).abs() <= ProbabilityTable::MAX_ERROR, "{direct} {tabled}");
    }

    #[test]
    fn cell_counts_are_consistent_and_more_well_filled_cells_never_lower_the_probability(
        sides_a in prop::array::uniform3(0.0f32..10.0),
        sides_b in prop::array::uniform3(0.0f32..10.0),
        d in 0.0f32..20.0,
        (wf_a, wf_b) in (0..=64u32, 0..=64u32),
        (da, db) in (0..=64u32, 0..=64u32),
        lb in lb(),
    ) {
        let v = overlap_volume(sides_a, sides_b, d);
        let (va, vb) = (node_volume(sides_a), node_volume(sides_b));
        prop_assert!(v.is_finite() && v >= 0.0 && va >= 0.0 && vb >= 0.0);
        let c = cell_counts(v, va, vb, wf_a, wf_b, S_MAX);
        prop_assert!(c.s <= S_MAX && c.s_a <= c.s && c.s_b <= c.s, "{c:?}");
        let more = cell_counts(v, va, vb, wf_a + da, wf_b + db, S_MAX);
        prop_assert_eq!(more.s, c.s);
        prop_assert!(more.s_a >= c.s_a && more.s_b >= c.s_b, "{c:?} {more:?}");
        let t = table();
        let (p, q) = (t.collision_probability(c, lb, 10), t.collision_probability(more, lb, 10));
        prop_assert!(in_unit(p) && in_unit(q));
        prop_assert!(q >= p - 2.0 * ProbabilityTable::MAX_ERROR, "{p} -> {q}");
        prop_assert!(
            collision_probability(more, lb, 10) >= collision_probability(c, lb, 10) - EPS
        );
    }
}

proptest! {
    #![proptest_config(config(60))]

    /// Extreme counts: `s` in the hundreds of thousands, the pigeonhole regime, zero counts,
    /// counts above `s` (clamped): finite, in [0, 1], never NaN.
    #[test]
    fn extreme_counts_stay_finite_and_in_range(
        s in 0..400_000u32,
        fa in 0.0..=1.2f64,
        fb in 0.0..=1.2f64,
        x in prop_oneof![Just(0u32), Just(1), 1..50u32, Just(u32::MAX)],
        lb in lb(),
    ) {
        let (s_a, s_b) = ((fa * f64::from(s)) as u32, (fb * f64::from(s)) as u32);
        let p = prob_at_least(s, s_a, s_b, x);
        prop_assert!(in_unit(p), "{p}");
        let (ca, cb) = (s_a.min(s), s_b.min(s));
        if x >= 1 && u64::from(x) + u64::from(s) <= u64::from(ca) + u64::from(cb) {
            prop_assert_eq!(p, 1.0);
        }
        let c = CellCounts { s, s_a: ca, s_b: cb };
        let q = collision_probability(c, lb, 10);
        prop_assert!(in_unit(q), "{q}");
        let t = table().collision_probability(c, lb, 10);
        prop_assert!((q - t).abs() <= ProbabilityTable::MAX_ERROR);
    }
}
