//! The parsers of the numbers and points the subcommands take.
//!
//! Every option that takes a number takes a value that begins with `-` (`allow_negative_numbers`, or
//! `allow_hyphen_values` where the value may be `-.5`, `-inf` or more than one number), so that a
//! negative value reaches the option's parser and is refused with its range, rather than taken for an
//! option of its own.

use glam::Vec3;

/// A point or vector written `X,Y,Z`, each a finite number.
pub fn point(s: &str) -> Result<Vec3, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let [x, y, z] = parts[..] else {
        return Err(format!(
            "expected three numbers separated by commas, X,Y,Z (such as 0,1.5,-4), found \"{s}\""
        ));
    };
    Ok(Vec3::new(number(x.trim())?, number(y.trim())?, number(z.trim())?))
}

/// A finite number.
pub fn number(s: &str) -> Result<f32, String> {
    let v: f32 = s
        .parse()
        .map_err(|_| format!("expected a number, found \"{s}\""))?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("expected a finite number, found {s}"))
    }
}

/// A finite number of at least 0; `-0` is 0.
pub fn non_negative(s: &str) -> Result<f32, String> {
    let v = number(s)?;
    if v >= 0.0 {
        // -0 + 0 is +0: the value is the same for every later sign test, bit pattern or digest.
        Ok(v + 0.0)
    } else {
        Err(format!("expected a number of at least 0, found {s}"))
    }
}

/// A finite number above 0.
pub fn positive(s: &str) -> Result<f32, String> {
    let v = number(s)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("expected a number above 0, found {s}"))
    }
}

/// A whole number of 0 to `u64::MAX`, refused with that range when negative or larger (`u64`'s own
/// parser calls a minus sign an invalid digit).
pub fn whole(s: &str) -> Result<u64, String> {
    s.parse().map_err(|_| match s.parse::<i128>() {
        Ok(_) => format!("{s} is not in 0..={}", u64::MAX),
        Err(_) => format!("expected a whole number, found \"{s}\""),
    })
}

/// An image format named by `--output-format`.
pub fn image_format(s: &str) -> Result<whitted::image::film::ImageFormat, String> {
    whitted::image::film::ImageFormat::of(std::path::Path::new(&format!("x.{s}")))
        .map_err(|_| format!("expected png, ppm, jpg, jpeg or exr, found \"{s}\""))
}

/// A scene format named by `--format`.
pub fn scene_format(s: &str) -> Result<whitted::scene::Format, String> {
    whitted::scene::Format::named(s).ok_or_else(|| format!("expected p3f, nff, ply or obj, found \"{s}\""))
}

/// An angle of a field of view: above 0 and below 180 degrees.
pub fn angle(s: &str) -> Result<f32, String> {
    let v = number(s)?;
    if v > 0.0 && v < 180.0 {
        Ok(v)
    } else {
        Err(format!(
            "expected an angle between 0 and 180 degrees (both excluded), found {s}"
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_are_three_finite_numbers_separated_by_commas() {
        assert_eq!(point("1,2,3"), Ok(Vec3::new(1.0, 2.0, 3.0)));
        assert_eq!(point(" -1.5 , 0,2e3 "), Ok(Vec3::new(-1.5, 0.0, 2000.0)));
        let three = "expected three numbers separated by commas, X,Y,Z (such as 0,1.5,-4)";
        assert_eq!(point("1,2"), Err(format!("{three}, found \"1,2\"")));
        assert_eq!(point("1 2 3"), Err(format!("{three}, found \"1 2 3\"")));
        assert_eq!(point("1,2,3,4"), Err(format!("{three}, found \"1,2,3,4\"")));
        assert_eq!(point("1,x,3"), Err("expected a number, found \"x\"".to_string()));
        assert_eq!(
            point("1,inf,3"),
            Err("expected a finite number, found inf".to_string())
        );
    }

    #[test]
    fn negative_numbers_are_refused_with_the_range() {
        assert_eq!(non_negative("-0").map(f32::to_bits), Ok(0));
        assert_eq!(
            non_negative("-1"),
            Err("expected a number of at least 0, found -1".to_string())
        );
        assert_eq!(whole("18446744073709551615"), Ok(u64::MAX));
        let range = |v: &str| Err(format!("{v} is not in 0..=18446744073709551615"));
        assert_eq!(whole("-1"), range("-1"));
        assert_eq!(whole("18446744073709551616"), range("18446744073709551616"));
        assert_eq!(
            whole("1.5"),
            Err("expected a whole number, found \"1.5\"".to_string())
        );
    }
}
