//! The ADB probability model on arbitrary counts and floats: every result is finite and in
//! [0, 1], the table agrees with the direct evaluation, the counts stay consistent.
#![no_main]

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use stochastic_collision::adb::probability::{
    CellCounts, box_overlap_volume, cell_counts, collision_probability, depth_lower_bound,
    node_volume, overlap_volume, prob_at_least, sphere_lens_volume, tail_probabilities,
};
use stochastic_collision::adb::tables::{ProbabilityTable, table};

#[derive(Debug, Arbitrary)]
struct Input {
    s: u32,
    s_a: u32,
    s_b: u32,
    x: u8,
    x_max: u8,
    lb: f64,
    sides_a: [f32; 3],
    sides_b: [f32; 3],
    d: f32,
    wf_a: u32,
    wf_b: u32,
    cells: u32,
    depths: [u32; 4],
    small: bool,
}

fn unit(p: f64, what: &str) {
    assert!((0.0..=1.0).contains(&p), "{what} = {p}");
}

fuzz_target!(|i: Input| {
    // Keep the direct evaluation cheap: its cost grows with the law's width (~sqrt(s)).
    let (s, s_a, s_b) = if i.small {
        (i.s % 80, i.s_a % 80, i.s_b % 80)
    } else {
        (i.s % 2_000_000, i.s_a, i.s_b)
    };
    let x = u32::from(i.x);
    let x_max = u32::from(i.x_max % 40);
    let p = prob_at_least(s, s_a, s_b, x);
    unit(p, "prob_at_least");
    assert!(
        (p - prob_at_least(s, s_b, s_a, x)).abs() <= 1e-12,
        "symmetry"
    );
    if x > 0 {
        assert!(
            prob_at_least(s, s_a, s_b, x - 1) >= p - 1e-12,
            "tail non-increasing in x"
        );
    }
    let t = table().prob_at_least(s, s_a, s_b, x);
    unit(t, "tabled prob_at_least");
    assert!(
        (t - p).abs() <= ProbabilityTable::MAX_ERROR,
        "table {t} vs direct {p}"
    );

    let mut tails = [0.0; 12];
    tail_probabilities(s, s_a, s_b, &mut tails);
    for (k, w) in tails.iter().enumerate() {
        unit(*w, "tail");
        if k > 0 {
            assert!(*w <= tails[k - 1]);
        }
    }

    let counts = CellCounts {
        s,
        s_a: s_a.min(s),
        s_b: s_b.min(s),
    };
    let c = collision_probability(counts, i.lb, x_max);
    unit(c, "collision_probability");
    let ct = table().collision_probability(counts, i.lb, x_max);
    unit(ct, "tabled collision_probability");
    assert!(
        (c - ct).abs() <= ProbabilityTable::MAX_ERROR,
        "eq9 table {ct} vs direct {c}"
    );

    let v = overlap_volume(i.sides_a, i.sides_b, i.d);
    assert!(v.is_finite() && v >= 0.0, "overlap {v}");
    let bv = box_overlap_volume(i.sides_a, i.sides_b, i.d);
    assert!(bv.is_finite() && bv >= 0.0, "box overlap {bv}");
    let sl = sphere_lens_volume(i.sides_a[0].into(), i.sides_b[0].into(), i.d.into());
    assert!(!sl.is_nan() && sl >= 0.0, "lens {sl}");
    let (va, vb) = (node_volume(i.sides_a), node_volume(i.sides_b));
    assert!(va >= 0.0 && vb >= 0.0, "{va} {vb}");
    let cc = cell_counts(v, va, vb, i.wf_a, i.wf_b, i.cells);
    assert!(
        cc.s <= i.cells && cc.s_a <= cc.s && cc.s_b <= cc.s,
        "{cc:?}"
    );
    let [da, db, ma, mb] = i.depths;
    unit(depth_lower_bound(da, db, ma, mb), "depth_lower_bound");
});
