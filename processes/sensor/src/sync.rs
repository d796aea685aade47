//! Pairs two streams of stamped samples (own `pose_true` and `twist_true`) by equal stamps.
//!
//! Physics publishes both with the same stamp in the same step, but they arrive on separate
//! topics, so one may be visible a step before the other. The IMU needs both for one
//! instant; pairing by stamp, instead of taking the latest of each, never mixes instants.

use std::collections::VecDeque;

/// Samples waiting for their partner; stamps are assumed to increase within each stream.
pub struct Pairer<A, B> {
    a: VecDeque<(u64, A)>,
    b: VecDeque<(u64, B)>,
    capacity: usize,
}

impl<A, B> Pairer<A, B> {
    /// Keeps at most `capacity` unpaired samples per stream (the oldest go first).
    pub fn new(capacity: usize) -> Self {
        Self {
            a: VecDeque::with_capacity(capacity + 1),
            b: VecDeque::with_capacity(capacity + 1),
            capacity,
        }
    }

    pub fn push_a(&mut self, stamp: u64, value: A) {
        self.a.push_back((stamp, value));
        if self.a.len() > self.capacity {
            self.a.pop_front();
        }
    }

    pub fn push_b(&mut self, stamp: u64, value: B) {
        self.b.push_back((stamp, value));
        if self.b.len() > self.capacity {
            self.b.pop_front();
        }
    }

    /// The oldest pair with equal stamps. Samples older than the other stream's oldest can
    /// no longer find a partner and are dropped.
    pub fn pop(&mut self) -> Option<(u64, A, B)> {
        loop {
            let (sa, sb) = (self.a.front()?.0, self.b.front()?.0);
            if sa < sb {
                self.a.pop_front();
            } else if sb < sa {
                self.b.pop_front();
            } else {
                let (_, a) = self.a.pop_front()?;
                let (_, b) = self.b.pop_front()?;
                return Some((sa, a, b));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pairs_equal_stamps_and_drops_orphans() {
        let mut p = Pairer::new(4);
        p.push_a(10, 'a');
        assert_eq!(p.pop(), None);
        p.push_b(10, 1);
        assert_eq!(p.pop(), Some((10, 'a', 1)));
        // b lost stamp 20; a's 20 is dropped once b shows 30.
        p.push_a(20, 'b');
        p.push_a(30, 'c');
        p.push_b(30, 3);
        assert_eq!(p.pop(), Some((30, 'c', 3)));
        assert_eq!(p.pop(), None);
        for s in 0..10 {
            p.push_a(100 + s, 'x');
        }
        assert_eq!(p.a.len(), 4);
    }
}
