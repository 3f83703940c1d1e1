//! Meshes on the GPU: the two-level BVH (instanced meshes beside the scene's own shapes) against
//! brute-force ray casting, and texture lookup at known texture coordinates.

mod common;

use caustica::render::frame_params;
use caustica::render::{Renderer, SceneData, SceneFeatures, WALK_QUEUE_VAR};
use caustica::scene::{Environment, EnvironmentMap, Instance, MapProjection, Mesh, Scene, Texture};
use common::{gpu, image_of, parse, render, srgb_to_linear};
use glam::{Mat4, Quat, Vec2, Vec3};

/// Primary rays through image-plane points (pixel units, y down), as camera.glsl builds them.
struct PinholeRays {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    tan_half: f32,
    aspect: f32,
    size: Vec2,
}

impl PinholeRays {
    fn new(scene: &Scene) -> PinholeRays {
        let p = frame_params(scene, &SceneData::new(scene, 0), 0);
        PinholeRays {
            eye: Vec3::from_slice(&p.cam_origin),
            forward: Vec3::from_slice(&p.cam_forward),
            right: Vec3::from_slice(&p.cam_right),
            up: Vec3::from_slice(&p.cam_up),
            tan_half: p.tan_half_fov,
            aspect: p.aspect,
            size: Vec2::new(scene.film.width as f32, scene.film.height as f32),
        }
    }

    fn dir(&self, film: Vec2) -> Vec3 {
        let f = film / self.size;
        let x = (2.0 * f.x - 1.0) * self.tan_half * self.aspect;
        let y = (1.0 - 2.0 * f.y) * self.tan_half;
        (self.forward + x * self.right + y * self.up).normalize()
    }
}

fn ray_triangle(o: Vec3, d: Vec3, v: [Vec3; 3]) -> Option<(f32, Vec2)> {
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-20 {
        return None;
    }
    let s = o - v[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let w = d.dot(q) / det;
    let t = e2.dot(q) / det;
    (u >= 0.0 && w >= 0.0 && u + w <= 1.0 && t > 0.0).then_some((t, Vec2::new(u, w)))
}

/// A closed tetrahedron and an open, folded strip: different shapes, so instances of each overlap
/// in depth in every way.
fn tetrahedron(material: u32) -> Mesh {
    let positions = vec![
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(1.0, -1.0, -1.0),
        Vec3::new(-1.0, 1.0, -1.0),
        Vec3::new(-1.0, -1.0, 1.0),
    ];
    let triangles = vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]];
    Mesh {
        name: "tetrahedron".into(),
        positions,
        triangle_materials: vec![material; 4],
        triangles,
        ..Default::default()
    }
}

fn folded_strip(material: u32) -> Mesh {
    let positions: Vec<Vec3> = (0..10)
        .map(|i| {
            Vec3::new(
                (i / 2) as f32 * 0.5 - 1.0,
                if i % 2 == 0 { -1.0 } else { 1.0 },
                if (i / 2) % 2 == 0 { 0.0 } else { 0.4 },
            )
        })
        .collect();
    let triangles: Vec<[u32; 3]> =
        (0..8).map(|i| if i % 2 == 0 { [i, i + 1, i + 2] } else { [i + 1, i, i + 2] }).collect();
    Mesh { name: "strip".into(), positions, triangle_materials: vec![material; 8], triangles, ..Default::default() }
}

/// Deterministic numbers in [0, 1) from `seed`.
fn uniform_numbers(seed: u64) -> impl FnMut() -> f32 {
    let mut state = seed;
    move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((state >> 40) as f32) / (1u64 << 24) as f32
    }
}

/// Overlapping, interpenetrating triangles in [-1, 1]^3, each with one of `materials`: enough of
/// them that the mesh's BVH has several levels, so rays enter both children of its nodes, often
/// find the nearest hit in the farther one, and a lost child shows as a wrong colour. Each is
/// equilateral (no slivers that could slip between the test's sample points) and turned at random.
fn triangle_soup(materials: [u32; 3], count: u32) -> Mesh {
    let mut next = uniform_numbers(0x2545_f491_4f6c_dd1d);
    let mut positions = vec![];
    for _ in 0..count {
        let center = 1.6 * (Vec3::new(next(), next(), next()) - 0.5);
        let rotation = Quat::from_euler(glam::EulerRot::ZYX, next() * 6.3, next() * 6.3, next() * 6.3);
        let corner = |k: f32| center + rotation * (0.35 * Vec3::new((k * 2.094).cos(), (k * 2.094).sin(), 0.0));
        positions.extend([corner(0.0), corner(1.0), corner(2.0)]);
    }
    let triangles = (0..count).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    let triangle_materials = (0..count).map(|t| materials[t as usize % 3]).collect();
    Mesh { name: "soup".into(), positions, triangle_materials, triangles, ..Default::default() }
}

/// Deterministic placements: rotations, non-uniform scales and some mirroring ones.
fn placements(count: usize) -> Vec<Mat4> {
    let mut next = uniform_numbers(0x9e37_79b9_7f4a_7c15);
    (0..count)
        .map(|k| {
            let translate = Vec3::new(next() * 3.0 - 1.5, next() * 3.0 - 1.5, next() * 2.0 - 1.0);
            let rotation = Quat::from_euler(glam::EulerRot::ZYX, next() * 6.3, next() * 6.3, next() * 6.3);
            let mut scale = Vec3::new(0.15 + 0.3 * next(), 0.15 + 0.3 * next(), 0.15 + 0.3 * next());
            if k % 5 == 0 {
                scale.x = -scale.x;
            }
            Mat4::from_scale_rotation_translation(scale, rotation, translate)
        })
        .collect()
}

#[test]
fn instanced_meshes_and_shapes_match_brute_force_ray_casting() {
    // 40 placements of two small meshes and two of the soup, with the sphere's instance: a top
    // level deeper than its root, walked with a stack of its own.
    let features = instances_match_brute_force_ray_casting(40, 8, 1.0);
    assert!(features.top_level && features.top_level_tree, "{features:?}");
}

#[test]
fn a_scene_a_tenth_the_size_matches_brute_force_ray_casting() {
    // The same scene shrunk tenfold about the origin, camera included: the same pixels, with every
    // ray distance below 1. A walk's stack entries keep the top bits of a float distance
    // (bvh.glsl's stack_entry), and a misread of them can overstate only some magnitudes'
    // distances (mutation walk-stack-entry-bound-misread overstates those below 2 only): a
    // node popped with an overstated distance is skipped, and a nearer surface in it missed.
    instances_match_brute_force_ray_casting(40, 8, 0.1);
}

#[test]
fn a_top_level_of_few_instances_matches_brute_force_ray_casting() {
    // The two soups, which overlap on screen, and the sphere's instance: the top level is its root
    // alone (SCENE_TOP_LEVEL_TREE 0), whose instances are walked in turn, nearest first, and left
    // once the hit is nearer (mutation bvh-flat-top-level-walks-nearest-instance-only).
    let features = instances_match_brute_force_ray_casting(0, 12, 1.0);
    assert!(features.top_level && !features.top_level_tree, "{features:?}");
}

/// Renders `placed` placements of a tetrahedron and a folded strip (alternately), two of a triangle
/// soup and a sphere, all black emitters of distinct colours, and checks every pixel that sees one
/// thing over its whole footprint against brute-force ray casting, of which more than one in
/// `sparsest` must see geometry, with the whole scene, camera included, scaled by `scale` about the
/// origin. Returns the features its kernel was compiled with.
fn instances_match_brute_force_ray_casting(placed: usize, sparsest: usize, scale: f32) -> SceneFeatures {
    // Black emitters: a pixel's value is exactly the colour of what its rays see first.
    let (sphere_center, sphere_radius) = (scale * Vec3::new(0.3, -0.2, 0.0), scale * 0.5);
    let emitters = [
        ("red", [1, 0, 0], true),
        ("green", [0, 1, 0], true),
        ("blue", [0, 0, 1], false),
        ("yellow", [1, 1, 0], true),
        ("cyan", [0, 1, 1], true),
        ("magenta", [1, 0, 1], true),
    ];
    let materials: String = emitters
        .iter()
        .map(|(name, [r, g, b], two_sided)| {
            format!("[materials.{name}]\nalbedo = [0, 0, 0]\nemission = [{r}, {g}, {b}]\ntwo_sided = {two_sided}\n")
        })
        .collect();
    let mut scene = parse(&format!(
        r#"
        camera = {{ position = [0, 0, {eye_z}], look_at = [0, 0, 0], fov = 40 }}
        film = {{ width = 96, height = 96, spp = 2 }}
        {materials}
        [[spheres]]
        center = [{sphere_x}, {sphere_y}, 0]
        radius = {sphere_radius}
        material = "blue"
        "#,
        eye_z = 6.0 * scale,
        sphere_x = sphere_center.x,
        sphere_y = sphere_center.y,
    ));
    let index = |name: &str| scene.materials.iter().position(|m| m.name == name).expect("material") as u32;
    let soup = triangle_soup([index("yellow"), index("cyan"), index("magenta")], 150);
    scene.meshes = vec![tetrahedron(index("red")), folded_strip(index("green")), soup];
    let transforms = placements(placed);
    scene.instances =
        transforms.iter().enumerate().map(|(k, &transform)| Instance { mesh: (k % 2) as u32, transform }).collect();
    // The soup twice: once large on the left, once smaller, turned, behind the others on the right.
    scene.instances.push(Instance { mesh: 2, transform: Mat4::from_translation(Vec3::new(-1.0, 0.4, 0.5)) });
    scene.instances.push(Instance {
        mesh: 2,
        transform: Mat4::from_scale_rotation_translation(
            Vec3::splat(0.7),
            Quat::from_rotation_y(0.8),
            Vec3::new(1.2, -0.6, -1.0),
        ),
    });
    for inst in &mut scene.instances {
        inst.transform = Mat4::from_scale(Vec3::splat(scale)) * inst.transform;
    }

    // Brute force: every world-space triangle of every instance, and the sphere.
    let mut world: Vec<([Vec3; 3], [f32; 3])> = vec![];
    for inst in &scene.instances {
        let mesh = &scene.meshes[inst.mesh as usize];
        for (t, &m) in mesh.triangles.iter().zip(&mesh.triangle_materials) {
            world.push((
                t.map(|i| inst.transform.transform_point3(mesh.positions[i as usize])),
                scene.materials[m as usize].emission.to_array(),
            ));
        }
    }
    let rays = PinholeRays::new(&scene);
    // What a ray sees, and how far inside its triangle (least barycentric coordinate) it hits.
    let seen = |film: Vec2| -> ([f32; 3], f32) {
        let d = rays.dir(film);
        let mut best = (f32::INFINITY, [0.0; 3], 1.0f32);
        for (v, color) in &world {
            if let Some((t, b)) = ray_triangle(rays.eye, d, *v) {
                if t < best.0 {
                    best = (t, *color, b.x.min(b.y).min(1.0 - b.x - b.y));
                }
            }
        }
        // Unit-direction sphere test; the blue sphere emits only outward, which is the side seen.
        let oc = rays.eye - sphere_center;
        let b = oc.dot(d);
        let disc = b * b - (oc.length_squared() - sphere_radius * sphere_radius);
        if disc >= 0.0 && -b - disc.sqrt() > 0.0 && -b - disc.sqrt() < best.0 {
            best = (-b - disc.sqrt(), [0.0, 0.0, 1.0], 1.0);
        }
        (best.1, best.2)
    };

    let (_lock, ctx) = gpu();
    // The scene's own kernel and, where it walks a flat top level's rays from the walk queue
    // (lavapipe from Mesa 24), the same scene with the queue off: trace_ray's own walk of it is
    // what a GPU and Mesa 22.3 run (mutation bvh-flat-top-level-walks-nearest-instance-only
    // survived on Mesa 25 without it).
    let own = Renderer::new(&ctx, &scene, 3).expect("scene uploads");
    let queued = own.walk_queue.is_some();
    let mut images = vec![("the scene's kernel", image_of(own, scene.film.spp))];
    if queued {
        // Read when a renderer is made; the lock keeps other tests of this binary from making one.
        std::env::set_var(WALK_QUEUE_VAR, "0");
        let plain = Renderer::new(&ctx, &scene, 3);
        std::env::remove_var(WALK_QUEUE_VAR);
        let plain = plain.expect("scene uploads");
        assert!(plain.walk_queue.is_none(), "{WALK_QUEUE_VAR}=0 still walked from the queue");
        images.push(("the kernel without the walk queue", image_of(plain, scene.film.spp)));
    }
    let (mut checked, mut colored, mut soup_seen) = (0, 0, 0);
    for y in 0..scene.film.height {
        for x in 0..scene.film.width {
            // Only pixels that see one thing over their whole footprint have one expected value:
            // a 6 x 6 grid over the pixel, edges included, so slivers cannot slip between points.
            // Rays through a triangle edge may pass between the two triangles under rounding
            // (Moller-Trumbore is not watertight), so pixels an edge crosses are left out too.
            let views: Vec<([f32; 3], f32)> = (0..36)
                .map(|k| seen(Vec2::new(x as f32 + (k % 6) as f32 / 5.0, y as f32 + (k / 6) as f32 / 5.0)))
                .collect();
            if views.iter().any(|v| v.0 != views[0].0 || v.1 < 0.05) {
                continue;
            }
            let expected = views[0].0;
            for (kernel, image) in &images {
                let got = image.get(x, y);
                assert!(
                    (0..3).all(|c| (got[c] - expected[c]).abs() < 1e-4),
                    "pixel ({x}, {y}): {kernel} saw {got:?}, brute force {expected:?}"
                );
            }
            checked += 1;
            colored += usize::from(expected != [0.0; 3]);
            soup_seen += usize::from(expected.iter().sum::<f32>() == 2.0);
        }
    }
    let pixels = (scene.film.width * scene.film.height) as usize;
    assert!(checked > pixels / 2, "only {checked} of {pixels} pixels were unambiguous");
    assert!(colored > pixels / sparsest, "only {colored} pixels see geometry: the test scene is too sparse");
    // The soup's deeper BVH is what tests descending past the first level in the bottom levels.
    assert!(soup_seen > pixels / 40, "only {soup_seen} pixels see the triangle soup");
    SceneFeatures::of(&SceneData::new(&scene, 0))
}

/// Bilinear with wrapping, texel centres at half-integers, as textures.glsl does.
fn bilinear(t: &Texture, uv: Vec2) -> [f32; 3] {
    let p = uv * Vec2::new(t.width as f32, t.height as f32) - 0.5;
    let f = p - p.floor();
    let wrap = |i: f32, n: u32| i.rem_euclid(n as f32) as u32;
    let (x0, y0) = (wrap(p.x.floor(), t.width), wrap(p.y.floor(), t.height));
    let (x1, y1) = ((x0 + 1) % t.width, (y0 + 1) % t.height);
    let texel = |x: u32, y: u32, c: usize| srgb_to_linear(t.texels[(y * t.width + x) as usize][c]);
    std::array::from_fn(|c| {
        let top = texel(x0, y0, c) * (1.0 - f.x) + texel(x1, y0, c) * f.x;
        let bottom = texel(x0, y1, c) * (1.0 - f.x) + texel(x1, y1, c) * f.x;
        top * (1.0 - f.y) + bottom * f.y
    })
}

/// A textured diffuse square open to a white sky reflects exactly its albedo: each pixel is the
/// texture filtered at the texture coordinate it sees. The coordinates run from -0.5 to 1.5, so
/// wrapping is exercised on every side.
#[test]
fn textured_albedo_is_sampled_bilinearly_with_wrapping() {
    let mut scene = parse(
        r#"
        camera = { position = [0, 0, 3], look_at = [0, 0, 0], fov = 30 }
        film = { width = 64, height = 64, spp = 16 }
        environment = { color = [1, 1, 1] }
        [materials.textured]
        albedo = [1, 1, 1]
        "#,
    );
    let texels: Vec<[u8; 4]> =
        (0..16u32).map(|i| [(i * 53 % 256) as u8, (i * 101 % 256) as u8, (255 - i * 16) as u8, 255]).collect();
    scene.textures =
        vec![Texture { name: "test".into(), width: 4, height: 4, texels, srgb: true, wrap: Default::default() }];
    scene.materials[0].albedo_texture = Some(0);
    let corners =
        [Vec3::new(-1.0, 1.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(-1.0, -1.0, 0.0)];
    let uv_of = |p: Vec3| Vec2::new(p.x + 0.5, 0.5 - p.y);
    scene.meshes = vec![Mesh {
        name: "square".into(),
        positions: corners.to_vec(),
        normals: vec![Vec3::Z; 4],
        uvs: corners.iter().map(|&p| uv_of(p)).collect(),
        triangles: vec![[0, 3, 2], [0, 2, 1]],
        triangle_materials: vec![0, 0],
        tangents: Vec::new(),
        colors: Vec::new(),
    }];
    scene.instances = vec![Instance { mesh: 0, transform: Mat4::IDENTITY }];

    let (_lock, ctx) = gpu();
    let image = render(&ctx, &scene, 5);
    let rays = PinholeRays::new(&scene);
    let texture = &scene.textures[0];
    let mut checked = 0;
    for y in 0..scene.film.height {
        for x in 0..scene.film.width {
            let d = rays.dir(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
            let t = -rays.eye.z / d.z;
            let uv = uv_of(rays.eye + t * d);
            // Texel-centre lines are kinks of the bilinear filter, where the pixel's average
            // differs from its centre value; and the jitter's mean is off centre by about
            // 0.29 / sqrt(spp) pixels, a 0.01 error at this magnification.
            let texel = uv * 4.0 - 0.5;
            let to_kink = (texel - texel.round()).abs().min_element();
            if to_kink < 0.1 {
                continue;
            }
            let expected = bilinear(texture, uv);
            let got = image.get(x, y);
            assert!(
                (0..3).all(|c| (got[c] - expected[c]).abs() < 0.03),
                "pixel ({x}, {y}) at uv {uv}: got {got:?}, expected {expected:?}"
            );
            checked += 1;
        }
    }
    assert!(checked > 2000, "only {checked} pixels checked");
}

/// A glTF file written here: one square (0.5 across; texture coordinates run left to right and
/// top to bottom across it) on a node translated to z = -1 and scaled by 2, and a camera node at
/// z = 3 with a 0.5 rad field of view. `material` is the square's material, `top_level` more
/// members of the root object (each followed by a comma).
fn write_square_gltf_with(path: &std::path::Path, material: &str, top_level: &str) {
    use base64::Engine as _;
    let positions: [[f32; 3]; 4] = [[-0.5, -0.5, 0.0], [0.5, -0.5, 0.0], [0.5, 0.5, 0.0], [-0.5, 0.5, 0.0]];
    let uvs: [[f32; 2]; 4] = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bytes: Vec<u8> =
        positions.iter().flatten().chain(uvs.iter().flatten()).flat_map(|f| f.to_le_bytes()).collect();
    bytes.extend(indices.iter().flat_map(|i| i.to_le_bytes()));
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  {top_level}
  "scene": 0,
  "scenes": [{{"nodes": [0, 1]}}],
  "nodes": [
    {{"mesh": 0, "translation": [0, 0, -1], "scale": [2, 2, 2]}},
    {{"camera": 0, "translation": [0, 0, 3]}}
  ],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.5, "aspectRatio": 1.0, "znear": 0.1}}}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1}}, "indices": 2, "material": 0}}]}}],
  "materials": [{material}],
  "buffers": [{{"byteLength": {len}, "uri": "data:application/octet-stream;base64,{data}"}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 48}},
    {{"buffer": 0, "byteOffset": 48, "byteLength": 32}},
    {{"buffer": 0, "byteOffset": 80, "byteLength": 12}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-0.5, -0.5, 0], "max": [0.5, 0.5, 0]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}}
  ]
}}"#,
        len = bytes.len(),
        data = base64::engine::general_purpose::STANDARD.encode(&bytes),
    );
    std::fs::write(path, json).unwrap();
}

/// The square of [`write_square_gltf_with`], emissive: black base, emissive factor (1, 0.5, 0.25)
/// at strength 2 (`KHR_materials_emissive_strength`).
fn write_square_gltf(path: &std::path::Path) {
    let material = r#"{
    "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0},
    "emissiveFactor": [1, 0.5, 0.25],
    "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2}}
  }"#;
    write_square_gltf_with(path, material, r#""extensionsUsed": ["KHR_materials_emissive_strength"],"#);
}

/// `caustica render model.gltf` end to end: the file's camera, node transform and emissive
/// material, under the default white sky.
#[test]
fn gltf_file_renders_as_a_scene_with_its_camera() {
    let dir = common::temp_dir("gltf");
    let path = dir.join("square.gltf");
    write_square_gltf(&path);
    let mut scene = Scene::load(&path).expect("the glTF loads as a scene");
    // The square spans [-1, 1]^2 at distance 4; the view's half-height there is 4 tan(0.25) = 1.02:
    // at 128 pixels the sky border is 1.3 pixels wide, so the corner pixel sees only sky.
    let size = 128;
    scene.film.width = size;
    scene.film.height = size;
    scene.film.spp = 2;
    let (_lock, ctx) = gpu();
    let image = render(&ctx, &scene, 1);
    let half_view = 4.0 * 0.25f32.tan();
    let inside = (0.5 * size as f32 * (1.0 - 0.9 / half_view)) as u32;
    let (middle, last) = (size / 2, size - 1);
    for (x, y) in [(middle, middle), (inside, inside), (last - inside, middle), (middle, last - inside)] {
        // Its emission, plus what its (black-based, rough) dielectric coat reflects of the sky:
        // a little, the same in every channel.
        let p = image.get(x, y);
        let coat = p[0] - 2.0;
        let grey = (p[1] - 1.0 - coat).abs() < 1e-4 && (p[2] - 0.5 - coat).abs() < 1e-4;
        assert!((0.0..0.05).contains(&coat) && grey, "pixel ({x}, {y}) sees the emissive square: {p:?}");
    }
    assert_eq!(image.get(0, 0), [1.0, 1.0, 1.0], "the corner sees the white sky");
}

/// The square of [`write_square_gltf_with`] with base colour `base`, the given metallic and
/// roughness factors and, if given, a metallic-roughness texture (width x 1 texels of (G, B)).
fn write_metal_square_gltf(
    path: &std::path::Path,
    base: [f32; 3],
    metallic: f32,
    roughness: f32,
    texture: Option<&[(u8, u8)]>,
) {
    use base64::Engine as _;
    let (texture_json, textures) = match texture {
        Some(texels) => {
            let mut png = Vec::new();
            let mut encoder = png::Encoder::new(&mut png, texels.len() as u32, 1);
            encoder.set_color(png::ColorType::Rgb);
            let data: Vec<u8> = texels.iter().flat_map(|&(g, b)| [0, g, b]).collect();
            encoder.write_header().unwrap().write_image_data(&data).unwrap();
            (
                r#", "metallicRoughnessTexture": {"index": 0}"#.to_owned(),
                format!(
                    r#""textures": [{{"source": 0}}], "images": [{{"uri": "data:image/png;base64,{}"}}],"#,
                    base64::engine::general_purpose::STANDARD.encode(&png)
                ),
            )
        }
        None => (String::new(), String::new()),
    };
    let [r, g, b] = base;
    let material = format!(
        r#"{{"pbrMetallicRoughness": {{"baseColorFactor": [{r}, {g}, {b}, 1], "metallicFactor": {metallic}, "roughnessFactor": {roughness}{texture_json}}}}}"#
    );
    write_square_gltf_with(path, &material, &textures);
}

/// The metallic-roughness texture (linear; G = roughness, B = metallic, scaling factors 1 and 1)
/// sets R, T and roughness per texel: each of four bands of the texture renders as the same
/// square with its values given as factors, under a white sky. The smooth metal band reflects
/// exactly its F0, the base colour (Schlick's (1 - cos)^5 term is below 1e-7 at these angles);
/// the rough metal loses energy to GGX's single scattering, and the rough plastic's blue comes
/// from its coat alone, so swapping G and B, or ignoring the texture, fails.
#[test]
fn gltf_metallic_roughness_texture_matches_the_same_values_as_factors() {
    let dir = common::temp_dir("gltf-metallic-roughness");
    let base = [0.8, 0.4, 0.0];
    // (metallic, roughness) per band, left to right; each band is four texels wide. The last band's
    // values lie between 0 and 1, where decoding the (linear) texture as sRGB would change them.
    let half = 128.0f32 / 255.0;
    let bands = [(0.0, 1.0), (1.0, 0.0), (1.0, 1.0), (half, half)];
    let texels: Vec<(u8, u8)> =
        bands.iter().flat_map(|&(m, r)| [((r * 255.0).round() as u8, (m * 255.0).round() as u8); 4]).collect();
    let band_width = 1.0 / bands.len() as f32;
    let size = 64;
    let load = |name: &str, metallic: f32, roughness: f32, texture: Option<&[(u8, u8)]>| {
        let path = dir.join(name);
        write_metal_square_gltf(&path, base, metallic, roughness, texture);
        let mut scene = Scene::load(&path).expect("the glTF loads as a scene");
        (scene.film.width, scene.film.height, scene.film.spp) = (size, size, 32);
        scene
    };
    let textured = load("textured.gltf", 1.0, 1.0, Some(&texels));
    assert!(textured.materials[0].metallic_roughness.is_some());
    let (_lock, ctx) = gpu();
    let image = render(&ctx, &textured, 1);
    let rays = PinholeRays::new(&textured);
    for (band, &(metallic, roughness)) in bands.iter().enumerate() {
        let factors = load(&format!("band{band}.gltf"), metallic, roughness, None);
        let reference = render(&ctx, &factors, 2);
        // Pixels whose footprint lies inside the band's unfiltered middle (the bilinear filter
        // blends half a texel, 1/32 of the square, at each side, and a pixel spans 1/47 of it).
        let (u0, u1) = (band as f32 * band_width + 0.06, (band + 1) as f32 * band_width - 0.06);
        let mut diffs = [vec![], vec![], vec![]];
        let mut mean = [0.0f64; 3];
        for y in 0..size {
            for x in 0..size {
                let d = rays.dir(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                let p = rays.eye + (-1.0 - rays.eye.z) / d.z * d;
                let uv = Vec2::new(p.x + 1.0, 1.0 - p.y) / 2.0;
                if !(u0..u1).contains(&uv.x) || !(0.1..0.9).contains(&uv.y) {
                    continue;
                }
                let (got, want) = (image.get(x, y), reference.get(x, y));
                for c in 0..3 {
                    diffs[c].push(f64::from(got[c] - want[c]));
                    mean[c] += f64::from(got[c]);
                }
                if (metallic, roughness) == (1.0, 0.0) {
                    assert!(
                        (0..3).all(|c| (got[c] - base[c]).abs() < 1e-3),
                        "band {band}, pixel ({x}, {y}): smooth metal {got:?}, expected its F0 {base:?}"
                    );
                }
            }
        }
        let n = diffs[0].len() as f64;
        assert!(n > 200.0, "band {band}: only {n} pixels checked");
        for c in 0..3 {
            // Two independent renders: each difference has mean zero, so its second moment is its variance.
            let d = diffs[c].iter().sum::<f64>() / n;
            let stderr = (diffs[c].iter().map(|d| d * d).sum::<f64>() / n / n).sqrt();
            assert!(d.abs() <= 5.0 * stderr + 1e-4, "band {band} (metallic {metallic}, roughness {roughness}), channel {c}: textured mean {:.4} differs from the factors' by {d:.5} ({stderr:.5} standard error)", mean[c] / n);
        }
    }
}

/// A textured, normal-mapped sphere mesh (uv sphere) placed twice, under a lat-long sky with a
/// sun: every kind of array the renderer may split across bindings is non-trivial in size.
fn sphere_scene() -> Scene {
    let mut scene = parse(
        r#"
        camera = { position = [0, 0.4, 4], look_at = [0, 0, 0], fov = 40 }
        film = { width = 32, height = 32, spp = 3 }
        [materials.textured]
        albedo = [1, 1, 1]
        "#,
    );
    let (rings, segments) = (12u32, 16u32);
    let mut mesh = Mesh {
        name: "uv sphere".into(),
        positions: vec![],
        normals: vec![],
        uvs: vec![],
        tangents: vec![],
        colors: vec![],
        triangles: vec![],
        triangle_materials: vec![],
    };
    for r in 0..=rings {
        for s in 0..=segments {
            let (theta, phi) =
                (std::f32::consts::PI * r as f32 / rings as f32, std::f32::consts::TAU * s as f32 / segments as f32);
            let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            mesh.positions.push(n);
            mesh.normals.push(n);
            mesh.uvs.push(Vec2::new(s as f32 / segments as f32 * 2.0, r as f32 / rings as f32));
        }
    }
    let vertex = |r: u32, s: u32| r * (segments + 1) + s;
    for r in 0..rings {
        for s in 0..segments {
            mesh.triangles.push([vertex(r, s), vertex(r + 1, s), vertex(r + 1, s + 1)]);
            mesh.triangles.push([vertex(r, s), vertex(r + 1, s + 1), vertex(r, s + 1)]);
        }
    }
    mesh.triangle_materials = vec![0; mesh.triangles.len()];
    scene.meshes = vec![mesh];
    scene.instances = vec![
        Instance { mesh: 0, transform: Mat4::from_translation(Vec3::new(-0.9, 0.0, 0.0)) },
        Instance {
            mesh: 0,
            transform: Mat4::from_scale_rotation_translation(
                Vec3::splat(0.7),
                Quat::from_rotation_z(0.5),
                Vec3::new(1.0, 0.2, -0.5),
            ),
        },
    ];
    let texels: Vec<[u8; 4]> =
        (0..64 * 32u32).map(|i| [(i * 53 % 256) as u8, (i * 101 % 256) as u8, (255 - i % 256) as u8, 255]).collect();
    scene.textures =
        vec![Texture { name: "noise".into(), width: 64, height: 32, texels, srgb: true, wrap: Default::default() }];
    scene.materials[0].albedo_texture = Some(0);
    let mut sky = caustica::image::RgbImage::new(32, 16);
    for y in 0..16 {
        for x in 0..32 {
            let sun = if (x, y) == (9, 4) { 400.0 } else { 0.0 };
            sky.set(x, y, [0.3 + sun, 0.4 + 0.02 * y as f32, 0.6]);
        }
    }
    scene.environment = Environment::Map(EnvironmentMap {
        projection: MapProjection::LatLong,
        image: sky,
        intensity: 1.0,
        rotation_deg: 0.0,
    });
    scene
}

/// On a device whose storage and texel-buffer bindings see only 4 KiB, the BVH nodes, mesh
/// triangles (both texel buffers), texels,
/// environment map and accumulation image are each split across several
/// bindings, and the image is the same, bit for bit, as with every array in one binding.
#[test]
fn arrays_split_across_bindings_render_the_same_image() {
    let scene = sphere_scene();
    let accumulate = |limit: Option<u64>| {
        let (_lock, ctx) = common::gpu_with_storage_limit(limit);
        let mut r = caustica::render::Renderer::new(&ctx, &scene, 3).expect("scene uploads");
        r.render(scene.film.spp, |_| {}).expect("render succeeds without validation messages");
        (r.accumulation().expect("readback"), r.geometry.split_arrays.clone())
    };
    let (whole, unsplit) = accumulate(None);
    let (split, windows) = accumulate(Some(4096));
    assert!(unsplit.is_empty(), "nothing is split on the real device: {unsplit:?}");
    for name in ["BVH nodes", "mesh triangles", "textures", "environment map", "accumulation image"] {
        assert!(windows.iter().any(|&(n, w)| n == name && w > 1), "{name} split: {windows:?}");
    }
    assert!(whole.iter().any(|p| p[0] > 0.0), "the render sees something");
    assert!(whole == split, "split arrays give another image");
}

/// A scene whose buffers cannot fit the device fails before any upload, naming what needs how much.
#[test]
fn scene_too_large_for_the_device_fails_before_upload() {
    // Bindings of 64 KiB hold at most 8 windows, 512 KiB, of accumulation: 32768 pixels.
    let (_lock, ctx) = common::gpu_with_storage_limit(Some(64 << 10));
    let mut scene = Scene::default_scene();
    scene.film.width = 256;
    scene.film.height = 256;
    let e = format!("{:#}", caustica::render::Renderer::new(&ctx, &scene, 1).err().expect("too large for the device"));
    assert!(
        e.contains("accumulation image")
            && e.contains("1.0 MiB")
            && e.contains(&ctx.info.name)
            && e.contains("8 bindings of 0.1 MiB"),
        "{e}"
    );
}
