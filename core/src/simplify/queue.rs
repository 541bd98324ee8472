//! The collapse queue: a min-priority queue whose working part stays in cache.
//!
//! A greedy collapse keeps millions of candidates queued (the dragon starts
//! with 1.3 M edges and every collapse queues its new edges, leaving the old
//! ones stale), and a binary heap of that size misses the cache on every level
//! of every pop: that was a third of the dragon's collapse time. Here only the
//! smallest entries live in a heap ("hot"); the rest wait unsorted ("cold").
//! Every hot entry is ≤ `bar` ≤ every cold entry, so the heap's minimum is the
//! global minimum and the order is exactly a single heap's. When the hot heap
//! runs dry, the next batch is selected from the cold entries in linear time,
//! and entries the caller no longer wants (stale edges) are dropped on the way.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Entries moved to the heap per refill: small enough for the L2 cache.
const BATCH: usize = 1 << 14;

#[derive(Clone)]
pub(crate) struct CollapseQueue<T: Ord + Copy> {
    hot: BinaryHeap<Reverse<T>>,
    cold: Vec<T>,
    /// The largest entry moved to `hot` by the last refill; `None` before one.
    bar: Option<T>,
}

impl<T: Ord + Copy> CollapseQueue<T> {
    pub fn with_capacity(n: usize) -> Self {
        Self {
            hot: BinaryHeap::with_capacity(BATCH),
            cold: Vec::with_capacity(n),
            bar: None,
        }
    }

    pub fn push(&mut self, e: T) {
        match self.bar {
            Some(bar) if e <= bar => self.hot.push(Reverse(e)),
            _ => self.cold.push(e),
        }
    }

    /// The smallest entry; a refill first drops the cold entries `keep` rejects.
    pub fn pop(&mut self, keep: impl Fn(&T) -> bool) -> Option<T> {
        self.refill(keep);
        self.hot.pop().map(|Reverse(e)| e)
    }

    /// The smallest entry, left in place (refilling as `pop` does).
    pub fn peek(&mut self, keep: impl Fn(&T) -> bool) -> Option<&T> {
        self.refill(keep);
        self.hot.peek().map(|Reverse(e)| e)
    }

    /// Moves the next batch to the heap when it has run dry.
    fn refill(&mut self, keep: impl Fn(&T) -> bool) {
        if !self.hot.is_empty() {
            return;
        }
        self.cold.retain(|e| keep(e));
        if self.cold.is_empty() {
            self.bar = None;
            return;
        }
        let k = BATCH.min(self.cold.len());
        self.cold.select_nth_unstable(k - 1);
        self.bar = Some(self.cold[k - 1]);
        self.hot.extend(self.cold.drain(..k).map(Reverse));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn pops_in_the_order_of_one_heap() {
        let mut rng = Rng::new(3);
        let mut q = CollapseQueue::with_capacity(0);
        let mut reference = BinaryHeap::new();
        let mut popped = 0;
        // Interleave pushes and pops over several refills; odd entries are "stale".
        for round in 0..40_000u32 {
            for _ in 0..3 {
                let e = (rng.below(50_000) as u32, round);
                q.push(e);
                if e.0 % 2 == 0 {
                    reference.push(Reverse(e));
                }
            }
            if round % 2 == 0 {
                loop {
                    let got = q.pop(|e| e.0 % 2 == 0);
                    match got {
                        Some(e) if e.0 % 2 == 1 => continue,
                        _ => {
                            if let Some(e) = got {
                                // What is left starts no lower.
                                let next = q.peek(|e| e.0 % 2 == 0).copied();
                                assert!(next.is_none_or(|n| n >= e));
                            }
                            assert_eq!(got, reference.pop().map(|Reverse(e)| e));
                            popped += 1;
                            break;
                        }
                    }
                }
            }
        }
        while let Some(e) = q.pop(|e| e.0 % 2 == 0) {
            if e.0 % 2 == 0 {
                assert_eq!(Some(e), reference.pop().map(|Reverse(e)| e));
                popped += 1;
            }
        }
        assert!(reference.is_empty());
        assert!(popped > 2 * BATCH, "the test must cross refills");
    }
}
