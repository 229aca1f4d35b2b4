//! Mailboxing without shared state: a tiny per-query cache of tested primitives.

/// Remembers the most recently tested primitives of one query, so that a
/// primitive referenced by several cells or leaves along a ray is tested once
/// (Amanatides & Woo 1987; Wald 2004 for the per-ray variant).
///
/// It lives on the query's stack: queries run in parallel with no shared
/// mutable state. It is direct-mapped and lossy: a collision only means a
/// repeated test, which gives the same answer, so correctness never depends on it.
#[derive(Clone, Debug)]
pub struct Mailbox {
    slots: [u32; Self::SLOTS],
}

impl Default for Mailbox {
    fn default() -> Self {
        Self::new()
    }
}

impl Mailbox {
    /// Number of remembered primitives.
    pub const SLOTS: usize = 16;

    /// An empty mailbox.
    #[inline]
    #[must_use]
    pub const fn new() -> Self {
        Self {
            slots: [u32::MAX; Self::SLOTS],
        }
    }

    /// Records `prim` and tells whether it was already recorded (then the
    /// caller skips the test).
    #[inline]
    pub fn seen(&mut self, prim: u32) -> bool {
        let slot = &mut self.slots[prim as usize & (Self::SLOTS - 1)];
        if *slot == prim {
            true
        } else {
            *slot = prim;
            false
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remembers_until_evicted() {
        let mut m = Mailbox::new();
        assert!(!m.seen(3));
        assert!(m.seen(3));
        assert!(!m.seen(3 + Mailbox::SLOTS as u32)); // same slot: evicts 3
        assert!(!m.seen(3));
        assert!(!m.seen(u32::MAX - 1));
    }
}
