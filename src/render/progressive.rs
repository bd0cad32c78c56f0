//! Progressive rendering: passes of one jittered sample per pixel averaged into a running mean,
//! col_n = col_{n−1} + (c_n − col_{n−1}) / n, so that the film after n passes is the mean of n passes
//! (up to rounding) and can be shown or written at any point while it converges.

use super::film::Film;

/// The running mean of the passes so far.
#[derive(Clone, Debug)]
pub struct Progressive {
    film: Film,
    passes: u32,
}

impl Progressive {
    /// No pass yet: a black `width` × `height` film.
    pub fn new(width: u32, height: u32) -> Self {
        Progressive {
            film: Film::new(width, height),
            passes: 0,
        }
    }

    /// Folds in one more pass (of the same size).
    pub fn add(&mut self, pass: &Film) {
        assert_eq!(
            (pass.width, pass.height),
            (self.film.width, self.film.height),
            "a pass of another size"
        );
        self.passes += 1;
        let inv = 1.0 / self.passes as f32;
        for (mean, c) in self.film.pixels.iter_mut().zip(&pass.pixels) {
            *mean += (*c - *mean) * inv;
        }
    }

    /// Passes averaged so far.
    pub fn passes(&self) -> u32 {
        self.passes
    }

    /// The mean so far.
    pub fn film(&self) -> &Film {
        &self.film
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn running_mean_is_the_mean() {
        let mut p = Progressive::new(2, 1);
        let values = [0.25f32, 1.0, 0.0, 0.5, 0.75];
        for (i, v) in values.iter().enumerate() {
            let mut f = Film::new(2, 1);
            f.pixels = vec![Vec3::splat(*v), Vec3::new(i as f32, 0.0, 1.0)];
            p.add(&f);
        }
        assert_eq!(p.passes(), 5);
        let mean = values.iter().sum::<f32>() / 5.0;
        assert!((p.film().pixels[0] - Vec3::splat(mean)).abs().max_element() < 1e-6);
        assert!(
            (p.film().pixels[1] - Vec3::new(2.0, 0.0, 1.0))
                .abs()
                .max_element()
                < 1e-6
        );
    }
}
