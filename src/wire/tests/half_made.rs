//! A stream whose iceoryx2 service file a process left half-made (it died between writing the service's
//! description and making the file read-only) opens again, and joins the live service rather than a new one.

use silrig_wire::ipc::{self, half_made::HALF_MADE_AFTER, namespace::RunId};
use silrig_wire::topology::Stream;
use silrig_wire::wire::LogAckSample;
use std::os::unix::fs::PermissionsExt;
use std::time::SystemTime;

#[test]
fn a_stream_left_half_made_by_a_dead_creator_opens_again_and_joins_the_live_service() {
    let run = RunId::new(&format!("hm{}", std::process::id())).unwrap();
    let plant = ipc::create_node(&run, "plant").unwrap();
    let acks = ipc::open_stream::<LogAckSample>(&plant, Stream::LogAck).unwrap();
    let _reader = acks.subscriber(4).unwrap();
    // As a creator killed before its last step leaves it: writable, and older than a live creator would be.
    let services = run.root_dir().join("services");
    for path in std::fs::read_dir(&services).unwrap().map(|e| e.unwrap().path()) {
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o600)).unwrap();
        let file = std::fs::File::options().write(true).open(&path).unwrap();
        file.set_modified(SystemTime::now() - HALF_MADE_AFTER * 2).unwrap();
    }
    let logger = ipc::create_node(&run, "logger").unwrap();
    let opened = ipc::open_stream::<LogAckSample>(&logger, Stream::LogAck).expect("opened again");
    let _writer = opened.publisher().unwrap();
    assert_eq!(opened.number_of_subscribers(), 1, "the plant's reader is on the same service");
    for path in std::fs::read_dir(&services).unwrap().map(|e| e.unwrap().path()) {
        assert_eq!(std::fs::metadata(&path).unwrap().permissions().mode() & 0o777, 0o400, "{}", path.display());
    }
    drop((_writer, opened, logger, _reader, acks, plant));
    let cleaned = ipc::namespace::cleanup_run(&run).unwrap();
    assert!(cleaned.is_clean(), "{cleaned:?}");
    let prefix = run.prefix();
    let left: Vec<_> = std::fs::read_dir("/dev/shm")
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|name| name.starts_with(&prefix) || name == &format!("silrig_{run}"))
        .collect();
    assert!(left.is_empty(), "left in /dev/shm: {left:?}");
}
