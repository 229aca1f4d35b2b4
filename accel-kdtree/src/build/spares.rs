//! Spare buffers of one serial build: the lists a split consumes (its
//! primitive list, its destination words, the straddlers' events) and the
//! lists of the leaves it ends in are kept and handed to the next split
//! instead of being freed and allocated anew. A build makes about a dozen
//! lists per node, and the allocator's share of the build was about 8% of
//! its instructions (callgrind, 200k-triangle terrain).

use super::events::Event;
use super::sah::{Plane, Planes};
use super::split::NodeWork;

/// How many spare lists of each kind are kept; more are freed.
const KEEP: usize = 64;

/// Cleared lists with capacity, ready for reuse.
#[derive(Debug)]
pub(crate) struct Spares<T> {
    events: Vec<Vec<Event<T>>>,
    words: Vec<Vec<u32>>,
    planes: Vec<Vec<Plane<T>>>,
}

impl<T> Default for Spares<T> {
    fn default() -> Self {
        Self {
            events: Vec::new(),
            words: Vec::new(),
            planes: Vec::new(),
        }
    }
}

impl<T> Spares<T> {
    /// An empty event list, recycled when one is spare.
    #[inline]
    pub(crate) fn events(&mut self) -> Vec<Event<T>> {
        self.events.pop().unwrap_or_default()
    }

    /// An empty word list, recycled when one is spare.
    #[inline]
    pub(crate) fn words(&mut self) -> Vec<u32> {
        self.words.pop().unwrap_or_default()
    }

    /// Three empty plane lists, recycled where spare.
    #[inline]
    pub(crate) fn planes(&mut self) -> Planes<T> {
        [(); 3].map(|()| self.planes.pop().unwrap_or_default())
    }

    /// Keeps the plane lists for reuse (emptied), or frees them when enough
    /// are kept.
    #[inline]
    pub(crate) fn give_planes(&mut self, planes: Planes<T>) {
        for mut list in planes {
            if list.capacity() > 0 && self.planes.len() < KEEP {
                list.clear();
                self.planes.push(list);
            }
        }
    }

    /// Keeps `list` for reuse (emptied), or frees it when enough are kept.
    #[inline]
    pub(crate) fn give_events(&mut self, mut list: Vec<Event<T>>) {
        if list.capacity() > 0 && self.events.len() < KEEP {
            list.clear();
            self.events.push(list);
        }
    }

    /// Keeps `list` for reuse (emptied), or frees it when enough are kept.
    #[inline]
    pub(crate) fn give_words(&mut self, mut list: Vec<u32>) {
        if list.capacity() > 0 && self.words.len() < KEEP {
            list.clear();
            self.words.push(list);
        }
    }

    /// Keeps the lists of a node that became a leaf.
    pub(crate) fn recycle(&mut self, node: NodeWork<T>) {
        self.give_words(node.prims);
        for list in node.events {
            self.give_events(list);
        }
        if let Some(planes) = node.planes {
            self.give_planes(planes);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn given_lists_come_back_empty_with_their_capacity() {
        let mut spares = Spares::<f32>::default();
        spares.give_words(vec![1, 2, 3]);
        let w = spares.words();
        assert!(w.is_empty());
        assert!(w.capacity() >= 3);
        // Nothing spare: a new, empty list.
        assert_eq!(spares.words().capacity(), 0);
        let mut e = Vec::with_capacity(5);
        e.push(Event::new(1.0f32, 0, 0));
        spares.give_events(e);
        let e = spares.events();
        assert!(e.is_empty() && e.capacity() >= 5);
    }

    #[test]
    fn at_most_keep_lists_are_kept() {
        let mut spares = Spares::<f64>::default();
        for _ in 0..KEEP + 10 {
            spares.give_words(Vec::with_capacity(1));
        }
        assert_eq!(spares.words.len(), KEEP);
    }
}
