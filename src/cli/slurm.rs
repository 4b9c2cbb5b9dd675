//! Slurm batch scripts for a sharded sweep ([`super::shard`]): an array job
//! whose task `K` runs shard `K/N`, and a merge job to submit with a
//! dependency on it. Plain text only: nothing here needs Slurm.

use std::path::Path;

use posg_fsc::output::{PlotFormat, PlotSize};

use super::common::PlotArgs;

/// What the scripts run and where.
#[derive(Debug, Clone)]
pub struct SlurmSweep<'a> {
    /// The `posg-fsc` executable (an absolute path).
    pub program: &'a Path,
    /// The directory the sweep was prepared in; the jobs run there, so
    /// relative paths in `sweep_arguments` keep their meaning.
    pub working_directory: &'a Path,
    /// The arguments after the program (`sweep GAME ... --out DIR`),
    /// without `--shard`, `--slurm`, `--slurm-option` and `--shards`.
    pub sweep_arguments: &'a [String],
    /// The sweep's output directory (absolute).
    pub out: &'a Path,
    /// N, the number of shards (array tasks).
    pub shards: usize,
    /// The plots' format and size, passed on to `sweep-merge` (`--format
    /// png --size 1200x700`).
    pub plot: PlotArgs,
    /// Extra `#SBATCH` options, each as given (`--partition=short`).
    pub options: &'a [String],
    /// The command line that wrote the scripts, recorded in them.
    pub command_line: &'a [String],
}

/// The subdirectory of the sweep's directory for Slurm's log files
/// (created before submitting: Slurm does not create it).
pub const LOG_DIRECTORY: &str = "slurm-logs";

/// `text` as one word of a POSIX shell: in single quotes, with each `'`
/// written as `'\''`.
pub fn shell_quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', r"'\''"))
}

/// Checks an `#SBATCH` option given by the user: it starts with `-` and is
/// one line.
pub fn check_option(option: &str) -> Result<(), String> {
    if !option.starts_with('-') {
        return Err(format!(
            "--slurm-option `{option}`: an sbatch option starts with `-` (e.g. --partition=short)"
        ));
    }
    if option.contains(['\n', '\r']) {
        return Err(format!("--slurm-option `{option}`: must be one line"));
    }
    Ok(())
}

fn header(sweep: &SlurmSweep, name: &str, log: &str) -> String {
    let mut text = String::from("#!/bin/sh\n");
    text += &format!("#SBATCH --job-name={name}\n");
    text += &format!("#SBATCH --chdir={}\n", sweep.working_directory.display());
    text += &format!(
        "#SBATCH --output={}\n",
        sweep.out.join(LOG_DIRECTORY).join(log).display()
    );
    text
}

fn footer(sweep: &SlurmSweep, what: &str) -> String {
    let mut text = String::new();
    for option in sweep.options {
        text += &format!("#SBATCH {option}\n");
    }
    text += &format!(
        "# {what}; written by posg-fsc {} ({})\n",
        env!("CARGO_PKG_VERSION"),
        sweep
            .command_line
            .iter()
            .map(|a| shell_quote(a))
            .collect::<Vec<_>>()
            .join(" ")
    );
    text += "set -e\n";
    text += &format!(
        "cd {}\n",
        shell_quote(&sweep.working_directory.display().to_string())
    );
    text
}

/// `sweep.sbatch`: an array job `1-N` whose task `K` runs
/// `posg-fsc sweep ... --shard K/N`.
pub fn array_script(sweep: &SlurmSweep) -> String {
    let mut text = header(sweep, "posg-fsc-sweep", "shard-%a-of-%A.out");
    text += &format!("#SBATCH --array=1-{}\n", sweep.shards);
    text += &footer(sweep, "one shard of a posg-fsc sweep per array task");
    let arguments: Vec<String> = sweep
        .sweep_arguments
        .iter()
        .map(|a| shell_quote(a))
        .collect();
    text += &format!(
        "exec {} {} --shard \"$SLURM_ARRAY_TASK_ID/{}\"\n",
        shell_quote(&sweep.program.display().to_string()),
        arguments.join(" "),
        sweep.shards
    );
    text
}

/// `sweep-merge.sbatch`: `posg-fsc sweep-merge DIR`, to run after every
/// array task succeeded.
pub fn merge_script(sweep: &SlurmSweep) -> String {
    let mut text = header(sweep, "posg-fsc-sweep-merge", "merge-%j.out");
    text += &footer(sweep, "the merge of a sharded posg-fsc sweep");
    let mut format = match sweep.plot.format {
        PlotFormat::Svg => String::new(),
        format => format!(" --format {format}"),
    };
    if sweep.plot.size != PlotSize::default() {
        format += &format!(" --size {}", sweep.plot.size);
    }
    if sweep.plot.dpi != PlotSize::DEFAULT_DPI {
        format += &format!(" --dpi {}", sweep.plot.dpi);
    }
    text += &format!(
        "exec {} sweep-merge {}{format}\n",
        shell_quote(&sweep.program.display().to_string()),
        shell_quote(&sweep.out.display().to_string())
    );
    text
}

/// The shell commands that submit the array job and the merge after it
/// (`afterok`: only if every task succeeded).
pub fn submit_commands(array_script: &Path, merge_script: &Path) -> String {
    format!(
        "JOBID=$(sbatch --parsable {}) && JOBID=${{JOBID%%;*}}\n\
         sbatch --dependency=afterok:$JOBID {}\n",
        shell_quote(&array_script.display().to_string()),
        shell_quote(&merge_script.display().to_string())
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quoting_survives_single_quotes_and_spaces() {
        assert_eq!(shell_quote("a b"), "'a b'");
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
    }

    #[test]
    fn options_must_start_with_a_dash_and_be_one_line() {
        assert!(check_option("--partition=short").is_ok());
        assert!(check_option("partition=short").is_err());
        assert!(check_option("--x\n#SBATCH --y").is_err());
    }
}
