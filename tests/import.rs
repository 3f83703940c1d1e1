//! Mitsuba 3 XML import (src/scene/import): each construct maps onto caustica's scene as
//! docs/importers.md documents, bad input is an error naming the file and line, `convert` writes TOML that
//! loads to the same scene, and an XML scene renders bit for bit like its hand-written TOML twin.

mod common;

use caustica::input_file::InputFiles;
use caustica::scene::import::{import, Imported};
use caustica::scene::{metal, AlphaMode, Conductor, Filter, Light, LightSelection, Microfacet, Sampler, Scene, Shape};
use common::{
    close, gpu, import_text, import_text_error, import_text_scene, render, temp_dir, write_files, WrittenFiles,
};
use glam::{Mat4, Vec3};
use std::path::Path;

/// A sensor block for scenes whose camera does not matter.
const SENSOR: &str = r#"<sensor type="perspective">
    <float name="fov" value="45"/>
    <transform name="to_world"><lookat origin="0, 1, 4" target="0, 1, 0" up="0, 1, 0"/></transform>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="24"/><rfilter type="box"/></film>
    <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
</sensor>"#;

/// Writes `files` (name, text) into a fresh folder; reads as the path of the first.
fn write_scene(tag: &str, files: &[(&str, &str)]) -> WrittenFiles {
    write_files(&format!("import-{tag}"), files)
}

fn xml(body: &str) -> String {
    format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")
}

fn imported(tag: &str, body: &str) -> anyhow::Result<Imported> {
    import_text(&format!("import-{tag}"), "scene.xml", &xml(body))
}

fn scene(tag: &str, body: &str) -> Scene {
    import_text_scene(&format!("import-{tag}"), "scene.xml", &xml(body)).unwrap_or_else(|e| panic!("{e:#}"))
}

fn error(tag: &str, body: &str) -> String {
    import_text_error(&format!("import-{tag}"), "scene.xml", &xml(body))
}

#[test]
fn the_camera_follows_lookat_fov_axis_and_the_thin_lens() {
    let sensor = |fov_axis: &str, width: u32, height: u32| {
        format!(
            r#"<sensor type="thinlens">
                <float name="fov" value="60"/><string name="fov_axis" value="{fov_axis}"/>
                <float name="aperture_radius" value="0.25"/><float name="focus_distance" value="3"/>
                <transform name="to_world"><lookat origin="1, 2, 3" target="1, 2, 0" up="0, 1, 0"/></transform>
                <film type="hdrfilm"><integer name="width" value="{width}"/><integer name="height" value="{height}"/></film>
            </sensor>"#
        )
    };
    let tan30 = 30f32.to_radians().tan();
    let vertical = |t: f32| 2.0 * t.atan().to_degrees();
    for (axis, w, h, expected) in [
        ("x", 32, 24, vertical(tan30 * 24.0 / 32.0)),
        ("y", 32, 24, 60.0),
        ("diagonal", 32, 24, vertical(tan30 * 24.0 / 40.0)),
        ("smaller", 32, 24, 60.0),
        ("smaller", 24, 32, vertical(tan30 * 32.0 / 24.0)),
        ("larger", 32, 24, vertical(tan30 * 24.0 / 32.0)),
    ] {
        let s = scene("camera", &sensor(axis, w, h));
        assert!((s.camera.fov_deg - expected).abs() < 1e-4, "{axis} {w}x{h}: {} against {expected}", s.camera.fov_deg);
        assert!(
            close(s.camera.position, Vec3::new(1.0, 2.0, 3.0))
                && close(s.camera.look_at, Vec3::new(1.0, 2.0, 2.0))
                && close(s.camera.up, Vec3::Y)
        );
        assert_eq!((s.camera.aperture, s.camera.focus_distance), (0.25, 3.0));
        // Mitsuba's default filter and sampler.
        assert_eq!(
            (s.film.width, s.film.height, s.film.filter, s.film.spp, s.integrator.sampler),
            (w, h, Filter::Gaussian, 4, Sampler::Independent)
        );
    }
}

#[test]
fn transforms_compose_in_document_order() {
    // Translate first, then rotate +90 degrees about y: the rectangle's centre (0, 0, 0) goes to
    // (1, 0, 0), then to (0, 0, -1); its normal +z to +x.
    let s = scene(
        "order",
        &format!(
            r#"{SENSOR}<shape type="rectangle"><transform name="to_world"><translate x="1"/><rotate y="1" angle="90"/></transform></shape>
               <shape type="rectangle"><transform name="to_world"><rotate y="1" angle="90"/><translate x="1"/></transform></shape>"#
        ),
    );
    let centre_and_normal = |shape: &Shape| match *shape {
        Shape::Quad { origin, u, v, .. } => (origin + 0.5 * (u + v), u.cross(v).normalize()),
        _ => panic!("a quad"),
    };
    let (c, n) = centre_and_normal(&s.shapes[0]);
    assert!(close(c, Vec3::new(0.0, 0.0, -1.0)) && close(n, Vec3::X), "{c} {n}");
    let (c, n) = centre_and_normal(&s.shapes[1]);
    assert!(close(c, Vec3::new(1.0, 0.0, 0.0)) && close(n, Vec3::X), "{c} {n}");
}

#[test]
fn flip_normals_and_mirrors_turn_the_front_side() {
    let s = scene(
        "flip",
        &format!(
            r#"{SENSOR}<shape type="rectangle"><boolean name="flip_normals" value="true"/></shape>
               <shape type="rectangle"><transform name="to_world"><scale z="-1"/></transform></shape>
               <shape type="disk"/>"#
        ),
    );
    let normal = |shape: &Shape| match *shape {
        Shape::Quad { u, v, .. } => u.cross(v).normalize(),
        Shape::Triangle { v, .. } => (v[1] - v[0]).cross(v[2] - v[0]).normalize(),
        _ => panic!("a quad or triangle"),
    };
    assert!(close(normal(&s.shapes[0]), -Vec3::Z));
    assert!(close(normal(&s.shapes[1]), -Vec3::Z));
    assert_eq!(s.shapes.len(), 2 + 64, "a disk is a 64-gon");
    assert!(s.shapes[2..].iter().all(|t| close(normal(t), Vec3::Z)));
}

#[test]
fn max_depth_is_the_longest_path_in_segments_and_rr_depth_where_roulette_starts() {
    let depth = |integrator: &str| {
        let s = scene("depth", &format!("{SENSOR}{integrator}"));
        (s.integrator.max_bounces, s.integrator.rr_start)
    };
    assert_eq!(
        depth(
            r#"<integrator type="path"><integer name="max_depth" value="3"/><integer name="rr_depth" value="2"/></integrator>"#
        ),
        (3, 2)
    );
    assert_eq!(depth(r#"<integrator type="path"><integer name="max_depth" value="-1"/></integrator>"#), (1024, 5));
    assert_eq!(depth(""), (1024, 5), "a scene without an integrator gets path's defaults");
    assert_eq!(
        scene("selection", SENSOR).integrator.light_selection,
        LightSelection::Bvh,
        "Mitsuba scenes get caustica's default, the light tree"
    );
    assert!(error(
        "depth0",
        &format!(r#"{SENSOR}<integrator type="path"><integer name="max_depth" value="0"/></integrator>"#)
    )
    .contains("max_depth 0"));
}

#[test]
fn bsdfs_map_onto_caustica_materials_with_named_metals_and_iors() {
    let i = imported(
        "bsdfs",
        &format!(
            r#"{SENSOR}
            <bsdf type="conductor" id="gold"><string name="material" value="Au"/></bsdf>
            <bsdf type="roughconductor" id="rough"><float name="alpha" value="0.04"/><string name="distribution" value="ggx"/></bsdf>
            <bsdf type="dielectric" id="water"><string name="int_ior" value="water"/></bsdf>
            <bsdf type="roughplastic" id="plastic"><rgb name="diffuse_reflectance" value="0.2, 0.4, 0.6"/><float name="int_ior" value="1.5"/><float name="ext_ior" value="1.0"/><string name="distribution" value="ggx"/></bsdf>
            <bsdf type="twosided" id="paper"><bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf></bsdf>
            <bsdf type="roughconductor" id="brushed"><float name="alpha" value="0.09"/></bsdf>
            <bsdf type="thindielectric" id="pane"><float name="int_ior" value="1.52"/></bsdf>
            <shape type="sphere"><ref id="brushed"/></shape>
            <shape type="sphere"><ref id="pane"/></shape>
            <shape type="sphere"><ref id="gold"/></shape>
            <shape type="sphere"><ref id="rough"/></shape>
            <shape type="sphere"><ref id="water"/></shape>
            <shape type="sphere"><ref id="plastic"/></shape>
            <shape type="sphere"><ref id="paper"/></shape>"#
        ),
    )
    .unwrap();
    let s = i.into_scene(&InputFiles::anywhere()).unwrap();
    let m = |name: &str| {
        s.materials.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no material {name}")).clone()
    };
    let (eta, k) = metal("gold").unwrap();
    assert_eq!(
        (m("gold").conductor, m("gold").reflectivity, m("gold").roughness),
        (Conductor::Complex { eta, k }, 1.0, 0.0)
    );
    assert!(
        (m("rough").roughness - 0.2).abs() < 1e-6
            && m("rough").conductor == Conductor::Mirror
            && m("rough").reflectivity == 1.0
    );
    assert!((m("water").ior - 1.3330 / 1.000277).abs() < 1e-6 && m("water").transparency == 1.0);
    let plastic = m("plastic");
    assert!(
        plastic.coat
            && plastic.ior == 1.5
            && (plastic.roughness - 0.1f32.sqrt()).abs() < 1e-6
            && close(plastic.albedo, Vec3::new(0.2, 0.4, 0.6))
    );
    assert!(close(m("paper").albedo, Vec3::splat(0.7)));
    // Mitsuba's default distribution is Beckmann, and caustica's kernel has it.
    assert_eq!(
        (m("brushed").microfacet, m("rough").microfacet, plastic.microfacet),
        (Microfacet::Beckmann, Microfacet::Ggx, Microfacet::Ggx)
    );
    assert!((m("brushed").roughness - 0.3).abs() < 1e-6);
    // Mitsuba's reflecting BSDFs are black from behind unless twosided; its dielectrics are not.
    let sides: Vec<bool> =
        ["gold", "rough", "plastic", "brushed", "paper", "water", "pane"].iter().map(|&n| m(n).one_sided).collect();
    assert_eq!(sides, [true, true, true, true, false, false, false]);
    let pane = m("pane");
    assert!(pane.thin && pane.transparency == 1.0 && (pane.ior - 1.52 / 1.000277).abs() < 1e-6, "{pane:?}");
}

#[test]
fn approximations_are_warnings_said_once_per_kind() {
    let i = imported(
        "warnings",
        &format!(
            r#"{SENSOR}
            <shape type="sphere"><bsdf type="roughconductor"/></shape>
            <shape type="sphere"><bsdf type="roughconductor"><float name="alpha" value="0.3"/></bsdf></shape>
            <shape type="sphere"><bsdf type="diffuse"><spectrum name="reflectance" value="400:0.5, 700:0.5"/></bsdf></shape>
            <shape type="sphere"><bsdf type="twosided"><bsdf type="diffuse"/></bsdf></shape>"#
        ),
    )
    .unwrap();
    let count = |needle: &str| i.warnings.iter().filter(|w| w.contains(needle)).count();
    assert_eq!(count("wavelengths"), 1, "{:?}", i.warnings);
    // One-sidedness is no approximation: the kernel has it.
    assert!(i.warnings.iter().all(|w| !w.contains("behind")), "{:?}", i.warnings);
}

#[test]
fn defaults_includes_refs_and_d_overrides() {
    let main = xml(&format!(
        r#"<default name="radius" value="2"/>
        <include filename="parts.xml"/>
        {SENSOR}
        <shape type="sphere"><float name="radius" value="$radius"/><ref id="later"/></shape>
        <bsdf type="diffuse" id="later"><rgb name="reflectance" value="0.25"/></bsdf>"#
    ));
    let parts = xml(
        r#"<emitter type="point"><point name="position" x="1" y="2" z="3"/><rgb name="intensity" value="5, 6, 7"/></emitter>"#,
    );
    let path = write_scene("defaults", &[("scene.xml", &main), ("parts.xml", &parts)]);
    let load = |defines: &[(String, String)]| {
        import(&InputFiles::anywhere(), &path, defines).unwrap().into_scene(&InputFiles::anywhere()).unwrap()
    };
    let s = load(&[]);
    assert!(matches!(s.shapes[0], Shape::Sphere { radius: 2.0, .. }));
    assert_eq!(s.materials[s.shapes[0].material() as usize].albedo, Vec3::splat(0.25));
    assert_eq!(
        s.lights,
        vec![Light::Point { position: Vec3::new(1.0, 2.0, 3.0), intensity: Vec3::new(5.0, 6.0, 7.0) }]
    );
    let s = load(&[("radius".into(), "0.5".into())]);
    assert!(matches!(s.shapes[0], Shape::Sphere { radius: 0.5, .. }), "-D wins over <default>");
}

#[test]
fn meshes_are_placed_by_their_to_world_and_shears_are_refused() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let body = |transform: &str| {
        xml(&format!(
            r#"{SENSOR}<shape type="obj"><string name="filename" value="tri.obj"/><transform name="to_world">{transform}</transform></shape>"#
        ))
    };
    let placed = body(r#"<scale value="2"/><rotate z="1" angle="90"/><translate x="1" y="2" z="3"/>"#);
    let path = write_scene("mesh", &[("scene.xml", &placed), ("tri.obj", obj)]);
    let s = import(&InputFiles::anywhere(), &path, &[]).unwrap().into_scene(&InputFiles::anywhere()).unwrap();
    let expected = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))
        * Mat4::from_rotation_z(90f32.to_radians())
        * Mat4::from_scale(Vec3::splat(2.0));
    assert!(s.instances[0].transform.abs_diff_eq(expected, 1e-5), "{:?}", s.instances[0].transform);
    let sheared = body(r#"<rotate z="1" angle="30"/><scale x="3"/>"#);
    let path = write_scene("shear", &[("scene.xml", &sheared), ("tri.obj", obj)]);
    let e = format!("{:#}", import(&InputFiles::anywhere(), &path, &[]).err().expect("a shear is refused"));
    assert!(e.contains("scene.xml:7: <shape type=\"obj\">") && e.contains("shear"), "{e}");
}

#[test]
fn shapegroup_instances_share_their_meshes() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let body = xml(&format!(
        r#"{SENSOR}
        <shape type="shapegroup" id="group">
            <shape type="obj"><string name="filename" value="tri.obj"/><transform name="to_world"><scale value="2"/></transform></shape>
            <shape type="sphere"><float name="radius" value="0.5"/></shape>
        </shape>
        <shape type="instance"><ref id="group"/><transform name="to_world"><translate x="1"/></transform></shape>
        <shape type="instance"><ref id="group"/><transform name="to_world"><translate x="-3"/></transform></shape>"#
    ));
    let path = write_scene("instances", &[("scene.xml", &body), ("tri.obj", obj)]);
    let s = import(&InputFiles::anywhere(), &path, &[]).unwrap().into_scene(&InputFiles::anywhere()).unwrap();
    assert_eq!((s.meshes.len(), s.instances.len()), (1, 2), "the mesh is stored once and placed twice");
    let placed = |k: usize| s.instances[k].transform;
    assert!(
        placed(0).abs_diff_eq(Mat4::from_translation(Vec3::X) * Mat4::from_scale(Vec3::splat(2.0)), 1e-6),
        "{:?}",
        placed(0)
    );
    assert!(placed(1).abs_diff_eq(Mat4::from_translation(-3.0 * Vec3::X) * Mat4::from_scale(Vec3::splat(2.0)), 1e-6));
    let centers: Vec<Vec3> = s
        .shapes
        .iter()
        .map(|sh| match *sh {
            Shape::Sphere { center, radius: 0.5, .. } => center,
            _ => panic!("a sphere of radius 0.5"),
        })
        .collect();
    assert_eq!(centers, vec![Vec3::X, -3.0 * Vec3::X]);
}

#[test]
fn unsupported_or_bad_input_is_an_error_naming_file_line_and_element() {
    for (body, needles) in [
        (format!("{SENSOR}\n<shape type=\"sphere\"><bsdf type=\"principled\"/></shape>"), vec!["scene.xml:8:", "<bsdf type=\"principled\">", "not supported"]),
        (format!("{SENSOR}\n<shape type=\"sphere\">\n<float name=\"radus\" value=\"1\"/></shape>"), vec!["scene.xml:9:", "'radus'", "not supported"]),
        (format!("{SENSOR}\n<shape type=\"sphere\"><ref id=\"nowhere\"/></shape>"), vec!["scene.xml:8:", "nowhere"]),
        (format!("{SENSOR}\n<shape type=\"sphere\"><float name=\"radius\" value=\"$r\"/></shape>"), vec!["scene.xml:8:", "$r"]),
        (format!("{SENSOR}\n<shape type=\"sphere\"><bsdf type=\"conductor\"><string name=\"material\" value=\"Cr\"/></bsdf></shape>"), vec!["scene.xml:8:", "'Cr'", "Au"]),
        (format!("{SENSOR}\n<shape type=\"serialized\"/>"), vec!["scene.xml:8:", "<shape type=\"serialized\">"]),
        (format!("{SENSOR}\n<shape type=\"sphere\"><bsdf type=\"diffuse\"><texture type=\"bitmap\" name=\"reflectance\"><string name=\"filename\" value=\"a.png\"/></texture></bsdf></shape>"), vec!["scene.xml:8:", "<shape type=\"sphere\">", "albedo_texture on this shape"]),
        (format!("{SENSOR}\n<shape type=\"sphere\"><bsdf type=\"diffuse\"><texture type=\"mesh_attribute\" name=\"reflectance\"/></bsdf></shape>"), vec!["scene.xml:8:", "<texture type=\"mesh_attribute\">", "not supported"]),
        (format!("{SENSOR}\n<shape type=\"sphere\"><bsdf type=\"plastic\"><texture type=\"checkerboard\" name=\"diffuse_reflectance\"/></bsdf></shape>"), vec!["scene.xml:8:", "textures ('diffuse_reflectance') are not supported"]),
        (format!("{SENSOR}\n<shape type=\"sphere\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"1.2, 0.5, 0.5\"/></bsdf></shape>"), vec!["scene.xml:8:", "reflectance must be in [0, 1]"]),
        (format!("{SENSOR}\n<emitter type=\"spot\"><float name=\"cutoff_angle\" value=\"10\"/><float name=\"beam_width\" value=\"20\"/></emitter>"), vec!["scene.xml:8:", "beam_width"]),
        (format!("{SENSOR}\n<integrator type=\"ptracer\"/>"), vec!["scene.xml:8:", "<integrator type=\"ptracer\">"]),
        (format!("{SENSOR}\n<shape type=\"sphere\"></shapee>"), vec!["scene.xml", "not well-formed"]),
        ("<shape type=\"sphere\"/>".to_owned(), vec!["scene.xml", "no <sensor>"]),
    ] {
        let e = error("bad", &body);
        for needle in needles {
            assert!(e.contains(needle), "'{needle}' missing from: {e}");
        }
    }
    // An include cycle ends with an error, not a hang.
    let path = write_scene(
        "cycle",
        &[("a.xml", &xml(r#"<include filename="b.xml"/>"#)), ("b.xml", &xml(r#"<include filename="a.xml"/>"#))],
    );
    let e = format!("{:#}", import(&InputFiles::anywhere(), &path, &[]).err().expect("a cycle is refused"));
    assert!(e.contains("nest more than"), "{e}");
}

/// The Mitsuba scene of the rendering tests: a lit floor, a box, a sphere and two lights.
fn lit_scene_xml(max_depth: i32) -> String {
    xml(&format!(
        r#"{SENSOR}
        <integrator type="path"><integer name="max_depth" value="{max_depth}"/></integrator>
        <bsdf type="twosided" id="white"><bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.7, 0.6"/></bsdf></bsdf>
        <shape type="rectangle"><transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform><ref id="white"/></shape>
        <shape type="cube"><transform name="to_world"><scale value="0.3"/><translate x="-0.8" y="0.3"/></transform><ref id="white"/></shape>
        <shape type="sphere"><point name="center" x="0.6" y="0.5" z="0"/><float name="radius" value="0.5"/>
            <bsdf type="dielectric"/></shape>
        <shape type="rectangle"><transform name="to_world"><scale value="0.5"/><rotate x="1" angle="90"/><translate y="2.5"/></transform>
            <ref id="white"/><emitter type="area"><rgb name="radiance" value="8"/></emitter></shape>
        <emitter type="point"><point name="position" x="1" y="2" z="1"/><rgb name="intensity" value="2"/></emitter>"#
    ))
}

#[test]
fn convert_writes_toml_that_loads_to_the_same_scene() {
    let path = write_scene("convert", &[("scene.xml", &lit_scene_xml(5))]);
    let i = import(&InputFiles::anywhere(), &path, &[]).unwrap();
    let folder = path.parent().unwrap();
    let toml = i.to_toml(folder).unwrap();
    let mut converted = Scene::parse(&toml, "converted", folder).unwrap_or_else(|e| panic!("{e:#}\n{toml}"));
    let mut direct = i.into_scene(&InputFiles::anywhere()).unwrap();
    (converted.name, direct.name) = (String::new(), String::new());
    assert_eq!(format!("{converted:?}"), format!("{direct:?}"));
    assert!(toml.contains("max_bounces = 5") && toml.contains("[materials.white]"), "{toml}");
}

/// The hand-written TOML twin of `lit_scene_xml(5)`: what docs/importers.md says each element becomes.
const LIT_SCENE_TOML: &str = r#"
[camera]
position = [0.0, 1.0, 4.0]
look_at = [0.0, 1.0, 3.0]
fov = 34.515877
[film]
width = 32
height = 24
spp = 4
filter = "box"
[integrator]
max_bounces = 5
rr_start = 5
sampler = "independent"
light_selection = "bvh"
[materials.white]
albedo = [0.8, 0.7, 0.6]
one_sided = true
[materials."white + emitter"]
albedo = [0.8, 0.7, 0.6]
emission = [8.0, 8.0, 8.0]
one_sided = true
[materials.glass]
transparency = 1.0
ior = 1.5041833
[[spheres]]
center = [0.6, 0.5, 0.0]
radius = 0.5
material = "glass"
[[lights]]
type = "point"
position = [1.0, 2.0, 1.0]
intensity = [2.0, 2.0, 2.0]
"#;

#[test]
fn an_xml_scene_renders_bit_for_bit_like_its_toml_twin() {
    let path = write_scene("twin", &[("scene.xml", &lit_scene_xml(5))]);
    let from_xml = import(&InputFiles::anywhere(), &path, &[]).unwrap().into_scene(&InputFiles::anywhere()).unwrap();
    // The quads come from the importer (their corners are transformed floats); everything else is
    // written by hand as docs/importers.md's mapping says.
    let mut twin = Scene::parse(LIT_SCENE_TOML, "twin.toml", Path::new(".")).unwrap();
    let material = |s: &Scene, k: usize| s.materials[s.shapes[k].material() as usize].clone();
    for (k, shape) in from_xml.shapes.iter().enumerate() {
        if let Shape::Quad { origin, u, v, .. } = *shape {
            let name = if material(&from_xml, k).is_emissive() { "white + emitter" } else { "white" };
            let m = twin.materials.iter().position(|m| m.name == name).unwrap() as u32;
            twin.shapes.insert(k, Shape::Quad { origin, u, v, material: m });
        }
    }
    assert_eq!(twin.shapes.len(), from_xml.shapes.len());
    for k in 0..twin.shapes.len() {
        let (a, b) = (material(&twin, k), material(&from_xml, k));
        assert_eq!(
            (a.albedo, a.emission, a.ior, a.transparency, a.reflectivity, a.coat, a.roughness),
            (b.albedo, b.emission, b.ior, b.transparency, b.reflectivity, b.coat, b.roughness),
            "shape {k}"
        );
    }
    assert!((twin.camera.fov_deg - from_xml.camera.fov_deg).abs() < 1e-5);
    twin.camera.fov_deg = from_xml.camera.fov_deg;
    let (_lock, ctx) = gpu();
    let (a, b) = (render(&ctx, &from_xml, 7), render(&ctx, &twin, 7));
    assert!(a.pixels.iter().any(|p| p[0] > 0.0), "the scene is lit");
    assert!(a.pixels == b.pixels, "the XML scene and its TOML twin differ");
}

#[test]
fn max_depth_one_shows_only_what_emits() {
    // Mitsuba's max_depth 1: the camera ray's own segment, so only the emitter seen directly;
    // 2 adds direct light. The floor is black at 1 and lit at 2.
    let path = write_scene("depth1", &[("scene.xml", &lit_scene_xml(1))]);
    let mut s = import(&InputFiles::anywhere(), &path, &[]).unwrap().into_scene(&InputFiles::anywhere()).unwrap();
    s.film.spp = 2;
    let (_lock, ctx) = gpu();
    let one = render(&ctx, &s, 1);
    s.integrator.max_bounces = 2;
    let two = render(&ctx, &s, 1);
    // The bottom row sees only the floor.
    let floor = |img: &caustica::image::RgbImage| (0..img.width).map(|x| img.get(x, img.height - 1)[0]).sum::<f32>();
    assert_eq!(floor(&one), 0.0, "max_depth 1 lights nothing");
    assert!(floor(&two) > 0.0, "max_depth 2 lights the floor");
}

#[test]
fn the_command_line_converts_and_fails_with_file_and_line() {
    let caustica =
        |args: &[&str]| std::process::Command::new(env!("CARGO_BIN_EXE_caustica")).args(args).output().unwrap();
    let sphere = "<default name=\"r\" value=\"1\"/>\n<shape type=\"sphere\"><float name=\"radius\" value=\"$r\"/><bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf></shape>";
    let path = write_scene("cli", &[("scene.xml", &xml(&format!("{SENSOR}\n{sphere}")))]);
    let out = path.with_file_name("scene.toml");
    let o = caustica(&["convert", path.to_str().unwrap(), "-o", out.to_str().unwrap(), "-D", "r=2.5"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = Scene::load(&out).unwrap();
    assert!(matches!(s.shapes[..], [Shape::Sphere { radius: 2.5, .. }]), "{:?}", s.shapes);
    let bad = write_scene(
        "cli-bad",
        &[(
            "scene.xml",
            &xml(&format!("{SENSOR}\n<shape type=\"sphere\"><float name=\"radius\" value=\"$nope\"/></shape>")),
        )],
    );
    for args in [
        vec!["render", bad.to_str().unwrap(), "-o", "/tmp/never.png"],
        vec!["convert", bad.to_str().unwrap(), "-o", "/tmp/never.toml"],
        vec!["render", "-D", "x"],
    ] {
        let o = caustica(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(stderr.contains("scene.xml:8:") || stderr.contains("NAME=VALUE"), "{args:?}: {stderr}");
    }
}

/// One mesh of a Mitsuba `.serialized` file as Mitsuba writes it (src/shapes/serialized.cpp):
/// the uncompressed header, then the zlib stream of flags, (version 4) name, counts, positions,
/// normals, texture coordinates and u32 indices, in f64 when `double`.
fn serialized_mesh(
    version: u16,
    positions: &[[f64; 3]],
    normals: Option<&[[f64; 3]]>,
    uvs: Option<&[[f64; 2]]>,
    triangles: &[[u32; 3]],
    double: bool,
) -> Vec<u8> {
    use std::io::Write;
    let mut raw = Vec::new();
    let flags = u32::from(normals.is_some()) | (2 * u32::from(uvs.is_some())) | if double { 0x2000 } else { 0x1000 };
    raw.extend(flags.to_le_bytes());
    if version == 4 {
        raw.extend(b"mesh\0");
    }
    raw.extend((positions.len() as u64).to_le_bytes());
    raw.extend((triangles.len() as u64).to_le_bytes());
    let mut floats = |values: &mut dyn Iterator<Item = f64>| {
        for v in values {
            if double {
                raw.extend(v.to_le_bytes());
            } else {
                raw.extend((v as f32).to_le_bytes());
            }
        }
    };
    floats(&mut positions.iter().flatten().copied());
    if let Some(n) = normals {
        floats(&mut n.iter().flatten().copied());
    }
    if let Some(uv) = uvs {
        floats(&mut uv.iter().flatten().copied());
    }
    raw.extend(triangles.iter().flatten().flat_map(|i| i.to_le_bytes()));
    let mut out = vec![0x1C, 0x04];
    out.extend(version.to_le_bytes());
    let mut z = flate2::write::ZlibEncoder::new(out, flate2::Compression::default());
    z.write_all(&raw).unwrap();
    z.finish().unwrap()
}

/// Meshes concatenated, then the dictionary of their offsets (u64 in version 4, u32 in 3) and
/// their count.
fn serialized_file(version: u16, meshes: &[Vec<u8>]) -> Vec<u8> {
    let mut file = Vec::new();
    let mut offsets = Vec::new();
    for m in meshes {
        offsets.push(file.len() as u64);
        file.extend(m);
    }
    for o in offsets {
        if version == 4 {
            file.extend(o.to_le_bytes());
        } else {
            file.extend((o as u32).to_le_bytes());
        }
    }
    file.extend((meshes.len() as u32).to_le_bytes());
    file
}

const QUAD: [[f64; 3]; 4] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
const QUAD_UVS: [[f64; 2]; 4] = [[0.0, 0.0], [0.25, 0.0], [0.25, 0.5], [0.0, 0.5]];
const QUAD_TRIANGLES: [[u32; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

fn serialized_quads(version: u16) -> Vec<u8> {
    let tilted: Vec<[f64; 3]> = QUAD.iter().map(|p| [p[0] + 0.125, p[1], p[2] + 0.5 * p[0]]).collect();
    let normals = [[0.0, 0.0, 1.0], [0.0, 0.0, 2.0], [0.0, 0.6, 0.8], [0.0, 0.0, 1.0]];
    serialized_file(
        version,
        &[
            serialized_mesh(version, &QUAD, None, None, &QUAD_TRIANGLES, false),
            serialized_mesh(version, &tilted, Some(&normals), Some(&QUAD_UVS), &QUAD_TRIANGLES, true),
        ],
    )
}

fn serialized_scene(tag: &str, file: &[u8], shape: &str) -> anyhow::Result<Scene> {
    let body = xml(&format!("{SENSOR}\n{shape}"));
    let path = write_scene(tag, &[("scene.xml", &body)]);
    std::fs::write(path.parent().unwrap().join("mesh.serialized"), file).unwrap();
    import(&InputFiles::anywhere(), &path, &[])?.into_scene(&InputFiles::anywhere())
}

#[test]
fn serialized_meshes_are_read_back_exactly_in_both_versions() {
    for version in [3, 4] {
        let file = serialized_quads(version);
        let shape = |index: u32| {
            format!(
                r#"<shape type="serialized"><string name="filename" value="mesh.serialized"/><integer name="shape_index" value="{index}"/></shape>"#
            )
        };
        let s = serialized_scene("serialized", &file, &shape(1)).unwrap_or_else(|e| panic!("{e:#}"));
        let mesh = &s.meshes[0];
        let expected: Vec<Vec3> =
            QUAD.iter().map(|p| Vec3::new(p[0] as f32 + 0.125, p[1] as f32, 0.5 * p[0] as f32)).collect();
        assert_eq!(mesh.positions, expected, "version {version}: the f64 positions of mesh 1");
        assert_eq!(mesh.triangles, QUAD_TRIANGLES.to_vec());
        // Texture coordinates as stored (Mitsuba's (0, 0) is the image's top-left, as caustica's).
        assert_eq!(mesh.uvs, QUAD_UVS.iter().map(|uv| glam::Vec2::new(uv[0] as f32, uv[1] as f32)).collect::<Vec<_>>());
        assert_eq!(mesh.normals, vec![Vec3::Z, Vec3::Z, Vec3::new(0.0, 0.6, 0.8), Vec3::Z], "unit normals as stored");
        // Mesh 0 (the default index) has no normals: Mitsuba's smooth ones, here the face's.
        let s = serialized_scene(
            "serialized-0",
            &file,
            r#"<shape type="serialized"><string name="filename" value="mesh.serialized"/></shape>"#,
        )
        .unwrap();
        assert_eq!(
            s.meshes[0].positions,
            QUAD.iter().map(|p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)).collect::<Vec<_>>()
        );
        assert_eq!(s.meshes[0].normals, vec![Vec3::Z; 4]);
        assert!(s.meshes[0].uvs.is_empty());
    }
}

#[test]
fn bad_serialized_files_are_errors_naming_the_file() {
    let good = serialized_quads(4);
    let shape = |index: i64| {
        format!(
            r#"<shape type="serialized"><string name="filename" value="mesh.serialized"/><integer name="shape_index" value="{index}"/></shape>"#
        )
    };
    let mut lying = serialized_mesh(4, &QUAD, None, None, &QUAD_TRIANGLES, false);
    // A header claiming 2^31 vertices over the same few compressed bytes: refused before any
    // allocation (the counts cannot fit in what the stream can inflate to).
    {
        use std::io::{Read, Write};
        let mut raw = Vec::new();
        flate2::read::ZlibDecoder::new(&lying[4..]).read_to_end(&mut raw).unwrap();
        raw[9..17].copy_from_slice(&(1u64 << 31).to_le_bytes());
        let mut z = flate2::write::ZlibEncoder::new(lying[..4].to_vec(), flate2::Compression::default());
        z.write_all(&raw).unwrap();
        lying = serialized_file(4, &[z.finish().unwrap()]);
    }
    let mut bad_index = serialized_mesh(4, &QUAD, None, None, &[[0, 1, 7]], false);
    bad_index = serialized_file(4, &[bad_index]);
    for (file, index, needles) in [
        (good.clone(), 2, vec!["mesh.serialized", "shape_index 2", "out of range", "2 meshes"]),
        (good.clone(), -1, vec!["scene.xml:8:", "shape_index must be >= 0"]),
        (
            serialized_mesh(4, &QUAD, None, None, &QUAD_TRIANGLES, false)[..40].to_vec(),
            0,
            vec!["mesh.serialized", "shape_index 0", "compressed data"],
        ),
        (good[..good.len() / 2].to_vec(), 1, vec!["mesh.serialized", "shape_index 1"]),
        (good[..3].to_vec(), 0, vec!["mesh.serialized", "truncated"]),
        (b"PK\x03\x04 not a mesh at all".to_vec(), 0, vec!["mesh.serialized", "not a Mitsuba serialized mesh"]),
        (lying, 0, vec!["mesh.serialized", "2147483648 vertices", "a corrupt file or a zlib bomb"]),
        (bad_index, 0, vec!["mesh.serialized", "triangle 0 uses vertex 7"]),
    ] {
        let e = format!("{:#}", serialized_scene("bad-serialized", &file, &shape(index)).expect_err("refused"));
        for needle in needles {
            assert!(e.contains(needle), "'{needle}' missing from: {e}");
        }
    }
    // shape_index is for serialized files only (TOML).
    let dir = temp_dir("shape-index-obj");
    std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let toml = "[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n[materials.m]\nalbedo = [0.5, 0.5, 0.5]\n[[meshes]]\nfile = \"tri.obj\"\nmaterial = \"m\"\nshape_index = 1\n";
    let e = format!("{:#}", Scene::parse(toml, "t.toml", &dir).expect_err("refused"));
    assert!(e.contains("tri.obj") && e.contains("shape_index"), "{e}");
}

#[test]
fn checkerboard_and_bitmap_reflectances_become_albedo_textures_read_through_to_uv() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n";
    let body = xml(&format!(
        r#"{SENSOR}
        <texture type="checkerboard" id="checks">
            <rgb name="color0" value="0.4"/><rgb name="color1" value="0.2"/>
            <transform name="to_uv"><scale x="8" y="4"/><translate x="0.5"/></transform>
        </texture>
        <shape type="obj"><string name="filename" value="tri.obj"/><bsdf type="diffuse"><ref name="reflectance" id="checks"/></bsdf></shape>
        <shape type="serialized"><string name="filename" value="mesh.serialized"/><integer name="shape_index" value="1"/>
            <bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="wood.png"/></texture></bsdf></shape>"#
    ));
    let path = write_scene("textures", &[("scene.xml", &body), ("tri.obj", obj)]);
    let dir = path.parent().unwrap();
    std::fs::write(dir.join("mesh.serialized"), serialized_quads(4)).unwrap();
    caustica::image::png::write(&dir.join("wood.png"), &caustica::image::RgbImage::new(3, 2), &Default::default())
        .unwrap();
    let i = import(&InputFiles::anywhere(), &path, &[]).unwrap();
    let s = i.into_scene(&InputFiles::anywhere()).unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(s.textures.len(), 2);
    let material = |mesh: usize| &s.materials[s.meshes[mesh].triangle_materials[0] as usize];
    let (checks, wood) = (material(0), material(1));
    assert_eq!((checks.albedo, wood.albedo), (Vec3::ONE, Vec3::ONE), "the texture is the whole colour");
    let checker = &s.textures[checks.albedo_texture.unwrap() as usize];
    let texel = |u: f32, v: f32| {
        checker.texels
            [(v * checker.height as f32) as usize * checker.width as usize + (u * checker.width as f32) as usize]
    };
    assert_eq!(
        (texel(0.1, 0.1), texel(0.6, 0.1)),
        ([102, 102, 102, 255], [51, 51, 51, 255]),
        "Mitsuba's colour 0 where u and v agree"
    );
    assert_eq!(&s.textures[wood.albedo_texture.unwrap() as usize].name, "wood.png");
    // to_uv maps the mesh's texture coordinates (OBJ's v turned upside down, as Mitsuba does):
    // (8 u + 0.5, 4 v).
    let uvs: Vec<(f32, f32)> = s.meshes[0].uvs.iter().map(|uv| (uv.x, uv.y)).collect();
    assert_eq!(uvs, vec![(0.5, 4.0), (8.5, 4.0), (0.5, 0.0)]);
    assert_eq!(s.meshes[1].uvs.len(), 4, "the bitmap's mesh keeps its own coordinates");

    // `convert` writes the textures, to_uv and shape_index out: the TOML, written elsewhere (so
    // with absolute paths), loads to the same meshes and textures.
    let out = temp_dir("textures-out");
    let toml = import(&InputFiles::anywhere(), &path, &[]).unwrap().to_toml(&out).unwrap();
    assert!(toml.contains("shape_index = 1") && toml.contains("to_uv") && toml.contains("checkerboard"), "{toml}");
    let t = Scene::parse(&toml, "converted.toml", &out).unwrap_or_else(|e| panic!("{e:#}\n{toml}"));
    assert_eq!(t.textures, s.textures);
    assert_eq!(
        (t.meshes[0].uvs.clone(), t.meshes[1].positions.clone()),
        (s.meshes[0].uvs.clone(), s.meshes[1].positions.clone())
    );
}

#[test]
fn textured_materials_need_meshes_with_texture_coordinates() {
    let dir = temp_dir("textured-toml");
    std::fs::write(dir.join("bare.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let material = "[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n[materials.checks]\nalbedo = [1, 1, 1]\nalbedo_texture = { checkerboard = [[0.4, 0.4, 0.4], [0.2, 0.2, 0.2]], to_uv = [[2, 0, 0], [0, 2, 0]] }\n";
    let refused = |extra: &str, needles: &[&str]| {
        let e = format!("{:#}", Scene::parse(&format!("{material}{extra}"), "t.toml", &dir).expect_err("refused"));
        for needle in needles {
            assert!(e.contains(needle), "'{needle}' missing from: {e}");
        }
    };
    refused(
        "[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"checks\"\n",
        &["materials.checks.albedo_texture", "texture coordinates"],
    );
    refused(
        "[[meshes]]\nfile = \"bare.obj\"\nmaterial = \"checks\"\n",
        &["bare.obj", "no texture coordinates", "checks"],
    );
    let both = "[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n[materials.m]\nalbedo_texture = { file = \"a.png\", checkerboard = [[0.4, 0.4, 0.4], [0.2, 0.2, 0.2]] }\n";
    let e = format!("{:#}", Scene::parse(both, "t.toml", &dir).expect_err("refused"));
    assert!(e.contains("materials.m.albedo_texture") && e.contains("one of file and checkerboard"), "{e}");
}

#[test]
fn an_envmap_turned_off_the_y_axis_is_resampled_to_its_axes() {
    // A lat-long map bright in its upper half, turned by Mitsuba's to_world so that its up (+y)
    // points down the world's -y: the world's lower half is then the bright one.
    let mut map = caustica::image::RgbImage::new(16, 8);
    for y in 0..4 {
        for x in 0..16 {
            map.set(x, y, [1.0; 3]);
        }
    }
    let body = xml(&format!(
        r#"{SENSOR}<emitter type="envmap"><string name="filename" value="sky.pfm"/><transform name="to_world"><rotate x="1" angle="180"/></transform></emitter>"#
    ));
    let path = write_scene("envmap-axes", &[("scene.xml", &body)]);
    caustica::image::pfm::write(&path.parent().unwrap().join("sky.pfm"), &map).unwrap();
    let s = import(&InputFiles::anywhere(), &path, &[])
        .unwrap()
        .into_scene(&InputFiles::anywhere())
        .unwrap_or_else(|e| panic!("{e:#}"));
    let caustica::scene::Environment::Map(m) = &s.environment else { panic!("a map") };
    for x in 0..16 {
        assert_eq!((m.image.get(x, 0), m.image.get(x, 7)), ([0.0; 3], [1.0; 3]), "column {x}");
    }
}

/// A square in z = 0 facing +z with vertex normals and a mirrored texture: u grows along -x, v
/// (in the file) along +y. MikkTSpace's bitangent follows v there, Mitsuba's cross(n, t) does not.
const SQUARE_OBJ: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nvt 1 0\nvt 0 0\nvt 0 1\nvt 1 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n";

/// Writes a 2 x 2 PNG of one 8-bit colour, byte for byte.
fn solid_png(path: &Path, rgb: [u8; 3]) {
    image::RgbImage::from_pixel(2, 2, image::Rgb(rgb)).save(path).unwrap();
}

/// The square under a normalmap and a mask, lit by a directional light, seen from above.
fn mapped_square_xml(opacity: &str) -> String {
    xml(&format!(
        r#"<sensor type="perspective">
            <float name="fov" value="20"/>
            <transform name="to_world"><lookat origin="0, 0, 3" target="0, 0, 0" up="0, 1, 0"/></transform>
            <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film>
            <sampler type="independent"><integer name="sample_count" value="4"/></sampler>
        </sensor>
        <integrator type="path"><integer name="max_depth" value="2"/></integrator>
        <emitter type="directional"><vector name="direction" x="0" y="-0.70710678" z="-0.70710678"/><rgb name="irradiance" value="2"/></emitter>
        <shape type="obj"><string name="filename" value="square.obj"/>
            <bsdf type="mask">{opacity}
                <bsdf type="normalmap">
                    <texture name="normalmap" type="bitmap"><string name="filename" value="tilt.png"/><boolean name="raw" value="true"/></texture>
                    <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
                </bsdf>
            </bsdf>
        </shape>"#
    ))
}

/// The tilted normal's texel: 30 degrees towards tangent-space +y.
const TILT_TEXEL: [u8; 3] = [128, 191, 238];

#[test]
fn normalmap_and_mask_map_onto_normal_and_opacity_textures_in_mitsubas_frame() {
    let path = write_scene(
        "normalmap",
        &[
            (
                "scene.xml",
                &mapped_square_xml(
                    r#"<texture name="opacity" type="bitmap"><string name="filename" value="holes.png"/></texture>"#,
                ),
            ),
            ("square.obj", SQUARE_OBJ),
        ],
    );
    let dir = path.parent().unwrap();
    solid_png(&dir.join("tilt.png"), TILT_TEXEL);
    solid_png(&dir.join("holes.png"), [200, 100, 50]);
    let s = scene_at(&path);
    let m = &s.materials[s.meshes[0].triangle_materials[0] as usize];
    let normal = m.maps.normal.expect("the normalmap is the material's normal map");
    assert!(!s.textures[normal.texture as usize].srgb, "raw: read as stored");
    let alpha = m.maps.alpha.expect("the mask is the material's opacity");
    assert_eq!(
        (alpha.factor, alpha.mode),
        (1.0, AlphaMode::Blend),
        "Mitsuba's mask is met with probability equal to its opacity"
    );
    // The opacity is the colour's luminance after sRGB decoding (Mitsuba's eval_1 of a bitmap).
    let decode = |b: u8| caustica::scene::srgb_to_linear(b);
    let luminance = 0.2126 * decode(200) + 0.7152 * decode(100) + 0.0722 * decode(50);
    assert_eq!(s.textures[alpha.texture.unwrap() as usize].texels[0][3], (luminance * 255.0).round() as u8);
    // Mitsuba's frame whichever way v grows: the tangent along -x (growing u) and the bitangent
    // cross(n, t) = -y, though v grows along +y (MikkTSpace's bitangent would follow it).
    assert!(
        s.meshes[0].tangents.iter().all(|t| (t.truncate() + Vec3::X).length() < 1e-5 && t.w == 1.0),
        "{:?}",
        s.meshes[0].tangents
    );

    // `convert` writes both textures out, and its TOML loads to the same scene.
    let out = temp_dir("normalmap-out");
    let toml = import(&InputFiles::anywhere(), &path, &[]).unwrap().to_toml(&out).unwrap();
    assert!(
        toml.contains("normal_texture") && toml.contains("opacity_texture") && toml.contains("encoding = \"linear\""),
        "{toml}"
    );
    let t = Scene::parse(&toml, "converted.toml", &out).unwrap_or_else(|e| panic!("{e:#}\n{toml}"));
    assert_eq!((&t.textures, &t.meshes[0].tangents), (&s.textures, &s.meshes[0].tangents));
    assert_eq!(t.materials[0].maps, m.maps);
}

/// A diffuse square whose normal map tilts every normal 30 degrees towards tangent-space +y, which
/// on SQUARE_OBJ is cross(n, t) = -y, lit along (0, -1, -1) / sqrt(2): each pixel is exactly
/// (albedo / pi) E n'.l, the light being a delta and the sky black. Read along +y (MikkTSpace's
/// bitangent, following v), n'.l rises from 0.259 to 0.965: a frame turned either way fails.
#[test]
fn a_normal_mapped_square_shades_with_the_bent_normal_mitsuba_would() {
    let path = write_scene(
        "normalmap-render",
        &[("scene.xml", &mapped_square_xml(r#"<float name="opacity" value="1"/>"#)), ("square.obj", SQUARE_OBJ)],
    );
    solid_png(&path.parent().unwrap().join("tilt.png"), TILT_TEXEL);
    let s = scene_at(&path);
    let texel = Vec3::from(TILT_TEXEL.map(|b| f32::from(b) / 255.0 * 2.0 - 1.0));
    let bent = Vec3::new(-texel.x, -texel.y, texel.z).normalize();
    let light = Vec3::new(0.0, 1.0, 1.0).normalize();
    let expected = 0.5 / std::f32::consts::PI * 2.0 * bent.dot(light);
    let (_lock, ctx) = gpu();
    let image = render(&ctx, &s, 3);
    for p in &image.pixels {
        assert!(
            (p[0] - expected).abs() < 2e-3 * expected,
            "pixel {p:?}, expected {expected} (with the bitangent along -y: {})",
            0.5 / std::f32::consts::PI * 2.0 * Vec3::new(bent.x, -bent.y, bent.z).dot(light)
        );
    }
}

#[test]
fn masks_and_normal_maps_need_meshes_and_one_texture_map() {
    let sphere = format!("{SENSOR}<shape type=\"sphere\"><bsdf type=\"mask\"><float name=\"opacity\" value=\"0.5\"/><bsdf type=\"diffuse\"/></bsdf></shape>");
    let e = error("mask-sphere", &sphere);
    assert!(e.contains("scene.xml:") && e.contains("opacity") && e.contains("<shape type=\"sphere\">"), "{e}");
    let dir = temp_dir("maps-toml");
    std::fs::write(dir.join("flat.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nf 1/1 2/2 3/3\n").unwrap();
    solid_png(&dir.join("n.png"), TILT_TEXEL);
    let head = "[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n";
    let refused = |toml: &str, needles: &[&str]| {
        let e = format!("{:#}", Scene::parse(&format!("{head}{toml}"), "t.toml", &dir).expect_err("refused"));
        for needle in needles {
            assert!(e.contains(needle), "'{needle}' missing from: {e}");
        }
    };
    refused(
        "[materials.m]\nnormal_texture = { file = \"n.png\" }\n[[meshes]]\nfile = \"flat.obj\"\nmaterial = \"m\"\n",
        &["flat.obj", "no vertex normals", "normal_texture"],
    );
    refused("[materials.m]\nopacity = 0.5\n[[quads]]\norigin = [0, 0, 0]\nedge_u = [1, 0, 0]\nedge_v = [0, 1, 0]\nmaterial = \"m\"\n", &["materials.m.opacity", "needs a mesh"]);
    refused("[materials.m]\nopacity = 1.5\n", &["materials.m.opacity", "[0, 1]"]);
    refused(
        "[materials.m]\nalbedo_texture = { file = \"n.png\", to_uv = [[2, 0, 0], [0, 2, 0]] }\nopacity_texture = { file = \"n.png\" }\n",
        &["materials.m.opacity_texture.to_uv differs from materials.m.albedo_texture.to_uv"],
    );
}

fn scene_at(path: &Path) -> Scene {
    import(&InputFiles::anywhere(), path, &[])
        .and_then(|i| i.into_scene(&InputFiles::anywhere()))
        .unwrap_or_else(|e| panic!("{e:#}"))
}

#[test]
fn flip_normals_and_face_normals_turn_and_flatten_meshes() {
    let shape = |params: &str| {
        format!(
            r#"<shape type="obj"><string name="filename" value="square.obj"/>{params}<bsdf type="diffuse"/></shape>"#
        )
    };
    let body = xml(&format!(
        "{SENSOR}{}{}{}",
        shape(""),
        shape(r#"<boolean name="flip_normals" value="true"/>"#),
        shape(r#"<boolean name="face_normals" value="true"/>"#)
    ));
    let path = write_scene("sides", &[("scene.xml", &body), ("square.obj", SQUARE_OBJ)]);
    let s = scene_at(&path);
    let [plain, flipped, flat] = [0, 1, 2].map(|k| &s.meshes[k]);
    assert_eq!(
        flipped.triangles,
        plain.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect::<Vec<_>>(),
        "the winding turns round"
    );
    assert_eq!(flipped.normals, plain.normals.iter().map(|n| -*n).collect::<Vec<_>>(), "and the normals with it");
    assert!(flat.normals.is_empty() && flat.triangles == plain.triangles, "face_normals drops the vertex normals");
    // One-sided (no twosided): the flipped square is black from the front, which the camera sees.
    assert!(s.materials[flipped.triangle_materials[0] as usize].one_sided);

    let out = temp_dir("sides-out");
    let toml = import(&InputFiles::anywhere(), &path, &[]).unwrap().to_toml(&out).unwrap();
    assert!(toml.contains("flip_normals = true") && toml.contains("face_normals = true"), "{toml}");
    let t = Scene::parse(&toml, "converted.toml", &out).unwrap_or_else(|e| panic!("{e:#}\n{toml}"));
    for k in 0..3 {
        assert_eq!(
            (&t.meshes[k].triangles, &t.meshes[k].normals),
            (&s.meshes[k].triangles, &s.meshes[k].normals),
            "mesh {k}"
        );
    }
}

/// alpha_u and alpha_v of roughconductor, roughdielectric and roughplastic become roughness
/// (along u) and roughness_v, each sqrt(alpha); equal ones are isotropic (no roughness_v), and an
/// alpha_v outside [0, 1] is an error naming it. Swapping the two, or dropping alpha_v, fails.
#[test]
fn alpha_u_and_alpha_v_map_onto_roughness_and_roughness_v() {
    let s = scene(
        "anisotropic",
        &format!(
            r#"{SENSOR}
            <bsdf type="roughconductor" id="brushed"><float name="alpha_u" value="0.04"/><float name="alpha_v" value="0.25"/><string name="distribution" value="ggx"/></bsdf>
            <bsdf type="roughdielectric" id="frosted"><float name="alpha_u" value="0.36"/><float name="alpha_v" value="0.01"/></bsdf>
            <bsdf type="roughplastic" id="satin"><float name="alpha_u" value="0.09"/><float name="alpha_v" value="0.16"/></bsdf>
            <bsdf type="roughconductor" id="even"><float name="alpha_u" value="0.09"/><float name="alpha_v" value="0.09"/></bsdf>
            <shape type="sphere"><ref id="brushed"/></shape>
            <shape type="sphere"><ref id="frosted"/></shape>
            <shape type="sphere"><ref id="satin"/></shape>
            <shape type="sphere"><ref id="even"/></shape>"#
        ),
    );
    let m = |name: &str| {
        s.materials.iter().find(|m| m.name == name).unwrap_or_else(|| panic!("no material {name}")).clone()
    };
    let near = |a: f32, b: f32| (a - b).abs() < 1e-6;
    for (name, u, v, distribution) in [
        ("brushed", 0.2, 0.5, Microfacet::Ggx),
        ("frosted", 0.6, 0.1, Microfacet::Beckmann),
        ("satin", 0.3, 0.4, Microfacet::Beckmann),
    ] {
        let material = m(name);
        assert!(
            near(material.roughness, u)
                && material.roughness_v.is_some_and(|r| near(r, v))
                && material.microfacet == distribution,
            "{name}: {material:?}"
        );
        assert!(material.is_anisotropic(), "{name}");
    }
    assert!(near(m("even").roughness, 0.3) && m("even").roughness_v.is_none() && !m("even").is_anisotropic());
    let e = error(
        "anisotropic-range",
        &format!(
            r#"{SENSOR}<bsdf type="roughconductor" id="b"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="1.5"/></bsdf><shape type="sphere"><ref id="b"/></shape>"#
        ),
    );
    assert!(e.contains("alpha_v must be in [0, 1], got 1.5"), "{e}");
}
