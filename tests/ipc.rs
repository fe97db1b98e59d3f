//! The iceoryx2 transport as the rig processes will use it. Every test runs in its own run namespace (root dir and
//! prefix carry the test process id and a tag), so the tests run in parallel, and each removes its shared-memory
//! files at the end. No timing figure is asserted as an upper bound.

use iceoryx2::prelude::*;
use silrig::clock::{TickSchedule, monotonic_ns};
use silrig::ipc::{
    self, IpcError, LoopEnd, RunId, TickTimer, cleanup_run, create_node, open_stream, rig_waitset, run_waitset,
};
use silrig::topology::{CONSUMER_BUFFER, LOGGER_BUFFER, Stream};
use silrig::wire::{CommandSample, PlantSample, SampleHeader, WireError, WireSample};
use std::sync::mpsc;
use std::time::Duration;

/// A run namespace for one test; removes the run's files when dropped (declare it first so it drops last).
struct TestRun {
    run: RunId,
}

impl TestRun {
    fn new(tag: &str) -> Self {
        let run = RunId::new(&format!("t{}-{tag}", std::process::id())).unwrap();
        // Leftovers of an earlier test process that had the same pid.
        let _ = cleanup_run(&run);
        Self { run }
    }

    fn shm_files(&self) -> Vec<String> {
        let prefix = self.run.prefix();
        std::fs::read_dir(ipc::SHM_DIR)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| n.starts_with(&prefix))
            .collect()
    }
}

impl Drop for TestRun {
    fn drop(&mut self) {
        let _ = cleanup_run(&self.run);
    }
}

fn plant_sample(x: f64) -> PlantSample {
    let mut s = PlantSample::with_outputs(&[x; 5]);
    s.t_sim_s = x;
    s
}

#[test]
fn two_threads_exchange_200_samples_without_loss() {
    let t = TestRun::new("pubsub");
    let (ready_tx, ready_rx) = mpsc::channel();
    let run = t.run.clone();
    let consumer = std::thread::spawn(move || {
        let node = create_node(&run, "logger").unwrap();
        let service = open_stream::<PlantSample>(&node, Stream::Plant).unwrap();
        let sub = service.subscriber(LOGGER_BUFFER).unwrap();
        let waitset = rig_waitset().unwrap();
        // The deadline only keeps a broken test from hanging.
        let guard = waitset.attach_deadline(sub.listener(), Duration::from_secs(10)).unwrap();
        ready_tx.send(()).unwrap();
        let mut got = Vec::new();
        let mut timed_out = false;
        let exit = run_waitset(&waitset, |id| {
            if id.has_missed_deadline(&guard) {
                timed_out = true;
                return CallbackProgression::Stop;
            }
            sub.drain(|r| got.push(*r)).unwrap();
            if got.len() >= 200 { CallbackProgression::Stop } else { CallbackProgression::Continue }
        })
        .unwrap();
        assert_eq!(exit.end, LoopEnd::Stopped);
        assert!(!timed_out, "no sample for 10 s; got {}", got.len());
        (got, sub.stats())
    });

    ready_rx.recv().unwrap();
    let node = create_node(&t.run, "plant").unwrap();
    let service = open_stream::<PlantSample>(&node, Stream::Plant).unwrap();
    let mut publisher = service.publisher().unwrap();
    let t_start_ns = monotonic_ns();
    for k in 0..200u64 {
        let delivered = publisher.send(1000 + k, &plant_sample(k as f64)).unwrap().delivered;
        assert_eq!(delivered, 1);
        std::thread::sleep(Duration::from_micros(200));
    }
    let (got, stats) = consumer.join().unwrap();

    assert_eq!(got.len(), 200);
    for (k, r) in got.iter().enumerate() {
        let h = r.sample.header;
        assert_eq!((h.seq, h.tick), (k as u64, 1000 + k as u64));
        assert_eq!(h.epoch, publisher.epoch());
        assert_eq!(h.layout_version, silrig::wire::WIRE_LAYOUT_VERSION);
        assert_eq!(r.sample.outputs[0], k as f64);
        assert!(r.invalid.is_none());
        assert_eq!(r.seq.lost_before, 0);
        assert!(h.t_send_ns >= t_start_ns && r.t_recv_ns >= h.t_send_ns);
    }
    assert_eq!((stats.received, stats.lost, stats.publisher_restarts, stats.invalid), (200, 0, 0, 0));
}

#[test]
fn a_second_publisher_is_refused_with_a_clear_error_and_a_restart_is_not() {
    let t = TestRun::new("twopub");
    let node_a = create_node(&t.run, "ctl-a").unwrap();
    let node_b = create_node(&t.run, "ctl-b").unwrap();
    let svc_a = open_stream::<CommandSample>(&node_a, Stream::Command).unwrap();
    let svc_b = open_stream::<CommandSample>(&node_b, Stream::Command).unwrap();
    let first = svc_a.publisher().unwrap();

    let err = svc_b.publisher().unwrap_err();
    assert!(matches!(err, IpcError::PublisherAlreadyActive { stream: "command", .. }), "{err:?}");
    let msg = err.to_string();
    assert!(msg.contains("stream `command`") && msg.contains("already has a live publisher"), "{msg}");
    assert!(msg.contains("node `ctl-a`") && msg.contains(&format!("pid {}", std::process::id())), "{msg}");
    assert!(msg.contains(t.run.as_str()), "{msg}");

    // The first one goes away (a controller restart): the new one is accepted, with another epoch.
    let old_epoch = first.epoch();
    drop(first);
    let second = svc_b.publisher().unwrap();
    assert_ne!(second.epoch(), old_epoch);
}

/// The plant sample of layout 4, the F-16's fixed fields (13 states, 3 surfaces, throttle, Nz, Ny, time, wake-up
/// lateness, step time, flags), as a peer built before named signals has it.
#[repr(C)]
#[derive(Debug, Clone, Copy, ZeroCopySend)]
#[type_name("silrig::PlantSample::v4")]
struct OldPlantSample {
    header: SampleHeader,
    fields: [f64; 23],
}

impl WireSample for OldPlantSample {
    const TYPE_NAME: &'static str = "silrig::PlantSample::v4";
    fn header(&self) -> &SampleHeader {
        &self.header
    }
    fn header_mut(&mut self) -> &mut SampleHeader {
        &mut self.header
    }
    fn validate(&self) -> Result<(), WireError> {
        Ok(())
    }
}

#[test]
fn a_peer_with_another_wire_layout_gets_a_clear_error() {
    let t = TestRun::new("layout");
    let plant = create_node(&t.run, "plant").unwrap();
    let _svc = open_stream::<PlantSample>(&plant, Stream::Plant).unwrap();

    let old = create_node(&t.run, "old-logger").unwrap();
    let err = open_stream::<OldPlantSample>(&old, Stream::Plant).unwrap_err();
    assert!(matches!(err, IpcError::OtherWireLayout { stream: "plant", .. }), "{err:?}");
    let msg = err.to_string();
    assert!(msg.starts_with("peer built with another wire layout: expected silrig::PlantSample::v4"), "{msg}");
    assert!(msg.contains(&format!("the service carries {} (328 B, align 8)", PlantSample::TYPE_NAME)), "{msg}");
}

#[test]
fn invalid_samples_are_refused_before_they_reach_the_wire() {
    let t = TestRun::new("nan");
    let node = create_node(&t.run, "plant").unwrap();
    let svc = open_stream::<PlantSample>(&node, Stream::Plant).unwrap();
    let sub = svc.subscriber(CONSUMER_BUFFER).unwrap();
    let mut publisher = svc.publisher().unwrap();
    let mut bad = plant_sample(1.0);
    bad.outputs[4] = f64::NAN;
    let msg = publisher.send(0, &bad).unwrap_err().to_string();
    assert!(msg.contains("stream `plant`") && msg.contains("`outputs[4]`") && msg.contains("NaN"), "{msg}");
    assert_eq!(publisher.next_seq(), 0);
    assert_eq!(sub.drain(|_| {}).unwrap(), 0);
    publisher.send(1, &plant_sample(1.0)).unwrap();
    assert_eq!(sub.latest().unwrap().unwrap().sample.header.seq, 0);
}

#[test]
fn a_stalled_consumer_sees_the_newest_samples_and_counts_the_gap_and_the_logger_loses_nothing() {
    let t = TestRun::new("stall");
    let node = create_node(&t.run, "plant").unwrap();
    let svc = open_stream::<PlantSample>(&node, Stream::Plant).unwrap();
    let consumer = svc.subscriber(CONSUMER_BUFFER).unwrap();
    let logger = svc.subscriber(LOGGER_BUFFER).unwrap();
    let mut publisher = svc.publisher().unwrap();

    publisher.send(0, &plant_sample(0.0)).unwrap();
    assert_eq!(consumer.drain(|_| {}).unwrap(), 1);
    // A stall as long as the logger's queue: LOGGER_BUFFER samples (4.1 s at 1 kHz) while nobody reads.
    let n = LOGGER_BUFFER as u64;
    for k in 1..=n {
        publisher.send(k, &plant_sample(k as f64)).unwrap();
    }
    let mut seqs = Vec::new();
    consumer.drain(|r| seqs.push((r.sample.header.seq, r.seq.lost_before))).unwrap();
    assert_eq!(seqs, vec![(n - 3, n - 4), (n - 2, 0), (n - 1, 0), (n, 0)]);
    assert_eq!(consumer.stats().lost, n - 4);

    let mut logged = Vec::new();
    logger.drain(|r| logged.push(r.sample.header.seq)).unwrap();
    // The first sample (seq 0) was overwritten: one more sent than the queue holds.
    assert_eq!(logged, (1..=n).collect::<Vec<_>>());
    assert_eq!(logger.stats().lost, 0, "the first sample seen is never counted as loss");

    // A publisher restart: a new epoch, counted as a restart, not as loss or reordering.
    drop(publisher);
    let mut publisher = svc.publisher().unwrap();
    publisher.send(500, &plant_sample(5.0)).unwrap();
    let r = logger.latest().unwrap().unwrap();
    assert!(r.seq.new_epoch && r.sample.header.seq == 0 && r.sample.header.tick == 500);
    assert_eq!(logger.stats().publisher_restarts, 1);
    assert_eq!(logger.stats().out_of_order, 0);
}

#[test]
fn two_runs_do_not_see_each_other() {
    let a = TestRun::new("iso-a");
    let b = TestRun::new("iso-b");
    let node_a = create_node(&a.run, "plant").unwrap();
    let node_b = create_node(&b.run, "plant").unwrap();
    let svc_a = open_stream::<PlantSample>(&node_a, Stream::Plant).unwrap();
    let svc_b = open_stream::<PlantSample>(&node_b, Stream::Plant).unwrap();
    let sub_a = svc_a.subscriber(LOGGER_BUFFER).unwrap();
    let sub_b = svc_b.subscriber(LOGGER_BUFFER).unwrap();
    // Each run has its own single publisher slot.
    let mut pub_a = svc_a.publisher().unwrap();
    let mut pub_b = svc_b.publisher().unwrap();

    for k in 0..5 {
        pub_a.send(k, &plant_sample(1.0)).unwrap();
    }
    pub_b.send(0, &plant_sample(2.0)).unwrap();
    let mut got_a = Vec::new();
    let mut got_b = Vec::new();
    sub_a.drain(|r| got_a.push(r.sample.outputs[0])).unwrap();
    sub_b.drain(|r| got_b.push(r.sample.outputs[0])).unwrap();
    assert_eq!(got_a, vec![1.0; 5]);
    assert_eq!(got_b, vec![2.0]);
    assert_eq!((svc_a.number_of_subscribers(), svc_b.number_of_subscribers()), (1, 1));
}

#[test]
fn cleanup_removes_every_file_of_the_run_but_only_once_no_node_is_alive() {
    let t = TestRun::new("cleanup");
    let root = t.run.root_dir();
    {
        let node = create_node(&t.run, "plant").unwrap();
        let svc = open_stream::<PlantSample>(&node, Stream::Plant).unwrap();
        let sub = svc.subscriber(CONSUMER_BUFFER).unwrap();
        let mut publisher = svc.publisher().unwrap();
        publisher.send(0, &plant_sample(0.0)).unwrap();
        assert_eq!(sub.drain(|_| {}).unwrap(), 1);
        assert!(!t.shm_files().is_empty() && root.exists());

        let report = cleanup_run(&t.run).unwrap();
        assert_eq!(report.alive.len(), 1, "{report:?}");
        assert_eq!(report.alive[0].name, "plant");
        assert!(!report.removed_root_dir && report.removed_shm_files.is_empty());
        assert!(!t.shm_files().is_empty() && root.exists());
    }
    // A clean exit still leaves the run's global_mgmt file and empty directories behind.
    assert!(!t.shm_files().is_empty() || root.exists());
    let report = cleanup_run(&t.run).unwrap();
    assert!(report.alive.is_empty() && report.is_clean(), "{report:?}");
    assert!(t.shm_files().is_empty(), "{:?}", t.shm_files());
    assert!(!root.exists());
    // Idempotent.
    let again = cleanup_run(&t.run).unwrap();
    assert!(!again.removed_root_dir && again.removed_shm_files.is_empty());
}

#[test]
fn timerfd_ticks_wake_a_waitset_on_the_absolute_grid() {
    let period_ns = 2_000_000;
    let schedule = TickSchedule::new(monotonic_ns() + period_ns, period_ns);
    let timer = TickTimer::new(schedule).unwrap();
    let waitset = rig_waitset().unwrap();
    let guard = waitset.attach_notification(&timer).unwrap();
    let mut expirations = 0;
    let mut wakes = Vec::new();
    let exit = run_waitset(&waitset, |id| {
        if id.has_event_from(&guard) {
            let now_ns = monotonic_ns();
            let n = timer.read_expirations().unwrap();
            expirations += n;
            if n > 0 {
                wakes.push((expirations - 1, now_ns));
            }
        }
        if expirations >= 10 { CallbackProgression::Stop } else { CallbackProgression::Continue }
    })
    .unwrap();
    assert_eq!(exit.end, LoopEnd::Stopped);
    assert!(expirations >= 10);
    // Never early: every wake-up comes at or after the due time of the newest expired tick.
    for (tick, now_ns) in wakes {
        assert!(now_ns >= schedule.deadline_ns(tick), "tick {tick} woke before its due time");
    }
    // Nothing pending right after a read: the fd is non-blocking.
    assert!(timer.read_expirations().unwrap() <= 1);
}
