//! The Slurm scripts `relume bake plan --slurm` writes beside a plan (docs/CLUSTER.md): an
//! array job of its shards, the merge, and `submit.sh`, which submits the shards not yet done
//! and the merge after them. They follow what Debian 12's Slurm 22.05 does: a dependency on
//! the array's id never succeeds once a task was requeued, while one on each task's id does;
//! a merge without --kill-on-invalid-dep waits for ever after a failed shard.

use anyhow::{Context, Result};
use std::path::{Path, PathBuf};

/// What the scripts need: absolute paths, since a task runs wherever Slurm puts it.
pub(crate) struct Settings {
    pub plan: PathBuf,
    /// Where relative paths among the bake's parameters resolve: the folder the plan was
    /// made in.
    pub folder: PathBuf,
    pub artifact: PathBuf,
    pub shards: usize,
    pub max_parallel: Option<u32>,
    pub cpus_per_task: u32,
}

/// Writes `slurm/` (its scripts and an empty `logs/`) into the plan folder `staged`; refuses
/// paths that an `#SBATCH` line cannot hold (white space, and `%`, which Slurm expands).
pub(crate) fn write_scripts(staged: &Path, settings: &Settings) -> Result<()> {
    for path in [&settings.plan, &settings.folder, &settings.artifact] {
        let text = path.display().to_string();
        if text.contains(|c: char| c.is_whitespace() || c == '%') {
            anyhow::bail!("{text}: a path with white space or % cannot go in an #SBATCH line; plan in, and bake to, folders without them");
        }
    }
    let folder = staged.join("slurm");
    std::fs::create_dir_all(folder.join("logs")).with_context(|| format!("{}: cannot create the folder", folder.display()))?;
    let program = std::env::current_exe().context("cannot find relume's own program")?;
    // An assignment: its quotes are removed and its value is not split.
    let program = format!("relume=${{RELUME:-{}}}", quoted(&program));
    let plan = quoted(&settings.plan);
    let logs = settings.plan.join("slurm/logs");
    let cpus = settings.cpus_per_task;
    let chdir = settings.folder.display();
    let shards = format!(
        "#!/bin/bash\n\
         # One shard of the plan per task of the array (written by `relume bake plan --slurm`;\n\
         # submit.sh submits it). RELUME overrides the program's path.\n\
         #SBATCH --job-name=relume-shard\n\
         #SBATCH --chdir={chdir}\n\
         #SBATCH --cpus-per-task={cpus}\n\
         #SBATCH --output={}/shard-%a.log\n\
         set -euo pipefail\n\
         {program}\n\
         exec \"$relume\" bake shard {plan} --index \"$SLURM_ARRAY_TASK_ID\" --threads \"${{SLURM_CPUS_PER_TASK:-{cpus}}}\"\n",
        logs.display()
    );
    // The merge's reduction runs on one node: it takes the whole node, all its cores and
    // memory (--exclusive alone leaves memory at the partition's default where it is limited).
    let merge = format!(
        "#!/bin/bash\n\
         # The merge of the plan's parts into the artifact (written by `relume bake plan --slurm`).\n\
         #SBATCH --job-name=relume-merge\n\
         #SBATCH --chdir={chdir}\n\
         #SBATCH --exclusive\n\
         #SBATCH --mem=0\n\
         #SBATCH --output={}/merge.log\n\
         set -euo pipefail\n\
         {program}\n\
         exec \"$relume\" bake merge {plan} --out {}\n",
        logs.display(),
        quoted(&settings.artifact)
    );
    let cap = settings.max_parallel.map(|k| format!("%{k}")).unwrap_or_default();
    let submit = format!(
        r#"#!/usr/bin/env bash
# Submits the plan's {} shards that are not done as one Slurm array, then the merge after them
# (written by `relume bake plan --slurm`). After a failure, run it again: it submits only the
# shards whose parts are missing or damaged. Its arguments go to the merge's sbatch (--wait:
# return when the merge ends, with its exit code). RELUME overrides the program's path.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
{program}
missing="$("$relume" bake status {plan} --missing)"
dependency=()
if [ -n "$missing" ]; then
  array="$(sbatch --parsable --array="$missing{cap}" "$here/shards.sbatch")"
  array="${{array%%;*}}"
  echo "submitted shards $missing as job $array"
  # On each task's id: afterok on the array's own id never succeeds once a task was requeued.
  after=afterok
  for i in ${{missing//,/ }}; do after+=":${{array}}_$i"; done
  # Without it a failed shard would leave the merge pending for ever.
  dependency=(--dependency="$after" --kill-on-invalid-dep=yes)
fi
echo "submitting the merge"
sbatch --parsable ${{dependency[@]+"${{dependency[@]}}"}} "$@" "$here/merge.sbatch"
"#,
        settings.shards
    );
    for (name, text) in [("shards.sbatch", shards), ("merge.sbatch", merge), ("submit.sh", submit)] {
        relume_bake::outputs::write_staged(&folder.join(name), text.as_bytes())
            .with_context(|| format!("{}: cannot write", folder.join(name).display()))?;
    }
    Ok(())
}

/// `path` as one word of a shell command line.
fn quoted(path: &Path) -> String {
    format!("'{}'", path.display().to_string().replace('\'', r"'\''"))
}
