//! Wavefront OBJ, the subset panels travel in between grade3d and peer
//! tools (`benches/peer_flatten.py`): `v x y z`, optional `vt u v`, and
//! `f` with 1-based (or negative, relative) indices, `v/vt/vn` forms
//! accepted; polygons are fan-triangulated; `g`/`o` groups name the pieces
//! of a garment ([`read_obj_panels`]). Everything else is ignored.
//!
//! Failure modes: [`ObjError`] naming the line — a malformed number, a
//! face with fewer than three corners, an index out of range.

use std::fmt::Write;

use glam::{DVec2, DVec3};
use grade3d_core::template::garment_panels::PanelMesh;

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
    /// A vertex (or texture coordinate) index out of range.
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

/// Reads positions and triangles (every group's).
///
/// # Errors
/// [`ObjError`].
pub fn read_obj(text: &str) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), ObjError> {
    let parsed = parse(text)?;
    Ok((parsed.positions, parsed.triangles))
}

/// Reads a garment exported one piece per group (issue #18: CLO3D,
/// Browzwear and Marvelous Designer write each pattern piece as a `g` or
/// `o` group): one [`PanelMesh`] per group that has faces, in the order of
/// their first face, named as the group (`default` for faces before any
/// `g`/`o` line; a name met again continues its group). Each piece has its
/// own vertices — those its faces use, in the order they are first used —
/// so two pieces that share a vertex of the file each get a copy (their
/// seam is found again by welding, `template::garment_panels`). A piece
/// whose every face corner names a texture coordinate (`f v/vt …`) gets
/// each vertex's, from its first use; the others get none.
///
/// # Errors
/// [`ObjError`].
pub fn read_obj_panels(text: &str) -> Result<Vec<PanelMesh>, ObjError> {
    let parsed = parse(text)?;
    // per piece: the mesh, each file vertex's local index, whether every corner had a `vt`
    let mut panels: Vec<(PanelMesh, Vec<u32>, bool)> = Vec::new();
    let mut slot: Vec<Option<usize>> = vec![None; parsed.groups.len()];
    for ((t, uv), &g) in parsed.triangles.iter().zip(&parsed.triangle_uvs).zip(&parsed.group_of) {
        let at = *slot[g].get_or_insert_with(|| {
            let mesh = PanelMesh { name: parsed.groups[g].clone(), ..PanelMesh::default() };
            panels.push((mesh, vec![u32::MAX; parsed.positions.len()], true));
            panels.len() - 1
        });
        let (mesh, local, textured) = &mut panels[at];
        *textured &= uv.is_some();
        let mut corners = [0; 3];
        for (k, c) in corners.iter_mut().enumerate() {
            let v = t[k] as usize;
            if local[v] == u32::MAX {
                local[v] = mesh.positions.len() as u32;
                mesh.positions.push(parsed.positions[v]);
                mesh.uv.push(uv.map_or(DVec2::ZERO, |w| parsed.uvs[w[k] as usize]));
            }
            *c = local[v];
        }
        mesh.triangles.push(corners);
    }
    Ok(panels
        .into_iter()
        .map(|(mesh, _, textured)| if textured { mesh } else { PanelMesh { uv: Vec::new(), ..mesh } })
        .collect())
}

/// An OBJ text read: positions, triangles, and each triangle's group.
struct Parsed {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// Texture coordinates (`vt`).
    uvs: Vec<DVec2>,
    /// Per triangle, its corners' indices into `uvs`, where every corner has one.
    triangle_uvs: Vec<Option<[u32; 3]>>,
    /// Per triangle, its index in `groups`.
    group_of: Vec<usize>,
    /// Group names, in the order first named (`default` first: faces before any group).
    groups: Vec<String>,
}

/// The next `N` fields of a line as finite numbers.
fn numbers<'a, const N: usize>(fields: &mut impl Iterator<Item = &'a str>, line: usize) -> Result<[f64; N], ObjError> {
    let mut c = [0.0; N];
    for x in &mut c {
        let t = fields.next().unwrap_or("");
        *x = t
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| ObjError::Number { line, text: t.to_string() })?;
    }
    Ok(c)
}

fn parse(text: &str) -> Result<Parsed, ObjError> {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    let mut uvs = Vec::new();
    let mut triangle_uvs = Vec::new();
    let mut group_of = Vec::new();
    let mut groups = vec!["default".to_string()];
    let mut group = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut it = raw.split_whitespace();
        match it.next() {
            Some("v") => positions.push(DVec3::from_array(numbers(&mut it, line)?)),
            Some("vt") => uvs.push(DVec2::from_array(numbers(&mut it, line)?)),
            Some("g" | "o") => {
                let name = it.collect::<Vec<_>>().join(" ");
                let name = if name.is_empty() { "default".to_string() } else { name };
                group = groups.iter().position(|g| *g == name).unwrap_or_else(|| {
                    groups.push(name);
                    groups.len() - 1
                });
            }
            Some("f") => {
                let mut corners = Vec::new();
                // each corner's `vt`, while every corner so far has one
                let mut textures: Option<Vec<u32>> = Some(Vec::new());
                // a 1-based index, or negative from the end of the `count` read so far
                let resolve = |t: &str, text: &str, count: usize| -> Result<u32, ObjError> {
                    let index: i64 = t.parse().map_err(|_| ObjError::Number { line, text: text.to_string() })?;
                    let resolved = if index > 0 { index - 1 } else { count as i64 + index };
                    if resolved < 0 || resolved >= count as i64 {
                        return Err(ObjError::Index { line, index, count });
                    }
                    Ok(resolved as u32)
                };
                for t in it {
                    let mut fields = t.split('/');
                    corners.push(resolve(fields.next().unwrap_or(""), t, positions.len())?);
                    match fields.next().filter(|f| !f.is_empty()) {
                        Some(vt) => {
                            let w = resolve(vt, t, uvs.len())?;
                            if let Some(ts) = textures.as_mut() {
                                ts.push(w);
                            }
                        }
                        None => textures = None,
                    }
                }
                if corners.len() < 3 {
                    return Err(ObjError::ShortFace { line });
                }
                for k in 1..corners.len() - 1 {
                    triangles.push([corners[0], corners[k], corners[k + 1]]);
                    triangle_uvs.push(textures.as_ref().map(|w| [w[0], w[k], w[k + 1]]));
                    group_of.push(group);
                }
            }
            _ => {}
        }
    }
    Ok(Parsed { positions, triangles, uvs, triangle_uvs, group_of, groups })
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

/// Writes a garment's pieces, one `g` group per piece with its own
/// vertices (what [`read_obj_panels`] reads back; positions to 1e-9).
pub fn write_obj_panels(pieces: &[PanelMesh], header: &str) -> String {
    let mut s = String::new();
    for line in header.lines() {
        let _ = writeln!(s, "# {line}");
    }
    let (mut base, mut uv_base) = (0usize, 0usize);
    for p in pieces {
        let _ = writeln!(s, "g {}", p.name);
        for v in &p.positions {
            let _ = writeln!(s, "v {:.9} {:.9} {:.9}", v.x, v.y, v.z);
        }
        let textured = !p.uv.is_empty() && p.uv.len() == p.positions.len();
        if textured {
            for t in &p.uv {
                let _ = writeln!(s, "vt {:.9} {:.9}", t.x, t.y);
            }
        }
        for t in &p.triangles {
            let [a, b, c] = t.map(|v| v as usize + base + 1);
            if textured {
                let [ta, tb, tc] = t.map(|v| v as usize + uv_base + 1);
                let _ = writeln!(s, "f {a}/{ta} {b}/{tb} {c}/{tc}");
            } else {
                let _ = writeln!(s, "f {a} {b} {c}");
            }
        }
        base += p.positions.len();
        if textured {
            uv_base += p.uv.len();
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn panels_round_trip_through_their_groups() {
        let piece = |name: &str, dx: f64, uv: Vec<DVec2>| PanelMesh {
            name: name.into(),
            positions: vec![DVec3::new(dx, 0.0, 0.0), DVec3::new(dx + 1.0, 0.0, 0.0), DVec3::new(dx, 0.5, 0.25)],
            triangles: vec![[0, 1, 2]],
            uv,
        };
        // texture coordinates (the pattern layout) where a piece has them
        let pieces = vec![
            piece("front", 0.0, vec![]),
            piece("back", 2.0, vec![DVec2::ZERO, DVec2::X, DVec2::new(0.25, 0.5)]),
            piece("sleeve", 4.0, vec![DVec2::ONE, DVec2::Y, DVec2::X]),
        ];
        let text = write_obj_panels(&pieces, "three pieces\nin metres");
        assert!(text.starts_with("# three pieces\n# in metres\ng front\n"), "{text}");
        assert!(text.contains("f 7/4 8/5 9/6"), "{text}");
        assert_eq!(read_obj_panels(&text).unwrap(), pieces);
    }

    #[test]
    fn a_piece_with_a_face_without_texture_coordinates_has_none() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
                    g a\nf 1/1 2/2 3/3\nf 2 4 3\ng b\nf 1/1 2/2 3/3\n";
        let panels = read_obj_panels(text).unwrap();
        assert_eq!((panels[0].uv.len(), panels[1].uv.len()), (0, 3));
        assert_eq!(panels[1].uv, vec![DVec2::ZERO, DVec2::X, DVec2::Y]);
        // a texture index beyond those read is named
        assert_eq!(
            read_obj_panels("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/2 3/3\n").unwrap_err(),
            ObjError::Index { line: 5, index: 2, count: 1 }
        );
        assert!(read_obj_panels("vt 0 x\n").is_err());
    }

    #[test]
    fn round_trip_and_polygons() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::ONE];
        let text = write_obj(&p, Some(&[DVec2::ZERO; 4]), &[[0, 1, 2], [1, 3, 2]]);
        assert_eq!(read_obj(&text).unwrap(), (p, vec![[0, 1, 2], [1, 3, 2]]));
        let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 -1\n";
        assert_eq!(read_obj(quad).unwrap().1, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn groups_become_pieces_with_their_own_vertices_and_weld_back_into_a_seam() {
        // two squares sharing the file's vertices 2 and 5 (x = 1): a front and a back
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\n\
                    g front\nf 1 2 3 4\no back piece\nf 2 5 6 3\ng front\nf 1 3 4\n";
        let panels = read_obj_panels(text).unwrap();
        assert_eq!(panels.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(), vec!["front", "back piece"]);
        // the front: its quad and the triangle met again under its name, 4 own vertices
        assert_eq!(panels[0].triangles, vec![[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
        assert_eq!(panels[0].positions.len(), 4);
        assert_eq!(
            panels[1].positions,
            vec![DVec3::X, DVec3::new(2.0, 0.0, 0.0), DVec3::new(2.0, 1.0, 0.0), DVec3::new(1.0, 1.0, 0.0)]
        );
        assert_eq!(panels[1].triangles, vec![[0, 1, 2], [0, 2, 3]]);
        // faces before any group: `default`
        let lone = read_obj_panels("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(lone[0].name, "default");
        // welded, the two pieces meet along x = 1 (the front's repeated triangle left out)
        use grade3d_core::template::garment_panels::{weld_panels, WeldOptions};
        let mut pieces = panels;
        pieces[0].triangles.pop();
        let g = weld_panels(&pieces, &WeldOptions::default()).unwrap();
        assert_eq!(g.seams.len(), 1);
        assert_eq!(g.seams[0].chain.len(), 2);
        assert!(g.seams[0].chain.iter().all(|&v| g.positions[v as usize].x == 1.0));
    }

    #[test]
    fn bad_lines_are_named() {
        assert_eq!(read_obj("v 0 0 x\n").unwrap_err(), ObjError::Number { line: 1, text: "x".into() });
        assert_eq!(read_obj("v 0 0 0\nf 1 2 3\n").unwrap_err(), ObjError::Index { line: 2, index: 2, count: 1 });
        assert_eq!(read_obj("v 0 0 0\nf 1 1\n").unwrap_err(), ObjError::ShortFace { line: 2 });
        assert!(read_obj("v 0 0 nan\n").is_err());
    }
}
