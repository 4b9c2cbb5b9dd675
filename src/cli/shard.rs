//! Sweeps split into shards that any batch system can run, and their merge.
//!
//! A sweep's *jobs* are its adversary sizes, each a *chain*: the defender
//! sizes in increasing order, each warm-started from the best defender of
//! the next smaller size (so the results are monotone in the defender's
//! size). A chain is never split, so a shard computes exactly what the
//! unsharded sweep computes. Shard `K/N` runs the chains at positions
//! `i` (0-based, in the order of the [`SweepPlan`]) with `i mod N = K - 1`.
//!
//! Layout of a sharded sweep directory `DIR` (docs/formats.md section 9):
//!
//! * `DIR/shards/shard-K-of-N.json`: a [`ShardRecord`] per shard that
//!   started (and `DIR/shards/slurm.json` when `--slurm` wrote the scripts),
//!   each with the command line, the crate version and the [`SweepPlan`];
//! * `DIR/def<N>-adv<M>/`: one size pair's `solve` directory with its
//!   `sweep.csv` row in [`ROW_FILE`], renamed into place whole
//!   ([`super::OutputDirectory`]), so a shard that dies leaves no
//!   half-written pair;
//! * `DIR/sweep.csv`, `DIR/sweep.svg`: written by [`merge`] once every
//!   pair is present.

use std::fmt;
use std::fs;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use posg_fsc::output::sweep::{SWEEP_COLUMNS, SweepRow, sweep_table};

use super::common::PlotArgs;
use posg_fsc::output::{OutputError, SweepPoint, Title, create_dir, plot_sweep, write_file};

/// The file in each pair directory holding its row of `sweep.csv`.
pub const ROW_FILE: &str = "row.csv";

/// The subdirectory holding the [`ShardRecord`]s.
pub const RECORDS_DIRECTORY: &str = "shards";

/// Shard `index` of `count` (both counted from 1), written `K/N`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// K, in `1..=count`.
    pub index: usize,
    /// N, at least 1.
    pub count: usize,
}

impl FromStr for Shard {
    type Err = String;

    fn from_str(text: &str) -> Result<Self, String> {
        let (k, n) = text
            .split_once('/')
            .ok_or_else(|| format!("`{text}` is not of the form K/N (e.g. 2/8)"))?;
        let number = |t: &str, what: &str| {
            t.trim()
                .parse::<usize>()
                .map_err(|_| format!("`{text}`: {what} `{t}` is not a non-negative integer"))
        };
        let (index, count) = (number(k, "K")?, number(n, "N")?);
        if count == 0 || index == 0 || index > count {
            return Err(format!(
                "`{text}`: K/N needs 1 <= K <= N (shards are counted from 1)"
            ));
        }
        Ok(Self { index, count })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

/// Everything that must agree between the shards of one sweep: the inputs
/// (game file fingerprint, objective), the optimiser's settings (with the
/// seed), the size lists, the number of shards, the crate version, and the
/// plot's title.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepPlan {
    /// The crate version that ran the shard.
    pub crate_version: String,
    /// [`fingerprint`] of the game file's bytes.
    pub game_fingerprint: String,
    /// The game's name, if it has one.
    pub game_name: Option<String>,
    /// The objective as the user gave it (formula or automaton file).
    pub objective: String,
    /// The optimiser's settings, as in `summary.json`.
    pub settings: serde_json::Value,
    /// Defender sizes, increasing (the order of each chain).
    pub defender_sizes: Vec<usize>,
    /// Adversary sizes, one chain each, in the order of the rows.
    pub adversary_sizes: Vec<usize>,
    /// N, the number of shards.
    pub shards: usize,
    /// The title of `sweep.svg`.
    pub title_main: String,
    /// The second line of the title of `sweep.svg`.
    pub title_detail: String,
}

impl SweepPlan {
    /// The adversary sizes (chains) that `shard` runs: those at positions
    /// `i` with `i mod N = K - 1`.
    pub fn chains_of(&self, shard: Shard) -> Vec<usize> {
        self.adversary_sizes
            .iter()
            .enumerate()
            .filter(|(i, _)| i % shard.count == shard.index - 1)
            .map(|(_, &m)| m)
            .collect()
    }

    /// The shard (1-based) that runs the chain of adversary size `m`.
    pub fn shard_of(&self, m: usize) -> Option<usize> {
        self.adversary_sizes
            .iter()
            .position(|&a| a == m)
            .map(|i| i % self.shards + 1)
    }

    /// Every size pair `(defender, adversary)`, in the order of `sweep.csv`.
    pub fn pairs(&self) -> Vec<(usize, usize)> {
        self.adversary_sizes
            .iter()
            .flat_map(|&m| self.defender_sizes.iter().map(move |&n| (n, m)))
            .collect()
    }

    /// The title of `sweep.svg`.
    pub fn title(&self) -> Title {
        Title {
            main: self.title_main.clone(),
            detail: self.title_detail.clone(),
        }
    }

    /// The name of the first field that differs from `other`, if any.
    pub fn first_difference(&self, other: &Self) -> Option<&'static str> {
        let fields: [(&'static str, bool); 10] = [
            ("crate_version", self.crate_version == other.crate_version),
            (
                "game_fingerprint (the game file)",
                self.game_fingerprint == other.game_fingerprint,
            ),
            ("game_name", self.game_name == other.game_name),
            ("objective", self.objective == other.objective),
            ("settings", self.settings == other.settings),
            (
                "defender_sizes",
                self.defender_sizes == other.defender_sizes,
            ),
            (
                "adversary_sizes",
                self.adversary_sizes == other.adversary_sizes,
            ),
            ("shards", self.shards == other.shards),
            ("title_main", self.title_main == other.title_main),
            ("title_detail", self.title_detail == other.title_detail),
        ];
        fields
            .into_iter()
            .find(|(_, same)| !same)
            .map(|(name, _)| name)
    }
}

/// `DIR/shards/*.json`: who wrote into a sharded sweep directory, with
/// what command and plan.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardRecord {
    /// `shard K/N` or `--slurm`.
    pub written_by: String,
    /// The command line that wrote it.
    pub command_line: Vec<String>,
    /// The plan it followed.
    pub plan: SweepPlan,
}

/// Why a sharded sweep directory cannot be written or merged.
#[derive(Debug, Error)]
pub enum ShardError {
    /// Reading or writing a file failed.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// A file is not what this module writes.
    #[error("{path}: {problem}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        problem: String,
    },
    /// Two records disagree on their plan.
    #[error(
        "{path} ({written_by}) was written with different {field} than {other} ({other_by}); \
         all shards of one sweep must use the same game, objective, sizes, settings, number \
         of shards and posg-fsc version: rerun it with the same settings, or use another --out"
    )]
    Mismatch {
        /// The record that disagrees.
        path: PathBuf,
        /// Its writer.
        written_by: String,
        /// The first field that differs.
        field: &'static str,
        /// The record it was compared with (or `this run`).
        other: String,
        /// That record's writer.
        other_by: String,
    },
    /// The directory holds no records: not a sharded sweep.
    #[error(
        "{path} holds no shard records ({path}/shards/*.json): it is not the --out of a \
         `sweep --shard K/N` run"
    )]
    NoRecords {
        /// The directory.
        path: PathBuf,
    },
    /// A non-empty directory that is not a sharded sweep's.
    #[error(
        "refusing to write shards into {path}: it is not empty and holds no shard records \
         ({path}/shards/; results of an unsharded run?); choose another --out"
    )]
    NotSharded {
        /// The directory.
        path: PathBuf,
    },
    /// Pairs are missing.
    #[error("{path}: {count} of {total} size pairs are missing: {list}", count = missing.len(), list = describe_missing(missing))]
    Missing {
        /// The directory.
        path: PathBuf,
        /// Every size pair of the plan.
        total: usize,
        /// The missing pairs.
        missing: Vec<MissingPair>,
    },
}

/// A size pair without results, and the shard that should have written it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MissingPair {
    /// Defender size.
    pub defender_nodes: usize,
    /// Adversary size.
    pub adversary_nodes: usize,
    /// The shard that runs its chain.
    pub shard: Shard,
    /// Whether that shard left a record (it started).
    pub shard_started: bool,
}

fn describe_missing(missing: &[MissingPair]) -> String {
    missing
        .iter()
        .map(|p| {
            format!(
                "{} (shard {}, {})",
                pair_directory_name(p.defender_nodes, p.adversary_nodes),
                p.shard,
                if p.shard_started {
                    "started but did not finish it: rerun that shard"
                } else {
                    "never started: run it"
                }
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The directory name of a size pair: `def<N>-adv<M>`.
pub fn pair_directory_name(defender_nodes: usize, adversary_nodes: usize) -> String {
    format!("def{defender_nodes}-adv{adversary_nodes}")
}

/// The record file of `written_by`: `shards/shard-K-of-N.json` for a shard.
pub fn shard_record_path(dir: &Path, shard: Shard) -> PathBuf {
    dir.join(RECORDS_DIRECTORY)
        .join(format!("shard-{}-of-{}.json", shard.index, shard.count))
}

/// The record file written by `--slurm`.
pub fn slurm_record_path(dir: &Path) -> PathBuf {
    dir.join(RECORDS_DIRECTORY).join("slurm.json")
}

/// A 64-bit FNV-1a hash of `bytes` in hexadecimal: identifies a game file
/// across machines (not a cryptographic hash).
pub fn fingerprint(bytes: &[u8]) -> String {
    let hash = bytes.iter().fold(0xcbf2_9ce4_8422_2325_u64, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    });
    format!("fnv1a64:{hash:016x}")
}

/// Every record in `dir/shards/`, sorted by file name.
pub fn read_records(dir: &Path) -> Result<Vec<(PathBuf, ShardRecord)>, ShardError> {
    let records = dir.join(RECORDS_DIRECTORY);
    if !records.is_dir() {
        return Ok(Vec::new());
    }
    let entries = fs::read_dir(&records).map_err(|e| OutputError::io("reading", &records, e))?;
    let mut paths = Vec::new();
    for entry in entries {
        let path = entry
            .map_err(|e| OutputError::io("reading", &records, e))?
            .path();
        let hidden = path
            .file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with('.'));
        if !hidden && path.extension().is_some_and(|e| e == "json") {
            paths.push(path);
        }
    }
    paths.sort();
    paths
        .into_iter()
        .map(|path| {
            let text =
                fs::read_to_string(&path).map_err(|e| OutputError::io("reading", &path, e))?;
            let record = serde_json::from_str(&text).map_err(|e| ShardError::Malformed {
                path: path.clone(),
                problem: format!("not a shard record: {e}"),
            })?;
            Ok((path, record))
        })
        .collect()
}

/// Checks that every record in `dir` follows `plan` (the first that does
/// not is named with the field that differs).
pub fn check_records(dir: &Path, plan: &SweepPlan) -> Result<(), ShardError> {
    for (path, record) in read_records(dir)? {
        if let Some(field) = record.plan.first_difference(plan) {
            return Err(ShardError::Mismatch {
                path,
                written_by: record.written_by,
                field,
                other: "this run".into(),
                other_by: "the command given".into(),
            });
        }
    }
    Ok(())
}

/// Prepares `dir` for a shard or for `--slurm`: creates it, refuses a
/// non-empty directory without a `shards/` subdirectory (shards starting
/// at once into a fresh `dir` all pass: the first creates it) and records
/// that disagree with `record`'s plan, then writes `record` to `path`
/// atomically.
pub fn begin(dir: &Path, path: &Path, record: &ShardRecord) -> Result<(), ShardError> {
    create_dir(dir)?;
    let empty = fs::read_dir(dir)
        .map_err(|e| OutputError::io("reading", dir, e))?
        .next()
        .is_none();
    if !empty && !dir.join(RECORDS_DIRECTORY).is_dir() {
        return Err(ShardError::NotSharded {
            path: dir.to_path_buf(),
        });
    }
    create_dir(&dir.join(RECORDS_DIRECTORY))?;
    check_records(dir, &record.plan)?;
    let text = serde_json::to_string_pretty(record).map_err(|e| ShardError::Malformed {
        path: path.to_path_buf(),
        problem: e.to_string(),
    })? + "\n";
    write_atomically(path, text.as_bytes())?;
    Ok(())
}

/// Writes `contents` to a hidden temporary file beside `path` and renames
/// it over `path`: readers see the old file or the new one, never a part.
pub fn write_atomically(path: &Path, contents: &[u8]) -> Result<(), OutputError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let temporary = path.with_file_name(format!(".{name}.partial-{}", std::process::id()));
    write_file(&temporary, contents)?;
    fs::rename(&temporary, path).map_err(|e| {
        let _ = fs::remove_file(&temporary);
        OutputError::io("renaming into", path, e)
    })
}

/// Writes `sweep.csv` and `sweep.svg` (or `sweep.png`, as `format` says)
/// of `rows` into `dir` (each atomically).
pub fn write_sweep(
    dir: &Path,
    rows: &[SweepRow],
    title: &Title,
    style: PlotArgs,
) -> Result<(), ShardError> {
    let format = style.format;
    let table = dir.join("sweep.csv");
    let text = sweep_table(rows).map_err(|e| ShardError::Malformed {
        path: table.clone(),
        problem: e.to_string(),
    })?;
    write_atomically(&table, &text)?;
    let points: Vec<SweepPoint> = rows
        .iter()
        .map(|r| SweepPoint {
            defender_nodes: r.defender_nodes,
            adversary_nodes: r.adversary_nodes,
            worst_case: r.worst_case,
            bracket: r.certified_lower.zip(r.upper_bound),
        })
        .collect();
    let name = format!("sweep.{format}");
    let plot = dir.join(&name);
    let temporary = dir.join(format!(".{name}.partial-{}", std::process::id()));
    plot_sweep(&temporary, (format, style.picture()), title, &points).map_err(|e| {
        ShardError::Malformed {
            path: plot.clone(),
            problem: e.to_string(),
        }
    })?;
    fs::rename(&temporary, &plot).map_err(|e| OutputError::io("renaming into", &plot, e))?;
    Ok(())
}

/// Reads the row of `sweep.csv` of one pair directory ([`ROW_FILE`]),
/// checked: the header is exactly [`SWEEP_COLUMNS`] and the row passes
/// [`SweepRow::check`]; an error names the file, the line and the column.
pub fn read_row(pair: &Path) -> Result<SweepRow, ShardError> {
    let path = pair.join(ROW_FILE);
    let malformed = |problem: String| ShardError::Malformed {
        path: path.clone(),
        problem,
    };
    let mut reader = csv::Reader::from_path(&path).map_err(|e| malformed(e.to_string()))?;
    let header = reader
        .headers()
        .map_err(|e| malformed(e.to_string()))?
        .clone();
    check_header(&header).map_err(|problem| malformed(format!("line 1: {problem}")))?;
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| malformed(e.to_string()))?;
        let line = record.position().map_or(0, csv::Position::line);
        let row: SweepRow = record
            .deserialize(Some(&header))
            .map_err(|e| malformed(format!("line {line}: {e}")))?;
        row.check()
            .map_err(|problem| malformed(format!("line {line}: {problem}")))?;
        rows.push(row);
    }
    match <[SweepRow; 1]>::try_from(rows) {
        Ok([row]) => Ok(row),
        Err(rows) => Err(malformed(format!("{} rows, expected 1", rows.len()))),
    }
}

/// `Err(problem)` unless `header` is exactly [`SWEEP_COLUMNS`], naming the
/// first column that differs.
fn check_header(header: &csv::StringRecord) -> Result<(), String> {
    let expected = || format!("the columns are {}", SWEEP_COLUMNS.join(","));
    for (i, &column) in SWEEP_COLUMNS.iter().enumerate() {
        match header.get(i) {
            Some(found) if found == column => {}
            Some(found) => {
                return Err(format!(
                    "column {} is `{found}`, expected `{column}` ({})",
                    i + 1,
                    expected()
                ));
            }
            None => {
                return Err(format!(
                    "column `{column}` is missing: {} columns, expected {} ({})",
                    header.len(),
                    SWEEP_COLUMNS.len(),
                    expected()
                ));
            }
        }
    }
    match header.get(SWEEP_COLUMNS.len()) {
        Some(extra) => Err(format!(
            "column {} `{extra}` is not a column of row.csv ({})",
            SWEEP_COLUMNS.len() + 1,
            expected()
        )),
        None => Ok(()),
    }
}

/// A merged sweep: the plan all shards followed and the rows of `sweep.csv`.
#[derive(Debug, Clone)]
pub struct Merged {
    /// The plan.
    pub plan: SweepPlan,
    /// The rows, in the order of the unsharded sweep.
    pub rows: Vec<SweepRow>,
}

/// Collects a sharded sweep in `dir`: every record must follow the same
/// plan, every size pair must be present (else [`ShardError::Missing`]
/// names each missing pair and its shard), each pair's row must be of its
/// sizes and its `summary.json` of the plan's settings. Writes nothing.
pub fn collect(dir: &Path) -> Result<Merged, ShardError> {
    let records = read_records(dir)?;
    let Some((first_path, first)) = records.first() else {
        return Err(ShardError::NoRecords {
            path: dir.to_path_buf(),
        });
    };
    for (path, record) in &records[1..] {
        if let Some(field) = record.plan.first_difference(&first.plan) {
            return Err(ShardError::Mismatch {
                path: path.clone(),
                written_by: record.written_by.clone(),
                field,
                other: first_path.display().to_string(),
                other_by: first.written_by.clone(),
            });
        }
    }
    let plan = first.plan.clone();
    let started = |index: usize| {
        let shard = Shard {
            index,
            count: plan.shards,
        };
        records
            .iter()
            .any(|(path, _)| *path == shard_record_path(dir, shard))
    };
    let mut rows = Vec::new();
    let mut missing = Vec::new();
    for (n, m) in plan.pairs() {
        let pair = dir.join(pair_directory_name(n, m));
        if !pair.join(ROW_FILE).is_file() {
            let index = plan.shard_of(m).unwrap_or(1);
            missing.push(MissingPair {
                defender_nodes: n,
                adversary_nodes: m,
                shard: Shard {
                    index,
                    count: plan.shards,
                },
                shard_started: started(index),
            });
            continue;
        }
        rows.push(checked_row(&pair, n, m, &plan)?);
    }
    if !missing.is_empty() {
        return Err(ShardError::Missing {
            path: dir.to_path_buf(),
            total: plan.pairs().len(),
            missing,
        });
    }
    Ok(Merged { plan, rows })
}

/// The row of the pair directory `pair`, checked to be of sizes `(n, m)`
/// and (by its `summary.json`) of the plan's settings.
fn checked_row(pair: &Path, n: usize, m: usize, plan: &SweepPlan) -> Result<SweepRow, ShardError> {
    let row = read_row(pair)?;
    if (row.defender_nodes, row.adversary_nodes) != (n, m) {
        return Err(ShardError::Malformed {
            path: pair.join(ROW_FILE),
            problem: format!(
                "a row of sizes ({}, {}) in the directory of ({n}, {m})",
                row.defender_nodes, row.adversary_nodes
            ),
        });
    }
    let summary = pair.join("summary.json");
    let text = fs::read_to_string(&summary).map_err(|e| OutputError::io("reading", &summary, e))?;
    let value: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| ShardError::Malformed {
            path: summary.clone(),
            problem: e.to_string(),
        })?;
    if value.get("settings") != Some(&plan.settings) {
        return Err(ShardError::Malformed {
            path: summary,
            problem: "its settings differ from the shard records' (a pair of another sweep?)"
                .into(),
        });
    }
    Ok(row)
}

/// `sweep-merge`: [`collect`], then writes `sweep.csv` and `sweep.svg` (or
/// `sweep.png`) into `dir`, the same as the unsharded sweep's.
pub fn merge(dir: &Path, plot: PlotArgs) -> Result<Merged, ShardError> {
    let merged = collect(dir)?;
    write_sweep(dir, &merged.rows, &merged.plan.title(), plot)?;
    Ok(merged)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(adversary_sizes: Vec<usize>, shards: usize) -> SweepPlan {
        SweepPlan {
            crate_version: "0".into(),
            game_fingerprint: fingerprint(b"game"),
            game_name: None,
            objective: "F goal".into(),
            settings: serde_json::json!({"seed": 0}),
            defender_sizes: vec![1, 2],
            adversary_sizes,
            shards,
            title_main: String::new(),
            title_detail: String::new(),
        }
    }

    #[test]
    fn shards_parse_from_k_slash_n_and_refuse_k_outside_one_to_n() {
        assert_eq!("2/3".parse::<Shard>(), Ok(Shard { index: 2, count: 3 }));
        for bad in ["0/3", "4/3", "1/0", "3", "a/2", "1/-2"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    #[test]
    fn every_chain_belongs_to_exactly_one_shard() {
        let plan = plan(vec![5, 1, 3, 2, 4], 3);
        let mut all: Vec<usize> = (1..=3)
            .flat_map(|index| plan.chains_of(Shard { index, count: 3 }))
            .collect();
        assert_eq!(plan.chains_of(Shard { index: 1, count: 3 }), vec![5, 2]);
        for &m in &plan.adversary_sizes {
            let shard = plan.shard_of(m).unwrap();
            assert!(
                plan.chains_of(Shard {
                    index: shard,
                    count: 3
                })
                .contains(&m)
            );
        }
        all.sort_unstable();
        assert_eq!(all, vec![1, 2, 3, 4, 5]);
    }

    #[test]
    fn the_first_differing_field_is_named() {
        let a = plan(vec![1, 2], 2);
        let mut b = a.clone();
        assert_eq!(a.first_difference(&b), None);
        b.settings = serde_json::json!({"seed": 1});
        assert_eq!(a.first_difference(&b), Some("settings"));
    }

    #[test]
    fn fingerprints_are_fnv1a_64() {
        assert_eq!(fingerprint(b""), "fnv1a64:cbf29ce484222325");
        assert_eq!(fingerprint(b"a"), "fnv1a64:af63dc4c8601ec8c");
    }

    #[test]
    fn a_row_survives_its_file_unchanged() {
        let dir = std::env::temp_dir().join(format!("posg-fsc-row-{}", std::process::id()));
        create_dir(&dir).unwrap();
        let row = SweepRow {
            defender_nodes: 2,
            adversary_nodes: 1,
            structure: "full".into(),
            gmc_states: 10,
            gmc_transitions: 30,
            defender_parameters: 4,
            adversary_parameters: 2,
            last_value: 0.1 + 0.2,
            worst_case: 1.0 / 3.0,
            error_bound: 1e-13,
            certified_lower: None,
            upper_bound: Some(0.7),
            iterations: 5,
            seconds: 0.25,
            warm_started: true,
            result: "optimised on full, starting from the 1-node result".into(),
        };
        write_file(
            &dir.join(ROW_FILE),
            sweep_table(std::slice::from_ref(&row)).unwrap(),
        )
        .unwrap();
        assert_eq!(read_row(&dir).unwrap(), row);
        let text = String::from_utf8(sweep_table(std::slice::from_ref(&row)).unwrap()).unwrap();
        assert_eq!(text.lines().next(), Some(SWEEP_COLUMNS.join(",").as_str()));
        fs::remove_dir_all(&dir).unwrap();
    }
}
