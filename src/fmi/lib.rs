//! silrig-fmi: co-simulation FMUs (FMI 2.0 and 3.0) opened, instantiated and stepped, for the rig's plant
//! process (and anything else that flies a `.fmu`).
//!
//! - [`Fmu::open`]: unpack the archive into a private folder (removed when the [`Fmu`] is dropped, or by the next
//!   open when its process was killed), read
//!   [`description::ModelDescription`], and load the Linux x86-64 binary; each step that fails names the file and
//!   what is wrong (not a zip, no `modelDescription.xml`, FMI 1.0, model exchange only, no binary for this
//!   platform, a binary cut short or built for another class or machine, a missing function: [`elf`] checks the
//!   binary's bytes before it is mapped, so a broken one is an error, not a SIGBUS).
//! - [`Fmu::instantiate`] gives an [`Instance`]: real values set and read by value reference (and numbers of every
//!   kind a signal can be, [`numbers::Numbers`]), `doStep`, and the
//!   FMU's own state taken, serialized and put back where the FMU offers it. Whatever the FMU logs is kept and
//!   joined to the error of the call that failed.
//! - [`fmi2`], [`fmi3`]: the two C APIs, declared by hand from the standard's headers (the functions a
//!   co-simulation importer calls, and nothing else).
//!
//! Layers: depends on no other silrig crate; the rig's plant process (silrig-rig) uses it.

/// A struct of an FMI version's functions, resolved in the FMU's binary by name, each a missing function named.
macro_rules! fmi_functions {
    ($standard:literal, $($field:ident: $symbol:literal: fn($($arg:ty),*) $(-> $ret:ty)?;)*) => {
        /// The functions a co-simulation importer calls, resolved in the FMU's binary.
        pub struct Functions {
            $($field: unsafe extern "C" fn($($arg),*) $(-> $ret)?,)*
            /// Keeps the binary loaded while the pointers above are in use.
            _library: libloading::Library,
        }

        impl Functions {
            /// Every function's name, as the binary must export it.
            pub const SYMBOLS: &'static [&'static str] = &[$($symbol),*];

            /// Load the binary (its bytes checked by [`crate::elf`] first) and resolve every function; a missing one
            /// is named.
            pub fn load(binary: &std::path::Path) -> Result<Self, String> {
                // SAFETY: loading runs the binary's initializers: an FMU's binary is code the user chose to run.
                let library = unsafe { libloading::Library::new(binary) }
                    .map_err(|e| format!("cannot load {}: {e}", binary.display()))?;
                Ok(Self {
                    $($field: {
                        // SAFETY: the symbol has the type the standard's function-types header gives it.
                        let symbol = unsafe {
                            library.get::<unsafe extern "C" fn($($arg),*) $(-> $ret)?>($symbol.as_bytes())
                        }
                        .map_err(|_| {
                            format!("its binary {} lacks the {} function {}", binary.display(), $standard, $symbol)
                        })?;
                        *symbol
                    },)*
                    _library: library,
                })
            }
        }
    };
}

mod calls;
pub mod description;
mod elf;
pub mod fmi2;
pub mod fmi3;
pub mod numbers;

use description::{FmiVersion, ModelDescription};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// What can go wrong with an FMU, each naming the file.
#[derive(Debug, thiserror::Error)]
pub enum FmiError {
    /// The file cannot be read or unpacked.
    #[error("FMU {file}: {problem}")]
    Archive {
        /// The .fmu.
        file: String,
        /// What is wrong with it.
        problem: String,
    },
    /// `modelDescription.xml` is missing or malformed.
    #[error("FMU {file}: modelDescription.xml: {problem}")]
    Description {
        /// The .fmu.
        file: String,
        /// What is wrong with it.
        problem: String,
    },
    /// Something the FMU is or needs that silrig does not import.
    #[error("FMU {file}: {what}")]
    Unsupported {
        /// The .fmu.
        file: String,
        /// What it is.
        what: String,
    },
    /// The binary cannot be loaded or lacks a function.
    #[error("FMU {file}: {problem}")]
    Binary {
        /// The .fmu.
        file: String,
        /// What is wrong.
        problem: String,
    },
    /// A call into the FMU returned an error status (or no instance).
    #[error("FMU {file}: {call} returned {status}{log}")]
    Call {
        /// The .fmu.
        file: String,
        /// The function and its arguments where they help (`fmi2DoStep at t = 1.23 s`).
        call: String,
        /// The status it returned (`fmi2Error`, `fmi2Discard`, `fmi2Fatal`, `no instance`).
        status: String,
        /// What the FMU logged before returning, joined (empty when it logged nothing).
        log: String,
    },
}

/// An FMU unpacked and loaded, ready to instantiate.
pub struct Fmu {
    /// The .fmu as given, for errors.
    file: String,
    /// Where it was unpacked (removed on drop).
    folder: PathBuf,
    /// What it says of itself.
    pub description: ModelDescription,
    api: Api,
}

enum Api {
    V2(Arc<fmi2::Functions>),
    V3(Arc<fmi3::Functions>),
}

impl Fmu {
    /// Unpack `path` into a private folder, read its description and load its binary.
    pub fn open(path: &Path) -> Result<Self, FmiError> {
        let file = path.display().to_string();
        remove_dead_unpacks();
        let folder = unpack_folder();
        let fmu = Self::open_into(path, &file, &folder);
        if fmu.is_err() {
            let _ = std::fs::remove_dir_all(&folder);
        }
        fmu
    }

    fn open_into(path: &Path, file: &str, folder: &Path) -> Result<Self, FmiError> {
        unpack(path, file, folder)?;
        let text = match std::fs::read_to_string(folder.join("modelDescription.xml")) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                return Err(FmiError::Description {
                    file: file.into(),
                    problem: "not in the archive (an FMU has it at its root)".into(),
                });
            }
            Err(e) => return Err(FmiError::Description { file: file.into(), problem: e.to_string() }),
        };
        let description = ModelDescription::parse(&text, file)?;
        let binary_dir = folder.join(description.version.binary_folder());
        let binary = binary_dir.join(format!("{}.so", description.co_simulation.model_identifier));
        if !binary.exists() {
            let found = list_binaries(folder);
            return Err(FmiError::Unsupported {
                file: file.into(),
                what: format!(
                    "no Linux x86-64 binary: {}/{}.so is not in the archive ({}); re-export the FMU for linux64",
                    description.version.binary_folder(),
                    description.co_simulation.model_identifier,
                    match found.is_empty() {
                        true => "it has no binaries at all: a source-only FMU is not compiled by silrig".into(),
                        false => format!("it has {}", found.join(", ")),
                    }
                ),
            });
        }
        let binary_error = |problem: String| FmiError::Binary { file: file.into(), problem };
        // Checked from its bytes before it is mapped: a binary cut short would kill this process with SIGBUS.
        let symbols = match description.version {
            FmiVersion::V2 => fmi2::Functions::SYMBOLS,
            FmiVersion::V3 => fmi3::Functions::SYMBOLS,
        };
        let inside =
            format!("{}/{}.so", description.version.binary_folder(), description.co_simulation.model_identifier);
        elf::check(&binary, &inside, description.version.label(), symbols).map_err(binary_error)?;
        let api = match description.version {
            FmiVersion::V2 => Api::V2(Arc::new(fmi2::Functions::load(&binary).map_err(binary_error)?)),
            FmiVersion::V3 => Api::V3(Arc::new(fmi3::Functions::load(&binary).map_err(binary_error)?)),
        };
        Ok(Self { file: file.into(), folder: folder.into(), description, api })
    }

    /// The .fmu as given.
    pub fn file(&self) -> &str {
        &self.file
    }

    /// The .fmu as given, and what it is: `airframe.fmu (FMI 2.0, model airframe)`.
    pub fn label(&self) -> String {
        format!("{} ({}, model {})", self.file, self.description.version.label(), self.description.model_name)
    }

    /// Create an instance named `name`, not yet initialized (set start values and parameters, then
    /// [`Instance::enter_initialization`]).
    pub fn instantiate(&self, name: &str) -> Result<Instance, FmiError> {
        let resources = self.folder.join("resources");
        let ctx = CallContext { file: self.file.clone(), log: Log::default() };
        let inner = match &self.api {
            Api::V2(f) => Inner::V2(fmi2::Instance::new(f.clone(), name, &self.description.token, &resources, ctx)?),
            Api::V3(f) => Inner::V3(fmi3::Instance::new(f.clone(), name, &self.description.token, &resources, ctx)?),
        };
        Ok(Instance { inner })
    }
}

// One unpacked FMU serves the instances of many threads (a sweep's workers): it must stay shareable.
const _: () = {
    const fn shareable<T: Send + Sync>() {}
    shareable::<Fmu>()
};

impl Drop for Fmu {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.folder);
    }
}

/// A folder of this process for one FMU: `<tmp>/silrig-fmu-<pid>-<n>`.
fn unpack_folder() -> PathBuf {
    use std::sync::atomic::{AtomicU32, Ordering};
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    std::env::temp_dir().join(format!("silrig-fmu-{}-{n}", std::process::id()))
}

/// Remove the unpack folders of processes that no longer run: a plant killed by a fault or by its FMU's own crash
/// never dropped its [`Fmu`]. Folders of live processes, and those this user cannot remove, stay.
fn remove_dead_unpacks() {
    let Ok(entries) = std::fs::read_dir(std::env::temp_dir()) else { return };
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some((pid, n)) = name.strip_prefix("silrig-fmu-").and_then(|rest| rest.split_once('-')) else { continue };
        let numbers = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
        if numbers(pid) && numbers(n) && !Path::new("/proc").join(pid).exists() {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

fn unpack(path: &Path, file: &str, folder: &Path) -> Result<(), FmiError> {
    let archive_error = |problem: String| FmiError::Archive { file: file.into(), problem };
    let reader = std::fs::File::open(path).map_err(|e| archive_error(format!("cannot be read: {e}")))?;
    let mut zip =
        zip::ZipArchive::new(reader).map_err(|e| archive_error(format!("not a zip archive, as an FMU is ({e})")))?;
    let _ = std::fs::remove_dir_all(folder);
    std::fs::create_dir_all(folder).map_err(|e| archive_error(format!("unpacking into {}: {e}", folder.display())))?;
    // extract() keeps every entry inside the folder (entries with `..` or absolute paths are refused).
    zip.extract(folder).map_err(|e| archive_error(format!("unpacking into {}: {e}", folder.display())))
}

/// The binaries an archive holds (`binaries/<platform>/<name>`), for an error that says what it has instead.
fn list_binaries(folder: &Path) -> Vec<String> {
    let mut found = Vec::new();
    if let Ok(platforms) = std::fs::read_dir(folder.join("binaries")) {
        for platform in platforms.flatten() {
            if let Ok(files) = std::fs::read_dir(platform.path()) {
                for f in files.flatten() {
                    found.push(format!(
                        "binaries/{}/{}",
                        platform.file_name().to_string_lossy(),
                        f.file_name().to_string_lossy()
                    ));
                }
            }
        }
    }
    found.sort();
    found
}

/// What an FMU logged, kept until the next failed call takes it into its error.
#[derive(Debug, Clone, Default)]
pub struct Log(Arc<Mutex<Vec<String>>>);

/// The most messages kept between two failed calls (an FMU that logs every step would grow it without end).
const LOG_KEEP: usize = 20;

impl Log {
    fn push(&self, line: String) {
        let mut lines = self.0.lock().unwrap_or_else(|e| e.into_inner());
        if lines.len() == LOG_KEEP {
            lines.remove(0);
        }
        lines.push(line);
    }

    /// Take what was logged since the last take, as `: a; b` (empty when nothing was).
    fn take_joined(&self) -> String {
        let lines = std::mem::take(&mut *self.0.lock().unwrap_or_else(|e| e.into_inner()));
        match lines.is_empty() {
            true => String::new(),
            false => format!(" (the FMU logged: {})", lines.join("; ")),
        }
    }
}

/// What a call into the FMU needs to say what went wrong.
pub(crate) struct CallContext {
    pub(crate) file: String,
    pub(crate) log: Log,
}

impl CallContext {
    pub(crate) fn error(&self, call: String, status: &str) -> FmiError {
        FmiError::Call { file: self.file.clone(), call, status: status.to_string(), log: self.log.take_joined() }
    }
}

/// An FMU's state as taken by [`Instance::save_state`]: serialized bytes, so it can go to disk.
pub type SavedState = Vec<u8>;

enum Inner {
    V2(fmi2::Instance),
    V3(fmi3::Instance),
}

/// One instance of an FMU, in co-simulation.
pub struct Instance {
    inner: Inner,
}

impl Instance {
    /// Start initialization at `start_time_s` (values set before this are start values and parameters).
    pub fn enter_initialization(&mut self, start_time_s: f64) -> Result<(), FmiError> {
        match &mut self.inner {
            Inner::V2(i) => i.enter_initialization(start_time_s),
            Inner::V3(i) => i.enter_initialization(start_time_s),
        }
    }

    /// End initialization: the instance is ready to step.
    pub fn exit_initialization(&mut self) -> Result<(), FmiError> {
        match &mut self.inner {
            Inner::V2(i) => i.exit_initialization(),
            Inner::V3(i) => i.exit_initialization(),
        }
    }

    /// Set real values by value reference.
    pub fn set_reals(&mut self, refs: &[u32], values: &[f64]) -> Result<(), FmiError> {
        match &mut self.inner {
            Inner::V2(i) => i.set_reals(refs, values),
            Inner::V3(i) => i.set_reals(refs, values),
        }
    }

    /// Read real values by value reference into `values`.
    pub fn get_reals(&mut self, refs: &[u32], values: &mut [f64]) -> Result<(), FmiError> {
        match &mut self.inner {
            Inner::V2(i) => i.get_reals(refs, values),
            Inner::V3(i) => i.get_reals(refs, values),
        }
    }

    /// Advance from `t_s` by `step_s`. Anything but OK (or a warning) is an error naming the status.
    pub fn do_step(&mut self, t_s: f64, step_s: f64) -> Result<(), FmiError> {
        match &mut self.inner {
            Inner::V2(i) => i.do_step(t_s, step_s),
            Inner::V3(i) => i.do_step(t_s, step_s),
        }
    }

    /// Take the FMU's whole state and serialize it (needs canGetAndSetFMUstate and canSerializeFMUstate).
    pub fn save_state(&mut self) -> Result<SavedState, FmiError> {
        match &mut self.inner {
            Inner::V2(i) => i.save_state(),
            Inner::V3(i) => i.save_state(),
        }
    }

    /// Put back a state [`Self::save_state`] took (in this or an earlier process of the same FMU).
    pub fn restore_state(&mut self, saved: &[u8]) -> Result<(), FmiError> {
        match &mut self.inner {
            Inner::V2(i) => i.restore_state(saved),
            Inner::V3(i) => i.restore_state(saved),
        }
    }
}

/// A C string of `text` for an FMI call (text with a NUL byte is cut there: FMI strings cannot hold one).
pub(crate) fn c_string(text: &str) -> std::ffi::CString {
    std::ffi::CString::new(text.split('\0').next().unwrap_or("")).expect("no NUL byte left")
}
