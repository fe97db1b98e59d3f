//! The logger's samples waiting for their partner, by tick: a queue kept in tick order. Samples come almost always
//! in order and leave from the front, so each is moved once on the way in and once on the way out; a `BTreeMap`
//! shifted the rest of its leaf at every removal from the front (a command sample is about 700 bytes: 7 % of a
//! lockstep logger's time went to those moves, inserts and removals).

use std::collections::VecDeque;

/// Values by tick, in tick order; one value a tick (a second insert of a tick replaces the first, as a map does).
#[derive(Debug)]
pub struct TickQueue<T> {
    entries: VecDeque<(u64, T)>,
}

impl<T> Default for TickQueue<T> {
    fn default() -> Self {
        Self { entries: VecDeque::new() }
    }
}

impl<T> TickQueue<T> {
    /// Where `tick` is, or where it would go.
    fn search(&self, tick: u64) -> Result<usize, usize> {
        // The usual cases first, without the search: a tick newer than all (an arrival), and ticks without a gap
        // (then tick k is k - first places in).
        let (Some((first, _)), Some((last, _))) = (self.entries.front(), self.entries.back()) else { return Err(0) };
        if *last < tick {
            return Err(self.entries.len());
        }
        let guess = tick.wrapping_sub(*first);
        if guess < self.entries.len() as u64 && self.entries[guess as usize].0 == tick {
            return Ok(guess as usize);
        }
        self.entries.binary_search_by_key(&tick, |(t, _)| *t)
    }

    /// Keep `value` for `tick`, replacing what was kept for it.
    pub fn insert(&mut self, tick: u64, value: T) {
        match self.search(tick) {
            Ok(at) => self.entries[at].1 = value,
            Err(at) if at == self.entries.len() => self.entries.push_back((tick, value)),
            Err(at) => self.entries.insert(at, (tick, value)),
        }
    }

    /// The value of `tick`, if kept.
    pub fn get(&self, tick: u64) -> Option<&T> {
        self.search(tick).ok().map(|at| &self.entries[at].1)
    }

    /// Whether a value of `tick` is kept.
    pub fn contains(&self, tick: u64) -> bool {
        self.search(tick).is_ok()
    }

    /// Take the value of `tick` out, if kept.
    pub fn remove(&mut self, tick: u64) -> Option<T> {
        let at = self.search(tick).ok()?;
        self.entries.remove(at).map(|(_, value)| value)
    }

    /// The oldest tick kept.
    pub fn first_tick(&self) -> Option<u64> {
        self.entries.front().map(|(t, _)| *t)
    }

    /// The newest tick kept.
    pub fn last_tick(&self) -> Option<u64> {
        self.entries.back().map(|(t, _)| *t)
    }

    /// Drop every value of a tick up to `tick`.
    pub fn drop_through(&mut self, tick: u64) {
        while self.first_tick().is_some_and(|t| t <= tick) {
            self.entries.pop_front();
        }
    }

    /// Values kept.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether none is kept.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn it_keeps_tick_order_and_one_value_a_tick_as_a_map_does_whatever_the_order_of_arrival() {
        let mut q = TickQueue::default();
        let mut map = std::collections::BTreeMap::new();
        // In order, then late, repeated and out-of-order ticks.
        for (tick, value) in [(3, 'a'), (4, 'b'), (6, 'c'), (5, 'd'), (1, 'e'), (4, 'f'), (9, 'g'), (2, 'h')] {
            q.insert(tick, value);
            map.insert(tick, value);
            assert_eq!((q.first_tick(), q.last_tick()), (map.keys().next().copied(), map.keys().last().copied()));
            assert_eq!(q.len(), map.len());
        }
        for tick in 0..11 {
            assert_eq!(q.get(tick), map.get(&tick), "tick {tick}");
            assert_eq!(q.contains(tick), map.contains_key(&tick), "tick {tick}");
        }
        assert_eq!(q.remove(5), Some('d'));
        assert_eq!(q.remove(5), None);
        assert_eq!(q.remove(1), Some('e'));
        q.drop_through(4);
        assert_eq!(q.entries.iter().copied().collect::<Vec<_>>(), [(6, 'c'), (9, 'g')]);
        q.drop_through(9);
        assert!(q.is_empty());
        assert_eq!((q.first_tick(), q.last_tick(), q.get(6)), (None, None, None));
    }
}
