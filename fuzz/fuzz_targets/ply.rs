#![no_main]
//! PLY (ply-rs plus caustica's conversion).
//! The loader takes a path, so each input is written to a file in a per-process temporary directory.
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn input_path() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("caustica-fuzz-ply-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join("input.ply")
    })
}

fuzz_target!(|data: &[u8]| {
    let path = input_path();
    std::fs::write(path, data).unwrap();
    let _ = caustica::scene::load_asset(path);
});
