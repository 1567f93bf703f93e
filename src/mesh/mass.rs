//! Mass properties of a triangle mesh: volume (or area), centre of mass and inertia tensor,
//! for rigid-body responses that turn bodies.
use glam::{DMat3, DVec3, Mat3, Vec3};

use super::TriMesh;

/// How the mass of a mesh is taken to be distributed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MassModel {
    /// A uniform solid: the mesh is closed and encloses a volume.
    Solid,
    /// A uniform thin shell over the surface: the mesh is open (or encloses no volume), so
    /// it has no inside to fill.
    Shell,
    /// The solid box of the mesh's bounds: the surface has no area (every triangle
    /// degenerate).
    Bounds,
}

/// Mass properties of a mesh of unit density per unit mass: what a rigid body of any mass
/// needs to turn (multiply [`MassProperties::inertia`] by the body's mass).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassProperties {
    /// How the mass is distributed.
    pub model: MassModel,
    /// The volume ([`MassModel::Solid`], [`MassModel::Bounds`]) or the surface area
    /// ([`MassModel::Shell`]).
    pub measure: f32,
    /// Centre of mass, in the mesh's frame.
    pub center: Vec3,
    /// Inertia tensor about the centre of mass, in the mesh's frame, for a body of unit mass.
    pub inertia: Mat3,
    /// Largest distance of a vertex from the centre of mass.
    pub radius: f32,
}

impl MassProperties {
    /// The inverse of [`MassProperties::inertia`] (unit mass). A tensor that cannot be
    /// inverted (a mesh flat as a line, whose inertia about its own axis is 0) is first
    /// given, on each axis, a millionth of the largest principal moment, so the inverse is
    /// finite: such a body spins easily about that axis instead of dividing by zero.
    pub fn inverse_inertia(&self) -> Mat3 {
        let i = self.inertia.as_dmat3();
        let floor = 1e-6 * (i.x_axis.x + i.y_axis.y + i.z_axis.z).max(f64::MIN_POSITIVE);
        let i = i + DMat3::from_diagonal(DVec3::splat(floor));
        let det = i.determinant();
        if det.is_finite() && det > 0.0 {
            i.inverse().as_mat3()
        } else {
            Mat3::ZERO
        }
    }
}

impl TriMesh {
    /// Mass properties of the mesh scaled by `scale` (per axis, in the mesh's frame): a
    /// uniform solid if the mesh is closed and encloses a volume (either orientation of
    /// its triangles), otherwise a uniform shell over its surface, or the solid box of its
    /// bounds when its surface has no area. Sums are taken in f64.
    ///
    /// ```
    /// use glam::Vec3;
    /// use stochastic_collision::mesh::{MassModel, generate};
    /// let cube = generate::cuboid(Vec3::new(1.0, 2.0, 3.0), 2);
    /// let m = cube.mass_properties(Vec3::ONE);
    /// assert_eq!(m.model, MassModel::Solid);
    /// assert!((m.measure - 48.0).abs() < 1e-3);
    /// // A box's moment about x: (h_y² + h_z²) / 3 per unit mass.
    /// assert!((m.inertia.x_axis.x - 13.0 / 3.0).abs() < 1e-4);
    /// ```
    pub fn mass_properties(&self, scale: Vec3) -> MassProperties {
        let scale = scale.as_dvec3();
        let points: Vec<DVec3> = self
            .positions()
            .iter()
            .map(|p| p.as_dvec3() * scale)
            .collect();
        let corners = |t: &[u32; 3]| t.map(|i| points[i as usize]);
        let (bounds_lo, bounds_hi) = points.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let size = (bounds_hi - bounds_lo).max(DVec3::ZERO);
        // A closed mesh's signed tetrahedra from the origin sum to its volume.
        let solid = self.is_closed().then(|| {
            let mut sums = Moments::default();
            for t in self.triangles() {
                let [a, b, c] = corners(t);
                let v = a.dot(b.cross(c)) / 6.0;
                let s = a + b + c;
                sums.add(v, s / 4.0, v / 20.0, [a, b, c], s);
            }
            sums
        });
        let reference = size.x * size.y * size.z;
        let (model, sums) = match solid {
            Some(s) if s.mass.abs() > 1e-9 * reference.max(f64::MIN_POSITIVE) => {
                (MassModel::Solid, s.oriented())
            }
            _ => {
                let mut sums = Moments::default();
                for t in self.triangles() {
                    let [a, b, c] = corners(t);
                    let area = 0.5 * (b - a).cross(c - a).length();
                    let s = a + b + c;
                    sums.add(area, s / 3.0, area / 12.0, [a, b, c], s);
                }
                if sums.mass > 0.0 {
                    (MassModel::Shell, sums)
                } else {
                    (MassModel::Bounds, Moments::of_box(bounds_lo, bounds_hi))
                }
            }
        };
        let center = sums.first / sums.mass;
        // Second moments about the centre, per unit mass; inertia = tr(C)·1 - C.
        let c = sums.second * (1.0 / sums.mass) - outer(center, center);
        let inertia = DMat3::from_diagonal(DVec3::splat(c.x_axis.x + c.y_axis.y + c.z_axis.z)) - c;
        let radius = points
            .iter()
            .map(|p| p.distance(center))
            .fold(0.0f64, f64::max);
        MassProperties {
            model,
            measure: sums.mass as f32,
            center: center.as_vec3(),
            inertia: inertia.as_mat3(),
            radius: radius as f32,
        }
    }
}

/// Running sums of mass (volume or area), first and second moments.
struct Moments {
    mass: f64,
    first: DVec3,
    second: DMat3,
}

impl Default for Moments {
    /// Nothing summed yet (not `DMat3::default()`, the identity).
    fn default() -> Self {
        Self {
            mass: 0.0,
            first: DVec3::ZERO,
            second: DMat3::ZERO,
        }
    }
}

impl Moments {
    /// Adds a simplex of measure `m` and centroid `centroid`, whose second moment is
    /// `factor · (Σ pᵢpᵢᵀ + s sᵀ)` over its corners (the origin, for a tetrahedron,
    /// contributes nothing), `s` the sum of the corners.
    fn add(&mut self, m: f64, centroid: DVec3, factor: f64, corners: [DVec3; 3], s: DVec3) {
        self.mass += m;
        self.first += centroid * m;
        let mut second = outer(s, s);
        for p in corners {
            second += outer(p, p);
        }
        self.second += second * factor;
    }

    /// The sums of an inward-oriented closed mesh are those of the outward one, negated.
    fn oriented(self) -> Moments {
        if self.mass >= 0.0 {
            return self;
        }
        Moments {
            mass: -self.mass,
            first: -self.first,
            second: -self.second,
        }
    }

    /// The solid box `lo..hi` (a point or a flat box has mass 0: given unit mass, so the
    /// centre is defined and the inertia that of the box, possibly 0).
    fn of_box(lo: DVec3, hi: DVec3) -> Moments {
        let (center, half) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
        let variance = half * half / 3.0;
        Moments {
            mass: 1.0,
            first: center,
            second: DMat3::from_diagonal(variance) + outer(center, center),
        }
    }
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;

    fn close(a: f32, b: f32, tolerance: f32) -> bool {
        (a - b).abs() <= tolerance * b.abs().max(1e-6)
    }

    fn diagonal(m: &Mat3) -> Vec3 {
        Vec3::new(m.x_axis.x, m.y_axis.y, m.z_axis.z)
    }

    #[test]
    fn a_box_off_the_origin_has_the_textbook_tensor_about_its_centre() {
        let h = Vec3::new(0.5, 1.0, 2.0);
        let moved: Vec<Vec3> = generate::cuboid(h, 3)
            .positions()
            .iter()
            .map(|p| *p + Vec3::new(3.0, -1.0, 5.0))
            .collect();
        let mesh = TriMesh::new(moved, generate::cuboid(h, 3).triangles().to_vec()).unwrap();
        let m = mesh.mass_properties(Vec3::ONE);
        assert_eq!(m.model, MassModel::Solid);
        assert!(close(m.measure, 8.0 * h.x * h.y * h.z, 1e-5));
        assert!((m.center - Vec3::new(3.0, -1.0, 5.0)).length() < 1e-4);
        let expected = Vec3::new(
            h.y * h.y + h.z * h.z,
            h.x * h.x + h.z * h.z,
            h.x * h.x + h.y * h.y,
        ) / 3.0;
        let d = diagonal(&m.inertia);
        for k in 0..3 {
            assert!(close(d[k], expected[k], 1e-4), "{d} against {expected}");
        }
        // Off-diagonal terms vanish for an axis-aligned box.
        assert!(m.inertia.x_axis.y.abs() < 1e-4 && m.inertia.x_axis.z.abs() < 1e-4);
    }

    #[test]
    fn scale_and_orientation_give_the_same_body() {
        let cube = generate::cuboid(Vec3::ONE, 2);
        let scaled = cube.mass_properties(Vec3::new(0.5, 1.0, 2.0));
        let built = generate::cuboid(Vec3::new(0.5, 1.0, 2.0), 2).mass_properties(Vec3::ONE);
        assert!(close(scaled.measure, built.measure, 1e-5));
        assert!((diagonal(&scaled.inertia) - diagonal(&built.inertia)).length() < 1e-4);
        // Triangles wound inwards: the same solid.
        let flipped: Vec<[u32; 3]> = cube
            .triangles()
            .iter()
            .map(|t| [t[0], t[2], t[1]])
            .collect();
        let inward = TriMesh::new(cube.positions().to_vec(), flipped).unwrap();
        let (a, b) = (
            inward.mass_properties(Vec3::ONE),
            cube.mass_properties(Vec3::ONE),
        );
        assert_eq!(a.model, MassModel::Solid);
        assert!(close(a.measure, b.measure, 1e-6));
        assert!((diagonal(&a.inertia) - diagonal(&b.inertia)).length() < 1e-5);
    }

    #[test]
    fn a_fine_sphere_and_torus_match_their_formulas() {
        let sphere = generate::icosphere(2.0, 4).mass_properties(Vec3::ONE);
        let volume = 4.0 / 3.0 * std::f32::consts::PI * 8.0;
        assert!(close(sphere.measure, volume, 0.01));
        for k in 0..3 {
            assert!(close(diagonal(&sphere.inertia)[k], 0.4 * 4.0, 0.01));
        }
        assert!(close(sphere.radius, 2.0, 1e-4));
        // A torus about its axis (the largest moment): m (R² + ¾a²); about a diameter (the
        // other two): m (R²/2 + ⅝a²).
        let (r, a) = (1.0f32, 0.25f32);
        let torus = generate::torus(r, a, 96, 48).mass_properties(Vec3::ONE);
        let mut d = diagonal(&torus.inertia).to_array();
        d.sort_by(f32::total_cmp);
        assert!(close(d[2], r * r + 0.75 * a * a, 0.01), "{d:?}");
        assert!(close(d[0], 0.5 * r * r + 0.625 * a * a, 0.01), "{d:?}");
        assert!(close(d[1], d[0], 1e-3));
    }

    #[test]
    fn open_and_degenerate_meshes_fall_back_without_nan() {
        // A square sheet in the xz plane: a shell; moments of a thin plate.
        let sheet = TriMesh::new(
            vec![
                Vec3::new(-1.0, 0.0, -1.0),
                Vec3::new(1.0, 0.0, -1.0),
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(-1.0, 0.0, 1.0),
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
        .unwrap();
        let m = sheet.mass_properties(Vec3::ONE);
        assert_eq!(m.model, MassModel::Shell);
        assert!(close(m.measure, 4.0, 1e-6));
        let d = diagonal(&m.inertia);
        assert!(
            close(d.x, 1.0 / 3.0, 1e-5) && close(d.z, 1.0 / 3.0, 1e-5),
            "{d}"
        );
        assert!(close(d.y, 2.0 / 3.0, 1e-5));
        assert!(m.inverse_inertia().is_finite());
        // Every triangle degenerate (collinear points): the bounds, a finite inverse.
        let line = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0], vec![[0, 1, 2]]).unwrap();
        let m = line.mass_properties(Vec3::ONE);
        assert_eq!(m.model, MassModel::Bounds);
        assert!((m.center - Vec3::X).length() < 1e-6);
        assert!(m.inertia.is_finite() && m.inverse_inertia().is_finite());
        // A single point: nothing to turn, still finite.
        let point = TriMesh::new(vec![Vec3::ONE], vec![[0, 0, 0]]).unwrap();
        let m = point.mass_properties(Vec3::ONE);
        assert!(m.inverse_inertia().is_finite() && m.center == Vec3::ONE);
    }
}
