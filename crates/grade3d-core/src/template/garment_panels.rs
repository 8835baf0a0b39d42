//! A designed garment as panels sewn together (issue #18 item 1, its first
//! step): the pieces a CAD export hands over — one mesh per pattern piece,
//! draped on the avatar — welded into one surface, and the seams found as
//! the boundaries two pieces share.
//!
//! # Method
//!
//! 1. **Weld.** Every vertex is snapped to the first earlier vertex within
//!    [`WeldOptions::tolerance_mm`] (a uniform grid of that cell size, the
//!    27 cells around a vertex searched; first in input order wins, so the
//!    result does not depend on hashing). The two sides of a seam, exported
//!    as separate pieces, land on the same vertices.
//! 2. **Boundaries.** Per panel, an edge used by one of its triangles only
//!    is on its boundary.
//! 3. **Seams.** A boundary edge of two panels is a seam edge between them;
//!    per pair of panels, the seam edges are chained into maximal paths
//!    (a pair may share several seams: a front and a back meet at both side
//!    seams), each from one end to the other, or a closed loop (a
//!    sleeve's armhole). The panel boundary edges on no seam are its free
//!    edges (hems, necklines, openings).
//!
//! # Failure modes
//!
//! [`PanelError`]: a garment with no panel, a panel with no triangle, a
//! non-finite position, a triangle naming a vertex its panel lacks or the
//! same vertex twice (before or after welding), a tolerance that is not
//! positive and finite, and an edge on the boundary of more than two
//! panels (a T-junction of seams: three pieces cannot be sewn along one
//! line).

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

/// One pattern piece as exported: its name and its own mesh.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PanelMesh {
    /// The piece's name (the OBJ group, the glTF mesh).
    pub name: String,
    /// Its vertices (metres).
    pub positions: Vec<DVec3>,
    /// Its triangles (indices into `positions`).
    pub triangles: Vec<[u32; 3]>,
    /// Its texture coordinates, one per vertex, or none: the 2D pattern
    /// layout CLO3D, Browzwear and Marvelous Designer export as UVs, the
    /// grain along `v` (`template::from_garment` reads it).
    pub uv: Vec<DVec2>,
}

/// Knobs of [`weld_panels`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct WeldOptions {
    /// Vertices closer than this are one vertex, mm. Default 0.5 (CAD
    /// exports write the two sides of a seam to within rounding; a
    /// 1 cm-edged drape is far coarser).
    pub tolerance_mm: f64,
}

impl Default for WeldOptions {
    fn default() -> Self {
        Self { tolerance_mm: 0.5 }
    }
}

/// Why panels could not be welded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PanelError {
    /// No panel.
    #[error("the garment has no panel")]
    NoPanel,
    /// A panel has no triangle.
    #[error("panel `{panel}` has no triangle")]
    EmptyPanel {
        /// Its name.
        panel: String,
    },
    /// A position is not finite.
    #[error("vertex {vertex} of panel `{panel}` is not finite")]
    NonFinite {
        /// The panel.
        panel: String,
        /// The vertex, in the panel's numbering.
        vertex: usize,
    },
    /// A triangle names a vertex the panel lacks, or one vertex twice.
    #[error("triangle {triangle} of panel `{panel}` is {corners:?}: {why}")]
    BadTriangle {
        /// The panel.
        panel: String,
        /// The triangle, in the panel's numbering.
        triangle: usize,
        /// Its corners as given.
        corners: [u32; 3],
        /// What is wrong.
        why: &'static str,
    },
    /// The tolerance is not a positive finite number.
    #[error("the weld tolerance {tolerance_mm} mm is not a positive finite number")]
    Tolerance {
        /// The tolerance given.
        tolerance_mm: f64,
    },
    /// An edge is on the boundary of more than two panels.
    #[error("the edge between welded vertices {a} and {b} is on the boundary of panels {panels:?}: three pieces cannot be sewn along one line")]
    Junction {
        /// One end (welded numbering).
        a: u32,
        /// The other end.
        b: u32,
        /// The panels (indices) whose boundary it is on.
        panels: Vec<usize>,
    },
}

/// A seam: a path of welded vertices along which two panels meet.
#[derive(Debug, Clone, PartialEq)]
pub struct Seam {
    /// The two panels (indices, lower first).
    pub panels: [usize; 2],
    /// The welded vertices along it, in order; a closed seam does not
    /// repeat its first vertex.
    pub chain: Vec<u32>,
    /// Whether it closes on itself.
    pub closed: bool,
}

/// The panels welded into one garment surface, with its seams.
#[derive(Debug, Clone, PartialEq)]
pub struct WeldedGarment {
    /// The panels' names, in input order.
    pub names: Vec<String>,
    /// The welded vertices (the first of each cluster's positions).
    pub positions: Vec<DVec3>,
    /// Every panel's triangles, in welded numbering, panel after panel.
    pub triangles: Vec<[u32; 3]>,
    /// The panel of each triangle.
    pub face_panel: Vec<usize>,
    /// Per panel, its vertex `i`'s welded vertex.
    pub welded: Vec<Vec<u32>>,
    /// The seams, by panel pair; per pair the open ones (from their
    /// lower-numbered end's side of the chaining) before the closed ones.
    pub seams: Vec<Seam>,
    /// Per panel, its boundary edges on no seam (welded numbering, each
    /// directed as its triangle runs it), by their vertices.
    pub free_edges: Vec<Vec<[u32; 2]>>,
}

/// Welds `panels` and finds their seams (module docs).
///
/// # Errors
/// [`PanelError`] (module docs).
pub fn weld_panels(panels: &[PanelMesh], opts: &WeldOptions) -> Result<WeldedGarment, PanelError> {
    if panels.is_empty() {
        return Err(PanelError::NoPanel);
    }
    let tol = opts.tolerance_mm * 1e-3;
    if !(tol.is_finite() && tol > 0.0) {
        return Err(PanelError::Tolerance { tolerance_mm: opts.tolerance_mm });
    }
    for p in panels {
        if p.triangles.is_empty() {
            return Err(PanelError::EmptyPanel { panel: p.name.clone() });
        }
        if let Some(vertex) = p.positions.iter().position(|q| !q.is_finite()) {
            return Err(PanelError::NonFinite { panel: p.name.clone(), vertex });
        }
    }
    // 1. weld: a grid of cell `tol`, the first earlier vertex within `tol` wins
    let cell = |q: DVec3| (q / tol).floor().as_i64vec3().to_array();
    let mut grid: BTreeMap<[i64; 3], Vec<u32>> = BTreeMap::new();
    let mut positions: Vec<DVec3> = Vec::new();
    let mut welded = Vec::with_capacity(panels.len());
    for p in panels {
        let mut map = Vec::with_capacity(p.positions.len());
        for &q in &p.positions {
            let c = cell(q);
            // the earliest vertex within `tol` in the 27 cells around
            let mut found: Option<u32> = None;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else { continue };
                        for &v in list {
                            if positions[v as usize].distance(q) <= tol && found.is_none_or(|f| v < f) {
                                found = Some(v);
                            }
                        }
                    }
                }
            }
            let v = found.unwrap_or_else(|| {
                positions.push(q);
                let v = (positions.len() - 1) as u32;
                grid.entry(c).or_default().push(v);
                v
            });
            map.push(v);
        }
        welded.push(map);
    }
    // 2. triangles in welded numbering, and each panel's boundary edges
    let mut triangles = Vec::new();
    let mut face_panel = Vec::new();
    let mut boundary: Vec<Vec<[u32; 2]>> = Vec::with_capacity(panels.len());
    for (pi, p) in panels.iter().enumerate() {
        let mut uses: BTreeMap<(u32, u32), (usize, [u32; 2])> = BTreeMap::new();
        for (ti, t) in p.triangles.iter().enumerate() {
            let bad = |why| PanelError::BadTriangle { panel: p.name.clone(), triangle: ti, corners: *t, why };
            if t.iter().any(|&v| v as usize >= p.positions.len()) {
                return Err(bad("a corner beyond the panel's vertices"));
            }
            let w = t.map(|v| welded[pi][v as usize]);
            if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
                return Err(bad("two corners on one vertex (after welding)"));
            }
            for k in 0..3 {
                let (a, b) = (w[k], w[(k + 1) % 3]);
                let e = uses.entry((a.min(b), a.max(b))).or_insert((0, [a, b]));
                e.0 += 1;
            }
            triangles.push(w);
            face_panel.push(pi);
        }
        boundary.push(uses.into_values().filter(|(n, _)| *n == 1).map(|(_, e)| e).collect());
    }
    // 3. seam edges: boundary edges of two panels
    let mut owners: BTreeMap<(u32, u32), Vec<usize>> = BTreeMap::new();
    for (pi, edges) in boundary.iter().enumerate() {
        for e in edges {
            owners.entry((e[0].min(e[1]), e[0].max(e[1]))).or_default().push(pi);
        }
    }
    let mut by_pair: BTreeMap<[usize; 2], Vec<(u32, u32)>> = BTreeMap::new();
    for (&(a, b), ps) in &owners {
        match ps[..] {
            [_] => {}
            [p, q] if p != q => by_pair.entry([p.min(q), p.max(q)]).or_default().push((a, b)),
            _ => return Err(PanelError::Junction { a, b, panels: ps.clone() }),
        }
    }
    let seams = by_pair
        .into_iter()
        .flat_map(|(pair, edges)| {
            chains(&edges).into_iter().map(move |(chain, closed)| Seam { panels: pair, chain, closed })
        })
        .collect();
    let free_edges = boundary
        .iter()
        .map(|edges| edges.iter().copied().filter(|e| owners[&(e[0].min(e[1]), e[0].max(e[1]))].len() == 1).collect())
        .collect();
    Ok(WeldedGarment {
        names: panels.iter().map(|p| p.name.clone()).collect(),
        positions,
        triangles,
        face_panel,
        welded,
        seams,
        free_edges,
    })
}

/// Undirected edges chained into maximal paths: from every vertex of
/// degree other than two first (open chains, end to end), then the loops
/// left; each from its lowest available start, deterministic.
fn chains(edges: &[(u32, u32)]) -> Vec<(Vec<u32>, bool)> {
    let mut adjacent: BTreeMap<u32, Vec<(u32, usize)>> = BTreeMap::new();
    for (k, &(a, b)) in edges.iter().enumerate() {
        adjacent.entry(a).or_default().push((b, k));
        adjacent.entry(b).or_default().push((a, k));
    }
    let mut used = vec![false; edges.len()];
    let mut out = Vec::new();
    let starts: Vec<u32> = adjacent
        .iter()
        .filter(|(_, n)| n.len() != 2)
        .map(|(&v, _)| v)
        .chain(adjacent.iter().filter(|(_, n)| n.len() == 2).map(|(&v, _)| v))
        .collect();
    for start in starts {
        while let Some(&(mut next, mut k)) = adjacent[&start].iter().find(|(_, k)| !used[*k]) {
            let mut chain = vec![start];
            loop {
                used[k] = true;
                if next == start {
                    out.push((chain, true));
                    break;
                }
                chain.push(next);
                match adjacent[&next].iter().find(|(_, k)| !used[*k]) {
                    Some(&(n, e)) if adjacent[&next].len() == 2 => (next, k) = (n, e),
                    _ => {
                        out.push((chain, false));
                        break;
                    }
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The flattening tests' grid (`ny` rows × `nx` columns over `(s, t) ∈ [0, 1]²`) as a piece.
    fn grid(name: &str, nx: usize, ny: usize, f: impl Fn(f64, f64) -> DVec3) -> PanelMesh {
        let (positions, triangles) = crate::pattern::flatten::shapes::grid(ny, nx, f);
        PanelMesh { name: name.into(), positions, triangles, uv: Vec::new() }
    }

    #[test]
    fn two_squares_sharing_a_side_weld_into_one_seam() {
        // element counts and the planted seam: the shared side x = 0.2, written twice, 0.1 mm apart
        let a = grid("left", 4, 3, |s, t| DVec3::new(0.2 * s, 0.3 * t, 0.0));
        let b = grid("right", 4, 3, |s, t| DVec3::new(0.2 + 0.0001 + 0.2 * s, 0.3 * t, 0.0));
        let g = weld_panels(&[a, b], &WeldOptions::default()).unwrap();
        assert_eq!(g.positions.len(), 2 * 20 - 4);
        assert_eq!(g.triangles.len(), 2 * 24);
        assert_eq!(g.seams.len(), 1);
        let s = &g.seams[0];
        assert_eq!((s.panels, s.closed, s.chain.len()), ([0, 1], false, 4));
        for &v in &s.chain {
            assert!((g.positions[v as usize].x - 0.2).abs() < 1e-12, "on the shared side");
        }
        // each panel keeps 4 + 3 + 4 = 11 free boundary edges (its other three sides)
        assert_eq!(g.free_edges.iter().map(Vec::len).collect::<Vec<_>>(), vec![11, 11]);
        // at a tolerance below the gap the sides stay apart: no seam
        let apart = weld_panels(
            &[
                grid("l", 4, 3, |s, t| DVec3::new(0.2 * s, 0.3 * t, 0.0)),
                grid("r", 4, 3, |s, t| DVec3::new(0.2001 + 0.2 * s, 0.3 * t, 0.0)),
            ],
            &WeldOptions { tolerance_mm: 0.05 },
        )
        .unwrap();
        assert!(apart.seams.is_empty());
        assert_eq!(apart.positions.len(), 40);
    }

    #[test]
    fn a_tube_in_two_halves_has_two_side_seams_and_free_hems() {
        // a front and a back meeting at both side seams (one panel pair, two chains)
        let half = |name: &str, from: f64| {
            grid(name, 8, 5, move |s, t| {
                let a = std::f64::consts::PI * (from + s);
                DVec3::new(0.15 * a.cos(), 0.5 * t, 0.15 * a.sin())
            })
        };
        let g = weld_panels(&[half("front", 0.0), half("back", 1.0)], &WeldOptions::default()).unwrap();
        assert_eq!(g.seams.len(), 2);
        for s in &g.seams {
            assert_eq!((s.panels, s.closed, s.chain.len()), ([0, 1], false, 6));
            // vertical: every vertex of a chain at one angle
            let x0 = g.positions[s.chain[0] as usize].x;
            assert!(s.chain.iter().all(|&v| (g.positions[v as usize].x - x0).abs() < 1e-9));
        }
        // the hems: the top and bottom rows, 8 edges each per panel
        assert_eq!(g.free_edges.iter().map(Vec::len).collect::<Vec<_>>(), vec![16, 16]);
    }

    #[test]
    fn a_sleeve_meets_its_body_along_a_closed_seam() {
        // a cylinder (the sleeve) and an annulus around its opening (the body): one closed seam
        let n = 12;
        let ring = |r: f64, k: usize| {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            DVec3::new(r * a.cos(), r * a.sin(), 0.0)
        };
        let mut sleeve = PanelMesh { name: "sleeve".into(), ..PanelMesh::default() };
        let mut body = PanelMesh { name: "body".into(), ..PanelMesh::default() };
        for k in 0..n {
            sleeve.positions.push(ring(0.05, k));
            sleeve.positions.push(ring(0.05, k) + DVec3::Z * 0.3);
            body.positions.push(ring(0.05, k));
            body.positions.push(ring(0.2, k));
        }
        for k in 0..n as u32 {
            let j = (k + 1) % n as u32;
            sleeve.triangles.extend([[2 * k, 2 * j, 2 * j + 1], [2 * k, 2 * j + 1, 2 * k + 1]]);
            body.triangles.extend([[2 * k, 2 * k + 1, 2 * j + 1], [2 * k, 2 * j + 1, 2 * j]]);
        }
        let g = weld_panels(&[body, sleeve], &WeldOptions::default()).unwrap();
        assert_eq!(g.seams.len(), 1);
        let s = &g.seams[0];
        assert!(s.closed);
        assert_eq!(s.chain.len(), n);
        assert_eq!(g.positions.len(), 3 * n);
    }

    #[test]
    fn bad_panels_are_refused_by_name() {
        let ok = grid("a", 1, 1, |s, t| DVec3::new(s, t, 0.0));
        assert_eq!(weld_panels(&[], &WeldOptions::default()), Err(PanelError::NoPanel));
        let empty = PanelMesh { triangles: vec![], ..ok.clone() };
        assert_eq!(weld_panels(&[empty], &WeldOptions::default()), Err(PanelError::EmptyPanel { panel: "a".into() }));
        let mut nan = ok.clone();
        nan.positions[2].z = f64::NAN;
        assert_eq!(
            weld_panels(&[nan], &WeldOptions::default()),
            Err(PanelError::NonFinite { panel: "a".into(), vertex: 2 })
        );
        let mut beyond = ok.clone();
        beyond.triangles[1] = [0, 1, 9];
        assert!(matches!(
            weld_panels(&[beyond], &WeldOptions::default()),
            Err(PanelError::BadTriangle { triangle: 1, .. })
        ));
        // two corners 0.1 mm apart weld into one: the triangle collapses
        let mut tiny = ok.clone();
        tiny.positions[1] = tiny.positions[0] + DVec3::X * 1e-4;
        assert!(matches!(
            weld_panels(&[tiny], &WeldOptions::default()),
            Err(PanelError::BadTriangle { triangle: 0, .. })
        ));
        assert_eq!(
            weld_panels(std::slice::from_ref(&ok), &WeldOptions { tolerance_mm: 0.0 }),
            Err(PanelError::Tolerance { tolerance_mm: 0.0 })
        );
        // three panels on one edge
        let fin = |name: &str, d: DVec3| PanelMesh {
            name: name.into(),
            positions: vec![DVec3::ZERO, DVec3::Y, d],
            triangles: vec![[0, 1, 2]],
            uv: Vec::new(),
        };
        assert!(matches!(
            weld_panels(&[fin("a", DVec3::X), fin("b", DVec3::NEG_X), fin("c", DVec3::Z)], &WeldOptions::default()),
            Err(PanelError::Junction { a: 0, b: 1, .. })
        ));
    }
}
