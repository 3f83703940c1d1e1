//! The `caustica` binary end to end on lavapipe: every scene renders to every format, the same seed
//! gives the same image, bad input fails with a message and a non-zero exit code.

mod common;

use caustica::image::read_image;
use caustica::render::Renderer;
use common::*;
use std::path::Path;
use std::process::Command;

fn caustica(args: &[&str]) -> std::process::Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_caustica"));
    if let Some(icd) = lavapipe_override() {
        cmd.env("VK_DRIVER_FILES", icd);
    }
    cmd.args(args).output().expect("run caustica")
}

#[test]
fn every_scene_renders_to_pfm_exr_and_png() {
    let dir = temp_dir("cli-scenes");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut rendered = 0;
    for entry in std::fs::read_dir(&scenes).unwrap() {
        let scene = entry.unwrap().path();
        if scene.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let stem = scene.file_stem().unwrap().to_string_lossy().to_string();
        if std::fs::read_to_string(&scene).unwrap().contains("$CAUSTICA_DATA") && !caustica::scene::data_dir().exists() {
            eprintln!("SKIPPED: {stem} needs the shared data folder ({} is missing)", caustica::scene::data_dir().display());
            continue;
        }
        for ext in ["pfm", "exr", "png"] {
            let out = dir.join(format!("{stem}.{ext}"));
            let o = caustica(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--width", "24", "--height", "16", "--spp", "2", "-q", "--validation"]);
            assert!(o.status.success(), "{stem}.{ext}: {}", String::from_utf8_lossy(&o.stderr));
            assert!(out.metadata().map(|m| m.len() > 0).unwrap_or(false), "{} was not written", out.display());
        }
        let image = read_image(&dir.join(format!("{stem}.exr"))).unwrap();
        assert_eq!((image.width, image.height), (24, 16));
        assert!(image.pixels.iter().flatten().all(|c| c.is_finite() && *c >= 0.0), "{stem}: non-finite or negative radiance");
        assert!(image.pixels.iter().flatten().any(|c| *c > 0.0), "{stem}: the image is black");
        rendered += 1;
    }
    assert!(rendered >= 3);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn default_scene_renders_with_no_scene_argument() {
    let dir = temp_dir("cli-default");
    let out = dir.join("default.pfm");
    let o = caustica(&["render", "-o", out.to_str().unwrap(), "--width", "16", "--height", "16", "--spp", "1", "-q"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(read_image(&out).unwrap().width, 16);
    std::fs::remove_dir_all(dir).ok();
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
    std::fs::write(dir.join("typo.toml"), "[camera]\nposition = [0.0, 0.0, 1.0]\nlook_at = [0.0, 0.0, 0.0]\nfovv = 30.0\n").unwrap();
    std::fs::write(dir.join("probe.toml"), "[camera]\nposition = [0.0, 0.0, 1.0]\nlook_at = [0.0, 0.0, 0.0]\n[environment]\nprobe = \"broken.pfm\"\n").unwrap();
    std::fs::write(dir.join("broken.pfm"), "PF\n4 4\n-1.0\nshort").unwrap();
    let path = |name: &str| dir.join(name).to_string_lossy().into_owned();
    let (out, missing, typo, probe, bmp) = (path("x.png"), path("missing.toml"), path("typo.toml"), path("probe.toml"), path("x.bmp"));
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
        assert!(stderr.contains(needle) && stderr.contains("error"), "{args:?}: stderr does not name '{needle}': {stderr}");
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn compare_prints_the_error_metrics_and_rejects_mismatched_sizes() {
    let dir = temp_dir("cli-compare");
    let render_to = |name: &str, seed: &str, width: &str| {
        let out = dir.join(name);
        let o = caustica(&["render", "-o", out.to_str().unwrap(), "--width", width, "--height", "8", "--spp", "4", "--seed", seed, "-q"]);
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
    std::fs::remove_dir_all(dir).ok();
}
