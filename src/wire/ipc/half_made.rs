//! Service files a process left half-made. iceoryx2 writes a service's static description to
//! `<run root>/services/<name>.service` owner-writable (0600), and makes it read-only (0400) once the service is
//! set up; an opener waits for that and then gives up with "hangs in creation". A process that died between the
//! two (a kill, in a chaos soak, at the wrong microsecond) leaves the file writable for ever, and every later
//! open of that stream fails: a restarted logger could not open `log-ack` for 9.5 s and died (the one-hour soak
//! of 2026-11-29). iceoryx2's dead-node cleanup does not look at these files; this module does, only after an
//! open failed, and only at files older than [`HALF_MADE_AFTER`] (a live creator finishes within milliseconds):
//! one whose description is whole is finished (made read-only, as its creator would have: the live service it
//! describes is joined, not replaced), one whose description is missing or cut short is removed (no process
//! could have opened it).

use std::os::unix::fs::PermissionsExt;
use std::path::Path;
use std::time::{Duration, SystemTime};

/// A service file writable for longer than this is a dead creator's.
pub const HALF_MADE_AFTER: Duration = Duration::from_secs(3);

/// The mode iceoryx2 gives a service file while creating it, and the one it leaves once created.
const MODE_IN_CREATION: u32 = 0o600;
const MODE_CREATED: u32 = 0o400;

/// What is done with one half-made file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mend {
    /// Its description is whole: made read-only.
    Finished,
    /// Its description is missing or cut short: removed.
    Removed,
}

/// Whether a service file's text is a whole description (its creator wrote it in one `write`, then died before
/// making the file read-only): it names its service and ends with its messaging pattern's section.
fn description_is_whole(text: &str) -> bool {
    text.starts_with("service_hash = ") && text.contains("\n[messaging_pattern.") && text.ends_with('\n')
}

/// The decision for one file: `None` leaves it (created, or young enough to have a live creator).
fn decide(mode: u32, age: Duration, text: &str) -> Option<Mend> {
    if mode & 0o777 != MODE_IN_CREATION || age < HALF_MADE_AFTER {
        return None;
    }
    Some(if description_is_whole(text) { Mend::Finished } else { Mend::Removed })
}

/// Mend every half-made service file in `services_dir`; returns what was done, each with the file's service name
/// (from its description) or file name, for the caller to say.
pub fn mend(services_dir: &Path) -> Vec<(Mend, String)> {
    let Ok(entries) = std::fs::read_dir(services_dir) else { return Vec::new() };
    let mut done = Vec::new();
    for path in entries.filter_map(|e| e.ok()).map(|e| e.path()) {
        if path.extension().is_none_or(|x| x != "service") {
            continue;
        }
        let Ok(meta) = std::fs::metadata(&path) else { continue };
        let age = meta.modified().ok().and_then(|t| SystemTime::now().duration_since(t).ok()).unwrap_or_default();
        let text = std::fs::read_to_string(&path).unwrap_or_default();
        let Some(mend) = decide(meta.permissions().mode(), age, &text) else { continue };
        let acted = match mend {
            Mend::Finished => std::fs::set_permissions(&path, std::fs::Permissions::from_mode(MODE_CREATED)),
            Mend::Removed => std::fs::remove_file(&path),
        };
        if acted.is_ok() {
            let field = |prefix: &str| text.lines().find_map(|l| l.strip_prefix(prefix)).map(str::to_owned);
            let name = match (field("service_name = "), field("[messaging_pattern.")) {
                (Some(name), Some(pattern)) => {
                    format!("{} ({})", name.trim_matches('"'), pattern.trim_end_matches(']'))
                }
                _ => path.file_name().unwrap_or_default().to_string_lossy().into_owned(),
            };
            done.push((mend, name));
        }
    }
    done
}

#[cfg(test)]
mod tests {
    use super::*;

    const WHOLE: &str = "service_hash = \"0ae0\"\nservice_name = \"silrig/log-ack\"\nattributes = []\n\n\
                         [messaging_pattern.Event]\nmax_notifiers = 2\n";

    #[test]
    fn only_an_old_writable_file_is_mended_finished_when_whole_removed_when_cut_short() {
        let old = HALF_MADE_AFTER + Duration::from_millis(1);
        assert_eq!(decide(0o100400, old, WHOLE), None, "created");
        assert_eq!(decide(0o100600, Duration::from_millis(5), WHOLE), None, "a live creator's");
        assert_eq!(decide(0o100600, old, WHOLE), Some(Mend::Finished));
        assert_eq!(decide(0o100600, old, ""), Some(Mend::Removed));
        assert_eq!(decide(0o100600, old, &WHOLE[..30]), Some(Mend::Removed));
    }

    #[test]
    fn the_files_are_finished_or_removed_and_named() {
        let dir = std::env::temp_dir().join(format!("silrig-half-made-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let old = SystemTime::now() - HALF_MADE_AFTER - Duration::from_secs(1);
        let write = |name: &str, text: &str, mode: u32, when: SystemTime| {
            let path = dir.join(name);
            std::fs::write(&path, text).unwrap();
            std::fs::File::options().write(true).open(&path).unwrap().set_modified(when).unwrap();
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode)).unwrap();
            path
        };
        let whole = write("a.service", WHOLE, 0o600, old);
        let cut = write("b.service", "service_hash = \"b", 0o600, old);
        let young = write("c.service", WHOLE, 0o600, SystemTime::now());
        let other = write("d.node", "", 0o600, old);
        let mut done = mend(&dir);
        done.sort_by_key(|(_, name)| name.clone());
        assert_eq!(
            done,
            vec![(Mend::Removed, "b.service".to_string()), (Mend::Finished, "silrig/log-ack (Event)".into())]
        );
        assert_eq!(std::fs::metadata(&whole).unwrap().permissions().mode() & 0o777, 0o400);
        assert!(!cut.exists());
        assert_eq!(std::fs::metadata(&young).unwrap().permissions().mode() & 0o777, 0o600);
        assert!(other.exists());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
