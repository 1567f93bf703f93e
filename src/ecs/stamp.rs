//! Run stamps: a run's number modulo 2³², stored where every run reads it (the collider and
//! pair tables' hot arrays, the broad phase) to say "changed in this run" by comparing for
//! equality and "how long ago" by subtracting. Aged every 2³⁰ runs, so that no stamp aliases
//! the current run after 2³² runs.

/// A run's number as a stamp.
#[inline]
pub(crate) fn stamp(run: u64) -> u32 {
    run as u32
}

/// Every this many runs the stamps are aged ([`age_stamp`]).
const STAMP_SWEEP: u64 = 1 << 30;

/// The largest age a stamp keeps, in runs.
const STAMP_MAX_AGE: u32 = 1 << 31;

/// Whether the stamps are aged in `run` (every 2³⁰ runs).
#[inline]
pub(crate) fn stamp_sweep_due(run: u64) -> bool {
    run.is_multiple_of(STAMP_SWEEP)
}

/// Sets a stamp older than 2³¹ runs (at `now`) to exactly that age. Aged every 2³⁰ runs, no
/// stamp gets 2³² runs old, so none ever reads as the current run (ages saturate at 2³¹).
#[inline]
pub(crate) fn age_stamp(s: &mut u32, now: u32) {
    if now.wrapping_sub(*s) > STAMP_MAX_AGE {
        *s = now.wrapping_sub(STAMP_MAX_AGE);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stamp_never_reads_as_the_current_run_however_many_runs_pass() {
        // Set in run 5, then left alone while the runs go on: it is aged at every sweep, and
        // 2³² runs later (and every later run up to 2³⁴) it is not "this run".
        let set = 5u64;
        let mut s = stamp(set);
        let mut run = set;
        while run < (1 << 34) + 10 {
            // The runs between sweeps change nothing; the sweep runs at every multiple.
            let next_sweep = (run / STAMP_SWEEP + 1) * STAMP_SWEEP;
            for probe in [next_sweep - 1, run + 1, set + (1 << 32), set + (1 << 33)] {
                if probe > set && probe < next_sweep {
                    assert_ne!(s, stamp(probe), "aliased in run {probe}");
                }
            }
            run = next_sweep;
            assert!(stamp_sweep_due(run));
            age_stamp(&mut s, stamp(run));
            assert_ne!(s, stamp(run));
            let age = stamp(run).wrapping_sub(s);
            let true_age = run - set;
            assert_eq!(u64::from(age), true_age.min(u64::from(STAMP_MAX_AGE)));
            // Until the next sweep, it grows at most to below 2³² runs: never "this run".
            assert!(u64::from(age) + STAMP_SWEEP < 1 << 32);
        }
    }

    #[test]
    fn recent_stamps_keep_their_age() {
        let now = stamp(3 << 30);
        let mut s = now.wrapping_sub(1000);
        age_stamp(&mut s, now);
        assert_eq!(now.wrapping_sub(s), 1000);
        assert!(!stamp_sweep_due((3 << 30) + 1));
    }
}
