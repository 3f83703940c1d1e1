//! The kernel's form of a scene's participating media (shaders/medium.glsl): the `media` records
//! and the 8-bit codes by which materials, the camera and a path's medium stack name them
//! (MEDIUM_CODES in layout.rs).

use super::layout::{GpuMedium, MEDIUM_HETEROGENEOUS, MEDIUM_HOMOGENEOUS, MEDIUM_STACK_EMPTY, MEDIUM_VACUUM};
use crate::scene::{Medium, MAX_MEDIA};

/// The records of `media`, and every density grid's values one after another.
pub fn gpu_media(media: &[Medium]) -> (Vec<GpuMedium>, Vec<f32>) {
    let mut densities = Vec::new();
    let records = media
        .iter()
        .map(|medium| {
            let mut record = GpuMedium {
                sigma_t_g: medium.sigma_t.extend(medium.phase.g()).into(),
                albedo_kind: medium.albedo.extend(f32::from_bits(MEDIUM_HOMOGENEOUS)).into(),
                ..bytemuck::Zeroable::zeroed()
            };
            if let Some(grid) = &medium.density {
                let [x, y, z] = grid.resolution;
                record.albedo_kind[3] = f32::from_bits(MEDIUM_HETEROGENEOUS);
                record.grid = [densities.len() as u32, x, y, z];
                // Trilinear interpolation stays within the cells' values: their largest bounds it.
                let majorant = medium.sigma_t.max_element() * grid.max_value();
                record.box_min_majorant = grid.bounds.0.extend(majorant).into();
                record.box_max = grid.bounds.1.extend(0.0).into();
                densities.extend_from_slice(&grid.values);
            }
            record
        })
        .collect();
    (records, densities)
}

/// The code of the medium at `index` in the scene's media (its index + 1); `vacuum` for none:
/// MEDIUM_VACUUM where the code must name a medium (the camera's), MEDIUM_STACK_EMPTY where none
/// given means empty space anyway (a material's interior).
pub fn medium_code(index: Option<u32>, vacuum: u32) -> u32 {
    match index {
        Some(i) => {
            assert!((i as usize) < MAX_MEDIA, "scene::media_from caps the media at MAX_MEDIA");
            i + 1
        }
        None => vacuum,
    }
}

/// The camera's medium code (FrameParams::camera_medium).
pub fn camera_medium_code(index: Option<u32>) -> u32 {
    medium_code(index, MEDIUM_VACUUM)
}

/// A material's interior code, to be shifted into its flags (MATERIAL_INTERIOR_SHIFT).
pub fn interior_code(index: Option<u32>) -> u32 {
    medium_code(index, MEDIUM_STACK_EMPTY)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_leave_room_for_empty_and_vacuum() {
        assert_eq!(camera_medium_code(None), MEDIUM_VACUUM);
        assert_eq!(interior_code(None), MEDIUM_STACK_EMPTY);
        assert_eq!(interior_code(Some(0)), 1);
        assert_eq!(interior_code(Some(MAX_MEDIA as u32 - 1)), 254);
        // The last medium's code, MAX_MEDIA, stays below the vacuum's.
        const { assert!((MAX_MEDIA as u32) < MEDIUM_VACUUM) };
    }
}
