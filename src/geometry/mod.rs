//! Ray-primitive intersection routines, each closed-form and scalar; the accelerators call them.

pub mod aabb;
pub mod cone;
pub mod cuboid;
pub mod plane;
pub mod ray;
pub mod sphere;
pub mod triangle;
