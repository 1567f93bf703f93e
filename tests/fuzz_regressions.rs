//! Every input the fuzz targets (`fuzz/`) found failing, replayed through the same checks
//! (`tests/fuzz_checks`, which the targets call too). The README's "Fuzzing" section lists the
//! runs and what each found.
mod fuzz_checks;

use fuzz_checks::TriTriInput;

/// `tri_tri`, run 1 (crash-e0aeaa4d…): a NaN corner. `triangles_intersect` said "intersecting"
/// and `closest_points_triangle_triangle` then hit its debug assertion that an intersection
/// point exists (a panic in debug builds). NaN or infinite corners now mean "disjoint",
/// distance `+∞`.
#[test]
fn tri_tri_nan_corner() {
    fuzz_checks::tri_tri(&TriTriInput::Single([
        [0.825_490_2, 907_636_050_000.0, 4.093_541_5e-34],
        [4.093_545e-34, 6.549_672e-33, 1.758_164_3e-24],
        [6.468e-42, 0.0, f32::NAN],
        [1.010_189e-39, 0.0, 0.0],
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0],
    ]));
}

/// `tri_tri`, run 2 (crash-2fa4a7aa…): triangles sharing a corner, scaled by `2^900` (now
/// `2^800`). The orientations overflow `f64` (NaN), and the test answered "disjoint". (Found
/// by a run that had been built, by mistake, from the code before the fix of run 1; that code
/// fails it.) Overflowing orientations now rescale the corners exactly and decide again.
#[test]
fn tri_tri_shared_corner_scaled_up() {
    fuzz_checks::tri_tri(&TriTriInput::Grid([
        [-1, -1, -1],
        [-1, 5, -9],
        [-1, -17, -17],
        [-5, 36, -17],
        [-1, -1, -1],
        [0, 0, 0],
    ]));
}

/// `tri_tri`, run 3 (crash-8258d5d1…): a bug of the check, not of the crate. Corners near
/// `f32::MAX` scaled by `2^900` became infinite, so "scaled, the answer is the same" did not
/// hold; the check now scales by `2^800`, which keeps every `f32` finite.
#[test]
fn tri_tri_corners_near_f32_max() {
    fuzz_checks::tri_tri(&TriTriInput::Single([
        [0.0, -4.487_532_6e28, -1.714_659_5e38],
        [-1.927_382_2e38, 8.8247e-41, 0.0],
        [0.0; 3],
        [0.0; 3],
        [0.0; 3],
        [0.0; 3],
    ]));
}

/// `tri_tri`, run 4 (crash-6abfa578…): coplanar triangles (all in the plane x = −1), apart,
/// scaled by `2^800`: the 3D orientations are exactly 0, but the coplanar test's 2D
/// orientations overflowed (NaN, read as "collinear") and the answer was "intersecting".
/// Corners beyond `2^300` are now rescaled before any predicate.
#[test]
fn tri_tri_coplanar_scaled_up() {
    fuzz_checks::tri_tri(&TriTriInput::Grid([
        [-1, -17, -1],
        [-1, -1, -17],
        [-1, -1, -1],
        [-1, 5, -1],
        [-1, -8, 93],
        [-1, -11, 0],
    ]));
}
