//! Hostile inputs. Every file a scene names is read only when it is a regular file within its
//! size cap (and, with `--confine`, inside the scene's folder or the shared data folder); glTF
//! accessors cannot claim more elements than the bytes behind them. The command-line tests run
//! the binary and expect exit status 1, within a time limit (a device or a FIFO read to the end
//! hangs), with the offending file named on stderr.

mod common;

use base64::Engine as _;
use caustica::scene::{load_asset, Scene};
use std::io::Read as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// What a run of the binary left: its exit code and stderr.
struct Run {
    code: Option<i32>,
    stderr: String,
}

/// Runs `caustica args` (through `sh -c` with `shell_prefix` first when given, e.g. a `ulimit`),
/// killing it and failing the test when it takes longer than a minute.
fn run_with(args: &[&str], env: &[(&str, &Path)], shell_prefix: Option<&str>) -> Run {
    let binary = env!("CARGO_BIN_EXE_caustica");
    let mut command = match shell_prefix {
        Some(prefix) => {
            let mut c = Command::new("sh");
            c.arg("-c").arg(format!("{prefix}; exec \"$0\" \"$@\"")).arg(binary).args(args);
            c
        }
        None => {
            let mut c = Command::new(binary);
            c.args(args);
            c
        }
    };
    if let Some(icd) = common::lavapipe_override() {
        command.env("VK_DRIVER_FILES", icd);
    }
    for (key, value) in env {
        command.env(key, value);
    }
    let mut child = command.stdout(Stdio::null()).stderr(Stdio::piped()).spawn().expect("run caustica");
    let mut stderr = child.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut text = String::new();
        stderr.read_to_string(&mut text).ok();
        text
    });
    let deadline = Instant::now() + Duration::from_secs(60);
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if Instant::now() > deadline {
            child.kill().ok();
            child.wait().ok();
            panic!("caustica {args:?} ran for more than a minute");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Run { code: status.code(), stderr: reader.join().unwrap() }
}

fn run(args: &[&str]) -> Run {
    run_with(args, &[], None)
}

/// `render SCENE` must fail with status 1 and name `needle` (and `problem`) on stderr.
fn assert_refused(scene: &Path, extra: &[&str], needles: &[&str]) {
    let out = scene.with_file_name("out.png");
    let mut args = vec!["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "-q"];
    args.extend(extra);
    let o = run(&args);
    assert_eq!(o.code, Some(1), "{args:?}: stderr {}", o.stderr);
    for needle in needles {
        assert!(o.stderr.contains(needle), "{args:?}: stderr does not contain '{needle}': {}", o.stderr);
    }
}

fn write(path: &Path, text: impl AsRef<[u8]>) -> PathBuf {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, text).unwrap();
    path.to_owned()
}

#[cfg(unix)]
fn link(target: &Path, link: &Path) -> PathBuf {
    std::os::unix::fs::symlink(target, link).unwrap();
    link.to_owned()
}

const CAMERA: &str = "[camera]\nposition = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\n";
const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n";

/// A scene placing `mesh` (a path as written in the scene), with `extra` appended.
fn scene_with_mesh(mesh: &str, extra: &str) -> String {
    format!("{CAMERA}[[meshes]]\nfile = \"{mesh}\"\n{extra}")
}

/// One triangle: three f32 positions then three u16 indices, padded to 4 bytes.
fn triangle_bin() -> Vec<u8> {
    let positions: [f32; 9] = [0., 0., 0., 1., 0., 0., 0., 1., 0.];
    let mut bytes: Vec<u8> = positions.iter().flat_map(|f| f.to_le_bytes()).collect();
    bytes.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    bytes.extend([0, 0]);
    bytes
}

fn data_uri(bytes: &[u8]) -> String {
    format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

fn png_bytes(width: u32, height: u32) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.write_header().unwrap().write_image_data(&vec![128; (width * height * 3) as usize]).unwrap();
    bytes
}

/// A glTF of one indexed triangle (accessor 0: POSITION, accessor 1: indices) whose buffer is at
/// `buffer_uri`; with `image_uri`, its material's base colour texture is that image.
fn triangle_gltf(buffer_uri: &str, image_uri: Option<&str>) -> String {
    let (material, extra) = match image_uri {
        Some(uri) => (
            r#", "material": 0"#.to_owned(),
            format!(
                r#", "materials": [{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}}}}}], "textures": [{{"source": 0}}], "images": [{{"uri": "{uri}"}}]"#
            ),
        ),
        None => (String::new(), String::new()),
    };
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
"meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1{material}}}]}}],
"buffers": [{{"uri": "{buffer_uri}", "byteLength": 44}}],
"bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}],
"accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
              {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}]{extra}}}"#
    )
}

#[cfg(unix)]
#[test]
fn dev_zero_and_directories_are_refused_as_every_kind_of_input() {
    let dir = common::temp_dir("hostile-zero");
    let zero = Path::new("/dev/zero");
    for name in [
        "zero.toml",
        "zero.obj",
        "zero.ply",
        "zero.gltf",
        "zero.glb",
        "zero.mtl",
        "zero.bin",
        "zero.png",
        "zero.pfm",
        "zero.exr",
    ] {
        link(zero, &dir.join(name));
    }
    std::fs::create_dir_all(dir.join("folder.obj")).unwrap();
    let bin = data_uri(&triangle_bin());
    let cases: Vec<(PathBuf, &str)> = vec![
        (zero.to_owned(), "/dev/zero"),
        (dir.join("zero.toml"), "zero.toml"),
        (dir.join("zero.obj"), "zero.obj"),
        (dir.join("zero.ply"), "zero.ply"),
        (dir.join("zero.gltf"), "zero.gltf"),
        (dir.join("zero.glb"), "zero.glb"),
        (write(&dir.join("mesh.toml"), scene_with_mesh("zero.obj", "")), "zero.obj"),
        (write(&dir.join("mtl.obj"), format!("mtllib zero.mtl\n{TRIANGLE_OBJ}")), "zero.mtl"),
        (write(&dir.join("texture.obj"), format!("mtllib texture.mtl\nusemtl t\n{TRIANGLE_OBJ}")), "zero.png"),
        (write(&dir.join("buffer.gltf"), triangle_gltf("zero.bin", None)), "zero.bin"),
        (write(&dir.join("image.gltf"), triangle_gltf(&bin, Some("zero.png"))), "zero.png"),
        (write(&dir.join("probe.toml"), format!("{CAMERA}[environment]\nprobe = \"zero.pfm\"\n")), "zero.pfm"),
        (write(&dir.join("latlong.toml"), format!("{CAMERA}[environment]\nlatlong = \"zero.exr\"\n")), "zero.exr"),
    ];
    write(&dir.join("texture.mtl"), "newmtl t\nmap_Kd zero.png\n");
    for (scene, file) in &cases {
        assert_refused(scene, &[], &[file, "not a regular file (a character device)"]);
    }
    assert_refused(&dir.join("folder.obj"), &[], &["folder.obj", "not a regular file (a directory)"]);
    // Partial renders (merge, and --resume, which reads them the same way).
    let out = dir.join("out.exr");
    let o = run(&["merge", dir.join("zero.exr").to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    assert!(o.stderr.contains("zero.exr") && o.stderr.contains("not a regular file"), "{}", o.stderr);
}

#[cfg(unix)]
#[test]
fn a_fifo_is_refused_without_waiting_for_a_writer() {
    let dir = common::temp_dir("hostile-fifo");
    for name in ["scene.toml", "pipe.obj"] {
        let status = Command::new("mkfifo").arg(dir.join(name)).status().expect("mkfifo");
        assert!(status.success());
    }
    assert_refused(&dir.join("scene.toml"), &[], &["scene.toml", "a FIFO"]);
    let scene = write(&dir.join("mesh.toml"), scene_with_mesh("pipe.obj", ""));
    assert_refused(&scene, &[], &["pipe.obj", "a FIFO"]);
}

#[test]
fn files_over_their_size_cap_are_refused_before_reading() {
    let dir = common::temp_dir("hostile-caps");
    // Sparse files: over the cap by their length, no disk used.
    let sparse = |name: &str, length: u64| {
        let path = dir.join(name);
        std::fs::File::create(&path).unwrap().set_len(length).unwrap();
        path
    };
    let scene = sparse("big.toml", (16 << 20) + 1);
    assert_refused(&scene, &[], &["big.toml", "over the 16 MiB limit for a scene file"]);
    let mesh = sparse("big.obj", (4 << 30) + 1);
    assert_refused(&mesh, &[], &["big.obj", "over the 4 GiB limit for a mesh file"]);
    sparse("big.mtl", (64 << 20) + 1);
    let obj = write(&dir.join("m.obj"), format!("mtllib big.mtl\n{TRIANGLE_OBJ}"));
    assert_refused(&obj, &[], &["big.mtl", "over the 64 MiB limit for an MTL material library"]);
    sparse("big.png", (1 << 30) + 1);
    write(&dir.join("t.mtl"), "newmtl t\nmap_Kd big.png\n");
    let obj = write(&dir.join("t.obj"), format!("mtllib t.mtl\nusemtl t\n{TRIANGLE_OBJ}"));
    assert_refused(&obj, &[], &["big.png", "over the 1 GiB limit for a texture"]);
}

/// The file that made caustica allocate 3 GB: 2^28 positions claimed through a sparse block
/// without a buffer view. Under a 1 GiB address-space limit it must fail at once, with a message.
#[cfg(unix)]
#[test]
fn a_sparse_accessor_claiming_2e28_positions_is_refused_in_bounded_memory() {
    let file =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions/gltf/sparse-position-count-2e28.gltf");
    let dir = common::temp_dir("hostile-sparse");
    let out = dir.join("out.png");
    let started = Instant::now();
    let o = run_with(&["render", file.to_str().unwrap(), "-o", out.to_str().unwrap()], &[], Some("ulimit -v 1048576"));
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    assert!(
        o.stderr.contains("sparse-position-count-2e28.gltf") && o.stderr.contains("accessor 0 has no buffer view"),
        "{}",
        o.stderr
    );
    assert!(started.elapsed() < Duration::from_secs(10), "took {:?}", started.elapsed());
}

/// Loads a glTF of one triangle primitive whose accessors and views are given, with a data-URI
/// buffer of `bin`; returns the error message.
fn gltf_error(tag: &str, bin: &[u8], views: &str, accessors: &str, primitive: &str) -> String {
    let json = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
"meshes": [{{"primitives": [{primitive}]}}], "buffers": [{{"uri": "{}", "byteLength": {}}}],
"bufferViews": {views}, "accessors": {accessors}}}"#,
        data_uri(bin),
        bin.len()
    );
    let dir = common::temp_dir(tag);
    let path = write(&dir.join("bad.gltf"), json);
    match load_asset(&path) {
        Ok(_) => panic!("{tag}: the glTF loaded"),
        Err(e) => {
            let message = e.to_string();
            assert!(message.contains(&path.display().to_string()), "{message}");
            message
        }
    }
}

#[test]
fn gltf_accessor_counts_are_bounded_by_the_bytes_behind_them() {
    let bin = triangle_bin();
    let views =
        r#"[{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}]"#;
    let position = |count: u64, sparse: &str| {
        format!(
            r#"{{"bufferView": 0, "componentType": 5126, "count": {count}, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]{sparse}}}"#
        )
    };
    let indices = r#"{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}"#;
    let primitive = r#"{"attributes": {"POSITION": 0}, "indices": 1}"#;

    let e = gltf_error("acc-count", &bin, views, &format!("[{}, {indices}]", position(1 << 28, "")), primitive);
    assert!(e.contains("accessor 0's 268435456 elements need 3 GiB but buffer view 0 holds 36 bytes"), "{e}");

    let e = gltf_error(
        "acc-indices",
        &bin,
        views,
        &format!("[{}, {}]", position(3, ""), indices.replace("\"count\": 3", "\"count\": 1000000")),
        primitive,
    );
    assert!(e.contains("accessor 1's 1000000 elements need") && e.contains("indices"), "{e}");

    let past =
        r#"[{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 600}]"#;
    let e = gltf_error("acc-view", &bin, past, &format!("[{}, {indices}]", position(3, "")), primitive);
    assert!(e.contains("buffer view 1 ends at byte 636 but buffer 0 holds 44 bytes"), "{e}");

    // Sparse blocks: the view 1 holds three u16 indices; view 0 three positions as values.
    let sparse = |count: u64| {
        format!(
            r#", "sparse": {{"count": {count}, "indices": {{"bufferView": 1, "componentType": 5123}}, "values": {{"bufferView": 0}}}}"#
        )
    };
    let no_view = |count: u64, sparse_count: u64| {
        position(count, &sparse(sparse_count)).replace(r#""bufferView": 0, "componentType""#, r#""componentType""#)
    };
    let e = gltf_error("acc-sparse-count", &bin, views, &format!("[{}, {indices}]", no_view(3, 4)), primitive);
    assert!(e.contains("replaces 4 sparse elements but has only 3"), "{e}");
    let e = gltf_error("acc-sparse-indices", &bin, views, &format!("[{}, {indices}]", no_view(10, 5)), primitive);
    assert!(e.contains("accessor 0's 5 sparse indices need 10 bytes but buffer view 1 holds 6 bytes"), "{e}");
    let e = gltf_error("acc-zeros", &bin, views, &format!("[{}, {indices}]", no_view(1 << 28, 3)), primitive);
    assert!(
        e.contains("accessor 0 has no buffer view: its 268435456 zero-initialised elements (3 GiB) are more data than"),
        "{e}"
    );
    // NORMAL and TEXCOORD_0 get the same checks as POSITION.
    let normal = no_view(1 << 28, 3).replace(r#", "min": [0, 0, 0], "max": [1, 1, 0]"#, "");
    let with_normal = r#"{"attributes": {"POSITION": 0, "NORMAL": 2}, "indices": 1}"#;
    let e = gltf_error("acc-normal", &bin, views, &format!("[{}, {indices}, {normal}]", position(3, "")), with_normal);
    assert!(e.contains("NORMAL accessor 2 has no buffer view"), "{e}");

    // A valid sparse accessor over zeros still loads.
    let json_ok = format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
"meshes": [{{"primitives": [{primitive}]}}], "buffers": [{{"uri": "{}", "byteLength": 44}}],
"bufferViews": {views}, "accessors": [{}, {indices}]}}"#,
        data_uri(&bin),
        no_view(3, 3)
    );
    let dir = common::temp_dir("acc-ok");
    let ok = write(&dir.join("ok.gltf"), json_ok);
    let asset = load_asset(&ok).unwrap();
    assert_eq!(asset.meshes[0].positions, [glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y]);
}

#[test]
fn one_accessor_reused_by_very_many_primitives_cannot_multiply_the_file() {
    // 10,000 positions (120 KB) read by 400 primitives: 48 MB decoded from a 150 KB file.
    let vertices = 10_000u64;
    let bin = vec![0u8; (vertices * 12) as usize];
    let primitives = vec![r#"{"attributes": {"POSITION": 0}}"#; 400].join(", ");
    let views = format!(r#"[{{"buffer": 0, "byteOffset": 0, "byteLength": {}}}]"#, bin.len());
    let accessors = format!(
        r#"[{{"bufferView": 0, "componentType": 5126, "count": {vertices}, "type": "VEC3", "min": [0, 0, 0], "max": [0, 0, 0]}}]"#
    );
    let e = gltf_error("acc-reuse", &bin, &views, &accessors, &primitives);
    assert!(e.contains("more than 64 times the") && e.contains("glTF and its buffers"), "{e}");
}

/// A glTF naming one 8 MiB file for 2,000 buffers, and one 4096 x 4096 PNG (64 MiB as RGBA8) for
/// 200 materials' textures: read and decoded once each, it loads in well under the 1 GiB
/// address-space limit (16 GB and 12.8 GB if each name were read or decoded again). It has no
/// meshes, so it fails after loading, with "no triangles to render".
#[cfg(unix)]
#[test]
fn one_file_named_many_times_in_a_gltf_is_read_and_decoded_once() {
    let dir = common::temp_dir("hostile-reuse");
    std::fs::File::create(dir.join("big.bin")).unwrap().set_len(8 << 20).unwrap();
    let mut png = Vec::new();
    let mut encoder = png::Encoder::new(&mut png, 4096, 4096);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.write_header().unwrap().write_image_data(&vec![200; 4096 * 4096]).unwrap();
    write(&dir.join("big.png"), png);
    let buffers = vec![format!(r#"{{"uri": "big.bin", "byteLength": {}}}"#, 8 << 20); 2000].join(", ");
    let materials = (0..200)
        .map(|i| format!(r#"{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": {i}}}}}}}"#))
        .collect::<Vec<_>>()
        .join(", ");
    let textures = (0..200).map(|i| format!(r#"{{"source": {i}}}"#)).collect::<Vec<_>>().join(", ");
    let images = vec![r#"{"uri": "big.png"}"#; 200].join(", ");
    let gltf = write(
        &dir.join("reuse.gltf"),
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "buffers": [{buffers}], "materials": [{materials}], "textures": [{textures}], "images": [{images}]}}"#
        ),
    );
    let out = dir.join("out.png");
    let started = Instant::now();
    let o = run_with(&["render", gltf.to_str().unwrap(), "-o", out.to_str().unwrap()], &[], Some("ulimit -v 1048576"));
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    assert!(o.stderr.contains("reuse.gltf: no triangles to render"), "{}", o.stderr);
    assert!(started.elapsed() < Duration::from_secs(20), "took {:?}", started.elapsed());
}

/// A scene folder with a mesh, its MTL and its texture in subfolders, and files outside it.
struct Confined {
    root: common::ScratchDir,
    scene_dir: PathBuf,
}

fn confined(tag: &str) -> Confined {
    let root = common::temp_dir(tag);
    let scene_dir = root.join("farm/job");
    write(&scene_dir.join("meshes/tri.obj"), format!("mtllib ../materials/tri.mtl\nusemtl t\n{TRIANGLE_OBJ}"));
    write(&scene_dir.join("materials/tri.mtl"), "newmtl t\nKd 0.5 0.5 0.5\nmap_Kd ../textures/t.png\n");
    write(&scene_dir.join("textures/t.png"), png_bytes(2, 2));
    write(&scene_dir.join("meshes/tri.bin"), triangle_bin());
    write(&scene_dir.join("meshes/tri.gltf"), triangle_gltf("tri.bin", Some("../textures/t.png")));
    // Outside the scene's folder.
    write(&root.join("secret/tri.obj"), TRIANGLE_OBJ);
    write(&root.join("secret/tri.mtl"), "newmtl t\nKd 1 0 0\n");
    write(&root.join("secret/tri.bin"), triangle_bin());
    write(&root.join("secret/t.png"), png_bytes(2, 2));
    Confined { root, scene_dir }
}

#[test]
fn confine_refuses_files_that_resolve_outside_the_scene_folder() {
    let c = confined("hostile-confine");
    let dir = &c.scene_dir;
    let cases: Vec<(PathBuf, &str)> = vec![
        (write(&dir.join("mesh.toml"), scene_with_mesh("../../secret/tri.obj", "")), "secret/tri.obj"),
        (write(&dir.join("mtllib.obj"), format!("mtllib ../../secret/tri.mtl\n{TRIANGLE_OBJ}")), "secret/tri.mtl"),
        (write(&dir.join("map.obj"), format!("mtllib map.mtl\nusemtl t\n{TRIANGLE_OBJ}")), "secret/t.png"),
        (write(&dir.join("buffer.gltf"), triangle_gltf("../../secret/tri.bin", None)), "secret/tri.bin"),
        (
            write(&dir.join("image.gltf"), triangle_gltf("meshes/tri.bin", Some("..%2F..%2Fsecret%2Ft.png"))),
            "secret/t.png",
        ),
        (
            write(&dir.join("absolute.toml"), scene_with_mesh(c.root.join("secret/tri.obj").to_str().unwrap(), "")),
            "secret/tri.obj",
        ),
        (write(&dir.join("passwd.gltf"), triangle_gltf("../../../../../../../../etc/passwd", None)), "/etc/passwd"),
    ];
    write(&dir.join("map.mtl"), "newmtl t\nmap_Kd ../../secret/t.png\n");
    for (scene, file) in &cases {
        assert_refused(scene, &["--confine"], &[file, "outside the folders that --confine allows"]);
        // Without --confine the same scene is read (the user's own files).
        if !file.starts_with('/') {
            let loaded = Scene::load(scene);
            assert!(loaded.is_ok(), "{}: {:#}", scene.display(), loaded.unwrap_err());
        }
    }
    #[cfg(unix)]
    {
        let linked = link(&c.root.join("secret/tri.obj"), &dir.join("meshes/link.obj"));
        let scene = write(&dir.join("link.toml"), scene_with_mesh("meshes/link.obj", ""));
        assert!(linked.exists());
        assert_refused(
            &scene,
            &["--confine"],
            &["meshes/link.obj", "secret/tri.obj", "outside the folders that --confine allows"],
        );
    }
}

#[test]
fn confine_allows_the_scene_folder_and_the_shared_data_folder() {
    let c = confined("hostile-confine-ok");
    let data = c.root.join("data");
    write(&data.join("shared.obj"), TRIANGLE_OBJ);
    let scene = write(
        &c.scene_dir.join("scene.toml"),
        format!(
            "{CAMERA}[[meshes]]\nfile = \"meshes/tri.obj\"\n[[meshes]]\nfile = \"meshes/tri.gltf\"\ntranslate = [1.0, 0.0, 0.0]\n[[meshes]]\nfile = \"$CAUSTICA_DATA/shared.obj\"\n[environment]\ncolor = [1.0, 1.0, 1.0]\n"
        ),
    );
    let out = c.scene_dir.join("out.pfm");
    let args = [
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--confine",
        "--width",
        "4",
        "--height",
        "4",
        "--spp",
        "1",
        "-q",
    ];
    let o = run_with(&args, &[("CAUSTICA_DATA", &data)], None);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(out.exists());
    // The data folder is allowed as $CAUSTICA_DATA, however it is named: once that points
    // elsewhere, the same folder is outside.
    let scene = write(&c.scene_dir.join("relative.toml"), scene_with_mesh("../../data/shared.obj", ""));
    let elsewhere = c.root.join("elsewhere");
    std::fs::create_dir_all(&elsewhere).unwrap();
    let args = ["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap(), "--confine", "-q"];
    let o = run_with(&args, &[("CAUSTICA_DATA", &elsewhere)], None);
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    assert!(
        o.stderr.contains("data/shared.obj") && o.stderr.contains("outside the folders that --confine allows"),
        "{}",
        o.stderr
    );
}

#[test]
fn a_long_toml_line_gives_a_short_message() {
    let dir = common::temp_dir("hostile-long-line");
    let scene = write(&dir.join("long.toml"), format!("{CAMERA}fov = \"{}\"\n", "x".repeat(1 << 20)));
    let out = dir.join("out.png");
    let o = run(&["render", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    assert!(o.stderr.contains("long.toml: line 4, column 7"), "{}", &o.stderr[..o.stderr.len().min(2000)]);
    assert!(o.stderr.len() < 2000, "{} bytes of stderr for one error", o.stderr.len());
}

/// A floor lit by a sun `diameter` degrees wide, low in the sky so that the disk is sampled.
fn floor_under_sun(diameter: &str) -> Scene {
    common::floor_point_scene(
        &format!(
            "[[lights]]\ntype = \"directional\"\ndirection = [0.3, -1.0, 0.2]\nirradiance = [2.0, 2.0, 2.0]\nangular_diameter = {diameter}"
        ),
        4,
        true,
    )
}

#[test]
fn a_sun_too_narrow_to_sample_renders_as_a_delta_light_without_dropping_samples() {
    let (_guard, ctx) = common::gpu();
    let render = |diameter: &str| {
        let scene = floor_under_sun(diameter);
        let mut renderer = caustica::render::Renderer::new(&ctx, &scene, 1).expect("scene uploads");
        renderer.render(scene.film.spp, |_| {}).expect("render");
        assert_eq!(renderer.nonfinite_samples, 0, "a sun {diameter} degrees wide dropped samples");
        renderer.image().expect("readback")
    };
    let delta = render("0");
    assert_eq!(render("1e-8").pixels, delta.pixels, "a disk of 1e-8 degrees is the delta light");
    let narrowest = render(&caustica::scene::MIN_DISK_DEGREES.to_string());
    let mean = |image: &caustica::image::RgbImage| {
        image.pixels.iter().map(|&p| common::luminance(p)).sum::<f64>() / image.pixels.len() as f64
    };
    let (narrow, delta) = (mean(&narrowest), mean(&delta));
    assert!(
        delta > 0.0 && (narrow / delta - 1.0).abs() < 1e-2,
        "the narrowest disk {narrow} against the delta light {delta}"
    );
}

/// A one-pixel partial render of samples `range` whose radiance sum is `value` in every channel.
fn part(range: std::ops::Range<u32>, value: f32) -> caustica::farm::PartialRender {
    let samples = range.end - range.start;
    caustica::farm::PartialRender {
        scene_hash: "ab12".into(),
        seed: 1,
        width: 1,
        height: 1,
        ranges: vec![range],
        accumulation: vec![[value, value, value, samples as f32]],
        aovs: Default::default(),
        aov_sums: None,
    }
}

#[test]
fn merge_and_resume_refuse_non_finite_or_negative_sums_and_sums_that_overflow() {
    let dir = common::temp_dir("hostile-sums");
    let (a, b, out) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("merged.exr"));
    part(0..2, 1.0).write(&a).unwrap();
    let merge = |b: &Path| run(&["merge", a.to_str().unwrap(), b.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    for value in [f32::NAN, f32::INFINITY, -1.0] {
        part(2..4, value).write(&b).unwrap();
        let o = merge(&b);
        assert_eq!(o.code, Some(1), "a sum of {value}: {}", o.stderr);
        assert!(o.stderr.contains(&b.display().to_string()) && o.stderr.contains("must be finite"), "{}", o.stderr);
        let scene = write(&dir.join("scene.toml"), CAMERA);
        let (scene, b_path, out_path) = (scene.to_str().unwrap(), b.to_str().unwrap(), out.to_str().unwrap());
        let resumed = run(&["render", scene, "--resume", "--checkpoint", b_path, "-o", out_path, "-q"]);
        assert_eq!(resumed.code, Some(1), "resuming a sum of {value}: {}", resumed.stderr);
        assert!(resumed.stderr.contains(&b.display().to_string()), "{}", resumed.stderr);
    }
    part(0..2, 3e38).write(&a).unwrap();
    part(2..4, 3e38).write(&b).unwrap();
    let o = merge(&b);
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    let both = format!("{}: its sums overflow when added to those of {}", b.display(), a.display());
    assert!(o.stderr.contains(&both), "{}", o.stderr);
    assert!(!out.exists(), "nothing is written");
}

#[test]
fn bench_suite_refuses_a_scenes_folder_that_does_not_exist() {
    let o = run(&["bench", "--suite", "--scenes", "/nonexistent/scenes"]);
    assert_eq!(o.code, Some(1), "{}", o.stderr);
    assert!(o.stderr.contains("--scenes /nonexistent/scenes: not a folder"), "{}", o.stderr);
}

/// A camera for Mitsuba scenes whose camera does not matter.
const MITSUBA_SENSOR: &str = r#"<sensor type="perspective"><float name="fov" value="45"/>
<film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>"#;

fn mitsuba(body: &str) -> String {
    format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")
}

/// The message importing the Mitsuba scene `text` gives, within `seconds`.
fn mitsuba_error_within(tag: &str, text: &str, seconds: u64) -> String {
    let started = Instant::now();
    let message = common::import_text_error(tag, "scene.xml", text);
    assert!(started.elapsed() < Duration::from_secs(seconds), "{tag} took {:?}", started.elapsed());
    message
}

#[test]
fn mitsuba_objects_nested_ten_thousand_deep_are_refused_naming_the_line() {
    let body = format!("{}{}", "<bsdf type=\"twosided\">\n".repeat(10_000), "</bsdf>".repeat(10_000));
    let message = mitsuba_error_within("hostile-nesting", &mitsuba(&body), 20);
    // The object at nesting 256 is on line 258 (the <scene> is line 1).
    assert!(message.contains("scene.xml:258: objects nest more than 256 deep"), "{message}");
}

#[test]
fn a_mitsuba_bsdf_containing_itself_is_refused() {
    for bsdfs in [
        r#"<bsdf type="mask" id="a"><ref id="a"/></bsdf>"#,
        r#"<bsdf type="normalmap" id="a"><ref id="a"/></bsdf>"#,
        r#"<bsdf type="mask" id="a"><bsdf type="twosided"><ref id="b"/></bsdf></bsdf>
<bsdf type="normalmap" id="b"><ref id="a"/></bsdf>"#,
    ] {
        let body = format!("{MITSUBA_SENSOR}\n{bsdfs}\n<shape type=\"sphere\"><ref id=\"a\"/></shape>");
        let message = mitsuba_error_within("hostile-self-bsdf", &mitsuba(&body), 20);
        assert!(message.contains("scene.xml:") && message.contains("contains itself"), "{bsdfs}: {message}");
    }
}

#[test]
fn mitsuba_substitution_cannot_make_more_text_than_a_scene_file_holds() {
    let value = "1".repeat(1 << 20);
    let many = "$v".repeat(20);
    let body =
        format!("<default name=\"v\" value=\"{value}\"/>\n{MITSUBA_SENSOR}\n<shape type=\"sphere\" id=\"{many}\"/>");
    let message = mitsuba_error_within("hostile-substitution", &mitsuba(&body), 20);
    assert!(message.contains("scene.xml:5: $name substitution makes more than 16 MiB of text"), "{message}");
}

#[test]
fn mitsuba_include_fan_out_is_bounded() {
    let includes = |name: &str| format!("<include filename=\"{name}\"/>\n").repeat(100);
    let files = common::write_files(
        "hostile-include-fan-out",
        &[
            ("scene.xml", &mitsuba(&includes("b.xml"))),
            ("b.xml", &mitsuba(&includes("c.xml"))),
            ("c.xml", &mitsuba(&includes("d.xml"))),
            ("d.xml", &mitsuba("")),
        ],
    );
    let started = Instant::now();
    let anywhere = caustica::input_file::InputFiles::anywhere();
    let error = caustica::scene::import::import(&anywhere, &files, &[]).err().expect("refused");
    assert!(started.elapsed() < Duration::from_secs(20), "took {:?}", started.elapsed());
    let message = format!("{error:#}");
    assert!(message.contains(".xml: the scene reads more than 4096 files through <include>s"), "{message}");
}

#[test]
fn mitsuba_import_is_linear_in_the_file_and_names_the_right_line() {
    let spheres = "<shape type=\"sphere\"><float name=\"radius\" value=\"1\"/></shape>\n".repeat(40_000);
    let body = format!("{MITSUBA_SENSOR}\n{spheres}<unknown/>");
    // Line 1 <scene>, lines 2-3 the sensor, 4 to 40,003 the spheres.
    let message = mitsuba_error_within("hostile-many-spheres", &mitsuba(&body), 20);
    assert!(message.contains("scene.xml:40004: <unknown> is not supported at the scene level"), "{message}");
}

#[test]
fn mitsuba_instances_of_a_shapegroup_are_bounded_in_shapes_before_any_is_made() {
    let spheres = "<shape type=\"sphere\"/>\n".repeat(2000);
    let instances = "<shape type=\"instance\"><ref id=\"g\"/></shape>\n".repeat(2001);
    let body = format!("{MITSUBA_SENSOR}\n<shape type=\"shapegroup\" id=\"g\">\n{spheres}</shape>\n{instances}");
    // Line 1 <scene>, 2-3 the sensor, 4 the group, 5-2004 its spheres, 2005 its end, then the
    // instances: the 2001st (line 4006) makes 4,002,000 shapes.
    let message = mitsuba_error_within("hostile-instances", &mitsuba(&body), 20);
    assert!(
        message.contains("scene.xml:4006: <shape type=\"instance\">: the scene places more than 4000000 shapes"),
        "{message}"
    );
}

const PBRT_OPTIONS: &str = "LookAt 0 1 4  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\n";

#[test]
fn a_pbrt_texture_referred_to_many_times_is_evaluated_once() {
    // Each mix refers to the one before twice: 2^30 evaluations of the first, read naively.
    let mut world = "Texture \"t0\" \"spectrum\" \"constant\" \"rgb value\" [0.5 0.5 0.5]\n".to_owned();
    for level in 1..=31 {
        let before = level - 1;
        world += &format!("Texture \"t{level}\" \"spectrum\" \"mix\" \"texture tex1\" \"t{before}\" \"texture tex2\" \"t{before}\" \"float amount\" 0.5\n");
    }
    world += "Material \"diffuse\" \"texture reflectance\" \"t31\"\nShape \"sphere\"\n";
    let started = Instant::now();
    let scene =
        common::import_text_scene("hostile-pbrt-mix", "scene.pbrt", &format!("{PBRT_OPTIONS}WorldBegin\n{world}"))
            .unwrap_or_else(|e| panic!("{e:#}"));
    assert!(started.elapsed() < Duration::from_secs(20), "took {:?}", started.elapsed());
    let albedo = scene.materials[scene.shapes[0].material() as usize].albedo;
    assert!(common::close(albedo, glam::Vec3::splat(0.5)), "{albedo}");
}

#[test]
fn pbrt_directives_of_very_many_parameters_are_read_in_linear_time() {
    let params: String = (0..200_000).map(|k| format!(" \"float p{k}\" 1")).collect();
    let text = format!("{PBRT_OPTIONS}WorldBegin\nShape \"sphere\"{params}\n");
    let started = Instant::now();
    let message = common::import_text_error("hostile-pbrt-params", "scene.pbrt", &text);
    assert!(started.elapsed() < Duration::from_secs(20), "took {:?}", started.elapsed());
    assert!(
        message.contains("scene.pbrt:5: 'float p0': Shape \"sphere\": the parameter 'p0' is not supported"),
        "{message}"
    );
}

#[test]
fn pbrt_includes_of_empty_files_are_bounded_in_number() {
    let includes = |name: &str| format!("Include \"{name}\"\n").repeat(100);
    let files = common::write_files(
        "hostile-pbrt-includes",
        &[
            ("scene.pbrt", &format!("{PBRT_OPTIONS}WorldBegin\n{}", includes("b.pbrt"))),
            ("b.pbrt", &includes("c.pbrt")),
            ("c.pbrt", &includes("empty.pbrt")),
            ("empty.pbrt", ""),
        ],
    );
    let started = Instant::now();
    let anywhere = caustica::input_file::InputFiles::anywhere();
    let error = caustica::scene::import::import(&anywhere, &files, &[]).err().expect("refused");
    assert!(started.elapsed() < Duration::from_secs(20), "took {:?}", started.elapsed());
    let message = format!("{error:#}");
    assert!(message.contains(".pbrt: the scene reads more than 4096 files through includes"), "{message}");
}

#[test]
fn an_output_name_of_255_bytes_is_written() {
    let dir = common::temp_dir("hostile-long-name");
    let out = dir.join(format!("{}.png", "x".repeat(251)));
    let o = run(&["render", "-o", out.to_str().unwrap(), "--width", "8", "--height", "8", "--spp", "1", "-q"]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
    assert!(out.is_file());
}

#[test]
fn importer_errors_quote_tokens_short_and_escape_control_characters() {
    let dir = common::temp_dir("hostile-long-token");
    let token = format!("{}\u{1b}c\u{8}", "9".repeat(1 << 20));
    let cases = [
        ("number.pbrt", format!("{PBRT_OPTIONS}WorldBegin\nShape \"sphere\" \"float radius\" [ {token} ]\n")),
        ("directive.pbrt", format!("{PBRT_OPTIONS}WorldBegin\n\u{7}{token}\n")),
        (
            "number.xml",
            mitsuba(&format!(
                "{MITSUBA_SENSOR}\n<shape type=\"sphere\"><float name=\"radius\" value=\"{}\"/></shape>",
                "9x".repeat(1 << 19)
            )),
        ),
    ];
    for (name, text) in cases {
        let scene = write(&dir.join(name), text);
        let o = run(&["render", scene.to_str().unwrap(), "-o", dir.join("out.png").to_str().unwrap(), "-q"]);
        assert_eq!(o.code, Some(1), "{name}");
        let shown = &o.stderr[..o.stderr.len().min(2000)];
        assert!(o.stderr.len() < 2000, "{name}: {} bytes of stderr: {shown}", o.stderr.len());
        assert!(o.stderr.contains(name) && o.stderr.contains("more characters)"), "{name}: {shown}");
        assert!(!o.stderr.contains(['\u{1b}', '\u{7}']), "{name}: raw control characters: {shown}");
    }
}
