//! When each recent tick went out, by tick ([`TickStamps`]): the plant side times a plant sample to the command
//! answering it, the controller side times the tick's stay on its host. A fixed ring of [`STAMPS`] ticks: a
//! command that lags more than that is not timed.

/// Plant-sample send stamps kept for the network leg (ticks a command may lag and still be timed).
const STAMPS: usize = 64;

/// Send stamps of recent ticks, by tick.
#[derive(Debug)]
pub(super) struct TickStamps([(u64, u64); STAMPS]);

impl TickStamps {
    pub(super) fn new() -> Self {
        Self([(u64::MAX, 0); STAMPS])
    }

    pub(super) fn put(&mut self, tick: u64, t_ns: u64) {
        self.0[(tick % STAMPS as u64) as usize] = (tick, t_ns);
    }

    pub(super) fn get(&self, tick: u64) -> Option<u64> {
        let (t, at) = self.0[(tick % STAMPS as u64) as usize];
        (t == tick).then_some(at)
    }
}
