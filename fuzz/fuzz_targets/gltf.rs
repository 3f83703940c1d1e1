#![no_main]
//! glTF/GLB (the gltf crate plus caustica's conversion); the input is written as .glb, which also accepts JSON glTF.
//! The loader takes a path, so each input is written to a file in a per-process temporary directory.
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn input_path() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("caustica-fuzz-gltf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join("input.glb")
    })
}

fuzz_target!(|data: &[u8]| {
    let path = input_path();
    std::fs::write(path, data).unwrap();
    let _ = caustica::scene::load_asset(path);
});
