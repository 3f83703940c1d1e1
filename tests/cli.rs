//! The `caustica` binary end to end on lavapipe: every scene renders to every format, the same seed
//! gives the same image, bad input fails with a message and a non-zero exit code.

mod common;

use caustica::image::read_image;
use caustica::render::Renderer;
use common::*;
use std::path::Path;
use std::process::Command;

#[test]
fn every_scene_renders_to_pfm_exr_and_png() {
    let dir = temp_dir("cli-scenes");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut rendered = 0;
    for entry in std::fs::read_dir(&scenes).unwrap() {
        let scene = entry.unwrap().path();
        // caustica's own scenes and the pbrt-v4 ones beside them (scenes/cornell.pbrt).
        if scene.extension().is_none_or(|e| e != "toml" && e != "pbrt") {
            continue;
        }
        let stem = scene.file_name().unwrap().to_string_lossy().replace('.', "_");
        if std::fs::read_to_string(&scene).unwrap().contains("$CAUSTICA_DATA") && !caustica::scene::data_dir().exists()
        {
            eprintln!(
                "SKIPPED: {stem} needs the shared data folder ({} is missing)",
                caustica::scene::data_dir().display()
            );
            continue;
        }
        for ext in ["pfm", "exr", "png"] {
            let out = dir.join(format!("{stem}.{ext}"));
            let o = caustica(&[
                "render",
                scene.to_str().unwrap(),
                "-o",
                out.to_str().unwrap(),
                "--width",
                "24",
                "--height",
                "16",
                "--spp",
                "2",
                "-q",
                "--validation",
            ]);
            assert!(o.status.success(), "{stem}.{ext}: {}", String::from_utf8_lossy(&o.stderr));
            assert!(out.metadata().map(|m| m.len() > 0).unwrap_or(false), "{} was not written", out.display());
        }
        let image = read_image(&dir.join(format!("{stem}.exr"))).unwrap();
        assert_eq!((image.width, image.height), (24, 16));
        assert!(
            image.pixels.iter().flatten().all(|c| c.is_finite() && *c >= 0.0),
            "{stem}: non-finite or negative radiance"
        );
        assert!(image.pixels.iter().flatten().any(|c| *c > 0.0), "{stem}: the image is black");
        rendered += 1;
    }
    assert!(rendered >= 3);
}

#[test]
fn default_scene_renders_with_no_scene_argument() {
    let dir = temp_dir("cli-default");
    let out = dir.join("default.pfm");
    let o = caustica(&["render", "-o", out.to_str().unwrap(), "--width", "16", "--height", "16", "--spp", "1", "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(read_image(&out).unwrap().width, 16);
}

#[test]
fn same_seed_gives_the_same_image_however_samples_are_split() {
    let (_lock, ctx) = gpu();
    let mut scene = caustica::scene::Scene::default_scene();
    scene.film.width = 16;
    scene.film.height = 16;
    scene.film.spp = 8;
    let a = render(&ctx, &scene, 7);
    let b = render(&ctx, &scene, 7);
    assert_eq!(a.pixels, b.pixels, "two renders with seed 7 differ");
    let mut split = Renderer::new(&ctx, &scene, 7).unwrap();
    split.render(3, |_| {}).unwrap();
    split.render(5, |_| {}).unwrap();
    assert_eq!(split.image().unwrap().pixels, a.pixels, "3 + 5 samples differ from 8 in one go");
    let c = render(&ctx, &scene, 8);
    assert_ne!(a.pixels, c.pixels, "seeds 7 and 8 gave the same image");
}

#[test]
fn bad_input_fails_with_a_message_and_nonzero_exit() {
    let dir = temp_dir("cli-bad");
    std::fs::write(
        dir.join("typo.toml"),
        "[camera]\nposition = [0.0, 0.0, 1.0]\nlook_at = [0.0, 0.0, 0.0]\nfovv = 30.0\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("probe.toml"),
        "[camera]\nposition = [0.0, 0.0, 1.0]\nlook_at = [0.0, 0.0, 0.0]\n[environment]\nprobe = \"broken.pfm\"\n",
    )
    .unwrap();
    std::fs::write(dir.join("broken.pfm"), "PF\n4 4\n-1.0\nshort").unwrap();
    let path = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let (out, missing, typo, probe, bmp) =
        (path("x.png"), path("missing.toml"), path("typo.toml"), path("probe.toml"), path("x.bmp"));
    let cases: [(&[&str], &str); 5] = [
        (&["render", &missing, "-o", &out], "missing.toml"),
        (&["render", &typo, "-o", &out], "fovv"),
        (&["render", &probe, "-o", &out], "broken.pfm"),
        (&["render", "-o", &bmp], "x.bmp"),
        (&["render", "--device", "no-such-gpu", "-o", &out], "no-such-gpu"),
    ];
    for (args, needle) in cases {
        let o = caustica(args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: exit status {:?}, stderr {stderr}", o.status);
        assert!(
            stderr.contains(needle) && stderr.contains("error"),
            "{args:?}: stderr does not name '{needle}': {stderr}"
        );
    }
}

#[test]
fn compare_prints_the_error_metrics_and_rejects_mismatched_sizes() {
    let dir = temp_dir("cli-compare");
    let render_to = |name: &str, seed: &str, width: &str| {
        let out = dir.join(name);
        let o = caustica(&[
            "render",
            "-o",
            out.to_str().unwrap(),
            "--width",
            width,
            "--height",
            "8",
            "--spp",
            "4",
            "--seed",
            seed,
            "-q",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        out
    };
    let (a, b, narrow) = (render_to("a.pfm", "1", "8"), render_to("b.exr", "2", "8"), render_to("c.pfm", "3", "6"));
    let o = caustica(&["compare", a.to_str().unwrap(), b.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    for key in ["relative MSE:", "mean absolute error:", "ratio of means:"] {
        assert!(text.contains(key), "missing {key}: {text}");
    }
    let o = caustica(&["compare", a.to_str().unwrap(), narrow.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("c.pfm"), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A device no machine has: a run that fails for another reason failed before it looked for a
/// device, so before any work.
const NO_DEVICE: [&str; 2] = ["--device", "no-such-gpu"];

/// Asserts exit status 1 and a `caustica: error:` or clap error naming each of `needles`; returns
/// stderr.
fn fails_naming(o: &std::process::Output, needles: &[&str]) -> String {
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "exit status {:?}, stderr {stderr}", o.status);
    assert!(stderr.contains("error"), "{stderr}");
    for needle in needles {
        assert!(stderr.contains(needle), "stderr does not say '{needle}': {stderr}");
    }
    stderr
}

#[test]
fn non_finite_exposure_is_refused_by_render_and_merge() {
    let dir = temp_dir("cli-exposure");
    let (png, part) = (dir.join("out.png"), dir.join("part.exr"));
    let (png, part) = (png.to_str().unwrap(), part.to_str().unwrap());
    for value in ["NaN", "inf", "-inf", "1e9"] {
        let render =
            caustica(&["render", "-o", png, "--width", "8", "--height", "8", "--spp", "1", "-q", "--exposure", value]);
        fails_naming(&render, &["--exposure", value]);
        let merge = caustica(&["merge", part, "-o", png, "-q", "--exposure", value]);
        fails_naming(&merge, &["--exposure", value]);
    }
    assert!(!Path::new(png).exists(), "a refused run wrote its image");
    let o = caustica(&["render", "-o", png, "--width", "8", "--height", "8", "--spp", "1", "-q", "--exposure", "-1.5"]);
    assert!(o.status.success(), "a negative exposure is fine: {}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn bad_output_checkpoint_and_sample_range_fail_before_the_device_is_touched() {
    let dir = temp_dir("cli-paths");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_owned();
    std::fs::create_dir_all(dir.join("folder.png")).unwrap();
    std::fs::write(dir.join("plain-file"), b"not a directory").unwrap();
    std::fs::write(dir.join("out.png"), b"an earlier image").unwrap();
    let (out, folder, in_missing, in_file) =
        (path("out.png"), path("folder.png"), path("missing/out.png"), path("plain-file/out.png"));
    let (ck_missing, ck_png, out_again) =
        (path("missing/ck.exr"), path("ck.png"), format!("{}/./out.png", dir.display()));
    let cases: [(&[&str], &[&str]); 8] = [
        (&["-o", &folder], &[&folder, "is a directory"]),
        (&["-o", &in_missing], &[&in_missing, "does not exist"]),
        (&["-o", &in_file], &[&in_file, "is not a directory"]),
        (&["-o", &out, "--checkpoint", &ck_missing], &[&ck_missing, "does not exist"]),
        (&["-o", &out, "--checkpoint", &out_again], &[&out_again, "are the same file"]),
        (&["-o", &out, "--checkpoint", &out], &["-o", "--checkpoint", "are the same file"]),
        (&["-o", &out, "--checkpoint", &ck_png], &["--checkpoint", &ck_png, "must end in .exr"]),
        (
            &["-o", &out, "--sample-offset", "4294967290", "--spp", "4294967295"],
            &["--sample-offset 4294967290", "at most 5 samples per pixel"],
        ),
    ];
    for (args, needles) in cases {
        let mut all = vec!["render", "--width", "8", "--height", "8", "-q"];
        all.extend_from_slice(args);
        if !args.contains(&"--spp") {
            all.extend(["--spp", "1"]);
        }
        all.extend_from_slice(&NO_DEVICE);
        let stderr = fails_naming(&caustica(&all), needles);
        assert!(!stderr.contains("no-such-gpu"), "{args:?}: checked only after the device: {stderr}");
    }
    assert_eq!(std::fs::read(dir.join("out.png")).unwrap(), b"an earlier image");
    // merge checks its output before reading any input.
    let missing_input = path("missing-part.exr");
    for (output, problem) in [(&folder, "is a directory"), (&in_missing, "does not exist")] {
        let stderr = fails_naming(&caustica(&["merge", &missing_input, "-o", output]), &[output, problem]);
        assert!(!stderr.contains("missing-part.exr"), "{stderr}");
    }
    let names: Vec<String> =
        std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert!(names.iter().all(|n| !n.contains(".tmp-")), "a probe left a file: {names:?}");
}

#[test]
fn compare_refuses_images_with_non_finite_pixels() {
    let dir = temp_dir("cli-compare-nan");
    let mut image = caustica::image::RgbImage::new(4, 2);
    image.set(1, 0, [f32::NAN, 0.0, 0.0]);
    image.set(3, 1, [0.0, f32::INFINITY, 0.0]);
    let (bad, good) = (dir.join("bad.pfm"), dir.join("good.pfm"));
    caustica::image::pfm::write(&bad, &image).unwrap();
    caustica::image::pfm::write(&good, &caustica::image::RgbImage::new(4, 2)).unwrap();
    let (bad, good) = (bad.to_str().unwrap(), good.to_str().unwrap());
    for (a, b) in [(bad, good), (good, bad)] {
        let o = caustica(&["compare", a, b]);
        fails_naming(&o, &[&format!("{bad} holds 2 non-finite pixels"), "(1, 0)"]);
        assert!(o.stdout.is_empty(), "no figures: {}", String::from_utf8_lossy(&o.stdout));
    }
}

#[test]
fn errors_say_each_cause_once() {
    let dir = temp_dir("cli-cause-once");
    let (missing, garbage) = (dir.join("missing.exr"), dir.join("garbage.exr"));
    std::fs::write(&garbage, b"not an exr").unwrap();
    let (missing, garbage) = (missing.to_str().unwrap(), garbage.to_str().unwrap());
    let cases: [(&[&str], &str); 3] = [
        (&["compare", missing, garbage], "No such file or directory"),
        (&["compare", garbage, garbage], "file identifier missing"),
        (&["merge", missing, "-o", garbage], "No such file or directory"),
    ];
    for (args, cause) in cases {
        let stderr = fails_naming(&caustica(args), &[cause]);
        assert_eq!(stderr.matches(cause).count(), 1, "{args:?}: {stderr}");
    }
}

#[test]
fn temp_files_of_killed_writes_are_cleared_and_no_others() {
    let dir = temp_dir("cli-leftovers");
    let dead = {
        let mut child = Command::new("true").spawn().unwrap();
        let pid = child.id();
        child.wait().unwrap();
        pid
    };
    let old = std::time::SystemTime::now() - std::time::Duration::from_secs(600);
    let leftover = |name: String, modified| {
        let path = dir.join(name);
        std::fs::File::create(&path).unwrap().set_modified(modified).unwrap();
        path
    };
    let stale_image = leftover(format!(".out.png.tmp-{dead}-0"), old);
    let stale_checkpoint = leftover(format!(".out.checkpoint.exr.tmp-{dead}-3"), old);
    let recent = leftover(format!(".out.png.tmp-{dead}-1"), std::time::SystemTime::now());
    let live_writer = leftover(format!(".out.png.tmp-{}-0", std::process::id()), old);
    let other_target = leftover(format!(".other.png.tmp-{dead}-0"), old);
    let out = dir.join("out.png");
    let o = caustica(&["render", "-o", out.to_str().unwrap(), "--width", "8", "--height", "8", "--spp", "1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stderr = String::from_utf8_lossy(&o.stderr);
    for removed in [&stale_image, &stale_checkpoint] {
        assert!(!removed.exists(), "{} is still there", removed.display());
        assert!(stderr.contains(&format!("removed {}", removed.display())), "{stderr}");
    }
    for kept in [&recent, &live_writer, &other_target] {
        assert!(kept.exists(), "{} was removed", kept.display());
    }
}

/// A shared data folder that is not there, so the suite must skip the scenes that need it.
const NO_DATA: &str = "/nonexistent/caustica-shared-data";

/// `bench --suite` at 8x8, 1 spp without the shared data: returns stdout and stderr.
fn tiny_suite(extra: &[&str]) -> (String, String) {
    let mut args = vec!["bench", "--suite", "--width", "8", "--height", "8", "--spp", "1"];
    args.extend_from_slice(extra);
    let o =
        caustica_command(&args).env("CAUSTICA_DATA", NO_DATA).current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap();
    let (stdout, stderr) =
        (String::from_utf8_lossy(&o.stdout).into_owned(), String::from_utf8_lossy(&o.stderr).into_owned());
    assert!(o.status.success(), "{stderr}");
    (stdout, stderr)
}

/// The checked-in scenes that need no shared data, and one that does.
const LOCAL_SCENES: [&str; 5] =
    ["cornell.toml (built-in)", "cornell_original.toml", "materials.toml", "probe.toml", "sky.toml"];
const SHARED_SCENE: &str = "bunny_cornell.toml";

#[test]
fn bench_suite_prints_one_table_and_says_loudly_what_it_skipped() {
    let (stdout, stderr) = tiny_suite(&[]);
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(lines[0].starts_with("device: "), "{stdout}");
    let header: Vec<&str> = lines[1].split_whitespace().collect();
    assert_eq!(header, ["scene", "size", "spp", "Msamples/s", "Mrays/s", "rays/sample", "seconds"], "{stdout}");
    for scene in LOCAL_SCENES {
        let row = lines.iter().find(|l| l.starts_with(scene)).unwrap_or_else(|| panic!("no row for {scene}: {stdout}"));
        let cells: Vec<&str> = row[scene.len()..].split_whitespace().collect();
        assert_eq!(cells[..2], ["8x8", "1"], "{row}");
        assert_eq!(cells.len(), 6, "{row}");
        assert!(cells[2..].iter().all(|c| c.parse::<f64>().is_ok_and(|v| v >= 0.0)), "{row}");
    }
    assert!(!stdout.contains(SHARED_SCENE), "{stdout}");
    assert_eq!(
        lines.iter().filter(|l| l.starts_with("cornell.toml")).count(),
        1,
        "the built-in box runs once (it is scenes/cornell.toml): {stdout}"
    );
    let skip = stderr
        .lines()
        .find(|l| l.contains(&format!("SKIPPED {SHARED_SCENE}")))
        .unwrap_or_else(|| panic!("no skip line for {SHARED_SCENE}: {stderr}"));
    assert!(skip.contains("shared data") && skip.contains(NO_DATA), "the reason names the folder: {skip}");
    assert!(
        stderr.lines().any(|l| l.starts_with("caustica: SKIPPED") && l.contains("of the suite's scenes")),
        "a summary of the skips at the end: {stderr}"
    );
}

#[test]
fn bench_suite_json_is_one_document_with_the_device_and_a_row_per_scene() {
    let (stdout, stderr) = tiny_suite(&["--json"]);
    let doc: serde_json::Value = serde_json::from_str(&stdout).expect("one JSON document");
    for key in ["device", "device_type", "api_version", "driver_name", "driver_info", "driver_version"] {
        assert!(doc[key].is_string(), "{key} in {doc}");
    }
    let rows = doc["rows"].as_array().unwrap();
    let scenes: Vec<&str> = rows.iter().map(|r| r["scene"].as_str().unwrap()).collect();
    for scene in LOCAL_SCENES {
        assert!(scenes.contains(&scene), "no row for {scene}: {scenes:?}");
    }
    for row in rows {
        assert_eq!(
            (row["width"].as_u64(), row["height"].as_u64(), row["samples"].as_u64()),
            (Some(8), Some(8), Some(1)),
            "{row}"
        );
        for key in ["samples_per_second", "rays_per_second", "rays_per_sample", "seconds"] {
            assert!(row[key].as_f64().is_some_and(|v| v > 0.0), "{key} in {row}");
        }
    }
    let skipped = doc["skipped"].as_array().unwrap();
    let bunny = skipped
        .iter()
        .find(|s| s["scene"] == SHARED_SCENE)
        .unwrap_or_else(|| panic!("{SHARED_SCENE} not among the skipped: {doc}"));
    assert!(bunny["reason"].as_str().unwrap().contains(NO_DATA), "{bunny}");
    assert_eq!(doc["failed"].as_array().map(Vec::len), Some(0), "{doc}");
    assert!(stderr.contains(&format!("SKIPPED {SHARED_SCENE}")), "said on stderr too: {stderr}");
}

#[test]
fn bench_of_one_scene_keeps_its_json_keys() {
    let o = caustica(&["bench", "--width", "8", "--height", "8", "--spp", "1", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let keys = [
        "scene",
        "device",
        "device_type",
        "width",
        "height",
        "samples",
        "aovs",
        "setup_seconds",
        "seconds",
        "samples_per_second",
        "rays_per_second",
        "rays_per_sample",
        "nonfinite_samples",
        "loop_limit",
        "repeated_dispatches",
        "primitives",
        "gpu_bytes",
        "walk_queue",
        "traversal",
    ];
    for key in keys {
        assert!(summary.get(key).is_some(), "{key} missing: {summary}");
    }
    assert_eq!((summary["width"].as_u64(), summary["samples"].as_u64()), (Some(8), Some(1)));
}

#[test]
fn bench_suite_refuses_a_scene_argument_and_bad_sizes_before_any_work() {
    fails_naming(&caustica(&["bench", "--suite", "scenes/sky.toml"]), &["--suite"]);
    fails_naming(&caustica(&["bench", "--scenes", "scenes"]), &["--suite"]);
    let stderr = fails_naming(&caustica(&["bench", "--suite", "--spp", "0", "--device", "no-such-gpu"]), &["spp"]);
    assert!(!stderr.contains("no-such-gpu"), "checked only after the device: {stderr}");
}

/// `--kernel-option`: one place for the kernel's A/B switches. A bad key or value fails before any
/// work (exit 1, naming it); `help` lists every key; an option reaches the kernel (bench's JSON
/// reports it) and overrides the environment variable; and the image does not depend on it.
#[test]
fn kernel_options_are_checked_listed_applied_and_leave_the_image_alone() {
    for (bad, says) in [
        ("walk-queue=2", "walk-queue=2"),
        ("no-such=1", "no kernel option 'no-such'"),
        ("take-tiles", "expected KEY=VALUE"),
    ] {
        fails_naming(&caustica(&["render", "--kernel-option", bad, "-o", "x.png", "-q"]), &[says]);
        fails_naming(&caustica(&["bench", "--kernel-option", bad]), &[says]);
    }
    let help = caustica(&["bench", "--kernel-option", "help"]);
    assert!(help.status.success());
    let text = String::from_utf8_lossy(&help.stdout);
    for key in [
        "wavefront",
        "walk-queue",
        "walk-records",
        "take-tiles",
        "workgroup",
        "bvh-width",
        "shadow-walk",
        "experimental",
        "GPU",
    ] {
        assert!(text.contains(key), "help does not list {key}: {text}");
    }
    let records = |extra: &[&str], env: Option<&str>| {
        let mut args = vec!["bench", "--width", "8", "--height", "8", "--spp", "1", "--json"];
        args.extend_from_slice(extra);
        let mut command = caustica_command(&args);
        if let Some(value) = env {
            command.env("CAUSTICA_WALK_RECORDS", value);
        }
        let o = command.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        summary["walk_records"].as_str().unwrap().to_owned()
    };
    assert_eq!(records(&["--kernel-option", "walk-records=storage"], None), "storage");
    assert_eq!(records(&["--kernel-option", "walk-records=texels"], Some("storage")), "texels", "the flag wins");
    assert_eq!(records(&[], Some("storage")), "storage");
    // The walk's candidates for GPUs (scripts/gpu-measure.sh, STEPS=traversal) reach the kernel too.
    let chosen = |option: &str, key: &str| {
        let args = ["bench", "--width", "8", "--height", "8", "--spp", "1", "--json", "--kernel-option", option];
        let o = caustica(&args);
        assert!(o.status.success(), "{option}: {}", String::from_utf8_lossy(&o.stderr));
        let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        summary[key].as_str().unwrap().to_owned()
    };
    assert_eq!(chosen("bvh-width=8", "bvh_width"), "8");
    assert_eq!(chosen("shadow-walk=unsorted", "shadow_walk"), "unsorted");
    let dir = temp_dir("cli-kernel-options");
    let render = |name: &str, option: &str| {
        let out = dir.join(name);
        let args = ["render", "-o", out.to_str().unwrap(), "--width", "16", "--height", "12", "--spp", "2", "-q"];
        let o = caustica(&[&args[..], &["--kernel-option", option]].concat());
        assert!(o.status.success(), "{option}: {}", String::from_utf8_lossy(&o.stderr));
        std::fs::read(out).unwrap()
    };
    assert_eq!(
        render("a.pfm", "walk-records=texels"),
        render("b.pfm", "walk-records=storage"),
        "walk-records changed the image"
    );
}
