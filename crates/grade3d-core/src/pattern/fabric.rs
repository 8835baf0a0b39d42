//! Thread strain of a pattern piece cut from woven cloth: how much the
//! flattening stretches or shortens the cloth along its **warp** (the grain
//! line) and its **weft** (across it), and how far it **shears** the weave
//! (the angle between warp and weft moved off 90°) — the three figures a
//! fabric's tensile and shear tests give (Kawabata KES-F; ASTM D5035 for
//! tensile, the bias for shear). Edge strain ([`super::flatten::distortion`])
//! mixes them: a mesh edge on the bias lengthens when the weave shears,
//! which woven cloth does at forces two orders of magnitude below those that
//! stretch its threads, so a piece can show a high edge strain that the
//! cloth takes without tension.
//!
//! # Contract
//!
//! [`fabric_strain`] takes one piece's 3D vertex positions and plane
//! positions (the same length unit for both), its triangles and the grain
//! direction in the plane. Per triangle, with `X` the triangle's two edges
//! in an orthonormal frame of its 3D plane and `U` the same edges in the
//! plane, the map from the garment to the pattern is `J = U X⁻¹`; a thread
//! along the unit plane direction `d` comes from the garment length
//! `|J⁻¹ d|` per unit of pattern length, so its strain is
//!
//! ```text
//! ε(d) = 1 / |J⁻¹ d| − 1      (> 0: the pattern is longer than the garment along d)
//! γ    = |90° − ∠(J⁻¹ g, J⁻¹ g⊥)|,   g the grain (warp), g⊥ the weft
//! ```
//!
//! Figures are area-weighted over the triangles (a percentile is the value
//! below which that share of the piece's 3D area lies). Triangles with an
//! index out of range, or degenerate in 3D or in the plane, are skipped;
//! a zero grain or no triangle left gives all zeros. Never panics.

use glam::{DMat2, DVec2, DVec3};
use serde::{Deserialize, Serialize};
use typed_index_collections::TiSlice;

use super::panels::{PanelFace, PanelVertex};

/// Thread strain and weave shear of a piece ([`fabric_strain`]).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize, utoipa::ToSchema)]
pub struct FabricStrain {
    /// 95th percentile (by area) of `|ε|` along the warp (the grain line).
    pub warp_p95: f64,
    /// 95th percentile (by area) of `|ε|` along the weft (across the grain).
    pub weft_p95: f64,
    /// 95th percentile (by area) of the larger of the two, per triangle.
    pub thread_p95: f64,
    /// Largest `|ε|` along either thread.
    pub thread_max: f64,
    /// 95th percentile (by area) of the weave's shear angle, degrees.
    pub shear_p95_deg: f64,
    /// Largest shear angle, degrees.
    pub shear_max_deg: f64,
}

/// One triangle's figures: area, warp `|ε|`, weft `|ε|`, shear (°).
type Row = (f64, f64, f64, f64);

/// Share of the area below the reported percentiles.
const PERCENTILE: f64 = 0.95;

/// Thread strain and weave shear of the piece (module docs): `positions`
/// in 3D and `uv` in the plane in one unit, `grain` the warp's direction in
/// the plane (any length).
pub fn fabric_strain(
    positions: &TiSlice<PanelVertex, DVec3>,
    triangles: &TiSlice<PanelFace, [PanelVertex; 3]>,
    uv: &TiSlice<PanelVertex, DVec2>,
    grain: DVec2,
) -> FabricStrain {
    let Some(g) = grain.try_normalize() else {
        return FabricStrain::default();
    };
    let weft = g.perp();
    let mut rows: Vec<Row> = Vec::with_capacity(triangles.len());
    for t in triangles {
        let idx = *t;
        if idx.iter().any(|&i| i.idx() >= positions.len() || i.idx() >= uv.len()) {
            continue;
        }
        let (p, q) = (idx.map(|i| positions[i]), idx.map(|i| uv[i]));
        let (a, b) = (p[1] - p[0], p[2] - p[0]);
        let n = a.cross(b);
        let area = 0.5 * n.length();
        let (Some(e1), Some(nn)) = (a.try_normalize(), n.try_normalize()) else {
            continue;
        };
        let e2 = nn.cross(e1);
        let x = DMat2::from_cols(DVec2::new(a.dot(e1), a.dot(e2)), DVec2::new(b.dot(e1), b.dot(e2)));
        let u = DMat2::from_cols(q[1] - q[0], q[2] - q[0]);
        if x.determinant().abs() <= f64::EPSILON * a.length_squared().max(b.length_squared())
            || u.determinant().abs()
                <= f64::EPSILON * (q[1] - q[0]).length_squared().max((q[2] - q[0]).length_squared())
        {
            continue;
        }
        // J⁻¹ = X U⁻¹: pattern direction → garment direction
        let inv = x * u.inverse();
        let (wg, wf) = (inv * g, inv * weft);
        let strain = |v: DVec2| (1.0 / v.length() - 1.0).abs();
        let cos = (wg.dot(wf) / (wg.length() * wf.length())).clamp(-1.0, 1.0);
        let shear = (90.0 - cos.acos().to_degrees()).abs();
        if [area, strain(wg), strain(wf), shear].iter().all(|v| v.is_finite()) {
            rows.push((area, strain(wg), strain(wf), shear));
        }
    }
    let total: f64 = rows.iter().map(|r| r.0).sum();
    if rows.is_empty() || total <= 0.0 {
        return FabricStrain::default();
    }
    let percentile = |value: &dyn Fn(&Row) -> f64| -> f64 {
        let mut v: Vec<(f64, f64)> = rows.iter().map(|r| (value(r), r.0)).collect();
        v.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut below = 0.0;
        for (x, w) in &v {
            below += w;
            if below >= PERCENTILE * total {
                return *x;
            }
        }
        v.last().map_or(0.0, |x| x.0)
    };
    let max = |value: &dyn Fn(&Row) -> f64| rows.iter().map(value).fold(0.0, f64::max);
    FabricStrain {
        warp_p95: percentile(&|r| r.1),
        weft_p95: percentile(&|r| r.2),
        thread_p95: percentile(&|r| r.1.max(r.2)),
        thread_max: max(&|r| r.1.max(r.2)),
        shear_p95_deg: percentile(&|r| r.3),
        shear_max_deg: max(&|r| r.3),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::flatten::shapes::{faces, vertices};

    /// [`super::fabric_strain`] of plain test arrays (`u32` ids).
    fn fabric_strain(p: &[DVec3], t: &[[u32; 3]], uv: &[DVec2], grain: DVec2) -> FabricStrain {
        super::fabric_strain(vertices(p), &faces(t), vertices(uv), grain)
    }

    /// A 4 × 4 grid of unit squares, each split into two triangles.
    fn grid() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for j in 0..5 {
            for i in 0..5 {
                p.push(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        let mut t = Vec::new();
        for j in 0..4u32 {
            for i in 0..4u32 {
                let v = j * 5 + i;
                t.push([v, v + 1, v + 6]);
                t.push([v, v + 6, v + 5]);
            }
        }
        (p, t)
    }

    #[test]
    fn an_isometry_strains_nothing_whatever_the_grain() {
        let (p, t) = grid();
        // the grid's columns on a cylinder of radius 3 (a developable polyhedron: its faces
        // are flat, a column apart by the chord c), laid flat with columns c apart and
        // rotated by 30°
        let r: f64 = 3.0;
        let c = 2.0 * r * (0.5 / r).sin();
        let bent: Vec<DVec3> = p.iter().map(|q| DVec3::new(r * (q.x / r).sin(), q.y, r * (q.x / r).cos())).collect();
        let rot = DVec2::from_angle(30f64.to_radians());
        let uv: Vec<DVec2> = p.iter().map(|q| rot.rotate(DVec2::new(c * q.x, q.y))).collect();
        for grain in [DVec2::NEG_Y, DVec2::new(1.0, 2.0)] {
            let f = fabric_strain(&bent, &t, &uv, grain);
            assert!(f.thread_max < 1e-12 && f.shear_max_deg < 1e-9, "{f:?}");
        }
    }

    #[test]
    fn a_planted_stretch_and_shear_come_back_on_their_threads() {
        let (p, t) = grid();
        // 3 % longer along y (the warp), unchanged along x (the weft)
        let uv: Vec<DVec2> = p.iter().map(|q| DVec2::new(q.x, 1.03 * q.y)).collect();
        let f = fabric_strain(&p, &t, &uv, DVec2::NEG_Y);
        assert!((f.warp_p95 - 0.03).abs() < 1e-12 && f.weft_p95 < 1e-12, "{f:?}");
        assert!((f.thread_p95 - 0.03).abs() < 1e-12 && f.shear_max_deg < 1e-9, "{f:?}");
        // a pure shear x += 0.1 y: the weft keeps its length; the warp's pre-image tilts
        // off the weft's perpendicular by atan(0.1) and keeps its length to first order
        let sheared: Vec<DVec2> = p.iter().map(|q| DVec2::new(q.x + 0.1 * q.y, q.y)).collect();
        let f = fabric_strain(&p, &t, &sheared, DVec2::NEG_Y);
        assert!((f.shear_p95_deg - 0.1f64.atan().to_degrees()).abs() < 1e-9, "{f:?}");
        assert!(f.weft_p95 < 1e-12, "{f:?}");
        // …while its diagonal mesh edges are strained by ≈ 5 %
        let d = crate::pattern::flatten::distortion(vertices(&p), &faces(&t), vertices(&sheared));
        assert!(d.strain_max > 0.04, "{d:?}");
    }

    #[test]
    fn bad_input_gives_zeros_or_skips() {
        let (p, t) = grid();
        assert_eq!(fabric_strain(&p, &t, &[], DVec2::Y), FabricStrain::default());
        assert_eq!(
            fabric_strain(&p, &t, &p.iter().map(|q| q.truncate()).collect::<Vec<_>>(), DVec2::ZERO),
            FabricStrain::default()
        );
        let mut bad = t.clone();
        bad.push([0, 0, 1]);
        bad.push([0, 99, 1]);
        let uv: Vec<DVec2> = p.iter().map(|q| q.truncate()).collect();
        assert_eq!(fabric_strain(&p, &bad, &uv, DVec2::Y), fabric_strain(&p, &t, &uv, DVec2::Y));
        let mut nan = p.clone();
        nan[0].x = f64::NAN;
        let f = fabric_strain(&nan, &t, &uv, DVec2::Y);
        assert!(f.thread_max.is_finite() && f.shear_max_deg.is_finite());
    }
}
