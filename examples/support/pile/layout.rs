//! The pile's layout from its body count and seed: the box's slabs and every body's start
//! (position, rotation, velocity), from the same random draws in the same order wherever it is
//! built. The main crate's pile scene uses it, and `integrations/avian`'s side by side with
//! avian3d includes this file by path, so both engines get the same scene.
use rand::rngs::Xoshiro256PlusPlus;
use rand::{RngExt, SeedableRng};
use stochastic_collision::prelude::{ContactLayers, Quat, TriMesh, Vec3};

/// The box's slabs' layers: members of a layer of their own (the highest bit) that collide
/// with every other layer but that one, so the bodies (all layers, the default) hit the
/// slabs and the slabs never pair with each other.
pub const LEVEL_LAYERS: ContactLayers = ContactLayers::new(1 << 31, !(1 << 31));

/// How a body starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyStart {
    pub position: Vec3,
    pub rotation: Quat,
    pub velocity: Vec3,
}

/// The box and the bodies of a pile.
#[derive(Debug, Clone, PartialEq)]
pub struct PileLayout {
    /// Half the box's inner width (x and z).
    pub half: f32,
    /// The box's slabs: half extents and centre; the floor first, then the four walls.
    pub slabs: Vec<(Vec3, Vec3)>,
    /// The bodies, in spawn order (body `i` is of kind `i % kinds`).
    pub bodies: Vec<BodyStart>,
}

/// The layout of a pile of `n` bodies from `seed`: a box whose floor holds about a quarter of
/// them per layer, layers falling from a little apart so that they land one after the other.
pub fn pile_layout(n: usize, seed: u64) -> PileLayout {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let per_row = ((n as f32 / 4.0).sqrt().ceil() as usize).max(2);
    let spacing = 0.6;
    let layer_gap = 1.2;
    let half = per_row as f32 * spacing * 0.5 + 0.3;
    let height = 1.5;
    let mut slabs = vec![(
        Vec3::new(half + 0.5, 0.5, half + 0.5),
        Vec3::new(0.0, -0.5, 0.0),
    )];
    for (x, z, h) in [
        (half + 0.25, 0.0, Vec3::new(0.25, height, half + 0.5)),
        (-half - 0.25, 0.0, Vec3::new(0.25, height, half + 0.5)),
        (0.0, half + 0.25, Vec3::new(half + 0.5, height, 0.25)),
        (0.0, -half - 0.25, Vec3::new(half + 0.5, height, 0.25)),
    ] {
        slabs.push((h, Vec3::new(x, height, z)));
    }
    let bodies = (0..n)
        .map(|i| {
            let (layer, k) = (i / (per_row * per_row), i % (per_row * per_row));
            let (row, col) = (k / per_row, k % per_row);
            let jitter = Vec3::new(
                rng.random_range(-0.05..0.05),
                0.0,
                rng.random_range(-0.05..0.05),
            );
            let position = Vec3::new(
                (col as f32 + 0.5) * spacing - half + 0.3,
                0.6 + layer as f32 * layer_gap,
                (row as f32 + 0.5) * spacing - half + 0.3,
            ) + jitter;
            let axis = Vec3::new(
                rng.random_range(-1.0..1.0),
                1.0,
                rng.random_range(-1.0..1.0),
            );
            let rotation = Quat::from_axis_angle(
                axis.normalize(),
                rng.random_range(0.0..std::f32::consts::TAU),
            );
            let velocity = Vec3::new(
                rng.random_range(-0.5..0.5),
                0.0,
                rng.random_range(-0.5..0.5),
            );
            BodyStart {
                position,
                rotation,
                velocity,
            }
        })
        .collect();
    PileLayout {
        half,
        slabs,
        bodies,
    }
}

/// `mesh` moved to its box centre and scaled so that its largest extent is `size`.
pub fn normalized(mesh: &TriMesh, size: f32) -> TriMesh {
    let b = mesh.aabb();
    let s = size / b.extents().max_element().max(1e-6);
    mesh.translated(-b.center())
        .and_then(|m| m.scaled(Vec3::splat(s)))
        .expect("moving and scaling keep a valid mesh")
}
