//! The kernel's frame parameters (its uniform block `frame`, layout.rs's FrameParams) for a
//! scene: its camera, film, integrator settings and the counts of what its data holds.

use super::layout::{
    FrameParams, FILTER_BOX, FILTER_GAUSSIAN, FILTER_TENT, INSTANCE_PRIMITIVES, SAMPLER_INDEPENDENT, SAMPLER_SOBOL,
};
use super::scene_data::SceneData;
use crate::scene::{Camera, Filter, Sampler, Scene};
use bytemuck::Zeroable;

/// Most texel bytes uploaded; larger texture sets are downsampled to fit (and say so). The same
/// bound caps one decoded texture (a larger one could never be uploaded whole).
pub const TEXTURE_BUDGET_BYTES: u64 = crate::scene::MAX_TEXTURE_BYTES;

/// The kernel's frame parameters (its uniform block `frame`) for `scene`, flattened as `data`,
/// with this seed.
pub fn frame_params(scene: &Scene, data: &SceneData, seed: u32) -> FrameParams {
    let mut params = frame_params_without_camera(scene, data, seed);
    set_camera_params(&mut params, &scene.camera);
    params
}

/// Writes the camera's fields of `params` (the film size must already be there).
pub(super) fn set_camera_params(params: &mut FrameParams, cam: &Camera) {
    let forward = (cam.look_at - cam.position).normalize();
    let right = forward.cross(cam.up).normalize();
    let up = right.cross(forward);
    params.cam_origin = cam.position.into();
    params.cam_forward = forward.into();
    params.tan_half_fov = (cam.fov_deg.to_radians() * 0.5).tan();
    params.cam_right = right.into();
    params.aspect = params.width as f32 / params.height as f32;
    params.cam_up = up.into();
    params.lens_radius = cam.aperture;
    params.focus_distance = cam.focus_distance;
}

fn frame_params_without_camera(scene: &Scene, data: &SceneData, seed: u32) -> FrameParams {
    let rot = data.env_rotation_deg.to_radians();
    let i = &scene.integrator;
    let filter = match scene.film.filter {
        Filter::Box => FILTER_BOX,
        Filter::Tent => FILTER_TENT,
        Filter::Gaussian => FILTER_GAUSSIAN,
    };
    let sampler = match i.sampler {
        Sampler::Independent => SAMPLER_INDEPENDENT,
        Sampler::Sobol => SAMPLER_SOBOL,
    };
    FrameParams {
        env_color: data.env_color.into(),
        env_rotation: [rot.cos(), rot.sin()],
        env_selection_probability: data.env_selection_probability(),
        width: scene.film.width,
        height: scene.film.height,
        seed,
        light_count: data.lights.len() as u32,
        rr_start: i.rr_start,
        nee: u32::from(i.nee),
        env_kind: data.env_kind,
        max_bounces: i.max_bounces,
        env_width: data.env_size[0],
        env_height: data.env_size[1],
        instance_count: data.acceleration.instances.len() as u32,
        node_count: data.acceleration.stats.nodes as u32,
        rr_absorption: i.absorption.unwrap_or(-1.0),
        rr_survival_min: 0.05,
        rr_survival_max: 0.95,
        radiance_clamp: i.clamp.unwrap_or(0.0),
        pixel_filter: filter,
        sampler_kind: sampler,
        light_total_power: data.light_distribution.total_power,
        light_tree_share: data.light_tree.as_ref().map_or(0.0, |t| t.tree.tree_share),
        light_tree: u32::from(data.light_tree.is_some()),
        punctual_light_count: data.punctual_lights.len() as u32,
        shape_instance: data
            .acceleration
            .instances
            .iter()
            .position(|i| i.info[0] == INSTANCE_PRIMITIVES)
            .map_or(u32::MAX, |i| i as u32),
        camera_medium: super::media::camera_medium_code(scene.camera_medium),
        ..FrameParams::zeroed()
    }
}
