//! The budget: one [`BudgetController`] that times every stage with its [`BudgetClock`] and
//! plans each run from measured costs; pair priorities and node-pair slices; per-pair seeds.
mod clock;
mod controller;
mod costs;
mod priority;

pub use clock::{BudgetClock, FakeClock, SystemClock};
pub(crate) use controller::TestsDone;
pub use controller::{BudgetController, RunPlan};
pub(crate) use priority::SliceShare;
pub use priority::{pair_priority, pair_seed, slices};
