//! The exact self-collision pass (the tracker's ground truth and fallback) side by side with
//! parry3d doing the same job its own way, on the same whirled meshes, single-threaded.
//!
//! Every frame, each side refits its tree to the frame's positions and reports every pair of
//! triangles more than two vertex rings apart (the tracker's default exclusion) whose distance is
//! at most the thickness (`TrackerConfig::for_surface`'s, a tenth of the mean edge length):
//! - **ours**: `CollisionMesh::set_positions` (refit) and `self_contacts_excluding` (neighbours
//!   excluded before any test, separation filters before the exact distance);
//! - **parry3d**: its `Bvh` over the triangles' boxes loosened by the thickness, refit as
//!   `TriMesh::set_vertices` does (`insert_or_update_partially` per triangle, then
//!   `refit_without_opt`), `traverse_bvtt_single_tree`, the same two-ring exclusion on each
//!   leaf pair, then the GJK distance of the two triangles (f32).
//!
//! `cargo bench --bench self_pass_vs_parry` prints the median frame of each side, their ratio,
//! and how many pairs each gets wrong against a reference that shares neither side's filters:
//! every leaf pair of parry's tree (boxes loosened by the thickness), the same exclusion, then
//! the f64 closest-points distance of the two triangles (`geometry::closest_points_triangle_triangle`)
//! against the thickness. Ours must differ by 0; parry's f32 GJK differs at small scales.
//! `docs/tracking.md` quotes the table (`docs/tracking/self_pass/output.txt`). Pass
//! `-- --quick` for the first 24 frames only.
use std::collections::BTreeSet;
use std::time::Instant;

use glam::Vec3;
use parry3d::bounding_volume::{Aabb as ParryAabb, BoundingVolume};
use parry3d::math::Pose as ParryPose;
use parry3d::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};
use parry3d::query::details::distance_support_map_support_map;
use parry3d::shape::Triangle;
use stochastic_collision::bvh::{
    CollisionMesh, QueryWorkspace, SelfContact, self_contacts_excluding,
};
use stochastic_collision::deform::Whirl;
use stochastic_collision::geometry::closest_points_triangle_triangle;
use stochastic_collision::mesh::{SelfExclusion, TriMesh, generate};
use stochastic_collision::tracking::{TrackedSurface, TrackerConfig};

mod support;

fn meshes() -> Vec<(String, TriMesh)> {
    let mut out = vec![(
        "tube_7k".to_string(),
        generate::tube(0.08, 2.0, 24, 160, true),
    )];
    for file in [
        "plane_50x50.obj",
        "large-intestine-sf+-hf-.obj",
        "small_intestine_100k.obj",
    ] {
        if let Some(mesh) = support::shared_mesh(file) {
            out.push((file.trim_end_matches(".obj").to_string(), mesh));
        }
    }
    out
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

type PairSet = BTreeSet<(u32, u32)>;

fn pair_set(contacts: &[SelfContact]) -> PairSet {
    contacts.iter().map(|c| (c.pair.a, c.pair.b)).collect()
}

/// parry3d's self pass: its own tree, refit and traversal, the same exclusion, GJK distance.
struct ParryPass {
    bvh: Bvh,
    workspace: BvhWorkspace,
    triangles: Vec<[u32; 3]>,
    thickness: f32,
}

impl ParryPass {
    fn new(mesh: &TriMesh, thickness: f32) -> Self {
        let triangles = mesh.triangles().to_vec();
        let boxes: Vec<ParryAabb> = (0..triangles.len())
            .map(|t| Self::leaf_box(mesh.positions(), triangles[t], thickness))
            .collect();
        ParryPass {
            bvh: Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes),
            workspace: BvhWorkspace::default(),
            triangles,
            thickness,
        }
    }

    fn leaf_box(pos: &[Vec3], t: [u32; 3], thickness: f32) -> ParryAabb {
        Triangle::new(pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize])
            .local_aabb()
            .loosened(thickness)
    }

    fn frame(&mut self, pos: &[Vec3], exclusion: &SelfExclusion, out: &mut PairSet) {
        for (i, &t) in self.triangles.iter().enumerate() {
            let aabb = Self::leaf_box(pos, t, self.thickness);
            self.bvh.insert_or_update_partially(aabb, i as u32, 0.0);
        }
        self.bvh.refit_without_opt();
        let (tris, h) = (&self.triangles, self.thickness);
        self.bvh
            .traverse_bvtt_single_tree::<false>(&mut self.workspace, &mut |a, b| {
                if exclusion.excludes(a, b) {
                    return;
                }
                let (ta, tb) = (tris[a as usize], tris[b as usize]);
                let tri = |t: [u32; 3]| {
                    Triangle::new(pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize])
                };
                let d = distance_support_map_support_map(&ParryPose::IDENTITY, &tri(ta), &tri(tb));
                if d <= h {
                    out.insert((a.min(b), a.max(b)));
                }
            });
    }
}

impl ParryPass {
    /// The reference: parry's candidates (its tree as refit by the last `frame`), the
    /// exclusion, the f64 distance.
    fn reference(&mut self, pos: &[Vec3], exclusion: &SelfExclusion, out: &mut PairSet) {
        let (tris, h) = (&self.triangles, self.thickness as f64);
        self.bvh
            .traverse_bvtt_single_tree::<false>(&mut self.workspace, &mut |a, b| {
                if exclusion.excludes(a, b) {
                    return;
                }
                let tri = |t: [u32; 3]| t.map(|v| pos[v as usize].as_dvec3());
                let (ta, tb) = (tri(tris[a as usize]), tri(tris[b as usize]));
                if closest_points_triangle_triangle(&ta, &tb).distance <= h {
                    out.insert((a.min(b), a.max(b)));
                }
            });
    }
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let frames = if quick { 24 } else { 120 };
    println!(
        "exact self pass, {frames} whirled frames (seed 1), the tracker's default thickness \
         (0.1 x mean edge) and exclusion rings, 1 thread, median frame"
    );
    println!(
        "{:<26} {:>7} {:>8} {:>10} {:>10} {:>11} {:>10} {:>12}",
        "mesh", "tris", "pairs", "ours ms", "parry ms", "ours/parry", "ours diff", "parry diff"
    );
    for (name, mesh) in meshes() {
        // The tracker's defaults for this mesh: what its exact fallback is run with.
        let config = TrackerConfig::for_surface(&TrackedSurface::new(mesh.clone()));
        let thickness = config.thickness;
        let whirl = Whirl::new(&mesh, frames, 1);
        let exclusion = SelfExclusion::new(&mesh, config.exclusion_rings);
        let mut ours_mesh = CollisionMesh::new(mesh.clone());
        let mut parry = ParryPass::new(&mesh, thickness);
        let mut ws = QueryWorkspace::new();
        let mut positions = Vec::new();
        let (mut ours_t, mut parry_t) = (Vec::new(), Vec::new());
        let mut out = Vec::new();
        let mut truth = PairSet::new();
        let (mut ours_diff, mut parry_diff, mut pairs) = (0usize, 0usize, 0usize);
        let mut parry_pairs = PairSet::new();
        for f in 0..frames {
            whirl.positions(f, &mut positions);

            let t0 = Instant::now();
            ours_mesh
                .set_positions(&positions)
                .expect("finite positions");
            out.clear();
            self_contacts_excluding(&ours_mesh, thickness, &exclusion, &mut ws, &mut out)
                .expect("the exclusion was built for this mesh");
            ours_t.push(t0.elapsed().as_secs_f64() * 1e3);

            let t0 = Instant::now();
            parry_pairs.clear();
            parry.frame(&positions, &exclusion, &mut parry_pairs);
            parry_t.push(t0.elapsed().as_secs_f64() * 1e3);

            truth.clear();
            parry.reference(&positions, &exclusion, &mut truth);
            let ours_set = pair_set(&out);
            ours_diff += ours_set.symmetric_difference(&truth).count();
            parry_diff += parry_pairs.symmetric_difference(&truth).count();
            pairs += truth.len();
        }
        let (o, q) = (median(&mut ours_t), median(&mut parry_t));
        println!(
            "{:<26} {:>7} {:>8} {:>10.3} {:>10.3} {:>10.2}x {:>10} {:>12}",
            name,
            mesh.triangle_count(),
            pairs,
            o,
            q,
            o / q,
            ours_diff,
            parry_diff
        );
    }
    println!(
        "pairs: summed over all frames; diff: pairs in one set and not the other, against the \
         reference (parry's candidates, the exclusion, f64 closest points)"
    );
}
