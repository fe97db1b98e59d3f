//! A sweep beyond one machine: `plan` writes a manifest (the scenario's text, seed, cases, shards) into a folder
//! every worker can read; `run` flies one shard, its index from the command line or the batch system's variable
//! (Slurm's `SLURM_ARRAY_TASK_ID`, a Kubernetes Indexed Job's `JOB_COMPLETION_INDEX`); `merge` checks that every
//! shard of this plan is there and builds the outputs a single-machine sweep writes, byte for byte. `slurm` writes
//! the `sbatch` array script.

use super::case::CaseResult;
use super::{Campaign, RigCommands};
use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The plan's file in the sweep folder.
pub const MANIFEST: &str = "manifest.json";
/// Where the shards' results go.
pub const SHARDS_DIR: &str = "shards";
/// Largest number of shards.
pub const MAX_SHARDS: u64 = 100_000;
/// Most cases in one shard: a worker holds its shard's results in memory (about 3.3 KB a case) until it writes
/// them, and merge reads one shard at a time.
pub const MAX_SHARD_CASES: u64 = 100_000;
/// The batch systems' variables that carry a task's index, in the order they are read.
pub const INDEX_VARIABLES: [&str; 2] = ["SLURM_ARRAY_TASK_ID", "JOB_COMPLETION_INDEX"];

/// `manifest.json`: everything a worker needs, so no worker reads the scenario file itself.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// The scenario file as the user named it (what the outputs and printed commands say).
    pub config: String,
    /// The scenario file's text when the sweep was planned.
    pub scenario_toml: String,
    /// Seed of the dispersions.
    pub seed: u64,
    /// Cases in the sweep.
    pub runs: u64,
    /// Shards the cases are split into.
    pub shards: u64,
    /// `--controller-cmd` and `--plant-cmd`: every case flown through the lockstep rig with these commands, run by
    /// each worker from the folder it starts in (absent: ours, in one process).
    #[serde(flatten)]
    pub commands: RigCommands,
    /// FNV-1a of all of the above: shard files carry it, so slices of different plans never merge.
    pub fingerprint: String,
}

/// One shard's results (`shards/shard-K-of-N.json`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ShardResult {
    /// The plan's fingerprint.
    pub fingerprint: String,
    /// Shard index.
    pub shard: u64,
    /// First case, and one past the last.
    pub cases_range: (u64, u64),
    /// The cases, in index order.
    pub cases: Vec<CaseResult>,
    /// A checksum of `cases` as written ([`cases_checksum`]): a shard edited after it was flown is refused at merge.
    #[serde(default)]
    pub checksum: String,
}

/// The checksum of a shard's cases: FNV-1a of their JSON, which reads back to the same bytes (floats round-trip).
fn cases_checksum(cases: &[CaseResult]) -> anyhow::Result<String> {
    Ok(fnv1a(&[&serde_json::to_string(cases)?]))
}

fn fnv1a(parts: &[&str]) -> String {
    let h = parts
        .iter()
        .flat_map(|p| p.bytes().chain([0u8]))
        .fold(0xcbf2_9ce4_8422_2325_u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3));
    format!("{h:016x}")
}

impl Manifest {
    fn new(config: String, scenario_toml: String, seed: u64, runs: u64, shards: u64, commands: RigCommands) -> Self {
        let mut parts =
            vec![config.clone(), scenario_toml.clone(), seed.to_string(), runs.to_string(), shards.to_string()];
        // Only when there is one, so the plans written before the fields existed keep their fingerprints; the plant's
        // named, so a plant command never fingerprints as the same controller command.
        parts.extend(commands.controller_cmd.clone());
        parts.extend(commands.plant_cmd.as_ref().map(|cmd| format!("--plant-cmd {cmd}")));
        let fingerprint = fnv1a(&parts.iter().map(String::as_str).collect::<Vec<_>>());
        Self { config, scenario_toml, seed, runs, shards, commands, fingerprint }
    }

    /// The cases of shard `k`: an even split, the first shards one case longer when it does not divide.
    pub fn range(&self, k: u64) -> std::ops::Range<u64> {
        let (base, extra) = (self.runs / self.shards, self.runs % self.shards);
        let start = k * base + k.min(extra);
        start..start + base + u64::from(k < extra)
    }

    fn shard_path(&self, dir: &Path, k: u64) -> PathBuf {
        dir.join(SHARDS_DIR).join(format!("shard-{k}-of-{}.json", self.shards))
    }

    fn campaign(&self) -> anyhow::Result<Campaign> {
        let mut campaign = Campaign::from_text(&self.scenario_toml, &self.config)?;
        // `config` names the commands already (it is the planned campaign's `command_config`).
        campaign.fly_commands(self.commands.clone())?;
        Ok(campaign)
    }

    /// Read `dir/manifest.json`.
    pub fn load(dir: &Path) -> anyhow::Result<Self> {
        let path = dir.join(MANIFEST);
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("reading {} (write it with `silrig sweep plan`)", path.display()))?;
        let m: Manifest =
            serde_json::from_str(&text).with_context(|| format!("{}: not a sweep manifest", path.display()))?;
        let expected =
            Manifest::new(m.config.clone(), m.scenario_toml.clone(), m.seed, m.runs, m.shards, m.commands.clone());
        anyhow::ensure!(
            expected.fingerprint == m.fingerprint,
            "{}: edited after planning (its fingerprint does not match)",
            path.display()
        );
        Ok(m)
    }
}

/// What `silrig sweep plan` is asked to do.
#[derive(Debug, Clone, clap::Args)]
pub struct PlanOptions {
    /// Scenario file (TOML) with `[dispersions]` and `[criteria]`.
    pub config: PathBuf,
    /// Number of cases.
    #[arg(long)]
    pub runs: u64,
    /// Seed of the dispersions (default: the scenario's `seed`).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Number of shards (array tasks).
    #[arg(long)]
    pub shards: u64,
    /// The sweep folder, readable and writable by every worker (a shared file system on a cluster).
    #[arg(long)]
    pub out: PathBuf,
    /// The plant or controller as an FMU, in place of the scenario's (every worker must reach the file).
    #[command(flatten)]
    pub fmus: silrig_adapters::in_process::FmuFlags,
    /// Sweep your own controller through the lockstep rig (as `silrig sweep --controller-cmd`); every worker runs
    /// this command from the folder it starts in, so it must find the program and its files from there.
    #[arg(long, value_name = "CMD")]
    pub controller_cmd: Option<String>,
    /// Sweep your own plant through the lockstep rig (as `silrig sweep --plant-cmd`); every worker runs this
    /// command from the folder it starts in, so it must find the program and its files from there.
    #[arg(long, value_name = "CMD")]
    pub plant_cmd: Option<String>,
}

/// `silrig sweep plan`: check the scenario, write the manifest.
pub fn plan(opts: &PlanOptions) -> anyhow::Result<Manifest> {
    super::check_runs(opts.runs)?;
    anyhow::ensure!(
        (1..=MAX_SHARDS.min(opts.runs)).contains(&opts.shards),
        "--shards must be within 1..={} (at most one per case), got {}",
        MAX_SHARDS.min(opts.runs),
        opts.shards
    );
    let fewest = opts.runs.div_ceil(MAX_SHARD_CASES);
    anyhow::ensure!(
        opts.shards >= fewest,
        "--shards must be at least {fewest} for {} cases: a shard's cases are held in memory until its results are \
         written, at most {MAX_SHARD_CASES} cases a shard (got {})",
        opts.runs,
        opts.shards
    );
    let text = std::fs::read_to_string(&opts.config).with_context(|| format!("reading {}", opts.config.display()))?;
    let commands =
        RigCommands { controller_cmd: opts.controller_cmd.clone(), plant_cmd: opts.plant_cmd.clone(), cold: false };
    let campaign = Campaign::load(&opts.config, &opts.fmus, &commands)?;
    let config = campaign.command_config();
    // Workers run from any folder: a plan that names FMUs carries the scenario with their paths made absolute.
    let text = if campaign.models.has_fmu() { campaign.scenario.to_toml() } else { text };
    anyhow::ensure!(
        !opts.out.join(MANIFEST).exists(),
        "{} already holds a sweep plan ({MANIFEST}); choose another --out or move it away: nothing is overwritten",
        opts.out.display()
    );
    let seed = opts.seed.unwrap_or(campaign.scenario.seed);
    let manifest = Manifest::new(config, text, seed, opts.runs, opts.shards, commands);
    std::fs::create_dir_all(opts.out.join(SHARDS_DIR)).with_context(|| format!("creating {}", opts.out.display()))?;
    silrig_flight::files::write_atomically(
        &opts.out.join(MANIFEST),
        &(serde_json::to_string_pretty(&manifest)? + "\n"),
    )?;
    Ok(manifest)
}

/// What `silrig sweep run` is asked to do.
#[derive(Debug, Clone, clap::Args)]
pub struct RunOptions {
    /// The sweep folder (with `manifest.json`).
    pub dir: PathBuf,
    /// The shard to fly, 0-based (default: $SLURM_ARRAY_TASK_ID, then $JOB_COMPLETION_INDEX).
    #[arg(long, conflicts_with = "shard")]
    pub index: Option<u64>,
    /// The shard as K/N (N must be the plan's number of shards).
    #[arg(long, value_name = "K/N")]
    pub shard: Option<String>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    pub jobs: Option<usize>,
}

/// The shard index from the flags or the batch system's variable.
fn shard_index(opts: &RunOptions, manifest: &Manifest) -> anyhow::Result<u64> {
    let k = if let Some(k) = opts.index {
        k
    } else if let Some(text) = &opts.shard {
        let (k, n) = text.split_once('/').ok_or_else(|| anyhow::anyhow!("--shard {text}: expected K/N, e.g. 3/8"))?;
        let (k, n): (u64, u64) = (
            k.trim().parse().map_err(|_| anyhow::anyhow!("--shard {text}: K is not a whole number"))?,
            n.trim().parse().map_err(|_| anyhow::anyhow!("--shard {text}: N is not a whole number"))?,
        );
        anyhow::ensure!(n == manifest.shards, "--shard {text}: the plan has {} shards, not {n}", manifest.shards);
        k
    } else {
        let (name, value) =
            INDEX_VARIABLES.iter().find_map(|v| std::env::var(v).ok().map(|value| (*v, value))).ok_or_else(|| {
                anyhow::anyhow!(
                    "no shard given: pass --index K or --shard K/N, or set {}",
                    INDEX_VARIABLES.join(" or ")
                )
            })?;
        value.trim().parse().map_err(|_| anyhow::anyhow!("${name} = {value:?} is not a shard index"))?
    };
    anyhow::ensure!(k < manifest.shards, "shard {k} is out of range: the plan has shards 0..={}", manifest.shards - 1);
    Ok(k)
}

/// `silrig sweep run`: fly one shard and write its results atomically (a killed worker leaves no half file).
pub fn run(opts: &RunOptions) -> anyhow::Result<(PathBuf, ShardResult)> {
    let manifest = Manifest::load(&opts.dir)?;
    let k = shard_index(opts, &manifest)?;
    let campaign = manifest.campaign()?;
    let jobs = campaign.threads(super::jobs(opts.jobs)?);
    let range = manifest.range(k);
    let mut cases = Vec::with_capacity((range.end - range.start) as usize);
    if let Some(interrupted) = campaign.fly_each(manifest.seed, range.clone(), jobs, |case| {
        cases.push(case);
        Ok(())
    })? {
        // A shard's results hold every case of it or none: merge counts on it.
        anyhow::bail!("{interrupted}: shard {k} is not written; fly it again");
    }
    let result = ShardResult {
        fingerprint: manifest.fingerprint.clone(),
        shard: k,
        cases_range: (range.start, range.end),
        checksum: cases_checksum(&cases)?,
        cases,
    };
    let path = manifest.shard_path(&opts.dir, k);
    std::fs::create_dir_all(path.parent().expect("in the shards folder"))?;
    silrig_flight::files::write_atomically(&path, &serde_json::to_string(&result)?)
        .with_context(|| format!("writing {}", path.display()))?;
    Ok((path, result))
}

/// `silrig sweep merge`: every shard of the plan, checked, into the single-machine outputs.
pub fn merge(dir: &Path) -> anyhow::Result<super::SweepRun> {
    let manifest = Manifest::load(dir)?;
    let campaign = manifest.campaign()?;
    anyhow::ensure!(
        !dir.join("sweep.json").exists(),
        "{} already holds merged results (sweep.json); move them away to merge again: nothing is overwritten",
        dir.display()
    );
    let missing: Vec<u64> = (0..manifest.shards).filter(|k| !manifest.shard_path(dir, *k).exists()).collect();
    if !missing.is_empty() {
        let list: Vec<String> = missing.iter().map(u64::to_string).collect();
        anyhow::bail!(
            "{} of {} shards have no results yet (shard {}); fly each with `silrig sweep run {} --index K`",
            missing.len(),
            manifest.shards,
            list.join(", "),
            dir.display()
        );
    }
    // One shard in memory at a time, its cases written as they are read.
    let mut writer = super::SweepWriter::create(&campaign, manifest.seed, dir, true)?;
    for k in 0..manifest.shards {
        if let Err(e) = read_shard(&manifest, dir, k).and_then(|cases| cases.iter().try_for_each(|c| writer.add(c))) {
            writer.discard();
            return Err(e);
        }
    }
    let (summary, files) = writer.finish(None)?;
    Ok(super::SweepRun { summary, files, fly_s: f64::NAN, jobs: 0 })
}

/// Shard `k`'s cases, checked: of this plan, this shard, unedited, exactly its range.
fn read_shard(manifest: &Manifest, dir: &Path, k: u64) -> anyhow::Result<Vec<CaseResult>> {
    let path = manifest.shard_path(dir, k);
    let text = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let shard: ShardResult =
        serde_json::from_str(&text).with_context(|| format!("{}: not a shard's results", path.display()))?;
    anyhow::ensure!(
        shard.fingerprint == manifest.fingerprint,
        "{} belongs to another plan (fingerprint {}, this plan's {}): shards of different plans never merge",
        path.display(),
        shard.fingerprint,
        manifest.fingerprint
    );
    anyhow::ensure!(
        shard.shard == k,
        "{} holds shard {}'s results, not shard {k}'s: renamed or copied over? fly shard {k} again",
        path.display(),
        shard.shard
    );
    anyhow::ensure!(
        shard.checksum == cases_checksum(&shard.cases)?,
        "{}: its cases were changed after it was flown (their checksum does not match); fly shard {k} again",
        path.display()
    );
    let range = manifest.range(k);
    anyhow::ensure!(
        shard.cases.iter().map(|c| c.index).eq(range.clone()),
        "{}: does not hold exactly cases {range:?}",
        path.display()
    );
    Ok(shard.cases)
}

/// What `silrig sweep slurm` is asked to do.
#[derive(Debug, Clone, clap::Args)]
pub struct SlurmOptions {
    /// The sweep folder (with `manifest.json`).
    pub dir: PathBuf,
    /// Cores per array task.
    #[arg(long, default_value_t = 1)]
    pub cpus_per_task: u32,
    /// Partition to submit to (default: the cluster's default).
    #[arg(long)]
    pub partition: Option<String>,
    /// Time limit per task, minutes.
    #[arg(long, default_value_t = 30)]
    pub time_min: u32,
}

/// `silrig sweep slurm`: the `sbatch` array script (one task per shard), written to `<dir>/sweep.sbatch`.
pub fn slurm_script(opts: &SlurmOptions) -> anyhow::Result<(PathBuf, String)> {
    let manifest = Manifest::load(&opts.dir)?;
    anyhow::ensure!((1..=1024).contains(&opts.cpus_per_task), "--cpus-per-task must be within 1..=1024");
    anyhow::ensure!((1..=10_080).contains(&opts.time_min), "--time-min must be within 1..=10080 (a week)");
    let dir = std::fs::canonicalize(&opts.dir)?;
    let exe = std::env::current_exe()?;
    let name = manifest.campaign()?.scenario.name;
    let partition = opts.partition.as_ref().map(|p| format!("#SBATCH --partition={p}\n")).unwrap_or_default();
    // A controller or plant command names its program and files as seen from here (`python3 examples/...`): run
    // it from here.
    let chdir = if manifest.commands.any() {
        format!("#SBATCH --chdir={}\n", std::env::current_dir()?.display())
    } else {
        String::new()
    };
    let quote = |p: &Path| format!("'{}'", p.display().to_string().replace('\'', "'\\''"));
    let script = format!(
        "#!/bin/sh\n\
         # silrig sweep of {config}: {runs} cases in {shards} shards, seed {seed}. Submit, then merge when all are done:\n\
         #   jobid=$(sbatch --parsable {script})\n\
         #   sbatch --dependency=afterok:$jobid --wrap \"{exe} sweep merge {dir}\"\n\
         #SBATCH --job-name=silrig-{name}\n\
         #SBATCH --array=0-{last}\n\
         #SBATCH --cpus-per-task={cpus}\n\
         #SBATCH --time={time}\n\
         {partition}\
         {chdir}\
         #SBATCH --output={logs}/shard-%a.log\n\
         exec {exe} sweep run {dir} --jobs \"${{SLURM_CPUS_PER_TASK:-1}}\"\n",
        config = manifest.config,
        runs = manifest.runs,
        shards = manifest.shards,
        seed = manifest.seed,
        script = quote(&dir.join("sweep.sbatch")),
        exe = quote(&exe),
        dir = quote(&dir),
        last = manifest.shards - 1,
        cpus = opts.cpus_per_task,
        time = opts.time_min,
        logs = dir.join("logs").display(),
    );
    std::fs::create_dir_all(dir.join("logs"))?;
    let path = dir.join("sweep.sbatch");
    std::fs::write(&path, &script).with_context(|| format!("writing {}", path.display()))?;
    Ok((path, script))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_every_case_once_in_order() {
        for (runs, shards) in [(10, 3), (7, 7), (1000, 8), (5, 1)] {
            let m = Manifest::new("c".into(), "t".into(), 1, runs, shards, RigCommands::default());
            let all: Vec<u64> = (0..shards).flat_map(|k| m.range(k)).collect();
            assert_eq!(all, (0..runs).collect::<Vec<_>>(), "{runs} in {shards}");
            let sizes: Vec<u64> = (0..shards).map(|k| m.range(k).end - m.range(k).start).collect();
            assert!(sizes.iter().max().unwrap() - sizes.iter().min().unwrap() <= 1);
        }
    }

    #[test]
    fn a_plan_of_a_plant_command_is_told_from_one_of_the_same_controller_command() {
        let with = |controller_cmd: Option<&str>, plant_cmd: Option<&str>| {
            let commands = RigCommands {
                controller_cmd: controller_cmd.map(String::from),
                plant_cmd: plant_cmd.map(String::from),
                cold: false,
            };
            Manifest::new("c".into(), "t".into(), 1, 10, 2, commands)
        };
        let (controller, plant, both) = (with(Some("x"), None), with(None, Some("x")), with(Some("x"), Some("x")));
        assert_ne!(controller.fingerprint, plant.fingerprint);
        assert_ne!(both.fingerprint, controller.fingerprint);
        // The fields stand at the top level of manifest.json, each only when given.
        let json = serde_json::to_value(&plant).unwrap();
        assert_eq!(json["plant_cmd"], "x");
        assert!(json.get("controller_cmd").is_none(), "{json}");
        let back: Manifest = serde_json::from_value(serde_json::to_value(&both).unwrap()).unwrap();
        assert_eq!(back, both);
    }
}
