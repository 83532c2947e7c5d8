//! The text form of rays used by `rt-view cast` (`docs/command-line.md`): one ray a line,
//! `ox,oy,oz,dx,dy,dz`; blank lines and lines starting with `#` are skipped.
//! Numbers are parsed at the geometry's precision ([`Real`]).

use crate::math::ray::Ray;
use crate::math::real::{Real, Vec3};

/// A ray-line error: the 1-based line number and what is wrong with it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LineError {
    /// 1-based line number.
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

impl std::fmt::Display for LineError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.line, self.message)
    }
}

/// Parses every line of `text`: blank lines and `#` comments are skipped; any
/// other line must be a ray. Stops at the first bad line.
pub fn parse_rays(text: &str) -> Result<Vec<Ray>, LineError> {
    let mut rays = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let error = |message| LineError { line: i + 1, message };
        if let Some(ray) = parse_ray_line(line).map_err(error)? {
            rays.push(ray);
        }
    }
    Ok(rays)
}

/// One line: `Ok(None)` for a blank or `#` line, the ray for
/// `ox,oy,oz,dx,dy,dz` (finite numbers, spaces around them allowed, a
/// non-zero direction), or what is wrong.
pub fn parse_ray_line(line: &str) -> Result<Option<Ray>, String> {
    let line = line.trim();
    if line.is_empty() || line.starts_with('#') {
        return Ok(None);
    }
    let fields: Vec<&str> = line.split(',').map(str::trim).collect();
    if fields.len() != 6 {
        return Err(format!(
            "expected 6 comma-separated numbers ox,oy,oz,dx,dy,dz, found {} fields",
            fields.len()
        ));
    }
    let mut v = [0.0 as Real; 6];
    for (k, (slot, field)) in v.iter_mut().zip(&fields).enumerate() {
        let name = ["ox", "oy", "oz", "dx", "dy", "dz"][k];
        *slot = field.parse().map_err(|_| format!("{name} = \"{field}\" is not a number"))?;
        if !slot.is_finite() {
            return Err(format!("{name} = \"{field}\" is not finite"));
        }
    }
    let dir = Vec3::new(v[3], v[4], v[5]);
    if dir == Vec3::ZERO {
        let precision = std::any::type_name::<Real>();
        return Err(format!("the direction (dx,dy,dz) is zero (in {precision}, the geometry's precision)"));
    }
    Ok(Some(Ray::new(Vec3::new(v[0], v[1], v[2]), dir)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blank_and_comment_lines_are_skipped() {
        assert_eq!(parse_ray_line("   "), Ok(None));
        assert_eq!(parse_ray_line("# a comment"), Ok(None));
        assert_eq!(parse_ray_line("  # indented comment"), Ok(None));
    }

    #[test]
    fn a_ray_line_allows_spaces_exponents_and_signs() {
        let r = parse_ray_line(" 1, -2.5 ,3e2, 0,0 , -1e-3\r").unwrap().unwrap();
        assert_eq!(r, Ray::new(Vec3::new(1.0, -2.5, 300.0), Vec3::new(0.0, 0.0, -1e-3)));
    }

    #[test]
    fn malformed_lines_say_what_is_wrong() {
        let cases = [
            ("1,2,3,4,5", "found 5 fields"),
            ("1,2,3,4,5,6,7", "found 7 fields"),
            ("1,2,x,4,5,6", "oz = \"x\" is not a number"),
            ("1,2,3,,5,6", "dx = \"\" is not a number"),
            ("1,2,3,NaN,5,6", "dx = \"NaN\" is not finite"),
            ("1,2,inf,4,5,6", "oz = \"inf\" is not finite"),
            ("1,2,3,0,-0,0", "the direction (dx,dy,dz) is zero"),
            ("1e400,0,0,1,0,0", "ox = \"1e400\" is not finite"),
        ];
        for (line, expected) in cases {
            let e = parse_ray_line(line).unwrap_err();
            assert!(e.contains(expected), "{line}: {e}");
        }
    }

    #[test]
    fn errors_carry_the_line_number_counting_skipped_lines() {
        let e = parse_rays("# header\n0,0,0,0,0,1\n\n0,0,0,0,0\n").unwrap_err();
        assert_eq!(e.line, 4);
        assert_eq!(e.to_string(), "4: expected 6 comma-separated numbers ox,oy,oz,dx,dy,dz, found 5 fields");
    }
}
