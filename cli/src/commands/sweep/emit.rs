//! `--emit slurm|k8s`: a scheduler's job with one task per shard, each task running
//! `critterbox sweep FILE --out DIR --shard I/N`, and the command that collects afterwards.
//! The scheduler then owns retries and placement; a task run twice redoes nothing finished.

use super::{plan, Emit, SweepArgs};
use anyhow::Context;
use critterbox::sweep::SweepFile;
use std::io::Write;
use std::path::Path;

/// Writes the job file into `dir` and says how to submit and collect.
pub fn run(
    emit: Emit,
    file: &SweepFile,
    dir: &Path,
    args: &SweepArgs,
    out: &mut dyn Write,
) -> anyhow::Result<()> {
    let runs = plan(file).len();
    let shards = args.shards.map_or(runs.clamp(1, 16), |s| s as usize);
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let stem = file.path.file_stem().map_or("sweep".into(), |s| {
        s.to_string_lossy()
            .to_lowercase()
            .replace(['_', '.', ' '], "-")
    });
    match emit {
        Emit::Slurm => {
            // Absolute paths: the tasks may start anywhere sbatch sends them.
            let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
            let exe = std::env::current_exe().context("finding the critterbox executable")?;
            let (sweep, outdir) = (abs(&file.path), abs(dir));
            let logs = outdir.join("slurm");
            std::fs::create_dir_all(&logs)
                .with_context(|| format!("creating {}", logs.display()))?;
            let script = slurm(&stem, &exe, &sweep, &outdir, shards, args.cpus);
            let path = dir.join("sweep.sbatch");
            std::fs::write(&path, script).with_context(|| format!("writing {}", path.display()))?;
            writeln!(
                out,
                "slurm        {} ({runs} runs in {shards} array tasks of {} cpus)",
                path.display(),
                args.cpus
            )?;
            writeln!(out, "submit       sbatch --wait {}", path.display())?;
        }
        Emit::K8s => {
            let yaml = k8s(&stem, &args.image, &file.path, dir, shards, args.cpus);
            let path = dir.join("sweep-job.yaml");
            std::fs::write(&path, yaml).with_context(|| format!("writing {}", path.display()))?;
            writeln!(
                out,
                "k8s          {} ({runs} runs in {shards} indexed completions of {} cpus)",
                path.display(),
                args.cpus
            )?;
            writeln!(out, "submit       kubectl apply -f {} && kubectl wait --for=condition=complete job/critterbox-{stem} --timeout=-1s", path.display())?;
        }
    }
    writeln!(
        out,
        "collect      critterbox sweep {} --collect {}",
        file.path.display(),
        dir.display()
    )?;
    Ok(())
}

/// Single quotes for the shell.
fn sh(p: &Path) -> String {
    format!("'{}'", p.display().to_string().replace('\'', r"'\''"))
}

fn slurm(stem: &str, exe: &Path, sweep: &Path, dir: &Path, shards: usize, cpus: u64) -> String {
    format!(
        r#"#!/bin/bash
# critterbox sweep {sweep}: one array task per shard. Shards count from 1, as
# SLURM_ARRAY_TASK_ID does here. A task run again (requeued, resubmitted) redoes only what is
# missing. When every task is done:
#   critterbox sweep {sweep} --collect {dir}
#SBATCH --job-name=critterbox-{stem}
#SBATCH --array=1-{shards}
#SBATCH --ntasks=1
#SBATCH --cpus-per-task={cpus}
#SBATCH --output={logs}/%A_%a.out
set -euo pipefail
exec {exe} sweep {sweep_q} --out {dir_q} \
  --shard "${{SLURM_ARRAY_TASK_ID}}/{shards}" --jobs "${{SLURM_CPUS_PER_TASK:-{cpus}}}"
"#,
        sweep = sweep.display(),
        dir = dir.display(),
        logs = dir.join("slurm").display(),
        exe = sh(exe),
        sweep_q = sh(sweep),
        dir_q = sh(dir),
    )
}

fn k8s(stem: &str, image: &str, sweep: &Path, dir: &Path, shards: usize, cpus: u64) -> String {
    format!(
        r#"# critterbox sweep {sweep}: one indexed completion per shard (JOB_COMPLETION_INDEX counts
# from 0, shards from 1). The image must hold critterbox and the sweep's files; the volume
# "sweep-out" (a ReadWriteMany claim) holds {dir} for every pod. When the job is complete:
#   critterbox sweep {sweep} --collect {dir}
apiVersion: batch/v1
kind: Job
metadata:
  name: critterbox-{stem}
spec:
  completionMode: Indexed
  completions: {shards}
  parallelism: {shards}
  backoffLimit: {backoff}
  template:
    spec:
      restartPolicy: Never
      containers:
        - name: sweep
          image: {image}
          command: ["sh", "-c"]
          args:
            - exec critterbox sweep '{sweep}' --out '{dir}' --shard "$((JOB_COMPLETION_INDEX + 1))/{shards}" --jobs {cpus}
          resources:
            requests:
              cpu: "{cpus}"
          volumeMounts:
            - name: sweep-out
              mountPath: {dir}
      volumes:
        - name: sweep-out
          persistentVolumeClaim:
            claimName: critterbox-{stem}
"#,
        sweep = sweep.display(),
        dir = dir.display(),
        backoff = shards * 2,
    )
}
