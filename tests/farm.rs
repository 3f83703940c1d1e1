//! Farm rendering end to end on lavapipe: resuming a checkpoint and merging partial renders give the
//! uninterrupted render, mismatched inputs are refused, time budgets and signals stop a render
//! cleanly, and the JSON summary parses.

mod common;

use caustica::farm::PartialRender;
use caustica::render::Renderer;
use caustica::scene::Scene;
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Runs a 16x16 render of the built-in scene with `args` added; panics unless it succeeds.
fn render(out: &Path, args: &[&str]) -> Output {
    let mut all = vec!["render", "-o", out.to_str().unwrap(), "--width", "16", "--height", "16", "-q", "--validation"];
    all.extend_from_slice(args);
    let o = caustica(&all);
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
    o
}

fn merge(inputs: &[&PathBuf], out: &Path) -> Output {
    let mut args = vec!["merge".to_owned(), "-q".to_owned(), "-o".to_owned(), out.to_str().unwrap().to_owned()];
    args.extend(inputs.iter().map(|p| p.to_str().unwrap().to_owned()));
    caustica(&args.iter().map(String::as_str).collect::<Vec<_>>())
}

/// As common's, and said as caustica's own error (not a usage error).
fn fails_with(o: &Output, needle: &str) {
    common::fails_with(o, needle);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("caustica: error:"), "not said as caustica's error: {stderr}");
}

#[test]
fn resume_from_a_checkpoint_is_bit_exact() {
    let dir = temp_dir("farm-resume");
    let (full, part, resumed, checkpoint) =
        (dir.join("full.exr"), dir.join("part.png"), dir.join("resumed.exr"), dir.join("ck.exr"));
    render(&full, &["--spp", "7", "--seed", "5"]);
    render(&part, &["--spp", "3", "--seed", "5", "--checkpoint", checkpoint.to_str().unwrap()]);
    assert_eq!(PartialRender::read(&checkpoint).unwrap().samples(), 3);
    render(&resumed, &["--spp", "7", "--seed", "5", "--resume", "--checkpoint", checkpoint.to_str().unwrap()]);
    let (a, b) = (PartialRender::read(&full).unwrap(), PartialRender::read(&resumed).unwrap());
    assert_eq!(b.ranges, vec![0..7]);
    assert!(a.accumulation == b.accumulation, "3 spp resumed to 7 differs from 7 in one go");
    assert_eq!(PartialRender::read(&checkpoint).unwrap(), b, "the checkpoint is brought up to date at the end");
}

#[test]
fn resume_refuses_another_seed_size_or_scene() {
    let dir = temp_dir("farm-resume-refuse");
    let (out, checkpoint) = (dir.join("out.png"), dir.join("ck.exr"));
    let ck = checkpoint.to_str().unwrap();
    render(&out, &["--spp", "2", "--checkpoint", ck]);
    let sky = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sky.toml");
    let o = out.to_str().unwrap();
    let cases: [(Vec<&str>, &str); 3] = [
        (vec!["render", "-o", o, "--width", "16", "--height", "16", "--seed", "2"], "different seed (1, not 2)"),
        (vec!["render", "-o", o, "--width", "16", "--height", "8"], "different size (16x16, not 16x8)"),
        (vec!["render", sky.to_str().unwrap(), "-o", o, "--width", "16", "--height", "16"], "different scene"),
    ];
    for (mut args, needle) in cases {
        args.extend(["--spp", "4", "--resume", "--checkpoint", ck]);
        let result = caustica(&args);
        fails_with(&result, needle);
        assert!(String::from_utf8_lossy(&result.stderr).contains("ck.exr: cannot resume"));
    }
}

#[test]
fn merged_partials_equal_one_render_of_all_samples() {
    let dir = temp_dir("farm-merge");
    // Partials of one sample each add up in the kernel's own order: bit for bit.
    let ones: Vec<PathBuf> = (0..3).map(|k| dir.join(format!("one{k}.exr"))).collect();
    for (k, path) in ones.iter().enumerate() {
        render(path, &["--spp", "1", "--sample-offset", &k.to_string()]);
    }
    let (whole3, merged3) = (dir.join("whole3.exr"), dir.join("merged3.exr"));
    render(&whole3, &["--spp", "3"]);
    let o = merge(&[&ones[2], &ones[0], &ones[1]], &merged3);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (whole, merged) = (PartialRender::read(&whole3).unwrap(), PartialRender::read(&merged3).unwrap());
    assert!(whole == merged, "3 x 1 spp merged differs from 3 spp");

    // Larger partials: the sums are grouped differently, so equal to float rounding.
    let twos: Vec<PathBuf> = (0..3).map(|k| dir.join(format!("two{k}.exr"))).collect();
    for (k, path) in twos.iter().enumerate() {
        render(path, &["--spp", "2", "--sample-offset", &(2 * k).to_string()]);
    }
    let (whole6, merged6, merged_png) = (dir.join("whole6.exr"), dir.join("merged6.exr"), dir.join("merged6.png"));
    render(&whole6, &["--spp", "6"]);
    assert!(merge(&[&twos[0], &twos[1], &twos[2]], &merged6).status.success());
    assert!(merge(&[&twos[0], &twos[1], &twos[2]], &merged_png).status.success());
    let (whole, merged) = (PartialRender::read(&whole6).unwrap(), PartialRender::read(&merged6).unwrap());
    assert_eq!(merged.ranges, vec![0..6]);
    assert_eq!((&merged.scene_hash, merged.seed), (&whole.scene_hash, whole.seed));
    for (a, b) in whole.accumulation.iter().zip(&merged.accumulation) {
        assert_eq!(a[3], b[3], "sample counts");
        for c in 0..3 {
            assert!((a[c] - b[c]).abs() <= 1e-5 * a[c].abs().max(b[c].abs()), "{a:?} vs {b:?}");
        }
    }
}

#[test]
fn merge_refuses_other_scenes_sizes_seeds_and_overlaps() {
    let dir = temp_dir("farm-merge-refuse");
    let path = |name: &str| dir.join(name);
    render(&path("a.exr"), &["--spp", "2"]);
    render(&path("overlap.exr"), &["--spp", "2", "--sample-offset", "1"]);
    render(&path("seed.exr"), &["--spp", "2", "--sample-offset", "2", "--seed", "9"]);
    let small = caustica(&[
        "render",
        "-o",
        path("small.exr").to_str().unwrap(),
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "2",
        "--sample-offset",
        "2",
        "-q",
    ]);
    assert!(small.status.success());
    let sky = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/sky.toml");
    let other = caustica(&[
        "render",
        sky.to_str().unwrap(),
        "-o",
        path("sky.exr").to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "2",
        "--sample-offset",
        "2",
        "-q",
    ]);
    assert!(other.status.success());
    std::fs::write(path("plain.pfm"), b"PF\n1 1\n-1.0\n\0\0\0\0\0\0\0\0\0\0\0\0").unwrap();
    let a = path("a.exr");
    fails_with(
        &merge(&[&a, &path("overlap.exr")], &path("m.exr")),
        "overlap.exr: samples 1..3 overlap samples 0..2 of",
    );
    fails_with(&merge(&[&a, &path("seed.exr")], &path("m.exr")), "seed.exr: cannot merge with");
    fails_with(&merge(&[&a, &path("small.exr")], &path("m.exr")), "different size (8x8, not 16x16)");
    fails_with(&merge(&[&a, &path("sky.exr")], &path("m.exr")), "different scene");
    fails_with(&merge(&[&a, &path("plain.pfm")], &path("m.exr")), "plain.pfm is not a caustica EXR checkpoint/partial");
    assert!(!path("m.exr").exists(), "a refused merge wrote its output");
}

#[test]
fn time_budget_stops_the_render_and_json_summary_parses() {
    let dir = temp_dir("farm-time");
    let out = dir.join("timed.png");
    let started = Instant::now();
    let o = render(&out, &["--time", "1s", "--json"]);
    // Generous: a 16x16 pass takes milliseconds; this only checks that the budget ends the render.
    assert!(started.elapsed() < Duration::from_secs(60), "--time 1s ran for {:?}", started.elapsed());
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).expect("--json prints JSON");
    assert_eq!(summary["outcome"], "time_up");
    assert!(summary["samples"].as_u64().unwrap() >= 1);
    assert_eq!((summary["width"].as_u64(), summary["height"].as_u64()), (Some(16), Some(16)));
    for key in ["scene", "device", "output", "scene_hash"] {
        assert!(summary[key].is_string(), "{key} in {summary}");
    }
    for key in ["seconds", "samples_per_second", "rays_per_second"] {
        assert!(summary[key].as_f64().is_some_and(|v| v > 0.0), "{key} in {summary}");
    }
    assert!(out.exists());

    // With --spp too, whichever comes first: here the sample count.
    let o = render(&out, &["--time", "10m", "--spp", "2", "--json"]);
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!((summary["outcome"].as_str(), summary["samples"].as_u64()), (Some("done"), Some(2)));
}

#[test]
fn bench_json_parses() {
    let o = caustica(&["bench", "--width", "16", "--height", "16", "--spp", "2", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).expect("bench --json prints JSON");
    assert!(summary["rays_per_second"].as_f64().is_some_and(|v| v > 0.0), "{summary}");
}

/// A 16x16 render to `out` of more samples than it will ever reach, checkpointing to `checkpoint`
/// after every pass, returned once the first checkpoint exists: rendering is then under way.
fn render_under_way(out: &Path, checkpoint: &Path) -> std::process::Child {
    let mut child = caustica_command(&[
        "render",
        "-o",
        out.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "10000000",
        "-q",
        "--checkpoint-every",
        "0s",
        "--checkpoint",
        checkpoint.to_str().unwrap(),
    ])
    .stdout(Stdio::null())
    .stderr(Stdio::piped())
    .spawn()
    .unwrap();
    let deadline = Instant::now() + Duration::from_secs(120);
    while !checkpoint.exists() {
        assert!(Instant::now() < deadline && child.try_wait().unwrap().is_none(), "no checkpoint appeared");
        std::thread::sleep(Duration::from_millis(20));
    }
    child
}

#[test]
fn sigint_and_sigterm_finish_the_pass_and_write_the_image() {
    let dir = temp_dir("farm-signal");
    for signal in ["INT", "TERM"] {
        let (out, checkpoint) = (dir.join(format!("{signal}.exr")), dir.join(format!("{signal}.checkpoint.exr")));
        let child = render_under_way(&out, &checkpoint);
        let kill = Command::new("kill").args([format!("-{signal}"), child.id().to_string()]).status().unwrap();
        assert!(kill.success());
        let o = child.wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(0), "SIG{signal}: {}", String::from_utf8_lossy(&o.stderr));
        let written = PartialRender::read(&out).unwrap();
        assert!(written.samples() >= 1 && written.samples() < 10_000_000, "SIG{signal}: {} spp", written.samples());
        assert_eq!(PartialRender::read(&checkpoint).unwrap(), written, "the checkpoint holds the final samples");
    }
}

/// GNU `timeout`, Slurm and Kubernetes may signal more than once: repeated SIGTERMs, some arriving
/// during the final write, are the first one (the image is written, exit 0).
#[cfg(unix)]
#[test]
fn repeated_sigterms_still_write_the_image() {
    let dir = temp_dir("farm-repeated-sigterm");
    let (out, checkpoint) = (dir.join("out.exr"), dir.join("out.checkpoint.exr"));
    let mut child = render_under_way(&out, &checkpoint);
    let deadline = Instant::now() + Duration::from_secs(60);
    // SIGTERM every 10 ms until the render exits.
    // SAFETY: kill(2) of a child not yet waited for, whose pid therefore cannot be reused.
    while child.try_wait().unwrap().is_none() && unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) } == 0 {
        assert!(Instant::now() < deadline, "the render did not stop");
        std::thread::sleep(Duration::from_millis(10));
    }
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", String::from_utf8_lossy(&o.stderr));
    let written = PartialRender::read(&out).unwrap();
    assert_eq!(PartialRender::read(&checkpoint).unwrap(), written, "the checkpoint holds the final samples");
}

/// A second SIGINT, sent once the first is taken (two sent at once may arrive as one), quits at
/// once: exit 130, no image. The second signal races the pass in flight (a CPU device's passes
/// last about a second): where the render finished first (exit 0, its image written), which a
/// loaded machine can make happen, the run says nothing of the second signal and is repeated.
#[cfg(unix)]
#[test]
fn a_second_sigint_quits_at_once() {
    use std::io::BufRead as _;
    for attempt in 1..=5 {
        let dir = temp_dir("farm-second-sigint");
        let (out, checkpoint) = (dir.join("out.exr"), dir.join("out.checkpoint.exr"));
        let mut child = render_under_way(&out, &checkpoint);
        let pid = child.id() as libc::pid_t;
        // SAFETY: kill(2) of a child not yet waited for, whose pid therefore cannot be reused.
        assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
        let mut stderr = std::io::BufReader::new(child.stderr.take().unwrap());
        let mut line = String::new();
        while !line.contains("finishing the pass in flight") {
            line.clear();
            assert!(stderr.read_line(&mut line).unwrap() > 0, "no word of the first SIGINT");
        }
        // SAFETY: as above.
        assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
        let code = child.wait().unwrap().code();
        if code == Some(0) && out.exists() {
            eprintln!("attempt {attempt}: the pass in flight ended before the second SIGINT came; again");
            continue;
        }
        assert_eq!(code, Some(130));
        assert!(!out.exists(), "quitting at once writes no image");
        return;
    }
    panic!("in 5 attempts the render always finished before the second SIGINT arrived");
}

#[test]
fn scene_hash_is_stable_and_covers_the_scene_and_size_not_the_seed() {
    let (_lock, ctx) = gpu();
    let mut scene = Scene::default_scene();
    scene.film.width = 16;
    scene.film.height = 16;
    let hash = |scene: &Scene, seed| Renderer::new(&ctx, scene, seed).unwrap().scene_hash.clone();
    let base = hash(&scene, 1);
    assert_eq!(base, hash(&scene, 1));
    assert_eq!(base, hash(&scene, 2), "the seed is recorded apart from the scene");
    scene.film.spp = 99;
    assert_eq!(base, hash(&scene, 1), "the sample count does not change the image");
    scene.film.width = 17;
    assert_ne!(base, hash(&scene, 1));
    scene.film.width = 16;
    for material in &mut scene.materials {
        material.albedo *= 0.5;
    }
    assert_ne!(base, hash(&scene, 1), "materials are part of the scene");
}

#[test]
fn renderer_restore_continues_the_sample_stream() {
    let (_lock, ctx) = gpu();
    let mut scene = Scene::default_scene();
    scene.film.width = 16;
    scene.film.height = 16;
    let mut whole = Renderer::new(&ctx, &scene, 3).unwrap();
    whole.set_sample_offset(10);
    whole.render(5, |_| {}).unwrap();
    let mut first = Renderer::new(&ctx, &scene, 3).unwrap();
    first.set_sample_offset(10);
    first.render(2, |_| {}).unwrap();
    let mut rest = Renderer::new(&ctx, &scene, 3).unwrap();
    rest.set_sample_offset(10);
    rest.restore(&first.accumulation().unwrap(), 2).unwrap();
    rest.render(3, |_| {}).unwrap();
    assert!(rest.accumulation().unwrap() == whole.accumulation().unwrap());
    let mut stops = 0;
    let mut stopped = Renderer::new(&ctx, &scene, 3).unwrap();
    stopped
        .render_while(50, |_| {
            stops += 1;
            false
        })
        .unwrap();
    assert_eq!((stops, stopped.samples_done), (1, 1), "the first pass is one sample, then it stops");
}

/// An 8x8 partial render of the samples `range` whose pixels hold `count` samples, written to `path`
/// without rendering: what the file's checks see, consistent or not.
fn write_partial(path: &Path, range: std::ops::Range<u32>, count: f32) {
    let partial = PartialRender {
        scene_hash: "0".repeat(64),
        seed: 1,
        width: 8,
        height: 8,
        ranges: vec![range],
        accumulation: vec![[0.5, 0.5, 0.5, count]; 64],
        aovs: Default::default(),
        aov_sums: None,
    };
    partial.write(path).unwrap();
}

#[test]
fn partials_whose_ranges_disagree_with_their_counts_are_refused() {
    let dir = temp_dir("farm-inconsistent");
    let (good, bad, out) = (dir.join("good.exr"), dir.join("bad.exr"), dir.join("out.png"));
    write_partial(&good, 0..4, 4.0);
    write_partial(&bad, 4..8, 3.0);
    let needles = [
        &format!("{} is not a caustica EXR checkpoint/partial", bad.display()),
        "pixel (0, 0) holds 3 samples (and 63 more pixels disagree), but its sample ranges 4..8 hold 4",
    ];
    let merged = merge(&[&good, &bad], &out);
    for needle in needles {
        fails_with(&merged, needle);
    }
    let resumed = caustica(&[
        "render",
        "-o",
        out.to_str().unwrap(),
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "9",
        "--resume",
        "--checkpoint",
        bad.to_str().unwrap(),
        "--device",
        "no-such-gpu",
    ]);
    for needle in needles {
        fails_with(&resumed, needle);
    }
    assert!(!out.exists());
}

#[test]
fn resuming_past_the_last_sample_index_is_refused_before_rendering() {
    let dir = temp_dir("farm-resume-range");
    let (checkpoint, out) = (dir.join("ck.exr"), dir.join("out.png"));
    write_partial(&checkpoint, 4294967290..4294967292, 2.0);
    let o = caustica(&[
        "render",
        "-o",
        out.to_str().unwrap(),
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "10",
        "--resume",
        "--checkpoint",
        checkpoint.to_str().unwrap(),
        "--device",
        "no-such-gpu",
    ]);
    fails_with(&o, "ck.exr: cannot resume to --spp 10: samples 4294967290..4294967300 run past the last sample index (4294967294): from sample 4294967290, at most 5 samples per pixel");
}

#[test]
fn a_resume_that_adds_no_samples_says_so() {
    let dir = temp_dir("farm-no-samples");
    let (out, checkpoint) = (dir.join("out.png"), dir.join("ck.exr"));
    let ck = checkpoint.to_str().unwrap();
    render(&out, &["--spp", "2", "--checkpoint", ck]);
    let o = caustica(&[
        "render",
        "-o",
        out.to_str().unwrap(),
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "2",
        "--resume",
        "--checkpoint",
        ck,
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("no samples added (") && stderr.contains("already held 2 spp") && !stderr.contains("NaN"),
        "{stderr}"
    );
    let o = render(&out, &["--spp", "2", "--resume", "--checkpoint", ck, "--json"]);
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).expect("--json prints JSON");
    assert_eq!(summary["samples_this_run"], 0);
    assert!(summary["samples_per_second"].is_null() && summary["rays_per_second"].is_null(), "{summary}");
}

#[test]
fn a_failed_image_write_keeps_the_samples_in_the_checkpoint() {
    let dir = temp_dir("farm-write-fails");
    let (images, checkpoint) = (dir.join("images"), dir.join("ck.exr"));
    std::fs::create_dir_all(&images).unwrap();
    let out = images.join("out.png");
    let child = render_under_way(&out, &checkpoint);
    // The output's directory goes away mid-render, after the up-front checks passed.
    std::fs::remove_dir_all(&images).unwrap();
    assert!(Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap().success());
    let o = child.wait_with_output().unwrap();
    let kept = PartialRender::read(&checkpoint).unwrap();
    fails_with(&o, &format!("images/out.png: No such file or directory (os error 2); the {} samples per pixel are saved in {}: rerun with --resume", kept.samples(), checkpoint.display()));
}

/// A farm task picks its GPU by UUID (docs/farm.md): `devices --json` lists each device's, and
/// `--device` takes it; a UUID no device has is refused naming the devices.
#[test]
fn devices_json_lists_uuids_that_device_selects() {
    let o = caustica(&["devices", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let devices: Vec<serde_json::Value> = serde_json::from_slice(&o.stdout).expect("one JSON array");
    assert!(!devices.is_empty(), "no devices listed");
    for (i, d) in devices.iter().enumerate() {
        assert_eq!(d["index"], i);
        let uuid = d["uuid"].as_str().expect("a UUID (every device here is Vulkan 1.1 or newer)");
        let groups: Vec<usize> = uuid.split('-').map(str::len).collect();
        assert_eq!(groups, [8, 4, 4, 4, 12], "{uuid}");
        assert!(uuid.chars().all(|c| c == '-' || c.is_ascii_hexdigit() && !c.is_ascii_uppercase()), "{uuid}");
    }
    let dir = temp_dir("farm-device-uuid");
    let out = dir.join("by-uuid.png");
    let uuid = devices[0]["uuid"].as_str().unwrap();
    render(&out, &["--spp", "1", "--device", uuid]);
    let o = caustica(&[
        "render",
        "-o",
        out.to_str().unwrap(),
        "--spp",
        "1",
        "--device",
        "00000000-0000-0000-0000-000000000000",
    ]);
    fails_with(&o, "no Vulkan device matches --device '00000000-0000-0000-0000-000000000000'");
}

/// `merge --watch` folds in parts and checkpoints as they appear (a checkpoint and its part hold
/// the same samples: counted once), ends when the planned samples are in with the merge's own
/// file, and on SIGINT writes what is in and exits 0.
#[test]
fn merge_watch_previews_the_parts_as_they_come_and_stops_when_all_are_in() {
    let dir = temp_dir("farm-watch");
    let parts = dir.join("parts");
    std::fs::create_dir(&parts).unwrap();
    let preview = dir.join("preview.exr");
    let watch = |spp: &str, out: &Path| {
        caustica_command(&["merge", "--watch", parts.to_str().unwrap(), "--spp", spp, "-o", out.to_str().unwrap()])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let mut watcher = watch("6", &preview);
    let mut files = vec![];
    for k in 0..3 {
        let (part, checkpoint) = (parts.join(format!("part-{k}.exr")), parts.join(format!("part-{k}.checkpoint.exr")));
        let offset = (2 * k).to_string();
        render(&part, &["--spp", "2", "--sample-offset", &offset, "--checkpoint", checkpoint.to_str().unwrap()]);
        files.push(part);
    }
    let waited = Instant::now();
    while watcher.try_wait().unwrap().is_none() {
        if waited.elapsed() > Duration::from_secs(30) {
            watcher.kill().unwrap();
            panic!("the watcher did not end when all samples were in");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let out = watcher.wait_with_output().unwrap();
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{said}");
    assert!(said.contains("6 of 6 planned spp in (100 %)") && said.contains("all 6 planned spp are in"), "{said}");
    let merged = dir.join("merged.exr");
    let o = merge(&files.iter().collect::<Vec<_>>(), &merged);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(std::fs::read(&preview).unwrap() == std::fs::read(&merged).unwrap(), "preview differs from the merge");

    // Planned 100: SIGINT once the preview holds what is there, and it stays written.
    let partial_preview = dir.join("partial-preview.exr");
    let mut watcher = watch("100", &partial_preview);
    let started = Instant::now();
    while !partial_preview.exists() {
        assert!(started.elapsed() < Duration::from_secs(30), "no preview written");
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(Command::new("kill").args(["-INT", &watcher.id().to_string()]).status().unwrap().success());
    let stopped = Instant::now();
    while watcher.try_wait().unwrap().is_none() {
        if stopped.elapsed() > Duration::from_secs(30) {
            watcher.kill().unwrap();
            panic!("the watcher did not end on SIGINT");
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    let status = watcher.wait().unwrap();
    assert!(status.success(), "{status}");
    assert_eq!(PartialRender::read(&partial_preview).unwrap().samples(), 6);
}

/// Merges of the same parts, given in any order and run in separate processes, are the same file
/// byte for byte: a farm's results can be compared with `cmp` or a checksum (the EXR header's
/// attributes are written sorted, not in a per-process hash order).
#[test]
fn merges_of_the_same_parts_in_any_order_are_the_same_file() {
    let dir = temp_dir("farm-merge-order");
    let parts: Vec<PathBuf> = (0..3).map(|k| dir.join(format!("part-{k}.exr"))).collect();
    for (k, part) in parts.iter().enumerate() {
        render(part, &["--spp", "1", "--sample-offset", &k.to_string()]);
    }
    let orders = [[0, 1, 2], [2, 0, 1], [1, 2, 0]];
    let mut files = vec![];
    for (i, order) in orders.iter().enumerate() {
        let out = dir.join(format!("merged-{i}.exr"));
        let inputs: Vec<&PathBuf> = order.iter().map(|&k| &parts[k]).collect();
        let o = merge(&inputs, &out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        files.push(std::fs::read(&out).unwrap());
    }
    assert!(files[1] == files[0] && files[2] == files[0], "merges in other orders are different files");
}
