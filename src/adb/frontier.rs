//! The frontier of an ADB answer the traversal did not settle, as the answer model reads it:
//! the node pairs left, their estimates and depth, and what the interpenetration certificate
//! said. (Its own module: the traversal makes it, [`AnswerModel`](super::AnswerModel) reads it.)

/// What the interpenetration certificate said of a pose it did not settle.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CertificateHint {
    /// It was not tried (no interior maps, [`AdbQuery::interior_after`](super::AdbQuery::interior_after) not reached, or no
    /// map whose confidence could reach `p_min`).
    #[default]
    NotTried,
    /// Every sample it looked up lay outside the other mesh: the pose is probably apart
    /// ([`PairLookup::Apart`](super::PairLookup::Apart)).
    Apart,
    /// It found samples inside but no crossing it could trust ([`PairLookup::Undecided`](super::PairLookup::Undecided), or
    /// a crossing in a map whose confidence is below `p_min`).
    Undecided,
}

/// The final frontier of an answer the traversal did not settle (a budget ran out, evidence
/// decided, or leaf pairs were left to their estimates): the node pairs that together cover
/// every overlapping leaf pair not ruled out, summed up. [`AdbOutcome::probability`](super::AdbOutcome::probability) is made
/// from these (see [`crate::adb::AnswerModel`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Frontier {
    /// Node pairs in the frontier (queued, and leaf or pruned pairs left for good).
    pub pairs: u32,
    /// `1 − (Π (1 − p))^(1/r)` over the frontier's pair probabilities (`r` disjoint pairs
    /// counting as one independent piece): the confidence before the answer model.
    pub raw_confidence: f64,
    /// The highest pair probability in the frontier.
    pub max_probability: f64,
    /// The queued pairs' mean relative depth `(d_A + d_B) / (d_maxA + d_maxB)` (1: leaf pairs
    /// of the deepest leaves; 0 when none is queued).
    pub mean_depth: f32,
    /// What the certificate said.
    pub certificate: CertificateHint,
}
