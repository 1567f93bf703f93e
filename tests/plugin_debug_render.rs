//! Debug drawing in a headless app (no window, no renderer): bevy_time's `TimePlugin`,
//! bevy_transform's `TransformPlugin`, bevy_asset's `AssetPlugin` and bevy_gizmos'
//! `GizmoPlugin`, the collision plugin in its default `FixedPostUpdate` with one fixed step
//! per update. The lines are read from the `GizmoAsset` that bevy_gizmos fills in `Last`,
//! and checked against the colliders' geometry: boxes around each collider, a cross at each
//! contact and a line along its normal, colours by confidence, feature pairs of a tracked
//! pair and of a self-colliding cloth.
#![cfg(feature = "debug_render")]
mod plugin_support;

use std::any::TypeId;
use std::time::Duration;

use bevy_app::prelude::*;
use bevy_asset::{AssetPlugin, Assets};
use bevy_color::{Color, LinearRgba, Mix, Oklaba};
use bevy_ecs::prelude::*;
use bevy_ecs::system::RunSystemOnce;
use bevy_gizmos::config::GizmoConfigStore;
use bevy_gizmos::{GizmoAsset, GizmoHandles, GizmoPlugin};
use bevy_time::{TimePlugin, TimeUpdateStrategy};
use bevy_transform::TransformPlugin;
use bevy_transform::components::Transform;
use plugin_support::{ball, pair, spawn};
use stochastic_collision::ecs::{
    BroadPhaseState, ColliderEntry, ColliderTable, ContactPoint, FeaturePairs, NormalLength,
    PairOutcome,
};
use stochastic_collision::prelude::*;

/// A headless game with the debug plugin, `settings` as its initial gizmo settings.
fn game(config: CollisionConfig, settings: CollisionGizmos) -> App {
    let mut app = App::new();
    app.add_plugins((
        TimePlugin,
        TransformPlugin,
        AssetPlugin::default(),
        GizmoPlugin,
        StochasticCollisionPlugin::default().with_config(CollisionConfig {
            budget: FrameBudget::Unlimited,
            ..config
        }),
        CollisionDebugPlugin::with_gizmos(settings),
    ))
    .insert_resource(TimeUpdateStrategy::FixedTimesteps(1));
    app
}

/// Runs `n` app updates (the first one runs no fixed step: it starts the clock).
fn steps(app: &mut App, n: usize) {
    for _ in 0..n {
        app.update();
    }
}

/// One line drawn in the collision gizmos group.
#[derive(Debug, Clone, Copy)]
struct Line {
    from: Vec3,
    to: Vec3,
    color: LinearRgba,
}

/// The lines of the collision gizmos group shown in the last frame.
fn lines(app: &App) -> Vec<Line> {
    let handles = app.world().resource::<GizmoHandles>();
    let Some(Some(handle)) = handles.handles().get(&TypeId::of::<CollisionGizmos>()) else {
        return Vec::new();
    };
    let asset = app
        .world()
        .resource::<Assets<GizmoAsset>>()
        .get(handle)
        .unwrap();
    let view = asset.buffer().buffer();
    assert!(view.strip_positions.is_empty(), "only line lists are drawn");
    assert_eq!(view.list_positions.len(), view.list_colors.len());
    view.list_positions
        .chunks(2)
        .zip(view.list_colors.chunks(2))
        .map(|(p, c)| {
            assert_eq!(c[0], c[1], "one colour per line");
            Line {
                from: p[0],
                to: p[1],
                color: c[0],
            }
        })
        .collect()
}

fn linear(c: Color) -> LinearRgba {
    c.into()
}

fn near(a: Vec3, b: Vec3) -> bool {
    a.distance(b) < 1e-4
}

/// Whether `l` joins `p` and `q`, in either direction.
fn joins(l: &Line, p: Vec3, q: Vec3) -> bool {
    (near(l.from, p) && near(l.to, q)) || (near(l.from, q) && near(l.to, p))
}

fn with_color(lines: &[Line], c: Color) -> Vec<Line> {
    lines
        .iter()
        .copied()
        .filter(|l| l.color == linear(c))
        .collect()
}

/// The world box of `e` as the pipeline has it.
fn world_box(app: &App, e: Entity) -> Aabb {
    app.world().resource::<ColliderTable>().get(e).unwrap().aabb
}

/// Asserts that the 12 edges of `b` are among `lines`: 4 edges along each axis, each as
/// long as the box, ends on its corners.
fn assert_box_drawn(lines: &[Line], b: &Aabb) {
    let corners: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new(
                [b.min.x, b.max.x][i & 1],
                [b.min.y, b.max.y][(i >> 1) & 1],
                [b.min.z, b.max.z][(i >> 2) & 1],
            )
        })
        .collect();
    let mut edges = 0;
    for (i, &p) in corners.iter().enumerate() {
        for &q in &corners[i + 1..] {
            let axes = (q - p)
                .abs()
                .cmpgt(Vec3::splat(1e-6))
                .bitmask()
                .count_ones();
            if axes == 1 {
                assert!(
                    lines.iter().any(|l| joins(l, p, q)),
                    "edge {p} – {q} of {b:?} not drawn"
                );
                edges += 1;
            }
        }
    }
    assert_eq!(edges, 12);
}

/// Every pair's answer and contacts, from the public system parameter.
fn answers(app: &mut App) -> Vec<(PairOutcome, f64, Vec<ContactPoint>)> {
    app.world_mut()
        .run_system_once(|pairs: CollisionPairs| {
            pairs
                .iter()
                .map(|p| (p.outcome().clone(), p.probability(), p.contacts().to_vec()))
                .collect::<Vec<_>>()
        })
        .unwrap()
}

/// Asserts that each contact has a cross of half-size `size` centred on it and a line from
/// it along its normal, `length` long, all in `color`.
fn assert_contacts_drawn(
    lines: &[Line],
    contacts: &[ContactPoint],
    size: f32,
    length: f32,
    color: Color,
) {
    let lines = with_color(lines, color);
    for c in contacts {
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            assert!(
                lines
                    .iter()
                    .any(|l| joins(l, c.point - axis * size, c.point + axis * size)),
                "no cross arm along {axis} at {c:?}"
            );
        }
        assert!(
            lines
                .iter()
                .any(|l| near(l.from, c.point) && near(l.to, c.point + c.normal * length)),
            "no normal at {c:?}"
        );
    }
}

/// Exact balls a, b overlapping at the origin; balls c, d overlapping near x = 20 under ADB
/// with estimated leaves (an answer strictly between 0 and 1), all placed with `Transform`.
fn four_balls(app: &mut App) -> [Entity; 4] {
    let ball = ball(1.0);
    let place = |x: f32, y: f32| Transform::from_xyz(x, y, 0.0);
    let a = spawn(app, (ball.clone(), place(0.0, 0.0), Fidelity::Exact));
    let b = spawn(app, (ball.clone(), place(1.5, 0.0), Fidelity::Exact));
    let c = spawn(app, (ball.clone(), place(20.0, 0.0)));
    let d = spawn(app, (ball, place(21.42, 1.42)));
    [a, b, c, d]
}

/// ADB answers strictly between 0 and 1, and reported colliding.
fn unsure_adb() -> CollisionConfig {
    CollisionConfig {
        adb_exact_leaves: false,
        adb_collide_at: 1e-6,
        ..Default::default()
    }
}

#[test]
fn boxes_contacts_and_normals_are_drawn_coloured_by_confidence() {
    let settings = CollisionGizmos::default();
    let mut app = game(unsure_adb(), settings.clone());
    let balls = four_balls(&mut app);
    steps(&mut app, 2);
    let drawn = lines(&app);

    // A box around each collider: its world box, which holds the unit ball at its centre.
    let boxes = with_color(&drawn, settings.box_color);
    assert_eq!(boxes.len(), 4 * 12);
    for (e, centre) in balls.into_iter().zip([
        Vec3::ZERO,
        Vec3::X * 1.5,
        Vec3::X * 20.0,
        Vec3::new(21.42, 1.42, 0.0),
    ]) {
        let b = world_box(&app, e);
        assert!(b.min.cmple(centre - 0.99).all() && b.max.cmpge(centre + 0.99).all());
        assert!(b.min.cmpge(centre - 1.2).all() && b.max.cmple(centre + 1.2).all());
        assert_box_drawn(&boxes, &b);
    }

    // Contacts and normals of both pairs, in the colour of their answers.
    let answers = answers(&mut app);
    assert_eq!(answers.len(), 2);
    let mut contacts = 0;
    for (outcome, p, points) in &answers {
        assert!(outcome.collides && !points.is_empty(), "{outcome:?}");
        let color = if (outcome.a, outcome.b) == pair(balls[0], balls[1]) {
            // Certain: lime green; the contacts lie between the balls, normals are unit.
            assert_eq!((outcome.method, *p), (Method::Exact, 1.0));
            for c in points {
                assert!((c.point.x - 0.75).abs() < 0.3, "{c:?}");
                assert!((c.normal.length() - 1.0).abs() < 1e-4, "{c:?}");
            }
            settings.certain_color
        } else {
            // Estimated: red to yellow by probability, in Oklab.
            assert_eq!((outcome.a, outcome.b), pair(balls[2], balls[3]));
            assert_eq!(outcome.method, Method::Adb);
            assert!(*p > 0.0 && *p < 1.0, "{p}");
            let (low, high) = (
                Oklaba::from(settings.unsure_color),
                Oklaba::from(settings.likely_color),
            );
            Color::from(low.mix(&high, *p as f32))
        };
        assert_eq!(settings.confidence_color(outcome.method, *p), color);
        assert_contacts_drawn(&drawn, points, settings.contact_size, 0.25, color);
        assert_eq!(with_color(&drawn, color).len(), points.len() * 4);
        contacts += points.len();
    }
    let (_, p, _) = answers.iter().find(|a| a.0.method == Method::Adb).unwrap();
    let unsure = settings.confidence_color(Method::Adb, *p);
    assert_ne!(linear(unsure), linear(settings.certain_color));
    assert!(!with_color(&drawn, unsure).is_empty());
    // Nothing else: boxes, and a cross and a normal per contact (no feature pairs here).
    assert_eq!(drawn.len(), 4 * 12 + contacts * 4);
}

#[test]
fn settings_choose_what_is_drawn() {
    let settings = CollisionGizmos {
        world_boxes: false,
        fat_boxes: true,
        normal_length: NormalLength::Depth {
            scale: 2.0,
            min: 0.01,
        },
        contact_size: 0.0,
        ..Default::default()
    };
    let mut app = game(CollisionConfig::default(), settings.clone());
    let [a, b, ..] = four_balls(&mut app);
    steps(&mut app, 2);
    let drawn = lines(&app);
    assert!(with_color(&drawn, settings.box_color).is_empty());
    // Fat boxes: 12 edges each, the broad phase's, around the world box.
    let fat = with_color(&drawn, settings.fat_box_color);
    assert_eq!(fat.len(), 4 * 12);
    for e in [a, b] {
        let w = world_box(&app, e);
        let f = app
            .world()
            .resource::<BroadPhaseState>()
            .fat_box(app.world().resource::<ColliderTable>(), e)
            .unwrap();
        assert!(
            f.min.cmple(w.min).all() && f.max.cmpge(w.max).all(),
            "{f:?} {w:?}"
        );
        assert_box_drawn(&fat, &f);
    }
    // No crosses: one line per contact, along its normal, twice its depth long (at least 0.01).
    let answers = answers(&mut app);
    let points: Vec<ContactPoint> = answers.iter().flat_map(|a| a.2.clone()).collect();
    let normals: Vec<Line> = drawn
        .iter()
        .copied()
        .filter(|l| l.color != linear(settings.fat_box_color))
        .collect();
    assert_eq!(normals.len(), points.len());
    for c in &points {
        let length = (2.0 * c.depth).max(0.01);
        assert!(
            normals
                .iter()
                .any(|l| near(l.from, c.point) && near(l.to, c.point + c.normal * length)),
            "{c:?}"
        );
    }

    // Disabled: nothing drawn.
    app.world_mut()
        .resource_mut::<GizmoConfigStore>()
        .config_mut::<CollisionGizmos>()
        .0
        .enabled = false;
    app.update();
    assert!(lines(&app).is_empty());
}

#[test]
fn lines_of_a_fixed_step_stay_until_the_next_step() {
    let mut app = game(CollisionConfig::default(), CollisionGizmos::default());
    four_balls(&mut app);
    steps(&mut app, 2);
    let first = lines(&app);
    assert!(!first.is_empty());
    // A frame shorter than the fixed step runs no step (no pipeline run): the same lines
    // are shown.
    let run = app.world().resource::<CollisionDiagnostics>().frame;
    app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_millis(1)));
    app.update();
    assert_eq!(app.world().resource::<CollisionDiagnostics>().frame, run);
    let again = lines(&app);
    assert_eq!(again.len(), first.len());
    assert!(
        first
            .iter()
            .zip(&again)
            .all(|(p, q)| p.from == q.from && p.to == q.to)
    );
}

/// Asserts that the feature-pair lines are, for each triangle pair (the first entity's
/// triangle, the second's), both triangles' outlines at their colliders' poses and a segment
/// or a cross between them; returns the number of lines that makes.
fn assert_feature_pairs_drawn(
    app: &App,
    lines: &[Line],
    (a, b): (Entity, Entity),
    size: f32,
) -> usize {
    let table = app.world().resource::<ColliderTable>();
    let (ea, eb) = (table.get(a).unwrap(), table.get(b).unwrap());
    let triangle = |e: &ColliderEntry, t: u32| {
        e.geometry
            .mesh()
            .mesh()
            .triangle(t as usize)
            .map(|p| e.pose.transform_point(p))
    };
    let pairs = app.world().get::<FeaturePairs>(a).unwrap().with(b).to_vec();
    assert!(!pairs.is_empty());
    let mut count = 0;
    for p in &pairs {
        let (ta, tb) = (triangle(ea, p.a), triangle(eb, p.b));
        for t in [ta, tb] {
            for i in 0..3 {
                assert!(
                    lines.iter().any(|l| joins(l, t[i], t[(i + 1) % 3])),
                    "{p:?}"
                );
            }
        }
        // The link between the two triangles: its ends within the pair's region.
        let hull = Aabb::from_points(ta.into_iter().chain(tb)).inflated(size + 1e-4);
        assert!(
            lines.iter().any(|l| hull.contains_point(l.from)
                && hull.contains_point(l.to)
                && !ta
                    .iter()
                    .chain(&tb)
                    .any(|v| near(l.from, *v) || near(l.to, *v))),
            "no link for {p:?}"
        );
        count += 6;
    }
    count
}

#[test]
fn feature_pairs_of_a_tracked_pair_are_drawn_once() {
    let settings = CollisionGizmos {
        world_boxes: false,
        contact_size: 0.01,
        normals: false,
        ..Default::default()
    };
    let mut app = game(CollisionConfig::default(), settings.clone());
    let tracked = Fidelity::Tracking {
        pairs_per_frame: 16,
    };
    let a = spawn(
        &mut app,
        (ball(1.0), tracked, Transform::from_xyz(0.0, 0.0, 0.0)),
    );
    let b = spawn(
        &mut app,
        (ball(1.0), tracked, Transform::from_xyz(1.7, 0.0, 0.0)),
    );
    for _ in 0..5 {
        app.update();
    }
    let drawn = lines(&app);
    let features = with_color(&drawn, settings.feature_pair_color);
    let outlines = assert_feature_pairs_drawn(&app, &features, (a, b), settings.contact_size);
    let pairs = app.world().get::<FeaturePairs>(a).unwrap().with(b).len();
    assert_eq!(
        app.world().get::<FeaturePairs>(b).unwrap().with(a).len(),
        pairs
    );
    // Once per pair, not again for b's swapped copy: 6 outline edges and a segment (1 line)
    // or a cross (3 lines) each.
    let n = features.len();
    assert!(
        n >= outlines + pairs && n <= outlines + 3 * pairs,
        "{n} lines, {pairs} pairs"
    );
    // Triangles of the two balls (on or inside their unit spheres, crosses reaching out by
    // their half-size), in the lens where they overlap.
    let r = 1.0 + settings.contact_size + 1e-3;
    for p in features.iter().flat_map(|l| [l.from, l.to]) {
        assert!(p.length() < r || (p - Vec3::X * 1.7).length() < r, "{p}");
        assert!(p.x > 0.4 && p.x < 1.3, "{p}");
    }
}

#[test]
fn feature_pairs_of_a_self_colliding_cloth_are_drawn() {
    let settings = CollisionGizmos {
        world_boxes: false,
        normals: false,
        contact_size: 0.01,
        ..Default::default()
    };
    let mut app = game(CollisionConfig::default(), settings.clone());
    // A cloth whose part beyond x = 0.1 is turned over and cut through the rest.
    let flat = generate::cloth_grid(1.0, 1.0, 20, 20);
    let mut cloth = Deformable::new(flat.clone());
    for (p, q) in cloth.positions_mut().iter_mut().zip(flat.positions()) {
        if q.x > 0.1 {
            *p = Vec3::new(0.2 - q.x, -0.04 * (1.0 - 4.0 * (q.x - 0.1)), q.z);
        }
    }
    let cloth = spawn(
        &mut app,
        (
            cloth,
            SelfCollision,
            Fidelity::Tracking {
                pairs_per_frame: 32,
            },
            Transform::default(),
        ),
    );
    for _ in 0..4 {
        app.update();
    }
    let drawn = lines(&app);
    let features = with_color(&drawn, settings.feature_pair_color);
    let outlines =
        assert_feature_pairs_drawn(&app, &features, (cloth, cloth), settings.contact_size);
    let pairs = app
        .world()
        .get::<FeaturePairs>(cloth)
        .unwrap()
        .with(cloth)
        .len();
    // Per pair: the outlines and a segment (1 line) or a cross (3 lines).
    assert!(features.len() >= outlines + pairs && features.len() <= outlines + 3 * pairs);
}

#[test]
fn the_plugin_needs_the_collision_and_gizmo_plugins() {
    let message = |result: std::thread::Result<()>| {
        let payload = result.unwrap_err();
        match payload.downcast::<String>() {
            Ok(s) => *s,
            Err(payload) => payload.downcast::<&str>().unwrap().to_string(),
        }
    };
    let without_pipeline = std::panic::catch_unwind(|| {
        App::new().add_plugins((
            AssetPlugin::default(),
            GizmoPlugin,
            CollisionDebugPlugin::default(),
        ));
    });
    assert!(message(without_pipeline).contains("add StochasticCollisionPlugin before it"));
    let without_gizmos = std::panic::catch_unwind(|| {
        let mut app = App::new();
        app.add_plugins((
            StochasticCollisionPlugin::in_schedule(PostUpdate),
            CollisionDebugPlugin::default(),
        ));
        app.finish();
    });
    assert!(message(without_gizmos).contains("GizmoPlugin"));
}
