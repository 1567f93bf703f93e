//! Pairs of colliders, kept from run to run: the [`PairTable`] and the [`CollisionPairs`] system
//! parameter that reads it.
mod collision_pairs;
mod table;

pub use collision_pairs::{CollisionPairs, PairView};
pub use table::PairTable;
pub(crate) use table::{PairEnds, PairSlot, Record};
