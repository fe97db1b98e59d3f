//! `silrig bench fmu FILE.fmu`: what one plant tick costs through an FMU's call path (set the inputs, `doStep`, get
//! the outputs: what the plant process does with an FMU each tick) beside the built-in F-16's tick (actuators, RK4,
//! outputs: [`silrig_adapters::builtin::f16_plant::F16Plant`]), both flown open loop from the scenario's initial condition with
//! their inputs held at what each announces as its failsafe hold (the F-16's trim). Each repeat is a fresh flight
//! whose set-up (unpacking, instantiation, trim) is not timed; the medians over repeats are reported.

use super::BenchFigure;
use silrig_adapters::builtin::f16_plant::F16Plant;
use silrig_adapters::fmu::plant::FmuPlant;
use silrig_flight::scenario::Scenario;
use silrig_rig::plant_model::PlantModel;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

/// The `silrig bench` subcommand that runs [`run`].
pub const SUBCOMMAND: &str = "fmu";

/// Arguments of `silrig bench fmu`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct FmuBenchArgs {
    /// The co-simulation FMU to time.
    pub fmu: PathBuf,
    /// Scenario (its `[plant.parameters]` go to the FMU, its initial condition to the built-in F-16); without it,
    /// the embedded default.
    pub config: Option<PathBuf>,
    /// Ticks flown per repeat.
    #[arg(long, default_value_t = 1000)]
    pub ticks: u64,
    /// Flights timed, each from its initial condition.
    #[arg(long, default_value_t = 30)]
    pub repeats: usize,
}

/// Per-tick time over `repeats` fresh flights of `ticks` ticks: `make` builds a flight (untimed), `tick` flies one
/// tick of it.
fn per_tick<P>(
    name: &str,
    ticks: u64,
    repeats: usize,
    mut make: impl FnMut() -> anyhow::Result<P>,
    mut tick: impl FnMut(&mut P) -> anyhow::Result<()>,
) -> anyhow::Result<BenchFigure> {
    let mut per_tick_ns = Vec::with_capacity(repeats);
    for _ in 0..repeats + 1 {
        let mut flight = make()?;
        let start = Instant::now();
        for _ in 0..ticks {
            tick(&mut flight)?;
        }
        per_tick_ns.push(start.elapsed().as_nanos() as f64 / ticks as f64);
    }
    // The first flight warms caches and pages up: not counted.
    per_tick_ns.remove(0);
    per_tick_ns.sort_by(f64::total_cmp);
    let q = |p: f64| per_tick_ns[((per_tick_ns.len() - 1) as f64 * p).round() as usize];
    Ok(BenchFigure {
        name: name.into(),
        median_ns: q(0.5),
        p10_ns: q(0.1),
        p90_ns: q(0.9),
        batch: ticks as usize,
        batches: repeats,
    })
}

/// Time both and say what an FMU tick costs against the built-in one.
pub fn run(args: &FmuBenchArgs) -> anyhow::Result<String> {
    anyhow::ensure!(args.ticks > 0 && args.repeats > 0, "--ticks and --repeats must be at least 1");
    let scenario = match &args.config {
        Some(path) => Scenario::load(path)?,
        None => Scenario::embedded_default(),
    };
    let mut f16_scenario = scenario.clone();
    f16_scenario.plant.parameters.clear();
    let builtin = per_tick(
        "plant tick, built-in F-16",
        args.ticks,
        args.repeats,
        || Ok((F16Plant::new(&f16_scenario)?, Vec::new())),
        |(plant, hold): &mut (F16Plant, Vec<f64>)| {
            if hold.is_empty() {
                *hold = plant.signals().hold();
            }
            black_box(plant.outputs());
            plant.step(hold, false).map(|_| ()).map_err(anyhow::Error::msg)
        },
    )?;
    let name = format!("plant tick, FMU {}", args.fmu.file_name().unwrap_or_default().to_string_lossy());
    let fmu = per_tick(
        &name,
        args.ticks,
        args.repeats,
        || {
            let plant = FmuPlant::open(&args.fmu, &scenario)?;
            let hold = plant.map.signals.hold();
            let outputs = vec![0.0; plant.map.output_refs.len()];
            Ok((plant, hold, outputs))
        },
        |(plant, hold, outputs): &mut (FmuPlant, Vec<f64>, Vec<f64>)| {
            plant.outputs(outputs).map_err(anyhow::Error::msg)?;
            black_box(&outputs);
            plant.step(hold).map_err(anyhow::Error::msg)
        },
    )?;
    Ok(format!(
        "{builtin}\n{fmu}\nFMU tick / built-in tick: {:.2} (medians; {} flights of {} ticks each)\n",
        fmu.median_ns / builtin.median_ns,
        args.repeats,
        args.ticks
    ))
}
