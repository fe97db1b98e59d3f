//! `silrig bench ipc`: the ceiling a lockstep rig can reach on this machine, measured as an iceoryx2 ping-pong
//! between two processes with the rig's own streams and ports (the plant's publish + notify, the controller's
//! listener wait, its answer, the plant's wait for it), and the lockstep rig measured right after it, as a ratio
//! to that ceiling. A lockstep cycle is one such round trip plus the plant's and controller's work and the logger
//! beside them, so the ratio says how much of the transport's speed the rig keeps.

use serde::Serialize;
use silrig_flight::role::Role;
use silrig_wire::clock::monotonic_ns;
use silrig_wire::ipc::{self, RunId, StreamSubscriber, WaitOutcome};
use silrig_wire::timing::{LatencyHistogram, LatencySummary, summary_line, summary_table_header};
use silrig_wire::topology::Stream;
use silrig_wire::wire::{CommandSample, PlantSample};
use std::process::{Command, Stdio};
use std::time::Duration;

/// The `silrig bench` subcommand that runs [`run`].
pub const SUBCOMMAND: &str = "ipc";

/// A ping unanswered this long ends the measurement with an error (the answering process died).
const ANSWER_TIMEOUT: Duration = Duration::from_secs(5);

/// Arguments of `silrig bench ipc`.
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct IpcBenchArgs {
    /// Round trips timed per repeat (after 1,000 untimed ones).
    #[arg(long, default_value_t = 20_000)]
    pub round_trips: u64,
    /// Lockstep rig ticks flown per repeat (0: measure the ceiling only).
    #[arg(long, default_value_t = 20_000)]
    pub lockstep_ticks: u64,
    /// Ping-pong and lockstep pairs, taken one after the other; the medians are reported.
    #[arg(long, default_value_t = 3)]
    pub repeats: u32,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Internal: answer the pings of the measuring process of this run id.
    #[arg(long, hide = true)]
    pub answer: Option<RunId>,
}

/// One ping-pong measurement.
#[derive(Debug, Clone, Serialize)]
pub struct PingPong {
    /// Round trips timed.
    pub round_trips: u64,
    /// Round trips per second.
    pub round_trips_per_s: f64,
    /// Round-trip time (publish of the ping to receipt of its answer), µs.
    pub round_trip: LatencySummary,
}

/// One lockstep rig run.
#[derive(Debug, Clone, Serialize)]
pub struct LockstepRun {
    /// Ticks flown.
    pub ticks: u64,
    /// Ticks per second of the plant's loop (first to last sample sent, from `timing.csv`).
    pub loop_cycles_per_s: f64,
    /// Ticks per second including the processes' start-up (the report's `cycles_per_s`).
    pub cycles_per_s_with_startup: f64,
}

/// What `silrig bench ipc` measured.
#[derive(Debug, Clone, Serialize)]
pub struct IpcBenchReport {
    /// Each ping-pong, in the order taken.
    pub ping_pongs: Vec<PingPong>,
    /// Each lockstep run, each taken right after the ping-pong of the same index.
    pub lockstep: Vec<LockstepRun>,
    /// Median round trips per second: the ceiling.
    pub ceiling_per_s: f64,
    /// Median lockstep loop cycles per second.
    pub lockstep_loop_per_s: Option<f64>,
    /// The lockstep loop rate over the ceiling.
    pub ratio: Option<f64>,
    /// Load averages at the start (1, 5, 15 min).
    pub load_average: [f64; 3],
    /// Online CPUs.
    pub cpu_count: usize,
}

fn median(mut v: Vec<f64>) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    (!v.is_empty()).then(|| v[v.len() / 2])
}

/// `silrig bench ipc`: measure (or, with `--answer`, be the answering process); returns what to print.
pub fn run(args: &IpcBenchArgs) -> anyhow::Result<String> {
    if let Some(run_id) = &args.answer {
        answer(run_id)?;
        return Ok(String::new());
    }
    silrig_rig::flag_in_range("round-trips", args.round_trips as f64, 100.0, 1e8, "round trips")
        .map_err(|e| anyhow::anyhow!(e))?;
    silrig_rig::flag_in_range("repeats", f64::from(args.repeats), 1.0, 100.0, "repeats")
        .map_err(|e| anyhow::anyhow!(e))?;
    anyhow::ensure!(
        args.lockstep_ticks == 0 || args.lockstep_ticks >= 100,
        "--lockstep-ticks must be 0 (no rig) or at least 100, got {}",
        args.lockstep_ticks
    );
    let conditions = silrig_rig::report::MachineConditions::now();
    let mut ping_pongs = Vec::new();
    let mut lockstep = Vec::new();
    for _ in 0..args.repeats {
        ping_pongs.push(ping_pong(args.round_trips)?);
        if args.lockstep_ticks > 0 {
            lockstep.push(lockstep_run(args.lockstep_ticks)?);
        }
    }
    let ceiling_per_s = median(ping_pongs.iter().map(|p| p.round_trips_per_s).collect()).unwrap_or(0.0);
    let lockstep_loop_per_s = median(lockstep.iter().map(|l| l.loop_cycles_per_s).collect());
    let report = IpcBenchReport {
        ratio: lockstep_loop_per_s.map(|l| l / ceiling_per_s),
        ping_pongs,
        lockstep,
        ceiling_per_s,
        lockstep_loop_per_s,
        load_average: conditions.load_average,
        cpu_count: conditions.cpu_count,
    };
    Ok(if args.json { serde_json::to_string_pretty(&report)? + "\n" } else { report.to_text() })
}

impl IpcBenchReport {
    /// The figures as a person reads them.
    pub fn to_text(&self) -> String {
        let mut out = format!(
            "ipc ping-pong between two processes (rig streams: publish + notify, listener wait, answer), {} CPUs, \
             load average {:.2} {:.2} {:.2}\n{}\n",
            self.cpu_count,
            self.load_average[0],
            self.load_average[1],
            self.load_average[2],
            summary_table_header()
        );
        for (k, p) in self.ping_pongs.iter().enumerate() {
            out += &format!(
                "{}   {:.0} round trips/s\n",
                summary_line(&format!("round trip #{}", k + 1), &p.round_trip),
                p.round_trips_per_s
            );
        }
        out += &format!("ceiling: {:.0} round trips/s (median of {})\n", self.ceiling_per_s, self.ping_pongs.len());
        for (k, l) in self.lockstep.iter().enumerate() {
            out += &format!(
                "lockstep rig #{}: {} ticks, {:.0} cycles/s in the loop, {:.0} cycles/s with start-up\n",
                k + 1,
                l.ticks,
                l.loop_cycles_per_s,
                l.cycles_per_s_with_startup
            );
        }
        if let (Some(l), Some(r)) = (self.lockstep_loop_per_s, self.ratio) {
            out += &format!("lockstep: {l:.0} cycles/s (median), {r:.2} of the ipc ceiling\n");
        }
        out
    }
}

/// A run id of this process for one measurement.
fn bench_run_id(what: &str) -> RunId {
    RunId::new(&format!("bench-{what}-{}", std::process::id())).expect("a valid run id")
}

/// Time `round_trips` ping-pongs against an answering child process (after 1,000 untimed ones).
fn ping_pong(round_trips: u64) -> anyhow::Result<PingPong> {
    let run_id = bench_run_id("ipc");
    let result = ping_pong_in(&run_id, round_trips);
    // The child has ended (or been killed) by now; its node and ours are gone.
    let _ = ipc::cleanup_run(&run_id);
    result
}

fn ping_pong_in(run_id: &RunId, round_trips: u64) -> anyhow::Result<PingPong> {
    let node = ipc::create_node(run_id, Role::Plant.label())?;
    let pings = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
    let answers = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
    let mut publisher = pings.publisher()?;
    let subscriber = answers.subscriber(Stream::Command.queue_depth(Role::Plant))?;
    let mut child = Command::new(std::env::current_exe()?)
        .args(["bench", SUBCOMMAND, "--answer", run_id.as_str()])
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .spawn()?;
    let measured = (|| {
        let deadline = monotonic_ns() + ANSWER_TIMEOUT.as_nanos() as u64;
        while pings.number_of_subscribers() < 1 || answers.number_of_publishers() < 1 {
            anyhow::ensure!(
                monotonic_ns() < deadline,
                "the answering process did not connect within {ANSWER_TIMEOUT:?}"
            );
            if child.try_wait()?.is_some() {
                anyhow::bail!("the answering process ended before it connected");
            }
            std::thread::sleep(Duration::from_millis(2));
        }
        let mut hist = LatencyHistogram::new();
        let mut ping = PlantSample::zeroed();
        for tick in 0..1_000 {
            round_trip(&mut publisher, &subscriber, &mut ping, tick)?;
        }
        let start = monotonic_ns();
        for tick in 1_000..1_000 + round_trips {
            hist.record_ns(round_trip(&mut publisher, &subscriber, &mut ping, tick)? as i64);
        }
        let elapsed_s = (monotonic_ns() - start) as f64 / 1e9;
        Ok(PingPong { round_trips, round_trips_per_s: round_trips as f64 / elapsed_s, round_trip: hist.summary() })
    })();
    let _ = publisher.announce_finished();
    let deadline = monotonic_ns() + ANSWER_TIMEOUT.as_nanos() as u64;
    while child.try_wait()?.is_none() {
        if monotonic_ns() > deadline {
            child.kill()?;
            child.wait()?;
            break;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    measured
}

/// One ping and its answer, as the lockstep plant does it: publish, then block on the answer's listener (no
/// polling); returns the round-trip time, ns.
fn round_trip(
    publisher: &mut ipc::StreamPublisher<PlantSample>,
    answers: &StreamSubscriber<CommandSample>,
    ping: &mut PlantSample,
    tick: u64,
) -> anyhow::Result<u64> {
    ping.t_sim_s = tick as f64;
    let sent = publisher.send(tick, ping)?;
    let deadline = sent.t_send_ns + ANSWER_TIMEOUT.as_nanos() as u64;
    loop {
        let mut answered = false;
        answers.drain(|r| answered |= r.sample.answers_tick == tick)?;
        if answered {
            return Ok(monotonic_ns() - sent.t_send_ns);
        }
        anyhow::ensure!(monotonic_ns() < deadline, "no answer to ping {tick} within {ANSWER_TIMEOUT:?}");
        answers.wait_readable_until(deadline);
    }
}

/// The answering process: wait on the ping stream's listener as the controller does, answer each ping at once,
/// end when the measuring process says it has finished (or is silent for [`ANSWER_TIMEOUT`]).
fn answer(run_id: &RunId) -> anyhow::Result<()> {
    let node = ipc::create_node(run_id, Role::Controller.label())?;
    let pings = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
    let answers = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
    let subscriber = pings.subscriber(Stream::Plant.queue_depth(Role::Controller))?;
    let mut publisher = answers.publisher()?;
    let mut reply = CommandSample::zeroed();
    loop {
        match subscriber.wait(ANSWER_TIMEOUT)? {
            WaitOutcome::TimedOut => anyhow::bail!("no ping within {ANSWER_TIMEOUT:?}"),
            WaitOutcome::Interrupted => continue,
            WaitOutcome::Notified => {}
        }
        let mut newest = None;
        subscriber.drain(|r| newest = Some(r.sample.header.tick))?;
        if subscriber.stats().finished_notices > 0 {
            return Ok(());
        }
        if let Some(tick) = newest {
            reply.answers_tick = tick;
            publisher.send(tick, &reply)?;
        }
    }
}

/// A lockstep rig run of `ticks` ticks through the launcher, in a temporary folder removed afterwards.
fn lockstep_run(ticks: u64) -> anyhow::Result<LockstepRun> {
    use clap::Parser;
    #[derive(Parser)]
    struct Launch {
        #[command(flatten)]
        opts: silrig_launch::launcher::LaunchOptions,
    }
    let run_id = bench_run_id("lockstep");
    let out = std::env::temp_dir().join(format!("silrig-{run_id}"));
    let _ = std::fs::remove_dir_all(&out);
    let scenario = silrig_flight::scenario::Scenario::embedded_default();
    let duration_s = (ticks - 1) as f64 * scenario.timing.dt_s;
    let argv = ["silrig-run", "--mode", "lockstep", "--duration-s", &duration_s.to_string(), "--run-id"]
        .map(String::from)
        .into_iter()
        .chain([run_id.to_string(), "--out".into(), out.display().to_string(), "--quiet".into()]);
    let launch = Launch::try_parse_from(argv)?;
    let result = (|| {
        let report = silrig_launch::launcher::run(&launch.opts)?;
        anyhow::ensure!(report.failures.is_empty(), "the lockstep run failed: {}", report.failures.join("; "));
        let timing = std::fs::read_to_string(out.join("timing.csv"))?;
        let sends: Vec<u64> = timing.lines().skip(1).filter_map(|l| l.split(',').nth(3)?.parse().ok()).collect();
        let (first, last) = (sends.first().copied().unwrap_or(0), sends.last().copied().unwrap_or(0));
        anyhow::ensure!(sends.len() >= 2 && last > first, "the lockstep run logged no ticks");
        Ok(LockstepRun {
            ticks: sends.len() as u64,
            loop_cycles_per_s: (sends.len() - 1) as f64 / ((last - first) as f64 / 1e9),
            cycles_per_s_with_startup: report.cycles_per_s,
        })
    })();
    let _ = std::fs::remove_dir_all(&out);
    result
}
