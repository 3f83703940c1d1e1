//! The kernel compiled for a scene (src/render/features.rs) renders the same sums, bit for bit, as
//! the general kernel: every checked-in scene (those of the shared data folder when present) and a
//! scene that uses every feature. A feature wrongly detected as absent drops its code and changes
//! the image (the mutations `features-*` of tests/mutations.toml remove each detection in turn).
//! Likewise for the order the workgroups take the image's rows in (src/render/group_order.rs).

mod common;

use caustica::render::{
    AovSet, GroupOrder, KernelChoice, Renderer, SceneFeatures, Workgroup, FEW_PRIMITIVES, WORKGROUP_VAR,
};
use caustica::scene::{Alpha, AlphaMode, Clearcoat, Instance, Mesh, NormalMap, Scene, Shape, Texture};
use common::{checked_in_scenes, floor_point_scene, gpu, parse};
use glam::{Mat4, Vec2, Vec3, Vec4};

/// The accumulated sums of `scene` (seed 3, its own spp), as bits, and the features its kernel had.
fn sums(ctx: &caustica::gpu::GpuContext, scene: &Scene, choice: KernelChoice) -> (Vec<[u32; 4]>, SceneFeatures) {
    sums_with(ctx, scene, choice, |_| {})
}

/// [`sums`] of a renderer that `configure` has set up.
fn sums_with(
    ctx: &caustica::gpu::GpuContext,
    scene: &Scene,
    choice: KernelChoice,
    configure: impl FnOnce(&mut Renderer),
) -> (Vec<[u32; 4]>, SceneFeatures) {
    let mut renderer = Renderer::with_kernel(ctx, scene, 3, AovSet::default(), choice).expect("scene uploads");
    configure(&mut renderer);
    renderer.render(scene.film.spp, |_| {}).expect("render succeeds without validation messages");
    let bits = renderer.accumulation().expect("readback").iter().map(|p| p.map(f32::to_bits)).collect();
    (bits, renderer.features)
}

/// Renders `scene` small with both kernels; returns the features the scene's kernel was compiled with.
fn assert_specialized_kernel_agrees(ctx: &caustica::gpu::GpuContext, mut scene: Scene) -> SceneFeatures {
    (scene.film.width, scene.film.height, scene.film.spp) = (40, 30, 2);
    let (specialized, features) = sums(ctx, &scene, KernelChoice::ForScene);
    let (general, all) = sums(ctx, &scene, KernelChoice::General);
    assert_eq!(all, SceneFeatures::ALL);
    let differing = specialized.iter().zip(&general).filter(|(a, b)| a != b).count();
    assert_eq!(
        differing,
        0,
        "{}: {differing} of {} pixels differ between the kernel compiled for {:?} and the general kernel",
        scene.name,
        general.len(),
        features.names()
    );
    features
}

#[test]
fn every_checked_in_scene_renders_the_same_with_its_own_kernel() {
    let (_lock, ctx) = gpu();
    let mut specialized = 0;
    for (_, scene) in checked_in_scenes() {
        if assert_specialized_kernel_agrees(&ctx, scene) != SceneFeatures::ALL {
            specialized += 1;
        }
    }
    // Otherwise the comparison above compared the general kernel with itself.
    assert!(specialized >= 3, "only {specialized} scenes got a kernel of their own");
}

/// A textured, instanced mesh with a rough metal (GGX and Beckmann, both anisotropic: oriented
/// by the spheres' longitude), a one-sided clear-coated plastic, a thin pane and a sphere of
/// absorbing glass under an environment map, lit by a mesh lamp with an emission texture, the
/// floor normal-mapped, vertex-coloured and anisotropically glossy along its tangents, and two squares with
/// alpha over it (a textured BLEND and a textured MASK), beside a glowing sphere, a quad, a
/// triangle, a spot light and a sun with a disk: every feature on, which the checked-in scenes
/// without the shared data lack (textures, several instances, textured emitters, normal maps,
/// alpha, clear coats, absorption, anisotropy).
#[test]
fn a_scene_with_every_feature_renders_the_same_with_its_own_kernel() {
    let mut scene = parse(
        r#"
        camera = { position = [0, 0.5, 3], look_at = [0, 0, 0], fov = 40 }
        film = { width = 40, height = 30, spp = 2 }
        environment = { probe = "scenes/probes/sky_probe.pfm" }
        [materials.textured]
        albedo = [1, 1, 1]
        reflectivity = 0.5
        roughness = 0.2
        roughness_v = 0.6
        [materials.metal]
        albedo = [0.9, 0.6, 0.3]
        reflectivity = 1.0
        roughness = 0.3
        roughness_v = 0.7
        [materials.plastic]
        albedo = [0.2, 0.5, 0.8]
        coat = true
        one_sided = true
        [materials.glow]
        albedo = [0, 0, 0]
        emission = [4, 3, 2]
        [materials.lace]
        albedo = [0.9, 0.9, 0.9]
        [materials.stencil]
        albedo = [0.8, 0.2, 0.2]
        [materials.brushed]
        albedo = [0.9, 0.9, 0.9]
        metal = "gold"
        reflectivity = 1.0
        roughness = 0.4
        roughness_v = 0.15
        distribution = "beckmann"
        [materials.pane]
        transparency = 1.0
        thin = true
        [materials.smoky_glass]
        transparency = 1.0
        attenuation_color = [0.6, 0.7, 0.9]
        attenuation_distance = 0.2
        [materials.haze_boundary]
        type = "null"
        interior = "haze"
        [[media]]
        name = "haze"
        type = "homogeneous"
        sigma_a = [0.5, 0.6, 0.7]
        sigma_s = [2.0, 1.5, 1.0]
        phase = "hg"
        g = 0.4
        [[spheres]]
        center = [-0.5, 0.15, 0.7]
        radius = 0.15
        material = "haze_boundary"
        [[spheres]]
        center = [0.0, 0.25, 0.4]
        radius = 0.25
        material = "smoky_glass"
        [[spheres]]
        center = [0.8, 0.3, 0.0]
        radius = 0.3
        material = "metal"
        [[spheres]]
        center = [-0.8, 0.3, 0.0]
        radius = 0.3
        material = "plastic"
        [[spheres]]
        center = [0.0, 0.3, 0.6]
        radius = 0.25
        material = "brushed"
        [[spheres]]
        center = [0.0, 0.8, 0.9]
        radius = 0.2
        material = "pane"
        [[spheres]]
        center = [-0.6, 1.2, -0.5]
        radius = 0.1
        material = "glow"
        [[quads]]
        origin = [-1.0, -0.2, -1.2]
        edge_u = [2.0, 0.0, 0.0]
        edge_v = [0.0, 1.5, 0.0]
        material = "lace"
        [[triangles]]
        vertices = [[0.6, -0.2, -0.9], [1.0, -0.2, -0.9], [0.8, 0.4, -0.9]]
        material = "metal"
        [[lights]]
        type = "spot"
        position = [0.5, 1.5, 1.0]
        look_at = [0.0, 0.0, 0.0]
        intensity = [2.0, 2.0, 2.0]
        cone_angle = 30.0
        falloff_start = 20.0
        [[lights]]
        type = "directional"
        direction = [-0.3, -1.0, -0.2]
        irradiance = [1.0, 0.9, 0.8]
        angular_diameter = 5.0
        "#,
    );
    let texels: Vec<[u8; 4]> =
        (0..16u32).map(|i| [(i * 53 % 256) as u8, (i * 101 % 256) as u8, (255 - i * 16) as u8, 255]).collect();
    scene.textures =
        vec![Texture { name: "test".into(), width: 4, height: 4, texels, srgb: true, wrap: Default::default() }];
    scene.materials[0].albedo_texture = Some(0);
    // A bumpy normal map: each texel tilts the normal its own way.
    let bumps: Vec<[u8; 4]> =
        (0..16u32).map(|i| [(96 + i * 37 % 64) as u8, (96 + i * 23 % 64) as u8, 230, 255]).collect();
    scene.textures.push(Texture {
        name: "bumps".into(),
        width: 4,
        height: 4,
        texels: bumps,
        srgb: false,
        wrap: Default::default(),
    });
    scene.materials[0].maps.normal = Some(NormalMap { texture: 1, scale: 0.8 });
    let glow = scene.materials.iter().position(|m| m.name == "glow").unwrap() as u32;
    scene.materials[glow as usize].maps.emission = Some(0);
    // Opacity varying over the texture, read blended (lace) and cut at 0.5 (stencil).
    let holes: Vec<[u8; 4]> = (0..16u32).map(|i| [200, 200, 200, (i * 67 % 256) as u8]).collect();
    scene.textures.push(Texture {
        name: "holes".into(),
        width: 4,
        height: 4,
        texels: holes,
        srgb: true,
        wrap: Default::default(),
    });
    let lace = scene.materials.iter().position(|m| m.name == "lace").unwrap() as u32;
    scene.materials[lace as usize].maps.alpha = Some(Alpha { factor: 0.9, texture: Some(2), mode: AlphaMode::Blend });
    // A rough glTF clear coat over the plastic, its factor from the texture's R.
    let plastic = scene.materials.iter().position(|m| m.name == "plastic").unwrap();
    scene.materials[plastic].clearcoat =
        Some(Clearcoat { factor: 0.8, roughness: 0.3, texture: Some(0), roughness_texture: None });
    let stencil = scene.materials.iter().position(|m| m.name == "stencil").unwrap() as u32;
    scene.materials[stencil as usize].maps.alpha =
        Some(Alpha { factor: 1.0, texture: Some(2), mode: AlphaMode::Mask { cutoff: 0.5 } });
    let corners =
        [Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(-1.0, 0.0, 1.0)];
    let quad = |material: u32, triangles: [[u32; 3]; 2]| Mesh {
        name: "quad".into(),
        positions: corners.to_vec(),
        normals: vec![Vec3::Y; 4],
        uvs: corners.iter().map(|p| Vec2::new(p.x, p.z)).collect(),
        triangles: triangles.to_vec(),
        triangle_materials: vec![material; 2],
        tangents: vec![Vec4::new(1.0, 0.0, 0.0, 1.0); 4],
        colors: vec![Vec3::new(1.0, 0.8, 0.6), Vec3::new(0.6, 1.0, 0.8), Vec3::new(0.8, 0.6, 1.0), Vec3::ONE],
    };
    // The floor faces up; the lamp above it faces down.
    scene.meshes = vec![
        quad(0, [[0, 2, 1], [0, 3, 2]]),
        quad(glow, [[0, 1, 2], [0, 2, 3]]),
        quad(lace, [[0, 2, 1], [0, 3, 2]]),
        quad(stencil, [[0, 2, 1], [0, 3, 2]]),
    ];
    scene.instances = vec![
        Instance { mesh: 0, transform: Mat4::from_translation(Vec3::new(0.0, -0.2, 0.0)) },
        Instance { mesh: 0, transform: Mat4::from_translation(Vec3::new(0.0, -0.2, -2.0)) },
        Instance {
            mesh: 1,
            transform: Mat4::from_translation(Vec3::new(0.0, 1.5, 0.0)) * Mat4::from_scale(Vec3::splat(0.3)),
        },
        Instance {
            mesh: 2,
            transform: Mat4::from_translation(Vec3::new(-0.3, 0.6, 0.3)) * Mat4::from_scale(Vec3::splat(0.5)),
        },
        Instance {
            mesh: 3,
            transform: Mat4::from_translation(Vec3::new(0.4, 0.9, 0.2)) * Mat4::from_scale(Vec3::splat(0.4)),
        },
    ];
    let (_lock, ctx) = gpu();
    let features = assert_specialized_kernel_agrees(&ctx, scene.clone());
    assert_eq!(
        (features.few_shapes.len(), features.walked_shapes()),
        (scene.shapes.len(), false),
        "its few shapes are tested before the walk of its meshes"
    );
    // With more shapes than are tested apart, the walk meets them among the meshes: the general
    // kernel's every feature.
    let far_below = Shape::Sphere { center: Vec3::new(0.0, -50.0, 0.0), radius: 0.01, material: 0 };
    scene.shapes.resize(FEW_PRIMITIVES + 1, far_below);
    let features = assert_specialized_kernel_agrees(&ctx, scene);
    assert_eq!(features, SceneFeatures::ALL, "the scene was meant to use every feature");
}

/// Coats reflect through the reflection lobe even where no material is a mirror or a metal: a
/// plastic and a clear-coated diffuse sphere, nothing else shiny, keep that lobe in their kernel.
#[test]
fn coats_without_mirrors_render_the_same_with_their_own_kernel() {
    let mut scene = parse(
        r#"
        camera = { position = [0, 0.5, 3], look_at = [0, 0.3, 0], fov = 40 }
        film = { width = 40, height = 30, spp = 2 }
        environment = { color = [0.6, 0.7, 0.9] }
        [materials.plastic]
        albedo = [0.2, 0.5, 0.8]
        coat = true
        [materials.lacquered]
        albedo = [0.8, 0.3, 0.2]
        [materials.floor]
        albedo = [0.7, 0.7, 0.7]
        [[spheres]]
        center = [-0.4, 0.3, 0.0]
        radius = 0.3
        material = "plastic"
        [[spheres]]
        center = [0.4, 0.3, 0.0]
        radius = 0.3
        material = "lacquered"
        [[quads]]
        origin = [-2.0, 0.0, 2.0]
        edge_u = [4.0, 0.0, 0.0]
        edge_v = [0.0, 0.0, -4.0]
        material = "floor"
        "#,
    );
    let lacquered = scene.materials.iter().position(|m| m.name == "lacquered").unwrap();
    scene.materials[lacquered].clearcoat =
        Some(Clearcoat { factor: 1.0, roughness: 0.0, texture: None, roughness_texture: None });
    let (_lock, ctx) = gpu();
    let features = assert_specialized_kernel_agrees(&ctx, scene);
    assert!(features.reflectors && !features.dielectrics, "{:?}", features.names());
}

/// A kernel of exactly one light samples it at the constant index 0; one area light beside a
/// punctual light is two lights, which the pick must keep choosing between.
#[test]
fn one_light_and_one_area_light_beside_a_punctual_one_render_the_same_with_their_own_kernels() {
    let lamp = r#"
        [[spheres]]
        center = [-0.5, 1.2, 0.0]
        radius = 0.2
        material = "lamp"
        "#;
    let point = r#"
        [[lights]]
        type = "point"
        position = [0.8, 1.0, 0.5]
        intensity = [2.0, 2.0, 2.0]
        "#;
    let (_lock, ctx) = gpu();
    let features = assert_specialized_kernel_agrees(&ctx, floor_point_scene(lamp, 2, true));
    assert!(!features.light_pick, "one light is sampled without a pick");
    let features = assert_specialized_kernel_agrees(&ctx, floor_point_scene(&format!("{lamp}{point}"), 2, true));
    assert!(features.light_pick, "an area light and a point light are picked between");
}

/// Dealing the rows of workgroups into stripes (the default on lavapipe) renders each pixel once,
/// as in order: the same sums bit for bit. Each dispatch covers the whole image, 100 rows: 13 rows
/// of workgroups in 3 stripes of unequal length, so a row mapping that is off renders some rows
/// twice and others never (their sums change, or the host sees pixels missing).
#[test]
fn both_workgroup_orders_render_the_same_sums() {
    let mut scene = Scene::default_scene();
    (scene.film.width, scene.film.height, scene.film.spp) = (24, 100, 2);
    let (_lock, ctx) = gpu();
    let render = |order: GroupOrder| {
        sums_with(&ctx, &scene, KernelChoice::ForScene, |r| {
            r.set_group_order(order);
            r.fix_samples_per_dispatch(1);
        })
        .0
    };
    let (in_order, interleaved) = (render(GroupOrder::InOrder), render(GroupOrder::Interleaved));
    assert!(in_order.iter().all(|p| f32::from_bits(p[3]) == 2.0), "every pixel holds its 2 samples");
    let differing = in_order.iter().zip(&interleaved).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{differing} of {} pixels differ between the workgroup orders", in_order.len());
}

/// Every workgroup shape (src/render/workgroup.rs, a kernel variant) renders the same sums bit
/// for bit: each invocation is its pixel's alone. The image, 24x100, divides into none of the
/// shapes' heights but 4, so partial workgroups at the bottom are covered as well; a shape whose
/// dispatch or row mapping were off would render some pixels twice or never.
#[test]
fn every_workgroup_shape_renders_the_same_sums() {
    let mut scene = Scene::default_scene();
    (scene.film.width, scene.film.height, scene.film.spp) = (24, 100, 2);
    // The override is read when a renderer is made; the lock keeps this binary's other tests from
    // making one meanwhile.
    let (_lock, ctx) = gpu();
    let render = |shape: Option<&str>| {
        match shape {
            Some(shape) => std::env::set_var(WORKGROUP_VAR, shape),
            None => std::env::remove_var(WORKGROUP_VAR),
        }
        let mut renderer =
            Renderer::with_kernel(&ctx, &scene, 3, AovSet::default(), KernelChoice::ForScene).expect("scene uploads");
        std::env::remove_var(WORKGROUP_VAR);
        renderer.fix_samples_per_dispatch(1);
        renderer.render(scene.film.spp, |_| {}).expect("render succeeds without validation messages");
        (
            renderer.workgroup,
            renderer.accumulation().expect("readback").iter().map(|p| p.map(f32::to_bits)).collect::<Vec<_>>(),
        )
    };
    let (default_shape, reference) = render(None);
    assert_eq!(default_shape, Workgroup::EIGHT_BY_EIGHT, "lavapipe's shape");
    assert!(reference.iter().all(|p| f32::from_bits(p[3]) == 2.0), "every pixel holds its 2 samples");
    for shape in ["16x4", "32x2", "4x16", "8x16"] {
        let (used, sums) = render(Some(shape));
        assert_eq!(used.label(), shape, "the override was taken");
        let differing = reference.iter().zip(&sums).filter(|(a, b)| a != b).count();
        assert_eq!(differing, 0, "{differing} of {} pixels differ between workgroups of 8x8 and {shape}", sums.len());
    }
}
