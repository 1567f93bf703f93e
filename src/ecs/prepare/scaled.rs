//! Scaled copies of rigid colliders' trees, one per tree and scale, shared by every entity
//! that uses that tree at that scale, and dropped when none does.
use std::collections::HashMap;
use std::sync::{Arc, Weak};

use glam::Vec3;

use crate::adb::AdbTree;
use crate::mesh::MeshError;

/// The scaled trees in use, by the original tree's address and the scale's bits.
#[derive(Debug, Default)]
pub(crate) struct ScaledTrees {
    trees: HashMap<(usize, [u32; 3]), Weak<AdbTree>>,
    /// Inserts since the last sweep of dropped entries.
    inserts: usize,
}

impl ScaledTrees {
    /// `tree` at `scale` (the tree itself at scale 1): the copy in use if there is one, else
    /// a new one, built now with the tree's options.
    ///
    /// # Errors
    /// As [`AdbTree::scaled`].
    pub fn tree(&mut self, tree: &Arc<AdbTree>, scale: Vec3) -> Result<Arc<AdbTree>, MeshError> {
        if scale == Vec3::ONE {
            return Ok(tree.clone());
        }
        let key = (
            Arc::as_ptr(tree) as usize,
            scale.to_array().map(f32::to_bits),
        );
        if let Some(t) = self.trees.get(&key).and_then(Weak::upgrade) {
            return Ok(t);
        }
        let scaled = Arc::new(tree.scaled(scale)?);
        self.inserts += 1;
        if self.inserts > self.trees.len().max(16) {
            // Entries whose trees no entity uses any more (an address may be reused).
            self.trees.retain(|_, t| t.strong_count() > 0);
            self.inserts = 0;
        }
        self.trees.insert(key, Arc::downgrade(&scaled));
        Ok(scaled)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::CollisionMesh;
    use crate::mesh::generate;

    #[test]
    fn one_copy_per_tree_and_scale_while_in_use() {
        let tree = Arc::new(AdbTree::new(CollisionMesh::new(generate::icosphere(
            1.0, 1,
        ))));
        let mut cache = ScaledTrees::default();
        assert!(Arc::ptr_eq(&cache.tree(&tree, Vec3::ONE).unwrap(), &tree));
        let a = cache.tree(&tree, Vec3::splat(2.0)).unwrap();
        let b = cache.tree(&tree, Vec3::splat(2.0)).unwrap();
        assert!(Arc::ptr_eq(&a, &b), "shared");
        let c = cache.tree(&tree, Vec3::new(2.0, 1.0, 1.0)).unwrap();
        assert!(!Arc::ptr_eq(&a, &c), "another scale, another copy");
        let root = a.collision_mesh().bvh().root_aabb();
        assert!((root.max.x - 2.0 * tree.collision_mesh().bvh().root_aabb().max.x).abs() < 1e-5);
        drop((a, b));
        let again = cache.tree(&tree, Vec3::splat(2.0)).unwrap();
        assert_eq!(Arc::strong_count(&again), 1, "rebuilt once nobody held it");
    }
}
