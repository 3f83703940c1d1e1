#![no_main]
//! TOML scene parser and validation. The base directory (and $CAUSTICA_DATA) is empty, so referenced meshes and
//! probes fail to load and only the parser and the checks run.
use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn empty_dir() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("caustica-fuzz-scene-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // `$CAUSTICA_DATA/...` paths must not reach the real (large) shared data set either.
        std::env::set_var("CAUSTICA_DATA", &dir);
        dir
    })
}

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = caustica::scene::Scene::parse(text, "fuzz.toml", empty_dir());
    }
});
