//! Reading the files a scene names. The scene file itself, meshes, MTL libraries, glTF buffers,
//! textures, environment maps and the partial renders of `merge` and `--resume` are all read
//! through [`InputFiles`], never opened by a loader or a crate directly, so every one of them gets
//! the same checks whoever parses it:
//!
//! - only regular files: a device (`/dev/zero` never ends), a FIFO (blocks until someone writes)
//!   or a directory is refused by name before a byte is read;
//! - a size cap per [`InputKind`], checked on the file's metadata and again while reading, since a
//!   file can grow in between (or be a different file by then);
//! - with `render --confine`, a confinement: the file must resolve, after `..` and symbolic links,
//!   inside one of the allowed folders (the scene's folder and the shared data folder).
//!
//! The caps are generous bounds for real files, not quotas; they exist so that no input can make
//! caustica read without end. docs/cli.md ("Input files") lists them.

use std::fs::{File, Metadata};
use std::io::{self, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// What a file is read as, which decides its size cap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InputKind {
    /// A scene's TOML text: 16 MiB, a thousand times the largest scene in `scenes/`.
    Scene,
    /// An OBJ, PLY, glTF or GLB mesh file, or a glTF's external buffer: 4 GiB, what a GLB's 32-bit
    /// length field can describe (and a scan of hundreds of millions of triangles).
    Mesh,
    /// An OBJ's MTL material library: 64 MiB (a million materials).
    MaterialLibrary,
    /// A PNG or JPEG texture as stored: 1 GiB, the raw size of the largest texture caustica
    /// accepts (16384 x 16384 RGBA8), which any real encoding stays below.
    Texture,
    /// A PFM, EXR or Radiance .hdr radiance image (environment maps, `compare`): 4 GiB, the largest PFM accepted
    /// (2^28 RGB float pixels, 3 GiB) with room to spare.
    RadianceImage,
    /// A partial render or checkpoint (EXR) read by `merge` and `--resume`: 32 GiB, a 16384 x 16384
    /// render with every AOV stored uncompressed.
    PartialRender,
    /// A medium's density grid (Mitsuba's `.vol`): 4 GiB, a 1024^3 grid of floats.
    DensityGrid,
    /// A kernel shader file read from `$CAUSTICA_SHADER_DIR` (shader work, mutation testing):
    /// 4 MiB, a hundred times the largest shader file.
    Shader,
}

impl InputKind {
    /// The most bytes a file of this kind may hold.
    pub const fn cap(self) -> u64 {
        match self {
            InputKind::Scene => 16 << 20,
            InputKind::Mesh => 4 << 30,
            InputKind::MaterialLibrary => 64 << 20,
            InputKind::Texture => 1 << 30,
            InputKind::RadianceImage => 4 << 30,
            InputKind::PartialRender => 32 << 30,
            InputKind::DensityGrid => 4 << 30,
            InputKind::Shader => 4 << 20,
        }
    }

    fn noun(self) -> &'static str {
        match self {
            InputKind::Scene => "a scene file",
            InputKind::Mesh => "a mesh file or glTF buffer",
            InputKind::MaterialLibrary => "an MTL material library",
            InputKind::Texture => "a texture",
            InputKind::RadianceImage => "a PFM, EXR or Radiance .hdr image",
            InputKind::PartialRender => "a partial render",
            InputKind::DensityGrid => "a density grid",
            InputKind::Shader => "a shader file",
        }
    }
}

/// A byte count for messages: exact below 1 KiB, else in the largest binary unit that fits.
pub fn describe_bytes(bytes: u64) -> String {
    const UNITS: [&str; 4] = ["KiB", "MiB", "GiB", "TiB"];
    if bytes < 1024 {
        return format!("{bytes} bytes");
    }
    let mut value = bytes as f64 / 1024.0;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if value.fract() == 0.0 {
        format!("{value:.0} {}", UNITS[unit])
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// Why a file could not be read; the message starts with the file's path.
#[derive(Debug, thiserror::Error)]
#[error("{}: {problem}", path.display())]
pub struct InputError {
    path: PathBuf,
    problem: Problem,
}

impl InputError {
    /// The file, as the scene (or the command line) named it.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

#[derive(Debug, thiserror::Error)]
enum Problem {
    #[error("{0}")]
    Io(io::Error),
    #[error("not a regular file ({0}): caustica reads its inputs only from regular files")]
    NotRegular(&'static str),
    #[error("{size} bytes, over the {} limit for {}", describe_bytes(kind.cap()), kind.noun())]
    TooLarge { size: u64, kind: InputKind },
    #[error("grew past the {} limit for {} while being read", describe_bytes(kind.cap()), kind.noun())]
    Grew { kind: InputKind },
    #[error("not UTF-8 text ({0})")]
    NotText(std::str::Utf8Error),
    #[error("resolves to {}, outside the folders that --confine allows ({})", resolved.display(), list(allowed))]
    Outside { resolved: PathBuf, allowed: Vec<PathBuf> },
}

fn list(folders: &[PathBuf]) -> String {
    if folders.is_empty() {
        return "none exists".to_owned();
    }
    folders.iter().map(|f| f.display().to_string()).collect::<Vec<_>>().join(", ")
}

/// The one way caustica reads an input file, and where files may come from.
#[derive(Clone, Debug, Default)]
pub struct InputFiles {
    /// Canonical folders a file must resolve into; `None`: anywhere.
    allowed: Option<Vec<PathBuf>>,
    /// Every file opened, when recording ([`InputFiles::recording`]); shared by clones.
    opened: Option<std::sync::Arc<std::sync::Mutex<Vec<PathBuf>>>>,
}

impl InputFiles {
    /// Files from anywhere: the user's own scenes.
    pub fn anywhere() -> Self {
        InputFiles { allowed: None, opened: None }
    }

    /// These files, also noting every file opened (see [`InputFiles::opened`]): what a scene read,
    /// so that a viewer can watch them for changes.
    pub fn recording(self) -> Self {
        InputFiles { opened: Some(Default::default()), ..self }
    }

    /// The files opened so far, each once, in the order first opened (empty unless recording).
    pub fn opened(&self) -> Vec<PathBuf> {
        self.opened.as_ref().map(|o| o.lock().unwrap_or_else(|e| e.into_inner()).clone()).unwrap_or_default()
    }

    /// Only files that resolve, after `..` and symbolic links, inside one of `folders`. A folder
    /// that does not exist is left out (nothing can be inside it).
    pub fn confined_to<'a>(folders: impl IntoIterator<Item = &'a Path>) -> Self {
        let mut allowed: Vec<PathBuf> = folders.into_iter().filter_map(|f| f.canonicalize().ok()).collect();
        allowed.dedup();
        InputFiles { allowed: Some(allowed), opened: None }
    }

    /// Reads the whole file.
    pub fn read(&self, path: &Path, kind: InputKind) -> Result<Vec<u8>, InputError> {
        let fail = |problem| InputError { path: path.to_owned(), problem };
        let (file, size) = self.open_checked(path, kind)?;
        // The metadata's size is only a hint: `take` stops one byte past the cap whatever it said.
        let mut bytes = Vec::with_capacity(size as usize);
        file.take(kind.cap() + 1).read_to_end(&mut bytes).map_err(|e| fail(Problem::Io(e)))?;
        if bytes.len() as u64 > kind.cap() {
            return Err(fail(Problem::Grew { kind }));
        }
        Ok(bytes)
    }

    /// Reads the whole file as UTF-8 text.
    pub fn read_to_string(&self, path: &Path, kind: InputKind) -> Result<String, InputError> {
        String::from_utf8(self.read(path, kind)?)
            .map_err(|e| InputError { path: path.to_owned(), problem: Problem::NotText(e.utf8_error()) })
    }

    /// Opens the file for decoders that stream and seek (EXR) instead of taking bytes.
    pub fn open(&self, path: &Path, kind: InputKind) -> Result<CappedFile, InputError> {
        let (file, _) = self.open_checked(path, kind)?;
        Ok(CappedFile { file, path: path.to_owned(), kind, position: 0 })
    }

    /// Applies the confinement, then opens a regular file within the cap; returns it with the
    /// size its metadata gives.
    fn open_checked(&self, path: &Path, kind: InputKind) -> Result<(File, u64), InputError> {
        let fail = |problem| InputError { path: path.to_owned(), problem };
        let target = match &self.allowed {
            None => path.to_owned(),
            Some(allowed) => {
                let resolved = path.canonicalize().map_err(|e| fail(Problem::Io(e)))?;
                if !allowed.iter().any(|folder| resolved.starts_with(folder)) {
                    return Err(fail(Problem::Outside { resolved, allowed: allowed.clone() }));
                }
                // Open what was checked, not a path whose links could change meanwhile.
                resolved
            }
        };
        if let Some(opened) = &self.opened {
            let mut opened = opened.lock().unwrap_or_else(|e| e.into_inner());
            if !opened.contains(&target) {
                opened.push(target.clone());
            }
        }
        // Checked before opening: opening a FIFO for reading blocks until a writer comes.
        let metadata = std::fs::metadata(&target).map_err(|e| fail(Problem::Io(e)))?;
        check_metadata(&metadata, kind).map_err(fail)?;
        let file = open_without_blocking(&target).map_err(|e| fail(Problem::Io(e)))?;
        // And again on what was opened, which may have been replaced since.
        let metadata = file.metadata().map_err(|e| fail(Problem::Io(e)))?;
        check_metadata(&metadata, kind).map_err(fail)?;
        Ok((file, metadata.len()))
    }
}

fn check_metadata(metadata: &Metadata, kind: InputKind) -> Result<(), Problem> {
    if !metadata.is_file() {
        return Err(Problem::NotRegular(file_type_name(metadata)));
    }
    if metadata.len() > kind.cap() {
        return Err(Problem::TooLarge { size: metadata.len(), kind });
    }
    Ok(())
}

fn file_type_name(metadata: &Metadata) -> &'static str {
    let file_type = metadata.file_type();
    if file_type.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if file_type.is_char_device() {
            return "a character device";
        }
        if file_type.is_block_device() {
            return "a block device";
        }
        if file_type.is_fifo() {
            return "a FIFO";
        }
        if file_type.is_socket() {
            return "a socket";
        }
    }
    "not a plain file"
}

/// Opens for reading without blocking on a FIFO swapped in after the metadata check (O_NONBLOCK
/// changes nothing for the regular files that are then read).
fn open_without_blocking(path: &Path) -> io::Result<File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt as _;
        options.custom_flags(libc::O_NONBLOCK);
    }
    options.open(path)
}

/// An input file opened by [`InputFiles::open`]: reading past its kind's cap is an error, however
/// much the file grew after it was opened.
#[derive(Debug)]
pub struct CappedFile {
    file: File,
    path: PathBuf,
    kind: InputKind,
    position: u64,
}

impl Read for CappedFile {
    fn read(&mut self, buffer: &mut [u8]) -> io::Result<usize> {
        // At most one byte past the cap, which is enough to tell that the file is over it.
        let room = (self.kind.cap() + 1).saturating_sub(self.position);
        let length = buffer.len().min(usize::try_from(room).unwrap_or(usize::MAX));
        let read = self.file.read(&mut buffer[..length])?;
        self.position += read as u64;
        if self.position > self.kind.cap() {
            return Err(io::Error::other(InputError {
                path: self.path.clone(),
                problem: Problem::Grew { kind: self.kind },
            }));
        }
        Ok(read)
    }
}

impl Seek for CappedFile {
    fn seek(&mut self, to: SeekFrom) -> io::Result<u64> {
        self.position = self.file.seek(to)?;
        Ok(self.position)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::temp_dir;

    fn message(result: Result<Vec<u8>, InputError>) -> String {
        result.expect_err("the read should fail").to_string()
    }

    #[test]
    fn devices_and_directories_are_refused_by_name() {
        let files = InputFiles::anywhere();
        let err = message(files.read(Path::new("/dev/zero"), InputKind::Mesh));
        assert!(err.starts_with("/dev/zero: not a regular file (a character device)"), "{err}");
        let dir = temp_dir("input-dir");
        let err = message(files.read(&dir, InputKind::Scene));
        assert!(err.contains(&dir.display().to_string()) && err.contains("a directory"), "{err}");
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let dir = temp_dir("input-fifo");
        let fifo = dir.join("pipe.obj");
        let status = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
        assert!(status.success());
        let err = message(InputFiles::anywhere().read(&fifo, InputKind::Mesh));
        assert!(err.contains("pipe.obj") && err.contains("a FIFO"), "{err}");
    }

    #[test]
    fn every_kind_refuses_a_file_one_byte_over_its_cap() {
        let dir = temp_dir("input-caps");
        for kind in [
            InputKind::Scene,
            InputKind::Mesh,
            InputKind::MaterialLibrary,
            InputKind::Texture,
            InputKind::RadianceImage,
            InputKind::PartialRender,
            InputKind::Shader,
        ] {
            // A sparse file: its length is over the cap, its disk use nothing.
            let path = dir.join(format!("{kind:?}.bin"));
            let file = File::create(&path).unwrap();
            file.set_len(kind.cap() + 1).unwrap();
            let err = message(InputFiles::anywhere().read(&path, kind));
            let limit = format!("over the {} limit", describe_bytes(kind.cap()));
            assert!(err.contains(&path.display().to_string()) && err.contains(&limit), "{err}");
            file.set_len(16).unwrap();
            assert_eq!(InputFiles::anywhere().read(&path, kind).unwrap(), vec![0; 16]);
        }
    }

    #[test]
    fn a_file_growing_past_its_cap_while_read_is_stopped_there() {
        let dir = temp_dir("input-grow");
        let path = dir.join("scene.toml");
        std::fs::write(&path, b"[camera]\n").unwrap();
        let mut file = InputFiles::anywhere().open(&path, InputKind::Scene).unwrap();
        // Grows after the checks on open, as a file being written would.
        File::options().write(true).open(&path).unwrap().set_len(InputKind::Scene.cap() + 100).unwrap();
        let mut sink = Vec::new();
        let err = file.read_to_end(&mut sink).unwrap_err().to_string();
        assert!(err.contains("scene.toml") && err.contains("grew past the 16 MiB limit"), "{err}");
        assert!(sink.len() as u64 <= InputKind::Scene.cap(), "{} bytes came through", sink.len());
    }

    #[test]
    fn confinement_follows_dot_dot_and_links() {
        let root = temp_dir("input-confine");
        let inside = root.join("scene");
        std::fs::create_dir_all(inside.join("meshes")).unwrap();
        std::fs::write(inside.join("meshes/a.obj"), b"v 0 0 0\n").unwrap();
        std::fs::write(root.join("secret.txt"), b"secret").unwrap();
        let files = InputFiles::confined_to([inside.as_path(), root.join("missing").as_path()]);
        assert_eq!(files.read(&inside.join("meshes/../meshes/a.obj"), InputKind::Mesh).unwrap(), b"v 0 0 0\n");
        let err = message(files.read(&inside.join("../secret.txt"), InputKind::Mesh));
        assert!(err.contains("../secret.txt") && err.contains("outside the folders that --confine allows"), "{err}");
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(root.join("secret.txt"), inside.join("link.obj")).unwrap();
            let err = message(files.read(&inside.join("link.obj"), InputKind::Mesh));
            assert!(err.contains("link.obj") && err.contains("secret.txt"), "{err}");
            assert_eq!(InputFiles::anywhere().read(&inside.join("link.obj"), InputKind::Mesh).unwrap(), b"secret");
        }
    }

    #[test]
    fn byte_counts_read_well() {
        assert_eq!(describe_bytes(12), "12 bytes");
        assert_eq!(describe_bytes(16 << 20), "16 MiB");
        assert_eq!(describe_bytes(3 << 29), "1.5 GiB");
    }

    /// Outside this module, no library code opens or reads a file by itself: a loader that did
    /// would bypass the checks above. Test code (after `#[cfg(test)]`) may.
    #[test]
    fn no_loader_reads_files_around_this_module() {
        let forbidden = [
            "fs::read(",
            "fs::read_to_string(",
            "File::open(",
            "OpenOptions::new(",
            ".from_file(",
            "_from_file(",
            "load_obj(",
            "load_mtl(",
            "gltf::import",
            "image::open(",
            "ImageReader::open(",
        ];
        let mut offenders = Vec::new();
        let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut folders = vec![src.clone()];
        while let Some(folder) = folders.pop() {
            for entry in std::fs::read_dir(&folder).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    folders.push(path);
                    continue;
                }
                if path.extension().is_none_or(|e| e != "rs") || path.ends_with("input_file.rs") {
                    continue;
                }
                let text = std::fs::read_to_string(&path).unwrap();
                let library_code = text.split("#[cfg(test)]").next().unwrap_or_default();
                for (number, line) in library_code.lines().enumerate() {
                    if !line.trim_start().starts_with("//") && forbidden.iter().any(|f| line.contains(f)) {
                        offenders.push(format!("{}:{}: {}", path.display(), number + 1, line.trim()));
                    }
                }
            }
        }
        assert!(offenders.is_empty(), "read input files through input_file::InputFiles:\n{}", offenders.join("\n"));
    }
}
