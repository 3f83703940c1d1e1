#![no_main]
//! Wavefront OBJ (tobj plus caustica's conversion); a referenced MTL is
//! looked up in a directory holding only the two seed libraries (CornellBox-Original.mtl, tri.mtl).
//! The loader takes a path, so each input is written to a file in a per-process temporary directory.
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn input_path() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("caustica-fuzz-obj-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // The seeds' material libraries, so MTL parsing and material conversion run too.
        let mtl = include_bytes!("../../scenes/models/CornellBox-Original.mtl");
        std::fs::write(dir.join("CornellBox-Original.mtl"), mtl).unwrap();
        std::fs::write(dir.join("tri.mtl"), b"newmtl m\nKd 0.5 0.5 0.5\nKe 1 1 1\nd 0.5\nNi 1.4\nillum 7\n").unwrap();
        dir.join("input.obj")
    })
}

fuzz_target!(|data: &[u8]| {
    let path = input_path();
    std::fs::write(path, data).unwrap();
    let _ = caustica::scene::load_asset(path);
});
