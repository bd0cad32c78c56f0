//! The closed-form optics of a Whitted tracer: mirror reflection, Snell refraction, Schlick's Fresnel
//! approximation and Beer's absorption. Directions are unit vectors; `n` faces the incoming ray.

use glam::Vec3;

use super::lanes::{Fx, Lanes, V3};

/// Mirror direction of `d` about `n`: `d - 2(d·n)n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    reflect_lanes::<f32, 1>(V3::splat(d), V3::splat(n)).lanes()[0]
}

/// Snell's law, `eta = eta_i / eta_t`: the refracted direction, or `None` under total internal reflection.
/// With cos θi = −d·n and sin²θt = eta²(1 − cos²θi): t = eta·d + (eta·cos θi − cos θt)·n
/// (Heckbert's form, as in pbrt-v4 `Refract`).
#[inline]
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let (t, total) = refract_lanes::<f32, 1>(V3::splat(d), V3::splat(n), Fx(eta));
    (total == 0).then(|| t.lanes()[0])
}

/// Schlick's approximation (Schlick 1994) of the Fresnel reflectance from a medium of index `eta_i` into
/// one of index `eta_t` at incidence cosine `cos_i`: K_r = R0 + (1 − R0)(1 − cos θ)^5 with
/// R0 = ((η_i − η_t)/(η_i + η_t))². Leaving a denser medium, θ is the transmitted angle (the larger one),
/// and beyond the critical angle the reflectance is 1.
#[inline]
pub fn schlick(cos_i: f32, eta_i: f32, eta_t: f32) -> f32 {
    schlick_lanes::<f32, 1>(Fx(cos_i), Fx(eta_i), Fx(eta_t)).0
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
#[inline(always)]
pub(crate) fn reflect_lanes<L: Lanes<N>, const N: usize>(d: V3<L, N>, n: V3<L, N>) -> V3<L, N> {
    d - n * (Fx::splat(2.0) * d.dot(n))
}

/// [`refract`] in each lane: the refracted directions, and the lanes under total internal
/// reflection as bits (their directions are not numbers).
#[inline(always)]
pub(crate) fn refract_lanes<L: Lanes<N>, const N: usize>(
    d: V3<L, N>,
    n: V3<L, N>,
    eta: Fx<L, N>,
) -> (V3<L, N>, u32) {
    let one = Fx::splat(1.0);
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (one - cos_i * cos_i).max(Fx::splat(0.0));
    let cos_t = (one - sin2_t).sqrt();
    (d * eta + n * (eta * cos_i - cos_t), sin2_t.ge(one))
}

/// [`schlick`] in each lane (its powers as products: x² = x·x, x⁵ = x·(x²)²).
#[inline(always)]
pub(crate) fn schlick_lanes<L: Lanes<N>, const N: usize>(
    cos_i: Fx<L, N>,
    eta_i: Fx<L, N>,
    eta_t: Fx<L, N>,
) -> Fx<L, N> {
    let one = Fx::splat(1.0);
    let q = (eta_i - eta_t) / (eta_i + eta_t);
    let r0 = q * q;
    let e = eta_i / eta_t;
    let sin2_t = e * e * (one - cos_i * cos_i).max(Fx::splat(0.0));
    let denser = eta_i.gt(eta_t);
    let c = one - Fx::blend(denser, (one - sin2_t).sqrt(), cos_i).clamp01();
    let c2 = c * c;
    let k = r0 + (one - r0) * (c * (c2 * c2));
    Fx::blend(denser & sin2_t.ge(one), one, k)
}

#[cfg(test)]
mod tests {
    use super::*;

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
