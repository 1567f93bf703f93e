//! Hard cases for the exact triangle–triangle test and the closest-point queries.
//!
//! * A table of configurations with known answers (coplanar, touching, slivers, degenerate
//!   triangles, misses by a hair or by one ulp), each replayed under transforms that keep every
//!   coordinate exact: corner permutations, swapping the triangles, axis permutations and sign
//!   flips, scaling by powers of two from 2^-14 to 2^20 and translation by large offsets. The
//!   answer must never change.
//! * Random small-integer triangles (many degenerate, coplanar and touching) against an
//!   independent exact oracle: feasibility of the linear program "a convex combination of `a`'s
//!   corners equals one of `b`'s", decided by enumerating basic solutions in exact rational
//!   arithmetic.
//! * Random float triangles against a distance reference (ternary search along every edge),
//!   and the point/segment closest-point functions against independent brute-force references
//!   and dense sampling.

use glam::{DVec3, Vec3};
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::geometry::{
    ClosestPoints, closest_point_on_triangle, closest_points_segment_segment,
    closest_points_triangle_triangle, triangles_intersect, triangles_intersect_f32,
};

type Tri = [DVec3; 3];

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

fn next_up(x: f64) -> f64 {
    x.next_up()
}

fn next_down(x: f64) -> f64 {
    x.next_down()
}

// ---------------------------------------------------------------------------------------------
// Exact transforms.

/// `p ↦ scale · signs ⊙ (p permuted) + offset`, applied only when every coordinate stays exact.
#[derive(Debug, Clone, Copy)]
struct Xf {
    axes: [usize; 3],
    signs: [f64; 3],
    scale: f64,
    offset: DVec3,
}

impl Xf {
    const IDENTITY: Xf = Xf {
        axes: [0, 1, 2],
        signs: [1.0; 3],
        scale: 1.0,
        offset: DVec3::ZERO,
    };

    /// The image of `p`, or `None` when rounding would change it.
    fn apply(&self, p: DVec3) -> Option<DVec3> {
        let mut out = [0.0; 3];
        for (i, o) in out.iter_mut().enumerate() {
            let x = p[self.axes[i]] * self.signs[i] * self.scale;
            // Scaling by a power of two is exact unless it leaves the normal range.
            if x != 0.0 && !x.is_normal() {
                return None;
            }
            let (sum, err) = two_sum(x, self.offset[i]);
            if err != 0.0 {
                return None;
            }
            *o = sum;
        }
        Some(DVec3::from_array(out))
    }

    fn tri(&self, t: &Tri) -> Option<Tri> {
        Some([self.apply(t[0])?, self.apply(t[1])?, self.apply(t[2])?])
    }
}

/// Knuth's error-free sum: `a + b == sum + err` exactly.
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let sum = a + b;
    let bb = sum - a;
    let err = (a - (sum - bb)) + (b - bb);
    (sum, err)
}

const PERMS: [[usize; 3]; 6] = [
    [0, 1, 2],
    [1, 2, 0],
    [2, 0, 1],
    [0, 2, 1],
    [2, 1, 0],
    [1, 0, 2],
];

const SCALE_EXPONENTS: [i32; 7] = [-14, -9, -3, 0, 5, 13, 20];

fn offsets() -> [DVec3; 5] {
    let m = 1048576.0; // 2^20
    [
        DVec3::ZERO,
        v(1e6, 1e6, 1e6),
        v(m, -m, 3.0 * m),
        v(-1e6, m, 0.0),
        v(0.0, 0.0, -1e6),
    ]
}

/// All 48 axis permutations with sign flips.
fn axis_transforms() -> Vec<Xf> {
    let mut out = Vec::new();
    for axes in PERMS {
        for bits in 0..8 {
            let signs = [0, 1, 2].map(|i| if bits & (1 << i) != 0 { -1.0 } else { 1.0 });
            out.push(Xf {
                axes,
                signs,
                ..Xf::IDENTITY
            });
        }
    }
    out
}

fn permute(t: &Tri, p: [usize; 3]) -> Tri {
    p.map(|i| t[i])
}

// ---------------------------------------------------------------------------------------------
// Checks shared by the table and the random tests.

fn max_coord(ts: &[&Tri]) -> f64 {
    ts.iter()
        .flat_map(|t| t.iter())
        .fold(0.0, |m, p| m.max(p.abs().max_element()))
}

/// Distance from `x` to the triangle `t` (via the brute-force reference).
fn dist_to_tri(x: DVec3, t: &Tri) -> f64 {
    x.distance(ref_closest_on_triangle(x, t))
}

/// The closest-points answer agrees with the exact intersection answer `hit`: distance 0 and
/// a witness on both triangles when they meet, a positive distance (when `gap_is_resolvable`)
/// and points on their triangles otherwise.
fn check_closest_consistent(a: &Tri, b: &Tri, hit: bool, gap_is_resolvable: bool, ctx: &str) {
    let r = closest_points_triangle_triangle(a, b);
    let tol = 1e-12 * max_coord(&[a, b]).max(1e-300) * 64.0;
    assert!(
        r.distance.is_finite() && r.point_a.is_finite() && r.point_b.is_finite(),
        "{ctx}"
    );
    assert!(
        dist_to_tri(r.point_a, a) <= tol,
        "{ctx}: point_a off a: {r:?}"
    );
    assert!(
        dist_to_tri(r.point_b, b) <= tol,
        "{ctx}: point_b off b: {r:?}"
    );
    if hit {
        assert_eq!(r.distance, 0.0, "{ctx}: {r:?}");
        assert_eq!(r.point_a, r.point_b, "{ctx}");
    } else {
        assert!(r.distance >= 0.0, "{ctx}");
        if gap_is_resolvable {
            assert!(r.distance > 0.0, "{ctx}: {r:?}");
        }
        assert!(
            (r.distance - r.point_a.distance(r.point_b)).abs() <= tol,
            "{ctx}: {r:?}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// The table of hard cases.

struct Case {
    name: &'static str,
    a: Tri,
    b: Tri,
    hit: bool,
    /// For misses: a lower bound on the true distance (0 when unknown or ulp-small).
    gap: f64,
}

fn case(name: &'static str, a: Tri, b: Tri, hit: bool) -> Case {
    Case {
        name,
        a,
        b,
        hit,
        gap: 0.0,
    }
}

fn miss(name: &'static str, a: Tri, b: Tri, gap: f64) -> Case {
    Case {
        name,
        a,
        b,
        hit: false,
        gap,
    }
}

fn point(p: DVec3) -> Tri {
    [p; 3]
}

fn hard_cases() -> Vec<Case> {
    let h = 2f64.powi(-16); // "a hair": small, yet exact under every transform
    let a = [v(0., 0., 0.), v(4., 0., 0.), v(0., 4., 0.)];
    let mut cases = vec![
        // Separated and crossing, for reference.
        miss(
            "above",
            a,
            [v(0., 0., 1.), v(1., 0., 1.), v(0., 1., 2.)],
            1.0,
        ),
        case(
            "piercing",
            a,
            [v(1., 1., -1.), v(1., 1., 1.), v(9., 9., 0.)],
            true,
        ),
        // Coplanar.
        case(
            "coplanar overlapping",
            a,
            [v(1., 1., 0.), v(5., 1., 0.), v(1., 5., 0.)],
            true,
        ),
        case(
            "coplanar nested",
            a,
            [v(1., 1., 0.), v(2., 1., 0.), v(1., 2., 0.)],
            true,
        ),
        case("coplanar identical", a, a, true),
        case(
            "coplanar edge overlap",
            a,
            [v(1., 0., 0.), v(3., 0., 0.), v(2., -2., 0.)],
            true,
        ),
        case(
            "coplanar shared edge",
            a,
            [v(0., 0., 0.), v(4., 0., 0.), v(2., -2., 0.)],
            true,
        ),
        case(
            "coplanar vertex-vertex",
            a,
            [v(4., 0., 0.), v(6., 0., 0.), v(6., 2., 0.)],
            true,
        ),
        case(
            "coplanar vertex on edge",
            a,
            [v(2., 2., 0.), v(5., 5., 0.), v(5., 3., 0.)],
            true,
        ),
        case(
            "coplanar crossing edges",
            a,
            [v(1., -1., 0.), v(3., -1., 0.), v(2., 7., 0.)],
            true,
        ),
        miss(
            "coplanar disjoint by a hair",
            a,
            [v(2. + h, 2., 0.), v(6., 2., 0.), v(6., 6., 0.)],
            h * 0.7,
        ),
        miss(
            "coplanar parallel edges a hair apart",
            a,
            [v(0., -h, 0.), v(4., -h, 0.), v(2., -3., 0.)],
            h,
        ),
        miss(
            "coplanar far apart",
            a,
            [v(5., 5., 0.), v(6., 5., 0.), v(5., 6., 0.)],
            1.0,
        ),
        // Touching, not coplanar.
        case(
            "shared vertex",
            a,
            [v(0., 0., 0.), v(-1., -1., 3.), v(-2., 1., 2.)],
            true,
        ),
        miss(
            "vertex a hair away",
            a,
            [v(-h, 0., 0.), v(-1., -1., 3.), v(-2., 1., 2.)],
            h,
        ),
        case(
            "shared edge",
            a,
            [v(0., 0., 0.), v(4., 0., 0.), v(2., -1., 3.)],
            true,
        ),
        miss(
            "edge lifted by a hair",
            a,
            [v(0., 0., h), v(4., 0., h), v(2., -1., 3.)],
            h,
        ),
        case(
            "vertex on face interior",
            a,
            [v(1., 1., 0.), v(1., 1., 2.), v(3., 0., 2.)],
            true,
        ),
        miss(
            "vertex a hair above face",
            a,
            [v(1., 1., h), v(1., 1., 2.), v(3., 0., 2.)],
            h,
        ),
        case(
            "vertex on edge",
            a,
            [v(2., 0., 0.), v(2., -1., 2.), v(3., -1., 2.)],
            true,
        ),
        case(
            "edge crossing edge",
            a,
            [v(2., -1., -1.), v(2., 1., 1.), v(2., -3., 3.)],
            true,
        ),
        miss(
            "edge passing edge by a hair",
            a,
            [v(2., -1. - h, -1.), v(2., 1. - h, 1.), v(2., -3. - h, 3.)],
            h * 0.5,
        ),
        case(
            "edge on face",
            a,
            [v(1., 1., 0.), v(2., 1., 0.), v(1., 1., 3.)],
            true,
        ),
        miss(
            "edge a hair above face",
            a,
            [v(1., 1., h), v(2., 1., h), v(1., 1., 3.)],
            h,
        ),
        miss(
            "edge in plane, outside",
            a,
            [v(3., 3., 0.), v(5., 3., 0.), v(3., 3., 3.)],
            1.0,
        ),
        case(
            "edge in plane, across",
            a,
            [v(-1., 1., 0.), v(5., 1., 0.), v(2., 1., 3.)],
            true,
        ),
        // Planes cross inside both spans, but the intervals on the common line...
        miss(
            "intervals disjoint",
            a,
            [v(5., 1., -1.), v(7., 1., -1.), v(6., 1., 1.)],
            1.0,
        ),
        case(
            "intervals touching",
            a,
            [v(3., 1., -1.), v(5., 1., -1.), v(3., 1., 1.)],
            true,
        ),
        miss(
            "intervals a hair apart",
            a,
            [v(3. + h, 1., -1.), v(5., 1., -1.), v(3. + h, 1., 1.)],
            h * 0.5,
        ),
        case(
            "intervals nested",
            a,
            [v(1., 1., -1.), v(2., 1., 1.), v(1.5, 1.5, 1.)],
            true,
        ),
    ];

    // Nearly parallel slivers.
    let s1 = [v(0., 0., 0.), v(16., 0., 0.), v(0., 2f64.powi(-10), 0.)];
    let (e12, e14, e15, e20, e30) = (
        2f64.powi(-12),
        2f64.powi(-14),
        2f64.powi(-15),
        2f64.powi(-20),
        2f64.powi(-30),
    );
    let tilted = |y0: f64| [v(1., y0, -e30), v(15., y0, e30), v(15., y0 + e14, e30)];
    cases.extend([
        case("slivers crossing", s1, tilted(e12), true),
        case(
            "slivers touching at the hypotenuse",
            s1,
            tilted(2. * e12),
            true,
        ),
        miss(
            "slivers missing by 2^-40",
            s1,
            tilted(2. * e12 + 2f64.powi(-40)),
            0.0,
        ),
        case(
            "sliver vertex on sliver edge",
            s1,
            [v(8., 0., 0.), v(8. + e14, e12, e20), v(8. - e14, e12, e20)],
            true,
        ),
        miss(
            "sliver vertex 2^-40 off sliver edge",
            s1,
            [
                v(8., -(2f64.powi(-40)), 0.),
                v(8. + e14, e12, e20),
                v(8. - e14, e12, e20),
            ],
            0.0,
        ),
        case(
            "sliver vertex 2^-40 inside sliver",
            s1,
            [
                v(8., 2f64.powi(-40), 0.),
                v(8. + e14, e12, e20),
                v(8. - e14, e12, e20),
            ],
            true,
        ),
        case("sliver against its copy", s1, s1, true),
        miss(
            "sliver against its copy lifted",
            s1,
            s1.map(|p| p + v(0., 0., e15)),
            e15,
        ),
    ]);

    // Degenerate triangles: segments and points, touching and missing by one ulp.
    let seg_v = |x: f64, y: f64| [v(x, y, -1.), v(x, y, 1.), v(x, y, 0.5)];
    cases.extend([
        case("point on face", a, point(v(1., 1., 0.)), true),
        case("point on hypotenuse", a, point(v(2., 2., 0.)), true),
        miss(
            "point one ulp outside hypotenuse",
            a,
            point(v(2., next_up(2.), 0.)),
            0.0,
        ),
        case(
            "point one ulp inside hypotenuse",
            a,
            point(v(2., next_down(2.), 0.)),
            true,
        ),
        case("point on vertex", a, point(v(4., 0., 0.)), true),
        miss(
            "point one ulp past vertex",
            a,
            point(v(next_up(4.), 0., 0.)),
            0.0,
        ),
        miss("point above face", a, point(v(1., 1., h)), h),
        case("segment through face", a, seg_v(1., 1.), true),
        case("segment through hypotenuse", a, seg_v(2., 2.), true),
        miss(
            "segment one ulp past hypotenuse",
            a,
            seg_v(2., next_up(2.)),
            0.0,
        ),
        case(
            "segment ending on face",
            a,
            [v(1., 1., 0.), v(1., 1., 2.), v(1., 1., 1.)],
            true,
        ),
        miss(
            "segment ending a hair above face",
            a,
            [v(1., 1., h), v(1., 1., 2.), v(1., 1., 1.)],
            h,
        ),
        case(
            "segment with a repeated corner",
            a,
            [v(1., 1., -1.), v(1., 1., -1.), v(1., 1., 1.)],
            true,
        ),
        case(
            "segment in plane, across",
            a,
            [v(-1., 1., 0.), v(5., 1., 0.), v(2., 1., 0.)],
            true,
        ),
        case(
            "segment collinear with edge, touching vertex",
            a,
            [v(4., 0., 0.), v(6., 0., 0.), v(5., 0., 0.)],
            true,
        ),
        miss(
            "segment collinear with edge, one ulp past vertex",
            a,
            [v(next_up(4.), 0., 0.), v(6., 0., 0.), v(5., 0., 0.)],
            0.0,
        ),
        case(
            "segment overlapping an edge",
            a,
            [v(-1., 0., 0.), v(1., 0., 0.), v(0., 0., 0.)],
            true,
        ),
    ]);
    let seg1 = [v(0., 0., 0.), v(4., 4., 4.), v(2., 2., 2.)];
    let d = 2f64.powi(-50); // one ulp of 4
    cases.extend([
        case(
            "segments crossing",
            seg1,
            [v(0., 4., 0.), v(4., 0., 4.), v(1., 3., 1.)],
            true,
        ),
        miss(
            "segments skew by one ulp",
            seg1,
            [v(d, 4., -d), v(4. + d, 0., 4. - d), v(1. + d, 3., 1. - d)],
            0.0,
        ),
        case(
            "segments collinear overlapping",
            seg1,
            [v(3., 3., 3.), v(6., 6., 6.), v(5., 5., 5.)],
            true,
        ),
        case(
            "segments collinear touching",
            seg1,
            [v(4., 4., 4.), v(6., 6., 6.), v(5., 5., 5.)],
            true,
        ),
        miss(
            "segments collinear one ulp apart",
            seg1,
            [
                v(next_up(4.), next_up(4.), next_up(4.)),
                v(6., 6., 6.),
                v(5., 5., 5.),
            ],
            0.0,
        ),
        case(
            "segments T-junction",
            seg1,
            [v(2., 2., 2.), v(2., 5., 2.), v(2., 3., 2.)],
            true,
        ),
        miss(
            "segments T-junction missed by one ulp",
            seg1,
            [v(2., next_up(2.), 2.), v(2., 5., 2.), v(2., 3., 2.)],
            0.0,
        ),
        case("segment and point on it", seg1, point(v(1., 1., 1.)), true),
        miss(
            "segment and point one ulp off",
            seg1,
            point(v(1., 1., next_up(1.))),
            0.0,
        ),
        case(
            "equal points",
            point(v(1., 2., 3.)),
            point(v(1., 2., 3.)),
            true,
        ),
        miss(
            "points one ulp apart",
            point(v(1., 2., 3.)),
            point(v(1., 2., next_up(3.))),
            0.0,
        ),
    ]);

    // Far from the origin, missing by one ulp there.
    let m = 1048576.0; // 2^20
    let af = a.map(|p| p + v(m, m, m));
    cases.extend([
        case(
            "far: point on hypotenuse",
            af,
            point(v(m + 2., m + 2., m)),
            true,
        ),
        miss(
            "far: point one ulp outside",
            af,
            point(v(m + 2., next_up(m + 2.), m)),
            0.0,
        ),
        case(
            "far: segment through hypotenuse",
            af,
            [
                v(m + 2., m + 2., m - 1.),
                v(m + 2., m + 2., m + 1.),
                v(m + 2., m + 2., m),
            ],
            true,
        ),
        miss(
            "far: triangle one ulp above",
            af,
            [
                v(m + 1., m + 1., next_up(m)),
                v(m + 1., m + 1., m + 2.),
                v(m + 3., m, m + 2.),
            ],
            0.0,
        ),
        case(
            "far: vertex on face",
            af,
            [
                v(m + 1., m + 1., m),
                v(m + 1., m + 1., m + 2.),
                v(m + 3., m, m + 2.),
            ],
            true,
        ),
    ]);
    cases
}

/// Checks `triangles_intersect` (and the f32 wrapper when exact) on one transformed pair.
fn check_pair(a: &Tri, b: &Tri, hit: bool, ctx: &dyn Fn() -> String) {
    assert_eq!(triangles_intersect(a, b), hit, "{}: {a:?} {b:?}", ctx());
    let fa = a.map(|p| p.as_vec3());
    let fb = b.map(|p| p.as_vec3());
    let exact = |f: &[Vec3; 3], d: &Tri| f.iter().zip(d).all(|(x, y)| x.as_dvec3() == *y);
    if exact(&fa, a) && exact(&fb, b) {
        assert_eq!(triangles_intersect_f32(fa, fb), hit, "{} (f32)", ctx());
    }
}

#[test]
fn hard_cases_under_exact_transforms() {
    let cases = hard_cases();
    let axis_xfs = axis_transforms();
    let offsets = offsets();
    let mut total_translated = 0usize;
    for c in &cases {
        assert_eq!(triangles_intersect(&c.a, &c.b), c.hit, "{}", c.name);
        let mut applied = 0usize;
        let mut translated = 0usize;
        // Every corner permutation of both triangles, both orders, about half of the axis
        // transforms, each with a rotating choice of scale and offset.
        let mut k = 0usize;
        for pa in PERMS {
            for pb in PERMS {
                for swap in [false, true] {
                    for (ix, axis) in axis_xfs.iter().enumerate() {
                        let combo = (k * 7 + ix) % (SCALE_EXPONENTS.len() * offsets.len());
                        k += 1;
                        if !ix.is_multiple_of(4) && !combo.is_multiple_of(3) {
                            continue; // thin out to about half of the 48 axis transforms
                        }
                        let xf = Xf {
                            scale: 2f64.powi(SCALE_EXPONENTS[combo % SCALE_EXPONENTS.len()]),
                            offset: offsets[combo / SCALE_EXPONENTS.len()],
                            ..*axis
                        };
                        let (Some(a), Some(b)) =
                            (xf.tri(&permute(&c.a, pa)), xf.tri(&permute(&c.b, pb)))
                        else {
                            continue;
                        };
                        let (a, b) = if swap { (b, a) } else { (a, b) };
                        check_pair(&a, &b, c.hit, &|| {
                            format!("{} under {xf:?} {pa:?} {pb:?} swap={swap}", c.name)
                        });
                        applied += 1;
                        translated += usize::from(xf.offset != DVec3::ZERO);
                    }
                }
            }
        }
        // Every scale alone, and every offset alone, on the original corner order.
        for e in SCALE_EXPONENTS {
            for off in offsets {
                let xf = Xf {
                    scale: 2f64.powi(e),
                    offset: off,
                    ..Xf::IDENTITY
                };
                if let (Some(a), Some(b)) = (xf.tri(&c.a), xf.tri(&c.b)) {
                    check_pair(&a, &b, c.hit, &|| format!("{} under {xf:?}", c.name));
                    let resolvable = c.gap * xf.scale > 1e-9 * max_coord(&[&a, &b]);
                    check_closest_consistent(
                        &a,
                        &b,
                        c.hit,
                        resolvable,
                        &format!("{} under {xf:?}", c.name),
                    );
                    if !c.hit && c.gap > 0.0 {
                        let r = closest_points_triangle_triangle(&a, &b);
                        let tol = 1e-9 * max_coord(&[&a, &b]);
                        assert!(r.distance >= c.gap * xf.scale - tol, "{}: {r:?}", c.name);
                    }
                    applied += 1;
                }
            }
        }
        assert!(
            applied >= 300,
            "{}: only {applied} transforms were exact",
            c.name
        );
        // Hair-sized gaps are chosen to survive every translation (one-ulp ones cannot).
        if c.name.contains("hair") {
            assert!(
                translated >= 100,
                "{}: translated only {translated} times",
                c.name
            );
        }
        total_translated += translated;
    }
    assert!(total_translated > 10_000, "{total_translated}");
}

// ---------------------------------------------------------------------------------------------
// Exact oracle: linear-programming feasibility in rational arithmetic.

#[derive(Debug, Clone, Copy, PartialEq)]
struct Q {
    n: i128,
    d: i128,
}

fn gcd(mut a: i128, mut b: i128) -> i128 {
    a = a.abs();
    b = b.abs();
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a.max(1)
}

impl Q {
    fn int(n: i64) -> Q {
        Q { n: n.into(), d: 1 }
    }
    fn norm(n: i128, d: i128) -> Q {
        let g = gcd(n, d);
        let s = if d < 0 { -1 } else { 1 };
        Q {
            n: s * n / g,
            d: s * d / g,
        }
    }
    fn sub(self, o: Q) -> Q {
        Q::norm(self.n * o.d - o.n * self.d, self.d * o.d)
    }
    fn mul(self, o: Q) -> Q {
        Q::norm(self.n * o.n, self.d * o.d)
    }
    fn div(self, o: Q) -> Q {
        Q::norm(self.n * o.d, self.d * o.n)
    }
    fn is_zero(self) -> bool {
        self.n == 0
    }
}

/// Do the closed triangles with integer corners share a point? Exactly: is there
/// `x = (λ, μ) >= 0` with `Σλ = Σμ = 1` and `Σ λ_i a_i = Σ μ_j b_j`? An LP is feasible iff it
/// has a basic feasible solution, so try every set of linearly independent columns.
fn oracle_intersect(a: &[[i64; 3]; 3], b: &[[i64; 3]; 3]) -> bool {
    // 5 × 6 constraint matrix and right-hand side.
    let mut m = [[0i64; 6]; 5];
    for k in 0..3 {
        for i in 0..3 {
            m[k][i] = a[i][k];
            m[k][3 + i] = -b[i][k];
        }
    }
    for i in 0..3 {
        m[3][i] = 1;
        m[4][3 + i] = 1;
    }
    let rhs = [0, 0, 0, 1, 1];
    (1u32..64).any(|mask| {
        let cols: Vec<usize> = (0..6).filter(|c| mask & (1 << c) != 0).collect();
        let k = cols.len();
        if k > 5 {
            return false;
        }
        // Augmented matrix rows × (k + 1).
        let mut aug: Vec<Vec<Q>> = (0..5)
            .map(|r| {
                let mut row: Vec<Q> = cols.iter().map(|&c| Q::int(m[r][c])).collect();
                row.push(Q::int(rhs[r]));
                row
            })
            .collect();
        for col in 0..k {
            let Some(piv) = (col..5).find(|&r| !aug[r][col].is_zero()) else {
                return false; // dependent columns: not a basis
            };
            aug.swap(col, piv);
            let p = aug[col][col];
            for x in &mut aug[col][col..=k] {
                *x = x.div(p);
            }
            let pivot_row = aug[col].clone();
            for (r, row) in aug.iter_mut().enumerate() {
                if r != col && !row[col].is_zero() {
                    let f = row[col];
                    for (x, &pc) in row[col..=k].iter_mut().zip(&pivot_row[col..=k]) {
                        *x = x.sub(f.mul(pc));
                    }
                }
            }
        }
        let consistent = (k..5).all(|r| aug[r][k].is_zero());
        consistent && (0..k).all(|r| aug[r][k].n >= 0)
    })
}

fn rand_int_tri(rng: &mut Xoshiro256PlusPlus) -> [[i64; 3]; 3] {
    let mut p = || [0; 3].map(|_| rng.random_range(-2i64..=2));
    let (a, b) = (p(), p());
    let general = p();
    let kind = rng.random_range(0..10);
    let mut t = match kind {
        // A point.
        0 => [a; 3],
        // A segment: the third corner on the line through the first two.
        1 | 2 => {
            let k = rng.random_range(-1i64..=2);
            [a, b, [0, 1, 2].map(|i| a[i] + k * (b[i] - a[i]))]
        }
        // In the plane z = 0, to make coplanar pairs common.
        3 | 4 => [a, b, general].map(|q| [q[0], q[1], 0]),
        _ => [a, b, general],
    };
    let perm = PERMS[rng.random_range(0..6)];
    t = perm.map(|i| t[i]);
    t
}

fn to_tri(t: &[[i64; 3]; 3]) -> Tri {
    t.map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
}

fn rand_xf(rng: &mut Xoshiro256PlusPlus, offsets: &[DVec3]) -> Xf {
    let axes = PERMS[rng.random_range(0..6)];
    let signs = [0; 3].map(|_| if rng.random_bool(0.5) { -1.0 } else { 1.0 });
    Xf {
        axes,
        signs,
        scale: 2f64.powi(rng.random_range(-14..=20)),
        offset: offsets[rng.random_range(0..offsets.len())],
    }
}

#[test]
fn random_integer_triangles_match_exact_oracle() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x5eed_7417);
    let offsets = offsets();
    let (mut hits, mut coplanar_or_degenerate) = (0, 0);
    let n = 2500;
    for i in 0..n {
        let (ia, ib) = (rand_int_tri(&mut rng), rand_int_tri(&mut rng));
        let want = oracle_intersect(&ia, &ib);
        let (a, b) = (to_tri(&ia), to_tri(&ib));
        assert_eq!(triangles_intersect(&a, &b), want, "case {i}: {a:?} {b:?}");
        let xf = rand_xf(&mut rng, &offsets);
        let (xa, xb) = (xf.tri(&a).expect("exact"), xf.tri(&b).expect("exact"));
        check_pair(&xa, &xb, want, &|| format!("case {i} under {xf:?}"));
        check_pair(&xb, &xa, want, &|| format!("case {i} swapped under {xf:?}"));
        // Integer triangles that miss are at least ~1/100 apart: always resolvable.
        check_closest_consistent(&xa, &xb, want, true, &format!("case {i} under {xf:?}"));
        hits += usize::from(want);
        let flat = |t: &[[i64; 3]; 3]| t.iter().all(|p| p[2] == 0);
        coplanar_or_degenerate += usize::from(flat(&ia) && flat(&ib));
    }
    // The generator must exercise both answers and the coplanar path.
    assert!(hits > n / 5 && hits < n * 4 / 5, "{hits}");
    assert!(coplanar_or_degenerate > n / 50, "{coplanar_or_degenerate}");
}

// ---------------------------------------------------------------------------------------------
// Independent brute-force references for the closest-point functions.

/// Closest point on segment `ab` (zero length allowed).
fn ref_closest_on_segment(p: DVec3, a: DVec3, b: DVec3) -> DVec3 {
    let ab = b - a;
    let l2 = ab.length_squared();
    if l2 == 0.0 {
        return a;
    }
    a + ab * ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
}

/// Projection onto the plane if it falls inside (barycentric test), else the best edge point.
fn ref_closest_on_triangle(p: DVec3, t: &Tri) -> DVec3 {
    let mut best = t[0];
    for i in 0..3 {
        let q = ref_closest_on_segment(p, t[i], t[(i + 1) % 3]);
        if q.distance_squared(p) < best.distance_squared(p) {
            best = q;
        }
    }
    let (e0, e1) = (t[1] - t[0], t[2] - t[0]);
    let n = e0.cross(e1);
    let nn = n.length_squared();
    let longest = e0
        .length_squared()
        .max(e1.length_squared())
        .max((t[2] - t[1]).length_squared());
    if nn > 1e-20 * longest * longest {
        let x = p - n * (n.dot(p - t[0]) / nn);
        let inside = (0..3).all(|i| n.dot((t[(i + 1) % 3] - t[i]).cross(x - t[i])) >= 0.0);
        if inside && x.distance_squared(p) < best.distance_squared(p) {
            best = x;
        }
    }
    best
}

/// Minimum over the endpoint–segment pairs and the interior critical point of the two lines.
fn ref_segment_segment(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> f64 {
    let mut d = ref_closest_on_segment(p0, q0, q1).distance(p0);
    d = d.min(ref_closest_on_segment(p1, q0, q1).distance(p1));
    d = d.min(ref_closest_on_segment(q0, p0, p1).distance(q0));
    d = d.min(ref_closest_on_segment(q1, p0, p1).distance(q1));
    let (u, w, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, b, c, e, f) = (u.dot(u), u.dot(w), u.dot(r), w.dot(w), w.dot(r));
    let det = a * e - b * b;
    if det > 1e-12 * a * e {
        let s = (b * f - c * e) / det;
        let t = (a * f - b * c) / det;
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
            d = d.min((p0 + u * s).distance(q0 + w * t));
        }
    }
    d
}

fn rand_point(rng: &mut Xoshiro256PlusPlus, r: f64) -> DVec3 {
    DVec3::new(
        rng.random_range(-r..r),
        rng.random_range(-r..r),
        rng.random_range(-r..r),
    )
}

/// Random triangle, sometimes degenerate (repeated corners, a point, exactly collinear corners).
fn rand_tri(rng: &mut Xoshiro256PlusPlus) -> Tri {
    let (a, b, c) = (
        rand_point(rng, 1.0),
        rand_point(rng, 1.0),
        rand_point(rng, 1.0),
    );
    match rng.random_range(0..8) {
        0 => [a; 3],
        1 => [a, a, b],
        2 => [a, b, a + (b - a) * 0.5], // midpoint-ish: collinear up to rounding
        3 => [a, b, a.with_x(b.x)],     // a right angle, well shaped
        _ => [a, b, c],
    }
}

fn on_segment(x: DVec3, a: DVec3, b: DVec3, tol: f64) -> bool {
    ref_closest_on_segment(x, a, b).distance(x) <= tol
}

#[test]
fn closest_point_on_triangle_matches_reference_and_sampling() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
    for i in 0..400 {
        let t = rand_tri(&mut rng);
        let offset = if i % 4 == 0 {
            v(1e6, -1e6, 1e6)
        } else {
            DVec3::ZERO
        };
        let t = t.map(|c| c + offset);
        let p = rand_point(&mut rng, 2.0) + offset;
        let x = closest_point_on_triangle(p, &t);
        let tol = 1e-12 * (1.0 + offset.length());
        assert!(x.is_finite(), "{t:?} {p}");
        assert!(
            dist_to_tri(x, &t) <= tol,
            "point off the triangle: {t:?} {p} -> {x}"
        );
        let want = p.distance(ref_closest_on_triangle(p, &t));
        assert!(
            (p.distance(x) - want).abs() <= 1e-9 * (1.0 + offset.length() * 1e-6),
            "{t:?} {p}: {x} vs {want}"
        );
        // Dense barycentric sampling never beats it.
        let n = 24;
        for u in 0..=n {
            for w in 0..=(n - u) {
                let (fu, fw) = (u as f64 / n as f64, w as f64 / n as f64);
                let s = t[0] + (t[1] - t[0]) * fu + (t[2] - t[0]) * fw;
                assert!(
                    p.distance(x) <= p.distance(s) + tol,
                    "{t:?} {p}: sample {s} is closer than {x}"
                );
            }
        }
    }
}

#[test]
fn closest_points_segment_segment_matches_reference_and_sampling() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(12);
    for i in 0..400 {
        let (p0, mut p1) = (rand_point(&mut rng, 1.0), rand_point(&mut rng, 1.0));
        let (mut q0, mut q1) = (rand_point(&mut rng, 1.0), rand_point(&mut rng, 1.0));
        match i % 8 {
            0 => p1 = p0,                                                 // first is a point
            1 => q1 = q0,                                                 // second is a point
            2 => (p1, q1) = (p0, q0),                                     // both points
            3 => q1 = q0 + (p1 - p0) * 0.75,                              // parallel
            4 => (q0, q1) = (p0.lerp(p1, 0.25), p0.lerp(p1, 1.5)),        // collinear overlapping
            5 => (q0, q1) = (p0 + (p1 - p0) * 2.0, p0 + (p1 - p0) * 3.0), // collinear apart
            _ => {}
        }
        let r: ClosestPoints = closest_points_segment_segment(p0, p1, q0, q1);
        assert!(r.distance.is_finite() && r.point_a.is_finite() && r.point_b.is_finite());
        assert!(on_segment(r.point_a, p0, p1, 1e-12), "case {i}");
        assert!(on_segment(r.point_b, q0, q1, 1e-12), "case {i}");
        assert!((r.distance - r.point_a.distance(r.point_b)).abs() <= 1e-12);
        let want = ref_segment_segment(p0, p1, q0, q1);
        assert!(
            (r.distance - want).abs() <= 1e-9,
            "case {i}: {r:?} vs {want}"
        );
        let n = 64;
        for j in 0..=n {
            let a = p0.lerp(p1, j as f64 / n as f64);
            for k in 0..=n {
                let b = q0.lerp(q1, k as f64 / n as f64);
                assert!(r.distance <= a.distance(b) + 1e-12, "case {i}");
            }
        }
    }
}

/// Distance between two triangles as the minimum, over the six edges, of the edge–triangle
/// distance found by ternary search (the distance from a moving point to a convex set is convex
/// along a line). Every closest pair, touching or not, involves an edge point.
fn ref_triangle_distance(a: &Tri, b: &Tri) -> f64 {
    let edge = |p: DVec3, q: DVec3, t: &Tri| {
        let f = |s: f64| {
            let x = p.lerp(q, s);
            x.distance(ref_closest_on_triangle(x, t))
        };
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..100 {
            let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
            if f(m1) < f(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        f(0.5 * (lo + hi)).min(f(0.0)).min(f(1.0))
    };
    (0..3)
        .map(|i| edge(a[i], a[(i + 1) % 3], b).min(edge(b[i], b[(i + 1) % 3], a)))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn random_float_triangles_match_distance_reference() {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(13);
    let (mut hits, mut misses) = (0, 0);
    for i in 0..300u32 {
        let a = rand_tri(&mut rng);
        let shift = v(rng.random_range(0.0..1.2), 0.0, 0.0);
        let b = rand_tri(&mut rng).map(|p| p + shift);
        let hit = triangles_intersect(&a, &b);
        let r = closest_points_triangle_triangle(&a, &b);
        let want = ref_triangle_distance(&a, &b);
        // Away from the touching band the two answers must agree.
        if want > 1e-9 {
            assert!(!hit, "case {i}: reference distance {want} but intersecting");
        }
        if hit {
            assert!(
                want < 1e-9,
                "case {i}: intersecting but reference distance {want}"
            );
            assert_eq!(r.distance, 0.0);
            hits += 1;
        } else {
            assert!(
                (r.distance - want).abs() <= 1e-9,
                "case {i}: {r:?} vs {want}"
            );
            misses += 1;
        }
        check_closest_consistent(&a, &b, hit, false, &format!("case {i}"));
        // Sampling both triangles never finds a closer pair.
        if i.is_multiple_of(10) {
            let samples = |t: &Tri| {
                let n = 12;
                let mut out = Vec::new();
                for u in 0..=n {
                    for w in 0..=(n - u) {
                        let (fu, fw) = (u as f64 / n as f64, w as f64 / n as f64);
                        out.push(t[0] + (t[1] - t[0]) * fu + (t[2] - t[0]) * fw);
                    }
                }
                out
            };
            let (sa, sb) = (samples(&a), samples(&b));
            let sampled = sa
                .iter()
                .flat_map(|x| sb.iter().map(move |y| x.distance(*y)))
                .fold(f64::INFINITY, f64::min);
            assert!(r.distance <= sampled + 1e-12, "case {i}");
        }
    }
    assert!(hits > 20 && misses > 20, "{hits} {misses}");
}

/// Near-contact triangle pairs from two icospheres (f32 corners, the second posed in f64) that
/// parry3d 0.31's triangle–triangle `intersection_test` (on the corners rounded to f32) reports
/// as intersecting, with distance 0. Dense sampling shows them apart by the distances given.
#[test]
fn near_contact_pairs_parry_misjudges() {
    let cases = [
        (
            [
                v(
                    -0.5062980055809021,
                    -0.8598478436470032,
                    -0.06575755029916763,
                ),
                v(
                    -0.4863796532154083,
                    -0.8731277585029602,
                    -0.03290596231818199,
                ),
                v(
                    -0.5163236260414124,
                    -0.8557615280151367,
                    -0.032898467034101486,
                ),
            ],
            [
                v(
                    -0.47665282143783666,
                    -0.8777996875377635,
                    -0.04261703065785907,
                ),
                v(
                    -0.5075321046297573,
                    -0.8671093349992994,
                    -0.027097955900530657,
                ),
                v(
                    -0.4839398417649572,
                    -0.877580448759031,
                    -0.0040323175378177145,
                ),
            ],
            1.5142515663322447e-3,
        ),
        (
            [
                v(
                    -0.7482882738113403,
                    -0.5450409650802612,
                    0.37814682722091675,
                ),
                v(-0.7610446214675903, -0.5116444230079651, 0.3987869918346405),
                v(-0.7738109827041626, -0.5195250511169434, 0.3623676300048828),
            ],
            [
                v(
                    -0.7374032644646286,
                    -0.4996205269712003,
                    0.42334357511233567,
                ),
                v(-0.7583669230789604, -0.5217453681793791, 0.3962311206929009),
                v(
                    -0.7654157239892612,
                    -0.48323473016712154,
                    0.40055691060478127,
                ),
            ],
            2.489886167795244e-4,
        ),
    ];
    for (a, b, gap) in cases {
        assert!(!triangles_intersect(&a, &b) && !triangles_intersect(&b, &a));
        let r = closest_points_triangle_triangle(&a, &b);
        assert!((r.distance - gap).abs() < 1e-12, "{r:?}");
        assert!((ref_triangle_distance(&a, &b) - gap).abs() < 1e-12);
    }
}
