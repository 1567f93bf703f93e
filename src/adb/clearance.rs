//! How far each part of an [`InteriorMap`](super::InteriorMap) is from the nearest voxel that
//! is not wholly outside the mesh, and from the nearest that is not wholly inside: a whole
//! chunk of surface samples whose sphere lies in the clear is outside, one whose sphere lies
//! deep inside is inside, from one lookup instead of one per sample.
use glam::{UVec3, Vec3A};

/// Voxels along each side of a block.
pub(super) const BLOCK: u32 = 4;

/// Per block of [`BLOCK`]³ voxels, the Chebyshev distances in blocks to the nearest block that
/// holds a voxel not classified outside, and to the nearest that holds one not classified
/// inside (beyond the grid everything is outside), each 0 for such a block, at most 255.
#[derive(Debug, Clone, Default)]
pub(super) struct Clearance {
    /// Per block: `[to not outside, to not inside]`.
    blocks: Vec<[u8; 2]>,
    /// Blocks along each axis.
    dims: [u32; 3],
    /// The grid's last point (in voxels), just short of its far corner.
    last_point: Vec3A,
}

/// Whether a block `k` blocks (Chebyshev) from the nearest block of a kind is farther than
/// `reach` voxels (squared, `≥ 0`) from every voxel of that kind, with a voxel to spare for
/// rounding: a point in it is at least `k − 1` whole blocks from them, along some axis.
#[inline]
fn beyond(k: u8, reach_squared: f32) -> bool {
    let gap = (f32::from(k) - 1.0) * BLOCK as f32 - 1.0;
    gap > 0.0 && gap * gap > reach_squared
}

impl Clearance {
    /// The clearance of a voxel grid of `dims` voxels, `class(i)` telling whether voxel `i`
    /// (x fastest, then y, then z) is wholly outside (`Some(false)`), wholly inside
    /// (`Some(true)`) or neither (`None`).
    pub fn build(dims: [u32; 3], class: impl Fn(usize) -> Option<bool>) -> Self {
        let bd = dims.map(|d| d.div_ceil(BLOCK));
        let count = bd.iter().map(|&d| d as usize).product::<usize>();
        let mut blocks = vec![[u8::MAX; 2]; count];
        let block_of =
            |x: u32, y: u32, z: u32| ((z / BLOCK * bd[1] + y / BLOCK) * bd[0] + x / BLOCK) as usize;
        let mut i = 0;
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    let b = &mut blocks[block_of(x, y, z)];
                    match class(i) {
                        Some(false) => b[1] = 0,
                        Some(true) => b[0] = 0,
                        None => *b = [0, 0],
                    }
                    i += 1;
                }
            }
        }
        // Beyond the grid is outside: a block on its border, or one holding voxels beyond it
        // (the last ones along an axis whose voxels are not a multiple of a block), is next to
        // a voxel not inside.
        for z in 0..bd[2] {
            for y in 0..bd[1] {
                for x in 0..bd[0] {
                    let border = [x, y, z].iter().zip(bd).any(|(&c, n)| c == 0 || c + 1 == n);
                    let partial = [x, y, z]
                        .iter()
                        .zip(dims)
                        .any(|(&c, d)| (c + 1) * BLOCK > d);
                    let b = &mut blocks[((z * bd[1] + y) * bd[0] + x) as usize];
                    if partial {
                        b[1] = 0;
                    } else if border {
                        b[1] = b[1].min(1);
                    }
                }
            }
        }
        // Two chamfer passes over the 26-neighbourhood: the exact Chebyshev distance.
        let index = |x: i64, y: i64, z: i64| ((z * bd[1] as i64 + y) * bd[0] as i64 + x) as usize;
        let on_grid = |x: i64, y: i64, z: i64| {
            (0..bd[0] as i64).contains(&x)
                && (0..bd[1] as i64).contains(&y)
                && (0..bd[2] as i64).contains(&z)
        };
        let mut pass = |forward: bool| {
            let (nx, ny, nz) = (bd[0] as i64, bd[1] as i64, bd[2] as i64);
            for k in 0..nz * ny * nx {
                let k = if forward { k } else { nz * ny * nx - 1 - k };
                let (x, y, z) = (k % nx, k / nx % ny, k / (nx * ny));
                let mut best = blocks[index(x, y, z)];
                for dz in -1..=1i64 {
                    for dy in -1..=1i64 {
                        for dx in -1..=1i64 {
                            // Only the neighbours already visited in this pass's order.
                            let before = (dz, dy, dx) < (0, 0, 0);
                            if before != forward || (dx, dy, dz) == (0, 0, 0) {
                                continue;
                            }
                            let (px, py, pz) = (x + dx, y + dy, z + dz);
                            if on_grid(px, py, pz) {
                                let n = blocks[index(px, py, pz)];
                                for kind in 0..2 {
                                    best[kind] = best[kind].min(n[kind].saturating_add(1));
                                }
                            }
                        }
                    }
                }
                blocks[index(x, y, z)] = best;
            }
        };
        pass(true);
        pass(false);
        let last_point =
            Vec3A::from_array(dims.map(|d| (d as f32 * (1.0 - f32::EPSILON)).max(0.0)));
        Self {
            blocks,
            dims: bd,
            last_point,
        }
    }

    /// The blocks of the grid point nearest `centre` (voxel coordinates, finite) and the
    /// squared distance from `centre` to it.
    #[inline]
    fn nearest_block(&self, centre: Vec3A) -> Option<([u8; 2], f32)> {
        // A point of the grid is at least as far from the centre as from the nearest grid
        // point, and farther by the centre's distance beyond the grid (the angle at a
        // projection onto a box is obtuse).
        let nearest = centre.clamp(Vec3A::ZERO, self.last_point);
        let at: UVec3 = (nearest * (1.0 / BLOCK as f32)).as_uvec3();
        let k = *self
            .blocks
            .get(((at.z * self.dims[1] + at.y) * self.dims[0] + at.x) as usize)?;
        Some((k, (centre - nearest).length_squared()))
    }

    /// Whether every point within `radius` voxels of `centre` (in voxel coordinates) lies in a
    /// voxel classified outside or beyond the grid (`Some(false)`), or every one in a voxel
    /// classified inside (`Some(true)`). `None` if neither can be told from the blocks, for a
    /// grid without voxels, or a centre that is not finite.
    #[inline]
    pub fn sphere_side(&self, centre: Vec3A, radius: f32) -> Option<bool> {
        if !centre.is_finite() {
            return None;
        }
        let ([to_not_outside, to_not_inside], beyond_grid) = self.nearest_block(centre)?;
        let reach = radius * radius - beyond_grid;
        if reach < 0.0 || beyond(to_not_outside, reach) {
            Some(false)
        } else if beyond_grid == 0.0 && beyond(to_not_inside, reach) {
            Some(true)
        } else {
            None
        }
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        self.blocks.capacity()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a grid holding a ball (inside), its shell (neither) and a stray voxel (neither), the
    /// block distances are the Chebyshev ones found by brute force (beyond the grid counting
    /// as outside), a clear sphere reaches no voxel that is not outside, and a sphere said to
    /// be inside reaches only voxels inside.
    #[test]
    fn block_distances_are_chebyshev_and_clear_or_inside_spheres_are_so_voxel_by_voxel() {
        let dims = [41u32, 38, 35];
        let centre = Vec3A::new(20.0, 18.5, 17.0);
        let class_of = |x: u32, y: u32, z: u32| {
            let d = (Vec3A::new(x as f32, y as f32, z as f32) + 0.5).distance(centre);
            if (x, y, z) == (37, 3, 2) || (14.0..15.5).contains(&d) {
                None
            } else {
                Some(d < 14.0)
            }
        };
        let index = |x: u32, y: u32, z: u32| ((z * dims[1] + y) * dims[0] + x) as usize;
        let mut classes = vec![None; index(dims[0] - 1, dims[1] - 1, dims[2] - 1) + 1];
        let mut voxels = Vec::new();
        for z in 0..dims[2] {
            for y in 0..dims[1] {
                for x in 0..dims[0] {
                    classes[index(x, y, z)] = class_of(x, y, z);
                    voxels.push((x, y, z, class_of(x, y, z)));
                }
            }
        }
        let c = Clearance::build(dims, |i| classes[i]);
        let bd = dims.map(|d| d.div_ceil(BLOCK));
        let block = |v: u32| i64::from(v / BLOCK);
        for z in 0..bd[2] {
            for y in 0..bd[1] {
                for x in 0..bd[0] {
                    let distance = |kind: Option<bool>| {
                        let to_voxels = voxels
                            .iter()
                            .filter(|v| v.3 != kind)
                            .map(|v| {
                                let d = |a: u32, b: u32| (i64::from(a) - block(b)).abs();
                                d(x, v.0).max(d(y, v.1)).max(d(z, v.2))
                            })
                            .min()
                            .unwrap_or(255);
                        if kind == Some(true) {
                            // Beyond the grid, outside: one block past the border.
                            let to_border = [x, y, z]
                                .iter()
                                .zip(bd)
                                .map(|(&c, n)| i64::from(c.min(n - 1 - c)) + 1)
                                .min()
                                .unwrap();
                            to_voxels.min(to_border)
                        } else {
                            to_voxels
                        }
                    };
                    let k = c.blocks[((z * bd[1] + y) * bd[0] + x) as usize];
                    assert_eq!(
                        i64::from(k[0]),
                        distance(Some(false)).min(255),
                        "{x},{y},{z}"
                    );
                    assert!(i64::from(k[1]) <= distance(Some(true)), "{x},{y},{z}");
                }
            }
        }
        // Spheres around points of and beyond the grid: clear ones reach only voxels outside,
        // inside ones only voxels inside.
        let (mut clear, mut inside) = (0, 0);
        for z in (-6..dims[2] as i32 + 6).step_by(3) {
            for y in (-6..dims[1] as i32 + 6).step_by(3) {
                for x in (-6..dims[0] as i32 + 6).step_by(3) {
                    let p = Vec3A::new(x as f32 + 0.3, y as f32 + 0.6, z as f32 + 0.2);
                    for radius in [0.0f32, 1.5, 4.0, 9.0] {
                        let reaches = |v: &(u32, u32, u32, Option<bool>)| {
                            let lo = Vec3A::new(v.0 as f32, v.1 as f32, v.2 as f32);
                            (p.clamp(lo, lo + 1.0) - p).length() <= radius
                        };
                        if let Some(side) = c.sphere_side(p, radius) {
                            if side {
                                inside += 1;
                            } else {
                                clear += 1;
                            }
                            assert!(
                                voxels
                                    .iter()
                                    .filter(|v| reaches(v))
                                    .all(|v| v.3 == Some(side)),
                                "{p} r {radius}: {side}"
                            );
                        }
                    }
                }
            }
        }
        assert!(clear > 100 && inside > 3, "{clear} clear, {inside} inside");
        assert_eq!(c.sphere_side(Vec3A::new(f32::NAN, 0.0, 0.0), 1.0), None);
        assert_eq!(c.sphere_side(Vec3A::new(-30.0, 0.0, 0.0), 1.0), Some(false));
        // A grid without voxels says nothing.
        let empty = Clearance::build([0, 0, 0], |_| None);
        assert_eq!(empty.sphere_side(Vec3A::ZERO, 1.0), None);
    }
}
