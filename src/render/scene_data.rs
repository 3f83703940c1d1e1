//! Flattens a `Scene` into the arrays the kernel reads: the two-level acceleration structure,
//! materials, textures, the emitter list and the environment texels.

use super::acceleration::{gpu_primitive, Acceleration};
use super::bvh_width::BvhWidth;
use super::env_sampling::EnvDistribution;
use super::layout::*;
use super::light_selection::{area_light_power, emission_luminance, punctual_light_power, LightDistribution};
use super::light_tree::{LightBounds, LightTree, TreeLight};
use super::light_tree_index::KernelLightTree;
use super::textured_emission::mean_triangle_luminance;
use crate::scene::{
    average_fresnel, downsample_to_fit, Alpha, AlphaMode, Conductor, Environment, Light, LightSelection, MapProjection,
    Material, Microfacet, Scene, Shape, Texture, Wrap,
};
use glam::Vec3;

pub struct SceneData {
    pub acceleration: Acceleration,
    pub materials: Vec<GpuMaterial>,
    /// Every emitter in world space.
    pub lights: Vec<GpuPrimitive>,
    /// Point, spot and directional lights.
    pub punctual_lights: Vec<GpuPunctualLight>,
    /// How next-event estimation picks among `lights` and then `punctual_lights`
    /// (light_selection.rs).
    pub light_distribution: LightDistribution,
    /// The light tree that picks instead (light_tree.rs), where the scene asks for it and has
    /// more than one light; `None` otherwise.
    pub light_tree: Option<KernelLightTree>,
    /// Per entry of `acceleration.triangles`: a textured emitter's mean luminance (see
    /// `triangle_emission`); empty when no material has an emission texture.
    pub triangle_emission: Vec<f32>,
    pub textures: Vec<GpuTexture>,
    /// RGBA8 texels of every texture, packed little-endian (red in the low byte).
    pub texels: Vec<u32>,
    /// Texture bytes before any downsampling to the budget.
    pub texture_bytes_requested: u64,
    /// Environment map texels, top row first (one black texel for a constant sky).
    pub env_texels: Vec<[f32; 4]>,
    pub env_kind: u32,
    pub env_size: [u32; 2],
    /// Multiplier for a map, or the radiance of a constant sky.
    pub env_color: Vec3,
    pub env_rotation_deg: f32,
    /// The map's sampling distribution (env_sampling.rs); empty for a constant sky, a black map,
    /// or when the scene turns map sampling off.
    pub env_cdf: Vec<f32>,
    /// Participating media (media.rs), in the scene's order.
    pub media: Vec<GpuMedium>,
    /// The density grids of heterogeneous media, one after another.
    pub medium_densities: Vec<f32>,
}

/// An emitter in world space, with the luminance of its radiance that light selection weighs it by.
struct AreaLight {
    shape: Shape,
    luminance: f64,
    /// A mesh triangle's place in `mesh_triangles`, with TRIANGLE_LIGHT_MIRRORED when its placement
    /// mirrors it (and its vertices 1 and 2 were swapped to keep its front side): where a textured
    /// emitter's light sample finds its texture coordinates and mean luminance.
    mesh_triangle: Option<u32>,
}

impl AreaLight {
    /// The kernel's form (layout.glsl): the shape, a mesh triangle's place in a.w.
    fn gpu(&self) -> GpuPrimitive {
        let mut p = gpu_primitive(&self.shape);
        if let Some(bits) = self.mesh_triangle {
            p.a[3] = f32::from_bits(bits);
        }
        p
    }
}

/// Every emissive shape and every emissive triangle of every mesh instance, in world space.
/// `triangle_emission`: a textured emitter's mean luminance per entry of `mesh_triangles`.
fn world_lights(scene: &Scene, acceleration: &Acceleration, triangle_emission: &[f32]) -> Vec<AreaLight> {
    let emissive = |m: u32| scene.materials[m as usize].is_emissive();
    let mut lights: Vec<AreaLight> = scene
        .shapes
        .iter()
        .filter(|s| emissive(s.material()))
        .map(|&shape| AreaLight {
            shape,
            luminance: emission_luminance(&scene.materials[shape.material() as usize]),
            mesh_triangle: None,
        })
        .collect();
    for inst in &scene.instances {
        let mesh = &scene.meshes[inst.mesh as usize];
        let slots = &acceleration.triangle_slots[inst.mesh as usize];
        // A mirroring placement flips the winding; swap two vertices to keep the front side.
        let mirrored = inst.transform.determinant() < 0.0;
        for (t, (triangle, &m)) in
            mesh.triangles.iter().zip(&mesh.triangle_materials).enumerate().filter(|(_, (_, &m))| emissive(m))
        {
            let mut v = triangle.map(|i| inst.transform.transform_point3(mesh.positions[i as usize]));
            if mirrored {
                v.swap(1, 2);
            }
            let material = &scene.materials[m as usize];
            let slot = slots[t];
            let luminance = match material.maps.emission {
                Some(_) => triangle_emission[slot as usize] as f64,
                None => emission_luminance(material),
            };
            let mesh_triangle = Some(if mirrored { slot | TRIANGLE_LIGHT_MIRRORED } else { slot });
            lights.push(AreaLight { shape: Shape::Triangle { v, material: m }, luminance, mesh_triangle });
        }
    }
    lights
}

/// Per entry of `mesh_triangles`, for triangles of emissive materials with an emission texture:
/// the mean luminance of their textured emission (textured_emission.rs; 0 for other triangles).
/// Empty when no material has one. `textures` are the scene's as uploaded.
fn triangle_emission(scene: &Scene, acceleration: &Acceleration, textures: &[Texture]) -> Vec<f32> {
    let textured = |m: u32| {
        let material = &scene.materials[m as usize];
        material.maps.emission.filter(|_| material.is_emissive()).map(|t| (material.emission, &textures[t as usize]))
    };
    if !scene.materials.iter().enumerate().any(|(m, _)| textured(m as u32).is_some()) {
        return Vec::new();
    }
    let mut emission = vec![0.0; acceleration.triangles.len()];
    for (mesh, slots) in scene.meshes.iter().zip(&acceleration.triangle_slots) {
        for ((triangle, &m), &slot) in mesh.triangles.iter().zip(&mesh.triangle_materials).zip(slots) {
            if let Some((factor, texture)) = textured(m) {
                let uv = triangle.map(|i| mesh.uvs.get(i as usize).copied().unwrap_or_default());
                emission[slot as usize] = mean_triangle_luminance(texture, factor, uv) as f32;
            }
        }
    }
    emission
}

/// What the light tree knows of an area light of power `power`: its bounds and emission cone.
fn area_light_bounds(shape: &Shape, material: &Material, power: f64) -> TreeLight {
    let flat = |corners: &[Vec3], normal: Vec3| {
        LightBounds::flat(corners, normal.normalize_or_zero(), power, material.two_sided)
    };
    TreeLight::Bounded(match *shape {
        Shape::Sphere { center, radius, .. } => {
            LightBounds::omnidirectional(center - Vec3::splat(radius), center + Vec3::splat(radius), power)
        }
        Shape::Quad { origin, u, v, .. } => flat(&[origin, origin + u, origin + v, origin + u + v], u.cross(v)),
        Shape::Triangle { v, .. } => flat(&v, (v[1] - v[0]).cross(v[2] - v[0])),
    })
}

/// What the light tree knows of a point, spot or directional light of power `power`
/// (light_selection.rs): a spot's bounds carry the power of the point light it cuts its cone
/// from, 4 pi x intensity, since its cone bounds where that power goes (as pbrt-v4).
fn punctual_light_bounds(light: &Light, power: f64) -> TreeLight {
    match *light {
        Light::Point { position, .. } => TreeLight::Bounded(LightBounds::omnidirectional(position, position, power)),
        Light::Spot { position, axis, intensity, cone_angle, falloff_start } => {
            let phi = 4.0 * std::f64::consts::PI * super::luminance(&intensity.to_array());
            TreeLight::Bounded(LightBounds::spot(position, axis.normalize_or_zero(), cone_angle, falloff_start, phi))
        }
        Light::Directional { .. } => TreeLight::Infinite { power },
    }
}

/// A point, spot or directional light in the kernel's form (layout.glsl), with its power.
fn gpu_punctual_light(light: &Light, power: f64) -> GpuPunctualLight {
    let kind = |k: u32| f32::from_bits(k);
    let power = power as f32;
    match *light {
        Light::Point { position, intensity } => GpuPunctualLight {
            position_kind: position.extend(kind(LIGHT_POINT)).into(),
            axis_cos: [0.0, 0.0, 0.0, 1.0],
            value_power: intensity.extend(power).into(),
            shape: [0.0; 4],
        },
        Light::Spot { position, axis, intensity, cone_angle, falloff_start } => GpuPunctualLight {
            position_kind: position.extend(kind(LIGHT_SPOT)).into(),
            axis_cos: axis.extend(cone_angle.cos()).into(),
            value_power: intensity.extend(power).into(),
            shape: [cone_angle, falloff_start, 0.0, 0.0],
        },
        Light::Directional { direction, irradiance, angular_diameter } => {
            let half = 0.5 * angular_diameter as f64;
            // 1 - cos as 2 sin^2(half / 2): no cancellation for a sun-sized disk.
            let one_minus_cos = 2.0 * (0.5 * half).sin().powi(2);
            GpuPunctualLight {
                position_kind: [0.0, 0.0, 0.0, kind(LIGHT_DIRECTIONAL)],
                axis_cos: direction.extend(half.cos() as f32).into(),
                value_power: light.disk_radiance().unwrap_or(irradiance).extend(power).into(),
                shape: [0.0, 0.0, one_minus_cos as f32, 0.0],
            }
        }
    }
}

fn gpu_material(m: &Material) -> GpuMaterial {
    let (kind, eta, k) = match m.conductor {
        Conductor::Mirror => (CONDUCTOR_MIRROR, Vec3::ZERO, Vec3::ZERO),
        Conductor::Complex { eta, k } => (CONDUCTOR_COMPLEX, eta, k),
        Conductor::Albedo => (CONDUCTOR_ALBEDO, Vec3::ZERO, Vec3::ZERO),
    };
    let coat_norm = if m.coat { 1.0 / (1.0 - average_fresnel(m.ior)) } else { 0.0 };
    let texture_bits = |t: Option<u32>| f32::from_bits(t.unwrap_or(NO_TEXTURE));
    let metallic_roughness = match m.metallic_roughness {
        Some(mr) => [f32::from_bits(mr.texture), mr.metallic, mr.roughness, mr.transmission],
        None => [f32::from_bits(NO_TEXTURE), 0.0, 0.0, 0.0],
    };
    let (alpha_u, alpha_v) = m.microfacet_alphas();
    GpuMaterial {
        albedo_r: m.albedo.extend(m.reflectivity).into(),
        emission_t: m.emission.extend(m.transparency).into(),
        params: [
            m.ior,
            if m.two_sided { 1.0 } else { 0.0 },
            f32::from_bits(m.albedo_texture.unwrap_or(NO_TEXTURE)),
            alpha_u,
        ],
        conductor_eta: eta.extend(f32::from_bits(kind)).into(),
        conductor_k: k.extend(coat_norm).into(),
        metallic_roughness,
        maps: [
            texture_bits(m.maps.emission),
            texture_bits(m.maps.normal.map(|n| n.texture)),
            m.maps.normal.map_or(0.0, |n| n.scale),
            f32::from_bits(material_flags(m)),
        ],
        alpha: gpu_alpha(m.maps.alpha),
        coat: match m.clearcoat {
            Some(c) => [c.factor, c.roughness, texture_bits(c.texture), texture_bits(c.roughness_texture)],
            None => [0.0, 0.0, texture_bits(None), texture_bits(None)],
        },
        volume: m.attenuation.map_or(Vec3::ZERO, |a| a.sigma_a()).extend(alpha_v.unwrap_or(0.0)).into(),
    }
}

/// A material's MATERIAL_* flags (layout.glsl).
fn material_flags(m: &Material) -> u32 {
    let beckmann = if m.microfacet == Microfacet::Beckmann { MATERIAL_BECKMANN } else { 0 };
    let thin = if m.thin { MATERIAL_THIN } else { 0 };
    let one_sided = if m.one_sided { MATERIAL_ONE_SIDED } else { 0 };
    let coat_internal = if m.coat_internal_reflections { MATERIAL_COAT_INTERNAL } else { 0 };
    let null = if m.null_surface { MATERIAL_NULL } else { 0 };
    let interior = super::media::interior_code(m.interior) << MATERIAL_INTERIOR_SHIFT;
    beckmann | thin | one_sided | coat_internal | null | interior
}

/// A material's `alpha` row: texture, factor, cutoff and mode (layout.glsl).
fn gpu_alpha(alpha: Option<Alpha>) -> [f32; 4] {
    let texture_bits = |t: Option<u32>| f32::from_bits(t.unwrap_or(NO_TEXTURE));
    match alpha {
        None => [texture_bits(None), 1.0, 0.0, f32::from_bits(ALPHA_OPAQUE)],
        Some(Alpha { factor, texture, mode: AlphaMode::Mask { cutoff } }) => {
            [texture_bits(texture), factor, cutoff, f32::from_bits(ALPHA_MASK)]
        }
        Some(Alpha { factor, texture, mode: AlphaMode::Blend }) => {
            [texture_bits(texture), factor, 0.0, f32::from_bits(ALPHA_BLEND)]
        }
    }
}

impl SceneData {
    /// `texture_budget`: most bytes of texels to upload; larger texture sets are downsampled.
    pub fn new(scene: &Scene, texture_budget: u64) -> SceneData {
        Self::with_bvh_width(scene, texture_budget, BvhWidth::Four)
    }

    /// As [`SceneData::new`], the meshes' and shapes' BVHs in the node format `width` names
    /// (bvh_width.rs).
    pub fn with_bvh_width(scene: &Scene, texture_budget: u64, width: BvhWidth) -> SceneData {
        let acceleration = Acceleration::build_with(scene, width);
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(gpu_material).collect();
        let texture_bytes_requested = scene.textures.iter().map(|t| t.width as u64 * t.height as u64 * 4).sum();
        let mut textures = Vec::new();
        let mut texels = Vec::new();
        let mut fitted = scene.textures.clone();
        downsample_to_fit(&mut fitted, texture_budget);
        for t in &fitted {
            let wrap_bits = |w: Wrap| match w {
                Wrap::Repeat => TEXTURE_WRAP_REPEAT,
                Wrap::ClampToEdge => TEXTURE_WRAP_CLAMP,
                Wrap::MirroredRepeat => TEXTURE_WRAP_MIRROR,
            };
            let srgb = if t.srgb { TEXTURE_SRGB } else { 0 };
            let flags =
                srgb | wrap_bits(t.wrap[0]) << TEXTURE_WRAP_U_SHIFT | wrap_bits(t.wrap[1]) << TEXTURE_WRAP_V_SHIFT;
            textures.push(GpuTexture { offset: texels.len() as u32, width: t.width, height: t.height, flags });
            texels.extend(t.texels.iter().map(|&p| u32::from_le_bytes(p)));
        }
        let (env_texels, env_kind, env_size, env_color, env_rotation_deg) = match &scene.environment {
            Environment::Constant(c) => (vec![[0.0; 4]], ENV_CONSTANT, [1, 1], *c, 0.0),
            Environment::Map(map) => (
                map.image.pixels.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect(),
                match map.projection {
                    MapProjection::Angular => ENV_ANGULAR,
                    MapProjection::LatLong => ENV_LATLONG,
                },
                [map.image.width, map.image.height],
                Vec3::splat(map.intensity),
                map.rotation_deg,
            ),
        };
        let env_cdf = match &scene.environment {
            Environment::Map(map) if scene.integrator.sample_environment => EnvDistribution::new(map).cdf,
            _ => Vec::new(),
        };
        let triangle_emission = triangle_emission(scene, &acceleration, &fitted);
        let area_lights = world_lights(scene, &acceleration, &triangle_emission);
        let mut powers: Vec<f64> = area_lights
            .iter()
            .map(|l| area_light_power(&l.shape, &scene.materials[l.shape.material() as usize], l.luminance))
            .collect();
        let bounds = acceleration.bounds;
        let scene_radius = 0.5 * (bounds.max - bounds.min).as_dvec3().length();
        // An empty scene has empty (infinite) bounds.
        let scene_radius = if scene_radius.is_finite() { scene_radius } else { 0.0 };
        let punctual_powers: Vec<f64> = scene.lights.iter().map(|l| punctual_light_power(l, scene_radius)).collect();
        let mut punctual_lights: Vec<GpuPunctualLight> =
            scene.lights.iter().zip(&punctual_powers).map(|(l, &p)| gpu_punctual_light(l, p)).collect();
        let light_tree = (scene.integrator.light_selection == LightSelection::Bvh
            && area_lights.len() + scene.lights.len() > 1)
            .then(|| {
                let materials = &scene.materials;
                let bounds: Vec<TreeLight> = area_lights
                    .iter()
                    .zip(&powers)
                    .map(|(l, &p)| area_light_bounds(&l.shape, &materials[l.shape.material() as usize], p))
                    .chain(scene.lights.iter().zip(&punctual_powers).map(|(l, &p)| punctual_light_bounds(l, p)))
                    .collect();
                let tree = LightTree::build(&bounds);
                KernelLightTree::new(tree, scene, &acceleration, |m| materials[m as usize].is_emissive())
            });
        // A directional light's share beside the tree travels in its record (layout.rs).
        if let Some(t) = &light_tree {
            for (light, share) in punctual_lights.iter_mut().zip(&t.tree.infinite_share[area_lights.len()..]) {
                light.shape[3] = *share;
            }
        }
        powers.extend(&punctual_powers);
        let light_distribution =
            LightDistribution::new(&powers, scene.integrator.light_selection == LightSelection::Power);
        let lights = area_lights.iter().map(AreaLight::gpu).collect();
        let (media, medium_densities) = super::media::gpu_media(&scene.media);
        SceneData {
            media,
            medium_densities,
            env_cdf,
            lights,
            punctual_lights,
            light_distribution,
            light_tree,
            triangle_emission,
            acceleration,
            materials,
            textures,
            texels,
            texture_bytes_requested,
            env_texels,
            env_kind,
            env_size,
            env_color,
            env_rotation_deg,
        }
    }

    /// Bytes of GPU memory the scene needs (excluding the image).
    pub fn gpu_bytes(&self) -> u64 {
        self.acceleration.gpu_bytes()
            + self.texture_bytes()
            + (std::mem::size_of_val(&self.materials[..])
                + std::mem::size_of_val(&self.lights[..])
                + std::mem::size_of_val(&self.punctual_lights[..])
                + std::mem::size_of_val(&self.light_distribution.table[..])
                + std::mem::size_of_val(&self.triangle_emission[..])
                + std::mem::size_of_val(&self.env_texels[..])
                + std::mem::size_of_val(&self.env_cdf[..])
                + std::mem::size_of_val(&self.media[..])
                + std::mem::size_of_val(&self.medium_densities[..])) as u64
            + self.light_tree.as_ref().map_or(0, KernelLightTree::gpu_bytes)
    }

    /// Probability that next-event estimation samples the environment map rather than an emitter:
    /// a map with radiance shares it evenly with the emitters, and is not sampled without one.
    pub fn env_selection_probability(&self) -> f32 {
        match (self.env_cdf.is_empty(), self.lights.is_empty() && self.punctual_lights.is_empty()) {
            (true, _) => 0.0,
            (false, true) => 1.0,
            (false, false) => 0.5,
        }
    }

    /// Bytes of texels uploaded (after any downsampling).
    pub fn texture_bytes(&self) -> u64 {
        std::mem::size_of_val(&self.texels[..]) as u64
    }
}
