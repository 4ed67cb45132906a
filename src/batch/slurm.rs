//! The Slurm job-array script of a batch (`groombake batch M --emit slurm`).
//!
//! Task `i` runs shard `i/N` of the manifest's `N` jobs, with `N` written
//! into the script: any subset of the tasks (`sbatch --array=3 bake.sbatch`
//! to bake job 3 again) runs the same jobs as in the full array. The lowest
//! task of a submission submits the merge, which waits for the whole array.

use super::Manifest;
use serde::Deserialize;
use std::path::Path;

/// Scheduler requests of the array tasks: the manifest's `[slurm]` table,
/// overridden by the command line's `--time`, `--mem`, `--partition`,
/// `--account`. Unset ones are left to the cluster's defaults.
#[derive(Debug, Clone, Default, Deserialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub struct SlurmSettings {
    /// Wall-time limit of each task, in Slurm's forms: `MINUTES`,
    /// `MM:SS`, `HH:MM:SS`, `D-HH`, `D-HH:MM`, `D-HH:MM:SS`.
    pub time: Option<String>,
    /// Memory of each task: a whole number with an optional unit
    /// `K`, `M`, `G` or `T` (Slurm's default unit is megabytes).
    pub mem: Option<String>,
    /// Partition (or a comma-separated list of partitions).
    pub partition: Option<String>,
    /// Account charged for the tasks.
    pub account: Option<String>,
}

impl SlurmSettings {
    /// Each value checked ([`check`]); the first bad one named.
    pub fn check(&self) -> Result<(), String> {
        for (key, value) in self.entries() {
            check(key, value)?;
        }
        Ok(())
    }

    /// The set values, with their `sbatch` option names.
    fn entries(&self) -> impl Iterator<Item = (&'static str, &str)> {
        [
            ("time", &self.time),
            ("mem", &self.mem),
            ("partition", &self.partition),
            ("account", &self.account),
        ]
        .into_iter()
        .filter_map(|(k, v)| v.as_deref().map(|v| (k, v)))
    }

    /// These settings with `other`'s set values in their place.
    pub fn overridden_by(&self, other: &SlurmSettings) -> SlurmSettings {
        SlurmSettings {
            time: other.time.clone().or_else(|| self.time.clone()),
            mem: other.mem.clone().or_else(|| self.mem.clone()),
            partition: other.partition.clone().or_else(|| self.partition.clone()),
            account: other.account.clone().or_else(|| self.account.clone()),
        }
    }
}

/// Whether `text` is a Slurm time limit (see [`SlurmSettings::time`]).
fn is_time(text: &str) -> bool {
    let numbers = |t: &str, most: usize| {
        let parts: Vec<&str> = t.split(':').collect();
        parts.len() <= most
            && parts
                .iter()
                .all(|p| !p.is_empty() && p.len() <= 4 && p.bytes().all(|b| b.is_ascii_digit()))
    };
    match text.split_once('-') {
        Some((days, rest)) => {
            !days.is_empty() && days.bytes().all(|b| b.is_ascii_digit()) && numbers(rest, 3)
        }
        None => numbers(text, 3),
    }
}

/// Checks one value: a wrong one would make `sbatch` refuse the whole
/// array on the farm, long after the script was written; and no value may
/// carry a character the script's lines cannot hold.
pub fn check(key: &str, value: &str) -> Result<(), String> {
    let ok = match key {
        "time" => is_time(value),
        "mem" => {
            let digits = value.trim_end_matches(['K', 'M', 'G', 'T']);
            !digits.is_empty()
                && value.len() - digits.len() <= 1
                && digits.bytes().all(|b| b.is_ascii_digit())
        }
        _ => {
            !value.is_empty()
                && value
                    .bytes()
                    .all(|b| b.is_ascii_alphanumeric() || matches!(b, b'_' | b'-' | b'.' | b','))
        }
    };
    if ok {
        return Ok(());
    }
    let expected = match key {
        "time" => "MINUTES, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS",
        "mem" => "a whole number with an optional unit K, M, G or T (e.g. 8G)",
        _ => "letters, digits, '_', '-', '.' and ','",
    };
    Err(format!("slurm {key} '{value}': expected {expected}"))
}

/// Quotes a word for a POSIX shell.
fn shell_quote(text: &str) -> String {
    format!("'{}'", text.replace('\'', r"'\''"))
}

/// A Slurm job-array script: task `i` of the array `0-(N-1)` runs shard
/// `i/N` (job `i`) of the manifest's `N` jobs. `sbatch` it as it is, or a
/// subset of it (`sbatch --array=3 THIS_FILE`).
pub fn script(
    manifest: &Manifest,
    executable: &Path,
    threads: usize,
    settings: &SlurmSettings,
) -> String {
    let exe = shell_quote(&executable.display().to_string());
    let path = std::path::absolute(&manifest.path).unwrap_or_else(|_| manifest.path.clone());
    let out = std::path::absolute(&manifest.out).unwrap_or_else(|_| manifest.out.clone());
    let manifest_arg = shell_quote(&path.display().to_string());
    let logs = shell_quote(&out.join("slurm").display().to_string());
    let jobs = manifest.jobs.len();
    let last = jobs.saturating_sub(1);
    let requests: String = settings
        .entries()
        .map(|(key, value)| format!("#SBATCH --{key}={value}\n"))
        .collect();
    // The merge runs where the tasks may: the same partition and account.
    let merge_options: String = settings
        .entries()
        .filter(|(key, _)| matches!(*key, "partition" | "account"))
        .map(|(key, value)| format!(" --{key}={value}"))
        .collect();
    format!(
        r#"#!/bin/bash
# groombake batch of {manifest}: {jobs} job(s) as a Slurm job array.
# Submit with `sbatch THIS_FILE`; bake some jobs again with
# `sbatch --array=3,5 THIS_FILE`. Task i runs job i of the {jobs}: emit the
# script again after adding or removing jobs. The lowest task of each
# submission submits the merge of the reports, which runs when every task
# of the submission has ended.
#SBATCH --job-name=groombake
#SBATCH --array=0-{last}
#SBATCH --ntasks=1
#SBATCH --cpus-per-task={threads}
{requests}#SBATCH --output={log_dir}/groombake-%A_%a.log
set -euo pipefail
exe={exe}
manifest={manifest_arg}
jobs={jobs}
if [ "$SLURM_ARRAY_TASK_ID" = "${{SLURM_ARRAY_TASK_MIN:-0}}" ]; then
  if merge=$(sbatch --parsable --job-name=groombake-merge{merge_options} \
    --dependency="afterany:$SLURM_ARRAY_JOB_ID" \
    --output={logs}/groombake-merge-%j.log \
    --wrap="$(printf '%q ' "$exe" batch "$manifest" --merge)"); then
    echo "merge job: $merge"
  else
    # The bake goes on; the reports can be merged by hand.
    echo "groombake: could not submit the merge; run: $exe batch $manifest --merge" >&2
  fi
fi
exec "$exe" batch "$manifest" --threads {threads} \
  --shard "$SLURM_ARRAY_TASK_ID/$jobs"
"#,
        manifest = path.display(),
        log_dir = out.join("slurm").display(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slurm_values_are_checked() {
        for good in ["30", "1:30", "02:00:00", "1-12", "1-12:30", "2-00:00:00"] {
            assert_eq!(check("time", good), Ok(()), "{good}");
        }
        for bad in ["", "1h", "1:2:3:4", "-1", "1-", "10 00"] {
            assert!(check("time", bad).is_err(), "{bad}");
        }
        for good in ["8G", "512", "64000M"] {
            assert_eq!(check("mem", good), Ok(()), "{good}");
        }
        for bad in ["", "G", "8GB", "8 G", "-1"] {
            assert!(check("mem", bad).is_err(), "{bad}");
        }
        assert_eq!(check("partition", "gpu,cpu"), Ok(()));
        let err = check("account", "a\n#SBATCH --x").unwrap_err();
        assert!(err.contains("slurm account"), "{err}");
    }
}
