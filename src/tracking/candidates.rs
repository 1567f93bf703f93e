//! Where new pairs are drawn from, kept between steps: the overlapping patch pairs and the
//! sharp edges of one surface (self-collision), refreshed where the surface moved: all of
//! them at the default settings, within a time allowance per step under a time budget.
//!
//! The patch tree is cut into blocks (its subtrees at a depth that gives them about
//! [`BLOCK_PATCHES`] patches each, at most [`MAX_BLOCK_DEPTH`] levels down). The overlapping
//! patch pairs are kept per pair of blocks (a block with itself: the pairs inside it), the
//! sharp edges per block (with the block's pair with itself). Each patch has an odometer (how
//! far its vertices moved in all, kept by the surface update), and so each block (the sum of
//! its patches'). A step refreshes the lists that are the most out of date first (how much
//! the odometers of their blocks grew since they were made, and for sharp edges those of the
//! blocks next to it too: an edge's second triangle may lie there), until its allowance is
//! spent (an allowance of [`Duration::MAX`] is never spent: every list whose blocks moved is
//! made again, and the lists are those of a search of the whole surface): a surface at rest
//! costs nothing, and a motion in one place refreshes the pairs of the blocks it reached
//! only. Where no vertex moved, the lists are exact. The lists are only
//! where samples start: a pair drawn from an out-of-date list is measured on the current
//! surface by the local search like any other, so a stale list costs samples, never a wrong
//! contact.

use std::time::{Duration, Instant};

use super::sharp_edges::sharp_edges_of;
use super::surface::TrackedSurface;

/// Blocks hold about this many patches (at least, where the tree allows): fewer, and the
/// bookkeeping of the pairs of blocks outweighs what a refresh finds. A setting of the
/// amortization (how finely the work of one full search is divided), not fitted to any mesh.
pub(crate) const BLOCK_PATCHES: usize = 32;

/// The tree is cut at most this deep: at most 64 blocks (2080 pairs of blocks).
pub(crate) const MAX_BLOCK_DEPTH: u32 = 6;

/// A subtree of the patch tree.
#[derive(Debug, Clone, Default)]
struct Block {
    /// Root node in the patch tree.
    root: u32,
    /// Its patches.
    patches: Vec<u32>,
    /// Its patches' sharp edges when its pair with itself was last refreshed (as
    /// [`sharp_edges_of`] gives them, near known contacts or not).
    sharp: Vec<(f32, u32, bool)>,
    /// The sum of its patches' [travels](super::patch_tree::Patch::travel): it grows by at
    /// least as much as any of its vertices moves.
    odometer: f64,
    /// The other blocks holding a patch adjacent to one of its patches: whether an edge of
    /// the block is sharp, or a patch of it may crease, depends on their triangles too.
    neighbours: Vec<u32>,
    /// Its neighbours' odometers when its sharp edges were last found.
    neighbours_seen: Vec<f64>,
}

/// Two blocks (or a block with itself) and the overlapping patch pairs between them.
#[derive(Debug, Clone, Default)]
struct BlockPair {
    /// The blocks, `x <= y`.
    x: u32,
    y: u32,
    /// Its overlapping patch pairs (`a <= b`) when last refreshed.
    overlaps: Vec<(u32, u32)>,
    /// The margin they were found with; `None`: never refreshed.
    margin: Option<f32>,
    /// The two blocks' odometers when it was last refreshed.
    seen: (f64, f64),
}

/// Candidate patch pairs and sharp edges of one surface, kept between steps (see the module
/// docs).
#[derive(Debug, Clone, Default)]
pub(crate) struct KeptCandidates {
    /// The surface the blocks were made for ([`TrackedSurface::topology_id`]).
    made_for: Option<u64>,
    blocks: Vec<Block>,
    pairs: Vec<BlockPair>,
    /// Scratch: (how out of date, block pair) in refresh order.
    order: Vec<(f64, u32)>,
    stack: Vec<(u32, u32)>,
    /// Block pairs refreshed by the last [`KeptCandidates::refresh`].
    pub refreshed: usize,
    /// The overlapping patch pairs of the lists the last [`KeptCandidates::refresh`] made
    /// again (those where the surface moved).
    pub refreshed_overlaps: usize,
}

impl KeptCandidates {
    /// Blocks in all.
    #[cfg(test)]
    pub fn block_count(&self) -> usize {
        self.blocks.len()
    }

    /// Block pairs in all (a block with itself included): the lists kept.
    pub fn pair_count(&self) -> usize {
        self.pairs.len()
    }

    /// Brings the lists up to date where `surface` moved most, the most out of date first,
    /// until `allowance` is spent ([`Duration::MAX`]: every list whose blocks moved; lists
    /// never made, or made with a smaller margin than `margin`, are made whatever the
    /// allowance); then writes the overlapping patch pairs to
    /// `overlaps` and the sharp edges to `sharp` (as [`sharp_edges_of`] gives them with no
    /// known contact).
    pub fn refresh(
        &mut self,
        surface: &TrackedSurface,
        margin: f32,
        allowance: Duration,
        overlaps: &mut Vec<(u32, u32)>,
        sharp: &mut Vec<(f32, u32, bool)>,
    ) {
        let started = Instant::now();
        let tree = &surface.patches;
        if self.made_for != Some(surface.topology_id()) {
            self.make_blocks(surface);
            self.made_for = Some(surface.topology_id());
        }
        for block in &mut self.blocks {
            block.odometer = block
                .patches
                .iter()
                .map(|&p| tree.patches[p as usize].travel)
                .sum();
        }
        // A list is as out of date as the most one of its blocks' odometers grew since it was
        // made (zero: no vertex there moved, the list is exact); a larger margin than it was
        // found with makes it incomplete.
        self.order.clear();
        for (k, pair) in self.pairs.iter().enumerate() {
            // Two blocks whose boxes are apart hold no overlapping patch pairs: an empty list
            // of theirs is exact (a list that is not empty is refreshed, to empty).
            let (rx, ry) = (
                self.blocks[pair.x as usize].root,
                self.blocks[pair.y as usize].root,
            );
            if pair.x != pair.y
                && pair.overlaps.is_empty()
                && pair.margin.is_some_and(|m| m >= margin)
                && !tree.nodes_meet(rx, ry, margin)
            {
                continue;
            }
            let staleness = match pair.margin {
                Some(m) if m >= margin => {
                    let grew = |b: u32, seen: f64| self.blocks[b as usize].odometer - seen;
                    let mut staleness = grew(pair.x, pair.seen.0).max(grew(pair.y, pair.seen.1));
                    if pair.x == pair.y {
                        let block = &self.blocks[pair.x as usize];
                        for (&q, &seen) in block.neighbours.iter().zip(&block.neighbours_seen) {
                            staleness = staleness.max(grew(q, seen));
                        }
                    }
                    staleness
                }
                _ => f64::INFINITY,
            };
            if staleness > 0.0 {
                self.order.push((staleness, k as u32));
            }
        }
        self.order
            .sort_unstable_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        self.refreshed = 0;
        self.refreshed_overlaps = 0;
        for i in 0..self.order.len() {
            let (staleness, k) = self.order[i];
            if staleness.is_finite() && self.refreshed > 0 && started.elapsed() >= allowance {
                break;
            }
            self.refresh_pair(surface, k as usize, margin);
            self.refreshed += 1;
            self.refreshed_overlaps += self.pairs[k as usize].overlaps.len();
        }
        overlaps.clear();
        for pair in &self.pairs {
            overlaps.extend_from_slice(&pair.overlaps);
        }
        sharp.clear();
        for block in &self.blocks {
            sharp.extend_from_slice(&block.sharp);
        }
    }

    /// Cuts `surface`'s patch tree into blocks, and makes their pairs.
    fn make_blocks(&mut self, surface: &TrackedSurface) {
        let tree = &surface.patches;
        self.blocks = tree
            .block_roots(
                (tree.patches.len() / BLOCK_PATCHES)
                    .max(1)
                    .ilog2()
                    .min(MAX_BLOCK_DEPTH),
            )
            .into_iter()
            .map(|root| {
                let mut patches = Vec::new();
                tree.patches_below(root, &mut patches);
                Block {
                    root,
                    patches,
                    ..Block::default()
                }
            })
            .collect();
        let mut block_of = vec![0u32; tree.patches.len()];
        for (b, block) in self.blocks.iter().enumerate() {
            for &p in &block.patches {
                block_of[p as usize] = b as u32;
            }
        }
        for (b, block) in self.blocks.iter_mut().enumerate() {
            let mut neighbours: Vec<u32> = block
                .patches
                .iter()
                .flat_map(|&p| tree.patches[p as usize].adjacent.iter())
                .map(|&q| block_of[q as usize])
                .filter(|&q| q != b as u32)
                .collect();
            neighbours.sort_unstable();
            neighbours.dedup();
            block.neighbours = neighbours;
        }
        let m = self.blocks.len() as u32;
        self.pairs = (0..m)
            .flat_map(|x| (x..m).map(move |y| (x, y)))
            .map(|(x, y)| BlockPair {
                x,
                y,
                ..BlockPair::default()
            })
            .collect();
    }

    /// Finds block pair `k`'s overlapping patch pairs anew (and, for a block with itself,
    /// the block's sharp edges).
    fn refresh_pair(&mut self, surface: &TrackedSurface, k: usize, margin: f32) {
        let tree = &surface.patches;
        let pair = &mut self.pairs[k];
        let (bx, by) = (&self.blocks[pair.x as usize], &self.blocks[pair.y as usize]);
        self.stack.clear();
        self.stack.push((bx.root, by.root));
        pair.seen = (bx.odometer, by.odometer);
        pair.margin = Some(margin);
        pair.overlaps.clear();
        tree.self_overlaps_from(margin, &mut self.stack, &mut pair.overlaps);
        if pair.x == pair.y {
            // Reuses the block's own vector: no allocation per refresh.
            let mut seen = std::mem::take(&mut self.blocks[pair.x as usize].neighbours_seen);
            seen.clear();
            let neighbours = &self.blocks[pair.x as usize].neighbours;
            seen.extend(neighbours.iter().map(|&q| self.blocks[q as usize].odometer));
            let block = &mut self.blocks[pair.x as usize];
            block.neighbours_seen = seen;
            block.sharp.clear();
            sharp_edges_of(
                surface,
                block.patches.iter().copied(),
                &[],
                &mut block.sharp,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::tracking::sharp_edges::sharp_edges;
    use glam::Vec3;

    const MARGIN: f32 = 0.02;

    /// A full search of `surface`: its overlapping patch pairs and its sharp edges, sorted.
    fn full_search(surface: &TrackedSurface) -> (Vec<(u32, u32)>, Vec<u32>) {
        let (mut stack, mut overlaps, mut sharp) = (Vec::new(), Vec::new(), Vec::new());
        surface
            .patches
            .self_overlaps(MARGIN, &mut stack, &mut overlaps);
        sharp_edges(surface, &[], &mut sharp);
        sorted(overlaps, sharp)
    }

    fn sorted(
        mut overlaps: Vec<(u32, u32)>,
        sharp: Vec<(f32, u32, bool)>,
    ) -> (Vec<(u32, u32)>, Vec<u32>) {
        overlaps.sort_unstable();
        let mut edges: Vec<u32> = sharp.iter().map(|s| s.1).collect();
        edges.sort_unstable();
        (overlaps, edges)
    }

    fn refresh(
        kept: &mut KeptCandidates,
        surface: &TrackedSurface,
        allowance: Duration,
    ) -> (Vec<(u32, u32)>, Vec<u32>) {
        let (mut overlaps, mut sharp) = (Vec::new(), Vec::new());
        kept.refresh(surface, MARGIN, allowance, &mut overlaps, &mut sharp);
        let distinct = overlaps.len();
        let result = sorted(overlaps, sharp);
        let mut unique = result.0.clone();
        unique.dedup();
        assert_eq!(unique.len(), distinct, "a patch pair is kept twice");
        result
    }

    /// A sheet (of 48 × 48 squares in the tests) whose right half is turned about the z axis
    /// by `angle` (folded over the left half at π, a little above it).
    fn folded(sheet: &crate::mesh::TriMesh, angle: f32) -> Vec<Vec3> {
        sheet
            .positions()
            .iter()
            .map(|p| {
                if p.x > 0.0 {
                    let (s, c) = angle.sin_cos();
                    Vec3::new(
                        p.x * c,
                        p.x * s + 0.01 * (angle / std::f32::consts::PI),
                        p.z,
                    )
                } else {
                    *p
                }
            })
            .collect()
    }

    /// With time for everything, the kept lists are a full search's at every step of a fold
    /// and of its unfolding (patches come together, then apart), and a step after which
    /// nothing moved refreshes nothing.
    #[test]
    fn given_the_time_the_kept_lists_are_a_full_search() {
        let sheet = generate::cloth_grid(1.0, 1.0, 48, 48);
        let mut surface = TrackedSurface::with_patch_size(sheet.clone(), 4);
        let mut kept = KeptCandidates::default();
        let mut saw_overlaps = false;
        for step in (0..=8).chain((3..8).rev()) {
            let angle = std::f32::consts::PI * step as f32 / 8.0;
            surface.set_positions(&folded(&sheet, angle)).unwrap();
            let lists = refresh(&mut kept, &surface, Duration::MAX);
            assert_eq!(lists, full_search(&surface), "step {step}");
            saw_overlaps |= !lists.0.is_empty() && !lists.1.is_empty();
            assert!(kept.refreshed > 0 && kept.block_count() >= 16);
            assert_eq!(
                kept.pair_count(),
                kept.block_count() * (kept.block_count() + 1) / 2
            );
        }
        assert!(
            saw_overlaps,
            "the fold brings far patches together and folds edges"
        );
        let before = full_search(&surface);
        assert_eq!(refresh(&mut kept, &surface, Duration::MAX), before);
        assert_eq!(kept.refreshed, 0, "nothing moved, nothing to refresh");
        // Another surface (another topology) starts over.
        let other = TrackedSurface::with_patch_size(generate::torus(1.0, 0.3, 24, 12), 8);
        assert_eq!(
            refresh(&mut kept, &other, Duration::ZERO),
            full_search(&other)
        );
        assert_eq!(kept.refreshed, kept.pair_count());
    }

    /// Without time, a step refreshes one list only (the most out of date), except on the
    /// first step, which makes every list; the lists come back to a full search's within as
    /// many steps as there are lists once the surface stops, and a motion in one place
    /// refreshes the lists of the block it reached only.
    #[test]
    fn without_time_the_lists_catch_up_a_block_per_step() {
        let sheet = generate::cloth_grid(1.0, 1.0, 48, 48);
        let mut surface = TrackedSurface::with_patch_size(sheet.clone(), 4);
        let mut kept = KeptCandidates::default();
        assert_eq!(
            refresh(&mut kept, &surface, Duration::ZERO),
            full_search(&surface)
        );
        assert_eq!(kept.refreshed, kept.pair_count());
        surface
            .set_positions(&folded(&sheet, std::f32::consts::PI))
            .unwrap();
        let target = full_search(&surface);
        let mut steps = 0;
        loop {
            let lists = refresh(&mut kept, &surface, Duration::ZERO);
            if kept.refreshed == 0 {
                assert_eq!(lists, target);
                break;
            }
            assert_eq!(kept.refreshed, 1);
            steps += 1;
            assert!(steps <= kept.pair_count());
        }
        assert!(steps > 1, "the fold reached more than one block");
        // A motion of one corner vertex: the pairs of its block (one with each block), or of
        // the few blocks sharing it.
        let mut moved = surface.mesh().positions().to_vec();
        moved[0] += Vec3::new(0.0, 0.05, 0.0);
        surface.set_positions(&moved).unwrap();
        refresh(&mut kept, &surface, Duration::MAX);
        assert!(kept.refreshed >= 1 && kept.refreshed <= 4 * kept.block_count());
        assert!(kept.refreshed < kept.pair_count() / 4);
        assert_eq!(
            refresh(&mut kept, &surface, Duration::MAX),
            full_search(&surface)
        );
    }

    /// A larger margin than the lists were made with refreshes them whatever the time.
    #[test]
    fn a_larger_margin_refreshes_every_list() {
        let sheet = generate::cloth_grid(1.0, 1.0, 48, 48);
        let mut surface = TrackedSurface::with_patch_size(sheet.clone(), 4);
        surface
            .set_positions(&folded(&sheet, std::f32::consts::PI))
            .unwrap();
        let mut kept = KeptCandidates::default();
        refresh(&mut kept, &surface, Duration::ZERO);
        let (mut overlaps, mut sharp) = (Vec::new(), Vec::new());
        kept.refresh(&surface, 0.5, Duration::ZERO, &mut overlaps, &mut sharp);
        assert_eq!(kept.refreshed, kept.pair_count());
        let (mut stack, mut wide) = (Vec::new(), Vec::new());
        surface.patches.self_overlaps(0.5, &mut stack, &mut wide);
        wide.sort_unstable();
        overlaps.sort_unstable();
        assert_eq!(overlaps, wide);
    }
}
