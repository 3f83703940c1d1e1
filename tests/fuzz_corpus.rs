//! Replays the fuzzing corpus (fuzz/corpus/<target>/) and the minimized crashers the fuzzers found
//! (tests/fuzz_regressions/<target>/) through the same entry points as the fuzz targets in fuzz/,
//! on stable `cargo test` without libFuzzer. Every input must give a value or an error that names
//! the file; none may panic. See docs/fuzzing.md.

mod common;

use caustica::scene::{load_asset, Scene};
use std::path::{Path, PathBuf};

#[path = "../fuzz/fuzz_targets/accessor_gltf.rs"]
mod accessor_gltf;

/// The files of `fuzz/corpus/<target>` and `tests/fuzz_regressions/<target>`, sorted.
fn inputs(target: &str) -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in [root.join("fuzz/corpus").join(target), root.join("tests/fuzz_regressions").join(target)] {
        let Ok(entries) = std::fs::read_dir(&dir) else { continue };
        for entry in entries {
            let path = entry.unwrap().path();
            if path.is_file() {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// Runs `check` on every input of `target`, naming the input that panicked.
fn replay(target: &str, mut check: impl FnMut(&[u8])) {
    let files = inputs(target);
    assert!(!files.is_empty(), "no corpus for fuzz target '{target}'");
    for file in &files {
        let bytes = std::fs::read(file).unwrap();
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| check(&bytes)));
        assert!(outcome.is_ok(), "fuzz input {} panicked", file.display());
    }
}

fn assert_names(message: &str, name: &str) {
    assert!(message.contains(name), "error does not name the file '{name}': {message}");
}

#[test]
fn pfm_corpus() {
    replay("pfm", |bytes| match caustica::image::pfm::decode(bytes, "fuzz.pfm") {
        Ok(img) => {
            assert_eq!(img.pixels.len(), img.width as usize * img.height as usize);
            if let Err(e) = caustica::image::pfm::check_finite(&img, "fuzz.pfm") {
                assert_names(&e.to_string(), "fuzz.pfm");
            }
        }
        Err(e) => assert_names(&e.to_string(), "fuzz.pfm"),
    });
}

#[test]
fn scene_corpus() {
    // An empty base directory: referenced meshes and probes fail to load, so only the parser and
    // the validation run (as in the fuzz target, which also points $CAUSTICA_DATA there).
    let base = common::temp_dir("fuzz-scene");
    replay("scene", |bytes| {
        if let Ok(text) = std::str::from_utf8(bytes) {
            if let Err(e) = Scene::parse(text, "fuzz.toml", &base) {
                assert_names(&format!("{e:#}"), "fuzz.toml");
            }
        }
    });
}

/// Writes each input to `input.<extension>` in a scratch directory and loads it as a mesh file.
fn replay_asset(target: &str, extension: &str, setup: impl FnOnce(&Path)) {
    let dir = common::temp_dir(&format!("fuzz-{target}"));
    setup(&dir);
    let path = dir.join(format!("input.{extension}"));
    replay(target, |bytes| {
        std::fs::write(&path, bytes).unwrap();
        if let Err(e) = load_asset(&path) {
            assert_names(&e.to_string(), &path.display().to_string());
        }
    });
}

#[test]
fn obj_corpus() {
    replay_asset("obj", "obj", |dir| {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        std::fs::copy(root.join("scenes/models/CornellBox-Original.mtl"), dir.join("CornellBox-Original.mtl")).unwrap();
        std::fs::write(dir.join("tri.mtl"), b"newmtl m\nKd 0.5 0.5 0.5\nKe 1 1 1\nd 0.5\nNi 1.4\nillum 7\n").unwrap();
    });
}

#[test]
fn ply_corpus() {
    replay_asset("ply", "ply", |_| {});
}

#[test]
fn serialized_corpus() {
    // The fuzz target's entry point: the first and the second mesh of each file.
    let dir = common::temp_dir("fuzz-serialized");
    let path = dir.join("input.serialized");
    replay("serialized", |bytes| {
        std::fs::write(&path, bytes).unwrap();
        for shape_index in [None, Some(1)] {
            if let Err(e) =
                caustica::scene::load_asset_part(&caustica::input_file::InputFiles::anywhere(), &path, shape_index)
            {
                assert_names(&e.to_string(), &path.display().to_string());
            }
        }
    });
}

#[test]
fn gltf_corpus() {
    replay_asset("gltf", "glb", |_| {});
}

/// The `gltf_accessors` target: each input chooses the accessors of an otherwise valid glTF.
#[test]
fn gltf_accessors_corpus() {
    let dir = common::temp_dir("fuzz-gltf-accessors");
    let path = dir.join("input.gltf");
    let load = |bytes: &[u8]| {
        let (json, buffer) = accessor_gltf::gltf(bytes);
        std::fs::write(dir.join(accessor_gltf::BUFFER_FILE), buffer).unwrap();
        std::fs::write(&path, json).unwrap();
        load_asset(&path).map_err(|e| assert_names(&e.to_string(), &path.display().to_string())).is_ok()
    };
    let mut loaded = 0;
    replay("gltf_accessors", |bytes| loaded += usize::from(load(bytes)));
    assert!(loaded >= 3, "the seeds of valid sparse and indexed triangles load ({loaded} did)");
    // And a thousand more inputs from a fixed generator, so that stable `cargo test` probes
    // the counts-versus-bytes space too (each must load or fail with the file named, in bounded
    // time and memory).
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    for _ in 0..1000 {
        let bytes: Vec<u8> = (0..64)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                state as u8
            })
            .collect();
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| load(&bytes)));
        assert!(outcome.is_ok(), "generated input {bytes:?} panicked");
    }
}
