//! Where new pairs are drawn from, kept between steps: the overlapping patch pairs and the
//! sharp edges of one surface (self-collision), refreshed where the surface moved, within a
//! time allowance per step.
//!
//! The patch tree is cut into blocks (its subtrees at [`BLOCK_DEPTH`]); each block owns the
//! overlapping patch pairs inside it and between it and half of the other blocks (taken round
//! the circle of blocks, so that every pair of blocks has one owner and every block owns as
//! many), and the sharp edges of its patches. A step refreshes the blocks whose lists are the
//! most out of date first (how much the vertices of their patches, or of the blocks they own
//! pairs with, moved since their lists were made), until its allowance is spent; a surface at
//! rest costs nothing. The lists are only where samples start: a pair drawn from an out-of-date
//! list is measured on the current surface by the local search like any other, so a stale
//! list costs samples, never a wrong contact.

use std::time::{Duration, Instant};

use super::sampling::sharp_edges_of;
use super::surface::TrackedSurface;

/// The tree is cut at this depth: at most 64 blocks. A setting of the amortization (how
/// finely the work of one full search is divided), not fitted to any mesh.
pub(crate) const BLOCK_DEPTH: u32 = 6;

/// A subtree of the patch tree and what it owns.
#[derive(Debug, Clone, Default)]
struct Block {
    /// Root node in the patch tree.
    root: u32,
    /// Its patches.
    patches: Vec<u32>,
    /// The blocks it owns the pairs with (itself excluded).
    partners: Vec<u32>,
    /// Its overlapping patch pairs (`a <= b`) when last refreshed.
    overlaps: Vec<(u32, u32)>,
    /// Its patches' sharp edges when last refreshed (as [`sharp_edges_of`] gives them,
    /// near known contacts or not).
    sharp: Vec<(f32, u32, bool)>,
    /// The margin its pairs were found with; `None`: never refreshed.
    margin: Option<f32>,
    /// The sum of its patches' [travels](super::patch_tree::Patch::travel): it grows by at
    /// least as much as any of its vertices moves.
    odometer: f64,
    /// Its own odometer, then its partners', when it was last refreshed.
    seen: Vec<f64>,
}

/// Candidate patch pairs and sharp edges of one surface, kept between steps (see the module
/// docs).
#[derive(Debug, Clone, Default)]
pub(crate) struct KeptCandidates {
    /// The surface the blocks were made for ([`TrackedSurface::topology_id`]).
    made_for: Option<u64>,
    blocks: Vec<Block>,
    /// Scratch: (how out of date, block) in refresh order.
    order: Vec<(f64, u32)>,
    stack: Vec<(u32, u32)>,
    /// Blocks refreshed by the last [`KeptCandidates::refresh`].
    pub refreshed: usize,
    /// Blocks in all.
    pub block_count: usize,
}

impl KeptCandidates {
    /// Brings the lists up to date where `surface` moved most, blocks in order of how out of
    /// date they are, until `allowance` is spent (blocks never refreshed, or found with a
    /// smaller margin than `margin`, are refreshed whatever the allowance); then writes the
    /// overlapping patch pairs to `overlaps` and the sharp edges to `sharp` (as
    /// [`sharp_edges_of`] gives them with no known contact).
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
        // The odometers: the sum of the blocks' patches' travels.
        for block in &mut self.blocks {
            block.odometer = block
                .patches
                .iter()
                .map(|&p| tree.patches[p as usize].travel)
                .sum();
        }
        // A block's lists are as out of date as the most its own odometer, or that of a block
        // it owns pairs with, grew since they were made (zero: no vertex there moved, the
        // lists are exact); a larger margin than they were found with makes them incomplete.
        self.order.clear();
        for (i, block) in self.blocks.iter().enumerate() {
            let staleness = match block.margin {
                Some(m) if m >= margin => std::iter::once(i as u32)
                    .chain(block.partners.iter().copied())
                    .zip(&block.seen)
                    .map(|(q, &seen)| self.blocks[q as usize].odometer - seen)
                    .fold(0.0, f64::max),
                _ => f64::INFINITY,
            };
            if staleness > 0.0 {
                self.order.push((staleness, i as u32));
            }
        }
        self.order
            .sort_unstable_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        self.refreshed = 0;
        for k in 0..self.order.len() {
            let (staleness, i) = self.order[k];
            if staleness.is_finite() && self.refreshed > 0 && started.elapsed() >= allowance {
                break;
            }
            self.refresh_block(surface, i as usize, margin);
            self.refreshed += 1;
        }
        overlaps.clear();
        sharp.clear();
        for block in &self.blocks {
            overlaps.extend_from_slice(&block.overlaps);
            sharp.extend_from_slice(&block.sharp);
        }
    }

    /// Cuts `surface`'s patch tree into blocks and shares the pairs of blocks among them.
    fn make_blocks(&mut self, surface: &TrackedSurface) {
        let tree = &surface.patches;
        let roots = tree.block_roots(BLOCK_DEPTH);
        let m = roots.len();
        self.blocks = roots
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
        // Block x owns the pairs with the next ⌊(m − 1) / 2⌋ blocks round the circle, and,
        // when m is even, the first half of the blocks also own the pair with the block
        // opposite.
        for x in 0..m {
            let mut partners: Vec<u32> = (1..=(m - 1) / 2).map(|k| ((x + k) % m) as u32).collect();
            if m.is_multiple_of(2) && x < m / 2 {
                partners.push((x + m / 2) as u32);
            }
            self.blocks[x].partners = partners;
        }
        self.block_count = m;
    }

    /// Finds block `i`'s overlapping patch pairs and sharp edges anew.
    fn refresh_block(&mut self, surface: &TrackedSurface, i: usize, margin: f32) {
        let tree = &surface.patches;
        let root = self.blocks[i].root;
        self.stack.clear();
        self.stack.push((root, root));
        let mut seen = std::mem::take(&mut self.blocks[i].seen);
        seen.clear();
        seen.push(self.blocks[i].odometer);
        for &q in &self.blocks[i].partners {
            let other = &self.blocks[q as usize];
            self.stack
                .push((root.min(other.root), root.max(other.root)));
            seen.push(other.odometer);
        }
        let block = &mut self.blocks[i];
        block.seen = seen;
        block.overlaps.clear();
        tree.self_overlaps_from(margin, &mut self.stack, &mut block.overlaps);
        block.sharp.clear();
        sharp_edges_of(
            surface,
            block.patches.iter().copied(),
            &[],
            &mut block.sharp,
        );
        block.margin = Some(margin);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::generate;
    use crate::tracking::sampling::sharp_edges;
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

    /// A 24 × 24 sheet whose right half is turned about the z axis by `angle` (folded over
    /// the left half at π, a little above it).
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

    /// With time for everything, the kept lists are a full search's at every step of a fold,
    /// and a step after which nothing moved refreshes nothing.
    #[test]
    fn given_the_time_the_kept_lists_are_a_full_search() {
        let sheet = generate::cloth_grid(1.0, 1.0, 24, 24);
        let mut surface = TrackedSurface::with_patch_size(sheet.clone(), 8);
        let mut kept = KeptCandidates::default();
        let mut saw_overlaps = false;
        for step in 0..=8 {
            let angle = std::f32::consts::PI * step as f32 / 8.0;
            surface.set_positions(&folded(&sheet, angle)).unwrap();
            let lists = refresh(&mut kept, &surface, Duration::MAX);
            assert_eq!(lists, full_search(&surface), "step {step}");
            saw_overlaps |= !lists.0.is_empty() && !lists.1.is_empty();
            assert!(kept.refreshed > 0 && kept.block_count > 16);
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
        assert_eq!(kept.refreshed, kept.block_count);
    }

    /// Without time, a step refreshes one block only (the most out of date), except on the
    /// first step, which makes every list; the lists come back to a full search's within as
    /// many steps as there are blocks once the surface stops, and only the blocks the motion
    /// reached are refreshed.
    #[test]
    fn without_time_the_lists_catch_up_a_block_per_step() {
        let sheet = generate::cloth_grid(1.0, 1.0, 24, 24);
        let mut surface = TrackedSurface::with_patch_size(sheet.clone(), 8);
        let mut kept = KeptCandidates::default();
        assert_eq!(
            refresh(&mut kept, &surface, Duration::ZERO),
            full_search(&surface)
        );
        assert_eq!(kept.refreshed, kept.block_count);
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
            assert!(steps <= kept.block_count);
        }
        assert!(steps > 1, "the fold reached more than one block");
        // A motion of one corner vertex: the blocks owning pairs with its block, and its own.
        let mut moved = surface.mesh().positions().to_vec();
        moved[0] += Vec3::new(0.0, 0.05, 0.0);
        surface.set_positions(&moved).unwrap();
        refresh(&mut kept, &surface, Duration::MAX);
        assert!(kept.refreshed >= 1 && kept.refreshed <= kept.block_count / 2 + 1);
        assert_eq!(
            refresh(&mut kept, &surface, Duration::MAX),
            full_search(&surface)
        );
    }

    /// A larger margin than the lists were made with refreshes them whatever the time.
    #[test]
    fn a_larger_margin_refreshes_every_list() {
        let sheet = generate::cloth_grid(1.0, 1.0, 24, 24);
        let mut surface = TrackedSurface::with_patch_size(sheet.clone(), 8);
        surface
            .set_positions(&folded(&sheet, std::f32::consts::PI))
            .unwrap();
        let mut kept = KeptCandidates::default();
        refresh(&mut kept, &surface, Duration::ZERO);
        let (mut overlaps, mut sharp) = (Vec::new(), Vec::new());
        kept.refresh(&surface, 0.5, Duration::ZERO, &mut overlaps, &mut sharp);
        assert_eq!(kept.refreshed, kept.block_count);
        let (mut stack, mut wide) = (Vec::new(), Vec::new());
        surface.patches.self_overlaps(0.5, &mut stack, &mut wide);
        wide.sort_unstable();
        overlaps.sort_unstable();
        assert_eq!(overlaps, wide);
    }
}
