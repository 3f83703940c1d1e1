//! Where Open Image Denoise is looked for, and loading it: `CAUSTICA_OIDN` (the library file or its
//! folder) when set, and then only there; else the system's library path (`LD_LIBRARY_PATH`, the
//! loader's cache); else the project-local install of `scripts/install-oidn.sh`, `.oidn/lib` in
//! the project whose `target/<profile>/` holds the running executable.

use super::ffi::Oidn;
use anyhow::{anyhow, bail, Result};
use libloading::Library;
use std::path::{Path, PathBuf};

/// The library's file name: major version 2, the one whose C API `ffi` binds.
pub const LIBRARY_NAME: &str = "libOpenImageDenoise.so.2";
/// The variable that names the library (or its folder) to use.
pub const VARIABLE: &str = "CAUSTICA_OIDN";
/// What a user runs to install it (named by the error when it is missing).
pub const INSTALL_SCRIPT: &str = "scripts/install-oidn.sh";

/// Where the library was found, for messages.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Origin {
    /// `CAUSTICA_OIDN`, resolved to the file.
    Variable(PathBuf),
    /// The system's library path (the loader found `LIBRARY_NAME` by name).
    System,
    /// The project-local install.
    ProjectLocal(PathBuf),
}

impl std::fmt::Display for Origin {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        match self {
            Origin::Variable(path) => write!(f, "{} ({VARIABLE})", path.display()),
            Origin::System => write!(f, "{LIBRARY_NAME} on the system's library path"),
            Origin::ProjectLocal(path) => write!(f, "{}", path.display()),
        }
    }
}

/// Finds and loads the library as the module's documentation says. Errors name where it looked and
/// what was wrong: a `CAUSTICA_OIDN` that is missing or not OIDN 2, or no OIDN anywhere (naming
/// the install script).
pub fn load() -> Result<(Oidn, Origin)> {
    match std::env::var_os(VARIABLE).filter(|v| !v.is_empty()) {
        Some(value) => {
            let path = from_variable(Path::new(&value))?;
            let oidn = open(&path).map_err(|e| anyhow!("{VARIABLE}={}: {e}", Path::new(&value).display()))?;
            Ok((oidn, Origin::Variable(path)))
        }
        None => {
            if let Some(oidn) = open_system()? {
                return Ok((oidn, Origin::System));
            }
            let candidates = project_local_candidates();
            for path in &candidates {
                if path.is_file() {
                    let oidn = open(path).map_err(|e| anyhow!("{}: {e}", path.display()))?;
                    return Ok((oidn, Origin::ProjectLocal(path.clone())));
                }
            }
            let looked: Vec<String> = candidates.iter().map(|p| p.display().to_string()).collect();
            bail!(
                "Intel Open Image Denoise 2 ({LIBRARY_NAME}) is not installed: not on the system's library path{}{}. \
                 Run {INSTALL_SCRIPT} (it installs it under the project, no root needed), or set {VARIABLE} to the library",
                if looked.is_empty() { "" } else { " nor in " },
                looked.join(", ")
            )
        }
    }
}

/// The library file `CAUSTICA_OIDN` names: the file itself, or `LIBRARY_NAME` in the folder.
fn from_variable(value: &Path) -> Result<PathBuf> {
    let path = if value.is_dir() { value.join(LIBRARY_NAME) } else { value.to_owned() };
    if !path.exists() {
        bail!("{VARIABLE}={}: {} does not exist (it names the Open Image Denoise 2 library, {LIBRARY_NAME}, or its folder)", value.display(), path.display());
    }
    if !path.is_file() {
        bail!("{VARIABLE}={}: {} is not a file", value.display(), path.display());
    }
    Ok(path)
}

/// Loads a library file and checks that it has OIDN 2's functions.
fn open(path: &Path) -> Result<Oidn> {
    // An absolute path, so that the loader takes this file and does not search for the name.
    let path = std::path::absolute(path).unwrap_or_else(|_| path.to_owned());
    // SAFETY: loading runs the library's initialisers. The file is the one the user named or the
    // project's install put there, as trusted as the executable itself; what it exports is checked
    // before any of it is called.
    let library = unsafe { Library::new(&path) }.map_err(|e| anyhow!("cannot load it as a library ({e})"))?;
    Oidn::from_library(library).map_err(|missing| {
        anyhow!(
            "not Open Image Denoise 2: it has no function {missing} (caustica needs {LIBRARY_NAME}, major version 2)"
        )
    })
}

/// The library found by name on the system's library path; `None` where the loader finds none.
fn open_system() -> Result<Option<Oidn>> {
    // SAFETY: as in `open`; the loader takes the file the system's configuration names.
    match unsafe { Library::new(LIBRARY_NAME) } {
        Ok(library) => Oidn::from_library(library).map(Some).map_err(|missing| {
            anyhow!(
                "{LIBRARY_NAME} on the system's library path is not Open Image Denoise 2: it has no function {missing}"
            )
        }),
        // The loader's message for a name it cannot find; anything else (a dependency missing, a
        // broken file) is worth reporting rather than passing over.
        Err(e) if e.to_string().contains("No such file") => Ok(None),
        Err(e) => bail!("{LIBRARY_NAME} on the system's library path cannot be loaded: {e}"),
    }
}

/// `.oidn/lib/LIBRARY_NAME` in the project that built the running executable: its
/// `target/<profile>/caustica` (and `target/<profile>/deps/` for tests), two or three folders up.
fn project_local_candidates() -> Vec<PathBuf> {
    let Ok(exe) = std::env::current_exe() else { return vec![] };
    let exe = exe.canonicalize().unwrap_or(exe);
    let mut found = vec![];
    for up in [3, 4] {
        if let Some(root) = exe.ancestors().nth(up) {
            if root.join("Cargo.toml").is_file() {
                found.push(root.join(".oidn/lib").join(LIBRARY_NAME));
            }
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::temp_dir;

    #[test]
    fn variable_names_a_file_or_its_folder() {
        let dir = temp_dir("oidn-variable");
        let err = from_variable(&dir).unwrap_err().to_string();
        assert!(err.contains(VARIABLE) && err.contains(LIBRARY_NAME) && err.contains("does not exist"), "{err}");
        std::fs::write(dir.join(LIBRARY_NAME), b"x").unwrap();
        assert_eq!(from_variable(&dir).unwrap(), dir.join(LIBRARY_NAME));
        let err = from_variable(&dir.join("missing.so")).unwrap_err().to_string();
        assert!(err.contains("missing.so") && err.contains("does not exist"), "{err}");
    }

    #[test]
    fn a_file_that_is_not_a_library_is_refused_by_name() {
        let dir = temp_dir("oidn-not-a-library");
        let file = dir.join(LIBRARY_NAME);
        std::fs::write(&file, b"not an ELF file").unwrap();
        let err = open(&file).err().expect("a text file is no library").to_string();
        assert!(err.contains("cannot load it as a library"), "{err}");
    }
}
