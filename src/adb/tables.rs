//! Lookup tables for Eq. 8, built once per process and shared (S1 §6.3: the tables "do not
//! depend on the objects nor on the type of BV, so we need to precompute the lookup tables only
//! once").
//!
//! [`table()`] is the lazily built global [`ProbabilityTable`]; [`collision_probability_tabled`]
//! is Eq. 9 read from it, the function the ADB traversal calls for every node pair it
//! estimates. Counts beyond the table fall back to the direct evaluation in
//! [`super::probability`].
//!
//! Next: [`adb_intersects`](super::adb_intersects), the traversal that ranks and decides by
//! these probabilities.

use std::fmt;
use std::sync::OnceLock;

use super::probability::{self, CellCounts};

/// Largest `s` (cells in `A ∩ B`) held in the table: 64 = a 4×4×4 grid per node. The cell
/// counts of [`probability::cell_counts`] never exceed the cells per node, so with a grid of at
/// most 64 cells every lookup hits the table.
///
/// Memory for `S` = `S_MAX`: `C(S+3, 3)` triples `s_A ≤ s_B ≤ s ≤ S`, times [`X_MAX`] `f32`s:
/// 47 905 × 40 B = 1.92 MB for 64. (For comparison: 125 cells would take 13.7 MB, 216 cells
/// 69 MB; larger grids use the direct path, which evaluates Eq. 9 term by term.)
pub const S_MAX: u32 = 64;

/// Largest `x` held in the table: the papers' cap ([`probability::DEFAULT_X_MAX`]).
pub const X_MAX: u32 = 10;

const XM: usize = X_MAX as usize;

/// `Pr[c(A∩B) ≥ x]` for every `s ≤ S_MAX`, `s_A ≤ s_B ≤ s` (the law is symmetric) and
/// `x = 1..=X_MAX`, stored as `f32`.
///
/// Quantisation: rounding a probability `p ∈ [0, 1]` to `f32` moves it by at most half an ulp,
/// `2^-25 ≈ 2.98·10⁻⁸` ([`ProbabilityTable::MAX_ERROR`]); the `f64` values it is built from are
/// accurate to about `10⁻¹⁴`. Entries that are exactly 0 or 1 (impossible and forced counts)
/// stay exact. (`u16` fixed point would have cost `7.6·10⁻⁶`, too coarse for a `10⁻⁶` check.)
///
/// Built from the ratio recurrence ([`probability::tail_probabilities`], one pass per triple),
/// single-threaded, once per process ([`table()`]).
pub struct ProbabilityTable {
    /// Row `index(s, s_a, s_b)` holds `Pr[c ≥ x]` at `x − 1`.
    rows: Box<[[f32; XM]]>,
}

/// Number of triples `s_A ≤ s_B ≤ s ≤ S_MAX`.
const ROWS: usize = {
    let s = S_MAX as usize;
    (s + 1) * (s + 2) * (s + 3) / 6
};

/// Row of `(s, a, b)` with `a ≤ b ≤ s ≤ S_MAX`: the triples are laid out by `s`, then `a`,
/// then `b`.
#[inline]
fn index(s: u32, a: u32, b: u32) -> usize {
    let (s, a, b) = (s as usize, a as usize, b as usize);
    // Σ_{s' < s} (s'+1)(s'+2)/2  +  Σ_{a' < a} (s − a' + 1)  +  (b − a)
    s * (s + 1) * (s + 2) / 6 + a * (2 * s + 3 - a) / 2 + (b - a)
}

impl ProbabilityTable {
    /// Largest difference between a table entry and the exact `Pr[c ≥ x]`: `f32` rounding of a
    /// value in `[0, 1]` (`2^-25`), plus a margin for the `f64` evaluation.
    pub const MAX_ERROR: f64 = 3.0e-8;

    /// Builds the table (single-threaded; see the type docs for size and time). Prefer the shared
    /// [`table()`].
    pub fn build() -> Self {
        let mut rows = vec![[0.0f32; XM]; ROWS].into_boxed_slice();
        let mut buf = [0.0f64; XM];
        for s in 0..=S_MAX {
            for a in 0..=s {
                for b in a..=s {
                    probability::tail_probabilities(s, a, b, &mut buf);
                    rows[index(s, a, b)] = buf.map(|p| p as f32);
                }
            }
        }
        Self { rows }
    }

    /// Heap memory held by the table, in bytes.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(&*self.rows)
    }

    /// The stored tails `[Pr[c ≥ 1], …, Pr[c ≥ X_MAX]]` of `(s, s_a, s_b)` (counts above `s`
    /// clamped to `s`; `s_a`, `s_b` in either order), or `None` when `s > S_MAX`.
    #[inline]
    pub fn tails(&self, s: u32, s_a: u32, s_b: u32) -> Option<&[f32; XM]> {
        if s > S_MAX {
            return None;
        }
        let (a, b) = ordered(s_a.min(s), s_b.min(s));
        Some(&self.rows[index(s, a, b)])
    }

    /// Eq. 8, `Pr[c(A∩B) ≥ x]`, from the table when `s ≤ S_MAX` and `x ≤ X_MAX`, else from
    /// [`probability::prob_at_least`]. Same edge cases as that function; within
    /// [`Self::MAX_ERROR`] of it.
    #[inline]
    pub fn prob_at_least(&self, s: u32, s_a: u32, s_b: u32, x: u32) -> f64 {
        if x == 0 {
            return 1.0;
        }
        let (a, b) = ordered(s_a.min(s), s_b.min(s));
        if x > a {
            return 0.0;
        }
        if s > S_MAX || x > X_MAX {
            return probability::prob_at_least(s, s_a, s_b, x);
        }
        f64::from(self.rows[index(s, a, b)][x as usize - 1])
    }

    /// Eq. 9 ([`probability::collision_probability`]) with the tails read from the table; the
    /// direct evaluation when `s > S_MAX` or `min(s_A, s_B, x_max) > X_MAX`. No allocation;
    /// within [`Self::MAX_ERROR`] of the direct value.
    #[inline]
    pub fn collision_probability(&self, counts: CellCounts, lb: f64, x_max: u32) -> f64 {
        let s = counts.s;
        let (a, b) = ordered(counts.s_a.min(s), counts.s_b.min(s));
        let k = a.min(x_max);
        if k == 0 || lb.is_nan() || lb <= 0.0 {
            return 0.0; // also NaN LB
        }
        let lb = lb.min(1.0);
        if s > S_MAX || k > X_MAX {
            return probability::collision_probability(counts, lb, x_max);
        }
        let row = &self.rows[index(s, a, b)];
        let q = 1.0 - lb;
        let mut f = 0.0f64;
        let mut best = 0.0f64;
        for &t in &row[..k as usize] {
            let t = f64::from(t);
            if t <= best {
                break; // tails are non-increasing and f ≤ 1: nothing later can win
            }
            f = lb + q * f;
            let v = t * f;
            if v > best {
                best = v;
            }
        }
        best
    }
}

impl fmt::Debug for ProbabilityTable {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ProbabilityTable")
            .field("s_max", &S_MAX)
            .field("x_max", &X_MAX)
            .field("rows", &self.rows.len())
            .field("memory_bytes", &self.memory_bytes())
            .finish()
    }
}

#[inline]
fn ordered(a: u32, b: u32) -> (u32, u32) {
    if a <= b { (a, b) } else { (b, a) }
}

static TABLE: OnceLock<ProbabilityTable> = OnceLock::new();

/// The process-wide table, built on first use (call it once at startup to keep the build out
/// of a time-critical frame).
#[inline]
pub fn table() -> &'static ProbabilityTable {
    TABLE.get_or_init(ProbabilityTable::build)
}

/// Eq. 9 via the shared [`table()`]: the node-pair probability of the ADB traversal
/// (see [`ProbabilityTable::collision_probability`]).
#[inline]
pub fn collision_probability_tabled(counts: CellCounts, lb: f64, x_max: u32) -> f64 {
    table().collision_probability(counts, lb, x_max)
}
