//! [`SelfExclusion`] answered for every pair of a small set of triangles at once: each
//! triangle's neighbourhood as a bit mask over the set's few vertices, so that a pair's test
//! is one `AND` instead of a merge of two lists.

use super::SelfExclusion;

/// The exclusion of a few triangles (a neighbourhood of the surface), as bit masks over the
/// vertices their lists hold; built by [`LocalExclusion::build`], reused between builds.
#[derive(Debug, Default, Clone)]
pub(crate) struct LocalExclusion {
    /// Per vertex of the mesh, its bit plus one in the current set (0: none); all zero
    /// between builds.
    bit_of: Vec<u8>,
    /// Vertices given a bit in the current build (reset at the next).
    used: Vec<u32>,
    /// Per triangle of the set: the masks of its two lists (see [`SelfExclusion::excludes`]).
    first: Vec<u128>,
    second: Vec<u128>,
}

impl LocalExclusion {
    /// Prepares the masks of `triangles` under `exclusion`. Returns `false` when their lists
    /// hold more than 128 distinct vertices (the masks are then not to be used: ask
    /// `exclusion` pair by pair).
    pub fn build(&mut self, exclusion: &SelfExclusion, triangles: &[u32]) -> bool {
        for &v in &self.used {
            self.bit_of[v as usize] = 0;
        }
        self.used.clear();
        self.first.clear();
        self.second.clear();
        let vertices = exclusion.mesh_size().0;
        if self.bit_of.len() < vertices {
            self.bit_of.resize(vertices, 0);
        }
        // The lists lie scattered over the whole mesh's: asked for all at once, their loads
        // overlap.
        for &t in triangles {
            exclusion.prefetch_lists(t);
        }
        for &t in triangles {
            let (outer, inner) = exclusion.lists(t);
            let Some(first) = self.mask(outer) else {
                return false;
            };
            // With an even number of rings both lists are the same one.
            let second = if std::ptr::eq(outer, inner) {
                Some(first)
            } else {
                self.mask(inner)
            };
            let Some(second) = second else {
                return false;
            };
            self.first.push(first);
            self.second.push(second);
        }
        true
    }

    /// The mask of `list`, giving new vertices the next bits; `None` past 128.
    fn mask(&mut self, list: &[u32]) -> Option<u128> {
        let mut mask = 0u128;
        for &v in list {
            let slot = &mut self.bit_of[v as usize];
            if *slot == 0 {
                if self.used.len() == 128 {
                    return None;
                }
                self.used.push(v);
                *slot = self.used.len() as u8;
            }
            mask |= 1u128 << (*slot - 1);
        }
        Some(mask)
    }

    /// Whether the `i`-th and `j`-th triangles of the last successful build are excluded:
    /// the same answer as [`SelfExclusion::excludes`] on them, in that order.
    #[inline]
    pub fn excludes(&self, i: usize, j: usize) -> bool {
        self.first[i] & self.second[j] != 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate::noisy_sphere;

    /// On every pair of many small neighbourhoods of an irregular mesh, for 0–3 rings, the
    /// masks answer as the lists do; a set too large for 128 bits is refused.
    #[test]
    fn the_masks_answer_as_the_lists_do() {
        let mesh = noisy_sphere(1.0, 3, 0.2, 7);
        let n = mesh.triangle_count() as u32;
        let mut local = LocalExclusion::default();
        for rings in 0..4 {
            let exclusion = SelfExclusion::new(&mesh, rings);
            let (mut checked, mut refused) = (0, 0);
            for start in (0..n).step_by(37) {
                let set: Vec<u32> = (0..10).map(|k| (start + k * 3) % n).collect();
                let distinct: std::collections::HashSet<u32> = set
                    .iter()
                    .flat_map(|&t| {
                        let (x, y) = exclusion.lists(t);
                        x.iter().chain(y).copied()
                    })
                    .collect();
                if !local.build(&exclusion, &set) {
                    assert!(
                        distinct.len() > 128,
                        "refused at {} vertices",
                        distinct.len()
                    );
                    refused += 1;
                    continue;
                }
                for (i, &t) in set.iter().enumerate() {
                    for (j, &u) in set.iter().enumerate() {
                        assert_eq!(
                            local.excludes(i, j),
                            exclusion.excludes(t, u),
                            "rings {rings}, triangles {t} and {u}"
                        );
                        checked += 1;
                    }
                }
            }
            assert!(
                checked > 1000 && refused < 10,
                "{checked} pairs checked, {refused} sets refused"
            );
            let everything: Vec<u32> = (0..n).collect();
            assert!(!local.build(&exclusion, &everything), "too many vertices");
            // A refused build leaves nothing behind: the next small one is right again.
            let set = [0, 1, 2, 40, 41];
            assert!(local.build(&exclusion, &set));
            assert_eq!(local.excludes(0, 3), exclusion.excludes(0, 40));
            assert_eq!(local.excludes(1, 2), exclusion.excludes(1, 2));
        }
    }
}
