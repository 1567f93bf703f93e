//! Every input the fuzz targets (`fuzz/`) found failing, replayed through the same checks
//! (`tests/fuzz_checks`, which the targets call too). `docs/robustness.md` ("Fuzzing") says what
//! each found.
mod fuzz_checks;

use fuzz_checks::{MeshInput, MeshQueryInput, ProbabilityInput, TriTriInput};

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

/// `mesh_query`, run 1 (crash-9139f371…): `closest_points` with no distance limit answered
/// `None` for finite poses whose translation is near `f32::MAX`.
#[test]
fn mesh_query_closest_points_near_f32_max() {
    let mesh = |positions: Vec<[f32; 3]>, triangles: Vec<[u8; 3]>| MeshInput {
        positions,
        triangles,
        grid: 0,
    };
    fuzz_checks::mesh_query(&MeshQueryInput {
        a: mesh(
            vec![
                [-1.6654e35, -6.490_371e35, 3.470_346_8e-25],
                [14_668_745_000_000.0, 1.116_144_2e-13, 3.774_425_2e-14],
                [-1.52422e26, 3.756_151e-14, 3.774_353_4e-14],
            ],
            vec![
                [41, 41, 58],
                [252, 234, 121],
                [41, 41, 85],
                [41, 41, 252],
                [41, 41, 41],
                [252, 234, 126],
                [41, 41, 250],
                [250, 41, 122],
                [41, 41, 41],
            ],
        ),
        b: mesh(vec![], vec![[41, 41, 249], [250, 127, 127], [0, 0, 0]]),
        same: true,
        pose_a: (
            [3.396_176_3e38, 5.51012e-40, 9.334_581e-15],
            [
                9.334_581e-15,
                -1.180_104e-38,
                -1.180_104e-38,
                -1.180_104e-38,
            ],
        ),
        pose_b: (
            [-1.180_104e-38, -1.180_104e-38, 9.351_352e-15],
            [
                9.334_581e-15,
                3.76567e-39,
                14_660_155_000_000.0,
                4.781_360_4e-14,
            ],
        ),
        fit: true,
        budget: 43,
    });
}

/// `probability`, run 2 (crash-6ab21f95…): a bug of the check, not of the model. Boxes with
/// infinite sides have an infinite overlap volume, which `overlap_volume` documents (never
/// NaN); the check demanded a finite one. It now does so only for finite sides.
#[test]
fn probability_infinite_box_sides() {
    fuzz_checks::probability(&ProbabilityInput {
        s: 2_137_877_869,
        s_a: 2_139_070_591,
        s_b: 2_139_062_143,
        x: 127,
        x_max: 127,
        lb: 4.128_269_8e-317,
        sides_a: [f32::INFINITY, 8.65661e-19, 1.170_882e-38],
        sides_b: [0.0, f32::INFINITY, 8.65661e-19],
        d: 2.475_987_8e27,
        wf: [1_835_887_981, 1_835_887_981],
        cells: 1_835_887_981,
        depths: [627_928_429, 1_835_887_981, 1_835_887_981, 4_128_064_126],
        small: false,
    });
}

/// `mesh_query`, run 2 (slow-unit-4871357b…, 10 s under load): 22 triangles that are all the
/// same point. The ADB calibration fit looks for near-contact poses; for meshes of zero extent
/// every attempt scanned 64 offsets that were all 0 (each an exact query over all pairs), 40
/// attempts per build. Now a single offset is tried.
#[test]
fn mesh_query_mesh_of_one_point() {
    let mut triangles = vec![[255, 251, 251]];
    triangles.extend([[251; 3]; 5]);
    triangles.extend([[255; 3]; 12]);
    triangles.extend([[251; 3]; 3]);
    triangles.push([250; 3]);
    fuzz_checks::mesh_query(&MeshQueryInput {
        a: MeshInput {
            positions: vec![
                [3.5e-43, 0.0, -5.580_381_4e35],
                [6e-45, 0.0, -4.552_103e36],
                [4.353_815_5e-16, 1.114_611_5e-13, 3.763_496_5e-14],
                [5.8531e-41, 3.756_196_7e-14, 1.5005e-41],
            ],
            triangles,
            grid: 250,
        },
        b: MeshInput {
            positions: vec![],
            triangles: vec![],
            grid: 250,
        },
        same: true,
        pose_a: (
            [2.890_147_2e-14, 5.7e-44, 5.5e-44],
            [
                3.763_128_2e-14,
                3.756_124e-14,
                -2.195_832_5e35,
                -6.541_784_6e35,
            ],
        ),
        pose_b: (
            [3.774_323_2e-14, 1.074_491_7e-38, 1.637_307_4e32],
            [
                -2.598_501_2e36,
                1.525_160_5e35,
                -3.697_314e28,
                -2.450_560_3e36,
            ],
        ),
        fit: true,
        budget: 251,
    });
}

/// `mesh_query`, run 3 (crash-56057365…): coordinates near `f32::MAX`. The `f32` box-distance
/// lower bound overflowed to +∞ and pruned the pair at distance 0, so `closest_points`
/// answered +∞. An overflowing bound is now 0, and an overflowing box test does not cull.
#[test]
fn mesh_query_boxes_near_f32_max() {
    let far = 3.396_151_4e38;
    let mut triangles = vec![[41, 41, 255]];
    triangles.extend([[255; 3]; 11]);
    triangles.extend([[255, 255, 0], [33, 41, 0], [41, 1, 122]]);
    let tiny = -1.974_495e-11;
    fuzz_checks::mesh_query(&MeshQueryInput {
        a: MeshInput {
            positions: vec![
                [-6.510_676e35, -33_554_436.0, 0.0],
                [-1.974_472_1e-11, tiny, tiny],
                [3.334_268e-14, 3.752_814e-14, 1.4708e-41],
                [2.312_865e38, far, far],
                [far; 3],
                [far; 3],
                [far; 3],
                [far, 2.858_388_6e-14, 3.773_205e-39],
                [1.474_142_85e-36, -1.009_317_2e37, 3.334_31e-14],
            ],
            triangles,
            grid: 0,
        },
        b: MeshInput {
            positions: vec![],
            triangles: vec![],
            grid: 0,
        },
        same: true,
        pose_a: (
            [541_515_150_000.0, 225_831_060_000.0, -7.331_54e-12],
            [tiny; 4],
        ),
        pose_b: (
            [tiny, tiny, -1.974_470_4e-11],
            [tiny, -7.428_208e-12, 7.105_502_4e-12, 3.752_553_8e-14],
        ),
        fit: true,
        budget: 173,
    });
}
