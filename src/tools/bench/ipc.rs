//! `silrig bench ipc`: the ceiling a lockstep rig can reach on this machine, measured as an iceoryx2 ping-pong
//! between two processes with the rig's own streams and ports (the plant's publish + notify, the controller's
//! listener wait, its answer, the plant's wait for it), and the lockstep rig measured right after it, as a ratio
//! to that ceiling. A lockstep cycle is one such round trip plus the plant's and controller's work and the logger
//! beside them, so the ratio says how much of the transport's speed the rig keeps.
//!
//! The ping-pong is taken two ways in each repeat, because how a process waits decides what a round trip costs:
//! [`WaitStrategy::Block`] (take what waits, then sleep on the listener: what the lockstep plant and controller
//! do, and what an idle machine pays two vCPU wake-ups a round trip for) and [`WaitStrategy::Poll`] (look again
//! and again, yielding the CPU between looks, for [`POLL_SPIN_NS`] before sleeping, so an answer that comes quickly is taken by a process still
//! on its CPU: the transport's own cost). The rig's three processes keep the vCPUs busier than a bare ping-pong,
//! so lockstep can beat the blocking figure; the polling one is the ceiling no wait strategy gets past.

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

/// How a side of the ping-pong waits for the other's message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum WaitStrategy {
    /// Take what waits, then sleep on the listener until notified (the lockstep rig's plant and controller).
    Block,
    /// Look again and again for [`POLL_SPIN_NS`] (yielding the CPU between looks), then sleep on the listener.
    Poll,
}

impl WaitStrategy {
    fn label(self) -> &'static str {
        match self {
            WaitStrategy::Block => "block",
            WaitStrategy::Poll => "poll",
        }
    }

    /// How long to keep looking before sleeping, ns.
    fn spin_ns(self) -> u64 {
        match self {
            WaitStrategy::Block => 0,
            WaitStrategy::Poll => POLL_SPIN_NS,
        }
    }
}

/// [`WaitStrategy::Poll`]: how long a side looks for the other's message before it sleeps, ns (a round trip
/// of a polling pair takes well under this).
pub const POLL_SPIN_NS: u64 = 200_000;

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
    /// Internal: how the answering process waits.
    #[arg(long, hide = true, value_enum, default_value_t = WaitStrategy::Block)]
    pub answer_wait: WaitStrategy,
}

/// One ping-pong measurement.
#[derive(Debug, Clone, Serialize)]
pub struct PingPong {
    /// How both sides waited.
    pub wait: WaitStrategy,
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
    /// Each ping-pong, in the order taken (blocking, then polling, in each repeat).
    pub ping_pongs: Vec<PingPong>,
    /// Each lockstep run, each taken right after the ping-pongs of its repeat.
    pub lockstep: Vec<LockstepRun>,
    /// Median round trips per second of the blocking ping-pong: what two processes that sleep on every wait reach.
    pub blocking_per_s: f64,
    /// Median round trips per second of the polling ping-pong: the ceiling.
    pub ceiling_per_s: f64,
    /// Median lockstep loop cycles per second.
    pub lockstep_loop_per_s: Option<f64>,
    /// The lockstep loop rate over the ceiling (the polling ping-pong).
    pub ratio: Option<f64>,
    /// The lockstep loop rate over the blocking ping-pong.
    pub ratio_to_blocking: Option<f64>,
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
        answer(run_id, args.answer_wait)?;
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
        for wait in [WaitStrategy::Block, WaitStrategy::Poll] {
            ping_pongs.push(ping_pong(args.round_trips, wait)?);
        }
        if args.lockstep_ticks > 0 {
            lockstep.push(lockstep_run(args.lockstep_ticks)?);
        }
    }
    let rate = |wait| {
        median(ping_pongs.iter().filter(|p| p.wait == wait).map(|p| p.round_trips_per_s).collect()).unwrap_or(0.0)
    };
    let (blocking_per_s, ceiling_per_s) = (rate(WaitStrategy::Block), rate(WaitStrategy::Poll));
    let lockstep_loop_per_s = median(lockstep.iter().map(|l| l.loop_cycles_per_s).collect());
    let report = IpcBenchReport {
        ratio: lockstep_loop_per_s.map(|l| l / ceiling_per_s),
        ratio_to_blocking: lockstep_loop_per_s.map(|l| l / blocking_per_s),
        ping_pongs,
        lockstep,
        blocking_per_s,
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
             load average {:.2} {:.2} {:.2}\nblock: each side sleeps on its listener; poll: each side looks for \
             {} us before it sleeps\n{}\n",
            self.cpu_count,
            self.load_average[0],
            self.load_average[1],
            self.load_average[2],
            POLL_SPIN_NS / 1_000,
            summary_table_header()
        );
        for (k, p) in self.ping_pongs.iter().enumerate() {
            out += &format!(
                "{}   {:.0} round trips/s\n",
                summary_line(&format!("{} #{}", p.wait.label(), k / 2 + 1), &p.round_trip),
                p.round_trips_per_s
            );
        }
        let n = self.ping_pongs.len() / 2;
        out += &format!("blocking ping-pong: {:.0} round trips/s (median of {n})\n", self.blocking_per_s);
        out += &format!("ceiling (polling ping-pong): {:.0} round trips/s (median of {n})\n", self.ceiling_per_s);
        for (k, l) in self.lockstep.iter().enumerate() {
            out += &format!(
                "lockstep rig #{}: {} ticks, {:.0} cycles/s in the loop, {:.0} cycles/s with start-up\n",
                k + 1,
                l.ticks,
                l.loop_cycles_per_s,
                l.cycles_per_s_with_startup
            );
        }
        if let (Some(l), Some(r), Some(b)) = (self.lockstep_loop_per_s, self.ratio, self.ratio_to_blocking) {
            out += &format!(
                "lockstep: {l:.0} cycles/s (median), {r:.2} of the ceiling ({b:.2} of the blocking ping-pong)\n"
            );
        }
        out
    }
}

/// A run id of this process for one measurement.
fn bench_run_id(what: &str) -> RunId {
    RunId::new(&format!("bench-{what}-{}", std::process::id())).expect("a valid run id")
}

/// Time `round_trips` ping-pongs against an answering child process (after 1,000 untimed ones), both sides
/// waiting the `wait` way.
fn ping_pong(round_trips: u64, wait: WaitStrategy) -> anyhow::Result<PingPong> {
    let run_id = bench_run_id("ipc");
    let result = ping_pong_in(&run_id, round_trips, wait);
    // The child has ended (or been killed) by now; its node and ours are gone.
    let _ = ipc::cleanup_run(&run_id);
    result
}

fn ping_pong_in(run_id: &RunId, round_trips: u64, wait: WaitStrategy) -> anyhow::Result<PingPong> {
    let node = ipc::create_node(run_id, Role::Plant.label())?;
    let pings = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
    let answers = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
    let mut publisher = pings.publisher()?;
    let subscriber = answers.subscriber(Stream::Command.queue_depth(Role::Plant))?;
    let mut child = Command::new(std::env::current_exe()?)
        .args(["bench", SUBCOMMAND, "--answer", run_id.as_str(), "--answer-wait", wait.label()])
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
            round_trip(&mut publisher, &subscriber, &mut ping, tick, wait)?;
        }
        let start = monotonic_ns();
        for tick in 1_000..1_000 + round_trips {
            hist.record_ns(round_trip(&mut publisher, &subscriber, &mut ping, tick, wait)? as i64);
        }
        let elapsed_s = (monotonic_ns() - start) as f64 / 1e9;
        Ok(PingPong {
            wait,
            round_trips,
            round_trips_per_s: round_trips as f64 / elapsed_s,
            round_trip: hist.summary(),
        })
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

/// One ping and its answer, as the lockstep plant does it: publish, take what waits, and (with
/// [`WaitStrategy::Poll`] after looking again for its spin time) block on the answer's listener; returns the
/// round-trip time, ns.
fn round_trip(
    publisher: &mut ipc::StreamPublisher<PlantSample>,
    answers: &StreamSubscriber<CommandSample>,
    ping: &mut PlantSample,
    tick: u64,
    wait: WaitStrategy,
) -> anyhow::Result<u64> {
    ping.t_sim_s = tick as f64;
    let sent = publisher.send(tick, ping)?;
    let deadline = sent.t_send_ns + ANSWER_TIMEOUT.as_nanos() as u64;
    let spin_until = sent.t_send_ns + wait.spin_ns();
    loop {
        let mut answered = false;
        answers.drain(|r| answered |= r.sample.answers_tick == tick)?;
        let now = monotonic_ns();
        if answered {
            return Ok(now - sent.t_send_ns);
        }
        anyhow::ensure!(now < deadline, "no answer to ping {tick} within {ANSWER_TIMEOUT:?}");
        if now < spin_until {
            // Yield rather than spin: on a busy machine the answer may need this very CPU.
            std::thread::yield_now();
            continue;
        }
        answers.wait_readable_until(deadline);
    }
}

/// The answering process: wait on the ping stream's listener as the controller does (with [`WaitStrategy::Poll`],
/// after looking again for its spin time since its last answer), answer each ping at once, end when the measuring
/// process says it has finished (or is silent for [`ANSWER_TIMEOUT`]).
fn answer(run_id: &RunId, wait: WaitStrategy) -> anyhow::Result<()> {
    let node = ipc::create_node(run_id, Role::Controller.label())?;
    let pings = ipc::open_stream::<PlantSample>(&node, Stream::Plant)?;
    let answers = ipc::open_stream::<CommandSample>(&node, Stream::Command)?;
    let subscriber = pings.subscriber(Stream::Plant.queue_depth(Role::Controller))?;
    let mut publisher = answers.publisher()?;
    let mut reply = CommandSample::zeroed();
    let mut spin_until = monotonic_ns() + wait.spin_ns();
    loop {
        if monotonic_ns() < spin_until {
            // Polling: look without sleeping (yielding the CPU to whoever waits for it); the drain below takes
            // whatever came.
            std::thread::yield_now();
        } else {
            match subscriber.wait(ANSWER_TIMEOUT)? {
                WaitOutcome::TimedOut => anyhow::bail!("no ping within {ANSWER_TIMEOUT:?}"),
                WaitOutcome::Interrupted => continue,
                WaitOutcome::Notified => {}
            }
        }
        let mut newest = None;
        subscriber.drain(|r| newest = Some(r.sample.header.tick))?;
        if subscriber.stats().finished_notices > 0 {
            return Ok(());
        }
        if let Some(tick) = newest {
            reply.answers_tick = tick;
            publisher.send(tick, &reply)?;
            spin_until = monotonic_ns() + wait.spin_ns();
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
