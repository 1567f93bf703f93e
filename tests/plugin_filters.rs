//! Which pairs are tested, in a game: named collision layers (`contact_layers!`,
//! `ContactLayers::from_layers`) and the pair filter hook (`PairFilter`, `PairFilterPlugin`,
//! `RefilterPairs`), against brute force over every pair of a seeded scene, in a real app
//! (`TimePlugin`, `TransformPlugin`, the default `FixedPostUpdate`, entities placed with
//! `Transform`).
#![cfg(feature = "transform")]
mod plugin_support;

use std::sync::atomic::{AtomicUsize, Ordering};

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_ecs::system::{RunSystemOnce, SystemParam};
use bevy_transform::components::Transform;
use plugin_support::*;
use rand::rngs::Xoshiro256PlusPlus as StdRng;
use rand::{RngExt, SeedableRng};
use stochastic_collision::prelude::*;

stochastic_collision::contact_layers! {
    /// The test game's layers.
    pub enum Layer { Ground, Player, Enemy, Debris }
}

fn touching(app: &App, a: Entity, b: Entity) -> bool {
    app.world().get::<TouchingEntities>(a).unwrap().contains(b)
}

/// Unit balls at seeded random places in a small volume (many overlap), each with `extra`.
fn scene<B: Bundle>(
    app: &mut App,
    seed: u64,
    n: usize,
    mut extra: impl FnMut(&mut StdRng) -> B,
) -> Vec<(Entity, Vec3)> {
    let mut rng = StdRng::seed_from_u64(seed);
    let ball = ball(1.0);
    (0..n)
        .map(|_| {
            let at = Vec3::new(
                rng.random_range(-4.0..4.0),
                rng.random_range(-4.0..4.0),
                rng.random_range(-2.0..2.0),
            );
            let bundle = (
                ball.clone(),
                Transform::from_translation(at),
                extra(&mut rng),
            );
            (app.world_mut().spawn(bundle).id(), at)
        })
        .collect()
}

/// Whether two unit balls (icospheres: their surfaces are within 2 % of the sphere) at these
/// centres surely overlap, surely do not, or are too close to call.
fn balls_overlap(a: Vec3, b: Vec3) -> Option<bool> {
    let d = a.distance(b);
    if d < 1.9 {
        Some(true)
    } else if d > 2.05 {
        Some(false)
    } else {
        None
    }
}

#[test]
fn named_layers_decide_which_pairs_touch() {
    let mut app = game();
    let layers_of = |l: Layer| match l {
        Layer::Ground => ContactLayers::from_layers([Layer::Ground], Layer::all()),
        Layer::Player => ContactLayers::from_layers([Layer::Player], [Layer::Ground, Layer::Enemy]),
        Layer::Enemy => ContactLayers::from_layers([Layer::Enemy], [Layer::Ground, Layer::Player]),
        Layer::Debris => ContactLayers::from_layers([Layer::Debris], [Layer::Ground]),
    };
    let mut kinds = Vec::new();
    let bodies = scene(&mut app, 11, 60, |rng| {
        let kind = Layer::all()[rng.random_range(0..4)];
        kinds.push(kind);
        layers_of(kind)
    });
    app.update();
    app.update();
    let (mut checked, mut filtered) = (0, 0);
    for i in 0..bodies.len() {
        for j in i + 1..bodies.len() {
            let ((a, pa), (b, pb)) = (bodies[i], bodies[j]);
            let Some(overlap) = balls_overlap(pa, pb) else {
                continue;
            };
            let interacts = layers_of(kinds[i]).interacts_with(&layers_of(kinds[j]));
            assert_eq!(
                touching(&app, a, b),
                overlap && interacts,
                "{:?} and {:?} at distance {}",
                kinds[i],
                kinds[j],
                pa.distance(pb)
            );
            checked += overlap as usize;
            filtered += (overlap && !interacts) as usize;
        }
    }
    // The scene has overlapping pairs of both kinds.
    assert!(
        checked > 20 && filtered > 5,
        "{checked} overlapping, {filtered} filtered"
    );
}

#[test]
fn a_layer_builder_adds_and_removes_bits() {
    let l = ContactLayers::NONE
        .with_membership(Layer::Player)
        .with_filter(Layer::Enemy)
        .with_filter(Layer::Debris)
        .without_filter(Layer::Debris);
    assert_eq!(l, ContactLayers::new(0b0010, 0b0100));
    assert_eq!(l.without_membership(Layer::Player).memberships, 0);
    assert!(!ContactLayers::NONE.interacts_with(&ContactLayers::ALL));
}

#[derive(Component, Clone, Copy, PartialEq, Eq, Debug)]
struct Team(u8);

/// How many times the filter was asked.
#[derive(Resource, Default)]
struct Asked(AtomicUsize);

#[derive(SystemParam)]
struct OtherTeamsOnly<'w, 's> {
    teams: Query<'w, 's, &'static Team>,
    asked: Res<'w, Asked>,
}

impl PairFilter for OtherTeamsOnly<'_, '_> {
    fn test_pair(&self, a: Entity, b: Entity) -> bool {
        self.asked.0.fetch_add(1, Ordering::Relaxed);
        assert!(a < b, "pairs are asked in entity order");
        match (self.teams.get(a), self.teams.get(b)) {
            (Ok(x), Ok(y)) => x != y,
            _ => true,
        }
    }
}

fn filtered_game() -> App {
    let mut app = game();
    app.init_resource::<Asked>()
        .add_plugins(PairFilterPlugin::<OtherTeamsOnly>::default());
    app
}

fn asked(app: &App) -> usize {
    app.world().resource::<Asked>().0.load(Ordering::Relaxed)
}

#[test]
fn the_pair_filter_rejects_pairs_against_brute_force() {
    let mut app = filtered_game();
    let mut teams = Vec::new();
    let bodies = scene(&mut app, 5, 60, |rng| {
        let t = Team(rng.random_range(0..3));
        teams.push(t);
        t
    });
    app.update();
    app.update();
    let (mut overlapping, mut rejected) = (0, 0);
    for i in 0..bodies.len() {
        for j in i + 1..bodies.len() {
            let ((a, pa), (b, pb)) = (bodies[i], bodies[j]);
            let Some(overlap) = balls_overlap(pa, pb) else {
                continue;
            };
            let accepted = teams[i] != teams[j];
            assert_eq!(touching(&app, a, b), overlap && accepted);
            overlapping += overlap as usize;
            rejected += (overlap && !accepted) as usize;
        }
    }
    assert!(overlapping > 20 && rejected > 5);
    // Rejected pairs are not listed, nor ever reported.
    let listed = app
        .world_mut()
        .run_system_once(|c: CollisionPairs| c.iter().map(|p| p.entities()).collect::<Vec<_>>())
        .unwrap();
    let team = |e: Entity| teams[bodies.iter().position(|b| b.0 == e).unwrap()];
    assert!(!listed.is_empty());
    assert!(listed.iter().all(|&(a, b)| team(a) != team(b)));
    assert!(log(&app).started.iter().all(|&(a, b)| team(a) != team(b)));
}

#[test]
fn the_filter_is_asked_when_pairs_are_created_not_every_run() {
    let mut app = filtered_game();
    let bodies = scene(&mut app, 9, 30, |rng| Team(rng.random_range(0..2)));
    // (The first update of a game runs no fixed step.)
    app.update();
    app.update();
    let first = asked(&app);
    assert!(first > 0);
    for _ in 0..5 {
        app.update();
    }
    assert_eq!(asked(&app), first, "nothing moved: nothing is asked again");
    // A new ball: its pairs, and only they, are asked about, once.
    let at = bodies[0].1 + Vec3::new(0.5, 0.5, 0.0);
    spawn(
        &mut app,
        (ball(1.0), Transform::from_translation(at), Team(0)),
    );
    app.update();
    let near = bodies.iter().filter(|(_, p)| p.distance(at) < 2.0).count();
    let new = asked(&app) - first;
    assert!(near > 0);
    assert!(
        (near..=bodies.len()).contains(&new),
        "{new} asked, {near} near"
    );
    for _ in 0..3 {
        app.update();
    }
    assert_eq!(asked(&app), first + new);
}

#[test]
fn a_refiltered_touching_pair_ends_and_starts_again() {
    let mut app = filtered_game();
    let ball = ball(1.0);
    let a = spawn(&mut app, (ball.clone(), Transform::default(), Team(1)));
    let b = spawn(
        &mut app,
        (ball, Transform::from_xyz(1.5, 0.0, 0.0), Team(2)),
    );
    app.update();
    app.update();
    assert!(touching(&app, a, b));
    // Same team now: the pair is asked again and rejected; its contact ends.
    *app.world_mut().get_mut::<Team>(b).unwrap() = Team(1);
    app.world_mut().write_message(RefilterPairs(b));
    app.update();
    assert!(!touching(&app, a, b));
    assert_eq!(log(&app).ended, vec![pair(a, b)]);
    let listed = app
        .world_mut()
        .run_system_once(move |c: CollisionPairs| c.get(a, b).is_some())
        .unwrap();
    assert!(!listed);
    // A change of layers also asks again; other teams again: it touches again.
    *app.world_mut().get_mut::<Team>(b).unwrap() = Team(3);
    app.world_mut()
        .entity_mut(a)
        .insert(ContactLayers::ALL.without_membership(Layer::Debris));
    app.update();
    assert!(touching(&app, a, b));
    assert_eq!(log(&app).started, vec![pair(a, b), pair(a, b)]);
}

#[test]
#[should_panic(expected = "one pair filter")]
fn a_second_pair_filter_is_refused_at_startup() {
    #[derive(SystemParam)]
    struct Everything;
    impl PairFilter for Everything {
        fn test_pair(&self, _: Entity, _: Entity) -> bool {
            true
        }
    }
    let mut app = filtered_game();
    app.add_plugins(PairFilterPlugin::<Everything>::default());
}

#[test]
#[should_panic(expected = "add StochasticCollisionPlugin before it")]
fn a_pair_filter_without_the_pipeline_is_refused() {
    App::new()
        .init_resource::<Asked>()
        .add_plugins(PairFilterPlugin::<OtherTeamsOnly>::default());
}
