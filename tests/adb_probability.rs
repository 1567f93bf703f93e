//! The ADB-tree probability model: Eq. 8 against exact rational arithmetic, large-count
//! stability, Eq. 9, the lookup table against direct evaluation, and the volume and cell-count
//! estimates.
use stochastic_collision::adb::probability::*;
use stochastic_collision::adb::tables::*;

/// Largest `s` checked against exact binomials (`C(60, 30)² < 2^128`).
const EXACT_S: usize = 60;

/// Pascal's triangle in `u128`, exact up to `EXACT_S`.
fn pascal() -> Vec<Vec<u128>> {
    let mut c = vec![vec![0u128; EXACT_S + 1]; EXACT_S + 1];
    for n in 0..=EXACT_S {
        c[n][0] = 1;
        for k in 1..=n {
            c[n][k] = c[n - 1][k - 1] + if k < n { c[n - 1][k] } else { 0 };
        }
    }
    c
}

/// Exact `Pr[c ≥ x]` for `x = 0..=min(s_a, s_b) + 1`: suffix sums of exact integer terms, one
/// rounding per conversion.
fn exact_tails(c: &[Vec<u128>], s: usize, sa: usize, sb: usize) -> Vec<f64> {
    let hi = sa.min(sb);
    let term = |t: usize| -> u128 {
        if t > sb || sa < t || s - sb < sa - t {
            0
        } else {
            c[sb][t] * c[s - sb][sa - t]
        }
    };
    let den = c[s][sa];
    let mut out = vec![0.0; hi + 2];
    let mut suffix = 0u128;
    for x in (0..=hi).rev() {
        suffix += term(x);
        out[x] = suffix as f64 / den as f64;
    }
    out
}

#[test]
fn eq8_matches_exact_binomials_for_small_s() {
    let c = pascal();
    let mut buf = vec![0.0; EXACT_S + 2];
    let mut checked = 0usize;
    for s in 0..=EXACT_S {
        for sa in 0..=s {
            for sb in 0..=s {
                let exact = exact_tails(&c, s, sa, sb);
                let (s32, a32, b32) = (s as u32, sa as u32, sb as u32);
                tail_probabilities(s32, a32, b32, &mut buf[..exact.len() - 1]);
                for (x, &e) in exact.iter().enumerate() {
                    let p = prob_at_least(s32, a32, b32, x as u32);
                    assert!(
                        (p - e).abs() <= 1e-12,
                        "Pr[c>={x}] s={s} sa={sa} sb={sb}: {p} vs exact {e}"
                    );
                    // Small tails keep their relative accuracy.
                    if e > 0.0 && e < 1e-3 {
                        assert!(
                            ((p - e) / e).abs() <= 1e-11,
                            "relative: s={s} sa={sa} sb={sb} x={x}: {p} vs {e}"
                        );
                    }
                    if x >= 1 {
                        let q = buf[x - 1];
                        assert!((q - e).abs() <= 1e-12, "tail_probabilities s={s} x={x}");
                    }
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 1_000_000, "{checked}");
}

#[test]
fn eq8_edge_cases() {
    // x = 0 is certain, even with nothing to collide.
    for (s, a, b) in [(0, 0, 0), (5, 0, 3), (100_000, 7, 9)] {
        assert_eq!(prob_at_least(s, a, b, 0), 1.0);
    }
    // s = 0, s_A = 0, s_B = 0: nothing collides.
    assert_eq!(prob_at_least(0, 0, 0, 1), 0.0);
    assert_eq!(prob_at_least(0, 3, 4, 1), 0.0); // counts are clamped to s
    for x in 1..5 {
        assert_eq!(prob_at_least(10, 0, 7, x), 0.0);
        assert_eq!(prob_at_least(10, 7, 0, x), 0.0);
    }
    // x beyond min(s_A, s_B) is impossible.
    assert_eq!(prob_at_least(50, 3, 40, 4), 0.0);
    assert_eq!(prob_at_least(50, 3, 40, u32::MAX), 0.0);
    // s_A = s: every cell of B collides.
    assert_eq!(prob_at_least(20, 20, 7, 7), 1.0);
    assert_eq!(prob_at_least(20, 20, 7, 8), 0.0);
    // One-cell law.
    assert_eq!(prob_at_least(1, 1, 1, 1), 1.0);
    assert!((prob_at_least(2, 1, 1, 1) - 0.5).abs() < 1e-15);
    // Overflowing inputs stay sane.
    let p = prob_at_least(u32::MAX, u32::MAX / 2, u32::MAX / 3, 3);
    assert!(p.is_finite() && (0.0..=1.0).contains(&p));
    assert_eq!(prob_at_least(u32::MAX, u32::MAX, u32::MAX, u32::MAX), 1.0);
}

#[test]
fn eq8_pigeonhole_is_exactly_one_below_the_forced_count() {
    for (s, a, b) in [
        (10u32, 7u32, 6u32),
        (64, 40, 50),
        (1000, 700, 800),
        (100_000, 99_990, 20),
    ] {
        let forced = a + b - s;
        for x in 1..=forced {
            assert_eq!(prob_at_least(s, a, b, x), 1.0, "s={s} a={a} b={b} x={x}");
            assert_eq!(table().prob_at_least(s, a, b, x), 1.0);
        }
        let next = prob_at_least(s, a, b, forced + 1);
        assert!(next > 0.0 && next <= 1.0, "s={s}: {next}");
    }
    // Where the next count is genuinely uncertain, it is below 1: 7 + 6 − 10 = 3 forced.
    assert!(prob_at_least(10, 7, 6, 4) < 0.99);
}

#[test]
fn eq8_large_s_is_finite_monotone_symmetric() {
    let cases = [
        (1000u32, 1u32, 1u32),
        (1000, 10, 10),
        (1000, 500, 500),
        (1000, 30, 900),
        (1000, 999, 999),
        (5000, 2500, 2500),
        (5000, 40, 60),
        (5000, 4000, 1500),
        (100_000, 50_000, 50_000),
        (100_000, 100, 100),
        (100_000, 3, 99_000),
        (100_000, 99_999, 5),
    ];
    for (s, a, b) in cases {
        let hi = a.min(b);
        let xs: Vec<u32> = (0..=hi.min(40))
            .chain((0..=30).map(|i| (u64::from(hi) * i / 30) as u32))
            .chain([hi, hi + 1])
            .collect();
        let mut xs = xs;
        xs.sort_unstable();
        xs.dedup();
        let mut prev = 1.0;
        for &x in &xs {
            let p = prob_at_least(s, a, b, x);
            assert!(
                p.is_finite() && (0.0..=1.0).contains(&p),
                "s={s} a={a} b={b} x={x}: {p}"
            );
            assert!(
                p <= prev + 1e-15,
                "not monotone: s={s} a={a} b={b} x={x}: {p} > {prev}"
            );
            let q = prob_at_least(s, b, a, x);
            assert!(
                (p - q).abs() <= 1e-12,
                "asymmetric s={s} a={a} b={b} x={x}: {p} vs {q}"
            );
            prev = p;
        }
        assert_eq!(prob_at_least(s, a, b, hi + 1), 0.0);
    }
}

#[test]
fn eq8_large_s_mean_and_zero_term() {
    // Σ_{x≥1} Pr[c ≥ x] = E[c] = s_A·s_B/s, over the whole support in one pass.
    for (s, a, b) in [
        (1000u32, 500u32, 500u32),
        (5000, 2500, 2500),
        (100_000, 50_000, 50_000),
    ] {
        let mut tails = vec![0.0; a.min(b) as usize];
        tail_probabilities(s, a, b, &mut tails);
        assert!(tails.windows(2).all(|w| w[1] <= w[0]));
        let mean: f64 = tails.iter().sum();
        let want = f64::from(a) * f64::from(b) / f64::from(s);
        assert!(
            ((mean - want) / want).abs() < 1e-9,
            "s={s}: {mean} vs {want}"
        );
        assert_eq!(tails[0], 1.0);
        assert!(*tails.last().unwrap() < 1e-250);
    }
    // 1 − Pr[c ≥ 1] = P(0) = Π_{i<s_A} (s − s_B − i)/(s − i), a stable product here.
    for (s, a, b) in [
        (1000u32, 3u32, 200u32),
        (5000, 20, 100),
        (100_000, 30, 2000),
    ] {
        let p0: f64 = (0..a)
            .map(|i| f64::from(s - b - i) / f64::from(s - i))
            .product();
        let p = prob_at_least(s, a, b, 1);
        assert!(((1.0 - p) - p0).abs() < 1e-12, "s={s}: {} vs {p0}", 1.0 - p);
    }
    // Deep tails keep their relative accuracy: Pr[c ≥ s_A] = P(s_A) = Π_{i<s_A} (s_B − i)/(s − i).
    for (s, a, b) in [
        (5000u32, 40u32, 600u32),
        (100_000, 30, 2000),
        (1000, 200, 300),
        (64, 20, 21),
    ] {
        let exact: f64 = (0..a)
            .map(|i| f64::from(b - i) / f64::from(s - i))
            .product();
        let p = prob_at_least(s, a, b, a);
        assert!(
            exact > 1e-250 && ((p - exact) / exact).abs() < 1e-10,
            "s={s}: {p} vs {exact}"
        );
    }
    // Below about 1e-270 the tail is flushed to 0, never garbage: here P(100) ≈ 1e-342.
    assert_eq!(prob_at_least(100_000, 100, 100, 100), 0.0);
}

#[test]
fn eq9_collision_probability() {
    let counts = |s, s_a, s_b| CellCounts { s, s_a, s_b };
    for c in [
        counts(64, 10, 12),
        counts(30, 25, 20),
        counts(5000, 300, 200),
        counts(8, 1, 1),
    ] {
        assert_eq!(collision_probability(c, 0.0, 10), 0.0);
        assert_eq!(collision_probability(c, -1.0, 10), 0.0);
        assert_eq!(collision_probability(c, f64::NAN, 10), 0.0);
        let p1 = prob_at_least(c.s, c.s_a, c.s_b, 1);
        assert!((collision_probability(c, 1.0, 10) - p1).abs() < 1e-13);
        assert!((collision_probability(c, 7.0, 10) - p1).abs() < 1e-13);
        assert_eq!(collision_probability(c, 0.5, 0), 0.0);
        // Monotone in LB and in the x cap.
        let mut prev = 0.0;
        for i in 0..=50 {
            let p = collision_probability(c, f64::from(i) / 50.0, 10);
            assert!((0.0..=1.0).contains(&p));
            assert!(p >= prev - 1e-15, "LB monotone: {c:?} {i}");
            prev = p;
        }
        let mut prev = 0.0;
        for x_max in 0..=20 {
            let p = collision_probability(c, 0.3, x_max);
            assert!(p >= prev - 1e-15);
            prev = p;
        }
    }
    // The cap is respected: with x_max = 1 the value is Pr[c ≥ 1]·LB.
    let c = counts(64, 30, 30);
    let want = prob_at_least(64, 30, 30, 1) * 0.2;
    assert!((collision_probability(c, 0.2, 1) - want).abs() < 1e-15);
    // And the maximum is over the capped range only: explicit check.
    for x_max in [1u32, 3, 10, 25] {
        let lb: f64 = 0.15;
        let mut want: f64 = 0.0;
        for x in 1..=x_max.min(30) {
            let f = 1.0 - (1.0 - lb).powi(x as i32);
            want = want.max(prob_at_least(64, 30, 30, x) * f);
        }
        let got = collision_probability(c, lb, x_max);
        assert!((got - want).abs() < 1e-13, "x_max={x_max}: {got} vs {want}");
    }
    // No collision cells on one side: 0.
    assert_eq!(collision_probability(counts(64, 0, 40), 1.0, 10), 0.0);
    assert_eq!(collision_probability(counts(0, 0, 0), 1.0, 10), 0.0);
    // Many x (streaming path) agrees with the stack path and stays in range.
    let big = counts(5000, 300, 200);
    let a = collision_probability(big, 0.01, 64);
    let b = collision_probability(big, 0.01, 65);
    let c200 = collision_probability(big, 0.01, 200);
    assert!(
        b >= a - 1e-15 && c200 >= b - 1e-15 && c200 <= 1.0,
        "{a} {b} {c200}"
    );
    let pig = counts(100, 80, 90); // 70 forced collisions
    let p = collision_probability(pig, 0.01, 1000);
    let forced: f64 = 1.0 - 0.99f64.powi(70);
    assert!(p >= forced - 1e-12 && p <= 1.0, "{p} vs {forced}");
}

#[test]
fn curvature_bounds() {
    assert_eq!(depth_lower_bound(0, 0, 0, 0), 0.0);
    assert_eq!(depth_lower_bound(0, 0, 5, 7), 0.0);
    assert_eq!(depth_lower_bound(5, 7, 5, 7), 1.0);
    assert!((depth_lower_bound(2, 3, 5, 5) - 0.5).abs() < 1e-15);
    assert_eq!(
        depth_lower_bound(u32::MAX, u32::MAX, u32::MAX, u32::MAX),
        1.0
    );
    assert_eq!(depth_lower_bound(9, 9, 1, 1), 1.0);
}

#[test]
fn table_matches_direct_evaluation_everywhere() {
    let tab = table();
    assert_eq!(tab.memory_bytes(), 47_905 * 10 * 4);
    let mut direct = [0.0; X_MAX as usize];
    let mut worst = 0.0f64;
    for s in 0..=S_MAX {
        for a in 0..=s {
            for b in a..=s {
                tail_probabilities(s, a, b, &mut direct);
                let row = tab.tails(s, a, b).unwrap();
                assert_eq!(tab.tails(s, b, a).unwrap(), row);
                for (x, (&t, &d)) in row.iter().zip(&direct).enumerate() {
                    let err = (f64::from(t) - d).abs();
                    worst = worst.max(err);
                    assert!(
                        err <= ProbabilityTable::MAX_ERROR,
                        "s={s} a={a} b={b} x={}",
                        x + 1
                    );
                    if d == 0.0 || d == 1.0 {
                        assert_eq!(f64::from(t), d);
                    }
                }
            }
        }
    }
    assert!(worst <= 1e-6);
    // The lookup functions, including the symmetric order and the clamping of counts.
    assert_eq!(tab.prob_at_least(64, 50, 10, 0), 1.0);
    assert_eq!(tab.prob_at_least(64, 50, 10, 11), 0.0);
    let d = prob_at_least(64, 50, 10, 8);
    assert!((tab.prob_at_least(64, 50, 10, 8) - d).abs() <= 1e-7);
    assert!((tab.prob_at_least(64, 10, 50, 8) - d).abs() <= 1e-7);
    assert_eq!(tab.prob_at_least(20, 90, 90, 20), 1.0);
}

#[test]
fn table_falls_back_beyond_its_range() {
    let tab = table();
    assert!(tab.tails(S_MAX + 1, 1, 1).is_none());
    for (s, a, b, x) in [
        (65u32, 30u32, 40u32, 5u32),
        (500, 100, 200, 3),
        (64, 40, 40, 25),
        (100_000, 60, 70, 1),
    ] {
        assert_eq!(tab.prob_at_least(s, a, b, x), prob_at_least(s, a, b, x));
    }
    for (c, x_max) in [
        (
            CellCounts {
                s: 125,
                s_a: 40,
                s_b: 60,
            },
            10,
        ),
        (
            CellCounts {
                s: 64,
                s_a: 40,
                s_b: 40,
            },
            30,
        ),
        (
            CellCounts {
                s: 100_000,
                s_a: 500,
                s_b: 900,
            },
            10,
        ),
    ] {
        let got = collision_probability_tabled(c, 0.4, x_max);
        assert_eq!(got, collision_probability(c, 0.4, x_max));
    }
}

#[test]
fn tabled_eq9_matches_direct() {
    let mut checked = 0;
    for s in (0..=S_MAX).step_by(3) {
        for a in (0..=s).step_by(2) {
            for b in (0..=s).step_by(5) {
                let c = CellCounts { s, s_a: a, s_b: b };
                for lb in [0.0, 1e-9, 0.05, 0.5, 0.97, 1.0, 1.5, f64::NAN] {
                    for x_max in [0, 1, 4, 10] {
                        let t = collision_probability_tabled(c, lb, x_max);
                        let d = collision_probability(c, lb, x_max);
                        assert!(
                            (t - d).abs() <= 1e-7,
                            "{c:?} lb={lb} x_max={x_max}: {t} vs {d}"
                        );
                        assert!((0.0..=1.0).contains(&t));
                        checked += 1;
                    }
                }
            }
        }
    }
    assert!(checked > 10_000);
}

#[test]
fn ln_factorial_is_accurate() {
    // Exact small values, and the table/Stirling seam against summed logs.
    assert_eq!(ln_factorial(0), 0.0);
    assert_eq!(ln_factorial(1), 0.0);
    assert!((ln_factorial(5) - 120f64.ln()).abs() < 1e-15);
    let mut sum = 0.0f64;
    for n in 2..=5000u32 {
        sum += f64::from(n).ln();
        let got = ln_factorial(n);
        assert!(((got - sum) / sum).abs() < 1e-12, "n={n}: {got} vs {sum}");
    }
    let big = ln_factorial(u32::MAX);
    assert!(big.is_finite() && big > 9.0e10);
}

// ------------------------------------------------------------------------------------------------
// Volumes and cell counts
// ------------------------------------------------------------------------------------------------

#[test]
fn box_volume_formula() {
    let cube = [2.0f32, 2.0, 2.0];
    assert!((box_overlap_volume(cube, cube, 0.0) - 8.0).abs() < 1e-12);
    let brick = [3.0f32, 1.0, 2.0];
    assert!((box_overlap_volume(brick, brick, 0.0) - 6.0).abs() < 1e-12);
    // Never above the smaller box, symmetric in A and B.
    let other = [2.5f32, 2.0, 0.5];
    for d in [0.0f32, 0.3, 1.0] {
        let v = box_overlap_volume(brick, other, d);
        assert!(v <= 2.5 + 1e-12);
        assert_eq!(v, box_overlap_volume(other, brick, d));
    }
    // V1 dominates near 0: (a − d)·b·c for a cube at small d.
    assert!((box_overlap_volume(cube, cube, 0.5) - 1.5 * 4.0).abs() < 1e-9);
    // Clamping: far beyond every diagonal the value is 0, not a positive even power.
    let diag = ((12.0f64).sqrt() as f32).next_up();
    for d in [diag, diag * 1.01, 5.0, 100.0, f32::MAX, f32::INFINITY] {
        assert_eq!(box_overlap_volume(cube, cube, d), 0.0, "d={d}");
    }
    // Between a and the diagonals only V2/V3 are left, and they stay small and positive.
    let v = box_overlap_volume(cube, cube, 2.5);
    assert!(v > 0.0 && v < 8.0 * 0.2, "{v}");
    // Monotone non-increasing in d.
    let mut prev = f64::INFINITY;
    for i in 0..=400 {
        let v = box_overlap_volume(brick, other, i as f32 * 0.01);
        assert!(v <= prev && v >= 0.0, "i={i}");
        prev = v;
    }
    // Degenerate and bad input: 0, never NaN.
    assert_eq!(box_overlap_volume([0.0, 0.0, 0.0], cube, 0.0), 0.0);
    assert_eq!(box_overlap_volume([1.0, 1.0, 0.0], cube, 0.0), 0.0);
    assert_eq!(box_overlap_volume([f32::NAN, 1.0, 1.0], cube, 0.0), 0.0);
    assert_eq!(box_overlap_volume(cube, cube, f32::NAN), 0.0);
    assert_eq!(
        box_overlap_volume(cube, cube, -0.5),
        box_overlap_volume(cube, cube, 0.5)
    );
    let inf = [f32::INFINITY; 3];
    assert!(!box_overlap_volume(inf, inf, 1.0).is_nan());
    assert!(!box_overlap_volume(inf, inf, f32::INFINITY).is_nan());
}

#[test]
fn sphere_lens_limits() {
    use std::f64::consts::PI;
    let ball = |r: f64| 4.0 / 3.0 * PI * r * r * r;
    // Contained (and d = 0): the smaller ball.
    assert_eq!(sphere_lens_volume(2.0, 1.0, 0.0), ball(1.0));
    assert_eq!(sphere_lens_volume(1.0, 2.0, 0.5), ball(1.0));
    assert_eq!(sphere_lens_volume(2.0, 1.0, 1.0), ball(1.0)); // internally touching
    // Equal radii at d = 0 and at tiny d: the whole ball, no NaN.
    assert_eq!(sphere_lens_volume(1.0, 1.0, 0.0), ball(1.0));
    for d in [1e-300, 1e-12, 1e-6] {
        let v = sphere_lens_volume(1.0, 1.0, d);
        assert!((v - ball(1.0)).abs() < 1e-5 && v <= ball(1.0), "d={d}: {v}");
    }
    // Touching and disjoint: 0.
    assert_eq!(sphere_lens_volume(1.0, 2.0, 3.0), 0.0);
    assert_eq!(sphere_lens_volume(1.0, 2.0, 30.0), 0.0);
    let v = sphere_lens_volume(1.0, 2.0, 3.0 - 1e-9);
    assert!((0.0..1e-12).contains(&v));
    // Textbook value: two unit balls one radius apart share 5π/12.
    assert!((sphere_lens_volume(1.0, 1.0, 1.0) - 5.0 * PI / 12.0).abs() < 1e-12);
    // Continuous at containment, monotone in d.
    let inner = sphere_lens_volume(2.0, 1.0, 1.0 + 1e-9);
    assert!((inner - ball(1.0)).abs() < 1e-6);
    let mut prev = f64::INFINITY;
    for i in 0..=310 {
        let v = sphere_lens_volume(2.0, 1.0, f64::from(i) * 0.01);
        assert!(v <= prev + 1e-12 && v >= 0.0, "i={i}");
        prev = v;
    }
    // Degenerate input.
    assert_eq!(sphere_lens_volume(0.0, 1.0, 0.0), 0.0);
    assert_eq!(sphere_lens_volume(-1.0, 1.0, 0.0), 0.0);
    assert_eq!(sphere_lens_volume(f64::NAN, 1.0, 0.5), 0.0);
    assert_eq!(sphere_lens_volume(1.0, 1.0, f64::NAN), 0.0);
    assert!(!sphere_lens_volume(1e200, 1e200, 1e200).is_nan());
}

#[test]
fn overlap_volume_policy() {
    let cube = [2.0f32, 2.0, 2.0];
    // Similar boxes: the box formula.
    let similar = [2.2f32, 1.9, 2.1];
    assert_eq!(
        overlap_volume(cube, similar, 0.7),
        box_overlap_volume(cube, similar, 0.7)
    );
    // Very different sizes: the bounding spheres' lens, clamped to the smaller box.
    let small = [0.5f32, 0.5, 0.5];
    let v = overlap_volume(cube, small, 0.2);
    assert!((v - 0.125).abs() < 1e-12, "{v}");
    let v = overlap_volume(cube, small, 1.9);
    let r_big = 0.5 * 12f64.sqrt();
    let r_small = 0.5 * 0.75f64.sqrt();
    let lens = sphere_lens_volume(r_big, r_small, 1.9f32.into());
    assert!((v - lens.min(0.125)).abs() < 1e-12 && v > 0.0);
    assert!(v <= 0.125 && v < box_overlap_volume(cube, cube, 0.0));
    // Never above the smaller node volume; 0 far away.
    for (a, b) in [(cube, small), (cube, similar), ([4.0, 0.1, 0.1], cube)] {
        for d in [0.0f32, 0.5, 1.0, 3.0] {
            let v = overlap_volume(a, b, d);
            assert!(v >= 0.0 && v <= node_volume(a).min(node_volume(b)) + 1e-12);
        }
        assert_eq!(overlap_volume(a, b, 1e6), 0.0);
    }
    // Flat nodes keep a positive volume (one cell layer thick) and a positive overlap.
    let flat = [2.0f32, 2.0, 0.0];
    assert!((node_volume(flat) - 2.0 * 2.0 * 0.5).abs() < 1e-12);
    let v = overlap_volume(flat, flat, 0.0);
    assert!((v - node_volume(flat)).abs() < 1e-12);
    assert!(overlap_volume(flat, cube, 0.5) > 0.0);
    // Point boxes and bad input: 0, not NaN.
    assert_eq!(node_volume([0.0; 3]), 0.0);
    assert_eq!(overlap_volume([0.0; 3], cube, 0.0), 0.0);
    assert_eq!(overlap_volume([f32::NAN; 3], cube, 0.0), 0.0);
    assert_eq!(overlap_volume(cube, cube, f32::NAN), 0.0);
}

/// Two trees of different grid resolutions: each fill density is over its own grid (a node
/// whose every cell is well filled counts every overlap cell, whatever the other's resolution),
/// and with equal grids the counts are `cell_counts`'.
#[test]
fn cell_counts_of_different_grids_use_each_trees_own_density() {
    // A: 2³ cells, all well filled; B: 4³ cells, a quarter well filled; full overlap.
    let c = cell_counts_of_grids(8.0, (8.0, 8, 8), (8.0, 16, 64));
    assert_eq!(
        c,
        CellCounts {
            s: 64,
            s_a: 64,
            s_b: 16
        }
    );
    // Swapped, the same counts swapped.
    let d = cell_counts_of_grids(8.0, (8.0, 16, 64), (8.0, 8, 8));
    assert_eq!((d.s, d.s_a, d.s_b), (c.s, c.s_b, c.s_a));
    for (v, wa, wb) in [(8.0, 16, 40), (4.0, 3, 60), (1.0, 64, 0)] {
        assert_eq!(
            cell_counts_of_grids(v, (8.0, wa, 64), (8.0, wb, 64)),
            cell_counts(v, 8.0, 8.0, wa, wb, 64)
        );
    }
    assert_eq!(
        cell_counts_of_grids(4.0, (8.0, 3, 0), (8.0, 3, 64)),
        CellCounts::default()
    );
}

#[test]
fn cell_count_invariants() {
    // Equal nodes fully overlapping: every cell, densities carried over.
    let c = cell_counts(8.0, 8.0, 8.0, 16, 40, 64);
    assert_eq!(
        c,
        CellCounts {
            s: 64,
            s_a: 16,
            s_b: 40
        }
    );
    // Half the volume: half the cells, densities scaled (ρ·s rounded, halves up).
    let c = cell_counts(4.0, 8.0, 8.0, 16, 40, 64);
    assert_eq!(
        c,
        CellCounts {
            s: 32,
            s_a: 8,
            s_b: 20
        }
    );
    // The coarser grid sets the cell volume.
    let c = cell_counts(1.0, 2.0, 8.0, 64, 64, 64);
    assert_eq!(
        c,
        CellCounts {
            s: 8,
            s_a: 8,
            s_b: 8
        }
    );
    // A tiny positive overlap still has one cell.
    let c = cell_counts(1e-12, 8.0, 8.0, 64, 64, 64);
    assert_eq!(
        c,
        CellCounts {
            s: 1,
            s_a: 1,
            s_b: 1
        }
    );
    // No overlap, no cells, no grid: zeros.
    for c in [
        cell_counts(0.0, 8.0, 8.0, 10, 10, 64),
        cell_counts(-1.0, 8.0, 8.0, 10, 10, 64),
        cell_counts(f64::NAN, 8.0, 8.0, 10, 10, 64),
        cell_counts(4.0, 8.0, 8.0, 10, 10, 0),
    ] {
        assert_eq!(c, CellCounts::default());
    }
    // Zero/NaN volumes with a positive overlap: the whole node.
    assert_eq!(
        cell_counts(1.0, 0.0, 0.0, 32, 64, 64),
        CellCounts {
            s: 64,
            s_a: 32,
            s_b: 64
        }
    );
    assert_eq!(cell_counts(1.0, f64::NAN, f64::INFINITY, 8, 8, 64).s, 64);
    // Overlap above the node volume and counts above the grid are clamped.
    assert_eq!(
        cell_counts(1e300, 1.0, 1.0, 500, 7, 64),
        CellCounts {
            s: 64,
            s_a: 64,
            s_b: 7
        }
    );
    // Extreme grids do not overflow.
    let c = cell_counts(1.0, 1.0, 1.0, u32::MAX, u32::MAX / 2, u32::MAX);
    assert_eq!(c.s, u32::MAX);
    assert_eq!(c.s_a, u32::MAX);
    // Invariants on a sweep.
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    for _ in 0..20_000 {
        let n = (next() % 300) as u32;
        let va = (next() % 1000) as f64 / 100.0;
        let vb = (next() % 1000) as f64 / 100.0;
        let v = va.min(vb) * (next() % 1001) as f64 / 1000.0;
        let wa = (next() % 400) as u32;
        let wb = (next() % 400) as u32;
        let c = cell_counts(v, va, vb, wa, wb, n);
        assert!(c.s_a <= c.s && c.s_b <= c.s && c.s <= n, "{c:?}");
        assert_eq!(c.s == 0, n == 0 || v == 0.0, "{c:?} v={v}");
        // The definitions, in plain arithmetic: s = round(v / max(V_A, V_B) · n) in [1, n],
        // s_A = round(w_A · s / n) (halves up) at most s.
        let vmax = va.max(vb);
        if v > 0.0 && n > 0 && vmax > 0.0 {
            let s = (v / vmax * f64::from(n)).round().clamp(1.0, f64::from(n)) as u32;
            let scaled = |w: u32| {
                let (w, s, n) = (u128::from(w.min(n)), u128::from(s), u128::from(n));
                ((2 * w * s + n) / (2 * n)).min(s) as u32
            };
            assert_eq!((c.s, c.s_a, c.s_b), (s, scaled(wa), scaled(wb)), "v={v}");
        }
    }
}

#[test]
fn end_to_end_pipeline_stays_in_range() {
    // Two equal boxes sliding apart: fewer cells with distance, probability in range, 0 at the
    // end. (The probability itself need not be monotone: s, s_A, s_B are rounded separately.)
    let sides = [1.0f32, 0.8, 0.6];
    let vol = node_volume(sides);
    let mut prev_s = u32::MAX;
    let mut p = 1.0;
    for i in 0..=60 {
        let d = i as f32 * 0.025;
        let v = overlap_volume(sides, sides, d);
        let c = cell_counts(v, vol, vol, 24, 30, 64);
        assert!(c.s <= prev_s);
        prev_s = c.s;
        p = collision_probability_tabled(c, depth_lower_bound(6, 7, 10, 10), DEFAULT_X_MAX);
        assert!((0.0..=1.0).contains(&p));
    }
    assert_eq!(p, 0.0);
}
