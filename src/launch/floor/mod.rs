//! The OS timer floor a run's timing is read against: [`timer_baseline`] (a bare absolute-deadline loop of ours,
//! also `silrig timer-baseline`) and [`cyclictest`] (rt-tests' own, for `silrig run --floor cyclictest`).

pub mod cyclictest;
pub mod timer_baseline;
