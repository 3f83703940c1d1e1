//! Denoising with Intel Open Image Denoise 2 (src/denoise/): a denoised Cornell box at 16 spp is
//! much closer to a converged render than the noisy one and keeps its mean; a converged render
//! passes nearly unchanged; merge and `caustica denoise` denoise files; the guides follow mirrors
//! and glass; and a missing or wrong OIDN is refused by name, exit status 1, before any rendering.
//!
//! The tests that run OIDN need it installed (scripts/install-oidn.sh, which CI runs): without it
//! they say SKIPPED, or fail where CAUSTICA_REQUIRE_OIDN is set (as .ci/run sets it).

mod common;

use caustica::farm::{snapshot, PartialRender, DENOISED, NOISY_LAYER};
use caustica::image::{compare, read_exr_document, read_image, ExrDocument, RgbImage};
use caustica::render::{AovSet, Renderer};
use common::*;
use std::path::Path;

/// Whether OIDN can be loaded as caustica finds it; says SKIPPED (naming `test`) where it cannot,
/// or fails where CAUSTICA_REQUIRE_OIDN asks for it.
fn oidn_installed(test: &str) -> bool {
    match caustica::denoise::Library::load() {
        Ok(_) => true,
        Err(e) if std::env::var_os("CAUSTICA_REQUIRE_OIDN").is_some() => {
            panic!("{test}: CAUSTICA_REQUIRE_OIDN is set but Open Image Denoise does not load: {e:#}")
        }
        Err(e) => {
            eprintln!("SKIPPED {test}: Open Image Denoise is not installed ({e:#})");
            false
        }
    }
}

fn run_ok(args: &[&str]) -> String {
    let o = caustica(args);
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{args:?}: {stderr}");
    stderr
}

/// The "R", "G", "B" channels of layer `name` ("" for the top level) of `doc`.
fn rgb_layer(doc: &ExrDocument, name: &str) -> RgbImage {
    let layer = doc.layer(name).unwrap_or_else(|| panic!("layer '{name}' is missing"));
    let at = |c: &str| layer.channels.iter().position(|n| n == c).unwrap_or_else(|| panic!("{name}.{c} is missing"));
    let (r, g, b, n) = (at("R"), at("G"), at("B"), layer.channels.len());
    let pixels = layer.data.chunks_exact(n).map(|p| [p[r], p[g], p[b]]).collect();
    RgbImage { width: doc.width, height: doc.height, pixels }
}

fn luminance(p: [f32; 3]) -> f64 {
    (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64
}

fn mean(image: &RgbImage) -> f64 {
    image.pixels.iter().map(|&p| luminance(p)).sum::<f64>() / image.pixels.len() as f64
}

/// The standard error of `noisy`'s mean luminance, from the scatter of its pixels about
/// `reference` (independent per pixel; the reference's own noise makes it slightly larger).
fn standard_error(noisy: &RgbImage, reference: &RgbImage) -> f64 {
    let n = noisy.pixels.len() as f64;
    let variance =
        noisy.pixels.iter().zip(&reference.pixels).map(|(&a, &b)| (luminance(a) - luminance(b)).powi(2)).sum::<f64>()
            / n;
    (variance / n).sqrt()
}

fn relative_mse(image: &RgbImage, reference: &RgbImage) -> f64 {
    compare(image, reference, ("image", "reference")).unwrap().relative_mse
}

#[test]
fn denoised_cornell_box_at_16_spp_is_5x_closer_to_the_reference_and_keeps_its_mean() {
    if !oidn_installed("denoised_cornell_box_at_16_spp_is_5x_closer_to_the_reference_and_keeps_its_mean") {
        return;
    }
    // 128 x 128: at 64 x 64 the light is a strip three pixels tall, whose edges the denoiser
    // moves by a few percent of the image's mean (measured 2026-12-07: up to 1.8 % at 64 x 64,
    // 0.4 % at 128 x 128).
    const SPP: u32 = 16;
    const REFERENCE_SPP: u32 = 256;
    let dir = temp_dir("denoise-cornell");
    let (reference, denoised) = (dir.join("reference.exr"), dir.join("denoised.exr"));
    let size = ["--width", "128", "--height", "128"];
    let reference_spp = REFERENCE_SPP.to_string();
    run_ok(
        &[&["render", "-q", "--seed", "7", "--spp", &reference_spp, "-o", reference.to_str().unwrap()][..], &size]
            .concat(),
    );
    let stderr = run_ok(
        &[
            &["render", "--seed", "1", "--spp", &SPP.to_string(), "--denoise", "-o", denoised.to_str().unwrap()][..],
            &size,
        ]
        .concat(),
    );
    let device_said = stderr.contains(" on CPU") || stderr.contains(" on CUDA");
    assert!(stderr.contains("denoising with Open Image Denoise 2.") && device_said, "says which device: {stderr}");
    let reference = read_image(&reference).unwrap();
    let doc = read_exr_document(&denoised).unwrap();
    let (clean, noisy) = (rgb_layer(&doc, ""), rgb_layer(&doc, NOISY_LAYER));
    assert!(doc.attributes[DENOISED].contains("quality high, guides albedo and normal"), "{:?}", doc.attributes);
    for guide in ["albedo", "normal"] {
        assert!(doc.layer(guide).is_some(), "the EXR keeps the guide '{guide}'");
    }

    // Pixel by pixel: the relative MSE against the reference, whose own noise (1/16 of the noisy
    // image's) is counted against the denoised image, which makes the test stricter, not looser.
    let (noisy_error, clean_error) = (relative_mse(&noisy, &reference), relative_mse(&clean, &reference));
    eprintln!(
        "relative MSE: noisy {noisy_error:.4e}, denoised {clean_error:.4e} ({:.1}x lower)",
        noisy_error / clean_error
    );
    assert!(clean_error * 5.0 <= noisy_error, "denoised {clean_error:.4e}, noisy {noisy_error:.4e}: not 5x lower");

    // The mean: within 1 % of the reference's, plus five standard errors of the reference's mean
    // (its noise, from the noisy image's scatter scaled to its sample count, ~0.4 %). Fails a
    // denoiser that adds or loses 1.5 % of the energy.
    let reference_error = 5.0 * standard_error(&noisy, &reference) * (SPP as f64 / REFERENCE_SPP as f64).sqrt();
    let tolerance = 0.01 + reference_error / mean(&reference);
    assert!(tolerance <= 0.015, "the reference's noise ({reference_error:.2e}) no longer resolves a 1.5 % error");
    let ratio = mean(&clean) / mean(&reference);
    eprintln!("denoised mean / reference mean: {ratio:.5} (tolerance {:.3} %)", tolerance * 100.0);
    assert!((ratio - 1.0).abs() <= tolerance, "denoised mean off by {:+.3} %", (ratio - 1.0) * 100.0);
}

#[test]
fn a_converged_render_passes_nearly_unchanged_through_caustica_denoise() {
    if !oidn_installed("a_converged_render_passes_nearly_unchanged_through_caustica_denoise") {
        return;
    }
    // 256 spp as two halves of 128: their difference measures the noise the merged render still
    // holds, which is what the denoiser may take away; anything beyond it is a change of the image.
    let dir = temp_dir("denoise-converged");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_owned();
    let (halves, merged, denoised) = ([path("a.exr"), path("b.exr")], path("merged.exr"), path("denoised.exr"));
    for (half, offset) in halves.iter().zip(["0", "128"]) {
        let args = ["--width", "64", "--height", "64", "--spp", "128", "--sample-offset", offset];
        run_ok(&[&["render", "-q", "--aov", "albedo,normal", "-o", half][..], &args].concat());
    }
    run_ok(&["merge", "-q", &halves[0], &halves[1], "-o", &merged]);
    run_ok(&["denoise", &merged, "-o", &denoised, "-q"]);
    let doc = read_exr_document(Path::new(&denoised)).unwrap();
    let (clean, noisy) = (rgb_layer(&doc, ""), rgb_layer(&doc, NOISY_LAYER));
    assert_eq!(noisy, read_image(Path::new(&merged)).unwrap(), "the noisy layer is the input's mean");
    // The halves differ by twice the variance of one, which is twice the merged render's.
    let [a, b] = halves.map(|h| read_image(Path::new(&h)).unwrap());
    let noise = relative_mse(&a, &b) / 4.0;
    let (change, ratio) = (relative_mse(&clean, &noisy), mean(&clean) / mean(&noisy));
    eprintln!("converged render: noise {noise:.3e}, change {change:.3e} (relative MSE), mean ratio {ratio:.5}");
    // Measured 2026-12-07: a change of about the noise and the mean within 0.2 %. A denoiser that
    // blurred the image beyond its noise, or changed its energy by 1 %, fails.
    assert!(change < 1.5 * noise, "the denoiser changed a converged image by {change:.3e}, its noise is {noise:.3e}");
    assert!(
        (ratio - 1.0).abs() < 0.01,
        "the denoiser changed a converged image's mean by {:+.3} %",
        (ratio - 1.0) * 100.0
    );
    // The accumulation is kept, so the denoised file still merges and resumes.
    let partial = PartialRender::read(Path::new(&denoised)).unwrap();
    assert_eq!(partial, PartialRender::read(Path::new(&merged)).unwrap());
}

#[test]
fn merge_denoise_denoises_the_merged_partials_once() {
    if !oidn_installed("merge_denoise_denoises_the_merged_partials_once") {
        return;
    }
    let dir = temp_dir("denoise-merge");
    let parts: Vec<String> = (0..2).map(|i| dir.join(format!("part{i}.exr")).to_str().unwrap().to_owned()).collect();
    for (i, part) in parts.iter().enumerate() {
        let offset = (8 * i).to_string();
        run_ok(&[
            "render",
            "-q",
            "--width",
            "32",
            "--height",
            "32",
            "--spp",
            "8",
            "--sample-offset",
            &offset,
            "--denoise",
            "-o",
            part,
        ]);
    }
    let (plain, denoised) = (dir.join("merged.exr"), dir.join("denoised.exr"));
    run_ok(&["merge", "-q", &parts[0], &parts[1], "-o", plain.to_str().unwrap()]);
    let stderr = run_ok(&["merge", &parts[0], &parts[1], "--denoise", "fast", "-o", denoised.to_str().unwrap()]);
    assert!(stderr.contains("quality fast, guides albedo and normal"), "{stderr}");
    let doc = read_exr_document(&denoised).unwrap();
    assert_eq!(rgb_layer(&doc, NOISY_LAYER), read_image(&plain).unwrap(), "the noisy layer is the merged mean");
    let clean = rgb_layer(&doc, "");
    assert!(relative_mse(&clean, &rgb_layer(&doc, NOISY_LAYER)) > 1e-3, "the merged image was not denoised");
    assert!(doc.attributes[DENOISED].contains("quality fast"));
}

#[test]
fn glass_shows_the_albedo_and_normal_of_the_surface_seen_through_it() {
    // A slab of smooth glass (black albedo, two parallel faces at z = -1 and -1.5) fills the view;
    // behind it a wall whose normal leans 37 degrees to +x. Rays that pass straight through
    // (two refractions) reach the wall; those the glass reflects escape to a sky of the wall's
    // colour, which counts as that albedo with a zero normal. So the albedo is the wall's
    // exactly, and the normal the wall's scaled by the share transmitted (~0.92). A kernel that
    // stopped at the glass would give black and (0, 0, 1).
    let scene = parse(
        r#"
        camera = { position = [0, 0, 0], look_at = [0, 0, -1], fov = 20 }
        film = { width = 8, height = 8, spp = 64, filter = "box" }
        environment = { color = [0.7, 0.1, 0.3] }
        [materials.glass]
        albedo = [0, 0, 0]
        transparency = 1.0
        ior = 1.5
        [materials.wall]
        albedo = [0.7, 0.1, 0.3]
        [[quads]]
        origin = [-1, -1, -1]
        edge_u = [2, 0, 0]
        edge_v = [0, 2, 0]
        material = "glass"
        [[quads]]
        origin = [-1, -1, -1.5]
        edge_u = [2, 0, 0]
        edge_v = [0, 2, 0]
        material = "glass"
        [[quads]]
        origin = [-8, -10, 1]
        edge_u = [16, 0, -12]
        edge_v = [0, 20, 0]
        material = "wall"
        "#,
    );
    let partial = {
        let (_lock, ctx) = gpu();
        let mut renderer = Renderer::with_aovs(&ctx, &scene, 3, AovSet::ALL).expect("scene uploads");
        renderer.render(scene.film.spp, |_| {}).expect("render succeeds");
        snapshot(&renderer).unwrap().unwrap()
    };
    let counts: Vec<f32> = partial.accumulation.iter().map(|a| a[3]).collect();
    let sums = partial.aov_sums.as_ref().unwrap();
    let wall_normal = [0.6f32, 0.0, 0.8];
    for (i, (albedo, normal)) in sums.albedo(&counts).into_iter().zip(sums.normal(&counts)).enumerate() {
        assert!(
            (0..3).all(|c| (albedo[c] - [0.7, 0.1, 0.3][c]).abs() < 1e-5),
            "pixel {i}: albedo {albedo:?}, expected the wall's seen through the glass"
        );
        let length = normal.iter().map(|c| c * c).sum::<f32>().sqrt();
        let cosine = (0..3).map(|c| normal[c] * wall_normal[c]).sum::<f32>() / length;
        // Fresnel at ~1.5: 4 % per face, ~8 % over two, and a little more off-axis.
        assert!((0.8..=1.0).contains(&length), "pixel {i}: normal {normal:?} of length {length}, expected ~0.92");
        assert!(cosine > 0.9999, "pixel {i}: normal {normal:?}, expected the wall's {wall_normal:?}");
    }
}

/// A copy of the caustica binary in a folder of its own, away from the project's .oidn/.
fn binary_away_from_the_project(dir: &Path) -> std::path::PathBuf {
    let folder = dir.join("a/b/c");
    std::fs::create_dir_all(&folder).unwrap();
    let copy = folder.join("caustica");
    std::fs::copy(env!("CARGO_BIN_EXE_caustica"), &copy).unwrap();
    copy
}

/// Runs `render --denoise` with `env` set (and CAUSTICA_OIDN removed unless `env` sets it); checks
/// exit status 1, the message holding each of `needles`, and that nothing was rendered.
fn refused_before_rendering(binary: &Path, env: &[(&str, &str)], needles: &[&str]) {
    let dir = temp_dir("denoise-refused");
    let output = dir.join("out.png");
    let mut cmd = std::process::Command::new(binary);
    if let Some(icd) = lavapipe_override() {
        cmd.env("VK_DRIVER_FILES", icd);
    }
    cmd.env_remove("CAUSTICA_OIDN").env_remove("LD_LIBRARY_PATH");
    for (key, value) in env {
        cmd.env(key, value);
    }
    let args = ["render", "--width", "8", "--height", "8", "--spp", "1", "--denoise", "-o", output.to_str().unwrap()];
    let o = cmd.args(args).output().unwrap();
    for needle in needles {
        fails_with(&o, needle);
    }
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!output.exists() && !stderr.contains("wrote"), "rendered in vain: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "one message, no panic: {stderr}");
}

#[test]
fn missing_oidn_names_the_install_script_before_rendering() {
    let system = std::process::Command::new("/sbin/ldconfig").arg("-p").output();
    if system.is_ok_and(|o| String::from_utf8_lossy(&o.stdout).contains(caustica::denoise::LIBRARY_NAME)) {
        eprintln!("SKIPPED missing_oidn_names_the_install_script_before_rendering: OIDN is installed system-wide");
        return;
    }
    let dir = temp_dir("denoise-missing");
    let binary = binary_away_from_the_project(&dir);
    refused_before_rendering(
        &binary,
        &[],
        &["Open Image Denoise 2 (libOpenImageDenoise.so.2) is not installed", "scripts/install-oidn.sh"],
    );
}

#[test]
fn a_wrong_caustica_oidn_is_refused_by_name_before_rendering() {
    let dir = temp_dir("denoise-wrong");
    let binary = Path::new(env!("CARGO_BIN_EXE_caustica"));
    let missing = dir.join("missing/libOpenImageDenoise.so.2");
    let missing = missing.to_str().unwrap();
    refused_before_rendering(
        binary,
        &[("CAUSTICA_OIDN", missing)],
        &[&format!("CAUSTICA_OIDN={missing}"), "does not exist"],
    );
    let folder = dir.to_str().unwrap();
    refused_before_rendering(
        binary,
        &[("CAUSTICA_OIDN", folder)],
        &[&format!("CAUSTICA_OIDN={folder}"), "does not exist"],
    );
    refused_before_rendering(
        binary,
        &[("CAUSTICA_OIDN", "/bin/ls")],
        &["CAUSTICA_OIDN=/bin/ls", "cannot load it as a library"],
    );
    // A library with OIDN 2's functions that reports version 1.4.3 (tests/support/fake_oidn.c).
    let fake = dir.join("libOpenImageDenoise.so.2");
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/support/fake_oidn.c");
    let built = std::process::Command::new("cc")
        .args(["-shared", "-fPIC", "-o", fake.to_str().unwrap(), source.to_str().unwrap()])
        .status();
    assert!(built.is_ok_and(|s| s.success()), "cc (which cargo links with) builds tests/support/fake_oidn.c");
    refused_before_rendering(
        binary,
        &[("CAUSTICA_OIDN", folder)],
        &[fake.to_str().unwrap(), "CAUSTICA_OIDN", "version 1.4.3, not 2"],
    );
}
