//! The collider table: one stable slot per valid collider, kept from run to run and updated
//! from the ECS's change detection, so a collider that does not change costs nothing.
use std::sync::Arc;

use bevy_ecs::entity::EntityHashMap;
use bevy_ecs::prelude::*;
use glam::{Vec3, Vec3A};
use smallvec::SmallVec;

use super::super::components::{ContinuousCollision, Fidelity};
use super::super::layers::ContactLayers;
use super::super::stamp::{age_stamp, stamp, stamp_sweep_due};
use super::deformed::{DeformedStates, placed};
use crate::adb::AdbTree;
use crate::bvh::CollisionMesh;
use crate::ccd::RigidMotion;
use crate::geometry::{Aabb, Pose};

/// The geometry of a collider: a shared rigid tree or a deformable mesh.
#[derive(Debug, Clone)]
pub enum Geometry {
    /// A rigid collider's shared ADB-tree (and BVH).
    Rigid(Arc<AdbTree>),
    /// A deformable mesh as last refitted.
    Deformable(Arc<CollisionMesh>),
}

impl Geometry {
    /// The mesh and its BVH.
    #[inline]
    pub fn mesh(&self) -> &CollisionMesh {
        match self {
            Geometry::Rigid(t) => t.collision_mesh(),
            Geometry::Deformable(m) => m,
        }
    }

    /// The ADB-tree (rigid colliders only).
    #[inline]
    pub fn adb(&self) -> Option<&AdbTree> {
        match self {
            Geometry::Rigid(t) => Some(t),
            Geometry::Deformable(_) => None,
        }
    }

    /// The geometry's identity: the address of its shared data (a swapped collider is a
    /// change).
    pub(crate) fn id(&self) -> usize {
        match self {
            Geometry::Rigid(t) => Arc::as_ptr(t) as usize,
            Geometry::Deformable(m) => Arc::as_ptr(m) as usize,
        }
    }
}

/// One valid collider as the pipeline sees it.
#[derive(Debug, Clone)]
pub struct ColliderEntry {
    /// The entity.
    pub entity: Entity,
    /// Its geometry.
    pub geometry: Geometry,
    /// Its pose.
    pub pose: Pose,
    /// Its world box (inflated by [`CollisionConfig::aabb_margin`](super::super::CollisionConfig::aabb_margin)).
    pub aabb: Aabb,
    /// Its fidelity.
    pub fidelity: Fidelity,
    /// Its layers.
    pub layers: ContactLayers,
    /// Whether it has the [`SelfCollision`](super::super::SelfCollision) marker and is
    /// deformable.
    pub self_collision: bool,
    /// Translation in the last run it moved in, if that was this run (an estimate of
    /// speed × time step); zero otherwise.
    pub motion: Vec3,
    /// Its pose before its last move: where a swept collider's motion starts (its pose at the
    /// end of the run before, after the responses).
    pub previous_pose: Pose,
    /// Its pose at the end of the last run (after the responses, for a collider with
    /// [`ContinuousCollision`](super::super::ContinuousCollision)).
    pub(crate) end_pose: Pose,
    /// Its [`ContinuousCollision`](super::super::ContinuousCollision), if any.
    pub continuous: Option<ContinuousCollision>,
    /// The last run in which it was swept (its world box covers the motion from
    /// `previous_pose` to `pose`, or a deformable's from its state before to its state now,
    /// and its pairs are tested over that motion).
    pub swept_run: u64,
    /// A deformable collider with continuous collision: its mesh in world coordinates now and
    /// before its last update.
    pub(crate) deformed: Option<DeformedStates>,
    /// The run ([`CollisionDiagnostics::frame`](super::super::CollisionDiagnostics::frame))
    /// since which the entity's pose and geometry are unchanged: an answer computed in that
    /// run or later still holds for a rigid pair.
    pub still_since: u64,
    /// The run since which its geometry is the same (a swapped mesh or collider is new
    /// geometry; a deformable mesh refitted in place is not): what a pair's memory says of
    /// triangles holds only from then on.
    pub geometry_since: u64,
    /// The identity of its geometry ([`Geometry::id`]), kept while the table lets go of a
    /// deformable mesh during its refit.
    pub(crate) geometry_id: usize,
    /// Its pairs' slots in the [`PairTable`](super::super::PairTable).
    pub(crate) pairs: SmallVec<[u32; 12]>,
    /// The last run in which it changed (listed in [`ColliderTable::changed`] once per run).
    pub(crate) changed_run: u64,
    /// The last run in which its layers or self-collision marker changed.
    pub(crate) filter_run: u64,
}

impl ColliderEntry {
    /// Whether the collider is rigid (its answers can be kept while it does not move).
    #[inline]
    pub fn is_rigid(&self) -> bool {
        matches!(self.geometry, Geometry::Rigid(_))
    }

    /// Whether its pairs are tested over its motion in `run` (a rigid collider's from its
    /// previous pose, a deformable one's from its state before its last update).
    #[inline]
    pub fn is_swept(&self, run: u64) -> bool {
        self.swept_run == run
            && (self.is_rigid() || self.deformed.as_ref().is_some_and(|d| d.before.is_some()))
    }

    /// Its motion in `run`: from its previous pose if it moved in this run, else still.
    pub fn motion_in(&self, run: u64) -> RigidMotion {
        if self.still_since == run && self.previous_pose != self.pose {
            RigidMotion::new(self.previous_pose, self.pose)
        } else {
            RigidMotion::still(self.pose)
        }
    }

    /// Its pairs' slots in the pair table.
    pub(crate) fn pair_slots(&self) -> &[u32] {
        &self.pairs
    }

    /// A rigid exact icosphere of radius 1 (`subdivisions`) at `x` on the x axis, entity
    /// `index`, unchanged since `since`.
    #[cfg(test)]
    pub(crate) fn sphere_for_tests(index: u32, subdivisions: u32, x: f32, since: u64) -> Self {
        let mesh = CollisionMesh::new(crate::mesh::generate::icosphere(1.0, subdivisions));
        let geometry = Geometry::Rigid(Arc::new(AdbTree::new(mesh)));
        let pose = Pose::new(Vec3::new(x, 0.0, 0.0), glam::Quat::IDENTITY);
        Self {
            entity: Entity::from_raw_u32(index).expect("a valid index"),
            aabb: super::world_aabb(&geometry.mesh().bvh().root_aabb(), &pose),
            geometry_id: geometry.id(),
            geometry,
            pose,
            fidelity: Fidelity::Exact,
            layers: Default::default(),
            self_collision: false,
            motion: Vec3::ZERO,
            previous_pose: pose,
            end_pose: pose,
            continuous: None,
            swept_run: 0,
            deformed: None,
            still_since: since,
            geometry_since: since,
            pairs: Default::default(),
            changed_run: 0,
            filter_run: 0,
        }
    }
}

/// A collider's world box in SIMD lanes and the last run it changed in (as a stamp: the run's
/// number modulo 2³²): what every run reads of it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BoxStamp {
    min: Vec3A,
    max: Vec3A,
    pub stamp: u32,
}

impl BoxStamp {
    fn new(aabb: &Aabb, stamp: u32) -> Self {
        Self {
            min: aabb.min.into(),
            max: aabb.max.into(),
            stamp,
        }
    }

    /// Whether the two boxes overlap (touching counts), as [`Aabb::intersects`].
    #[inline]
    pub fn intersects(&self, o: &BoxStamp) -> bool {
        (self.min.cmple(o.max) & o.min.cmple(self.max)).all()
    }
}

/// What planning a pair reads of a collider.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BodyPlan {
    pub aabb: Aabb,
    pub motion: Vec3,
    pub fidelity: Fidelity,
    pub still_since: u64,
    pub rigid: bool,
    /// The run in which its world box last covered its motion ([`ColliderEntry::is_swept`]).
    pub swept_run: u64,
}

impl BodyPlan {
    fn of(e: &ColliderEntry) -> Self {
        Self {
            aabb: e.aabb,
            motion: e.motion,
            fidelity: e.fidelity,
            still_since: e.still_since,
            rigid: e.is_rigid(),
            swept_run: e.swept_run,
        }
    }
}

/// Every valid collider, one stable slot each, kept from run to run (read-only for users:
/// what the stages see).
///
/// The Prepare stage updates only the entities whose pose, collider, fidelity, layers or
/// markers changed (Bevy's change detection), and those removed or despawned; a collider at
/// rest costs nothing per run.
#[derive(Resource, Debug, Default)]
pub struct ColliderTable {
    slots: Vec<Option<ColliderEntry>>,
    /// Per slot, what every run reads of the collider, and what planning a pair reads.
    boxes: Vec<BoxStamp>,
    plans: Vec<BodyPlan>,
    free: Vec<u32>,
    index: EntityHashMap<u32>,
    /// Slots whose collider changed in this run (each once).
    changed: Vec<u32>,
    /// Colliders removed in this run, with their slots: the broad phase drops their proxies
    /// and pairs, then frees the slots.
    pub(crate) removed: Vec<(u32, ColliderEntry)>,
    /// Slots whose collider moved in the last run (their motion is reset when they rest).
    moved: Vec<u32>,
}

impl ColliderTable {
    /// The entry of `entity`, if it is a valid collider.
    pub fn get(&self, entity: Entity) -> Option<&ColliderEntry> {
        self.index.get(&entity).map(|&i| self.entry(i))
    }

    /// Every valid collider, in slot order (stable from run to run).
    pub fn iter(&self) -> impl Iterator<Item = &ColliderEntry> {
        self.slots.iter().flatten()
    }

    /// Number of valid colliders.
    pub fn len(&self) -> usize {
        self.index.len()
    }

    /// Whether there is no valid collider.
    pub fn is_empty(&self) -> bool {
        self.index.is_empty()
    }

    /// The slot of `entity`.
    pub(crate) fn slot_of(&self, entity: Entity) -> Option<u32> {
        self.index.get(&entity).copied()
    }

    /// The collider in slot `i`, which must be live (pairs only refer to live colliders).
    #[inline]
    pub(crate) fn entry(&self, i: u32) -> &ColliderEntry {
        self.slots[i as usize]
            .as_ref()
            .expect("pairs and lists refer to live collider slots only")
    }

    /// Whether slot `i` holds a collider.
    #[inline]
    pub(crate) fn is_live(&self, i: u32) -> bool {
        self.slots.get(i as usize).is_some_and(Option::is_some)
    }

    /// The collider in slot `i`, to write.
    #[inline]
    pub(crate) fn entry_mut(&mut self, i: u32) -> &mut ColliderEntry {
        self.slots[i as usize]
            .as_mut()
            .expect("pairs and lists refer to live collider slots only")
    }

    /// Slots whose collider changed in this run.
    pub(crate) fn changed(&self) -> &[u32] {
        &self.changed
    }

    /// Starts run `run`: ages the change stamps when due, forgets the last run's changes; the colliders that moved in the last
    /// run and not (yet) in this one get zero motion.
    pub(crate) fn begin_run(&mut self, run: u64) {
        if stamp_sweep_due(run) {
            for b in &mut self.boxes {
                age_stamp(&mut b.stamp, stamp(run));
            }
        }
        self.changed.clear();
        for i in std::mem::take(&mut self.moved) {
            if let Some(e) = self.slots[i as usize].as_mut() {
                e.motion = Vec3::ZERO;
                self.plans[i as usize].motion = Vec3::ZERO;
            }
        }
    }

    /// What planning reads, by slot.
    #[inline]
    pub(crate) fn plans(&self) -> &[BodyPlan] {
        &self.plans
    }

    /// The world boxes and change stamps, by slot.
    #[inline]
    pub(crate) fn boxes(&self) -> &[BoxStamp] {
        &self.boxes
    }

    /// Marks slot `i` as changed in `run` (listed once); `moved`: its pose or geometry changed.
    /// Its world box is read again.
    pub(crate) fn mark_changed(&mut self, i: u32, run: u64, moved: bool) {
        self.boxes[i as usize] = BoxStamp::new(&self.entry(i).aabb, stamp(run));
        self.plans[i as usize] = BodyPlan::of(self.entry(i));
        let e = self.entry_mut(i);
        let first = e.changed_run != run;
        e.changed_run = run;
        if first {
            self.changed.push(i);
        }
        if moved {
            self.moved.push(i);
        }
    }

    /// Adds a new collider; returns its slot.
    pub(crate) fn insert(&mut self, entry: ColliderEntry) -> u32 {
        let entity = entry.entity;
        let (aabb, plan) = (entry.aabb, BodyPlan::of(&entry));
        let i = match self.free.pop() {
            Some(i) => {
                self.slots[i as usize] = Some(entry);
                self.boxes[i as usize] = BoxStamp::new(&aabb, u32::MAX);
                self.plans[i as usize] = plan;
                i
            }
            None => {
                self.slots.push(Some(entry));
                self.boxes.push(BoxStamp::new(&aabb, u32::MAX));
                self.plans.push(plan);
                (self.slots.len() - 1) as u32
            }
        };
        self.index.insert(entity, i);
        i
    }

    /// Removes `entity`'s collider, if any: it leaves the table now, its slot after the broad
    /// phase has dropped its proxy and pairs.
    pub(crate) fn remove(&mut self, entity: Entity) {
        if let Some(i) = self.index.remove(&entity)
            && let Some(entry) = self.slots[i as usize].take()
        {
            self.removed.push((i, entry));
        }
    }

    /// Frees the slot of a removed collider (its proxy and pairs are gone).
    pub(crate) fn free_slot(&mut self, i: u32) {
        self.free.push(i);
    }
}

impl ColliderEntry {
    /// Its mesh in world coordinates at the start and at the end of its motion in `run`: a
    /// swept deformable's states before and now; a rigid collider at its previous pose and
    /// its pose when it moved in the run (else at its pose, both); another deformable where it
    /// is now.
    pub(crate) fn world_states(&self, run: u64) -> (Arc<CollisionMesh>, Arc<CollisionMesh>) {
        if let Some(d) = &self.deformed
            && self.swept_run == run
            && let Some(before) = &d.before
        {
            return (before.clone(), d.now.clone());
        }
        let mesh = self.geometry.mesh();
        let end = Arc::new(placed(mesh, &self.pose));
        let motion = self.motion_in(run);
        let start = match &self.geometry {
            Geometry::Rigid(_) if motion.start != motion.end => {
                Arc::new(placed(mesh, &motion.start))
            }
            _ => end.clone(),
        };
        (start, end)
    }
}
