//! The queue of the ADB traversal: node pairs waiting to be expanded, in the query's
//! [`Order`].
use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::options::Order;

/// The pairs waiting to be expanded, in the query's [`Order`]: a max-heap, and a stack (for
/// [`Order::EvidenceFirst`] the pairs below the evidence bar, for [`Order::DepthFirst`] and
/// [`Order::Straddle`] all).
#[derive(Debug, Default)]
pub(super) struct Queue {
    heap: BinaryHeap<Entry>,
    stack: Vec<Entry>,
    order: Order,
    /// Pairs at least this probable count as evidence.
    evidence_bar: f64,
}

impl Queue {
    pub(super) fn reset(&mut self, order: Order, evidence_bar: f64) {
        self.heap.clear();
        self.stack.clear();
        self.order = order;
        self.evidence_bar = evidence_bar;
    }

    pub(super) fn pop(&mut self) -> Option<Entry> {
        match self.order {
            Order::BestFirst => self.heap.pop(),
            Order::EvidenceFirst => self.heap.pop().or_else(|| self.stack.pop()),
            Order::DepthFirst | Order::Straddle => self.stack.pop(),
        }
    }

    /// Queues a pair (or puts back one just popped, when the budget ends before it is
    /// expanded).
    pub(super) fn push(&mut self, e: Entry) {
        match self.order {
            Order::EvidenceFirst if e.p < self.evidence_bar => self.stack.push(e),
            Order::DepthFirst | Order::Straddle => self.stack.push(e),
            _ => self.heap.push(e),
        }
    }

    /// Queues the children of one expanded pair (at most four).
    pub(super) fn push_children(&mut self, children: &mut [Entry]) {
        if self.order != Order::BestFirst {
            // Least promising first, so that the most promising is popped next.
            children.sort_unstable();
        }
        for &c in children.iter() {
            self.push(c);
        }
    }

    /// The stack of pairs, to push and pop directly and to update in place (the heap, whose
    /// order depends on them, is not included: only [`Order::Straddle`] does either, and it
    /// uses only the stack).
    pub(super) fn stack_mut(&mut self) -> &mut Vec<Entry> {
        debug_assert!(self.heap.is_empty());
        &mut self.stack
    }

    pub(super) fn iter(&self) -> impl Iterator<Item = &Entry> {
        self.heap.iter().chain(self.stack.iter())
    }
}

/// A queued node pair, ordered by its rank, ties broken by node indices (deterministic).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Entry {
    /// The pair's probability ([`UNESTIMATED`](super::options::UNESTIMATED) if not estimated).
    pub(super) p: f64,
    /// Its rank in the queue: the probability, or for [`Order::DepthFirst`] the probability
    /// weighted by how squarely the boxes straddle each other's surface, for
    /// [`Order::Straddle`] that straddle alone.
    pub(super) rank: f64,
    /// Node of the first tree.
    pub(super) a: u32,
    /// Node of the second tree.
    pub(super) b: u32,
    /// Distance between the two boxes' centres (what an estimate needs).
    pub(super) center_distance: f32,
}

impl PartialEq for Entry {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Entry {}
impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Entry {
    fn cmp(&self, o: &Self) -> Ordering {
        self.rank
            .total_cmp(&o.rank)
            .then_with(|| o.a.cmp(&self.a))
            .then_with(|| o.b.cmp(&self.b))
    }
}
