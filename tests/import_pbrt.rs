//! pbrt-v4 import (src/scene/import/pbrt): each construct maps onto caustica's scene as docs/importers.md
//! documents (the camera and its handedness, the order of transformations, maxdepth, named
//! materials, instancing, front sides), bad input is an error naming the file and line, `convert`
//! writes TOML that loads to the same scene, and a pbrt scene renders bit for bit like its
//! hand-written TOML twin.

mod common;

use caustica::input_file::InputFiles;
use caustica::scene::import::{import, Imported};
use caustica::scene::{AlphaMode, Conductor, Environment, Filter, Light, LightSelection, Sampler, Scene, Shape};
use common::{
    close, gpu, import_text, import_text_error, import_text_scene, render, temp_dir, write_files, WrittenFiles,
};
use glam::Vec3;
use std::path::Path;

/// Options for scenes whose camera does not matter: a 32 x 24 film looking down -z from z = 4.
const OPTIONS: &str = "LookAt 0 1 4  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\nFilm \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 24\nSampler \"independent\" \"integer pixelsamples\" 4\nPixelFilter \"box\"\n";

/// Writes `files` (name, text) into a fresh folder; reads as the path of the first.
fn write_scene(tag: &str, files: &[(&str, &str)]) -> WrittenFiles {
    write_files(&format!("pbrt-{tag}"), files)
}

fn imported(tag: &str, text: &str) -> anyhow::Result<Imported> {
    import_text(&format!("pbrt-{tag}"), "scene.pbrt", text)
}

/// The scene of `OPTIONS`, WorldBegin and `world`.
fn scene(tag: &str, world: &str) -> Scene {
    scene_of(tag, &format!("{OPTIONS}WorldBegin\n{world}\n"))
}

fn scene_of(tag: &str, text: &str) -> Scene {
    import_text_scene(&format!("pbrt-{tag}"), "scene.pbrt", text).unwrap_or_else(|e| panic!("{e:#}"))
}

fn error(tag: &str, text: &str) -> String {
    import_text_error(&format!("pbrt-{tag}"), "scene.pbrt", text)
}

/// Where a world point lies across caustica's image: > 0 right of the centre.
fn rightwards(s: &Scene, p: Vec3) -> f32 {
    let forward = s.camera.look_at - s.camera.position;
    (p - s.camera.position).dot(forward.cross(s.camera.up))
}

#[test]
fn the_image_right_is_pbrts_camera_x_so_the_world_is_read_through_a_mirror() {
    // Looking down +z with +y up, pbrt shows world +x on the right (its left-handed LookAt);
    // caustica's right-handed camera would show it on the left, so the world is mirrored in x.
    let s = scene_of("hand", "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\nTranslate 1 0 0\nShape \"sphere\" \"float radius\" 0.1\n");
    let Shape::Sphere { center, .. } = s.shapes[0] else { panic!("a sphere") };
    assert!(close(center, Vec3::new(-1.0, 0.0, 0.0)), "{center}");
    assert!(rightwards(&s, center) > 0.0, "world +x is right of the centre, as in pbrt");
    // A camera transformation that mirrors already (exporters write Scale -1 1 1) needs no mirror:
    // there world +x is on the left in pbrt, and stays unmirrored.
    let s = scene_of("hand-mirrored", "Scale -1 1 1\nLookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\nTranslate 1 0 0\nShape \"sphere\" \"float radius\" 0.1\n");
    let Shape::Sphere { center, .. } = s.shapes[0] else { panic!("a sphere") };
    assert!(close(center, Vec3::new(1.0, 0.0, 0.0)), "{center}");
    assert!(rightwards(&s, center) < 0.0);
}

#[test]
fn an_asymmetric_scene_renders_with_pbrts_left_and_right() {
    // A two-sided emitting patch at world x in [1, 2] before a camera looking down +z: pbrt puts it
    // on the right half of the image, and so must the import; with Scale -1 1 1 on the left.
    let patch = "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true\nShape \"bilinearmesh\" \"point3 P\" [1 -1 0  2 -1 0  1 1 0  2 1 0]\nAttributeEnd\n";
    let options = "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 8\nSampler \"independent\" \"integer pixelsamples\" 1\nPixelFilter \"box\"\n";
    let lit_columns = |prefix: &str, tag: &str| {
        let s = scene_of(tag, &format!("{prefix}LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n{options}WorldBegin\n{patch}"));
        let (_lock, ctx) = gpu();
        let image = render(&ctx, &s, 1);
        (0..image.width).filter(|&x| (0..image.height).any(|y| image.get(x, y)[0] > 0.5)).collect::<Vec<_>>()
    };
    let right = lit_columns("", "lr");
    assert!(
        !right.is_empty() && right.iter().all(|&x| x >= 8),
        "lit columns {right:?}: the patch must be on the right"
    );
    let left = lit_columns("Scale -1 1 1\n", "lr-mirrored");
    assert!(!left.is_empty() && left.iter().all(|&x| x < 8), "lit columns {left:?}: mirrored, on the left");
}

#[test]
fn fov_is_for_the_shorter_axis_and_the_lens_and_screenwindow_map() {
    let camera = |params: &str, w: u32, h: u32| -> anyhow::Result<Scene> {
        let text = format!("LookAt 1 2 3  1 2 0  0 1 0\nCamera \"perspective\" \"float fov\" 60 {params}\nFilm \"rgb\" \"integer xresolution\" {w} \"integer yresolution\" {h}\nWorldBegin\n");
        import_text_scene("pbrt-camera", "scene.pbrt", &text)
    };
    let tan30 = 30f32.to_radians().tan();
    let vertical = |t: f32| 2.0 * t.atan().to_degrees();
    for (params, w, h, expected) in [
        ("", 32, 24, 60.0),
        ("", 24, 32, vertical(tan30 * 32.0 / 24.0)),
        ("\"float screenwindow\" [-2 2 -1.5 1.5]", 32, 24, vertical(tan30 * 1.5)),
    ] {
        let s = camera(params, w, h).unwrap();
        assert!(
            (s.camera.fov_deg - expected).abs() < 1e-4,
            "{params} {w}x{h}: {} against {expected}",
            s.camera.fov_deg
        );
        assert!(
            close(s.camera.position, Vec3::new(-1.0, 2.0, 3.0))
                && close(s.camera.look_at, Vec3::new(-1.0, 2.0, 2.0))
                && close(s.camera.up, Vec3::Y)
        );
        assert_eq!((s.film.width, s.film.height, s.camera.aperture), (w, h, 0.0));
    }
    let s = camera("\"float lensradius\" 0.25 \"float focaldistance\" 3", 32, 24).unwrap();
    assert_eq!((s.camera.aperture, s.camera.focus_distance), (0.25, 3.0));
    // pbrt's defaults: 1280 x 720, 16 spp, its Gaussian filter, the Sobol family of samplers.
    let s = scene_of("defaults", "Camera \"perspective\"\nWorldBegin\n");
    assert_eq!(
        (s.film.width, s.film.height, s.film.spp, s.film.filter, s.integrator.sampler),
        (1280, 720, 16, Filter::Gaussian, Sampler::Sobol)
    );
    let e = camera("\"float screenwindow\" [-1 3 -1.5 1.5]", 32, 24).unwrap_err().to_string();
    assert!(e.contains("scene.pbrt:2: Camera \"perspective\"") && e.contains("screenwindow"), "{e}");
}

#[test]
fn transformations_apply_in_pbrts_order_and_blocks_restore_them() {
    // Each directive multiplies the current transformation on the right: the last one written
    // acts on the shape first. Rotate 90 about y sends +x to -z.
    let s = scene(
        "order",
        "AttributeBegin\nRotate 90 0 1 0\nTranslate 1 0 0\nShape \"sphere\"\nAttributeEnd\n\
         AttributeBegin\nTranslate 1 0 0\nRotate 90 0 1 0\nShape \"sphere\"\nAttributeEnd\n\
         TransformBegin\nConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  0 2 0 1]\nCoordinateSystem \"up2\"\nTransformEnd\n\
         Shape \"sphere\"\nCoordSysTransform \"up2\"\nTranslate 0 0 1\nShape \"sphere\"\n\
         Transform [2 0 0 0  0 2 0 0  0 0 2 0  3 0 0 1]\nShape \"sphere\"\n",
    );
    let centres: Vec<(Vec3, f32)> = s
        .shapes
        .iter()
        .map(|s| match *s {
            Shape::Sphere { center, radius, .. } => (center, radius),
            _ => panic!("spheres only"),
        })
        .collect();
    // In caustica's (mirrored) world x is negated.
    let expected = [
        (Vec3::new(0.0, 0.0, -1.0), 1.0),
        (Vec3::new(-1.0, 0.0, 0.0), 1.0),
        (Vec3::ZERO, 1.0),
        (Vec3::new(0.0, 2.0, 1.0), 1.0),
        (Vec3::new(-3.0, 0.0, 0.0), 2.0),
    ];
    for (k, ((c, r), (ec, er))) in centres.iter().zip(expected).enumerate() {
        assert!(close(*c, ec) && *r == er, "sphere {k}: {c} r {r}, expected {ec} r {er}");
    }
    assert_eq!(centres.len(), 5);
}

#[test]
fn include_shares_the_graphics_state_and_import_keeps_its_own() {
    let path = write_scene(
        "include",
        &[
            ("scene.pbrt", &format!("{OPTIONS}WorldBegin\nInclude \"sub.pbrt\"\nShape \"sphere\"\nAttributeBegin\nImport \"sub.pbrt\"\nShape \"sphere\"\nAttributeEnd\nImport \"sub.pbrt\"\nShape \"sphere\"\n")),
            ("sub.pbrt", "Translate 0 1 0\nMaterial \"diffuse\" \"rgb reflectance\" [0.2 0.2 0.2]\n"),
        ],
    );
    let s = import(&InputFiles::anywhere(), &path, &[]).unwrap().into_scene(&InputFiles::anywhere()).unwrap();
    let spheres: Vec<(Vec3, Vec3)> = s
        .shapes
        .iter()
        .map(|shape| match *shape {
            Shape::Sphere { center, material, .. } => (center, s.materials[material as usize].albedo),
            _ => panic!("spheres only"),
        })
        .collect();
    // Include: the translation and material carry on; Import: they stay inside the imported file.
    assert!(close(spheres[0].0, Vec3::Y) && close(spheres[0].1, Vec3::splat(0.2)), "{spheres:?}");
    assert!(close(spheres[1].0, Vec3::Y) && close(spheres[1].1, Vec3::splat(0.2)), "{spheres:?}");
    assert!(close(spheres[2].0, Vec3::Y) && close(spheres[2].1, Vec3::splat(0.2)), "{spheres:?}");
}

#[test]
fn maxdepth_zero_shows_only_what_emits_and_one_adds_direct_light() {
    // pbrt's maxdepth 0 is caustica's max_bounces 1: the floor under the lamp is black; 1 lights it.
    let floor = |depth: u32| {
        let text = LIT_SCENE.replace("\"integer maxdepth\" 4", &format!("\"integer maxdepth\" {depth}"));
        let mut s = scene_of(&format!("depth{depth}"), &text);
        assert_eq!(s.integrator.max_bounces, depth + 1);
        s.film.spp = 2;
        let (_lock, ctx) = gpu();
        let image = render(&ctx, &s, 1);
        (0..image.width).map(|x| image.get(x, image.height - 1)[0]).sum::<f32>()
    };
    assert_eq!(floor(0), 0.0, "maxdepth 0 lights nothing");
    assert!(floor(1) > 0.0, "maxdepth 1 lights the floor");
}

#[test]
fn maxdepth_counts_bounces_one_less_than_caustica_segments() {
    let integrator = |text: &str| {
        let s = scene_of("depth", &format!("Camera \"perspective\"\n{text}\nWorldBegin\n"));
        (s.integrator.max_bounces, s.integrator.rr_start, s.integrator.light_selection)
    };
    assert_eq!(integrator("Integrator \"path\" \"integer maxdepth\" 0"), (1, 1, LightSelection::Bvh));
    assert_eq!(
        integrator("Integrator \"volpath\" \"integer maxdepth\" 3 \"string lightsampler\" \"uniform\""),
        (4, 1, LightSelection::Uniform)
    );
    assert_eq!(integrator(""), (6, 1, LightSelection::Bvh), "pbrt's default maxdepth is 5, its lightsampler bvh");
    assert_eq!(integrator("Integrator \"path\" \"string lightsampler\" \"power\"").2, LightSelection::Power);
    assert_eq!(integrator("Integrator \"path\" \"integer maxdepth\" -1").0, 1024);
    assert!(error("bdpt", "Camera \"perspective\"\nIntegrator \"bdpt\"\nWorldBegin\n")
        .contains("scene.pbrt:2: Integrator \"bdpt\""));
}

#[test]
fn materials_map_with_named_spectra_roughness_and_constant_textures() {
    let s = scene(
        "materials",
        "NamedMaterial \"later\"\nShape \"sphere\"\n\
         MakeNamedMaterial \"later\" \"string type\" \"diffuse\" \"rgb reflectance\" [0.1 0.2 0.3]\n\
         Material \"conductor\" \"spectrum eta\" \"metal-Au-eta\" \"spectrum k\" \"metal-Au-k\" \"float roughness\" 0.01\nShape \"sphere\"\n\
         Material \"conductor\" \"rgb reflectance\" [0.5 0.5 0.5] \"float roughness\" 0.01 \"bool remaproughness\" false\nShape \"sphere\"\n\
         Material \"dielectric\" \"spectrum eta\" \"glass-BK7\"\nShape \"sphere\"\n\
         Texture \"half\" \"spectrum\" \"constant\" \"rgb value\" [0.5 0.5 0.5]\n\
         Texture \"quarter\" \"spectrum\" \"scale\" \"texture tex\" \"half\" \"float scale\" 0.5\n\
         Texture \"mixed\" \"spectrum\" \"mix\" \"texture tex1\" \"half\" \"texture tex2\" \"quarter\" \"float amount\" 0.5\n\
         Material \"coateddiffuse\" \"texture reflectance\" \"mixed\" \"float eta\" 1.4\nShape \"sphere\"\n\
         Material \"conductor\"\nShape \"sphere\"\n",
    );
    let m = |k: usize| s.materials[s.shapes[k].material() as usize].clone();
    assert!(close(m(0).albedo, Vec3::new(0.1, 0.2, 0.3)), "a named material defined after its use");
    let gold = caustica::scene::metal("gold").unwrap();
    assert_eq!(m(1).conductor, Conductor::Complex { eta: gold.0, k: gold.1 });
    // remapped: alpha = sqrt(0.01) = 0.1, caustica's roughness sqrt(alpha); not remapped: alpha 0.01.
    assert!((m(1).roughness - 0.1f32.sqrt()).abs() < 1e-6 && (m(2).roughness - 0.1).abs() < 1e-6);
    // reflectance 0.5: eta 1 and the k whose normal-incidence reflectance is 0.5.
    let Conductor::Complex { eta, k } = m(2).conductor else { panic!("a complex conductor") };
    assert!(close(eta, Vec3::ONE) && ((k.x * k.x) / (4.0 + k.x * k.x) - 0.5).abs() < 1e-5);
    assert_eq!((m(3).transparency, m(3).ior), (1.0, 1.5168));
    assert!(m(4).coat && m(4).coat_internal_reflections && close(m(4).albedo, Vec3::splat(0.375)) && m(4).ior == 1.4);
    let copper = caustica::scene::metal("copper").unwrap();
    assert_eq!(m(5).conductor, Conductor::Complex { eta: copper.0, k: copper.1 }, "pbrt's default conductor is copper");
    let warnings = imported("warn", &format!("{OPTIONS}WorldBegin\nMaterial \"dielectric\" \"spectrum eta\" \"glass-F11\"\nShape \"sphere\"\nMaterial \"coateddiffuse\"\nShape \"sphere\"\n")).unwrap().warnings;
    assert!(warnings.iter().any(|w| w.contains("scene.pbrt:7:") && w.contains("587.6 nm")), "{warnings:?}");
    assert!(warnings.iter().any(|w| w.contains("coateddiffuse")), "{warnings:?}");
    // An image where caustica's materials take a constant is an error naming the line.
    let e = error("imagemap", &format!("{OPTIONS}WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\"\nMaterial \"conductor\" \"texture reflectance\" \"t\"\nShape \"sphere\"\n"));
    assert!(e.contains("scene.pbrt:8: 'texture reflectance': the texture varies over the surface"), "{e}");
    let s = scene("thin", "Material \"thindielectric\" \"float eta\" 1.33\nShape \"sphere\"");
    assert!(
        s.materials[0].thin && s.materials[0].transparency == 1.0 && s.materials[0].ior == 1.33,
        "{:?}",
        s.materials[0]
    );
}

#[test]
fn fronts_follow_the_winding_reverse_orientation_and_normals_through_the_mirror() {
    let s = scene(
        "fronts",
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n\
         Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0]\n\
         ReverseOrientation\nShape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0]\n\
         Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0] \"normal N\" [0 0 1  0 0 1  0 0 1]\n\
         Shape \"bilinearmesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0  1 1 0]\n\
         AttributeEnd\n",
    );
    let normal = |shape: &Shape| match *shape {
        Shape::Quad { u, v, .. } => u.cross(v).normalize(),
        Shape::Triangle { v, .. } => (v[1] - v[0]).cross(v[2] - v[0]).normalize(),
        _ => panic!("a quad or triangle"),
    };
    // caustica lists quads before triangles: the patch comes first.
    assert!(matches!(s.shapes[0], Shape::Quad { .. }), "a parallelogram patch is a quad");
    let fronts: Vec<Vec3> = s.shapes.iter().map(normal).collect();
    // Object +z, mirrored in x, is still +z; ReverseOrientation turns it, unless normals decide.
    assert!(
        close(fronts[1], Vec3::Z)
            && close(fronts[2], -Vec3::Z)
            && close(fronts[3], Vec3::Z)
            && close(fronts[0], -Vec3::Z),
        "{fronts:?}"
    );
}

/// A two-triangle square in ASCII PLY.
const SQUARE_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";

#[test]
fn object_instances_share_meshes_and_copy_other_shapes() {
    let path = write_scene(
        "instances",
        &[
            (
                "scene.pbrt",
                &format!(
                    "{OPTIONS}WorldBegin\nObjectBegin \"thing\"\nShape \"plymesh\" \"string filename\" \"square.ply\"\nTranslate 0 0 1\nShape \"sphere\" \"float radius\" 0.5\nObjectEnd\n\
                     ObjectInstance \"thing\"\nTranslate 2 0 0\nObjectInstance \"thing\"\n\
                     AttributeBegin\nAreaLightSource \"diffuse\"\nShape \"plymesh\" \"string filename\" \"square.ply\"\nAttributeEnd\n"
                ),
            ),
            ("square.ply", SQUARE_PLY),
        ],
    );
    let s = import(&InputFiles::anywhere(), &path, &[]).unwrap().into_scene(&InputFiles::anywhere()).unwrap();
    assert_eq!((s.meshes.len(), s.instances.len()), (1, 2), "one mesh placed twice");
    assert!(close(s.instances[1].transform.transform_point3(Vec3::X), Vec3::new(-3.0, 0.0, 0.0)));
    let spheres: Vec<Vec3> = s
        .shapes
        .iter()
        .filter_map(|s| if let Shape::Sphere { center, .. } = *s { Some(center) } else { None })
        .collect();
    assert!(
        spheres.len() == 2
            && close(spheres[0], Vec3::new(0.0, 0.0, 1.0))
            && close(spheres[1], Vec3::new(-2.0, 0.0, 1.0)),
        "{spheres:?}"
    );
    // The emitting mesh is written out as triangles facing as pbrt has them (+z).
    let triangles: Vec<&Shape> = s.shapes.iter().filter(|s| matches!(s, Shape::Triangle { .. })).collect();
    assert_eq!(triangles.len(), 2);
    for t in triangles {
        let Shape::Triangle { v, material } = *t else { unreachable!() };
        assert!(
            close((v[1] - v[0]).cross(v[2] - v[0]).normalize(), Vec3::Z)
                && s.materials[material as usize].is_emissive()
        );
    }
    let e = error("no-object", &format!("{OPTIONS}WorldBegin\nObjectInstance \"nothing\"\n"));
    assert!(e.contains("scene.pbrt:7: ObjectInstance \"nothing\""), "{e}");
}

#[test]
fn lights_map_to_caustica_lights_in_the_mirrored_world() {
    let s = scene(
        "lights",
        "LightSource \"point\" \"point3 from\" [1 2 3] \"rgb I\" [1 2 3] \"float scale\" 2\n\
         LightSource \"spot\" \"point3 from\" [1 0 0] \"point3 to\" [1 -1 0] \"float coneangle\" 30 \"float conedeltaangle\" 10\n\
         LightSource \"distant\" \"point3 from\" [1 1 0] \"point3 to\" [0 0 0] \"blackbody L\" [6500]\n\
         LightSource \"infinite\" \"rgb L\" [0.1 0.2 0.3]\n",
    );
    match s.lights[0] {
        Light::Point { position, intensity } => {
            assert!(close(position, Vec3::new(-1.0, 2.0, 3.0)) && close(intensity, Vec3::new(2.0, 4.0, 6.0)))
        }
        ref other => panic!("{other:?}"),
    }
    match s.lights[1] {
        Light::Spot { position, axis, cone_angle, falloff_start, .. } => {
            assert!(close(position, Vec3::new(-1.0, 0.0, 0.0)) && close(axis, -Vec3::Y));
            assert!(
                (cone_angle - 30f32.to_radians()).abs() < 1e-6 && (falloff_start - 20f32.to_radians()).abs() < 1e-6
            );
        }
        ref other => panic!("{other:?}"),
    }
    match s.lights[2] {
        Light::Directional { direction, irradiance, .. } => {
            assert!(close(direction, Vec3::new(1.0, -1.0, 0.0).normalize()), "{direction}");
            assert!(
                (0.2126 * irradiance.x + 0.7152 * irradiance.y + 0.0722 * irradiance.z - 1.0).abs() < 1e-3,
                "a black body has unit luminance: {irradiance}"
            );
        }
        ref other => panic!("{other:?}"),
    }
    assert!(matches!(s.environment, Environment::Constant(c) if close(c, Vec3::new(0.1, 0.2, 0.3))));
}

#[test]
fn an_equal_area_environment_map_is_resampled_to_lat_long_with_its_rotation() {
    // Bright where the map's z > 0 (the diamond |u| + |v| < 1 in the middle of the square); pbrt
    // scenes turn the map's z up with Rotate -90 1 0 0, so the sky is bright and the ground dark.
    let mut sky = caustica::image::RgbImage::new(32, 32);
    for y in 0..32 {
        for x in 0..32 {
            let (u, v) = ((x as f32 + 0.5) / 16.0 - 1.0, (y as f32 + 0.5) / 16.0 - 1.0);
            sky.set(x, y, if u.abs() + v.abs() < 1.0 { [1.0; 3] } else { [0.0; 3] });
        }
    }
    let dir = temp_dir("pbrt-envmap");
    caustica::image::pfm::write(&dir.join("sky.pfm"), &sky).unwrap();
    let path = dir.join("scene.pbrt");
    std::fs::write(&path, format!("{OPTIONS}WorldBegin\nAttributeBegin\nRotate -90 1 0 0\nLightSource \"infinite\" \"string filename\" \"sky.pfm\" \"float scale\" 2\nAttributeEnd\n")).unwrap();
    let s = import(&InputFiles::anywhere(), &path, &[]).unwrap().into_scene(&InputFiles::anywhere()).unwrap();
    let Environment::Map(map) = &s.environment else { panic!("an environment map") };
    assert_eq!(
        (map.projection, map.intensity, map.image.width, map.image.height),
        (caustica::scene::MapProjection::LatLong, 2.0, 64, 32)
    );
    for y in [0, 5, 10] {
        assert!(
            (0..64).all(|x| map.image.get(x, y)[0] == 1.0 && map.image.get(x, 31 - y)[0] == 0.0),
            "row {y} bright, row {} dark",
            31 - y
        );
    }
    // Not square: an error naming the file.
    caustica::image::pfm::write(&dir.join("sky.pfm"), &caustica::image::RgbImage::new(8, 4)).unwrap();
    let e = format!(
        "{:#}",
        import(&InputFiles::anywhere(), &path, &[]).and_then(|i| i.into_scene(&InputFiles::anywhere())).err().unwrap()
    );
    assert!(e.contains("sky.pfm") && e.contains("must be square"), "{e}");
}

#[test]
fn bad_input_is_an_error_naming_file_and_line_never_a_panic() {
    let cases: [(&str, &str, &str); 11] = [
        ("Shape \"sphere\" \"float radius\" [1]\nShape \"sph", "scene.pbrt:8: unterminated string", "unterminated"),
        ("Frobnicate 1 2 3", "scene.pbrt:7: unknown directive 'Frobnicate'", "unknown directive"),
        ("Include \"missing.pbrt\"", "scene.pbrt:7: in the Include of", "missing include"),
        (
            "Shape \"sphere\" \"string radius\" \"1\"",
            "scene.pbrt:7: 'string radius': Shape \"sphere\": 'radius' is a float",
            "wrong type",
        ),
        (
            "Shape \"sphere\" \"float radius\" \"one\"",
            "scene.pbrt:7: 'float radius': the values are not numbers",
            "string for a float",
        ),
        (
            "Shape \"sphere\"\n  \"float radiuss\" 1",
            "scene.pbrt:8: 'float radiuss': Shape \"sphere\": the parameter 'radiuss' is not supported",
            "unknown parameter",
        ),
        ("Shape \"disk\"", "scene.pbrt:7: Shape \"disk\": this shape is not supported", "unknown shape"),
        ("AttributeEnd", "scene.pbrt:7: AttributeEnd without AttributeBegin", "unbalanced"),
        ("AttributeBegin\nShape \"sphere\"", "scene.pbrt:7: this AttributeBegin is never ended", "unended"),
        (
            "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 3]",
            "scene.pbrt:7: Shape \"trianglemesh\": index 3 is not one of the 3 vertices",
            "bad index",
        ),
        (
            "Shape \"sphere\" \"float radius\" [1",
            "scene.pbrt:7: \"float radius\": the file ends before the list's ']'",
            "open list",
        ),
    ];
    for (world, expected, what) in cases {
        let e = error("bad", &format!("{OPTIONS}WorldBegin\n{world}\n"));
        assert!(e.contains(expected), "{what}: {e}");
    }
    let looped = write_scene(
        "loop",
        &[
            ("scene.pbrt", &format!("{OPTIONS}WorldBegin\nInclude \"loop.pbrt\"\n")),
            ("loop.pbrt", "Include \"loop.pbrt\"\n"),
        ],
    );
    let e = format!("{:#}", import(&InputFiles::anywhere(), &looped, &[]).err().expect("an include cycle is refused"));
    assert!(e.contains("loop.pbrt:1: Include \"loop.pbrt\": includes nest more than 16 deep"), "{e}");
    let e = error("no-world", "Camera \"perspective\"\n");
    assert!(e.contains("no WorldBegin"), "{e}");
    let e = error("late-camera", "WorldBegin\nCamera \"perspective\"\n");
    assert!(e.contains("scene.pbrt:2: Camera must come before WorldBegin"), "{e}");
}

/// A lit scene with a parallelogram floor, a glass sphere, an emitting patch and a point light.
const LIT_SCENE: &str = "LookAt 0 1 4  0 1 0  0 1 0
Camera \"perspective\" \"float fov\" 45
Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 24
Sampler \"independent\" \"integer pixelsamples\" 4
PixelFilter \"box\"
Integrator \"path\" \"integer maxdepth\" 4
WorldBegin
MakeNamedMaterial \"white\" \"string type\" \"diffuse\" \"rgb reflectance\" [0.8 0.7 0.6]
MakeNamedMaterial \"glass\" \"string type\" \"dielectric\"
NamedMaterial \"white\"
Shape \"bilinearmesh\" \"point3 P\" [-3 0 -3  -3 0 3  3 0 -3  3 0 3]
AttributeBegin
  AreaLightSource \"diffuse\" \"rgb L\" [8 8 8]
  Shape \"bilinearmesh\" \"point3 P\" [-0.5 2.5 -0.5  0.5 2.5 -0.5  -0.5 2.5 0.5  0.5 2.5 0.5]
AttributeEnd
AttributeBegin
  NamedMaterial \"glass\"
  Translate 0.6 0.5 0
  Shape \"sphere\" \"float radius\" 0.5
AttributeEnd
LightSource \"point\" \"point3 from\" [1 2 1] \"rgb I\" [2 2 2]
";

/// The hand-written TOML twin of `LIT_SCENE`: what docs/importers.md says each directive becomes, x
/// negated by the mirror (and the patches' edges swapped, which keeps their fronts).
const LIT_SCENE_TOML: &str = r#"
[camera]
position = [0.0, 1.0, 4.0]
look_at = [0.0, 1.0, 3.0]
fov = 45.0
[film]
width = 32
height = 24
spp = 4
filter = "box"
[integrator]
max_bounces = 5
rr_start = 1
sampler = "independent"
[materials.white]
albedo = [0.8, 0.7, 0.6]
[materials."white + area light at scene.pbrt:13"]
albedo = [0.8, 0.7, 0.6]
emission = [8.0, 8.0, 8.0]
[materials.glass]
transparency = 1.0
ior = 1.5
[[spheres]]
center = [-0.6, 0.5, 0.0]
radius = 0.5
material = "glass"
[[quads]]
origin = [3.0, 0.0, -3.0]
edge_u = [-6.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 6.0]
material = "white"
[[quads]]
origin = [0.5, 2.5, -0.5]
edge_u = [0.0, 0.0, 1.0]
edge_v = [-1.0, 0.0, 0.0]
material = "white + area light at scene.pbrt:13"
[[lights]]
type = "point"
position = [-1.0, 2.0, 1.0]
intensity = [2.0, 2.0, 2.0]
"#;

#[test]
fn a_pbrt_scene_renders_bit_for_bit_like_its_toml_twin() {
    let path = write_scene("twin", &[("scene.pbrt", LIT_SCENE)]);
    let from_pbrt = import(&InputFiles::anywhere(), &path, &[]).unwrap().into_scene(&InputFiles::anywhere()).unwrap();
    let mut twin = Scene::parse(LIT_SCENE_TOML, "twin.toml", Path::new(".")).unwrap();
    // The camera goes through pbrt's look-at matrix and its inverse: equal up to rounding.
    let (c, t) = (&from_pbrt.camera, &twin.camera);
    assert!(
        close(c.position, t.position)
            && close(c.look_at, t.look_at)
            && close(c.up, t.up)
            && (c.fov_deg - t.fov_deg).abs() < 1e-5,
        "{c:?} against {t:?}"
    );
    twin.camera = from_pbrt.camera.clone();
    // Everything but the names is the same scene.
    let (mut a, mut b) = (from_pbrt.clone(), twin.clone());
    (a.name, b.name) = (String::new(), String::new());
    assert_eq!(format!("{:?}", a.shapes), format!("{:?}", b.shapes));
    let (_lock, ctx) = gpu();
    let (x, y) = (render(&ctx, &from_pbrt, 7), render(&ctx, &twin, 7));
    assert!(x.pixels.iter().any(|p| p[0] > 0.0), "the scene is lit");
    assert!(x.pixels == y.pixels, "the pbrt scene and its TOML twin differ");
}

#[test]
fn convert_writes_toml_that_loads_to_the_same_scene_and_the_cli_fails_with_file_and_line() {
    let path = write_scene("convert", &[("scene.pbrt", LIT_SCENE)]);
    let i = import(&InputFiles::anywhere(), &path, &[]).unwrap();
    let folder = path.parent().unwrap();
    let toml = i.to_toml(folder).unwrap();
    let mut converted = Scene::parse(&toml, "converted", folder).unwrap_or_else(|e| panic!("{e:#}\n{toml}"));
    let mut direct = i.into_scene(&InputFiles::anywhere()).unwrap();
    (converted.name, direct.name) = (String::new(), String::new());
    assert_eq!(format!("{converted:?}"), format!("{direct:?}"));

    let caustica =
        |args: &[&str]| std::process::Command::new(env!("CARGO_BIN_EXE_caustica")).args(args).output().unwrap();
    let out = path.with_file_name("scene.toml");
    let o = caustica(&["convert", path.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(Scene::load(&out).is_ok());
    let bad = write_scene(
        "cli-bad",
        &[("scene.pbrt", &format!("{OPTIONS}WorldBegin\nShape \"sphere\" \"float radius\" -1\n"))],
    );
    for args in [
        vec!["render", bad.to_str().unwrap(), "-o", "/tmp/never.png"],
        vec!["convert", bad.to_str().unwrap(), "-o", "/tmp/never.toml"],
        vec!["render", path.to_str().unwrap(), "-D", "x=1", "-o", "/tmp/never.png"],
    ] {
        let o = caustica(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(
            stderr.contains("scene.pbrt:7: Shape \"sphere\": radius must be > 0") || stderr.contains("-D x=..."),
            "{args:?}: {stderr}"
        );
    }
}

#[test]
fn scenes_cornell_pbrt_is_the_cornell_box_of_scenes_cornell_toml() {
    // The pbrt file is the TOML box mirrored in x, as pbrt shows it; caustica reads it back.
    let (pbrt, toml) = (
        Scene::load(Path::new("scenes/cornell.pbrt")).unwrap(),
        Scene::load(Path::new("scenes/cornell.toml")).unwrap(),
    );
    assert_eq!(format!("{:?}", pbrt.shapes), format!("{:?}", toml.shapes), "the same walls, light and spheres");
    let (c, t) = (&pbrt.camera, &toml.camera);
    assert!(
        close(c.position, t.position)
            && close(c.look_at - c.position, (t.look_at - t.position).normalize())
            && close(c.up, t.up)
            && (c.fov_deg - t.fov_deg).abs() < 1e-4
    );
    assert_eq!(
        (pbrt.film.width, pbrt.film.height, pbrt.film.spp, pbrt.film.filter),
        (toml.film.width, toml.film.height, toml.film.spp, toml.film.filter)
    );
    for (a, b) in pbrt.materials.iter().zip(&toml.materials) {
        assert!(a.name.starts_with(&b.name), "{} against {}", a.name, b.name);
        assert_eq!((a.emission, a.transparency, a.ior), (b.emission, b.transparency, b.ior), "{}", b.name);
        if a.transparency == 0.0 && a.reflectivity == 0.0 {
            assert_eq!(a.albedo, b.albedo, "{}", b.name);
        }
    }
}

/// A PLY square of four vertices with pbrt texture coordinates (0.1, 0.1), (0.3, 0.1), (0.1, 0.3)
/// and (0.3, 0.3).
const UV_SQUARE_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float u\nproperty float v\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0.1 0.1\n1 0 0 0.3 0.1\n0 1 0 0.1 0.3\n1 1 0 0.3 0.3\n3 0 1 3\n3 0 3 2\n";

#[test]
fn image_and_checkerboard_reflectances_become_albedo_textures_as_pbrt_reads_them() {
    let world = "Texture \"wood\" \"spectrum\" \"imagemap\" \"string filename\" \"wood.png\" \"float uscale\" 2 \"float vdelta\" 0.25 \"float scale\" 0.5\n\
                 Texture \"half\" \"spectrum\" \"scale\" \"texture tex\" \"wood\" \"float scale\" 0.5\n\
                 Material \"diffuse\" \"texture reflectance\" \"half\"\n\
                 Shape \"plymesh\" \"string filename\" \"square.ply\"\n\
                 Texture \"checks\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [0.4 0.4 0.4] \"rgb tex2\" [0.2 0.2 0.2] \"float uscale\" 4\n\
                 Material \"coateddiffuse\" \"texture reflectance\" \"checks\"\n\
                 Shape \"plymesh\" \"string filename\" \"square.ply\"\n";
    let path = write_scene(
        "textures",
        &[("scene.pbrt", &format!("{OPTIONS}WorldBegin\n{world}")), ("square.ply", UV_SQUARE_PLY)],
    );
    let dir = path.parent().unwrap();
    caustica::image::png::write(&dir.join("wood.png"), &caustica::image::RgbImage::new(3, 2), &Default::default())
        .unwrap();
    let s = import(&InputFiles::anywhere(), &path, &[])
        .unwrap()
        .into_scene(&InputFiles::anywhere())
        .unwrap_or_else(|e| panic!("{e:#}"));
    let material = |mesh: usize| &s.materials[s.meshes[mesh].triangle_materials[0] as usize];
    let (wood, checks) = (material(0), material(1));
    assert_eq!(
        (wood.albedo, checks.albedo),
        (Vec3::splat(0.25), Vec3::ONE),
        "the image's scale and the scale texture's multiply it"
    );
    assert!(checks.coat);
    assert_eq!(&s.textures[wood.albedo_texture.unwrap() as usize].name, "wood.png");
    // pbrt reads the image at (s, 1 - t) = (2 u, 1 - (v + 0.25)) from its top-left corner.
    let uv = |mesh: usize| -> Vec<(f32, f32)> { s.meshes[mesh].uvs.iter().map(|uv| (uv.x, uv.y)).collect() };
    let expected = [(0.1f32, 0.1f32), (0.3, 0.1), (0.1, 0.3), (0.3, 0.3)].map(|(u, v)| (2.0 * u, 1.0 - (v + 0.25)));
    assert!(
        uv(0).iter().zip(expected).all(|(a, b)| (a.0 - b.0).abs() < 1e-6 && (a.1 - b.1).abs() < 1e-6),
        "{:?} against {expected:?}",
        uv(0)
    );
    // pbrt's checkerboard: tex1 where floor(4 u) + floor(v) is even, so at the vertices of u = 0.1
    // (4 u = 0.4), tex2 at those of u = 0.3 (4 u = 1.2).
    let checker = &s.textures[checks.albedo_texture.unwrap() as usize];
    let texel = |(u, v): (f32, f32)| {
        let (x, y) = (u.rem_euclid(1.0) * checker.width as f32, v.rem_euclid(1.0) * checker.height as f32);
        checker.texels[y as usize * checker.width as usize + x as usize]
    };
    let colours: Vec<_> = uv(1).into_iter().map(texel).collect();
    assert_eq!(colours, vec![[102, 102, 102, 255], [51, 51, 51, 255], [102, 102, 102, 255], [51, 51, 51, 255]]);

    // The hand-written TOML twin: the same materials, textures and mapped coordinates (the
    // placement, which the mirror decides, is another test's).
    let twin = "[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n\
                [materials.wood]\nalbedo = [0.25, 0.25, 0.25]\nalbedo_texture = { file = \"wood.png\", to_uv = [[2, 0, 0], [0, 1, -0.25]] }\n\
                [materials.checks]\nalbedo = [1, 1, 1]\ncoat = true\ncoat_internal_reflections = true\nalbedo_texture = { checkerboard = [[0.4, 0.4, 0.4], [0.2, 0.2, 0.2]], to_uv = [[2, 0, 0], [0, -0.5, 0.5]] }\n\
                [[meshes]]\nfile = \"square.ply\"\nmaterial = \"wood\"\n\
                [[meshes]]\nfile = \"square.ply\"\nmaterial = \"checks\"\n";
    let t = Scene::parse(twin, "twin.toml", dir).unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(t.textures, s.textures);
    assert_eq!(
        format!("{:?}", t.meshes.iter().map(|m| &m.uvs).collect::<Vec<_>>()),
        format!("{:?}", s.meshes.iter().map(|m| &m.uvs).collect::<Vec<_>>())
    );
    let unnamed = |s: &Scene, mesh: usize| {
        let mut m = s.materials[s.meshes[mesh].triangle_materials[0] as usize].clone();
        m.name = String::new();
        format!("{m:?}")
    };
    assert_eq!((unnamed(&t, 0), unnamed(&t, 1)), (unnamed(&s, 0), unnamed(&s, 1)));

    // What caustica cannot texture is an error naming the line.
    let refused = |tag: &str, world: &str, needles: &[&str]| {
        let path = write_scene(
            tag,
            &[("scene.pbrt", &format!("{OPTIONS}WorldBegin\n{world}\n")), ("square.ply", UV_SQUARE_PLY)],
        );
        let e = format!(
            "{:#}",
            import(&InputFiles::anywhere(), &path, &[])
                .and_then(|i| i.into_scene(&InputFiles::anywhere()))
                .expect_err("refused")
        );
        for needle in needles {
            assert!(e.contains(needle), "{tag}: '{needle}' missing from: {e}");
        }
    };
    let checks = "Texture \"c\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [0.4 0.4 0.4]";
    refused(
        "tex-sphere",
        &format!("{checks}\nMaterial \"diffuse\" \"texture reflectance\" \"c\"\nShape \"sphere\""),
        &["scene.pbrt:9: Shape \"sphere\"", "texture coordinates"],
    );
    refused("tex-patch", &format!("{checks}\nMaterial \"diffuse\" \"texture reflectance\" \"c\"\nShape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0]"), &["scene.pbrt:9: Shape \"bilinearmesh\"", "albedo_texture is supported on a plymesh"]);
    refused("tex-emitting", &format!("{checks}\nMaterial \"diffuse\" \"texture reflectance\" \"c\"\nAreaLightSource \"diffuse\"\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]"), &["scene.pbrt:10: Shape \"trianglemesh\"", "does not emit"]);
    refused("tex-exr", "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"a.exr\"\nMaterial \"diffuse\" \"texture reflectance\" \"t\"\nShape \"plymesh\" \"string filename\" \"square.ply\"", &["scene.pbrt:7: Texture \"imagemap\"", "a.exr", "PNG and JPEG"]);
    refused("tex-jpeg", "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"a.jpg\"\nMaterial \"diffuse\" \"texture reflectance\" \"t\"\nShape \"plymesh\" \"string filename\" \"square.ply\"", &["scene.pbrt:7:", "encoding \"linear\""]);
    refused("tex-spherical", &format!("{checks} \"string mapping\" \"spherical\"\nMaterial \"diffuse\" \"texture reflectance\" \"c\"\nShape \"plymesh\" \"string filename\" \"square.ply\""), &["scene.pbrt:7:", "mapping \"spherical\""]);
    refused("tex-3d", &format!("{checks} \"integer dimension\" 3\nMaterial \"diffuse\" \"texture reflectance\" \"c\"\nShape \"plymesh\" \"string filename\" \"square.ply\""), &["scene.pbrt:7:", "dimension 2"]);
    refused("tex-bright", &format!("{checks} \"rgb tex2\" [2 2 2]\nMaterial \"diffuse\" \"texture reflectance\" \"c\"\nShape \"plymesh\" \"string filename\" \"square.ply\""), &["scene.pbrt:8:", "energy conservation"]);
    refused("tex-roughness", "Texture \"r\" \"float\" \"checkerboard\"\nMaterial \"conductor\" \"texture roughness\" \"r\"\nShape \"sphere\"", &["scene.pbrt:7: Texture \"r\" \"checkerboard\"", "float"]);
    refused(
        "tex-conductor",
        &format!("{checks}\nMaterial \"conductor\" \"texture reflectance\" \"c\"\nShape \"sphere\""),
        &["scene.pbrt:8:", "varies over the surface"],
    );
}

#[test]
fn coatedconductor_is_causticas_clear_coat_over_the_conductor() {
    let s = scene(
        "coatedconductor",
        "Material \"coatedconductor\" \"float interface.roughness\" 0.01 \"spectrum conductor.eta\" \"metal-Au-eta\" \"spectrum conductor.k\" \"metal-Au-k\" \"float conductor.roughness\" 0.0625\nShape \"sphere\"\n\
         Material \"coatedconductor\" \"rgb reflectance\" [0.5 0.5 0.5]\nShape \"sphere\"\n",
    );
    let m = |k: usize| s.materials[s.shapes[k].material() as usize].clone();
    let gold = caustica::scene::metal("gold").unwrap();
    assert_eq!(m(0).conductor, Conductor::Complex { eta: gold.0, k: gold.1 });
    // alpha = sqrt(roughness), caustica's roughness sqrt(alpha): the coat's 0.01 -> 0.1^0.5, the
    // conductor's 0.0625 -> 0.5.
    let coat = m(0).clearcoat.expect("a clear coat");
    assert!(
        (coat.factor, coat.texture, coat.roughness_texture) == (1.0, None, None)
            && (coat.roughness - 0.1f32.sqrt()).abs() < 1e-6,
        "{coat:?}"
    );
    assert!((m(0).roughness - 0.5).abs() < 1e-6 && m(0).reflectivity == 1.0);
    let Conductor::Complex { eta, k } = m(1).conductor else { panic!("a complex conductor") };
    assert!(close(eta, Vec3::ONE) && ((k.x * k.x) / (4.0 + k.x * k.x) - 0.5).abs() < 1e-5);
    assert_eq!(m(1).clearcoat.map(|c| (c.factor, c.roughness)), Some((1.0, 0.0)), "a smooth coat by default");
    let warnings = imported(
        "coat-warn",
        &format!("{OPTIONS}WorldBegin\nMaterial \"coatedconductor\" \"float interface.eta\" 1.33\nShape \"sphere\"\n"),
    )
    .unwrap()
    .warnings;
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("scene.pbrt:7:") && w.contains("coatedconductor becomes caustica's clear coat")),
        "{warnings:?}"
    );
    assert!(warnings.iter().any(|w| w.contains("interface.eta 1.33 becomes 1.5")), "{warnings:?}");
    // The TOML twin: the same material from the scene file's clearcoat keys.
    let twin = "[camera]\nposition = [0, 0, 3]\nlook_at = [0, 0, 0]\n[materials.m]\nmetal = \"gold\"\nroughness = 0.5\nclearcoat = 1.0\nclearcoat_roughness = 0.31622776\n[[spheres]]\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n";
    let mut t = Scene::parse(twin, "twin.toml", Path::new(".")).unwrap().materials[0].clone();
    t.name = m(0).name.clone();
    assert_eq!(format!("{t:?}"), format!("{:?}", m(0)));
    let e = error(
        "coat-albedo",
        &format!("{OPTIONS}WorldBegin\nMaterial \"coatedconductor\" \"rgb albedo\" [0.5 0.5 0.5]\nShape \"sphere\"\n"),
    );
    assert!(e.contains("scene.pbrt:7: Material \"coatedconductor\": a scattering coat"), "{e}");
    let e = error("coat-both", &format!("{OPTIONS}WorldBegin\nMaterial \"coatedconductor\" \"rgb reflectance\" [0.5 0.5 0.5] \"rgb conductor.eta\" [1 1 1]\nShape \"sphere\"\n"));
    assert!(e.contains("scene.pbrt:7:") && e.contains("reflectance or conductor.eta and conductor.k"), "{e}");
}

#[test]
fn power_and_illuminance_scale_lights_as_pbrt_v4_does() {
    use std::f32::consts::PI;
    let s = scene(
        "power",
        "LightSource \"point\" \"rgb I\" [0.5 1 1] \"float scale\" 2 \"float power\" 100\n\
         LightSource \"spot\" \"float coneangle\" 60 \"float conedeltaangle\" 60 \"float power\" 10\n\
         LightSource \"distant\" \"float illuminance\" 3\n\
         LightSource \"infinite\" \"rgb L\" [1 0.5 0.5] \"float illuminance\" 2\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"float power\" 8 \"bool twosided\" true\n\
         Shape \"bilinearmesh\" \"point3 P\" [0 0 0  2 0 0  0 1 0  2 1 0]\nAttributeEnd\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 0.5 0.5] \"float power\" 6\n\
         Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0  3 0 0] \"integer indices\" [0 1 2  1 3 2]\n\
         Scale 2 2 2\nShape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n",
    );
    // pbrt scales the spectrum at unit luminance (the RGB as given) by power / k_e, whatever
    // the RGB's own brightness.
    match s.lights[0] {
        Light::Point { intensity, .. } => {
            assert!(close(intensity, Vec3::new(0.5, 1.0, 1.0) * 2.0 * 100.0 / (4.0 * PI)), "{intensity}")
        }
        ref other => panic!("{other:?}"),
    }
    // coneangle = conedeltaangle = 60: the falloff starts at the axis, k_e = 2 pi (1 - cos 60) / 2.
    match s.lights[1] {
        Light::Spot { intensity, falloff_start, .. } => {
            assert!(close(intensity, Vec3::splat(10.0 / (PI * 0.5))) && falloff_start == 0.0, "{intensity}")
        }
        ref other => panic!("{other:?}"),
    }
    match s.lights[2] {
        Light::Directional { irradiance, .. } => assert!(close(irradiance, Vec3::splat(3.0)), "{irradiance}"),
        ref other => panic!("{other:?}"),
    }
    assert!(
        matches!(s.environment, Environment::Constant(c) if close(c, Vec3::new(1.0, 0.5, 0.5) * 2.0 / PI)),
        "{:?}",
        s.environment
    );
    // Each shape (each triangle of a mesh) emits the whole power: L = power / (pi area), halved
    // on two sides; a sphere's area is pbrt's, without its transformation's scale.
    let emission = |k: usize| s.materials[s.shapes[k].material() as usize].emission;
    let Shape::Sphere { radius, .. } = s.shapes[0] else { panic!("the sphere first: {:?}", s.shapes[0]) };
    assert_eq!(radius, 1.0);
    assert!(close(emission(0), Vec3::new(1.0, 0.5, 0.5) * 6.0 / (PI * PI)), "sphere: {}", emission(0));
    assert!(close(emission(1), Vec3::splat(8.0 / (PI * 2.0 * 2.0))), "two-sided quad: {}", emission(1));
    assert!(close(emission(2), Vec3::new(1.0, 0.5, 0.5) * 6.0 / (PI * 0.5)), "triangle of area 1/2: {}", emission(2));
    assert!(close(emission(3), Vec3::new(1.0, 0.5, 0.5) * 6.0 / (PI * 1.0)), "triangle of area 1: {}", emission(3));
    assert_eq!(
        s.materials.len(),
        4,
        "one material per area, none left over: {:?}",
        s.materials.iter().map(|m| &m.name).collect::<Vec<_>>()
    );

    // An equal-area map of constant radiance c: pbrt's own illuminance is c pi / 2 (its 2 pi /
    // texels; the true one is c pi), so the map is scaled by E / (c pi / 2).
    let mut sky = caustica::image::RgbImage::new(64, 64);
    for y in 0..64 {
        for x in 0..64 {
            sky.set(x, y, [0.5; 3]);
        }
    }
    let dir = temp_dir("pbrt-illuminance");
    caustica::image::pfm::write(&dir.join("sky.pfm"), &sky).unwrap();
    let path = dir.join("scene.pbrt");
    std::fs::write(&path, format!("{OPTIONS}WorldBegin\nLightSource \"infinite\" \"string filename\" \"sky.pfm\" \"float scale\" 3 \"float illuminance\" 10\n")).unwrap();
    let s = import(&InputFiles::anywhere(), &path, &[]).unwrap().into_scene(&InputFiles::anywhere()).unwrap();
    let Environment::Map(map) = &s.environment else { panic!("an environment map") };
    let expected = 3.0 * 10.0 / (0.5 * PI / 2.0);
    assert!((map.intensity / expected - 1.0).abs() < 5e-3, "{} against {expected}", map.intensity);
    // A map dark above its horizon cannot be scaled to an illuminance.
    caustica::image::pfm::write(&dir.join("sky.pfm"), &caustica::image::RgbImage::new(8, 8)).unwrap();
    let e = format!("{:#}", import(&InputFiles::anywhere(), &path, &[]).err().unwrap());
    assert!(
        e.contains("scene.pbrt:7: LightSource \"infinite\"") && e.contains("no light onto its upper hemisphere"),
        "{e}"
    );
    let e = error("power-curved", &format!("{OPTIONS}WorldBegin\nAreaLightSource \"diffuse\" \"float power\" 1\nShape \"bilinearmesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0  1 1 1]\n"));
    assert!(e.contains("scene.pbrt:8: Shape \"bilinearmesh\"") && e.contains("not planar"), "{e}");
}

#[test]
fn a_textured_trianglemesh_keeps_its_texture_coordinates_and_convert_writes_it_as_ply() {
    let world = "Texture \"checks\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [0.4 0.4 0.4] \"rgb tex2\" [0.2 0.2 0.2] \"float uscale\" 4\n\
                 Material \"diffuse\" \"texture reflectance\" \"checks\"\n\
                 Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0] \"point2 uv\" [0.1 0.1  0.3 0.1  0.1 0.3]\n\
                 Texture \"wood\" \"spectrum\" \"imagemap\" \"string filename\" \"wood.png\"\n\
                 Material \"diffuse\" \"texture reflectance\" \"wood\"\n\
                 Shape \"trianglemesh\" \"point3 P\" [0 0 1  1 0 1  0 1 1]\n\
                 Material \"diffuse\"\n\
                 Shape \"trianglemesh\" \"point3 P\" [0 0 2  1 0 2  0 1 2] \"float uv\" [0 0 1 0 1 1]\n";
    let path = write_scene("textured-trianglemesh", &[("scene.pbrt", &format!("{OPTIONS}WorldBegin\n{world}"))]);
    caustica::image::png::write(
        &path.with_file_name("wood.png"),
        &caustica::image::RgbImage::new(3, 2),
        &Default::default(),
    )
    .unwrap();
    let s = import(&InputFiles::anywhere(), &path, &[])
        .unwrap()
        .into_scene(&InputFiles::anywhere())
        .unwrap_or_else(|e| panic!("{e:#}"));
    assert_eq!(
        (s.meshes.len(), s.shapes.len()),
        (2, 1),
        "the textured meshes are meshes, the untextured one a triangle"
    );
    // The mirror turns the winding, which the import turns back: corners 0, 2, 1, at the world
    // points pbrt has mirrored in x.
    let positions: Vec<Vec3> = s.meshes[0].positions.clone();
    assert_eq!(positions, vec![Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0), Vec3::new(-1.0, 0.0, 0.0)]);
    assert_eq!(s.instances.iter().map(|i| i.transform).collect::<Vec<_>>(), vec![glam::Mat4::IDENTITY; 2]);
    // pbrt's checkerboard: tex1 where floor(4 u) + floor(v) is even (u = 0.1), tex2 at u = 0.3.
    let checker = &s.textures[s.materials[s.meshes[0].triangle_materials[0] as usize].albedo_texture.unwrap() as usize];
    let texel = |uv: glam::Vec2| {
        checker.texels[(uv.y.rem_euclid(1.0) * checker.height as f32) as usize * checker.width as usize
            + (uv.x.rem_euclid(1.0) * checker.width as f32) as usize]
    };
    assert_eq!(s.meshes[0].uvs.iter().map(|&uv| texel(uv)[0]).collect::<Vec<_>>(), vec![102, 102, 51]);
    // Without uv, pbrt's (0, 0), (1, 0), (1, 1) at the corners (here in the order 0, 2, 1), v
    // turned down for caustica.
    let uvs: Vec<(f32, f32)> = s.meshes[1].uvs.iter().map(|uv| (uv.x, uv.y)).collect();
    assert_eq!(uvs, vec![(0.0, 1.0), (1.0, 0.0), (1.0, 1.0)]);

    // convert writes each as a PLY beside the TOML, which loads to the same meshes and textures.
    let out = temp_dir("textured-trianglemesh-out");
    let toml = import(&InputFiles::anywhere(), &path, &[]).unwrap().to_toml(&out).unwrap();
    assert!(
        toml.contains("scene-mesh-0.ply")
            && toml.contains("scene-mesh-1.ply")
            && out.join("scene-mesh-1.ply").is_file(),
        "{toml}"
    );
    let t = Scene::parse(&toml, "converted.toml", &out).unwrap_or_else(|e| panic!("{e:#}\n{toml}"));
    assert_eq!(t.textures, s.textures);
    let meshes = |s: &Scene| {
        s.meshes
            .iter()
            .map(|m| {
                format!(
                    "{:?} {:?} {:?} {:?}",
                    m.positions, m.uvs, m.triangles, s.materials[m.triangle_materials[0] as usize].albedo_texture
                )
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(meshes(&t), meshes(&s));

    let e = error("bad-uv", &format!("{OPTIONS}WorldBegin\nTexture \"c\" \"spectrum\" \"checkerboard\"\nMaterial \"diffuse\" \"texture reflectance\" \"c\"\nShape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0] \"point2 uv\" [0 0 1 0]\n"));
    assert!(e.contains("scene.pbrt:9: 'point2 uv'") && e.contains("needs a point2 a vertex (6 numbers)"), "{e}");
}

/// UV_SQUARE_PLY with vertex normals (+z), which a normal map needs.
const NORMAL_SQUARE_PLY: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0 0 0 1 0.1 0.1\n1 0 0 0 0 1 0.3 0.1\n0 1 0 0 0 1 0.1 0.3\n1 1 0 0 0 1 0.3 0.3\n3 0 1 3\n3 0 3 2\n";

#[test]
fn normalmaps_and_alpha_cut_outs_become_normal_textures_and_opacity() {
    let world = "Material \"diffuse\" \"string normalmap\" \"bumps.png\"\n\
                 Shape \"plymesh\" \"string filename\" \"square.ply\" \"float alpha\" 0.4\n\
                 Texture \"leaf\" \"float\" \"imagemap\" \"string filename\" \"leaf.png\"\n\
                 Shape \"plymesh\" \"string filename\" \"square.ply\" \"texture alpha\" \"leaf\"\n\
                 Shape \"plymesh\" \"string filename\" \"square.ply\" \"float alpha\" 1\n";
    let path = write_scene(
        "alpha",
        &[("scene.pbrt", &format!("{OPTIONS}WorldBegin\n{world}")), ("square.ply", NORMAL_SQUARE_PLY)],
    );
    let dir = path.parent().unwrap();
    for name in ["bumps.png", "leaf.png"] {
        image::RgbImage::from_pixel(2, 2, image::Rgb([128, 128, 255])).save(dir.join(name)).unwrap();
    }
    let s = import(&InputFiles::anywhere(), &path, &[])
        .unwrap()
        .into_scene(&InputFiles::anywhere())
        .unwrap_or_else(|e| panic!("{e:#}"));
    let material = |mesh: usize| &s.materials[s.meshes[mesh].triangle_materials[0] as usize];
    let [faded, leaf, whole] = [0, 1, 2].map(material);
    for m in [faded, leaf, whole] {
        let normal = m.maps.normal.expect("every shape wears the normal-mapped material");
        assert!(!s.textures[normal.texture as usize].srgb, "pbrt reads normal maps as linear");
    }
    let faded_alpha = faded.maps.alpha.expect("alpha 0.4 is an opacity");
    assert_eq!(
        (faded_alpha.factor, faded_alpha.texture, faded_alpha.mode),
        (0.4, None, AlphaMode::Blend),
        "pbrt's alpha is stochastic"
    );
    let leaf_alpha = leaf.maps.alpha.expect("an alpha texture is an opacity texture");
    assert_eq!(s.textures[leaf_alpha.texture.unwrap() as usize].name, "leaf.png");
    assert_eq!(whole.maps.alpha, None, "alpha 1 is a whole surface, sharing the material");
    assert!(s.meshes[0].tangents.iter().all(|t| t.w == 1.0), "pbrt's frame is Mitsuba's: (dp/du, cross(n, dp/du))");

    let e = error("alpha-sphere", &format!("{OPTIONS}WorldBegin\nShape \"sphere\" \"float alpha\" 0.5\n"));
    assert!(e.contains("scene.pbrt:7") && e.contains("opacity") && e.contains("Shape \"sphere\""), "{e}");
    let e = error(
        "alpha-range",
        &format!("{OPTIONS}WorldBegin\nShape \"plymesh\" \"string filename\" \"square.ply\" \"float alpha\" -0.5\n"),
    );
    assert!(e.contains("scene.pbrt:7") && e.contains("alpha must be in [0, 1]"), "{e}");
}

/// pbrt-v4's `uroughness` and `vroughness` (each defaulting to `roughness`) become roughness
/// (along u) and roughness_v: with remaproughness, alpha = sqrt(r) and caustica's roughness
/// sqrt(alpha); without, alpha = r. Equal ones are isotropic; a vroughness outside what gives an
/// alpha in [0, 1] is an error naming it. Swapping u and v, or skipping the remap, fails.
#[test]
fn uroughness_and_vroughness_map_onto_roughness_and_roughness_v() {
    let s = scene(
        "anisotropic",
        "Material \"conductor\" \"float uroughness\" 0.0001 \"float vroughness\" 0.0625\nShape \"sphere\"\n\
         Material \"dielectric\" \"float uroughness\" 0.04 \"float vroughness\" 0.25 \"bool remaproughness\" false\nShape \"sphere\"\n\
         Material \"coateddiffuse\" \"float roughness\" 0.0081 \"float vroughness\" 0.0256\nShape \"sphere\"\n\
         Material \"conductor\" \"float uroughness\" 0.01 \"float vroughness\" 0.01\nShape \"sphere\"\n",
    );
    let m = |k: usize| s.materials[s.shapes[k].material() as usize].clone();
    let near = |a: f32, b: f32| (a - b).abs() < 1e-6;
    // remapped: alpha 0.01 and 0.25, roughness 0.1 and 0.5; not remapped: alpha 0.04 and 0.25;
    // roughness stands for uroughness: alpha 0.09 along u, 0.16 along v.
    for (k, u, v) in [(0, 0.1, 0.5), (1, 0.2, 0.5), (2, 0.3, 0.4)] {
        let material = m(k);
        assert!(
            near(material.roughness, u) && material.roughness_v.is_some_and(|r| near(r, v)),
            "material {k}: {material:?}"
        );
    }
    assert!(near(m(3).roughness, 0.1f32.sqrt()) && m(3).roughness_v.is_none());
    let e = error("anisotropic-range", &format!("{OPTIONS}WorldBegin\nMaterial \"conductor\" \"float uroughness\" 0.1 \"float vroughness\" -1\nShape \"sphere\"\n"));
    assert!(e.contains("scene.pbrt:7:") && e.contains("vroughness"), "{e}");
}
