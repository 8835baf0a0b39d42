//! Wavefront OBJ, the subset panels travel in between grade3d and peer
//! tools (`benches/peer_flatten.py`): `v x y z`, optional `vt u v`, and
//! `f` with 1-based (or negative, relative) indices, `v/vt/vn` forms
//! accepted; polygons are fan-triangulated. Everything else is ignored.
//!
//! Failure modes: [`ObjError`] naming the line — a malformed number, a
//! face with fewer than three corners, an index out of range.

use std::fmt::Write;

use glam::{DVec2, DVec3};

/// Why an OBJ text could not be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ObjError {
    /// A number did not parse.
    #[error("line {line}: malformed number '{text}'")]
    Number {
        /// 1-based line.
        line: usize,
        /// The text.
        text: String,
    },
    /// A face with fewer than three corners.
    #[error("line {line}: a face needs three corners")]
    ShortFace {
        /// 1-based line.
        line: usize,
    },
    /// A vertex index out of range.
    #[error("line {line}: vertex index {index} out of range (1..={count})")]
    Index {
        /// 1-based line.
        line: usize,
        /// The index as written.
        index: i64,
        /// Vertices defined so far.
        count: usize,
    },
}

/// Reads positions and triangles.
///
/// # Errors
/// [`ObjError`].
pub fn read_obj(text: &str) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), ObjError> {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut it = raw.split_whitespace();
        match it.next() {
            Some("v") => {
                let mut c = [0.0; 3];
                for x in &mut c {
                    let t = it.next().unwrap_or("");
                    *x = t
                        .parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| ObjError::Number { line, text: t.to_string() })?;
                }
                positions.push(DVec3::from_array(c));
            }
            Some("f") => {
                let mut corners = Vec::new();
                for t in it {
                    let head = t.split('/').next().unwrap_or("");
                    let index: i64 = head.parse().map_err(|_| ObjError::Number { line, text: t.to_string() })?;
                    let count = positions.len();
                    let resolved = if index > 0 { index - 1 } else { count as i64 + index };
                    if resolved < 0 || resolved >= count as i64 {
                        return Err(ObjError::Index { line, index, count });
                    }
                    corners.push(resolved as u32);
                }
                if corners.len() < 3 {
                    return Err(ObjError::ShortFace { line });
                }
                for k in 1..corners.len() - 1 {
                    triangles.push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            _ => {}
        }
    }
    Ok((positions, triangles))
}

/// Writes positions, optional texture coordinates (one per vertex) and triangles.
pub fn write_obj(positions: &[DVec3], uv: Option<&[DVec2]>, triangles: &[[u32; 3]]) -> String {
    let mut s = String::with_capacity(48 * (positions.len() + triangles.len()));
    for p in positions {
        let _ = writeln!(s, "v {:.9} {:.9} {:.9}", p.x, p.y, p.z);
    }
    if let Some(uv) = uv {
        for t in uv {
            let _ = writeln!(s, "vt {:.9} {:.9}", t.x, t.y);
        }
    }
    for t in triangles {
        let [a, b, c] = t.map(|v| v + 1);
        if uv.is_some() {
            let _ = writeln!(s, "f {a}/{a} {b}/{b} {c}/{c}");
        } else {
            let _ = writeln!(s, "f {a} {b} {c}");
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_polygons() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::ONE];
        let text = write_obj(&p, Some(&[DVec2::ZERO; 4]), &[[0, 1, 2], [1, 3, 2]]);
        assert_eq!(read_obj(&text).unwrap(), (p, vec![[0, 1, 2], [1, 3, 2]]));
        let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 -1\n";
        assert_eq!(read_obj(quad).unwrap().1, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn bad_lines_are_named() {
        assert_eq!(read_obj("v 0 0 x\n").unwrap_err(), ObjError::Number { line: 1, text: "x".into() });
        assert_eq!(read_obj("v 0 0 0\nf 1 2 3\n").unwrap_err(), ObjError::Index { line: 2, index: 2, count: 1 });
        assert_eq!(read_obj("v 0 0 0\nf 1 1\n").unwrap_err(), ObjError::ShortFace { line: 2 });
        assert!(read_obj("v 0 0 nan\n").is_err());
    }
}
