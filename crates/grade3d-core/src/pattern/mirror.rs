//! A mirror pair's second piece flattened as the mirror image of its first
//! (issue #18; issue #8's mirror pairs).
//!
//! # Method
//!
//! A pattern maker drafts one piece of a mirror pair and cuts it twice
//! ("cut 2", the second face down). On a mirror-symmetric body the refined
//! surface is made exactly symmetric ([`crate::refine::symmetry`]) and the
//! second panel's darts are the mirror images of the first's, so the second
//! panel is the reflection `M(p) = p − 2(n·p − d)n` of the first across the
//! body's mid-sagittal plane `n·p = d`. ARAP commutes with reflections, so
//! the exact flattening of the second is the first's with `u ↦ −u`; but two
//! ARAP runs that stop short of convergence (long or darted pieces) stop at
//! different states, and the pair's sew lines came apart by up to 2.8 mm
//! (issue #18, session 27: the princess dress on 9 of 40 population bodies,
//! against a 0.5 mm bar). Here the second's flattening is the first's,
//! mirrored, through a vertex map of the two panels:
//!
//! 1. every triangle `t` of the second is matched to the triangle of the
//!    first whose centroid lies nearest `M(centroid(t))`, within the
//!    tolerance;
//! 2. each corner of `t` is matched to the corner of that triangle nearest
//!    its mirror image, within the tolerance (a triangle's corners are
//!    distinct points, so this is unique even where a dart slit put two
//!    vertices on one point: the slit's sides are told apart by their
//!    triangles);
//! 3. the map must be one-to-one and onto, every vertex of the second
//!    mapped the same way from each of its triangles.
//!
//! Then `uv₂(v) = (−u₁(m(v)), v₁(m(v)))`; the two pieces are exact mirror
//! images in the plane (their figures — strain, area, lengths — are equal).
//!
//! # Contract
//!
//! Input: the two panels, the first's flattening, the mirror plane and a
//! tolerance (metres). Output: the second's flattening, or `None` where the
//! panels are not mirror images within the tolerance (a scan; a surface not
//! symmetrised) — the caller flattens the second on its own then. No
//! failure modes.

use glam::{DVec2, DVec3};
use typed_index_collections::TiVec;

use super::flatten::Flattening;
use super::panels::{Panel, PanelVertex};

/// The vertex of `first` that each vertex of `second` mirrors
/// (`M(p₂(v)) ≈ p₁(m(v))` within `tol`, metres), if the two panels are
/// mirror images across `n·p = d` vertex for vertex and triangle for
/// triangle (module docs); else `None`.
pub fn mirror_map(
    first: &Panel,
    second: &Panel,
    (n, d): (DVec3, f64),
    tol: f64,
) -> Option<TiVec<PanelVertex, PanelVertex>> {
    let (n1, n2) = (first.positions.len(), second.positions.len());
    if n1 != n2 || first.triangles.len() != second.triangles.len() || tol.is_nan() || tol < 0.0 {
        return None;
    }
    let reflect = |p: DVec3| p - 2.0 * (n.dot(p) - d) * n;
    let centroid = |ps: &TiVec<PanelVertex, DVec3>, f: &[PanelVertex; 3]| (ps[f[0]] + ps[f[1]] + ps[f[2]]) / 3.0;
    // the first's triangles by their centroids' height along the plane's tangent `e`
    let e = n.any_orthonormal_vector();
    let mut by_e: Vec<(f64, usize)> =
        first.triangles.iter().enumerate().map(|(i, f)| (e.dot(centroid(&first.positions, f)), i)).collect();
    by_e.sort_by(|a, b| a.0.total_cmp(&b.0));
    let none = PanelVertex::from(usize::MAX);
    let mut map: TiVec<PanelVertex, PanelVertex> = vec![none; n2].into();
    let mut taken = vec![false; first.triangles.len()];
    for f in &second.triangles {
        let c = reflect(centroid(&second.positions, f));
        let h = e.dot(c);
        let lo = by_e.partition_point(|q| q.0 < h - tol);
        let (dist, j) = by_e[lo..]
            .iter()
            .take_while(|q| q.0 <= h + tol)
            .map(|&(_, j)| (centroid(&first.positions, &first.triangles.raw[j]).distance(c), j))
            .min_by(|a, b| a.0.total_cmp(&b.0))?;
        if dist > tol || std::mem::replace(&mut taken[j], true) {
            return None;
        }
        let g = first.triangles.raw[j];
        for &v in f {
            let q = reflect(second.positions[v]);
            let (dv, w) = g.iter().map(|&w| (first.positions[w].distance(q), w)).min_by(|a, b| a.0.total_cmp(&b.0))?;
            if dv > tol || (map[v] != none && map[v] != w) {
                return None;
            }
            map[v] = w;
        }
    }
    // one-to-one and onto (every vertex in a triangle: a panel has no loose vertex)
    let mut hit = vec![false; n1];
    for &w in &map {
        if w == none || std::mem::replace(&mut hit[usize::from(w)], true) {
            return None;
        }
    }
    Some(map)
}

/// The flattening of `second` as the mirror image (`u ↦ −u`) of `first`'s
/// flattening `flat`, through `map` ([`mirror_map`]): the same figures,
/// pins mapped back.
pub fn mirrored_flattening(flat: &Flattening, map: &TiVec<PanelVertex, PanelVertex>) -> Flattening {
    let mut back = vec![PanelVertex::from(0); map.len()];
    for (v, &w) in map.iter_enumerated() {
        back[usize::from(w)] = v;
    }
    Flattening {
        uv: map.iter().map(|&w| DVec2::new(-flat.uv[w].x, flat.uv[w].y)).collect(),
        lscm_pins: flat.lscm_pins.map(|p| back[usize::from(p)]),
        ..flat.clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::mesh::VertexId;
    use crate::pattern::flatten::{distortion, flatten, FlattenOptions};

    /// A doubly curved, irregular patch (no symmetry of its own), as a panel.
    fn patch(nu: usize, nv: usize, reflect: bool) -> Panel {
        let mut positions: TiVec<PanelVertex, DVec3> = TiVec::new();
        for j in 0..nv {
            for i in 0..nu {
                let (u, v) = (i as f64 / (nu - 1) as f64, j as f64 / (nv - 1) as f64);
                let x = 0.05 + 0.3 * u + 0.02 * (3.0 * v).sin();
                let p = DVec3::new(x, 0.4 * v, 0.08 * (2.0 * u).sin() * (1.0 + v * v) + 0.03 * u * v);
                positions.push(if reflect { DVec3::new(-p.x, p.y, p.z) } else { p });
            }
        }
        let id = |i: usize, j: usize| PanelVertex::from(j * nu + i);
        let mut triangles = TiVec::new();
        for j in 0..nv - 1 {
            for i in 0..nu - 1 {
                let (a, b, c, e) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                let (t1, t2) = ([a, b, c], [a, c, e]);
                // a reflection reverses the orientation: keep the faces outward
                if reflect {
                    triangles.push([t1[1], t1[0], t1[2]]);
                    triangles.push([t2[1], t2[0], t2[2]]);
                } else {
                    triangles.push(t1);
                    triangles.push(t2);
                }
            }
        }
        let mut outline = Vec::new();
        outline.extend((0..nu).map(|i| id(i, 0)));
        outline.extend((1..nv).map(|j| id(nu - 1, j)));
        outline.extend((0..nu - 1).rev().map(|i| id(i, nv - 1)));
        outline.extend((1..nv - 1).rev().map(|j| id(0, j)));
        if reflect {
            outline.reverse();
        }
        let n = positions.len();
        Panel {
            name: if reflect { "right".into() } else { "left".into() },
            index: 0,
            global: (0..n).map(VertexId::from).collect(),
            unique: n,
            darts: Vec::new(),
            positions,
            triangles,
            outline,
        }
    }

    /// Renumbers a panel's vertices and triangles (as a second panel cut from
    /// another part of the mesh would be numbered).
    fn shuffled(p: &Panel) -> Panel {
        let n = p.positions.len();
        let perm: Vec<usize> = (0..n).map(|i| (i * 7 + 3) % n).collect();
        let mut positions = p.positions.clone();
        for (i, &k) in perm.iter().enumerate() {
            positions[PanelVertex::from(k)] = p.positions[PanelVertex::from(i)];
        }
        let to = |v: PanelVertex| PanelVertex::from(perm[usize::from(v)]);
        let mut triangles: TiVec<_, _> = p.triangles.iter().map(|f| f.map(to)).collect();
        triangles.raw.reverse();
        Panel { positions, triangles, outline: p.outline.iter().map(|&v| to(v)).collect(), ..p.clone() }
    }

    #[test]
    fn a_reflected_panel_maps_vertex_for_vertex_and_flattens_to_the_mirror_image() {
        let first = patch(9, 12, false);
        let second = shuffled(&patch(9, 12, true));
        let map = mirror_map(&first, &second, (DVec3::X, 0.0), 1e-9).expect("exact mirror images");
        for (v, &w) in map.iter_enumerated() {
            let p = second.positions[v];
            assert!(DVec3::new(-p.x, p.y, p.z).distance(first.positions[w]) < 1e-12);
        }
        let opts = FlattenOptions::default();
        let flat = flatten(&first.positions, &first.triangles, &opts).expect("flattens");
        let mirrored = mirrored_flattening(&flat, &map);
        // planted: the same distortion, exactly; and the same as flattening the second on its own
        let d1 = distortion(&first.positions, &first.triangles, &flat.uv);
        let d2 = distortion(&second.positions, &second.triangles, &mirrored.uv);
        assert_eq!(d1.flipped, 0);
        assert_eq!(d2.flipped, 0);
        assert!((d1.strain_p95 - d2.strain_p95).abs() < 1e-12, "{d1:?} {d2:?}");
        assert!((d1.area_accuracy - d2.area_accuracy).abs() < 1e-12);
        let own = flatten(&second.positions, &second.triangles, &opts).expect("flattens");
        let d3 = distortion(&second.positions, &second.triangles, &own.uv);
        assert!((d3.strain_p95 - d2.strain_p95).abs() < 1e-6, "{d3:?} {d2:?}");
        // pins follow their vertices
        for (a, b) in flat.lscm_pins.iter().zip(mirrored.lscm_pins) {
            assert_eq!(map[b], *a);
        }
    }

    #[test]
    fn panels_that_are_not_mirror_images_have_no_map() {
        let first = patch(9, 12, false);
        let mut second = patch(9, 12, true);
        // one vertex 1 mm off its mirror image
        second.positions[PanelVertex::from(40)].z += 1e-3;
        assert!(mirror_map(&first, &second, (DVec3::X, 0.0), 1e-4).is_none());
        assert!(mirror_map(&first, &second, (DVec3::X, 0.0), 2e-3).is_some());
        // a different count
        let smaller = patch(9, 11, true);
        assert!(mirror_map(&first, &smaller, (DVec3::X, 0.0), 1.0).is_none());
        // the panel itself is not its own mirror image across x = 0
        assert!(mirror_map(&first, &first, (DVec3::X, 0.0), 1e-3).is_none());
    }
}
