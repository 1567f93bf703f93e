//! Debug drawing with bevy_gizmos (the `debug_render` feature): what the collision pipeline
//! sees, drawn after each run's Report stage.
//!
//! # Overview
//! Add [`CollisionDebugPlugin`] after
//! [`StochasticCollisionPlugin`](super::StochasticCollisionPlugin), in an app with bevy_gizmos'
//! `GizmoPlugin` (Bevy's `DefaultPlugins` have it). It draws, in the [`CollisionGizmos`]
//! gizmo config group:
//! * every collider's **world box**, from the [`ColliderTable`](super::ColliderTable), and on
//!   request its **broad-phase (fat) box**, from the
//!   [`BroadPhaseState`](super::BroadPhaseState);
//! * every pair's **contacts** (a cross at each point) and their **normals** (a line along the
//!   normal, fixed length or scaled by depth), read through
//!   [`CollisionPairs`](super::CollisionPairs), **coloured by confidence**: certain answers
//!   lime green, estimated ones (ADB, bounds, from memory, decayed) from red at probability 0
//!   to yellow at probability 1 ([`CollisionGizmos::confidence_color`]);
//! * the **feature pairs** of tracked pairs and self-colliding meshes, from the
//!   [`FeaturePairs`](super::FeaturePairs) components: both triangles' outlines and the segment
//!   between their closest points (a cross where they intersect), in magenta.
//!
//! Settings and colours are fields of [`CollisionGizmos`], kept in bevy_gizmos'
//! `GizmoConfigStore`; its `GizmoConfig::enabled` turns the drawing off (the systems then do
//! nothing).
//!
//! # Schedule
//! The systems run in the collision plugin's schedule after
//! [`CollisionSystems::Report`](super::CollisionSystems::Report). In a fixed schedule (the
//! default `FixedPostUpdate`), bevy_gizmos keeps the lines of the last fixed step and shows
//! them every frame until the next step replaces them; in `Update` or `PostUpdate` they are
//! drawn for that frame.
//!
//! # Without a window
//! The feature depends on bevy_gizmos (and bevy_color and bevy_asset, which it uses), not on
//! a renderer or a window (no bevy_render, no wgpu, no winit): the lines are collected into
//! bevy_gizmos' `GizmoAsset`s, which a headless app can read, and which Bevy's gizmo renderer
//! (bevy_gizmos_render's `GizmoRenderPlugin`, in `DefaultPlugins` with bevy_gizmos'
//! `GizmoPlugin`) draws when there is one.
mod config;
mod draw;
mod plugin;

pub use config::{CollisionGizmos, NormalLength};
pub use draw::{draw_collider_boxes, draw_contacts, draw_feature_pairs};
pub use plugin::CollisionDebugPlugin;
