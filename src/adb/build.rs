//! The build of an [`AdbTree`]: the per-node data of [`super::tree`], the interior map, and the
//! fits that the build options ask for ([`AdbBuildOptions`]).
use std::sync::Arc;

use glam::Vec3;

use super::calibration::ConfidenceCalibration;
use super::certificate_confidence::TRAINING_SEED;
use super::estimator::PlanarityEstimator;
use super::fit::FittedEstimator;
use super::interior::InteriorMap;
use super::options::AdbBuildOptions;
use super::tree::{AdbBuildProgress, AdbTree};
use crate::bvh::CollisionMesh;

impl AdbTree {
    /// Builds the tree with default options.
    pub fn new(mesh: CollisionMesh) -> Self {
        Self::build_with(mesh, AdbBuildOptions::default())
    }

    /// Builds the tree with the given options.
    pub fn build_with(mesh: CollisionMesh, options: AdbBuildOptions) -> Self {
        Self::build_with_progress(mesh, options, &|_| {})
    }

    /// Builds the tree, calling `progress` (from the build threads, in increasing
    /// `nodes_done` order per thread) as nodes are counted.
    pub fn build_with_progress(
        mesh: CollisionMesh,
        options: AdbBuildOptions,
        progress: &(dyn Fn(AdbBuildProgress) + Sync),
    ) -> Self {
        let mut tree = Self::with_nodes(mesh, options, progress);
        let mesh = tree.collision_mesh();
        tree.interior = (options.interior_resolution > 0).then(|| {
            let mut map =
                InteriorMap::build(mesh, options.interior_resolution, options.interior_samples);
            if options.certificate_poses > 0 {
                map.measure_certificate(mesh, options.certificate_poses, TRAINING_SEED);
            }
            map
        });
        if let Some(fit) = options.fit {
            let base = Arc::new(PlanarityEstimator::default());
            tree.calibration =
                Some(FittedEstimator::fit(&tree, &tree, base, fit).into_calibration());
            if options.confidence_fit && tree.interior.is_some() {
                tree.confidence_calibration = ConfidenceCalibration::fit(&tree, fit);
            }
        }
        tree
    }

    /// The tree of this mesh scaled by `scale` along its local axes (a negative factor
    /// mirrors it; triangles keep facing outwards), built with the same options.
    ///
    /// # Errors
    /// As [`TriMesh::scaled`](crate::mesh::TriMesh::scaled).
    ///
    /// # Example
    /// ```
    /// use stochastic_collision::adb::AdbTree;
    /// use stochastic_collision::prelude::*;
    /// let ball = AdbTree::new(CollisionMesh::new(generate::icosphere(1.0, 1)));
    /// let big = ball.scaled(Vec3::splat(2.0))?;
    /// assert_eq!(big.collision_mesh().bvh().root_aabb().max.x, 2.0 * ball.collision_mesh().bvh().root_aabb().max.x);
    /// # Ok::<(), MeshError>(())
    /// ```
    pub fn scaled(&self, scale: Vec3) -> Result<AdbTree, crate::mesh::MeshError> {
        let mesh = self.collision_mesh().mesh().scaled(scale)?;
        Ok(Self::build_with(CollisionMesh::new(mesh), *self.options()))
    }
}
