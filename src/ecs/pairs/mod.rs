//! Pairs of colliders, kept from run to run: the [`PairTable`], the [`CollisionPairs`] system
//! parameter that reads it, and the app's [`PairFilter`] that decides which pairs are tested.
mod collision_pairs;
mod filter;
mod table;

pub use collision_pairs::{CollisionPairs, PairView};
pub use filter::{PairFilter, PairFilterPlugin, RefilterPairs, filter_pairs};
pub use table::PairTable;
pub(crate) use table::{PairEnds, PairSlot, Record};
