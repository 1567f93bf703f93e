//! Collision layers: which entities collide with which, as bit masks ([`ContactLayers`]) or
//! named layers (an enum made with [`contact_layers!`](crate::contact_layers) or any type
//! implementing [`ContactLayer`]).
use bevy_ecs::prelude::*;
use bevy_reflect::prelude::*;

/// Which entities collide with which: a pair is tested only if each entity's `memberships`
/// share a bit with the other's `filters`. The default is all bits in both. Masks can be
/// written by hand or made from named layers ([`ContactLayers::from_layers`]).
///
/// # Example
/// ```
/// use stochastic_collision::prelude::*;
/// let debris = ContactLayers::new(0b01, 0b10); // member of layer 0, hits layer 1 only
/// let ground = ContactLayers::new(0b10, 0b01);
/// assert!(debris.interacts_with(&ground));
/// assert!(!debris.interacts_with(&debris));
/// ```
#[derive(Component, Reflect, Clone, Copy, Debug, PartialEq, Eq)]
#[reflect(Component, Clone, Debug, Default, PartialEq)]
pub struct ContactLayers {
    /// Layers this entity belongs to (bit mask).
    pub memberships: u32,
    /// Layers this entity collides with (bit mask).
    pub filters: u32,
}

impl Default for ContactLayers {
    fn default() -> Self {
        Self::ALL
    }
}

impl ContactLayers {
    /// Member of every layer, colliding with every layer.
    pub const ALL: Self = Self {
        memberships: u32::MAX,
        filters: u32::MAX,
    };

    /// Member of no layer, colliding with none: never tested.
    pub const NONE: Self = Self {
        memberships: 0,
        filters: 0,
    };

    /// Layers from masks.
    pub const fn new(memberships: u32, filters: u32) -> Self {
        Self {
            memberships,
            filters,
        }
    }

    /// Layers from named layers: member of each of `memberships`, colliding with each of
    /// `filters`.
    ///
    /// # Example
    /// ```
    /// use stochastic_collision::prelude::*;
    ///
    /// stochastic_collision::contact_layers! {
    ///     /// The game's layers.
    ///     pub enum Layer { Ground, Player, Enemy, Debris }
    /// }
    ///
    /// let player = ContactLayers::from_layers([Layer::Player], [Layer::Ground, Layer::Enemy]);
    /// let enemy = ContactLayers::from_layers([Layer::Enemy], [Layer::Ground, Layer::Player]);
    /// let debris = ContactLayers::from_layers([Layer::Debris], [Layer::Ground]);
    /// let ground = ContactLayers::from_layers([Layer::Ground], Layer::all());
    /// assert!(player.interacts_with(&enemy) && debris.interacts_with(&ground));
    /// assert!(!player.interacts_with(&debris) && !enemy.interacts_with(&enemy));
    /// assert_eq!(player.memberships, 1 << 1);
    /// ```
    pub fn from_layers<L: ContactLayer>(
        memberships: impl IntoIterator<Item = L>,
        filters: impl IntoIterator<Item = L>,
    ) -> Self {
        Self::new(mask_of(memberships), mask_of(filters))
    }

    /// These layers, also a member of `layer`.
    pub fn with_membership(mut self, layer: impl ContactLayer) -> Self {
        self.memberships |= layer.mask();
        self
    }

    /// These layers, no longer a member of `layer`.
    pub fn without_membership(mut self, layer: impl ContactLayer) -> Self {
        self.memberships &= !layer.mask();
        self
    }

    /// These layers, also colliding with `layer`.
    pub fn with_filter(mut self, layer: impl ContactLayer) -> Self {
        self.filters |= layer.mask();
        self
    }

    /// These layers, no longer colliding with `layer`.
    pub fn without_filter(mut self, layer: impl ContactLayer) -> Self {
        self.filters &= !layer.mask();
        self
    }

    /// Whether a pair of entities with these layers is tested.
    #[inline]
    pub fn interacts_with(&self, other: &ContactLayers) -> bool {
        self.memberships & other.filters != 0 && other.memberships & self.filters != 0
    }
}

/// A named collision layer: its bit(s) in a [`ContactLayers`] mask. An enum made with
/// [`contact_layers!`](crate::contact_layers) implements it with one bit per variant, in the
/// order declared; implement it by hand for other layouts (a layer may stand for several
/// bits, a group of layers).
pub trait ContactLayer: Copy {
    /// The layer's bits.
    fn mask(self) -> u32;
}

/// The union of the layers' bits.
fn mask_of<L: ContactLayer>(layers: impl IntoIterator<Item = L>) -> u32 {
    layers.into_iter().fold(0, |m, l| m | l.mask())
}

/// Declares an enum of named collision layers implementing [`ContactLayer`]: variant `k` (in
/// the order written, at most 32) is bit `k`. The enum derives `Clone`, `Copy`, `Debug`,
/// `PartialEq`, `Eq` and `Hash`, and gets `all()`, an array of its variants.
///
/// ```
/// stochastic_collision::contact_layers! {
///     /// Layers of a surgery trainer.
///     pub enum TissueLayer { Organ, Instrument, Table }
/// }
/// use stochastic_collision::ecs::ContactLayer;
/// assert_eq!(TissueLayer::Table.mask(), 0b100);
/// assert_eq!(TissueLayer::all().len(), 3);
/// ```
/// More than 32 variants do not compile:
/// ```compile_fail
/// stochastic_collision::contact_layers! {
///     enum TooMany {
///         L0, L1, L2, L3, L4, L5, L6, L7, L8, L9, L10, L11, L12, L13, L14, L15, L16,
///         L17, L18, L19, L20, L21, L22, L23, L24, L25, L26, L27, L28, L29, L30, L31, L32,
///     }
/// }
/// ```
#[macro_export]
macro_rules! contact_layers {
    (
        $(#[$meta:meta])*
        $vis:vis enum $name:ident {
            $($(#[$variant_meta:meta])* $variant:ident),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        #[repr(u32)]
        $vis enum $name {
            $($(#[$variant_meta])* $variant),*
        }

        impl $name {
            /// Every layer, in the order declared.
            #[allow(dead_code)]
            $vis const fn all() -> [Self; { [$(stringify!($variant)),*].len() }] {
                [$(Self::$variant),*]
            }
        }

        const _: () = assert!(
            [$(stringify!($variant)),*].len() <= 32,
            "contact_layers!: at most 32 layers (a ContactLayers mask has 32 bits)"
        );

        impl $crate::ecs::ContactLayer for $name {
            #[inline]
            fn mask(self) -> u32 {
                1u32 << (self as u32)
            }
        }
    };
}
