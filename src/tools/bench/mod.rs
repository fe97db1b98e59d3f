//! Benchmarks run by `silrig bench`: the cost of one plant derivative, one RK4 step, and closed-loop steps per
//! second in one process. Each figure is the median (and spread) of many batches, so one descheduled batch on a
//! shared machine does not move it. Beside them, the transport's ping-pong ceiling with the lockstep rig against it
//! ([`ipc`]), and one plant tick through an FMU against the built-in F-16's ([`fmu`]); the OS timer floor, ours and cyclictest's, is `silrig_launch::floor`, since `silrig run --floor` takes it
//! beside a run.

pub mod fmu;
pub mod ipc;

use serde::Serialize;
use silrig_model::integrator::rk4_step;
use silrig_model::plant::{ExternalForcing, F16Model, trim::trim_level_flight};
use std::hint::black_box;
use std::time::Instant;

/// Timing of one operation.
#[derive(Debug, Clone, Serialize)]
pub struct BenchFigure {
    /// What was timed.
    pub name: String,
    /// Median time per operation over batches, ns.
    pub median_ns: f64,
    /// 10th percentile over batches, ns.
    pub p10_ns: f64,
    /// 90th percentile over batches, ns.
    pub p90_ns: f64,
    /// Operations per batch.
    pub batch: usize,
    /// Batches timed.
    pub batches: usize,
}

impl std::fmt::Display for BenchFigure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:<28} median {:>9.1} ns   p10 {:>9.1} ns   p90 {:>9.1} ns   ({} batches of {})",
            self.name, self.median_ns, self.p10_ns, self.p90_ns, self.batches, self.batch
        )
    }
}

/// Time `op` in `batches` batches of `batch` calls each, after one warm-up batch.
pub fn measure(name: &str, batch: usize, batches: usize, mut op: impl FnMut()) -> BenchFigure {
    for _ in 0..batch {
        op();
    }
    let mut per_op: Vec<f64> = (0..batches)
        .map(|_| {
            let start = Instant::now();
            for _ in 0..batch {
                op();
            }
            start.elapsed().as_nanos() as f64 / batch as f64
        })
        .collect();
    per_op.sort_by(f64::total_cmp);
    let q = |p: f64| per_op[((per_op.len() - 1) as f64 * p).round() as usize];
    BenchFigure { name: name.into(), median_ns: q(0.5), p10_ns: q(0.1), p90_ns: q(0.9), batch, batches }
}

/// One derivative evaluation and one RK4 step of the full model at the 150 m/s, 25,000 ft trim.
pub fn plant_figures() -> Vec<BenchFigure> {
    let model = F16Model::default();
    let trim =
        trim_level_flight(&model, silrig_model::units::m_to_ft(150.0), 25_000.0).expect("the benchmark trim exists");
    let forcing = ExternalForcing::default();
    let (x0, u) = (trim.state, trim.controls);
    let derivative = measure("plant derivative", 10_000, 200, || {
        black_box(model.derivative(black_box(&x0), black_box(&u), &forcing));
    });
    let mut x = x0.to_array();
    let rk4 = measure("plant RK4 step (dt 0.01 s)", 10_000, 200, || {
        x = rk4_step(
            |_, s| model.derivative(&silrig_model::plant::F16State::from_array(s), &u, &forcing),
            0.0,
            black_box(&x),
            0.01,
        );
    });
    vec![derivative, rk4]
}

/// Closed-loop ticks per second in one process (plant, actuators, controller and trace recording) on the embedded
/// default scenario stretched to 60 s, as the median of `repeats` runs.
pub fn closed_loop_figure(repeats: usize) -> BenchFigure {
    let mut scenario = silrig_flight::scenario::Scenario::embedded_default();
    scenario.timing.duration_s = 60.0;
    let ticks = scenario.timing.ticks() as usize;
    let figure = measure("closed-loop tick (sim)", 1, repeats, || {
        black_box(silrig_flight::sim::run(&scenario).expect("the default scenario runs"));
    });
    let per_tick = |ns: f64| ns / ticks as f64;
    BenchFigure {
        median_ns: per_tick(figure.median_ns),
        p10_ns: per_tick(figure.p10_ns),
        p90_ns: per_tick(figure.p90_ns),
        batch: ticks,
        ..figure
    }
}
