//! Colliders from bevy_mesh's `Mesh` (the `bevy_mesh` feature): conversions of lists and
//! strips, indexed or not, against hand-built meshes; every error; and, in a game
//! (`TimePlugin`, `TransformPlugin`, bevy_asset's `AssetPlugin`, the default
//! `FixedPostUpdate` schedule), `Mesh3d` constructors: an asset added later, one build for
//! fifty entities, a glTF-like hierarchy, a bad mesh among good ones, modified and removed
//! assets, deformables and a large mesh built off the frame.
#![cfg(feature = "bevy_mesh")]
mod plugin_support;

use std::sync::Arc;
use std::time::Duration;

use bevy_app::prelude::*;
use bevy_asset::{AssetApp, AssetPlugin, Assets, Handle, RenderAssetUsages};
use bevy_ecs::name::Name;
use bevy_ecs::prelude::*;
use bevy_mesh::{Indices, Mesh, Mesh3d, Meshable, PrimitiveTopology, VertexFormat};
use bevy_shape::{Cuboid, Sphere};
use bevy_time::{TimePlugin, TimeUpdateStrategy};
use bevy_transform::TransformPlugin;
use bevy_transform::components::Transform;
use plugin_support::*;
use stochastic_collision::ecs::{CollisionErrorKind, MeshColliderCache};
use stochastic_collision::mesh::MeshError;
use stochastic_collision::prelude::*;

// ---------------------------------------------------------------------------------------
// Meshes

/// A zig-zag strip of `quads` unit quads in the xz plane starting at `x0`: vertex 2k at
/// (x0 + k, 0, 0), vertex 2k + 1 at (x0 + k, 0, 1).
fn strip_positions(x0: f32, quads: usize) -> Vec<[f32; 3]> {
    (0..=quads)
        .flat_map(|k| [[x0 + k as f32, 0.0, 0.0], [x0 + k as f32, 0.0, 1.0]])
        .collect()
}

/// The strip's triangles as a GPU draws them (odd triangles' last two corners swapped):
/// every normal is +y.
fn strip_triangles(first: u32, quads: u32) -> Vec<[u32; 3]> {
    (0..2 * quads)
        .map(|i| {
            let v = first + i;
            if i % 2 == 0 {
                [v, v + 1, v + 2]
            } else {
                [v, v + 2, v + 1]
            }
        })
        .collect()
}

fn hand_built(quads: usize) -> TriMesh {
    let positions = strip_positions(0.0, quads)
        .into_iter()
        .map(Vec3::from_array)
        .collect();
    TriMesh::new(positions, strip_triangles(0, quads as u32)).unwrap()
}

fn mesh(topology: PrimitiveTopology, positions: Vec<[f32; 3]>, indices: Option<Indices>) -> Mesh {
    let mesh = Mesh::new(topology, RenderAssetUsages::default())
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions);
    match indices {
        Some(i) => mesh.with_inserted_indices(i),
        None => mesh,
    }
}

fn flat(triangles: &[[u32; 3]]) -> Vec<u32> {
    triangles.iter().flatten().copied().collect()
}

fn u16s(i: &[u32]) -> Indices {
    Indices::U16(i.iter().map(|&i| i as u16).collect())
}

/// The same three quads written in every supported way.
fn three_quads_every_way() -> Vec<(&'static str, Mesh)> {
    let positions = strip_positions(0.0, 3);
    let list = flat(&strip_triangles(0, 3));
    let expanded: Vec<[f32; 3]> = list.iter().map(|&i| positions[i as usize]).collect();
    let strip: Vec<u32> = (0..positions.len() as u32).collect();
    use PrimitiveTopology::{TriangleList, TriangleStrip};
    vec![
        (
            "list u16",
            mesh(TriangleList, positions.clone(), Some(u16s(&list))),
        ),
        (
            "list u32",
            mesh(TriangleList, positions.clone(), Some(Indices::U32(list))),
        ),
        ("list without indices", mesh(TriangleList, expanded, None)),
        (
            "strip u16",
            mesh(TriangleStrip, positions.clone(), Some(u16s(&strip))),
        ),
        (
            "strip u32",
            mesh(TriangleStrip, positions.clone(), Some(Indices::U32(strip))),
        ),
        (
            "strip without indices",
            mesh(TriangleStrip, positions, None),
        ),
    ]
}

fn normal([a, b, c]: [Vec3; 3]) -> Vec3 {
    (b - a).cross(c - a).normalize()
}

fn cube(half: f32) -> Mesh {
    Cuboid::from_length(2.0 * half).mesh().into()
}

fn lines() -> Mesh {
    mesh(
        PrimitiveTopology::LineList,
        vec![[0.0; 3], [1.0, 0.0, 0.0]],
        None,
    )
}

// ---------------------------------------------------------------------------------------
// Conversion

#[test]
fn lists_and_strips_indexed_or_not_match_the_hand_built_mesh() {
    let expected = hand_built(3);
    for (what, mesh) in three_quads_every_way() {
        let got = stochastic_collision::ecs::trimesh_from_bevy_mesh(&mesh).unwrap();
        assert_eq!(got.triangle_count(), expected.triangle_count(), "{what}");
        for t in 0..expected.triangle_count() {
            assert_eq!(
                got.triangle(t),
                expected.triangle(t),
                "{what}: triangle {t}"
            );
            assert_eq!(
                normal(got.triangle(t)),
                Vec3::Y,
                "{what}: triangle {t} faces +y"
            );
        }
        if !what.contains("without") {
            assert_eq!(got, expected, "{what}: same vertices and indices");
        }
    }
}

#[test]
fn strips_drop_degenerate_joins_and_restart_at_the_restart_index() {
    // Two strips of two quads (vertices 0..6 at x 0..2, vertices 6..12 at x 5..7), joined by
    // repeating an index at each end (the degenerate triangles a GPU skips), or by the
    // primitive-restart index.
    let mut positions = strip_positions(0.0, 2);
    positions.extend(strip_positions(5.0, 2));
    let mut expected = strip_triangles(0, 2);
    expected.extend(strip_triangles(6, 2));
    let joined: Vec<u32> = [0, 1, 2, 3, 4, 5, 5, 6, 6, 7, 8, 9, 10, 11].to_vec();
    let mut restart16: Vec<u32> = (0..6).collect();
    restart16.push(u16::MAX as u32);
    restart16.extend(6..12);
    let mut restart32: Vec<u32> = (0..6).collect();
    restart32.push(u32::MAX);
    restart32.extend(6..12);
    let strip = PrimitiveTopology::TriangleStrip;
    let cases = [
        (
            "joined u16",
            mesh(strip, positions.clone(), Some(u16s(&joined))),
        ),
        (
            "joined u32",
            mesh(strip, positions.clone(), Some(Indices::U32(joined))),
        ),
        (
            "restart u16",
            mesh(strip, positions.clone(), Some(u16s(&restart16))),
        ),
        (
            "restart u32",
            mesh(strip, positions.clone(), Some(Indices::U32(restart32))),
        ),
    ];
    for (what, mesh) in cases {
        let got = stochastic_collision::ecs::trimesh_from_bevy_mesh(&mesh).unwrap();
        assert_eq!(got.triangles(), expected.as_slice(), "{what}");
        for t in 0..got.triangle_count() {
            assert_eq!(normal(got.triangle(t)), Vec3::Y, "{what}: triangle {t}");
        }
    }
}

#[test]
fn bevy_primitives_convert_vertex_for_vertex() {
    let sphere = Sphere::new(1.0).mesh().ico(2).unwrap();
    let collider = MeshCollider::from_bevy_mesh(&sphere).unwrap();
    let got = collider.collision_mesh().mesh();
    let Some(bevy_mesh::VertexAttributeValues::Float32x3(positions)) =
        sphere.attribute(Mesh::ATTRIBUTE_POSITION)
    else {
        panic!("bevy's sphere has Float32x3 positions");
    };
    assert_eq!(got.vertex_count(), positions.len());
    assert!(
        got.positions()
            .iter()
            .zip(positions)
            .all(|(a, b)| a.to_array() == *b)
    );
    let indices: Vec<usize> = sphere.indices().unwrap().iter().collect();
    assert_eq!(got.triangle_count() * 3, indices.len());
    // A closed sphere: every edge shared by exactly two triangles, and outward-facing.
    let topology = Topology::new(got);
    assert!(topology.is_closed(), "the icosphere is closed");
    for t in 0..got.triangle_count() {
        let tri = got.triangle(t);
        let centre = (tri[0] + tri[1] + tri[2]) / 3.0;
        assert!(normal(tri).dot(centre) > 0.0, "triangle {t} faces outwards");
    }
    let deformable = Deformable::from_bevy_mesh(&sphere).unwrap();
    assert_eq!(deformable.positions(), got.positions());
}

#[test]
fn each_bad_mesh_is_a_named_error() {
    use BevyMeshError as E;
    use PrimitiveTopology::*;
    let tri = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let convert = |m: &Mesh| stochastic_collision::ecs::trimesh_from_bevy_mesh(m).err();
    for topology in [PointList, LineList, LineStrip] {
        assert_eq!(
            convert(&mesh(topology, tri.clone(), None)),
            Some(E::UnsupportedTopology(topology))
        );
    }
    assert_eq!(
        convert(&Mesh::new(TriangleList, RenderAssetUsages::default())),
        Some(E::MissingPositions)
    );
    // `Mesh` checks the format of its own position attribute; an attribute of the same id
    // and another format gets past it.
    let position_2d =
        bevy_mesh::MeshVertexAttribute::new("Vertex_Position", 0, VertexFormat::Float32x2);
    let flat = Mesh::new(TriangleList, RenderAssetUsages::default())
        .with_inserted_attribute(position_2d, vec![[0.0f32; 2]; 3]);
    assert_eq!(
        convert(&flat),
        Some(E::PositionFormat {
            format: VertexFormat::Float32x2
        })
    );
    for indices in [Indices::U16(vec![0, 1, 3]), Indices::U32(vec![0, 1, 3])] {
        assert_eq!(
            convert(&mesh(TriangleList, tri.clone(), Some(indices))),
            Some(E::IndexOutOfRange {
                position: 2,
                index: 3,
                vertices: 3
            })
        );
    }
    // The restart index is an index like any other in a list.
    assert_eq!(
        convert(&mesh(
            TriangleList,
            tri.clone(),
            Some(Indices::U16(vec![0, 1, u16::MAX]))
        )),
        Some(E::IndexOutOfRange {
            position: 2,
            index: u16::MAX as u32,
            vertices: 3
        })
    );
    assert_eq!(
        convert(&mesh(
            TriangleList,
            tri.clone(),
            Some(Indices::U16(vec![0, 1, 2, 0]))
        )),
        Some(E::PartialTriangle {
            count: 4,
            indexed: true
        })
    );
    let mut four = tri.clone();
    four.push([1.0; 3]);
    assert_eq!(
        convert(&mesh(TriangleList, four, None)),
        Some(E::PartialTriangle {
            count: 4,
            indexed: false
        })
    );
    let mut nan = tri.clone();
    nan[1][2] = f32::NAN;
    assert!(matches!(
        convert(&mesh(TriangleList, nan, None)),
        Some(E::Mesh(MeshError::NonFinite { vertex: 1, .. }))
    ));
    assert_eq!(
        convert(&mesh(TriangleStrip, tri[..2].to_vec(), None)),
        Some(E::Mesh(MeshError::Empty {
            vertices: 2,
            triangles: 0
        }))
    );
    // Only degenerate strip triangles: nothing left.
    assert_eq!(
        convert(&mesh(
            TriangleStrip,
            tri.clone(),
            Some(Indices::U16(vec![0, 1, 1, 2]))
        )),
        Some(E::Mesh(MeshError::Empty {
            vertices: 3,
            triangles: 0
        }))
    );
    let mut extracted = mesh(TriangleList, tri, None);
    extracted.take_gpu_data().unwrap();
    assert_eq!(convert(&extracted), Some(E::ExtractedToRenderWorld));
    assert!(
        E::UnsupportedTopology(LineList)
            .to_string()
            .contains("LineList")
    );
}

// ---------------------------------------------------------------------------------------
// In a game

/// A game with assets: time, transforms, bevy_asset with `Mesh`, the plugin in its default
/// schedule, one fixed step per update.
fn game() -> App {
    let mut app = App::new();
    app.add_plugins((
        TimePlugin,
        TransformPlugin,
        AssetPlugin::default(),
        StochasticCollisionPlugin::default().with_config(CollisionConfig {
            budget: FrameBudget::Unlimited,
            ..Default::default()
        }),
    ))
    .init_asset::<Mesh>()
    .insert_resource(TimeUpdateStrategy::FixedTimesteps(1))
    .init_resource::<EventLog>()
    .add_systems(Last, log_events);
    app
}

/// Updates until `done` (a build runs on other threads), at most a few seconds.
fn update_until(app: &mut App, what: &str, done: impl Fn(&World) -> bool) {
    for _ in 0..5000 {
        if done(app.world()) {
            return;
        }
        app.update();
        std::thread::sleep(Duration::from_millis(1));
    }
    panic!("{what}: not done after 5000 updates");
}

fn add(app: &mut App, mesh: Mesh) -> Handle<Mesh> {
    app.world_mut().resource_mut::<Assets<Mesh>>().add(mesh)
}

fn has_collider(world: &World, e: Entity) -> bool {
    world.get::<MeshCollider>(e).is_some() || world.get::<Deformable>(e).is_some()
}

fn touching(app: &App, e: Entity) -> Vec<Entity> {
    let mut v: Vec<Entity> = app
        .world()
        .get::<TouchingEntities>(e)
        .map(|t| t.entities().to_vec())
        .unwrap_or_default();
    v.sort();
    v
}

fn cache(app: &App) -> &MeshColliderCache {
    app.world().resource::<MeshColliderCache>()
}

#[test]
fn converted_meshes_collide_like_the_hand_built_one() {
    let mut app = game();
    let small = ball(0.4);
    let mut colliders = vec![("hand-built", MeshCollider::new(hand_built(3)))];
    for (what, mesh) in three_quads_every_way() {
        colliders.push((what, MeshCollider::from_bevy_mesh(&mesh).unwrap()));
    }
    let mut cases = Vec::new();
    for (k, (what, collider)) in colliders.into_iter().enumerate() {
        let base = Vec3::new(0.0, 0.0, 20.0 * k as f32);
        // 0.3 above the strip (touching), and 0.6 above another copy (apart).
        let near = Transform::from_translation(base + Vec3::new(1.5, 0.3, 0.5));
        let far = Transform::from_translation(base + Vec3::new(11.5, 0.6, 0.5));
        let a = spawn(
            &mut app,
            (collider.clone(), Transform::from_translation(base)),
        );
        let b = spawn(&mut app, (small.clone(), near));
        let c = spawn(
            &mut app,
            (collider, Transform::from_translation(base + 10.0 * Vec3::X)),
        );
        let d = spawn(&mut app, (small.clone(), far));
        cases.push((what, a, b, c, d));
    }
    for _ in 0..3 {
        app.update();
    }
    for (what, a, b, c, d) in cases {
        assert_eq!(touching(&app, a), vec![b], "{what}: touching its neighbour");
        assert!(
            touching(&app, c).is_empty(),
            "{what}: clear of the far ball"
        );
        assert!(touching(&app, d).is_empty(), "{what}");
    }
}

#[test]
fn a_mesh_added_later_gets_its_collider_and_collides() {
    let mut app = game();
    let handle = app.world().resource::<Assets<Mesh>>().reserve_handle();
    let e = spawn(
        &mut app,
        (
            Mesh3d(handle.clone()),
            MeshColliderConstructor::Rigid,
            Transform::from_xyz(0.0, 0.0, 0.0),
        ),
    );
    let neighbour = spawn(&mut app, (ball(1.0), Transform::from_xyz(1.8, 0.0, 0.0)));
    for _ in 0..5 {
        app.update();
    }
    assert!(!has_collider(app.world(), e), "no asset yet: no collider");
    assert!(touching(&app, neighbour).is_empty());
    assert_eq!(cache(&app).builds(), 0);
    app.world_mut()
        .resource_mut::<Assets<Mesh>>()
        .insert(handle.id(), Sphere::new(1.0).mesh().ico(2).unwrap())
        .unwrap();
    update_until(&mut app, "collider", |w| has_collider(w, e));
    assert!(app.world().get::<MeshColliderConstructor>(e).is_none());
    app.update();
    assert_eq!(touching(&app, e), vec![neighbour]);
    assert_eq!(cache(&app).builds(), 1);
}

#[test]
fn fifty_entities_sharing_one_mesh_build_it_once() {
    let mut app = game();
    let handle = add(&mut app, Sphere::new(0.5).mesh().ico(2).unwrap());
    let entities: Vec<Entity> = (0..50)
        .map(|k| {
            spawn(
                &mut app,
                (
                    Mesh3d(handle.clone()),
                    MeshColliderConstructor::Rigid,
                    // A row of balls 0.9 apart: each touches its neighbours.
                    Transform::from_xyz(0.9 * k as f32, 0.0, 0.0),
                ),
            )
        })
        .collect();
    update_until(&mut app, "fifty colliders", |w| {
        entities.iter().all(|&e| has_collider(w, e))
    });
    app.update();
    assert_eq!(cache(&app).builds(), 1);
    assert_eq!(cache(&app).len(), 1);
    let first = app
        .world()
        .get::<MeshCollider>(entities[0])
        .unwrap()
        .tree()
        .clone();
    for (k, &e) in entities.iter().enumerate() {
        let tree = app.world().get::<MeshCollider>(e).unwrap().tree();
        assert!(Arc::ptr_eq(tree, &first), "entity {k} shares the tree");
        let mut expected: Vec<Entity> = [k.checked_sub(1), (k + 1 < 50).then_some(k + 1)]
            .into_iter()
            .flatten()
            .map(|j| entities[j])
            .collect();
        expected.sort();
        assert_eq!(touching(&app, e), expected, "entity {k}");
    }
}

#[test]
fn a_gltf_like_hierarchy_gets_colliders_placed_by_its_transforms() {
    let mut app = game();
    let cube_handle = add(&mut app, cube(0.5));
    let small = ball(0.3);
    let mesh = || Mesh3d(cube_handle.clone());
    let root = spawn(
        &mut app,
        (
            MeshColliderConstructorHierarchy {
                filter: MeshNameFilter::Except(vec!["Decoration".into()]),
                ..Default::default()
            },
            Transform::from_xyz(10.0, 0.0, 0.0),
        ),
    );
    let child = spawn(&mut app, (mesh(), Transform::default(), ChildOf(root)));
    let node = spawn(
        &mut app,
        (
            Name::new("Node"),
            Transform::from_xyz(0.0, 5.0, 0.0),
            ChildOf(root),
        ),
    );
    let grandchild = spawn(
        &mut app,
        (mesh(), Transform::from_xyz(2.0, 0.0, 0.0), ChildOf(node)),
    );
    let decoration = spawn(
        &mut app,
        (
            mesh(),
            Name::new("Decoration"),
            Transform::from_xyz(0.0, 0.0, 5.0),
            ChildOf(root),
        ),
    );
    // A second scene: only what is under a node named "Wanted".
    let other_root = spawn(
        &mut app,
        (
            MeshColliderConstructorHierarchy {
                filter: MeshNameFilter::Only(vec!["Wanted".into()]),
                ..Default::default()
            },
            Transform::from_xyz(-50.0, 0.0, 0.0),
        ),
    );
    let wanted = spawn(
        &mut app,
        (
            Name::new("Wanted"),
            Transform::default(),
            ChildOf(other_root),
        ),
    );
    let wanted_mesh = spawn(&mut app, (mesh(), Transform::default(), ChildOf(wanted)));
    let unwanted = spawn(
        &mut app,
        (
            mesh(),
            Transform::from_xyz(0.0, 3.0, 0.0),
            ChildOf(other_root),
        ),
    );
    // Neighbours in the world, 0.2 from each cube's face (touching if placed right).
    let near_child = spawn(
        &mut app,
        (small.clone(), Transform::from_xyz(10.7, 0.0, 0.0)),
    );
    let near_grandchild = spawn(
        &mut app,
        (small.clone(), Transform::from_xyz(12.7, 5.0, 0.0)),
    );
    let near_decoration = spawn(
        &mut app,
        (small.clone(), Transform::from_xyz(10.7, 0.0, 5.0)),
    );
    app.update();
    // A child spawned after the scene, scaled by 2: half size 1 at (10, -5, 0).
    let late = spawn(
        &mut app,
        (
            mesh(),
            Transform::from_xyz(0.0, -5.0, 0.0).with_scale(Vec3::splat(2.0)),
            ChildOf(root),
        ),
    );
    // 0.2 from the scaled cube's face (0.7 from the unscaled one's: apart).
    let near_late = spawn(
        &mut app,
        (small.clone(), Transform::from_xyz(11.2, -5.0, 0.0)),
    );
    let with_colliders = [child, grandchild, late, wanted_mesh];
    update_until(&mut app, "hierarchy colliders", |w| {
        with_colliders.iter().all(|&e| has_collider(w, e))
    });
    app.update();
    for e in [decoration, unwanted, root, node, other_root, wanted] {
        assert!(!has_collider(app.world(), e), "{e:?} gets no collider");
        assert!(app.world().get::<MeshColliderConstructor>(e).is_none());
    }
    assert!(
        app.world()
            .get::<MeshColliderConstructorHierarchy>(root)
            .is_some()
    );
    assert_eq!(touching(&app, near_child), vec![child]);
    assert_eq!(touching(&app, near_grandchild), vec![grandchild]);
    assert_eq!(touching(&app, near_late), vec![late]);
    assert!(touching(&app, near_decoration).is_empty());
    assert_eq!(cache(&app).builds(), 1, "one cube mesh, one build");
}

#[test]
fn a_bad_mesh_is_reported_for_each_entity_and_the_others_go_on() {
    let mut app = game();
    let bad = add(&mut app, lines());
    let good = add(&mut app, Sphere::new(1.0).mesh().ico(2).unwrap());
    let bad_entities: Vec<Entity> = (0..3)
        .map(|k| {
            spawn(
                &mut app,
                (
                    Mesh3d(bad.clone()),
                    MeshColliderConstructor::Rigid,
                    Transform::from_xyz(0.0, 10.0 * k as f32 + 10.0, 0.0),
                ),
            )
        })
        .collect();
    let e = spawn(
        &mut app,
        (
            Mesh3d(good),
            MeshColliderConstructor::Rigid,
            Transform::default(),
        ),
    );
    let neighbour = spawn(&mut app, (ball(1.0), Transform::from_xyz(1.8, 0.0, 0.0)));
    update_until(&mut app, "good collider", |w| has_collider(w, e));
    for _ in 0..3 {
        app.update();
    }
    assert_eq!(touching(&app, e), vec![neighbour]);
    let errors = &log(&app).errors;
    assert_eq!(errors.len(), 3, "{errors:?}");
    for &b in &bad_entities {
        assert!(!has_collider(app.world(), b));
        assert!(app.world().get::<MeshColliderConstructor>(b).is_none());
        let reported: Vec<_> = errors.iter().filter(|err| err.entity == b).collect();
        assert_eq!(reported.len(), 1);
        assert_eq!(
            reported[0].kind,
            CollisionErrorKind::BevyMesh(BevyMeshError::UnsupportedTopology(
                PrimitiveTopology::LineList
            ))
        );
    }
    assert_eq!(cache(&app).builds(), 2, "the bad mesh was converted once");
}

#[test]
fn modified_and_removed_assets_leave_the_cache() {
    let mut app = game();
    let handle = add(&mut app, cube(0.5));
    let spawn_cube = |app: &mut App| {
        spawn(
            app,
            (
                Mesh3d(handle.clone()),
                MeshColliderConstructor::Rigid,
                Transform::default(),
            ),
        )
    };
    let half_size = |app: &App, e: Entity| {
        let tree = app.world().get::<MeshCollider>(e).unwrap().collision_mesh();
        tree.mesh().aabb().max.x
    };
    let first = spawn_cube(&mut app);
    update_until(&mut app, "first", |w| has_collider(w, first));
    assert_eq!(cache(&app).len(), 1);
    *app.world_mut()
        .resource_mut::<Assets<Mesh>>()
        .get_mut(handle.id())
        .unwrap() = cube(2.0);
    for _ in 0..2 {
        app.update();
    }
    assert!(cache(&app).is_empty(), "a modified asset drops its entry");
    let second = spawn_cube(&mut app);
    update_until(&mut app, "second", |w| has_collider(w, second));
    assert_eq!(cache(&app).builds(), 2);
    assert_eq!(
        half_size(&app, first),
        0.5,
        "built colliders keep their geometry"
    );
    assert_eq!(
        half_size(&app, second),
        2.0,
        "new ones get the new geometry"
    );
    app.world_mut()
        .resource_mut::<Assets<Mesh>>()
        .remove(handle.id())
        .unwrap();
    for _ in 0..2 {
        app.update();
    }
    assert!(cache(&app).is_empty(), "a removed asset drops its entry");
    let third = spawn_cube(&mut app);
    for _ in 0..5 {
        app.update();
    }
    assert!(!has_collider(app.world(), third), "waits for the asset");
    app.world_mut()
        .resource_mut::<Assets<Mesh>>()
        .insert(handle.id(), cube(1.0))
        .unwrap();
    update_until(&mut app, "third", |w| has_collider(w, third));
    assert_eq!(half_size(&app, third), 1.0);
    assert_eq!(cache(&app).builds(), 3);
}

#[test]
fn deformable_constructors_share_a_mesh_until_it_moves() {
    let mut app = game();
    let handle = add(&mut app, Sphere::new(1.0).mesh().ico(2).unwrap());
    let spawn_one = |app: &mut App, x: f32| {
        spawn(
            app,
            (
                Mesh3d(handle.clone()),
                MeshColliderConstructor::Deformable,
                Transform::from_xyz(x, 0.0, 0.0),
            ),
        )
    };
    let a = spawn_one(&mut app, 0.0);
    let b = spawn_one(&mut app, 10.0);
    let neighbour = spawn(&mut app, (ball(1.0), Transform::from_xyz(2.3, 0.0, 0.0)));
    update_until(&mut app, "deformables", |w| {
        has_collider(w, a) && has_collider(w, b)
    });
    app.update();
    assert_eq!(cache(&app).builds(), 1);
    assert!(touching(&app, a).is_empty(), "0.3 apart");
    let original = app
        .world()
        .get::<Deformable>(b)
        .unwrap()
        .positions()
        .to_vec();
    // Stretch a along x by 1.5: its surface reaches 0.2 into the neighbour.
    for p in app
        .world_mut()
        .get_mut::<Deformable>(a)
        .unwrap()
        .positions_mut()
    {
        p.x *= 1.5;
    }
    for _ in 0..2 {
        app.update();
    }
    assert_eq!(touching(&app, a), vec![neighbour]);
    let b_mesh = app.world().get::<Deformable>(b).unwrap().collision_mesh();
    assert_eq!(
        b_mesh.mesh().positions(),
        original.as_slice(),
        "b keeps its shape"
    );
}

#[test]
fn a_large_mesh_builds_off_the_frame() {
    let mut app = game();
    let sphere = Sphere::new(1.0).mesh().ico(25).unwrap();
    let handle = add(&mut app, sphere);
    let e = spawn(
        &mut app,
        (
            Mesh3d(handle),
            MeshColliderConstructor::Rigid,
            Transform::default(),
        ),
    );
    let neighbour = spawn(&mut app, (ball(1.0), Transform::from_xyz(1.8, 0.0, 0.0)));
    app.update();
    // The frame started the build and went on: the entity is not a collider yet.
    assert_eq!(cache(&app).running(), 1);
    assert!(!has_collider(app.world(), e));
    assert!(touching(&app, neighbour).is_empty());
    update_until(&mut app, "large collider", |w| has_collider(w, e));
    assert!(
        app.world()
            .get::<MeshCollider>(e)
            .unwrap()
            .collision_mesh()
            .mesh()
            .triangle_count()
            > 10_000
    );
    app.update();
    assert_eq!(touching(&app, e), vec![neighbour]);
}
