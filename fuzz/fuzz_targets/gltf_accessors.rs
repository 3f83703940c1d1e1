#![no_main]
//! glTF accessors: counts, offsets, strides, sparse blocks and the views and buffer behind them,
//! chosen by the fuzz bytes inside an otherwise valid glTF (see accessor_gltf.rs). Each input is
//! written as `input.gltf` and its buffer as `input.bin` in a per-process temporary directory.
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

mod accessor_gltf;

fn directory() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("caustica-fuzz-gltf-accessors-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    })
}

fuzz_target!(|data: &[u8]| {
    let (json, buffer) = accessor_gltf::gltf(data);
    let dir = directory();
    std::fs::write(dir.join(accessor_gltf::BUFFER_FILE), buffer).unwrap();
    let path = dir.join("input.gltf");
    std::fs::write(&path, json).unwrap();
    let _ = caustica::scene::load_asset(&path);
});
