//! URDF `<origin xyz rpy>` as an isometry.
//!
//! `xyz` in metres, `rpy` in radians, fixed-axis roll about x, then pitch
//! about y, then yaw about z: R = Rz(yaw) Ry(pitch) Rx(roll), which is
//! nalgebra's `Rotation3::from_euler_angles(roll, pitch, yaw)`.

use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

use crate::error::Problem;

/// The transform from the parent frame to the frame `origin` places.
pub(crate) fn isometry(origin: &urdf_rs::Pose) -> Result<Isometry3<f64>, Problem> {
    let [x, y, z] = finite(*origin.xyz, "origin xyz")?;
    let [roll, pitch, yaw] = finite(*origin.rpy, "origin rpy")?;
    Ok(Isometry3::from_parts(
        Translation3::new(x, y, z),
        UnitQuaternion::from_euler_angles(roll, pitch, yaw),
    ))
}

/// `v` if all three numbers are finite, else [`Problem::NonFinite`] naming `what`.
pub(crate) fn finite(v: [f64; 3], what: &'static str) -> Result<[f64; 3], Problem> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(v)
    } else {
        Err(Problem::NonFinite(what))
    }
}

/// `v` as a vector, checked finite.
pub(crate) fn vector(v: [f64; 3], what: &'static str) -> Result<Vector3<f64>, Problem> {
    finite(v, what).map(Vector3::from)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    #[test]
    fn rpy_is_rz_ry_rx() {
        let pose = urdf_rs::Pose {
            xyz: urdf_rs::Vec3([0.1, -0.2, 0.3]),
            rpy: urdf_rs::Vec3([0.3, -0.7, 1.1]),
        };
        let iso = isometry(&pose).unwrap();
        let rx = Rotation3::from_axis_angle(&Vector3::x_axis(), 0.3);
        let ry = Rotation3::from_axis_angle(&Vector3::y_axis(), -0.7);
        let rz = Rotation3::from_axis_angle(&Vector3::z_axis(), 1.1);
        let expected = rz * ry * rx;
        let got = iso.rotation.to_rotation_matrix();
        assert!((got.matrix() - expected.matrix()).abs().max() < 1e-12);
        assert_eq!(iso.translation.vector, Vector3::new(0.1, -0.2, 0.3));
    }

    #[test]
    fn nan_is_refused() {
        let pose = urdf_rs::Pose {
            xyz: urdf_rs::Vec3([f64::NAN, 0.0, 0.0]),
            rpy: urdf_rs::Vec3([0.0; 3]),
        };
        assert_eq!(isometry(&pose), Err(Problem::NonFinite("origin xyz")));
    }
}
