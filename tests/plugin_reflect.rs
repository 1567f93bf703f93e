//! Reflection: the plugin registers its components, resources and messages, their values
//! survive a round trip through bevy_reflect's serializer (RON, as Bevy scenes store them),
//! and edits made through reflection (as an inspector or `bevy_remote` makes them) reach the
//! pipeline.
mod plugin_support;

use std::any::TypeId;
use std::sync::Arc;
use std::time::Duration;

use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_ecs::reflect::{AppTypeRegistry, ReflectComponent, ReflectResource};
use bevy_reflect::serde::{TypedReflectDeserializer, TypedReflectSerializer};
use bevy_reflect::{FromReflect, GetPath, PartialReflect, Reflect, ReflectRef, TypeRegistry};
use plugin_support::*;
use serde::de::DeserializeSeed;
use stochastic_collision::adb::{Decision, Order};
use stochastic_collision::bvh::TrianglePair;
use stochastic_collision::ecs::{
    BodyAngularVelocity, BodyInertia, BodyMass, BodyVelocity, CollisionCounters, FeaturePairs,
    ImpulseSettings, PenaltySettings, Rest, Stage, StageRecord,
};
use stochastic_collision::prelude::*;

fn app() -> App {
    let mut app = App::new();
    app.add_plugins(StochasticCollisionPlugins::in_schedule(PostUpdate));
    app
}

fn round_trip<T: Reflect + FromReflect + PartialEq + std::fmt::Debug>(
    registry: &TypeRegistry,
    value: &T,
) -> T {
    let ron = ron::to_string(&TypedReflectSerializer::new(
        value.as_partial_reflect(),
        registry,
    ))
    .unwrap_or_else(|e| panic!("{} does not serialize: {e}", std::any::type_name::<T>()));
    let registration = registry
        .get(TypeId::of::<T>())
        .unwrap_or_else(|| panic!("{} is not registered", std::any::type_name::<T>()));
    let mut de = ron::Deserializer::from_str(&ron).unwrap();
    let dynamic = TypedReflectDeserializer::new(registration, registry)
        .deserialize(&mut de)
        .unwrap_or_else(|e| panic!("{ron} does not deserialize: {e}"));
    T::from_reflect(&*dynamic).unwrap_or_else(|| panic!("{ron} is not a value of its type"))
}

#[test]
fn every_public_type_is_registered_with_its_ecs_data() {
    let app = app();
    let registry = app.world().resource::<AppTypeRegistry>().read();
    let components = [
        TypeId::of::<MeshCollider>(),
        TypeId::of::<Deformable>(),
        TypeId::of::<Fidelity>(),
        TypeId::of::<SelfCollision>(),
        TypeId::of::<ContinuousCollision>(),
        TypeId::of::<ContactLayers>(),
        TypeId::of::<TouchingEntities>(),
        TypeId::of::<ColliderPose>(),
        TypeId::of::<ColliderScale>(),
        TypeId::of::<CollisionSensor>(),
        TypeId::of::<ObserveCollisions>(),
        TypeId::of::<FeaturePairs>(),
        TypeId::of::<BodyVelocity>(),
        TypeId::of::<BodyMass>(),
        TypeId::of::<BodyAngularVelocity>(),
        TypeId::of::<BodyInertia>(),
        TypeId::of::<Rest>(),
    ];
    for id in components {
        let r = registry.get(id).expect("component registered");
        assert!(
            r.data::<ReflectComponent>().is_some(),
            "{} has no ReflectComponent",
            r.type_info().type_path()
        );
    }
    let resources = [
        TypeId::of::<CollisionConfig>(),
        TypeId::of::<CollisionDiagnostics>(),
        TypeId::of::<ImpulseSettings>(),
        TypeId::of::<PenaltySettings>(),
    ];
    for id in resources {
        let r = registry.get(id).expect("resource registered");
        assert!(
            r.data::<ReflectResource>().is_some(),
            "{} has no ReflectResource",
            r.type_info().type_path()
        );
    }
    for id in [
        TypeId::of::<CollisionStarted>(),
        TypeId::of::<CollisionEnded>(),
        TypeId::of::<Contact>(),
        TypeId::of::<CollisionError>(),
        TypeId::of::<Method>(),
        TypeId::of::<FrameBudget>(),
    ] {
        assert!(registry.get(id).is_some());
    }
}

#[test]
fn values_survive_a_serialized_round_trip() {
    let app = app();
    let registry = app.world().resource::<AppTypeRegistry>().read();
    let pose = ColliderPose(Pose {
        rotation: Quat::from_rotation_y(0.7),
        translation: Vec3::new(1.0, -2.0, 3.5),
    });
    assert_eq!(round_trip(&registry, &pose), pose);
    for fidelity in [
        Fidelity::Exact,
        Fidelity::Adb { p_min: 0.9 },
        Fidelity::Tracking {
            pairs_per_frame: 17,
        },
        Fidelity::Bounds,
    ] {
        assert_eq!(round_trip(&registry, &fidelity), fidelity);
    }
    let layers = ContactLayers::new(0b101, 0b10);
    assert_eq!(round_trip(&registry, &layers), layers);
    let scale = ColliderScale(Vec3::new(2.0, -1.0, 0.5));
    assert_eq!(round_trip(&registry, &scale), scale);
    let config = CollisionConfig {
        budget: FrameBudget::Time(Duration::from_micros(750)),
        default_fidelity: Fidelity::Tracking { pairs_per_frame: 9 },
        adb_decision: Decision::Evidence,
        adb_order: Order::BestFirst,
        contact_messages: true,
        response_budget: ResponseBudget::Contacts(12),
        seed: 77,
        ..Default::default()
    };
    assert_eq!(round_trip(&registry, &config), config);
    let started = CollisionStarted {
        entity: Entity::from_raw_u32(3).unwrap(),
        other: Entity::from_raw_u32(8).unwrap(),
        method: Method::Adb,
        probability: 0.93,
        time_of_impact: Some(0.25),
    };
    assert_eq!(round_trip(&registry, &started), started);
    let contact = Contact {
        a: Entity::from_raw_u32(1).unwrap(),
        b: Entity::from_raw_u32(2).unwrap(),
        point: Vec3::new(0.5, 0.25, 0.0),
        normal: Vec3::Y,
        depth: 0.01,
        probability: 1.0,
        method: Method::Exact,
        triangles: Some(TrianglePair { a: 4, b: 9 }),
        priority: 2.5,
        frame: 40,
        time_of_impact: None,
    };
    assert_eq!(round_trip(&registry, &contact), contact);
    let untriangled = Contact {
        triangles: None,
        time_of_impact: Some(0.5),
        ..contact
    };
    assert_eq!(round_trip(&registry, &untriangled), untriangled);
    let settings = ImpulseSettings {
        dt: Some(0.02),
        restitution: 0.3,
        ..Default::default()
    };
    assert_eq!(round_trip(&registry, &settings), settings);
    let counters = CollisionCounters {
        node_pairs: 5,
        test_time: Duration::from_nanos(1234),
        ..Default::default()
    };
    assert_eq!(round_trip(&registry, &counters), counters);
    let record = StageRecord {
        last: Some(Duration::from_micros(3)),
        items: 2,
        runs: 1,
        total: Duration::from_micros(3),
    };
    assert_eq!(round_trip(&registry, &record), record);
    assert_eq!(round_trip(&registry, &Stage::Tracking), Stage::Tracking);
    assert_eq!(
        round_trip(&registry, &BodyVelocity(Vec3::X)),
        BodyVelocity(Vec3::X)
    );
    assert_eq!(round_trip(&registry, &BodyMass(3.0)), BodyMass(3.0));
    assert_eq!(
        round_trip(&registry, &BodyAngularVelocity(Vec3::Y)),
        BodyAngularVelocity(Vec3::Y)
    );
    let inertia =
        BodyInertia::from_properties(&generate::cuboid(Vec3::ONE, 1).mass_properties(Vec3::ONE));
    assert_eq!(round_trip(&registry, &inertia), inertia);
}

#[test]
fn a_reflected_collider_shares_its_tree() {
    let collider = MeshCollider::new(generate::icosphere(1.0, 1));
    let clone = collider.reflect_clone().unwrap();
    let clone = clone.downcast_ref::<MeshCollider>().unwrap();
    assert!(Arc::ptr_eq(collider.tree(), clone.tree()));
}

#[test]
fn edits_through_reflection_reach_the_pipeline() {
    let mut app = app();
    let a = app
        .world_mut()
        .spawn((ball(1.0), ColliderPose::from_translation(Vec3::ZERO)))
        .id();
    let b = app
        .world_mut()
        .spawn((ball(1.0), ColliderPose::from_translation(Vec3::X * 5.0)))
        .id();
    app.update();
    assert!(app.world().get::<TouchingEntities>(a).unwrap().is_empty());

    let registry = app.world().resource::<AppTypeRegistry>().clone();
    let registry = registry.read();
    // Move `b` next to `a` by inserting a deserialized pose, as a scene or bevy_remote does.
    let pose = ColliderPose::from_translation(Vec3::X * 1.5);
    let ron = ron::to_string(&TypedReflectSerializer::new(&pose, &registry)).unwrap();
    let registration = registry.get(TypeId::of::<ColliderPose>()).unwrap();
    let mut de = ron::Deserializer::from_str(&ron).unwrap();
    let value = TypedReflectDeserializer::new(registration, &registry)
        .deserialize(&mut de)
        .unwrap();
    let reflect_component = registration.data::<ReflectComponent>().unwrap();
    reflect_component.insert(
        &mut app.world_mut().entity_mut(b),
        value.as_partial_reflect(),
        &registry,
    );
    // Turn on contact messages through the reflected resource, as an inspector does.
    // A resource is stored on an entity of its own in Bevy 0.20; an inspector reaches it
    // through the type's `ReflectComponent` (implied by `ReflectResource`).
    assert!(
        registry
            .get_type_data::<ReflectResource>(TypeId::of::<CollisionConfig>())
            .is_some()
    );
    let reflect_config = registry
        .get_type_data::<ReflectComponent>(TypeId::of::<CollisionConfig>())
        .unwrap();
    {
        let world = app.world_mut();
        let config_entity = world.resource_entity::<CollisionConfig>().unwrap();
        let mut entity = world.entity_mut(config_entity);
        let mut config = reflect_config.reflect_mut(&mut entity).unwrap();
        *config
            .reflect_path_mut("contact_messages")
            .unwrap()
            .try_downcast_mut::<bool>()
            .unwrap() = true;
    }
    drop(registry);
    app.update();
    assert!(app.world().get::<TouchingEntities>(a).unwrap().contains(b));
    assert!(!app.world().resource::<Messages<Contact>>().is_empty());
}

#[test]
fn an_inspector_sees_the_fields_of_the_configuration() {
    let app = app();
    let config = app.world().resource::<CollisionConfig>();
    let budget: &FrameBudget = config.path("budget").unwrap();
    assert_eq!(*budget, CollisionConfig::default().budget);
    // `Order` is mirrored by `OrderReflect`: the field reads as an enum of the same variants.
    let order = config.reflect_path("adb_order").unwrap();
    let ReflectRef::Enum(order) = order.reflect_ref() else {
        panic!("adb_order is not reflected as an enum: {order:?}");
    };
    assert_eq!(
        order.variant_name(),
        format!("{:?}", CollisionConfig::default().adb_order)
    );
    let p: &f64 = config.path("default_fidelity.p_min").unwrap();
    assert_eq!(*p, 0.99);
}
