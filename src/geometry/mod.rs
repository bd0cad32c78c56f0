//! Ray-primitive intersection routines, each closed-form and scalar; the accelerators call them.

pub mod aabb;
pub mod cone;
pub mod cuboid;
pub mod plane;
pub mod ray;
pub mod sphere;
pub mod triangle;

use glam::Vec3;

/// `v`'s length and unit direction, without overflow or underflow: a vector whose squared length
/// leaves `f32`'s normal range (a camera 2e19 units from its target squares to 4e38, past `f32::MAX`)
/// is divided by its largest component first. Every other vector takes the plain path, bit for bit,
/// so images do not change. The direction of a zero or non-finite vector is not finite.
pub fn length_and_direction(v: Vec3) -> (f32, Vec3) {
    let squared = v.length_squared();
    if squared.is_normal() {
        // glam's `length` and `normalize` (a multiply by the reciprocal), operation for operation.
        let length = squared.sqrt();
        return (length, v * (1.0 / length));
    }
    let scale = v.abs().max_element();
    let unit = v / scale;
    let length = unit.length();
    (scale * length, unit / length)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn huge_and_tiny_vectors_keep_their_direction() {
        let (l, d) = length_and_direction(Vec3::new(0.0, 2e19, 0.0));
        assert_eq!((l, d), (2e19, Vec3::Y));
        let (l, d) = length_and_direction(Vec3::new(3e30, 4e30, 0.0));
        assert!((l / 5e30 - 1.0).abs() < 1e-6 && (d - Vec3::new(0.6, 0.8, 0.0)).length() < 1e-6);
        let (l, d) = length_and_direction(Vec3::new(3e-30, 0.0, -4e-30));
        assert!((l / 5e-30 - 1.0).abs() < 1e-6 && (d - Vec3::new(0.6, 0.0, -0.8)).length() < 1e-6);
        // In range: exactly glam's length and normalize.
        let v = Vec3::new(1.5, -2.25, 7.0);
        assert_eq!(length_and_direction(v), (v.length(), v.normalize()));
        assert!(!length_and_direction(Vec3::ZERO).1.is_finite());
    }
}
