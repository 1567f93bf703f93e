//! Which patches of a surface can hold triangles that self-collision excludes together (within
//! its vertex rings of each other): a filter in front of the per-triangle exclusion lists.

use super::patch_tree::PatchTree;
use crate::mesh::{Topology, TriMesh};

/// Per patch, the patches holding a triangle within the exclusion's rings of one of its
/// triangles (its own included), sorted: two triangles whose patches are not so related are
/// never excluded, which two small lookups say before the exclusion's lists are read.
#[derive(Debug, Clone, Default)]
pub(crate) struct PatchReach {
    offsets: Vec<u32>,
    patches: Vec<u32>,
}

impl PatchReach {
    /// Multi-source walks of `rings` vertex rings from each patch's corners on `topology`
    /// (the welded mesh's, whose triangles are the surface's, in the same order).
    pub(super) fn new(tree: &PatchTree, mesh: &TriMesh, topology: &Topology, rings: u32) -> Self {
        let mut reach = PatchReach {
            offsets: vec![0],
            patches: Vec::new(),
        };
        let mut mark = vec![u32::MAX; mesh.vertex_count()];
        let (mut reached, mut frontier, mut next, mut near) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (p, patch) in tree.patches.iter().enumerate() {
            let p = p as u32;
            reached.clear();
            frontier.clear();
            for &t in &patch.triangles {
                for v in mesh.triangles()[t as usize] {
                    if mark[v as usize] != p {
                        mark[v as usize] = p;
                        frontier.push(v);
                        reached.push(v);
                    }
                }
            }
            for _ in 0..rings {
                next.clear();
                for &v in &frontier {
                    for &w in topology.vertex_neighbours(v) {
                        if mark[w as usize] != p {
                            mark[w as usize] = p;
                            next.push(w);
                            reached.push(w);
                        }
                    }
                }
                std::mem::swap(&mut frontier, &mut next);
            }
            near.clear();
            for &v in &reached {
                near.extend(
                    topology
                        .vertex_triangles(v)
                        .iter()
                        .map(|&u| tree.patch_of[u as usize]),
                );
            }
            near.sort_unstable();
            near.dedup();
            reach.patches.extend_from_slice(&near);
            reach.offsets.push(reach.patches.len() as u32);
        }
        reach
    }

    /// Whether a triangle of patch `q` may be within the rings of one of patch `p`.
    #[inline]
    pub(super) fn may_meet(&self, p: u32, q: u32) -> bool {
        let (s, e) = (
            self.offsets[p as usize] as usize,
            self.offsets[p as usize + 1] as usize,
        );
        self.patches[s..e].contains(&q)
    }
}
