//! The farm on a real Slurm: a one-node cluster (Debian 12's Slurm 22.05, started by
//! scripts/local-slurm.sh) runs docs/slurm/caustica-array.sbatch, the script users copy, as an
//! array of 8 tasks rendering a 32x32 Cornell box, and the dependent merge job of the script's
//! header adds the parts up. Then the same array again with failures injected: one task preempted
//! (`scancel --signal=TERM`, requeued), one killed hard (its process and the step daemon watching
//! it SIGKILLed, as a node that dies takes both, then requeued). Its merge must be the first run's
//! bit for bit: nothing lost, no sample twice. docs/farm.md shows these commands and what each
//! failure cost.
//!
//! Needs root (the daemons) and Slurm (installed with apt-get when missing). Where the cluster
//! cannot start the test says SKIPPED and why, unless CAUSTICA_REQUIRE_SLURM is set (CI's .ci/run
//! sets it): then that is a failure.

mod common;

use caustica::farm::PartialRender;
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant, SystemTime};

const TASKS: u32 = 8;
/// Samples per pixel of one task: a few seconds of Mesa 25's lavapipe on a 32x32 image even on an
/// idle machine, so that a task can be caught between two checkpoints (at 1536 spp an idle CI
/// machine finished tasks 2 to 4 before the test could pause one).
const SPP_PER_TASK: u32 = 8192;
const SIZE: u32 = 32;
/// The tasks' `--checkpoint-every` (CHECKPOINT_EVERY of the script): several per task.
const CHECKPOINT_EVERY: &str = "300ms";
/// How long a whole array may take before the test gives up (it takes about 40 s on 2 cores).
const ARRAY_TIMEOUT: Duration = Duration::from_secs(240);

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// SLURM_CONF of the local cluster, started if it is not running; None (SKIPPED said) where it
/// cannot start.
fn cluster() -> Option<String> {
    let skip = |why: String| {
        if std::env::var_os("CAUSTICA_REQUIRE_SLURM").is_some() {
            panic!("CAUSTICA_REQUIRE_SLURM is set but the local Slurm cluster cannot start: {why}");
        }
        eprintln!("SKIPPED: the Slurm tests need a local cluster (scripts/local-slurm.sh start): {why}");
        None
    };
    let uid = Command::new("id").arg("-u").output().expect("run id");
    if String::from_utf8_lossy(&uid.stdout).trim() != "0" {
        return skip("not root".into());
    }
    let start =
        Command::new("bash").arg(repo().join("scripts/local-slurm.sh")).arg("start").output().expect("run bash");
    let said = format!("{}{}", String::from_utf8_lossy(&start.stdout), String::from_utf8_lossy(&start.stderr));
    if !start.status.success() {
        return skip(said);
    }
    let conf = said.lines().find_map(|l| l.strip_prefix("local-slurm: export SLURM_CONF=")).map(str::to_owned);
    Some(conf.unwrap_or_else(|| panic!("local-slurm.sh start did not say SLURM_CONF: {said}")))
}

/// A Slurm client command against the local cluster, run in `dir`, with this build's caustica
/// first on PATH (sbatch passes the environment on to the jobs) on the suite's Vulkan driver.
fn slurm_command(conf: &str, dir: &Path, program: &str, args: &[&str]) -> Command {
    let bin = Path::new(env!("CARGO_BIN_EXE_caustica")).parent().unwrap();
    let path = format!("{}:{}", bin.display(), std::env::var("PATH").unwrap_or_default());
    let mut cmd = Command::new(program);
    cmd.args(args).current_dir(dir).env("SLURM_CONF", conf).env("PATH", path);
    cmd.env("SPP_PER_TASK", SPP_PER_TASK.to_string()).env("CHECKPOINT_EVERY", CHECKPOINT_EVERY);
    if let Some(icd) = lavapipe_override() {
        cmd.env("VK_DRIVER_FILES", icd);
    }
    cmd
}

/// Runs [`slurm_command`] to its end; panics unless it succeeds.
fn slurm(conf: &str, dir: &Path, program: &str, args: &[&str]) -> Output {
    let out = slurm_command(conf, dir, program, args).output().unwrap_or_else(|e| panic!("{program}: {e}"));
    let said = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{program} {args:?} failed ({}): {said}", out.status);
    out
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).trim().to_owned()
}

/// A folder with the tiny Cornell box, parts/ and logs/, as docs/farm.md's commands expect.
fn farm_folder(tag: &str) -> ScratchDir {
    let dir = temp_dir(tag);
    let cornell = std::fs::read_to_string(repo().join("scenes/cornell.toml")).unwrap();
    let small =
        cornell.replace("width = 512", &format!("width = {SIZE}")).replace("height = 512", &format!("height = {SIZE}"));
    assert!(small.contains(&format!("width = {SIZE}\nheight = {SIZE}")), "scenes/cornell.toml's film changed");
    std::fs::write(dir.join("cornell.toml"), small).unwrap();
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    std::fs::create_dir_all(dir.join("logs")).unwrap();
    dir
}

/// Submits the array and its merge exactly as docs/farm.md says (the tasks' CPUs and memory cut
/// to what this small render needs, as on a laptop); returns the ids of both.
fn submit(conf: &str, dir: &Path) -> (String, String) {
    let script = repo().join("docs/slurm/caustica-array.sbatch");
    let array = format!("--array=0-{}", TASKS - 1);
    let args = ["--parsable", &array, "--cpus-per-task=1", "--mem=1G", script.to_str().unwrap(), "cornell.toml"];
    let job = stdout(&slurm(conf, dir, "sbatch", &args));
    let after = format!("--dependency=afterok:{job}");
    let merge = "caustica merge parts/part-*[0-9].exr -o final.exr && caustica merge final.exr -o final.png";
    let args = ["--parsable", &after, "--job-name=caustica-merge", "--output=logs/merge-%j.out", "--wrap", merge];
    (job.clone(), stdout(&slurm(conf, dir, "sbatch", &args)))
}

/// A job's (or array task's, `JOB_K`) state as scontrol says it: PENDING, RUNNING, COMPLETED...
fn state(conf: &str, dir: &Path, job: &str) -> String {
    let shown = stdout(&slurm(conf, dir, "scontrol", &["show", "job", "--oneliner", job]));
    let state = shown.split_whitespace().find_map(|w| w.strip_prefix("JobState=")).map(str::to_owned);
    state.unwrap_or_else(|| panic!("no JobState in: {shown}"))
}

/// Waits for `done`, polling every 50 ms; panics with the logs after ARRAY_TIMEOUT.
fn wait_for(dir: &Path, what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        if start.elapsed() > ARRAY_TIMEOUT {
            panic!("timed out waiting for {what}; logs:\n{}", logs(dir));
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

fn logs(dir: &Path) -> String {
    let mut all = String::new();
    for entry in std::fs::read_dir(dir.join("logs")).unwrap() {
        let path = entry.unwrap().path();
        all += &format!("== {}\n{}\n", path.display(), std::fs::read_to_string(&path).unwrap_or_default());
    }
    all
}

/// Waits for the merge job to end, and checks that it completed.
fn wait_for_merge(conf: &str, dir: &Path, merge: &str) {
    wait_for(dir, "the merge job", || {
        !["PENDING", "RUNNING", "CONFIGURING"].contains(&state(conf, dir, merge).as_str())
    });
    let end = state(conf, dir, merge);
    assert_eq!(end, "COMPLETED", "the merge job ended {end}; logs:\n{}", logs(dir));
}

/// Task k's `--json` summaries, one per run of it (the script appends a requeued run's log).
fn summaries(dir: &Path, job: &str, k: u32) -> Vec<serde_json::Value> {
    let log = std::fs::read_to_string(dir.join(format!("logs/caustica-{job}_{k}.out"))).unwrap();
    log.lines().filter(|l| l.starts_with('{')).map(|l| serde_json::from_str(l).expect("a JSON summary")).collect()
}

fn part(dir: &Path, k: u32) -> PathBuf {
    dir.join(format!("parts/part-{k}.exr"))
}

fn checkpoint(dir: &Path, k: u32) -> PathBuf {
    dir.join(format!("parts/part-{k}.checkpoint.exr"))
}

/// Samples in task k's checkpoint, if it is there and readable (it is replaced atomically).
fn checkpoint_samples(dir: &Path, k: u32) -> Option<u32> {
    PartialRender::read(&checkpoint(dir, k)).ok().map(|p| p.samples())
}

/// `caustica merge` run here (not through Slurm) of `inputs` into `out`.
fn merge(dir: &Path, inputs: &[PathBuf], out: &str) -> Output {
    let mut args = vec!["merge".to_owned(), "-q".to_owned(), "-o".to_owned(), dir.join(out).display().to_string()];
    args.extend(inputs.iter().map(|p| p.display().to_string()));
    caustica(&args.iter().map(String::as_str).collect::<Vec<_>>())
}

/// Task k's whole sample range.
fn range(k: u32) -> std::ops::Range<u32> {
    k * SPP_PER_TASK..(k + 1) * SPP_PER_TASK
}

/// Sends `signal` ("-STOP", "-KILL") to the process `pid`; whether it was delivered.
fn signal(pid: &str, signal: &str) -> bool {
    Command::new("kill").args([signal, pid]).status().unwrap().success()
}

/// Waits for array task k to start rendering and stops its caustica (SIGSTOP) between two
/// checkpoints, so a failure can be injected mid-render whatever the machine's speed; returns its
/// pid and the samples of its last checkpoint. None if the task ended before it could be caught.
fn paused_mid_render(conf: &str, dir: &Path, job: &str, k: u32) -> Option<(u32, String, u32)> {
    let task = format!("{job}_{k}");
    let ended = |s: &str| !["PENDING", "RUNNING", "CONFIGURING"].contains(&s);
    wait_for(dir, &format!("task {k} to checkpoint"), || {
        let s = state(conf, dir, &task);
        ended(&s) || (s == "RUNNING" && checkpoint(dir, k).exists())
    });
    let pattern = format!("-o parts/part-{k}.exr");
    let pid = stdout(&Command::new("pgrep").args(["-f", "--", &pattern]).output().unwrap());
    assert!(!pid.contains('\n'), "one caustica process for task {k}, not {pid:?}");
    if pid.is_empty() || !signal(&pid, "-STOP") {
        return None;
    }
    match checkpoint_samples(dir, k) {
        Some(n) if n < SPP_PER_TASK => Some((k, pid, n)),
        _ => {
            signal(&pid, "-CONT");
            None
        }
    }
}

#[test]
fn array_job_merges_to_one_render_and_survives_preemption_and_a_hard_kill() {
    let Some(conf) = cluster() else { return };

    // 1. Every task runs to its end; the dependent merge job adds the parts.
    let clean = farm_folder("slurm-clean");
    let started = Instant::now();
    let (job, merge_job) = submit(&conf, &clean);
    wait_for_merge(&conf, &clean, &merge_job);
    let clean_seconds = started.elapsed().as_secs_f64();
    for k in 0..TASKS {
        assert_eq!(state(&conf, &clean, &format!("{job}_{k}")), "COMPLETED");
        assert_eq!(PartialRender::read(&part(&clean, k)).unwrap().ranges, vec![range(k)], "part {k}");
    }
    let merged = PartialRender::read(&clean.join("final.exr")).unwrap();
    let all = TASKS * SPP_PER_TASK;
    assert_eq!(merged.ranges, vec![0..all]);
    assert!(clean.join("final.png").is_file(), "the merge job's PNG");

    // The merge equals one uninterrupted render of the same samples to float rounding: each sum of
    // N non-negative terms is within (N - 1) u of the exact sum (u = 2^-24) whatever the grouping,
    // so two groupings differ by at most 2 N u of the sum. A part missing or counted twice is off
    // by 1/8.
    let one = clean.join("one.exr");
    let spp = all.to_string();
    let o = caustica(&[
        "render",
        clean.join("cornell.toml").to_str().unwrap(),
        "-o",
        one.to_str().unwrap(),
        "--seed",
        "1",
        "--spp",
        &spp,
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let one = PartialRender::read(&one).unwrap();
    let bound = 2.0 * all as f32 * f32::EPSILON / 2.0;
    let mut worst = 0.0f32;
    for (i, (m, r)) in merged.accumulation.iter().zip(&one.accumulation).enumerate() {
        assert_eq!(m[3], r[3], "pixel {i}: sample counts");
        for c in 0..3 {
            let relative = (m[c] - r[c]).abs() / m[c].abs().max(r[c].abs()).max(f32::MIN_POSITIVE);
            worst = worst.max(relative);
            assert!(
                relative <= bound,
                "pixel {i} channel {c}: merged {} vs one render {} ({relative:e} > {bound:e})",
                m[c],
                r[c]
            );
        }
    }
    eprintln!("merge vs one render of {all} spp: largest relative difference {worst:e} (bound {bound:e})");

    // Merges of the same parts, by hand and in other orders, are the merge job's file byte for byte.
    let parts: Vec<PathBuf> = (0..TASKS).map(|k| part(&clean, k)).collect();
    let job_file = std::fs::read(clean.join("final.exr")).unwrap();
    let mut shuffled = parts.clone();
    shuffled.reverse();
    shuffled.swap(1, 5);
    for (order, name) in [(&parts, "again.exr"), (&shuffled, "shuffled.exr")] {
        let o = merge(&clean, order, name);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(std::fs::read(clean.join(name)).unwrap() == job_file, "{name} differs from the merge job's final.exr");
    }

    // A node that died mid-write: the part truncated. merge names it and writes nothing.
    let torn = clean.join("torn");
    std::fs::create_dir(&torn).unwrap();
    let torn_parts: Vec<PathBuf> = (0..TASKS).map(|k| torn.join(format!("part-{k}.exr"))).collect();
    for (from, to) in parts.iter().zip(&torn_parts) {
        std::fs::copy(from, to).unwrap();
    }
    let bytes = std::fs::read(&torn_parts[3]).unwrap();
    std::fs::write(&torn_parts[3], &bytes[..bytes.len() / 2]).unwrap();
    let o = merge(&clean, &torn_parts, "torn.exr");
    assert_eq!(o.status.code(), Some(1), "merge of a truncated part");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains(&format!("{}", torn_parts[3].display())), "the truncated part is not named: {stderr}");
    assert!(!clean.join("torn.exr").exists(), "merge wrote an image from a truncated part");

    // 2. The same array with failures injected.
    let failing = farm_folder("slurm-failures");
    let started = Instant::now();
    let (job, merge_job) = submit(&conf, &failing);
    let task = |k: u32| format!("{job}_{k}");

    // One task preempted: SIGTERM to the batch step (where the script's exec put caustica), which
    // finishes its pass, writes its part and checkpoint and exits; then requeued.
    let (preempted, pid, _) = (2..5)
        .find_map(|k| paused_mid_render(&conf, &failing, &job, k))
        .expect("no task of 2, 3, 4 could be caught mid-render: make SPP_PER_TASK larger");
    // Slurm 22.05's scancel delivers the signal to an array task at once, but then may retry
    // ("Job can not be altered now, try again later") until the task has ended: it runs beside the
    // task, and its exit status says nothing (docs/farm.md). The JSON summary shows the signal came.
    let scancel = slurm_command(&conf, &failing, "scancel", &["--batch", "--signal=TERM", &task(preempted)])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let signalled = Instant::now();
    std::thread::sleep(Duration::from_millis(200));
    signal(&pid, "-CONT");
    wait_for(&failing, "the preempted task to stop", || state(&conf, &failing, &task(preempted)) != "RUNNING");
    let stop_seconds = signalled.elapsed().as_secs_f64();
    let scancel = scancel.wait_with_output().unwrap();
    eprintln!("scancel: {} {}", scancel.status, String::from_utf8_lossy(&scancel.stderr).trim());
    let written = PartialRender::read(&part(&failing, preempted)).unwrap();
    assert!(written.samples() < SPP_PER_TASK, "the preempted task rendered its whole range");
    assert_eq!(PartialRender::read(&checkpoint(&failing, preempted)).unwrap(), written, "part and checkpoint");
    slurm(&conf, &failing, "scontrol", &["requeue", &task(preempted)]);

    // One task killed hard after a checkpoint: caustica and the slurmstepd watching it SIGKILLed
    // (the step daemon first, so nothing reports), as when a node dies; then requeued.
    let (killed, pid, kept) = (5..8)
        .find_map(|k| paused_mid_render(&conf, &failing, &job, k))
        .expect("no task of 5, 6, 7 could be caught mid-render: make SPP_PER_TASK larger");
    let parent = stdout(&Command::new("ps").args(["-o", "ppid=", "-p", &pid]).output().unwrap());
    signal(&parent, "-KILL");
    signal(&pid, "-KILL");
    let killed_at = SystemTime::now();
    let checkpoint_age =
        killed_at.duration_since(std::fs::metadata(checkpoint(&failing, killed)).unwrap().modified().unwrap()).unwrap();
    assert_eq!(checkpoint_samples(&failing, killed), Some(kept));
    assert!(!part(&failing, killed).exists(), "a SIGKILLed task wrote its part");
    slurm(&conf, &failing, "scontrol", &["requeue", &task(killed)]);

    wait_for_merge(&conf, &failing, &merge_job);
    let failing_seconds = started.elapsed().as_secs_f64();

    // Each resumed from its checkpoint and rendered exactly the rest of its range.
    let runs = summaries(&failing, &job, preempted);
    assert_eq!(runs.len(), 2, "task 2 ran twice: {runs:?}");
    assert_eq!(runs[0]["outcome"], "interrupted");
    assert_eq!(runs[0]["samples"], written.samples());
    assert_eq!(runs[1]["samples_this_run"], SPP_PER_TASK - written.samples(), "task 2 resumed from its checkpoint");
    let runs = summaries(&failing, &job, killed);
    assert_eq!(runs.len(), 1, "task 5's killed run printed nothing: {runs:?}");
    assert_eq!(runs[0]["samples_this_run"], SPP_PER_TASK - kept, "task 5 resumed from its last checkpoint");
    for k in 0..TASKS {
        assert_eq!(PartialRender::read(&part(&failing, k)).unwrap().ranges, vec![range(k)], "part {k}");
    }
    assert!(
        std::fs::read(failing.join("final.exr")).unwrap() == job_file,
        "the merge with a task preempted and one killed differs from the merge without failures"
    );

    // What the failures cost, for docs/farm.md.
    let rate = |run: &serde_json::Value| run["samples_per_second"].as_f64().unwrap() / f64::from(SIZE * SIZE);
    eprintln!("array of {TASKS} x {SPP_PER_TASK} spp, {SIZE}x{SIZE}: {clean_seconds:.1} s without failures, {failing_seconds:.1} s with");
    eprintln!(
        "preempted task {preempted}: stopped {stop_seconds:.2} s after SIGTERM with {} spp kept, 0 lost",
        written.samples()
    );
    eprintln!(
        "killed task {killed}: restarted from {kept} spp; its last checkpoint was {:.2} s old, about {:.0} spp lost",
        checkpoint_age.as_secs_f64(),
        checkpoint_age.as_secs_f64() * rate(&runs[0])
    );
}
