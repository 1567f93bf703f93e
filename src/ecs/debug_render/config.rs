//! What the collision gizmos draw and in which colours: the [`CollisionGizmos`] config group.
use bevy_color::palettes::{basic, css};
use bevy_color::{Color, Mix, Oklaba};
use bevy_gizmos::config::GizmoConfigGroup;
use bevy_reflect::Reflect;
use bevy_reflect::std_traits::ReflectDefault;

use super::super::narrow_phase::Method;

/// How long a contact's normal is drawn.
#[derive(Reflect, Debug, Clone, Copy, PartialEq)]
#[reflect(Debug, Clone, PartialEq, Default)]
pub enum NormalLength {
    /// Always this long (world units).
    Fixed(f32),
    /// The contact's depth times `scale`, at least `min` (a contact that merely touches still
    /// shows its direction).
    Depth {
        /// World units per unit of depth.
        scale: f32,
        /// The shortest normal drawn.
        min: f32,
    },
}

impl Default for NormalLength {
    /// [`NormalLength::Fixed`] of 0.25.
    fn default() -> Self {
        NormalLength::Fixed(0.25)
    }
}

impl NormalLength {
    /// The length of a normal drawn for a contact `depth` deep (never negative).
    pub fn of(&self, depth: f32) -> f32 {
        let length = match *self {
            NormalLength::Fixed(l) => l,
            NormalLength::Depth { scale, min } => (depth * scale).max(min),
        };
        if length.is_finite() {
            length.max(0.0)
        } else {
            0.0
        }
    }
}

/// The gizmo config group of [`CollisionDebugPlugin`](super::CollisionDebugPlugin): what is
/// drawn, and the palette.
///
/// It lives in bevy_gizmos' `GizmoConfigStore` with its `GizmoConfig` (line width, depth
/// bias, `enabled`, render layers); change it there:
/// `store.config_mut::<CollisionGizmos>().1.fat_boxes = true`.
///
/// # Palette
/// * World boxes [`box_color`](Self::box_color) (slate grey), broad-phase fat boxes
///   [`fat_box_color`](Self::fat_box_color) (dark grey), feature pairs
///   [`feature_pair_color`](Self::feature_pair_color) (magenta).
/// * Contacts (a cross at the point) and their normals take the colour of the pair's answer
///   ([`confidence_color`](Self::confidence_color)): [`certain_color`](Self::certain_color)
///   (lime green) for a certain answer ([`Method::is_certain`]: an exact test, tracking or
///   the self-collision pass, with probability 1);
///   any other answer (ADB, bounds, from memory, or one whose confidence decayed since it was
///   computed) is mixed in Oklab from [`unsure_color`](Self::unsure_color) (red, at
///   probability 0) to [`likely_color`](Self::likely_color) (yellow, at probability 1) by the
///   pair's [`probability`](super::super::PairView::probability).
#[derive(Reflect, GizmoConfigGroup, Debug, Clone, PartialEq)]
#[reflect(Debug, Clone, PartialEq, Default)]
pub struct CollisionGizmos {
    /// Draw every collider's world box (from the [`ColliderTable`](super::super::ColliderTable)).
    pub world_boxes: bool,
    /// Draw every collider's broad-phase (fat) box, which pairs are made from.
    pub fat_boxes: bool,
    /// Draw the contact points of the pairs (a cross of this half-size; 0: no crosses).
    pub contact_size: f32,
    /// Draw contact normals (from the point, along the normal that pushes the second entity
    /// away from the first).
    pub normals: bool,
    /// How long the normals are.
    pub normal_length: NormalLength,
    /// Draw the feature pairs of tracked pairs and self-colliding meshes (from the
    /// [`FeaturePairs`](super::super::FeaturePairs) components): both triangles' outlines and
    /// the segment between their closest points (a cross where they meet).
    pub feature_pairs: bool,
    /// Colour of the world boxes.
    pub box_color: Color,
    /// Colour of the fat boxes.
    pub fat_box_color: Color,
    /// Colour of the feature pairs.
    pub feature_pair_color: Color,
    /// Colour of the contacts of a certain answer.
    pub certain_color: Color,
    /// Colour of the contacts of an estimated answer of probability 0.
    pub unsure_color: Color,
    /// Colour of the contacts of an estimated answer of probability 1.
    pub likely_color: Color,
}

impl Default for CollisionGizmos {
    /// World boxes, contacts (crosses of half-size 0.05), fixed-length normals and feature
    /// pairs on, fat boxes off; the palette of the type's documentation.
    fn default() -> Self {
        Self {
            world_boxes: true,
            fat_boxes: false,
            contact_size: 0.05,
            normals: true,
            normal_length: NormalLength::default(),
            feature_pairs: true,
            box_color: css::SLATE_GRAY.into(),
            fat_box_color: css::DARK_GRAY.into(),
            feature_pair_color: css::MAGENTA.into(),
            certain_color: basic::LIME.into(),
            unsure_color: basic::RED.into(),
            likely_color: basic::YELLOW.into(),
        }
    }
}

impl CollisionGizmos {
    /// The colour of an answer found by `method` with `probability` (see the palette): the
    /// certain colour for a certain answer, else the Oklab mix of the unsure and likely
    /// colours at `probability` (clamped to [0, 1]; NaN counts as 0).
    pub fn confidence_color(&self, method: Method, probability: f64) -> Color {
        if method.is_certain(probability) {
            return self.certain_color;
        }
        let t = if probability.is_nan() {
            0.0
        } else {
            probability.clamp(0.0, 1.0) as f32
        };
        let (low, high) = (
            Oklaba::from(self.unsure_color),
            Oklaba::from(self.likely_color),
        );
        Color::from(low.mix(&high, t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy_color::{ColorToComponents, LinearRgba};

    #[test]
    fn certain_answers_take_their_colour_and_estimates_run_from_unsure_to_likely() {
        let g = CollisionGizmos::default();
        for m in [Method::Exact, Method::Tracking, Method::SelfCollision] {
            assert_eq!(g.confidence_color(m, 1.0), g.certain_color);
        }
        let rgb = |c: Color| LinearRgba::from(c).to_f32_array();
        let close = |a: [f32; 4], b: [f32; 4]| a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-4);
        for m in [Method::Adb, Method::Bounds, Method::Coherence] {
            assert!(close(rgb(g.confidence_color(m, 0.0)), rgb(g.unsure_color)));
            assert!(close(rgb(g.confidence_color(m, 1.0)), rgb(g.likely_color)));
        }
        // An exact answer that decayed is an estimate; out-of-range input is clamped.
        assert_ne!(g.confidence_color(Method::Exact, 0.9), g.certain_color);
        assert_eq!(
            g.confidence_color(Method::Adb, f64::NAN),
            g.confidence_color(Method::Adb, -3.0)
        );
        assert_eq!(
            g.confidence_color(Method::Adb, 7.0),
            g.confidence_color(Method::Adb, 1.0)
        );
        // Redder (less green) as the probability falls.
        let green = |p: f64| rgb(g.confidence_color(Method::Adb, p))[1];
        assert!(green(0.2) < green(0.5) && green(0.5) < green(0.8));
    }

    #[test]
    fn normals_are_fixed_or_scaled_by_depth_and_never_negative() {
        assert_eq!(NormalLength::Fixed(0.3).of(5.0), 0.3);
        let by_depth = NormalLength::Depth {
            scale: 2.0,
            min: 0.1,
        };
        assert_eq!(by_depth.of(0.5), 1.0);
        assert_eq!(by_depth.of(0.0), 0.1);
        assert_eq!(NormalLength::Fixed(-1.0).of(0.0), 0.0);
        assert_eq!(NormalLength::Fixed(f32::NAN).of(0.0), 0.0);
    }
}
