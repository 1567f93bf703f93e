//! The debug-drawing plugin: the [`CollisionGizmos`] group and the drawing systems, after the
//! pipeline's Report stage in its schedule.
use bevy_app::prelude::*;
use bevy_ecs::prelude::*;
use bevy_gizmos::{AppGizmoBuilder, GizmoPlugin};

use super::super::schedule::{CollisionSchedule, CollisionSystems};
use super::config::{CollisionGizmos, NormalLength};
use super::draw::{draw_collider_boxes, draw_contacts, draw_feature_pairs};

/// Draws what the collision pipeline sees with bevy_gizmos: world boxes, broad-phase boxes,
/// contacts and normals coloured by confidence, and the feature pairs of tracked pairs (see
/// [`CollisionGizmos`] for the settings and the palette).
///
/// Its systems run in the collision plugin's schedule
/// ([`CollisionSchedule`]), after [`CollisionSystems::Report`], so they draw every run's
/// answers. Gizmos drawn in a fixed schedule (the default `FixedPostUpdate`) stay on screen
/// until the next fixed step runs (bevy_gizmos keeps a fixed step's gizmos in their own
/// buffer and adds them to every frame until the next step clears them), so a frame without
/// a fixed step still shows the last run.
///
/// Needs bevy_gizmos' `GizmoPlugin` (part of Bevy's `DefaultPlugins`; it uses bevy_asset's
/// `AssetPlugin` but no window or renderer: drawing the lines on screen is the job of
/// bevy_gizmos_render's `GizmoRenderPlugin`, also in `DefaultPlugins`) and [`StochasticCollisionPlugin`](super::super::StochasticCollisionPlugin)
/// added before it.
///
/// # Panics
/// At startup, when [`StochasticCollisionPlugin`](super::super::StochasticCollisionPlugin)
/// was not added before it, or when no `GizmoPlugin` was added at all (nothing would collect
/// the lines).
#[derive(Debug, Clone, Default)]
pub struct CollisionDebugPlugin {
    /// The initial settings.
    pub gizmos: CollisionGizmos,
}

impl CollisionDebugPlugin {
    /// The plugin with these initial settings.
    pub fn with_gizmos(gizmos: CollisionGizmos) -> Self {
        Self { gizmos }
    }
}

impl Plugin for CollisionDebugPlugin {
    fn build(&self, app: &mut App) {
        let Some(&CollisionSchedule(schedule)) = app.world().get_resource::<CollisionSchedule>()
        else {
            panic!(
                "CollisionDebugPlugin: add StochasticCollisionPlugin before it (it draws in \
                 that schedule)"
            );
        };
        app.register_type::<CollisionGizmos>()
            .register_type::<NormalLength>()
            .init_gizmo_group::<CollisionGizmos>();
        app.world_mut()
            .resource_mut::<bevy_gizmos::config::GizmoConfigStore>()
            .config_mut::<CollisionGizmos>()
            .1
            .clone_from(&self.gizmos);
        app.add_systems(
            schedule,
            (draw_collider_boxes, draw_contacts, draw_feature_pairs)
                .after(CollisionSystems::Report),
        );
    }

    fn finish(&self, app: &mut App) {
        if !app.is_plugin_added::<GizmoPlugin>() {
            panic!(
                "CollisionDebugPlugin: add bevy_gizmos' GizmoPlugin (part of DefaultPlugins); \
                 without it no gizmo is collected"
            );
        }
    }
}
