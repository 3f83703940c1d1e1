#![no_main]
//! Mitsuba's .serialized meshes (caustica's reader, src/scene/asset/serialized.rs): the first and
//! the second mesh of each input, so the dictionary at the end of the file is read too.
//! The loader takes a path, so each input is written to a file in a per-process temporary directory.
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn input_path() -> &'static PathBuf {
    static PATH: OnceLock<PathBuf> = OnceLock::new();
    PATH.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("caustica-fuzz-serialized-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir.join("input.serialized")
    })
}

fuzz_target!(|data: &[u8]| {
    let path = input_path();
    std::fs::write(path, data).unwrap();
    let files = caustica::input_file::InputFiles::anywhere();
    for shape_index in [None, Some(1)] {
        let _ = caustica::scene::load_asset_part(&files, path, shape_index);
    }
});
