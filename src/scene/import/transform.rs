//! A foreign object-to-world matrix as caustica's mesh placement (scale, then rotation about x,
//! y and z, then translation), which cannot hold a shear: a matrix that is not such a product
//! (a non-uniform scale applied after a rotation) is refused rather than distorted.

use super::super::format::{Array, Placement, Scale};
use anyhow::{bail, Result};
use glam::{DMat4, EulerRot, Mat4, Quat, Vec3};

/// The placement equal to `m` up to float rounding, or an error saying why there is none.
pub fn placement(m: DMat4) -> Result<Placement> {
    let (scale, rotation, translation) = m.as_mat4().to_scale_rotation_translation();
    let (z, y, x) = rotation.to_euler(EulerRot::ZYX);
    // + 0.0 turns -0 into 0, for the converted file's sake.
    let rotate = Vec3::new(x, y, z) * (180.0 / std::f32::consts::PI) + Vec3::ZERO;
    let placement = Placement {
        translate: Array(translation.to_array()),
        scale: Some(if scale.x == scale.y && scale.y == scale.z {
            Scale::Uniform(scale.x)
        } else {
            Scale::PerAxis(Array(scale.to_array()))
        }),
        rotate: Array(rotate.to_array()),
    };
    // Rebuilt as scene::placement builds it, the matrix must come back.
    let rebuilt = Mat4::from_scale_rotation_translation(
        scale,
        Quat::from_euler(EulerRot::ZYX, rotate.z.to_radians(), rotate.y.to_radians(), rotate.x.to_radians()),
        translation,
    )
    .as_dmat4();
    let size = m.to_cols_array().iter().fold(1.0f64, |a, v| a.max(v.abs()));
    let error = (rebuilt - m).to_cols_array().iter().fold(0.0f64, |a, v| a.max(v.abs()));
    if error.is_nan() || error > 1e-4 * size || scale.x * scale.y * scale.z == 0.0 {
        bail!("its transformation is not a scale, rotation and translation (a shear, a zero scale, or a non-uniform scale after a rotation), which caustica cannot place a mesh by");
    }
    Ok(placement)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn rebuilt(p: &Placement) -> DMat4 {
        let s = match p.scale {
            Some(Scale::Uniform(s)) => Vec3::splat(s),
            Some(Scale::PerAxis(Array(s))) => Vec3::from(s),
            None => Vec3::ONE,
        };
        let r = Vec3::from(p.rotate.0);
        Mat4::from_scale_rotation_translation(
            s,
            Quat::from_euler(EulerRot::ZYX, r.z.to_radians(), r.y.to_radians(), r.x.to_radians()),
            Vec3::from(p.translate.0),
        )
        .as_dmat4()
    }

    #[test]
    fn scale_rotation_translation_products_come_back() {
        let m = DMat4::from_translation(DVec3::new(1.0, -2.0, 3.0))
            * DMat4::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 0.7)
            * DMat4::from_scale(DVec3::new(2.0, 0.5, 3.0));
        let p = placement(m).unwrap();
        assert!(rebuilt(&p).abs_diff_eq(m, 1e-5), "{p:?}");
        // A mirror too.
        let mirrored = m * DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0));
        assert!(rebuilt(&placement(mirrored).unwrap()).abs_diff_eq(mirrored, 1e-5));
    }

    #[test]
    fn a_shear_is_refused() {
        let sheared = DMat4::from_scale(DVec3::new(3.0, 1.0, 1.0)) * DMat4::from_rotation_z(0.5);
        assert!(placement(sheared).unwrap_err().to_string().contains("shear"));
        assert!(placement(DMat4::from_scale(DVec3::new(1.0, 0.0, 1.0))).is_err());
    }
}
