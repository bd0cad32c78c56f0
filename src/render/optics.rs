//! The closed-form optics of a Whitted tracer: mirror reflection, Snell refraction, Schlick's Fresnel
//! approximation and Beer's absorption. Directions are unit vectors; `n` faces the incoming ray.

use glam::Vec3;
use wide::f32x8;

use super::lanes::Vec3x8;

/// Mirror direction of `d` about `n`: `d - 2(d·n)n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Snell's law, `eta = eta_i / eta_t`: the refracted direction, or `None` under total internal reflection.
/// With cos θi = −d·n and sin²θt = eta²(1 − cos²θi): t = eta·d + (eta·cos θi − cos θt)·n
/// (Heckbert's form, as in pbrt-v4 `Refract`).
#[inline]
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(eta * d + (eta * cos_i - cos_t) * n)
}

/// Schlick's approximation (Schlick 1994) of the Fresnel reflectance from a medium of index `eta_i` into
/// one of index `eta_t` at incidence cosine `cos_i`: K_r = R0 + (1 − R0)(1 − cos θ)^5 with
/// R0 = ((η_i − η_t)/(η_i + η_t))². Leaving a denser medium, θ is the transmitted angle (the larger one),
/// and beyond the critical angle the reflectance is 1.
#[inline]
pub fn schlick(cos_i: f32, eta_i: f32, eta_t: f32) -> f32 {
    let r0 = ((eta_i - eta_t) / (eta_i + eta_t)).powi(2);
    let cos = if eta_i > eta_t {
        let sin2_t = (eta_i / eta_t).powi(2) * (1.0 - cos_i * cos_i).max(0.0);
        if sin2_t >= 1.0 {
            return 1.0;
        }
        (1.0 - sin2_t).sqrt()
    } else {
        cos_i
    };
    r0 + (1.0 - r0) * (1.0 - cos.clamp(0.0, 1.0)).powi(5)
}

/// Beer–Lambert attenuation over `distance` inside a medium whose colour is `color`: the absorption
/// coefficient is a = −ln(color) per scene unit, so I = I0·e^(−a·d) = I0·color^d. A white medium absorbs
/// nothing; a channel of 0.5 keeps half its light per unit travelled.
#[inline]
pub fn beer(color: Vec3, distance: f32) -> Vec3 {
    let absorption = -color.clamp(Vec3::splat(1e-6), Vec3::ONE).map(f32::ln);
    (-absorption * distance).map(f32::exp)
}

/// [`reflect`] in each lane.
#[inline]
pub(crate) fn reflect8(d: Vec3x8, n: Vec3x8) -> Vec3x8 {
    d - n * (f32x8::splat(2.0) * d.dot(n))
}

/// [`refract`] in each lane: the refracted directions, and the lanes under total internal
/// reflection as a lane mask (their directions are not numbers).
#[inline]
pub(crate) fn refract8(d: Vec3x8, n: Vec3x8, eta: f32x8) -> (Vec3x8, f32x8) {
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (f32x8::ONE - cos_i * cos_i).max(f32x8::ZERO);
    let cos_t = (f32x8::ONE - sin2_t).sqrt();
    (d * eta + n * (eta * cos_i - cos_t), sin2_t.simd_ge(f32x8::ONE))
}

/// [`schlick`] in each lane (its powers as the same products: x² = x·x, x⁵ = x·(x²)²).
#[inline]
pub(crate) fn schlick8(cos_i: f32x8, eta_i: f32x8, eta_t: f32x8) -> f32x8 {
    let q = (eta_i - eta_t) / (eta_i + eta_t);
    let r0 = q * q;
    let e = eta_i / eta_t;
    let sin2_t = e * e * (f32x8::ONE - cos_i * cos_i).max(f32x8::ZERO);
    let denser = eta_i.simd_gt(eta_t);
    let c = f32x8::ONE - clamp01(denser.select((f32x8::ONE - sin2_t).sqrt(), cos_i));
    let c2 = c * c;
    let k = r0 + (f32x8::ONE - r0) * (c * (c2 * c2));
    (denser & sin2_t.simd_ge(f32x8::ONE)).select(f32x8::ONE, k)
}

/// `x.clamp(0.0, 1.0)` in each lane (a NaN stays NaN).
#[inline]
pub(crate) fn clamp01(x: f32x8) -> f32x8 {
    let x = x.simd_lt(f32x8::ZERO).select(f32x8::ZERO, x);
    x.simd_gt(f32x8::ONE).select(f32x8::ONE, x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sampler::Sampler;

    /// The lanes forms give the scalar forms' bits, lane by lane, on random unit directions and
    /// normals at both sides of the critical angle, entering and leaving.
    #[test]
    fn lanes_are_the_scalar_bits() {
        let mut rng = Sampler::new(3, 1, 0, 1);
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        let (mut tir, mut through) = (0, 0);
        for round in 0..2_000 {
            let d: [Vec3; 8] = std::array::from_fn(|_| rng.in_unit_ball().normalize_or(Vec3::X));
            let n: [Vec3; 8] = std::array::from_fn(|k| {
                rng.in_unit_ball().normalize_or(Vec3::Y) * -d[k].dot(Vec3::ONE).signum()
            });
            let eta_i: [f32; 8] = std::array::from_fn(|k| {
                if (round + k) % 2 == 0 {
                    1.0
                } else {
                    1.0 + rng.uniform()
                }
            });
            let eta_t: [f32; 8] = std::array::from_fn(|k| {
                if (round + k) % 2 == 0 {
                    1.0 + rng.uniform()
                } else {
                    1.0
                }
            });
            let cos_i: [f32; 8] = std::array::from_fn(|k| (-d[k].dot(n[k])).clamp(0.0, 1.0));
            let (dl, nl) = (Vec3x8::from_lanes(&d), Vec3x8::from_lanes(&n));
            let eta: [f32; 8] = std::array::from_fn(|k| eta_i[k] / eta_t[k]);
            let reflected = reflect8(dl, nl);
            let (refracted, total) = refract8(dl, nl, f32x8::from(eta));
            let total = total.to_bitmask();
            let kr = schlick8(f32x8::from(cos_i), f32x8::from(eta_i), f32x8::from(eta_t)).to_array();
            let clamped = clamp01(-dl.dot(nl)).to_array();
            for k in 0..8 {
                assert_eq!(bits(reflected.lane(k)), bits(reflect(d[k], n[k])));
                match refract(d[k], n[k], eta[k]) {
                    Some(t) => {
                        assert_eq!(total >> k & 1, 0);
                        assert_eq!(bits(refracted.lane(k)), bits(t));
                        through += 1;
                    }
                    None => {
                        assert_eq!(total >> k & 1, 1);
                        tir += 1;
                    }
                }
                assert_eq!(kr[k].to_bits(), schlick(cos_i[k], eta_i[k], eta_t[k]).to_bits());
                assert_eq!(clamped[k].to_bits(), cos_i[k].to_bits());
            }
        }
        assert!(tir > 1_000 && through > 1_000, "{tir} {through}");
        let odd = f32x8::from([-1.0, -0.0, 0.0, 0.5, 1.0, 2.0, f32::NAN, f32::INFINITY]);
        for (got, x) in clamp01(odd).to_array().iter().zip(odd.to_array()) {
            assert_eq!(got.to_bits(), x.clamp(0.0, 1.0).to_bits());
        }
    }

    #[test]
    fn reflection_is_a_mirror() {
        let d = Vec3::new(1.0, -1.0, 0.0).normalize();
        let r = reflect(d, Vec3::Y);
        assert!((r - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
    }

    /// Snell's law at 30° into glass (η = 1.5): sin θt = sin 30° / 1.5 = 1/3.
    #[test]
    fn snell_angles() {
        let theta = 30f32.to_radians();
        let d = Vec3::new(theta.sin(), -theta.cos(), 0.0);
        let t = refract(d, Vec3::Y, 1.0 / 1.5).unwrap();
        assert!((t.length() - 1.0).abs() < 1e-6);
        let sin_t = t.x;
        assert!((sin_t - 1.0 / 3.0).abs() < 1e-6, "{sin_t}");
        assert!(t.y < 0.0);
        // And back out again: the original angle.
        let back = refract(t, Vec3::Y, 1.5).unwrap();
        assert!((back - d).length() < 1e-5);
    }

    /// Leaving glass (η = 1.5) the critical angle is asin(1/1.5) ≈ 41.8°: below it light refracts, above it
    /// everything reflects, and Schlick says 1.
    #[test]
    fn total_internal_reflection() {
        let critical = (1.0f32 / 1.5).asin();
        for (deg, tir) in [
            (critical.to_degrees() - 1.0, false),
            (critical.to_degrees() + 1.0, true),
        ] {
            let a = deg.to_radians();
            let d = Vec3::new(a.sin(), -a.cos(), 0.0);
            assert_eq!(refract(d, Vec3::Y, 1.5).is_none(), tir, "{deg}°");
            assert_eq!(schlick(a.cos(), 1.5, 1.0) == 1.0, tir, "{deg}°");
        }
    }

    /// Fresnel at normal incidence is R0 = ((1 − 1.5)/(1 + 1.5))² = 0.04, and tends to 1 at grazing.
    #[test]
    fn fresnel_limits() {
        assert!((schlick(1.0, 1.0, 1.5) - 0.04).abs() < 1e-7);
        assert!((schlick(1.0, 1.5, 1.0) - 0.04).abs() < 1e-7);
        assert!(schlick(1e-4, 1.0, 1.5) > 0.999);
        // Monotonic in between.
        let mut last = 0.0;
        for i in (0..=100).rev() {
            let k = schlick(i as f32 / 100.0, 1.0, 1.5);
            assert!(k >= last);
            last = k;
        }
    }

    #[test]
    fn beer_law() {
        let a = beer(Vec3::new(0.5, 1.0, 0.25), 2.0);
        assert!((a - Vec3::new(0.25, 1.0, 0.0625)).length() < 1e-6);
        assert_eq!(beer(Vec3::ONE, 100.0), Vec3::ONE);
        // e^(−a·d) with a = −ln 0.8 over d = 3.7.
        let want = (0.8f32.ln() * 3.7).exp();
        assert!((beer(Vec3::splat(0.8), 3.7).x - want).abs() < 1e-6);
    }
}
