//! Point containment in closed meshes (ray parity with exact crossing tests), for the solid
//! option of the exact queries.
use glam::{DVec3, Vec3};
use smallvec::{SmallVec, smallvec};

use super::collision_mesh::CollisionMesh;
use super::workspace::triangle_f64;
use crate::geometry::predicates::orient3d;
use crate::geometry::{PoseF64, triangles_intersect};

/// Whether `point` (in `mesh`'s own frame) is inside or on the closed mesh `mesh`.
///
/// Counts exact crossings of a ray with the surface (parity); a ray that grazes an edge or a
/// vertex is discarded and another direction is tried, so the answer does not depend on
/// rounding. A point on the surface counts as inside. For an open mesh
/// ([`CollisionMesh::is_closed`] false) there is no inside and the answer is `false`.
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// use stochastic_collision::bvh::contains_point;
/// let cube = CollisionMesh::new(generate::cuboid(Vec3::ONE, 1));
/// assert!(contains_point(&cube, Vec3::new(0.2, -0.5, 0.9)));
/// assert!(contains_point(&cube, Vec3::new(1.0, 0.0, 0.0)));
/// assert!(!contains_point(&cube, Vec3::new(1.5, 0.0, 0.0)));
/// ```
pub fn contains_point(mesh: &CollisionMesh, point: Vec3) -> bool {
    mesh.is_closed() && contains_point_f64(mesh, point.as_dvec3())
}

/// Whether some connected component of `inner`, placed in `outer`'s frame by `inner_to_outer`,
/// lies inside the closed mesh `outer`. Called only when the surfaces do not touch, so one
/// vertex per component decides for the whole component.
pub(crate) fn contained_in(
    inner: &CollisionMesh,
    outer: &CollisionMesh,
    inner_to_outer: &PoseF64,
) -> bool {
    if !outer.is_closed() {
        return false;
    }
    let positions = inner.mesh().positions();
    let root = outer.bvh().root_aabb();
    inner.component_vertices().iter().any(|&v| {
        let p = inner_to_outer.transform_point(positions[v as usize]);
        let inside_box = p.cmpge(root.min.as_dvec3()).all() && p.cmple(root.max.as_dvec3()).all();
        inside_box && contains_point_f64(outer, p)
    })
}

/// Ray directions tried in turn; irrational-looking so that grid-aligned meshes rarely graze.
const DIRECTIONS: [[f64; 3]; 8] = [
    [0.577_291_337_4, 0.618_012_947_3, 0.533_164_912_8],
    [-0.414_281_903_1, 0.732_001_456_2, 0.541_241_005_9],
    [0.301_123_456_7, -0.693_210_987_6, 0.654_601_234_5],
    [0.707_203_113_9, 0.207_851_117_3, -0.676_702_118_2],
    [-0.649_701_254_3, -0.312_538_911_4, 0.692_871_356_1],
    [0.158_179_227_6, 0.936_281_345_2, -0.313_402_881_7],
    [-0.851_612_338_4, 0.402_931_770_1, -0.335_468_223_9],
    [0.236_119_442_8, -0.447_261_019_5, -0.862_823_115_4],
];

enum Crossing {
    Miss,
    Cross,
    OnSurface,
    Grazing,
}

fn contains_point_f64(mesh: &CollisionMesh, p: DVec3) -> bool {
    let bvh = mesh.bvh();
    let root = bvh.root_aabb();
    let (lo, hi) = (root.min.as_dvec3(), root.max.as_dvec3());
    if p.cmplt(lo).any() || p.cmpgt(hi).any() {
        return false;
    }
    // Long enough to leave the mesh's box from anywhere inside it.
    let length = 2.0 * (hi - lo).length() + 1.0;
    let mut last_parity = false;
    'directions: for dir in DIRECTIONS {
        let q = p + DVec3::from_array(dir) * length;
        let mut parity = false;
        let mut stack: SmallVec<[u32; 64]> = smallvec![0u32];
        while let Some(i) = stack.pop() {
            let node = &bvh.nodes()[i as usize];
            if !segment_hits_box(p, q, node.min.as_dvec3(), node.max.as_dvec3()) {
                continue;
            }
            if !node.is_leaf() {
                stack.push(node.left());
                stack.push(node.left() + 1);
                continue;
            }
            for &t in bvh.triangles_of(node) {
                let tri =
                    triangle_f64(mesh.mesh().triangles()[t as usize], mesh.mesh().positions());
                match crossing(p, q, &tri) {
                    Crossing::Miss => {}
                    Crossing::Cross => parity = !parity,
                    Crossing::OnSurface => return true,
                    Crossing::Grazing => {
                        last_parity = parity;
                        continue 'directions;
                    }
                }
            }
        }
        return parity;
    }
    // Every direction grazed something (practically impossible): best effort.
    last_parity
}

/// Conservative segment–box test (slabs, with a relative margin against rounding).
fn segment_hits_box(p: DVec3, q: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let margin = (lo.abs().max(hi.abs()).max_element() + 1.0) * 1e-9;
    let (lo, hi) = (lo - margin, hi + margin);
    let d = q - p;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        if d[k] == 0.0 {
            if p[k] < lo[k] || p[k] > hi[k] {
                return false;
            }
            continue;
        }
        let inv = 1.0 / d[k];
        let (mut a, mut b) = ((lo[k] - p[k]) * inv, (hi[k] - p[k]) * inv);
        if a > b {
            std::mem::swap(&mut a, &mut b);
        }
        t0 = t0.max(a);
        t1 = t1.min(b);
        if t0 > t1 {
            return false;
        }
    }
    true
}

/// How segment `pq` (with `q` far outside the mesh) meets triangle `tri`, decided exactly.
fn crossing(p: DVec3, q: DVec3, tri: &[DVec3; 3]) -> Crossing {
    let [a, b, c] = *tri;
    let sp = orient3d(a, b, c, p);
    let sq = orient3d(a, b, c, q);
    if sp == 0.0 {
        if triangles_intersect(&[p, p, p], tri) {
            return Crossing::OnSurface;
        }
        if sq != 0.0 {
            return Crossing::Miss;
        }
    }
    if sp == 0.0 || sq == 0.0 {
        // The segment lies in the triangle's plane, the triangle is degenerate, or the far end
        // is on the plane: any contact is a graze.
        return if triangles_intersect(&[p, q, q], tri) {
            Crossing::Grazing
        } else {
            Crossing::Miss
        };
    }
    if (sp > 0.0) == (sq > 0.0) {
        return Crossing::Miss;
    }
    let e = [
        orient3d(p, q, a, b),
        orient3d(p, q, b, c),
        orient3d(p, q, c, a),
    ];
    let pos = e.iter().filter(|&&x| x > 0.0).count();
    let neg = e.iter().filter(|&&x| x < 0.0).count();
    match (pos, neg) {
        (3, 0) | (0, 3) => Crossing::Cross,
        (_, 0) | (0, _) => Crossing::Grazing,
        _ => Crossing::Miss,
    }
}
